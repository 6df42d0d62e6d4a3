"""cstep_bridge: a PyBullet drone and point maze over rclpy, with the C-STEP empowered reward from
`cstep node`.

Modules: :mod:`~cstep_bridge.sim` (PyBullet drone world), :mod:`~cstep_bridge.maze` (point maze
world and env), :mod:`~cstep_bridge.world` (what the two share), :mod:`~cstep_bridge.ros_io`
(rclpy bridge), :mod:`~cstep_bridge.env` (the drone's Gymnasium environment).
"""

__version__ = "0.1.0"
