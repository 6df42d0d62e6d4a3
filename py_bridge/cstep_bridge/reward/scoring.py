"""C-STEP scored in this process, without ROS: the node's own scoring step over NumPy arrays.

:class:`Scorer` is ``cstep_scoring.Scorer``, the extension module built from the node's Rust
core (``crates/cstep-py``; ``make venv`` builds and installs it with maturin). It scores a batch
of states through the same function the node's ``/cstep/evaluate_batch`` service calls, with the
same input checks, on all cores with the GIL released, so a state gets the same numbers, bit
for bit, as from a node started with the same parameters::

    from cstep_bridge.reward.scoring import Scorer
    scorer = Scorer(model="point_mass", safety_coefficient=0.5)
    answer = scorer.score_batch(positions, orientations, velocities, angular_velocities,
                                scans, goals, in_collision, angle_min=-3.14159, ...)
    answer["reward"], answer["empowerment"], answer["valid"], answer["status"]

(``help(Scorer.score_batch)`` gives the shapes and units.) :func:`bridge_scorer` is the scorer
a bridge's private node would be, and :func:`score_requests` scores the envs'
:class:`~cstep_bridge.envs.drone.RewardRequest` s with it: the envs' and the trainer's
``reward_source="inprocess"``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..resources import config_file
from ..sim.world import PAPER_LIDAR, Lidar

try:
    from cstep_scoring import Scorer
except ImportError as err:  # pragma: no cover - depends on the install
    raise ImportError(
        "cstep_bridge.reward.scoring needs the cstep_scoring extension (crates/cstep-py): `make venv` "
        "builds it into .venv, or `pip install ./crates/cstep-py` (Rust and maturin needed)"
    ) from err

__all__ = ["Answer", "Scorer", "bridge_scorer", "score_requests"]


@dataclass(frozen=True)
class Answer:
    """The scorer's answer for one state: what an env reads from the node's
    (:class:`~cstep_bridge.ros.bridge.Reward` has the same fields)."""

    reward: float
    task_reward: float
    empowerment: float
    valid: bool
    status: str


def _parameter(text: str) -> int | float | str:
    """A ``-p name:=value`` value as the number it spells, or the text."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def bridge_scorer(safety_coefficient: float, node_params: dict[str, str] | None = None) -> Scorer:
    """The scorer of a bridge's private node (:class:`~cstep_bridge.ros.bridge.CStepNode`): the
    packaged parameters file, then ``node_params`` (the node's ``-p`` values as text, numbers
    read as numbers), then ``safety_coefficient``."""
    params = {k: _parameter(v) for k, v in (node_params or {}).items()}
    return Scorer(config=str(config_file()), **params, safety_coefficient=float(safety_coefficient))


def score_requests(scorer: Scorer, requests: Sequence, lidar: Lidar = PAPER_LIDAR) -> list[Answer]:
    """``scorer``'s answers for the envs' :class:`~cstep_bridge.envs.drone.RewardRequest` s, in order,
    in one batch: each state, scan (laid out as ``lidar``, the simulated LiDAR's layout,
    :mod:`~cstep_bridge.sim.world`), goal and collision flag exactly as
    :class:`~cstep_bridge.ros.bridge.RosBridge` sends them to the node."""
    states = [r.state for r in requests]
    goals = [r.goal for r in requests]
    if any(g is None for g in goals) and not all(g is None for g in goals):
        raise ValueError("score_requests: every request needs a goal, or none")
    answer = scorer.score_batch(
        np.array([s.position for s in states], dtype=np.float64).reshape(-1, 3),
        np.array([s.quaternion for s in states], dtype=np.float64).reshape(-1, 4),
        np.array([s.body_velocity for s in states], dtype=np.float64).reshape(-1, 3),
        np.array([s.body_angular_velocity for s in states], dtype=np.float64).reshape(-1, 3),
        np.array([r.ranges for r in requests], dtype=np.float32).reshape(len(requests), -1),
        None if goals and goals[0] is None else np.array(goals, dtype=np.float64).reshape(-1, 3),
        np.array([r.in_collision for r in requests], dtype=bool),
        **lidar.scan_fields(),
    )
    return [
        Answer(
            reward=float(answer["reward"][i]),
            task_reward=float(answer["task_reward"][i]),
            empowerment=float(answer["empowerment"][i]),
            valid=bool(answer["valid"][i]),
            status=str(answer["status"][i]),
        )
        for i in range(len(requests))
    ]
