"""How long after odometry stops the node's diagnostics say STALE: `make bench-stale`.

rclpy feeds a live node (defaults: ``input_timeout`` 0.5 s, diagnostics every second) odometry
and scans at 20 Hz on a private domain, localhost only, until its diagnostics are OK; then stops
the odometry (scans go on) at a random phase of the node's diagnostics period and times the
first diagnostics message at level STALE against the last odometry sent. Repeats ``--repeats``
times and prints each delay, their median and range, and the bound the node promises:
``input_timeout`` + one diagnostics period (1.5 s with the defaults).
"""

import argparse
import random
import statistics
import sys
import time

from cstep_msgs.msg import Empowerment
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from live_node import RELIABLE, Feeder, LiveNode, use_private_domain

INPUT_TIMEOUT_S = 0.5  # config/cstep.yaml
DIAGNOSTICS_PERIOD_S = 1.0
FEED_HZ = 20.0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    use_private_domain()
    rng = random.Random(args.seed)
    with LiveNode():
        feeder = Feeder("cstep_stale_bench")
        try:
            delays = [measure(feeder, rng) for _ in range(args.repeats)] if ready(feeder) else []
        finally:
            feeder.close()
    if not delays:
        return 1
    bound = INPUT_TIMEOUT_S + DIAGNOSTICS_PERIOD_S
    print("odometry stopped -> STALE (s): " + ", ".join(f"{d:.3f}" for d in delays))
    print(
        f"median {statistics.median(delays):.3f} s, range {min(delays):.3f}-{max(delays):.3f} s "
        f"over {len(delays)} repeats; bound input_timeout + one period = {bound:.1f} s"
    )
    return 0 if max(delays) <= bound else 1


levels: list[tuple[float, int]] = []  # (arrival, level) of every diagnostics message


def ready(feeder: Feeder) -> bool:
    feeder.node.create_subscription(
        DiagnosticArray,
        "/diagnostics",
        lambda d: levels.append((time.perf_counter(), d.status[0].level)),
        RELIABLE,
    )
    # A score subscriber, so that the node scores (its OK state).
    feeder.node.create_subscription(Empowerment, "/cstep/empowerment", lambda _: None, RELIABLE)
    feeder.wait_for_node()
    return True


def feed_until(feeder: Feeder, condition, odom: bool, limit_s: float = 20.0) -> float:
    """Feeds at 20 Hz (odometry only if ``odom``) until ``condition()``; returns the time the
    last odometry went out."""
    last_odom = time.perf_counter()
    deadline = last_odom + limit_s
    k = 0
    while not condition():
        if time.perf_counter() > deadline:
            sys.exit(f"no change of diagnostics within {limit_s:.0f} s")
        k += 1
        feeder.send(k, odom=odom)
        if odom:
            last_odom = time.perf_counter()
        feeder.spin_for(1 / FEED_HZ)
    return last_odom


def measure(feeder: Feeder, rng: random.Random) -> float:
    """One stop of the odometry: the delay (s) from the last odometry to the STALE report."""
    seen = len(levels)
    feed_until(feeder, lambda: any(lv == DiagnosticStatus.OK for _, lv in levels[seen:]), True)
    # A random phase against the node's once-a-second diagnostics.
    until = time.perf_counter() + rng.uniform(0.0, DIAGNOSTICS_PERIOD_S)
    stopped = feed_until(feeder, lambda: time.perf_counter() >= until, True)
    seen = len(levels)
    feed_until(feeder, lambda: any(lv == DiagnosticStatus.STALE for _, lv in levels[seen:]), False)
    arrived = next(t for t, lv in levels[seen:] if lv == DiagnosticStatus.STALE)
    return arrived - stopped


if __name__ == "__main__":
    sys.exit(main())
