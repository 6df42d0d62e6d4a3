"""The live-node test rig, shared by the tests that drive `cstep node` (a pytest plugin).

``conftest.py`` loads this module as a plugin, so its fixtures (``cstep_node``, ``rig``,
``echo``) are available to every test; its helpers (``Rig``, ``Echo``, ``start_node``,
``corridor_scan``, ``odometry``, ``message_to_ordereddict``, and ``cstep_binary`` from
:mod:`cstep_bridge.resources`) are imported from it.
"""

import json
import math
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
import yaml
from conftest import REPO, wait_until
from corridor_inputs import corridor_scan, odometry
from cstep_bridge.resources import config_file, cstep_binary
from cstep_msgs.msg import EmpoweredReward, Empowerment
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

CONFIG = config_file()
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


def start_node(*params: str) -> subprocess.Popen:
    """`cstep node` on this test's domain (``ROS_DOMAIN_ID``) with ``-p`` for each of
    ``params`` (``name:=value``); its log in TMPDIR, named by the domain."""
    ros_args = ["--ros-args", *(arg for p in params for arg in ("-p", p))] if params else []
    domain = os.environ.get("ROS_DOMAIN_ID", "0")
    log = Path(os.environ.get("TMPDIR", "/tmp")) / f"cstep-node-{domain}.log"
    with open(log, "w") as out:
        return subprocess.Popen(
            [str(cstep_binary()), "node", "--config", str(CONFIG), *ros_args],
            stdout=out,
            stderr=subprocess.STDOUT,
            cwd=REPO,
        )


@pytest.fixture
def cstep_node(ros_domain):
    """A live `cstep node` on this test's domain; interrupted, then killed, by its PID."""
    proc = start_node()
    yield proc
    stop_gently(proc)


