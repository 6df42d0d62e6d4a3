"""A curriculum over the start–goal distance: goals first drawn part of the way from the start,
then further, until they are where the task puts them.

Exploration is what fails on the full task: a random policy rarely gets near a goal 3–4.5 m away
behind the block. Under the curriculum an episode's goal is moved to ``start + f·(goal − start)``
(moved along that line to the nearest point clear of obstacles where it is not), with ``f`` drawn
uniformly from [0, level]: goals anywhere up to the current level's share of the way, so the
easier ones stay in the mix and each level adds only the goals just beyond the last. The level
moves up once the agent succeeds often enough at the current one. Only the training episodes'
goal distance changes: the task, the reward function and the evaluation set stay as they are, and
the last level is always 1 (the task's own goals, not drawn), so the rest of training runs on them.

With ``full_task_share`` > 0, that share of the episodes below the last level keeps the task's own
goal, so the full task (past the block, for the drone) is met from the start rather than after
the levels have trained straight flights to near goals; only the level's own episodes count
toward moving up.

With ``moves: start`` the curriculum moves the *start* instead — to ``goal + f·(start − goal)``,
the same distance ``f`` of the way from the goal — and keeps the task's own goal (a reverse
curriculum, as Florensa et al. 2017 grow starts back from the goal): the first levels then train
the arrival at the task's goals, 49 of the 100 evaluation arenas' under 0.6 m from a wall (the
table of ``experiments/drone/failure_modes.py``), which partway goals (on the start–goal line,
0.3 m clear of obstacles) never ask for until the last level. A moved start keeps the same 0.3 m
clear, so where the line near the goal runs along the block it lies further out than its level.

What counts toward moving up is ``promote_on``: ``reached`` (default) counts an episode that came
within the env's success radius of the goal without a collision — the task's success; ``held``
counts one that *ended* there without a collision. Under ``reached`` a start a few tenths of a
metre from the goal succeeds by passing it, so the first levels of a reverse curriculum are left
before the agent can stop at a goal; ``held`` keeps the agent on them until it can (the drone
sweep's failure: agents that circle 0.3 m from the goal, ``experiments/protocol.md``). Only the
promotions change; the task, its reward and its success stay the same.

Configured by a protocol's ``curriculum`` entry (see :mod:`~cstep_bridge.training.protocol`)::

    curriculum:
      levels: [0.25, 0.5, 0.75, 1.0]   # fractions f, last = 1
      promote_at: 0.7                  # success rate over ...
      window: 60                       # ... the last this many episodes at the level
      full_task_share: 0.25            # optional: episodes on the task's own goal (default 0)
      moves: goal                      # optional: what the levels move, goal or start
      promote_on: reached              # optional: what an episode must do to count, reached or held
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError

logger = logging.getLogger(__name__)
"""Where this module's messages go (on stdout under the command-line tools)."""

CLEARANCE = 0.3
"""A curriculum goal is at least this far (m) from every obstacle (walls, block)."""
NUDGE = 0.05
"""Step (in f) by which a goal too close to an obstacle is moved on toward the task's goal."""
MOVES = ("goal", "start")
"""What a curriculum's levels move toward the other end: the goal (default) or the start."""
PROMOTE_ON = ("reached", "held")
"""What a level's episode must do to count toward moving up: come within the success radius of
the goal (default) or end there; without a collision either way."""


@dataclass(frozen=True)
class Curriculum:
    """The levels and when to move up; see the module docstring."""

    levels: tuple[float, ...]
    promote_at: float
    window: int
    full_task_share: float = 0.0
    moves: str = "goal"
    promote_on: str = "reached"

    @classmethod
    def from_settings(cls, value: dict[str, Any] | None) -> Curriculum | None:
        """The curriculum of a run's ``curriculum`` setting; None when it has none."""
        if not value:
            return None
        unknown = set(value) - {f.name for f in fields(cls)}
        if unknown:
            raise ConfigError(f"curriculum: unknown keys {sorted(unknown)}")
        levels = tuple(float(v) for v in value.get("levels", (0.25, 0.5, 0.75, 1.0)))
        if not levels or levels[-1] != 1.0 or any(not 0 < f <= 1 for f in levels):
            raise ConfigError(f"curriculum levels must lie in (0, 1] and end at 1, not {levels}")
        if list(levels) != sorted(levels):
            raise ConfigError(f"curriculum levels must increase, not {levels}")
        promote_at = float(value.get("promote_at", 0.7))
        window = int(value.get("window", 60))
        if not 0 < promote_at <= 1 or window <= 0:
            raise ConfigError("curriculum: promote_at must be in (0, 1] and window > 0")
        full_task_share = float(value.get("full_task_share", 0.0))
        if not 0 <= full_task_share < 1:
            raise ConfigError(
                f"curriculum: full_task_share must be in [0, 1), not {full_task_share}"
            )
        moves = str(value.get("moves", "goal"))
        if moves not in MOVES:
            raise ConfigError(f"curriculum: moves must be one of {MOVES}, not {moves!r}")
        promote_on = str(value.get("promote_on", cls.promote_on))
        if promote_on not in PROMOTE_ON:
            raise ConfigError(
                f"curriculum: promote_on must be one of {PROMOTE_ON}, not {promote_on!r}"
            )
        return cls(levels, promote_at, window, full_task_share, moves, promote_on)


