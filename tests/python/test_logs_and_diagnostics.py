"""Diagnostics and logs as ROS tools expect them. The diagnostics status is named
`<fully qualified node name>: empowerment` (diagnostic_updater's convention), carries the robot's
name as `hardware_id` and is stamped with the node's clock — `/clock` under `use_sim_time`. The
console log is rcutils' format and honours `--log-level`, globally and per logger; the same records
go to `/rosout` as rcl publishes them. Real nodes, real rclpy, real DDS, localhost only, a domain
per test."""

import os
import subprocess
import time
from pathlib import Path

import pytest
from builtin_interfaces.msg import Time
from conftest import REPO, wait_until
from diagnostic_msgs.msg import DiagnosticArray
from node_rig import CONFIG, RELIABLE, cstep_binary, stop_gently
from rcl_interfaces.msg import Log
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock

STARTED = "cstep node /"


def start(ros_domain: int, *ros_args: str, tag: str) -> tuple[subprocess.Popen, Path]:
    log_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"cstep-node-logs-{ros_domain}-{tag}.log"
    with open(log_path, "w") as log:
        proc = subprocess.Popen(
            [str(cstep_binary()), "node", "--config", str(CONFIG), "--ros-args", *ros_args],
            stdout=log,
            stderr=subprocess.STDOUT,
            cwd=REPO,
        )
    return proc, log_path


def log_of(ros_domain: int, *ros_args: str, tag: str) -> str:
    """The console output of a node started with these arguments, up to its start-up line."""
    proc, log_path = start(ros_domain, *ros_args, tag=tag)
    try:
        deadline = time.monotonic() + 30
        while STARTED not in log_path.read_text():
            assert proc.poll() is None, log_path.read_text()
            assert time.monotonic() < deadline, log_path.read_text()
            time.sleep(0.1)
    finally:
        stop_gently(proc)
    return log_path.read_text()


def test_log_level_debug_adds_debug_lines_that_the_default_leaves_out(ros_domain):
    default = log_of(ros_domain, tag="default")
    assert "[DEBUG]" not in default
    # Only the node's own lines: none of RustDDS's or ros2-client's internal records.
    assert "UDPListener" not in default and "Creating topic" not in default, default
    # rcutils' format, and the node's logger named as rcl names it.
    assert "[INFO] [" in default and "] [cstep_node]: cstep node /cstep_node on" in default

    debug = log_of(ros_domain, "--log-level", "debug", tag="debug")
    assert "[DEBUG]" in debug and "parameter override horizon = 1.0" in debug, debug

    # Per logger: the node's own logger name counts, another logger's does not.
    scoped = log_of(ros_domain, "--log-level", "cstep_node:=DEBUG", tag="scoped")
    assert "[DEBUG]" in scoped, scoped
    other = log_of(ros_domain, "--log-level", "controller_server:=debug", tag="other")
    assert "[DEBUG]" not in other, other
    in_namespace = log_of(
        ros_domain, "-r", "__ns:=/drone1", "--log-level", "drone1:=debug", tag="namespace"
    )
    assert "] [drone1.cstep_node]: " in in_namespace and "[DEBUG]" in in_namespace

    # --disable-stdout-logs: a running node that prints nothing of its own.
    proc, log_path = start(ros_domain, "--disable-stdout-logs", "--log-level", "debug", tag="quiet")
    try:
        time.sleep(3)
        assert proc.poll() is None, log_path.read_text()
    finally:
        stop_gently(proc)
    quiet = log_path.read_text()
    assert "[INFO]" not in quiet and "[DEBUG]" not in quiet, quiet


ROSOUT = QoSProfile(
    depth=1000, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
)
"""rcl's /rosout profile (rcl/logging_rosout.h): a late subscriber gets the records kept."""


def rosout_of(
    proc, log_path, ros_context, executor, started: str = STARTED, settle: float = 3.0
) -> list[Log]:
    """The /rosout records of logger-named ``cstep`` nodes, read by a subscriber that joins once
    the node has printed ``started`` (so only a kept history can give it what came before)."""
    deadline = time.monotonic() + 30
    while started not in log_path.read_text():
        assert proc.poll() is None, log_path.read_text()
        assert time.monotonic() < deadline, log_path.read_text()
        time.sleep(0.1)
    node = Node("cstep_rosout_probe", context=ros_context)
    executor.add_node(node)
    received: list[Log] = []
    node.create_subscription(Log, "/rosout", received.append, ROSOUT)
    try:
        end = time.monotonic() + settle
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
    finally:
        node.destroy_node()
    return [r for r in received if "cstep_node" in r.name]


