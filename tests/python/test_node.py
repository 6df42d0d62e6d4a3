"""`cstep node` against real rclpy over real DDS (localhost, a private domain per test)."""

import json
import math
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
from conftest import REPO, wait_until
from cstep_msgs.msg import EmpoweredReward, Empowerment
from cstep_msgs.srv import Evaluate
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import SetParameters
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

CONFIG = REPO / "config" / "cstep.yaml"
RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)


def message_to_ordereddict(message) -> dict:
    """A message as nested dicts and lists with the ROS field names (JSON-ready)."""
    if not hasattr(message, "get_fields_and_field_types"):
        if hasattr(message, "tolist"):  # numpy arrays (fixed-size fields), array.array
            return message.tolist()
        if isinstance(message, (list, tuple)):
            return [message_to_ordereddict(v) for v in message]
        return message
    return {
        name: message_to_ordereddict(getattr(message, name))
        for name in message.get_fields_and_field_types()
    }


def cstep_binary() -> Path:
    """The release binary `make test` builds (CSTEP_BIN overrides)."""
    if "CSTEP_BIN" in os.environ:
        return Path(os.environ["CSTEP_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "release" / "cstep"


@pytest.fixture
def cstep_node(ros_domain):
    """A live `cstep node` on this test's domain; interrupted, then killed, by its PID."""
    log_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"cstep-node-{ros_domain}.log"
    with open(log_path, "w") as log:
        proc = subprocess.Popen(
            [str(cstep_binary()), "node", "--config", str(CONFIG)],
            stdout=log,
            stderr=subprocess.STDOUT,
            cwd=REPO,
        )
        yield proc
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=5)


def corridor_scan(sec: int, width: float = 2.5, beams: int = 180) -> LaserScan:
    """A 360° scan from the middle of a corridor along x, 3 m range (the paper's LiDAR)."""
    scan = LaserScan()
    scan.header.stamp.sec = sec
    scan.header.frame_id = "base_link"
    scan.angle_min = -math.pi
    scan.angle_increment = 2 * math.pi / beams
    scan.angle_max = scan.angle_min + (beams - 1) * scan.angle_increment
    scan.range_min = 0.02
    scan.range_max = 3.0
    ranges = []
    for i in range(beams):
        s = abs(math.sin(scan.angle_min + i * scan.angle_increment))
        r = width / 2 / s if s > 1e-9 else math.inf
        ranges.append(r if r <= scan.range_max else math.inf)
    scan.ranges = ranges
    return scan


def odometry(vx: float = 0.5) -> Odometry:
    odom = Odometry()
    odom.header.frame_id = "odom"
    odom.child_frame_id = "base_link"
    odom.pose.pose.position.z = 1.0
    odom.pose.pose.orientation.w = 1.0
    odom.twist.twist.linear.x = vx
    return odom


class Rig:
    """This test's rclpy side: publishers of inputs, collectors of outputs."""

    def __init__(self, context, executor):
        self.node = Node("cstep_test_rig", context=context)
        executor.add_node(self.node)
        self.executor = executor
        self.odom = self.node.create_publisher(Odometry, "odom", RELIABLE)
        self.scan = self.node.create_publisher(LaserScan, "scan", qos_profile_sensor_data)
        self.empowerment: list[Empowerment] = []
        self.reward: list[EmpoweredReward] = []
        self.diagnostics: list[DiagnosticArray] = []
        self.node.create_subscription(
            Empowerment, "/cstep/empowerment", self.empowerment.append, RELIABLE
        )
        self.node.create_subscription(
            EmpoweredReward, "/cstep/reward", self.reward.append, RELIABLE
        )
        self.node.create_subscription(
            DiagnosticArray, "/diagnostics", self.diagnostics.append, RELIABLE
        )
        wait_until(
            lambda: (
                self.scan.get_subscription_count() >= 1
                and self.odom.get_subscription_count() >= 1
                and self.node.count_publishers("/cstep/reward") >= 1
            ),
            "the node's subscriptions and publishers",
            executor,
        )

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def feed(self, count: int, rate_hz: float = 20.0, first_sec: int = 1000, **odom) -> None:
        for k in range(count):
            self.odom.publish(odometry(**odom))
            self.scan.publish(corridor_scan(first_sec + k))
            self.spin_for(1.0 / rate_hz)

    def feed_until(self, condition, what: str, first_sec: int, timeout: float = 20.0) -> int:
        """Publish odometry and scans at 20 Hz until ``condition()``; returns the next stamp."""
        deadline = time.monotonic() + timeout
        sec = first_sec
        while not condition():
            if time.monotonic() > deadline:
                pytest.fail(f"timed out after {timeout:.0f} s feeding the node until {what}")
            self.feed(1, first_sec=sec)
            sec += 1
        return sec

    def warm_up(self) -> None:
        """Feed until the node has matched both ways (its first score arrives), then forget it."""
        self.feed_until(lambda: bool(self.reward), "the first score arrives", first_sec=1)
        self.spin_for(0.2)
        self.empowerment.clear()
        self.reward.clear()

    def status(self):
        return self.diagnostics[-1].status[0] if self.diagnostics else None


@pytest.fixture
def rig(cstep_node, ros_context, executor):
    r = Rig(ros_context, executor)
    r.warm_up()
    yield r
    r.node.destroy_node()


def test_every_scan_gets_both_outputs_with_its_stamp_and_cstep_eval_agrees(rig, tmp_path):
    rig.feed(40)
    rig.spin_for(1.0)
    stamps_e = {m.header.stamp.sec for m in rig.empowerment}
    stamps_r = {m.header.stamp.sec for m in rig.reward}
    both = stamps_e & stamps_r & set(range(1000, 1040))
    assert len(both) >= 36, f"only {len(both)} of 40 scans scored"
    for m in rig.empowerment + rig.reward:
        for name, value in message_to_ordereddict(m).items():
            if isinstance(value, float):
                assert math.isfinite(value), (name, m)
    assert all(m.valid and m.status == "ok" for m in rig.empowerment)
    assert all(m.header.frame_id == "odom" for m in rig.empowerment)

    # The same input through `cstep eval` gives the same numbers.
    (tmp_path / "odom.json").write_text(json.dumps(message_to_ordereddict(odometry())))
    scan = message_to_ordereddict(corridor_scan(1000))
    scan["ranges"] = [None if math.isinf(r) else r for r in scan["ranges"]]
    (tmp_path / "scan.json").write_text(json.dumps(scan))
    out = subprocess.run(
        [
            str(cstep_binary()),
            "eval",
            "--config",
            str(CONFIG),
            "--format",
            "json",
            "--odom",
            str(tmp_path / "odom.json"),
            "--scan",
            str(tmp_path / "scan.json"),
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    offline = json.loads(out.stdout)
    live = next(m for m in rig.empowerment if m.header.stamp.sec == 1000)
    assert offline["empowerment"] == pytest.approx(live.empowerment, abs=1e-12)
    assert offline["num_colliding"] == live.num_colliding
    live_reward = next(m for m in rig.reward if m.header.stamp.sec == 1000)
    assert offline["reward"] == pytest.approx(live_reward.reward, abs=1e-12)


def test_evaluate_service_answers_identically_and_rejects_a_zero_quaternion(rig):
    client = rig.node.create_client(Evaluate, "/cstep/evaluate")
    wait_until(lambda: client.service_is_ready(), "the evaluate service", rig.executor)

    def call(request):
        future = client.call_async(request)
        wait_until(future.done, "the evaluate reply", rig.executor)
        return future.result()

    request = Evaluate.Request(odom=odometry(), scan=corridor_scan(7))
    request.goal.x, request.goal.z, request.has_goal = 3.0, 1.0, True
    first, second = call(request), call(request)
    assert first.empowerment == second.empowerment
    assert first.reward == second.reward
    assert first.empowerment.valid and first.empowerment.header.stamp.sec == 7
    assert first.reward.task_reward == pytest.approx(math.exp(-3.0))

    bad = Evaluate.Request(odom=odometry(), scan=corridor_scan(8))
    bad.odom.pose.pose.orientation.w = 0.0
    answer = call(bad)
    assert not answer.empowerment.valid
    assert "zero quaternion" in answer.empowerment.status
    assert math.isfinite(answer.empowerment.empowerment)
    assert call(request).empowerment == first.empowerment  # still serving


def test_diagnostics_go_stale_when_inputs_stop_and_recover(rig):
    rig.feed_until(
        lambda: rig.status() is not None and rig.status().level == DiagnosticStatus.OK,
        "diagnostics report OK",
        first_sec=1000,
    )
    rig.spin_for(0.1)
    wait_until(
        lambda: rig.status().level == DiagnosticStatus.STALE,
        "diagnostics STALE",
        rig.executor,
        timeout=5,
    )
    assert "stale" in rig.status().message
    rig.feed_until(
        lambda: rig.status().level == DiagnosticStatus.OK, "diagnostics recover", first_sec=2000
    )
    values = {kv.key: kv.value for kv in rig.status().values}
    assert int(values["scans_scored"]) >= 10


def test_a_live_safety_coefficient_change_shows_in_the_next_reward(rig):
    client = rig.node.create_client(SetParameters, "/cstep_node/set_parameters")
    wait_until(lambda: client.service_is_ready(), "the parameter service", rig.executor)
    rig.feed(5)
    before = rig.reward[-1]
    assert before.safety_coefficient == 1.0
    value = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=0.5)
    future = client.call_async(
        SetParameters.Request(parameters=[Parameter(name="safety_coefficient", value=value)])
    )
    wait_until(future.done, "the parameter reply", rig.executor)
    assert future.result().results[0].successful
    rig.feed(5, first_sec=3000)
    after = next(m for m in rig.reward if m.header.stamp.sec >= 3000)
    assert after.safety_coefficient == 0.5
    assert after.empowerment_term == pytest.approx(before.empowerment_term + math.log(0.5))

    value = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=-1.0)
    future = client.call_async(
        SetParameters.Request(parameters=[Parameter(name="safety_coefficient", value=value)])
    )
    wait_until(future.done, "the parameter reply", rig.executor)
    assert not future.result().results[0].successful


def test_bad_inputs_are_skipped_and_counted_and_the_node_keeps_scoring(rig, cstep_node):
    short = corridor_scan(4000)
    short.ranges = short.ranges[:50]
    flat = corridor_scan(4001)
    flat.angle_increment = 0.0
    empty = corridor_scan(4002)
    empty.ranges = []
    huge = corridor_scan(4003, beams=150_000)
    for scan in (short, flat, empty, huge):
        rig.odom.publish(odometry())
        rig.scan.publish(scan)
        rig.spin_for(0.2)
    zero = odometry()
    zero.pose.pose.orientation.w = 0.0
    rig.odom.publish(zero)
    rig.scan.publish(corridor_scan(4004))
    nan = odometry()
    nan.pose.pose.position.x = math.nan
    rig.odom.publish(nan)
    rig.scan.publish(corridor_scan(4005))
    rig.spin_for(0.5)
    rig.feed(10, first_sec=5000)
    rig.spin_for(1.5)

    assert cstep_node.poll() is None, "the node died"
    stamps = {m.header.stamp.sec for m in rig.empowerment}
    assert {4000, 4001, 4004, 4005}.isdisjoint(stamps), "malformed input was scored"
    empty_out = [m for m in rig.empowerment if m.header.stamp.sec == 4002]
    assert all(not m.valid and m.status == "scan has no beams" for m in empty_out)
    assert len(stamps & set(range(5000, 5010))) >= 9, "scoring did not resume"
    for m in rig.empowerment:
        assert math.isfinite(m.empowerment)
    values = {kv.key: kv.value for kv in rig.status().values}
    assert int(values["inputs_rejected"]) >= 4
