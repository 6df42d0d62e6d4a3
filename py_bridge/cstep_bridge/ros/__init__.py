"""The ROS side, over rclpy: the bridge that asks a `cstep node` for the empowered reward
(:mod:`~cstep_bridge.ros.bridge`) and recording, replaying and comparing its bags
(:mod:`~cstep_bridge.ros.bag`). Importing either needs rclpy and cstep_msgs."""
