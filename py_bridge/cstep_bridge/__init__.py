"""cstep_bridge: a PyBullet drone, point maze and Husky over rclpy, with the C-STEP empowered
reward from `cstep node`.

Subpackages: :mod:`~cstep_bridge.sim` (the PyBullet worlds: the drone arena, the maze's layout and
ball, the Husky's hall), :mod:`~cstep_bridge.envs` (the Gymnasium environments, by name and by Gymnasium id),
:mod:`~cstep_bridge.reward` (the task reward, collisions, C-STEP scored in process),
:mod:`~cstep_bridge.ros` (the rclpy bridge to a `cstep node`, bags), :mod:`~cstep_bridge.training`
and :mod:`~cstep_bridge.evaluation` (the ``train`` extra). Beside them: :mod:`~cstep_bridge.errors`
(the package's errors, all :class:`CstepError` s, exported here), :mod:`~cstep_bridge.resources`
(where the node binary, config and URDF are found), :mod:`~cstep_bridge.observation` (the policy's
goal encoding, at the path committed models' pickles name) and the command-line tools, each
``python -m cstep_bridge.<tool>``: ``train``, ``evaluate``, ``campaign``, ``export``,
``selection``, ``eval_set`` and ``bag``. :mod:`cstep_bridge.env` is the drone env's documented
path.

Importing the package registers ``cstep/Drone-v0``, ``cstep/PointMaze-v0`` and ``cstep/Husky-v0``
with Gymnasium.
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