def test_rosout_carries_the_nodes_records_at_its_log_level(ros_domain, ros_context, executor):
    proc, log_path = start(ros_domain, "-r", "__ns:=/drone1", "--log-level", "debug", tag="rosout")
    try:
        records = rosout_of(proc, log_path, ros_context, executor)
    finally:
        stop_gently(proc)
    started = [r for r in records if r.msg.startswith("cstep node /drone1/cstep_node on")]
    assert len(started) == 1, [r.msg for r in records]
    [line] = started
    assert line.name == "drone1.cstep_node" and line.level == Log.INFO
    assert line.file.endswith(".rs") and line.line > 0 and line.function.startswith("cstep")
    assert abs(line.stamp.sec - time.time()) < 60  # the wall clock, as rcl stamps records
    # The records logged before the node existed (the parameter overrides, at debug) were held
    # and published when it did: a subscriber joining later still gets them.
    overrides = [r for r in records if r.msg.startswith("parameter override horizon = ")]
    assert len(overrides) == 1 and overrides[0].level == Log.DEBUG, [r.msg for r in records]
    assert overrides[0].stamp.sec <= line.stamp.sec

    # The level applies to /rosout as to the console; --disable-rosout-logs silences it.
    ignored = "--log-file-name x ignored"
    proc, log_path = start(
        ros_domain, "--log-level", "warn", "--log-file-name", "x", tag="rosout-warn"
    )
    try:
        warn_only = rosout_of(proc, log_path, ros_context, executor, started=ignored)
    finally:
        stop_gently(proc)
    assert any(r.msg.startswith(ignored) and r.level == Log.WARN for r in warn_only), warn_only
    assert all(r.level >= Log.WARN for r in warn_only), [(r.level, r.msg) for r in warn_only]
    proc, log_path = start(ros_domain, "--disable-rosout-logs", tag="rosout-off")
    try:
        assert rosout_of(proc, log_path, ros_context, executor) == []
    finally:
        stop_gently(proc)
    assert STARTED in log_path.read_text()  # the console still has it


def diagnostics_of(proc, ros_context, executor, clock_sec: int | None = None) -> DiagnosticArray:
    """The first diagnostics after a /clock at ``clock_sec`` (when given) was published."""
    node = Node("cstep_diagnostics_probe", context=ros_context)
    executor.add_node(node)
    received: list[DiagnosticArray] = []
    node.create_subscription(DiagnosticArray, "/diagnostics", received.append, RELIABLE)
    clock = node.create_publisher(Clock, "/clock", 10)
    try:
        wait_until(lambda: bool(received) or proc.poll() is not None, "diagnostics", executor)
        assert proc.poll() is None
        if clock_sec is None:
            return received[-1]

        def stamped() -> bool:
            clock.publish(Clock(clock=Time(sec=clock_sec, nanosec=5)))
            return any(d.header.stamp.sec == clock_sec for d in received)

        wait_until(stamped, "diagnostics stamped with /clock", executor, timeout=15)
        return received[-1]
    finally:
        node.destroy_node()


@pytest.mark.parametrize("use_sim_time", [False, True])
def test_diagnostics_are_named_for_the_node_and_stamped_with_its_clock(
    use_sim_time, ros_domain, ros_context, executor
):
    args = ["-r", "__ns:=/drone1", "-p", f"use_sim_time:={str(use_sim_time).lower()}"]
    proc, _ = start(ros_domain, *args, tag=f"diag-{use_sim_time}")
    try:
        diagnostics = diagnostics_of(
            proc, ros_context, executor, clock_sec=4242 if use_sim_time else None
        )
    finally:
        stop_gently(proc)
    [status] = diagnostics.status
    assert status.name == "/drone1/cstep_node: empowerment"
    assert status.hardware_id == "cf2x"  # the URDF's <robot name>
    stamp = diagnostics.header.stamp.sec + diagnostics.header.stamp.nanosec * 1e-9
    if use_sim_time:
        assert diagnostics.header.stamp.sec == 4242
    else:
        assert abs(stamp - time.time()) < 10  # the wall clock, no longer (0, 0)


def test_use_sim_time_set_while_running_switches_the_diagnostics_clock(
    ros_domain, ros_context, executor
):
    """`use_sim_time` is live (the parameter table): a set over the parameter services switches the
    diagnostics' stamps from the wall clock to the newest /clock and back, as rclcpp's time
    source does."""
    proc, log_path = start(ros_domain, tag="diag-live")
    node = Node("cstep_sim_time_probe", context=ros_context)
    executor.add_node(node)
    try:
        received: list[DiagnosticArray] = []
        node.create_subscription(DiagnosticArray, "/diagnostics", received.append, RELIABLE)
        clock = node.create_publisher(Clock, "/clock", 10)
        client = AsyncParameterClient(node, "/cstep_node")
        wait_until(client.services_are_ready, "the node's parameter services", executor)
        wait_until(lambda: bool(received), "diagnostics", executor)
        assert proc.poll() is None, log_path.read_text()

        def set_use_sim_time(on: bool) -> None:
            future = client.set_parameters([Parameter("use_sim_time", value=on)])
            wait_until(future.done, "set use_sim_time", executor)
            (result,) = future.result().results
            assert result.successful, result.reason

        def stamped_with(sec: int) -> bool:
            clock.publish(Clock(clock=Time(sec=sec, nanosec=5)))
            return any(d.header.stamp.sec == sec for d in received)

        # On the wall clock, a published /clock does not stamp the diagnostics.
        end = time.monotonic() + 2.5
        while time.monotonic() < end:
            assert not stamped_with(4242), "stamped with /clock before use_sim_time was set"
            executor.spin_once(timeout_sec=0.05)
        set_use_sim_time(True)
        wait_until(lambda: stamped_with(4242), "diagnostics stamped with /clock", executor, 15)
        set_use_sim_time(False)
        received.clear()
        wait_until(lambda: len(received) >= 2, "diagnostics after the switch back", executor)
        stamp = received[-1].header.stamp
        assert abs(stamp.sec + stamp.nanosec * 1e-9 - time.time()) < 10
    finally:
        node.destroy_node()
        stop_gently(proc)
