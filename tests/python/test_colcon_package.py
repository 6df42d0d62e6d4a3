"""cstep as a ROS 2 package: what one `colcon build` of the repository installs (`make colcon`,
``$CSTEP_COLCON_INSTALL``), found through colcon's own ``setup.bash`` and the ament index, and
the installed node started with exactly the command line ``ros2 launch cstep cstep.launch.py``
gives it.

launch_ros is not on PyPI, so it cannot run here; its command line is written down below from
its source (ros2/launch_ros, branch jazzy, 0.26.6: ``launch_ros/actions/node.py``) and every
path in it is resolved with the real ``ament_index_python`` (the library launch_ros's
``FindPackageShare`` and ``ExecutableInPackage`` call) in the environment ``setup.bash`` makes.
"""

import filecmp
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
import yaml
from conftest import REPO, wait_until
from cstep_msgs.msg import EmpoweredReward, Empowerment
from nav_msgs.msg import Odometry
from node_rig import RELIABLE, corridor_scan, odometry, stop_gently
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

# The files cargo-ament-build installs into share/cstep/ (Cargo.toml, [package.metadata.ros]).
SHARE_DIRS = ("config", "urdf", "launch")


@pytest.fixture(scope="module")
def install() -> Path:
    """The colcon install space (``--install-base``) `make colcon` built."""
    path = Path(os.environ.get("CSTEP_COLCON_INSTALL", REPO / "ros2_ws" / "install"))
    if not (path / "setup.bash").is_file():
        pytest.fail(f"no colcon install at {path}: run `make colcon` (or set CSTEP_COLCON_INSTALL)")
    return path


def sourced(install: Path, command: list[str]) -> list[str]:
    """``command`` run as a user runs it after ``source install/setup.bash``."""
    return ["bash", "-c", 'source "$0/setup.bash" && exec "$@"', str(install), *command]


def unsourced_env() -> dict[str, str]:
    """This process's environment without what a sourced ROS workspace sets, so that only
    ``setup.bash`` decides where packages are found."""
    return {k: v for k, v in os.environ.items() if k not in ("AMENT_PREFIX_PATH", "PYTHONPATH")}