def counts(promote_on: str, info: dict[str, Any]) -> bool:
    """Whether the episode whose last step's ``info`` this is counts toward moving up."""
    arrived = info["at_goal"] if promote_on == "held" else info["success"]
    return bool(arrived and not info["collision"])


def partway_goal(start: np.ndarray, goal: np.ndarray, fraction: float, clearance) -> np.ndarray:
    """The point ``fraction`` of the way from ``start`` to ``goal`` or, where that point is
    within :data:`CLEARANCE` of an obstacle (``clearance(xy)`` below it), the nearest point along
    the line, in steps of :data:`NUDGE`, that is not: nearer the start (in front of the block)
    or nearer the goal (past it). The goal itself when none is."""
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    if fraction >= 1.0:
        return goal.copy()
    steps = int(np.ceil(1.0 / NUDGE))
    for k in range(steps + 1):
        for f in (fraction - k * NUDGE, fraction + k * NUDGE):
            if 0.0 < f < 1.0:
                point = start + f * (goal - start)
                if clearance(point[:2]) >= CLEARANCE:
                    return point
    return goal.copy()


def training_endpoints(
    start: np.ndarray, goal: np.ndarray, fraction: float, clearance, moves: str = "goal"
) -> tuple[np.ndarray, np.ndarray]:
    """An episode's start and goal ``fraction`` of the task's start–goal distance apart: the goal
    moved toward the start (``moves="goal"``) or the start toward the goal (``"start"``), each by
    :func:`partway_goal` (clear of obstacles); the task's own at ``fraction`` 1."""
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    if fraction >= 1.0:
        return start, goal
    if moves == "start":
        return partway_goal(goal, start, fraction, clearance), goal
    return start, partway_goal(start, goal, fraction, clearance)


def training_fraction(
    level: float, rng: np.random.Generator, full_task_share: float = 0.0
) -> float:
    """How far along an episode's goal lies at curriculum ``level``: U(0, level), or 1 (the
    task's goal) at level 1 and, below it, with probability ``full_task_share``."""
    if level >= 1.0:
        return 1.0
    if full_task_share > 0 and rng.uniform() < full_task_share:
        return 1.0
    return float(rng.uniform(0.0, level))


def promotions(state: Path) -> list[list[int]]:
    """The ``[step, level]`` promotions kept in a run's ``state`` file, from ``[0, 0]`` (only that
    without one). Files from before the history was kept hold only the last promotion; before its
    step the level below it is taken."""
    if not state.exists():
        return [[0, 0]]
    record = json.loads(state.read_text())
    last = [record["step"], record["level"]]
    return record.get("history") or [[0, max(record["level"] - 1, 0)], last]


def level_at(state: Path, step: int) -> int:
    """The curriculum level a run had reached by ``step``: a run resumed from a checkpoint older
    than its last promotion goes on at the level of that checkpoint."""
    return max((level for at, level in promotions(state) if at <= step), default=0)


def make_callback(curriculum: Curriculum, state: Path):
    """An SB3 callback that sets the envs' ``goal_fraction`` and moves up the levels; each
    promotion is kept in the JSON file ``state``, so a resumed run goes on from the level of the
    checkpoint it resumes."""
    # stable-baselines3 is the train extra: the envs use this module without it
    from stable_baselines3.common.callbacks import BaseCallback

    class GoalCurriculum(BaseCallback):
        """Moves the training envs' goals out as the agent succeeds (see the module docstring)."""

        def _on_training_start(self) -> None:
            self.history = [h for h in promotions(state) if h[0] <= self.num_timesteps]
            self.level = max(level for _, level in self.history)
            self.outcomes: list[bool] = []
            # On the env itself: VecEnv.set_attr would set it on the outermost wrapper (Monitor).
            self.training_env.env_method(
                "set_wrapper_attr", "full_task_share", curriculum.full_task_share
            )
            self.training_env.env_method("set_wrapper_attr", "curriculum_moves", curriculum.moves)
            self._apply()

        def _apply(self) -> None:
            self.training_env.env_method(
                "set_wrapper_attr", "goal_fraction", curriculum.levels[self.level]
            )
            self.outcomes = []

        def _on_step(self) -> bool:
            for info in self.locals["infos"]:
                # The Monitor marks an episode's last step; the full-task share does not count.
                if "episode" in info and info["episode_goal_fraction"] < 1.0:
                    self.outcomes.append(counts(curriculum.promote_on, info))
            last = self.level == len(curriculum.levels) - 1
            recent = self.outcomes[-curriculum.window :]
            if (
                not last
                and len(recent) == curriculum.window
                and np.mean(recent) >= curriculum.promote_at
            ):
                self.level += 1
                logger.info(
                    f"curriculum: level {self.level} (goal fraction "
                    f"{curriculum.levels[self.level]:g}) at step {self.num_timesteps}",
                )
                self._apply()
                self.history.append([self.num_timesteps, self.level])
                record = {"level": self.level, "step": self.num_timesteps, "history": self.history}
                state.write_text(json.dumps(record))
            self.logger.record("cstep/goal_fraction", curriculum.levels[self.level])
            return True

    return GoalCurriculum()
