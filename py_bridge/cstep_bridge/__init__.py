"""cstep_bridge: a PyBullet drone over rclpy, with the C-STEP empowered reward from `cstep node`.

Modules: :mod:`~cstep_bridge.sim` (PyBullet world), :mod:`~cstep_bridge.ros_io` (rclpy bridge),
:mod:`~cstep_bridge.env` (Gymnasium environment).
"""

__version__ = "0.1.0"