def ament_lookup(install: Path) -> dict:
    """What ``ament_index_python`` answers in the environment ``setup.bash`` makes: every
    package's prefix, cstep's prefix and share directory (as launch_ros's
    ``ExecutableInPackage`` and ``FindPackageShare`` ask it)."""
    script = (
        "import json\n"
        "from ament_index_python.packages import (\n"
        "    get_package_prefix, get_package_share_directory, get_packages_with_prefixes)\n"
        "print(json.dumps({'packages': get_packages_with_prefixes(),\n"
        "    'prefix': get_package_prefix('cstep'), 'share': get_package_share_directory('cstep')}))\n"
    )
    out = subprocess.run(
        sourced(install, [sys.executable, "-c", script]),
        env=unsourced_env(),
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def test_colcon_installs_both_packages_with_the_node_and_its_share_files(install):
    found = ament_lookup(install)
    # One colcon build of the repository: both packages, each in its own (isolated) prefix.
    assert found["packages"]["cstep"] == str(install / "cstep")
    assert found["packages"]["cstep_msgs"] == str(install / "cstep_msgs")
    prefix, share = Path(found["prefix"]), Path(found["share"])
    assert share == prefix / "share" / "cstep"
    assert (prefix / "share/ament_index/resource_index/packages/cstep").is_file()

    binary = prefix / "lib" / "cstep" / "cstep"
    assert os.access(binary, os.X_OK)
    # The crate is compiled once: colcon's cargo build shares the checkout's target directory,
    # so what it installed is the release binary the other tests run.
    assert filecmp.cmp(binary, os.environ["CSTEP_BIN"], shallow=False)
    for name in SHARE_DIRS:
        same = filecmp.dircmp(REPO / name, share / name)
        assert not (same.left_only or same.right_only or same.diff_files), name
    assert (share / "package.xml").read_text() == (REPO / "package.xml").read_text()

    # The installed binary runs outside the checkout; cstep_msgs imports from the install.
    help_text = subprocess.run(
        [str(binary), "node", "--help"],
        capture_output=True,
        text=True,
        check=True,
        cwd=tempfile.gettempdir(),
    ).stdout
    assert "--ros-args" in help_text
    where = subprocess.run(
        sourced(install, [sys.executable, "-c", "import cstep_msgs; print(cstep_msgs.__file__)"]),
        env=unsourced_env(),
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert Path(where.strip()).is_relative_to(install / "cstep_msgs"), where

    # cstep_bridge finds the node's binary and share files there through the ament index.
    script = (
        f"import sys; sys.path.insert(0, {str(REPO / 'py_bridge')!r})\n"
        "from cstep_bridge import resources\n"
        "print(resources.cstep_binary()); print(resources.config_file())\n"
    )
    env = {k: v for k, v in unsourced_env().items() if k not in ("CSTEP_BIN", "CSTEP_ROOT")}
    found_by_bridge = subprocess.run(
        sourced(install, [sys.executable, "-c", script]),
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    assert found_by_bridge == [str(binary), str(share / "config" / "cstep.yaml")]


def launch_command_line(
    install: Path, tmp_path: Path, *, namespace: str, params_file: Path | None, log_level: str
) -> list[str]:
    """The command line launch_ros 0.26.6 (Jazzy) runs for ``ros2 launch cstep
    cstep.launch.py namespace:=NS [params_file:=F] log_level:=L``, with
    ``launch/cstep.launch.py``'s ``Node(package='cstep', executable='cstep',
    arguments=['node'], name='cstep_node', namespace=..., parameters=[params_file, {...}],
    ros_arguments=['--log-level', log_level])``. Line numbers: ``launch_ros/actions/node.py``.

    - ``cmd = [ExecutableInPackage(package, executable)]`` (l. 202): ``which(executable)`` in
      ``<get_package_prefix(package)>/lib/<package>`` (``substitutions/executable_in_package.py``).
    - ``+ arguments`` (l. 205), then ``['--ros-args'] + ros_arguments`` (l. 206), then a second
      ``'--ros-args'`` for launch_ros's own rules (l. 209), first ``-r __node:=<name>``
      (l. 210-212, 495).
    - ``-r __ns:=<ns>`` (l. 397-406, 497): the namespace made absolute (``'drone1'`` →
      ``'/drone1'``; ``make_namespace_absolute(prefix_namespace(None, ns))``).
    - For each entry of ``parameters`` in order (l. 444-466): a file → ``--params-file <path>``;
      a dict → a temporary file ``launch_params_*`` (l. 369-377) holding
      ``{<fully qualified node name>: {'ros__parameters': dict}}`` written by ``yaml.dump(...,
      default_flow_style=False)`` (``'/**'`` instead when name or namespace is unset), its
      values each a substitution's string read back with ``yaml.safe_load``
      (``utilities/evaluate_parameters.py`` l. 72-89: ``'false'`` → ``False``).
    """
    found = ament_lookup(install)
    share = Path(found["share"])
    executable = Path(found["prefix"]) / "lib" / "cstep" / "cstep"
    node_namespace = "/" + namespace.lstrip("/")
    node_fqn = f"{node_namespace}/cstep_node"
    evaluated = {
        "use_sim_time": yaml.safe_load("false"),
        "robot_description": yaml.safe_load(str(share / "urdf" / "cf2x.urdf")),
    }
    dict_file = tmp_path / "launch_params_cstep"
    with open(dict_file, "w") as h:
        yaml.dump({node_fqn: {"ros__parameters": evaluated}}, h, default_flow_style=False)
    return [
        str(executable),
        "node",
        "--ros-args",
        "--log-level",
        log_level,
        "--ros-args",
        "-r",
        "__node:=cstep_node",
        "-r",
        f"__ns:={node_namespace}",
        "--params-file",
        str(params_file or share / "config" / "cstep.yaml"),
        "--params-file",
        str(dict_file),
    ]


@pytest.mark.parametrize(
    "params_file_text, log_level, safety_coefficient",
    [
        # `ros2 launch cstep cstep.launch.py namespace:=drone1`: the installed defaults.
        (None, "info", 1.0),
        # A user's params file (a wildcard section, as multi-robot launch files write them)
        # and a log level.
        ("/**:\n  ros__parameters:\n    safety_coefficient: 0.25\n", "debug", 0.25),
    ],
    ids=["defaults", "params_file-and-log_level"],
)
def test_the_launch_files_command_line_runs_the_installed_node_under_its_namespace(
    install, tmp_path, ros_context, executor, params_file_text, log_level, safety_coefficient
):
    params_file = None
    if params_file_text is not None:
        params_file = tmp_path / "robot.yaml"
        params_file.write_text(params_file_text)
    command = launch_command_line(
        install, tmp_path, namespace="drone1", params_file=params_file, log_level=log_level
    )
    log_path = tmp_path / "node.log"
    with open(log_path, "w") as log:
        proc = subprocess.Popen(
            sourced(install, command), stdout=log, stderr=subprocess.STDOUT, env=unsourced_env()
        )
    try:
        # The robot's own topics, relative to a rig node in the same namespace.
        rig = Node("cstep_launch_rig", namespace="drone1", context=ros_context)
        executor.add_node(rig)
        odom = rig.create_publisher(Odometry, "odom", RELIABLE)
        scan = rig.create_publisher(LaserScan, "scan", qos_profile_sensor_data)
        scores: list[Empowerment] = []
        rig.create_subscription(Empowerment, "cstep/empowerment", scores.append, RELIABLE)
        rig.create_subscription(EmpoweredReward, "cstep/reward", lambda _: None, RELIABLE)

        def up() -> bool:
            assert proc.poll() is None, (
                f"the node exited ({proc.returncode}): {log_path.read_text()}"
            )
            return (
                odom.get_subscription_count() >= 1
                and scan.get_subscription_count() >= 1
                and rig.count_publishers("/drone1/cstep/empowerment") >= 1
                and ("cstep_node", "/drone1") in rig.get_node_names_and_namespaces()
            )

        wait_until(up, "/drone1/cstep_node and its topics", executor)
        assert rig.count_publishers("/cstep/empowerment") == 0, "an output left the namespace"

        sec = 1
        while len(scores) < 3:
            assert sec < 400, f"no scores on /drone1/cstep/empowerment: {log_path.read_text()}"
            odom.publish(odometry())
            scan.publish(corridor_scan(sec))
            sec += 1
            end = time.monotonic() + 0.05
            while time.monotonic() < end:
                executor.spin_once(timeout_sec=0.01)
        assert all(m.valid for m in scores)
        assert {m.safety_coefficient for m in scores} == {safety_coefficient}
    finally:
        stop_gently(proc)
