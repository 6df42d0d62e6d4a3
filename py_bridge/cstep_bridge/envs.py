"""The environments by name, so the trainer and the evaluation build them the same way.

``drone`` is :class:`~cstep_bridge.env.CStepDroneEnv` (the paper's PyBullet drone arena) and
``maze`` is :class:`~cstep_bridge.maze.CStepMazeEnv` (the paper's point maze). Each module is
imported only when its environment is asked for.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

ENV_NAMES = ("drone", "maze")


def make_env(
    name: str, *, empowered: bool, safety_coefficient: float = 1.0, **kwargs: Any
) -> gym.Env:
    """A new environment ``name`` (one of :data:`ENV_NAMES`); ``kwargs`` go to its constructor."""
    if name == "drone":
        from .env import CStepDroneEnv

        return CStepDroneEnv(empowered, safety_coefficient, **kwargs)
    if name == "maze":
        from .maze import CStepMazeEnv

        return CStepMazeEnv(empowered, safety_coefficient, **kwargs)
    raise ValueError(f"unknown environment {name!r}: choose one of {', '.join(ENV_NAMES)}")