def stop_gently(proc: subprocess.Popen) -> None:
    """Stops a node as Ctrl-C does (it shuts down cleanly), killing it if it has not ended 5 s
    later; nothing when it has ended already."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)


def cstep_eval(tmp_path, odom, scan, goal=None, params: dict[str, str] | None = None) -> dict:
    """`cstep eval --format json` on these messages (written as rosbridge-style JSON), with
    ``params`` overriding config/cstep.yaml as a node's ``-p name:=value`` would."""
    (tmp_path / "odom.json").write_text(json.dumps(message_to_ordereddict(odom)))
    s = message_to_ordereddict(scan)
    s["ranges"] = [None if math.isinf(r) else r for r in s["ranges"]]
    (tmp_path / "scan.json").write_text(json.dumps(s))
    command = [str(cstep_binary()), "eval", "--config", str(CONFIG), "--format", "json"]
    command += ["--odom", str(tmp_path / "odom.json"), "--scan", str(tmp_path / "scan.json")]
    if goal is not None:
        # One argument, `--goal=X,Y,Z`: a separate value starting with "-" would read as a flag.
        command.append("--goal=" + ",".join(repr(float(g)) for g in goal))
    for name, value in (params or {}).items():
        command += ["-p", f"{name}:={value}"]
    out = subprocess.run(command, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


class Rig:
    """This test's rclpy side: publishers of inputs, collectors of outputs."""

    def __init__(self, context, executor, namespace: str = "/"):
        """A rig for the node in ``namespace``: its topics are the rig's relative names there."""
        self.node = Node("cstep_test_rig", namespace=namespace, context=context)
        executor.add_node(self.node)
        self.executor = executor
        self.odom = self.node.create_publisher(Odometry, "odom", RELIABLE)
        self.scan = self.node.create_publisher(LaserScan, "scan", qos_profile_sensor_data)
        self.empowerment: list[Empowerment] = []
        self.reward: list[EmpoweredReward] = []
        self.diagnostics: list[DiagnosticArray] = []
        # The node scores scans only while someone subscribes to a score topic.
        self.score_subscriptions = [
            self.node.create_subscription(
                Empowerment, "cstep/empowerment", self.empowerment.append, RELIABLE
            ),
            self.node.create_subscription(
                EmpoweredReward, "cstep/reward", self.reward.append, RELIABLE
            ),
        ]
        self.node.create_subscription(
            DiagnosticArray, "/diagnostics", self.diagnostics.append, RELIABLE
        )
        reward = self.node.resolve_topic_name("cstep/reward")
        wait_until(
            lambda: (
                self.scan.get_subscription_count() >= 1
                and self.odom.get_subscription_count() >= 1
                and self.node.count_publishers(reward) >= 1
            ),
            lambda: (
                "the node's subscriptions and publishers (matched subscribers of "
                f"{self.scan.topic_name}: {self.scan.get_subscription_count()}, of "
                f"{self.odom.topic_name}: {self.odom.get_subscription_count()}; publishers of "
                f"{reward}: {self.node.count_publishers(reward)}; nodes seen: "
                f"{self.node.get_node_names_and_namespaces()})"
            ),
            executor,
        )

    def spin_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.01)

    def feed(
        self, count: int, rate_hz: float = 20.0, first_sec: int = 1000, width: float = 2.5, **odom
    ) -> None:
        """Publish ``count`` odometries and corridor scans (``width`` m wide) at ``rate_hz``."""
        for k in range(count):
            self.odom.publish(odometry(**odom))
            self.scan.publish(corridor_scan(first_sec + k, width=width))
            self.spin_for(1.0 / rate_hz)

    def feed_until(
        self, condition, what: str, first_sec: int, timeout: float = 20.0, **odom
    ) -> int:
        """Publish odometry and scans at 20 Hz until ``condition()``; returns the next stamp."""
        deadline = time.monotonic() + timeout
        sec = first_sec
        while not condition():
            if time.monotonic() > deadline:
                pytest.fail(f"timed out after {timeout:.0f} s feeding the node until {what}")
            self.feed(1, first_sec=sec, **odom)
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

    def values(self) -> dict[str, str]:
        """The key-values of the newest diagnostics."""
        status = self.status()
        return {kv.key: kv.value for kv in status.values} if status else {}

    def next_diagnostics(self, count: int = 1) -> dict[str, str]:
        """Spin until ``count`` more diagnostics arrive; their newest key-values."""
        seen = len(self.diagnostics)
        wait_until(
            lambda: len(self.diagnostics) >= seen + count, "diagnostics", self.executor, timeout=5
        )
        return self.values()


@pytest.fixture
def rig(cstep_node, ros_context, executor):
    r = Rig(ros_context, executor)
    r.warm_up()
    yield r
    r.node.destroy_node()


class Echo:
    """A `cstep echo` process this test started; killed by its PID if still running."""

    def __init__(self, *args: str, env: dict[str, str] | None = None) -> None:
        self.proc = subprocess.Popen(
            [str(cstep_binary()), "echo", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=REPO,
            env=env,
        )
        self.stdout = ""
        self.stderr = ""

    def running(self) -> bool:
        return self.proc.poll() is None

    def finish(self, timeout: float = 10.0) -> int:
        try:
            self.stdout, self.stderr = self.proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail(f"cstep echo did not exit within {timeout:.0f} s")
        return self.proc.returncode

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # by PID: this very process
        self.stdout, self.stderr = self.proc.communicate(timeout=10)

    def documents(self) -> list:
        """The YAML documents printed (the stream ends with `---`, an empty last document)."""
        return [d for d in yaml.safe_load_all(self.stdout) if d is not None]


@pytest.fixture
def echo():
    """Start `cstep echo` processes; every one still running is killed when the test ends."""
    started: list[Echo] = []

    def start(*args: str, **kwargs) -> Echo:
        e = Echo(*args, **kwargs)
        started.append(e)
        return e

    yield start
    for e in started:
        if e.running():
            e.kill()
