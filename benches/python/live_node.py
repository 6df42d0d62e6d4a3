"""What the node benchmarks over real DDS share: a live `cstep node` on a private domain, an
rclpy node to talk to it, feeding it, waiting for discovery, and quantiles.

Used by ``bench_latency.py`` (`make bench-latency`), ``bench_stale.py`` (`make bench-stale`) and
``soak.py`` (`make soak`). Everything stays on this machine: localhost-only discovery, on
``ROS_DOMAIN_ID`` if set, else a domain offset from this process id.
"""

from __future__ import annotations

import array
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Self

import rclpy
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "python"))

from node_rig import CONFIG, corridor_scan, cstep_binary, odometry, stop_gently

RELIABLE = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
DISCOVERY_TIMEOUT_S = 20.0


def quantile(values: list[float], q: float) -> float:
    """The ``q`` quantile of ``values`` (nearest rank)."""
    ordered = sorted(values)
    return ordered[round((len(ordered) - 1) * q)]


def use_private_domain() -> int:
    """Sets this process's ROS domain (``ROS_DOMAIN_ID`` if set, else one offset from the
    process id) and localhost-only discovery, inherited by the node it starts; returns the id."""
    os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    os.environ.pop("ROS_STATIC_PEERS", None)
    return int(os.environ["ROS_DOMAIN_ID"])


class LiveNode:
    """`cstep node --config CONFIG` on this process's domain; interrupted, then killed, by its PID
    when the ``with`` block ends."""

    def __init__(self, *ros_args: str) -> None:
        args = [str(cstep_binary()), "node", "--exit-with-parent", "--config", str(CONFIG)]
        if ros_args:
            args += ["--ros-args", *ros_args]
        self.proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def rss_mib(self) -> float:
        """The node's resident set size now (MiB), from /proc."""
        for line in Path(f"/proc/{self.proc.pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
        raise RuntimeError(f"no VmRSS for the node (pid {self.proc.pid}): has it exited?")

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *_exc) -> None:
        stop_gently(self.proc)


class Feeder:
    """An rclpy node that publishes odometry and a corridor scan of ``beams`` beams to the node,
    each scan stamped with its own whole second ``k`` (so answers are matched by stamp)."""

    def __init__(self, name: str, beams: int = 180) -> None:
        rclpy.init()
        self.node: Node = rclpy.create_node(name)
        self.odom_pub = self.node.create_publisher(Odometry, "odom", RELIABLE)
        self.scan_pub = self.node.create_publisher(LaserScan, "scan", qos_profile_sensor_data)
        self.odom = odometry()
        self.scan = corridor_scan(0, beams=beams)
        # float32 as the field is; an array.array skips rclpy's per-element checks.
        self.scan.ranges = array.array("f", self.scan.ranges)

    def send(self, k: int, odom: bool = True) -> float:
        """Publishes the odometry (unless ``odom`` is false), then the scan stamped ``k`` s;
        returns the ``time.perf_counter()`` at which the scan went out."""
        if odom:
            self.odom_pub.publish(self.odom)
        self.scan.header.stamp.sec = k
        sent = time.perf_counter()
        self.scan_pub.publish(self.scan)
        return sent

    def spin_for(self, seconds: float) -> None:
        end = time.perf_counter() + seconds
        while time.perf_counter() < end:
            rclpy.spin_once(self.node, timeout_sec=min(0.01, max(end - time.perf_counter(), 0)))

    def wait_for(self, condition: Callable[[], bool], what: str) -> None:
        """Spins until ``condition()``; exits with an error after the discovery timeout."""
        deadline = time.monotonic() + DISCOVERY_TIMEOUT_S
        while not condition():
            if time.monotonic() > deadline:
                sys.exit(f"timed out after {DISCOVERY_TIMEOUT_S:.0f} s waiting for {what}")
            rclpy.spin_once(self.node, timeout_sec=0.05)

    def wait_for_node(self, output: str = "/cstep/empowerment") -> None:
        """Until the node's scan and odometry subscriptions and its ``output`` publisher have
        matched this node's."""
        self.wait_for(
            lambda: (
                self.scan_pub.get_subscription_count() >= 1
                and self.odom_pub.get_subscription_count() >= 1
                and self.node.count_publishers(output) >= 1
            ),
            "the cstep node on DDS",
        )

    def close(self) -> None:
        self.node.destroy_node()
        rclpy.try_shutdown()


def diagnostic_values(msg) -> dict[str, str]:
    """The key-values of a cstep diagnostics message."""
    return {kv.key: kv.value for kv in msg.status[0].values}
