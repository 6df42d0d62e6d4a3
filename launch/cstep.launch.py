"""Launch the cstep node: ``ros2 launch cstep cstep.launch.py [namespace:=drone1] [...]``.

Arguments (``ros2 launch cstep cstep.launch.py --show-args`` lists them):

- ``namespace``: the node's namespace; its outputs follow it (``/drone1/cstep/empowerment``).
- ``use_sim_time``: take time from ``/clock``.
- ``params_file``: the parameters file; default: the installed ``share/cstep/config/cstep.yaml``.
- ``robot_description``: the robot's URDF file, or the URDF text itself as
  ``robot_state_publisher`` takes it (the node reads its dynamics from it); default: the
  installed ``share/cstep/urdf/cf2x.urdf`` (Crazyflie 2.x).
- ``log_level``: the node's log level (debug, info, warn, error, fatal).

The command line this produces is written down, from launch_ros's source, in
``tests/python/test_colcon_package.py``, which runs the installed node with it.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare


def generate_launch_description() -> LaunchDescription:
    """The node with the five arguments above, as its executable's ``node`` subcommand."""
    share = FindPackageShare("cstep")
    arguments = [
        DeclareLaunchArgument("namespace", default_value="", description="Node namespace"),
        DeclareLaunchArgument(
            "use_sim_time", default_value="false", description="Use the /clock topic's time"
        ),
        DeclareLaunchArgument(
            "params_file",
            default_value=PathJoinSubstitution([share, "config", "cstep.yaml"]),
            description="Parameters file (ros__parameters YAML)",
        ),
        DeclareLaunchArgument(
            "robot_description",
            default_value=PathJoinSubstitution([share, "urdf", "cf2x.urdf"]),
            description="The robot's URDF file",
        ),
        DeclareLaunchArgument(
            "log_level", default_value="info", description="Log level of the node"
        ),
    ]
    node = Node(
        package="cstep",
        executable="cstep",
        # The binary's subcommand; launch_ros appends its own --ros-args after it.
        arguments=["node"],
        name="cstep_node",
        namespace=LaunchConfiguration("namespace"),
        parameters=[
            LaunchConfiguration("params_file"),
            {
                "use_sim_time": LaunchConfiguration("use_sim_time"),
                "robot_description": LaunchConfiguration("robot_description"),
            },
        ],
        ros_arguments=["--log-level", LaunchConfiguration("log_level")],
        output="screen",
    )
    return LaunchDescription([*arguments, node])
