"""cstep_bridge: a PyBullet drone and point maze over rclpy, with the C-STEP empowered reward from
`cstep node`.

Modules: :mod:`~cstep_bridge.sim` (PyBullet drone world), :mod:`~cstep_bridge.maze` (point maze
world and env), :mod:`~cstep_bridge.world` (what the two share), :mod:`~cstep_bridge.ros_io`
(rclpy bridge), :mod:`~cstep_bridge.env` (the drone's Gymnasium environment),
:mod:`~cstep_bridge.envs` (the environments by name and their Gymnasium ids),
:mod:`~cstep_bridge.resources` (where the node binary, config and URDF are found),
:mod:`~cstep_bridge.errors` (the package's errors, all :class:`CstepError` s, exported here).

Importing the package registers ``cstep/Drone-v0`` and ``cstep/PointMaze-v0`` with Gymnasium.
"""

from .envs import register_envs
from .errors import (
    BagError,
    ConfigError,
    CstepError,
    NodeDied,
    NodeError,
    RayUnavailable,
    ResourceNotFound,
    RewardTimeout,
)

__all__ = [
    "BagError",
    "ConfigError",
    "CstepError",
    "NodeDied",
    "NodeError",
    "RayUnavailable",
    "ResourceNotFound",
    "RewardTimeout",
    "register_envs",
]

__version__ = "0.1.0"
"""The package version (pyproject.toml reads it from here)."""

register_envs()
