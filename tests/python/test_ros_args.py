"""The command line launch_ros and `ros2 run --ros-args` produce means to
`cstep node` what it means to an rclpy node. rclpy itself is the reference: for each command line
the test asks a real rclpy node which parameter overrides it got, then asks a real `cstep node`
started with the same command line which values it uses (the `horizon`, `num_trajectories` and
`safety_coefficient` its `cstep/evaluate` answer reports). Real nodes, real DDS, localhost only."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import REPO, wait_until
from cstep_msgs.srv import Evaluate
from node_rig import CONFIG, corridor_scan, cstep_binary, odometry, stop_gently
from rclpy.node import Node

# A parameters file as launch files write them: the `/**` wildcard, a `/**/node` wildcard, nested
# namespace keys, a `/ns/*` wildcard and a fully qualified section, plus a node that is not ours.
PARAMS = """\
/**:
  ros__parameters:
    horizon: 0.5
    safety_coefficient: 0.3
/**/cstep_node:
  ros__parameters:
    safety_coefficient: 0.7
drone1:
  cstep_node:
    ros__parameters:
      trajectories: 60
/drone1/*:
  ros__parameters:
    horizon: 0.75
/drone1/cstep_node:
  ros__parameters:
    safety_coefficient: 0.9
controller_server:
  ros__parameters:
    horizon: 9.0
"""

# What rclpy reports: the overrides a node gets from this command line.
RCLPY_OVERRIDES = """
import json, sys, rclpy
from rclpy.node import Node
rclpy.init(args=sys.argv)
node = Node("cstep_node")
print(json.dumps({name: p.value for name, p in node._parameter_overrides.items()}))
"""

# The node's built-in defaults, where no override applies.
DEFAULTS = {"horizon": 1.0, "trajectories": 150, "safety_coefficient": 1.0}


def rclpy_overrides(ros_args: list[str]) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", RCLPY_OVERRIDES, "--ros-args", *ros_args],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def cstep_values(ros_args: list[str], service: str, ros_context, executor, tag: str) -> dict:
    """The values a live `cstep node` with these ROS arguments reports through ``service``."""
    log_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"cstep-node-args-{tag}.log"
    with open(log_path, "w") as log:
        proc = subprocess.Popen(
            [str(cstep_binary()), "node", "--ros-args", *ros_args],
            stdout=log,
            stderr=subprocess.STDOUT,
            cwd=REPO,
        )
    node = Node(f"cstep_args_client_{tag}", context=ros_context)
    executor.add_node(node)
    try:
        client = node.create_client(Evaluate, service)
        wait_until(lambda: client.service_is_ready() or proc.poll() is not None, service, executor)
        assert proc.poll() is None, log_path.read_text()
        future = client.call_async(Evaluate.Request(odom=odometry(), scan=corridor_scan(3)))
        wait_until(future.done, f"the {service} reply", executor)
        e = future.result().empowerment
        return {
            "horizon": e.horizon,
            "trajectories": e.num_trajectories,
            "safety_coefficient": e.safety_coefficient,
        }
    finally:
        node.destroy_node()
        stop_gently(proc)


def expected(ros_args: list[str]) -> dict:
    overrides = rclpy_overrides(ros_args)
    return {name: overrides.get(name, default) for name, default in DEFAULTS.items()}


@pytest.mark.parametrize(
    "case",
    [
        # launch_ros: Node(name="cstep_node", namespace="drone1", parameters=[FILE],
        # remappings=[...], ros_arguments=["--log-level", ...]) runs the executable with
        # `--ros-args -r __node:=cstep_node -r __ns:=/drone1 --params-file FILE -r from:=to`.
        # A node-scoped -p before the file; a node-scoped remap for this node and one for
        # another node; an enclave, unused without ROS_SECURITY_ENABLE (as in rcl).
        {
            "args": [
                "--log-level",
                "cstep_node:=warn",
                "--enable-stdout-logs",
                "--disable-external-lib-logs",
                "-e",
                "/cstep",
                "-r",
                "__node:=cstep_node",
                "-r",
                "__ns:=/drone1",
                "-p",
                "cstep_node:trajectories:=40",
                "--params-file",
                "{params}",
                "-r",
                "cstep_node:cstep/evaluate:=/drone1/evaluate_here",
                "-r",
                "controller_server:cstep/evaluate:=/wrong",
            ],
            "service": "/drone1/evaluate_here",
        },
        # The root namespace: `/**`, `/**/cstep_node`, and a node-scoped -p after the file.
        {
            "args": ["--params-file", "{params}", "--param", "cstep_node:horizon:=0.25"],
            "service": "/cstep/evaluate",
        },
        # Another namespace, with a global -p (it joins the `/**` section where that first
        # appeared) and the long --remap form for the namespace.
        {
            "args": ["--remap", "__ns:=/drone2", "--params-file", "{params}", "-p", "horizon:=0.4"],
            "service": "/drone2/cstep/evaluate",
        },
    ],
    ids=["launch_ros-drone1", "root-scoped-p", "drone2-global-p"],
)
def test_cstep_reads_a_command_line_as_rclpy_does(case, tmp_path, ros_context, executor):
    params = tmp_path / "params.yaml"
    params.write_text(PARAMS)
    args = [a.replace("{params}", str(params)) for a in case["args"]]
    reference = expected(args)
    got = cstep_values(
        args, case["service"], ros_context, executor, tag=str(abs(hash(tuple(args))))
    )
    assert got == pytest.approx(reference), (args, reference)


@pytest.mark.parametrize(
    "args, part",
    [
        (["-r", "__ns:=drone1"], "'-r __ns:=drone1'"),
        (["--log-level", "loud"], "not one of unset, debug, info, warn, error, fatal"),
        (["-p", "seed"], "'-p seed'"),
        (["--no-such-flag"], 'unknown ROS argument "--no-such-flag"'),
        (["-r", "scan:=a//b"], "'-r scan:=a//b'"),
    ],
)
def test_a_malformed_ros_argument_is_one_clear_line(args, part):
    out = subprocess.run(
        [str(cstep_binary()), "node", "--config", str(CONFIG), "--ros-args", *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert out.returncode != 0
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and part in lines[0], out.stderr


def test_security_enabled_is_refused_rather_than_run_unsecured(monkeypatch):
    monkeypatch.setenv("ROS_SECURITY_ENABLE", "true")
    out = subprocess.run(
        [str(cstep_binary()), "node", "--ros-args", "-e", "/cstep"],
        check=False,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert out.returncode != 0
    assert "ROS_SECURITY_ENABLE=true" in out.stderr and "refusing" in out.stderr, out.stderr
