"""The drone's Gymnasium environment by the path users' scripts and ``cstep/Drone-v0`` name:
:class:`~cstep_bridge.envs.drone.CStepDroneEnv`."""

from .envs.drone import CStepDroneEnv

__all__ = ["CStepDroneEnv"]
