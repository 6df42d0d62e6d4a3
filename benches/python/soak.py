"""Soak: 1080-beam scans at 200 Hz into a live `cstep node` for 10 minutes: `make soak`.

rclpy publishes odometry and a 1080-beam corridor scan at ``--rate`` Hz (200) for ``--duration``
seconds (600) to a node on a private domain, localhost only, while subscribing to its scores.
Prints the node's resident memory every ``--every`` seconds, and at the end the accounting —
every scan sent was scored or skipped by the node (newest scan wins; skipped ones were replaced
before the scorer got to them) or lost on the way (the scan topic is best-effort, REP 2003) — and
the scan → score latency (p50, p99) of the scans that were scored. Exits 1 if the node's counts
do not add up (scored + skipped + stale + rejected = received ≤ sent), if a score was published
that did not arrive, or if the node died.
"""

import argparse
import sys
import time

from cstep_msgs.msg import Empowerment
from diagnostic_msgs.msg import DiagnosticArray
from live_node import RELIABLE, Feeder, LiveNode, diagnostic_values, quantile, use_private_domain

COUNTS = ("scans_scored", "scans_skipped", "scans_stale", "inputs_rejected", "scans_unwatched")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=600.0, help="seconds of load (600)")
    parser.add_argument("--rate", type=float, default=200.0, help="scans per second (200)")
    parser.add_argument("--beams", type=int, default=1080)
    parser.add_argument("--every", type=float, default=30.0, help="RSS sample period, s (30)")
    args = parser.parse_args()
    domain = use_private_domain()
    with LiveNode() as node:
        feeder = Feeder("cstep_soak", beams=args.beams)
        try:
            print(f"soak: ROS_DOMAIN_ID {domain}, node pid {node.proc.pid}", flush=True)
            return soak(node, feeder, args)
        finally:
            feeder.close()


def soak(node: LiveNode, feeder: Feeder, args) -> int:
    sent: dict[int, float] = {}
    latency_ms: list[float] = []
    diagnostics: list[dict[str, str]] = []

    def on_score(m: Empowerment) -> None:
        t = sent.pop(m.header.stamp.sec, None)
        if t is not None:
            latency_ms.append((time.perf_counter() - t) * 1e3)

    feeder.node.create_subscription(Empowerment, "/cstep/empowerment", on_score, RELIABLE)
    feeder.node.create_subscription(
        DiagnosticArray,
        "/diagnostics",
        lambda d: diagnostics.append(diagnostic_values(d)),
        RELIABLE,
    )
    feeder.wait_for_node()
    feeder.wait_for(lambda: bool(diagnostics), "the node's diagnostics")
    before = {key: int(diagnostics[-1][key]) for key in COUNTS}
    rss = [(0.0, node.rss_mib())]
    print("     t (s)   RSS (MiB)   scans sent   scores received", flush=True)
    print(f"{0:10.0f} {rss[0][1]:11.1f} {0:12d} {0:17d}", flush=True)
    period = 1.0 / args.rate
    total = round(args.duration * args.rate)
    start = time.perf_counter()
    next_sample = args.every
    for k in range(1, total + 1):
        sent[k] = feeder.send(k)
        feeder.spin_for(start + k * period - time.perf_counter())
        now = time.perf_counter() - start
        if now >= next_sample:
            rss.append((now, node.rss_mib()))
            print(f"{now:10.0f} {rss[-1][1]:11.1f} {k:12d} {len(latency_ms):17d}", flush=True)
            next_sample += args.every
    elapsed = time.perf_counter() - start
    # Two diagnostics after the last scan: the node has scored or dropped everything by then.
    seen = len(diagnostics)
    feeder.wait_for(lambda: len(diagnostics) >= seen + 2, "the final diagnostics")
    rss.append((time.perf_counter() - start, node.rss_mib()))
    if node.proc.poll() is not None:
        print(f"the node exited ({node.proc.returncode})")
        return 1
    final = diagnostics[-1]
    counts = {key: int(final[key]) - before[key] for key in COUNTS}
    received = sum(counts.values())
    scored, skipped = counts["scans_scored"], counts["scans_skipped"]
    print(f"sent {total} scans of {args.beams} beams in {elapsed:.1f} s ({total / elapsed:.1f} Hz)")
    print(
        f"node: received {received} = scored {scored} + skipped {skipped} + stale "
        f"{counts['scans_stale']} + rejected {counts['inputs_rejected']} + unwatched "
        f"{counts['scans_unwatched']}; lost on the way (best-effort scan topic): {total - received}"
    )
    print(f"scored + skipped = {scored + skipped} of {total} sent")
    print(f"scores received by the subscriber: {len(latency_ms)} (node published {scored})")
    rss_values = [r for _, r in rss]
    print(
        f"node RSS: start {rss_values[0]:.1f} MiB, end {rss_values[-1]:.1f} MiB, "
        f"max {max(rss_values):.1f} MiB; after the first sample: "
        f"{rss_values[1] if len(rss_values) > 1 else rss_values[0]:.1f} -> {rss_values[-1]:.1f} MiB"
    )
    if latency_ms:
        print(
            f"scan -> score latency: p50 {quantile(latency_ms, 0.5):.2f} ms, "
            f"p99 {quantile(latency_ms, 0.99):.2f} ms, max {max(latency_ms):.2f} ms"
        )
    ok = received <= total and len(latency_ms) == scored and scored > 0
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
