"""Scan → score latency of `cstep node` over real DDS: `make bench-latency`.

rclpy publishes odometry and a 180-beam corridor scan at 40 Hz to a live node (default
150-trajectory quadrotor) on a private domain, localhost only, and times each scan's
`/cstep/empowerment` arriving back. The node's own evaluation time comes from its diagnostics;
what is left is the cost of the ROS path (serialization, DDS, scheduling). Prints medians and
p99 over `--scans` scans (after a warm-up).
"""

import argparse
import math
import statistics
import sys
import time

from cstep_msgs.msg import Empowerment
from diagnostic_msgs.msg import DiagnosticArray
from live_node import RELIABLE, Feeder, LiveNode, diagnostic_values, quantile, use_private_domain


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scans", type=int, default=400)
    parser.add_argument("--rate", type=float, default=40.0)
    args = parser.parse_args()
    use_private_domain()
    with LiveNode():
        feeder = Feeder("cstep_latency_bench")
        try:
            return run(feeder, args.scans, args.rate)
        finally:
            feeder.close()


def run(feeder: Feeder, scans: int, rate: float) -> int:
    sent: dict[int, float] = {}
    latency_ms: dict[int, float] = {}
    eval_us: list[float] = []

    def on_score(m: Empowerment) -> None:
        k = m.header.stamp.sec
        if k in sent:
            latency_ms[k] = (time.perf_counter() - sent[k]) * 1e3

    def on_diagnostics(d: DiagnosticArray) -> None:
        values = diagnostic_values(d)
        if values.get("evaluation_time_us", "0") != "0":
            eval_us.append(float(values["evaluation_time_us"]))

    feeder.node.create_subscription(Empowerment, "/cstep/empowerment", on_score, RELIABLE)
    feeder.node.create_subscription(DiagnosticArray, "/diagnostics", on_diagnostics, RELIABLE)
    feeder.wait_for_node()
    period = 1.0 / rate
    warmup = 40
    start = time.perf_counter()
    for k in range(1, warmup + scans + 1):
        sent[k] = feeder.send(k)
        feeder.spin_for(start + k * period - time.perf_counter())
    feeder.spin_for(1.5)
    measured = [latency_ms[k] for k in range(warmup + 1, warmup + scans + 1) if k in latency_ms]
    if not measured or not eval_us:
        print("no scores or no diagnostics arrived", file=sys.stderr)
        return 1
    evaluation_ms = statistics.median(eval_us) / 1e3
    overhead = [m - evaluation_ms for m in measured]
    print(f"scans: {scans} at {rate:.0f} Hz, scored {len(measured)}")
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


if __name__ == "__main__":
    sys.exit(main())
