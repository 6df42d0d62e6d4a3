"""Scan → score latency of `cstep node` over real DDS: `make bench-latency`.

rclpy publishes odometry and a 180-beam corridor scan at 40 Hz to a live node (default
150-trajectory quadrotor) on a private domain, localhost only, and times each scan's
`/cstep/empowerment` arriving back. The node's own evaluation time comes from its diagnostics;
what is left is the cost of the ROS path (serialization, DDS, scheduling). Prints medians and
p99 over `--scans` scans (after a warm-up).
"""

import argparse
import math
import os
import signal
import statistics
import subprocess
import sys
import time
from pathlib import Path

import rclpy
from cstep_msgs.msg import Empowerment
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "python"))
from nav_msgs.msg import Odometry
from node_rig import CONFIG, corridor_scan, cstep_binary, odometry
from sensor_msgs.msg import LaserScan


def quantile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[round((len(ordered) - 1) * q)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", type=int, default=400)
    parser.add_argument("--rate", type=float, default=40.0)
    args = parser.parse_args()
    os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    node_proc = subprocess.Popen(
        [str(cstep_binary()), "node", "--config", str(CONFIG)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    rclpy.init()
    node = rclpy.create_node("cstep_latency_bench")
    try:
        reliable = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        odom_pub = node.create_publisher(Odometry, "odom", reliable)
        scan_pub = node.create_publisher(LaserScan, "scan", qos_profile_sensor_data)
        sent: dict[int, float] = {}
        latency_ms: dict[int, float] = {}
        eval_us: list[float] = []

        def on_score(m: Empowerment) -> None:
            k = m.header.stamp.sec
            if k in sent:
                latency_ms[k] = (time.perf_counter() - sent[k]) * 1e3

        def on_diagnostics(d: DiagnosticArray) -> None:
            values = {kv.key: kv.value for kv in d.status[0].values}
            if values.get("evaluation_time_us", "0") != "0":
                eval_us.append(float(values["evaluation_time_us"]))

        node.create_subscription(Empowerment, "/cstep/empowerment", on_score, reliable)
        node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, reliable)
        deadline = time.monotonic() + 20
        while scan_pub.get_subscription_count() == 0 or not node.count_publishers(
            "/cstep/empowerment"
        ):
            if time.monotonic() > deadline:
                print("the node did not appear on DDS within 20 s", file=sys.stderr)
                return 1
            rclpy.spin_once(node, timeout_sec=0.05)
        period = 1.0 / args.rate
        warmup = 40
        start = time.perf_counter()
        for k in range(1, warmup + args.scans + 1):
            odom_pub.publish(odometry())
            scan = corridor_scan(k)
            sent[k] = time.perf_counter()
            scan_pub.publish(scan)
            while time.perf_counter() < start + k * period:
                rclpy.spin_once(node, timeout_sec=0.001)
        end = time.perf_counter() + 1.5
        while time.perf_counter() < end:
            rclpy.spin_once(node, timeout_sec=0.01)
        measured = [
            latency_ms[k] for k in range(warmup + 1, warmup + args.scans + 1) if k in latency_ms
        ]
        if not measured or not eval_us:
            print("no scores or no diagnostics arrived", file=sys.stderr)
            return 1
        evaluation_ms = statistics.median(eval_us) / 1e3
        overhead = [m - evaluation_ms for m in measured]
        print(f"scans: {args.scans} at {args.rate:.0f} Hz, scored {len(measured)}")
        print(f"evaluation (node diagnostics, median): {evaluation_ms:.2f} ms")
        print(
            f"scan -> score latency: p50 {quantile(measured, 0.5):.2f} ms, "
            f"p99 {quantile(measured, 0.99):.2f} ms"
        )
        print(
            f"above the evaluation: p50 {quantile(overhead, 0.5):.2f} ms, "
            f"p99 {quantile(overhead, 0.99):.2f} ms"
        )
        return 0 if math.isfinite(quantile(measured, 0.99)) else 1
    finally:
        node.destroy_node()
        rclpy.shutdown()
        node_proc.send_signal(signal.SIGINT)
        try:
            node_proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            node_proc.kill()


if __name__ == "__main__":
    sys.exit(main())
