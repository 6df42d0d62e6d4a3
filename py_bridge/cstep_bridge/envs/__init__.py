"""The environments by name, so the trainer, the evaluation and Gymnasium build them the same way.

``drone`` is :class:`~cstep_bridge.envs.drone.CStepDroneEnv` (the paper's PyBullet drone arena),
``maze`` is :class:`~cstep_bridge.envs.maze.CStepMazeEnv` (the paper's point maze) and ``husky``
is :class:`~cstep_bridge.envs.husky.CStepHuskyEnv` (a Clearpath Husky driving a hall through a
door between pallets). Each module is imported only when its environment is asked for.

Gymnasium knows them as ``cstep/Drone-v0``, ``cstep/PointMaze-v0`` and ``cstep/Husky-v0``
(namespace ``cstep``): importing :mod:`cstep_bridge` registers them, as Gymnasium 1.x plugins do (ale_py,
gymnasium_robotics), so ``gymnasium.make("cstep/Drone-v0", empowered=True,
safety_coefficient=0.5)`` passes its keyword arguments to the constructor.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
from gymnasium.envs.registration import load_env_creator

from ..errors import ConfigError


@dataclass(frozen=True)
class EnvEntry:
    """One environment: its Gymnasium id and its class."""

    gym_id: str
    """Its Gymnasium id, ``cstep/<Name>-v<version>`` (a contract: users' scripts name it)."""
    entry_point: str
    """Its class as ``"module:Class"``, imported only when an env is built."""


ENVS = {
    "drone": EnvEntry("cstep/Drone-v0", "cstep_bridge.env:CStepDroneEnv"),
    "maze": EnvEntry("cstep/PointMaze-v0", "cstep_bridge.envs.maze:CStepMazeEnv"),
    "husky": EnvEntry("cstep/Husky-v0", "cstep_bridge.envs.husky:CStepHuskyEnv"),
}
"""Every environment by the name the command-line tools take."""

ENV_NAMES = tuple(ENVS)
"""The names :func:`make_env` and the command-line tools accept."""

REWARD_SOURCES = ("node", "inprocess")
"""Where an empowered env's reward is computed (its ``reward_source``): a ``cstep node`` over ROS
(:mod:`~cstep_bridge.ros.bridge`), or the node's scoring function in this process
(:mod:`~cstep_bridge.reward.scoring`). The answers are the same, bit for bit."""


def make_env(
    name: str, *, empowered: bool, safety_coefficient: float = 1.0, **kwargs: Any
) -> gym.Env:
    """A new environment ``name`` (one of :data:`ENV_NAMES`), unwrapped; ``kwargs`` go to its
    constructor."""
    if name not in ENVS:
        raise ConfigError(f"unknown environment {name!r}: choose one of {', '.join(ENV_NAMES)}")
    return load_env_creator(ENVS[name].entry_point)(empowered, safety_coefficient, **kwargs)


def register_envs() -> None:
    """Registers every environment with Gymnasium under its id; ``cstep_bridge`` calls this
    when it is imported."""
    for entry in ENVS.values():
        gym.register(id=entry.gym_id, entry_point=entry.entry_point)
