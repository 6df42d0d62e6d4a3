"""Measures a discovery defect between RustDDS and Fast DDS (not a test: run it by hand).

Two `cstep node`s in two namespaces, started within milliseconds of each other and of an rclpy
(Fast DDS) participant, used to stay partly or wholly undiscovered by Fast DDS for good now and
then: rclpy never listed a node, or listed it without its subscriptions, although Fast DDS
acknowledged all of the node's SEDP samples (seen on the loopback interface). The fix holds a
discovery writer's pushes until the remote reader has acknacked (vendor/rustdds/CSTEP_PATCH.md,
section 4). Measured with this script on 2 cores, `UNPATCHED` the binary built from bac5ded
(the commit before the fix), `PATCHED` from 4d7105f, 15 s to discover (``--wait 15``):

    R=".venv/bin/python tests/python/repro_simultaneous_start.py --wait 15"
    $R --cstep $UNPATCHED --cstep $PATCHED --runs 20  # idle: 5 of 20 against 0 of 20
    # beside 3 busy loops (`sh -c 'while :; do :; done' &` three times):
    $R --cstep $UNPATCHED --cstep $PATCHED --runs 40  # 5 of 40 against 0 of 40
    $R --cstep $UNPATCHED --rclpy-after 3 --runs 25   # rclpy 3 s after the nodes: 0 of 25
    $R --cstep $UNPATCHED --rclpy-before 3 --runs 25  # rclpy up 3 s before them: 2 of 25
    $R --cstep $UNPATCHED --nodes 1 --runs 40         # one node: 0 of 40

Discovery is not slower with the fix: 0.10-0.21 s, median 0.20, against 0.05-0.21 s, median
0.21, under load (idle: 0.20 against 0.20).

Localhost-only discovery on a domain of its own (``--domain``, default 52).
"""

import argparse
import os
import statistics
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent / "py_bridge"))

ROBOTS = (("/drone1", 0.5), ("/drone2", 2.0))


def one_start(args, binary: str | None) -> tuple[float | None, str]:
    """One start of the nodes (``binary``, or the one cstep_bridge finds) and the rclpy side:
    the seconds from the rig's endpoints to every node fully discovered, or None with what rclpy
    saw of each namespace after ``args.wait`` seconds."""
    import rclpy
    from cstep_bridge.resources import config_file, cstep_binary
    from cstep_msgs.msg import EmpoweredReward
    from nav_msgs.msg import Odometry
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    robots = ROBOTS[: args.nodes]
    context = Context()
    if args.rclpy_before:
        rclpy.init(context=context, domain_id=args.domain)
        time.sleep(args.rclpy_before)
    nodes = [
        subprocess.Popen(
            [str(cstep_binary(binary)), "node", "--config", str(config_file()), "--ros-args"]
            + ["-r", f"__ns:={namespace}", "-p", f"safety_coefficient:={coefficient}"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        for namespace, coefficient in robots
    ]
    try:
        if not args.rclpy_before:
            time.sleep(args.rclpy_after)
            rclpy.init(context=context, domain_id=args.domain)
        executor = SingleThreadedExecutor(context=context)
        rigs = []
        for namespace, _ in robots:
            node = Node("repro_rig", namespace=namespace, context=context)
            executor.add_node(node)
            odom = node.create_publisher(Odometry, "odom", reliable)
            node.create_subscription(EmpoweredReward, "cstep/reward", lambda _: None, reliable)
            rigs.append((namespace, node, odom))

        def seen() -> dict:
            return {
                ns: (odom.get_subscription_count(), node.count_publishers(f"{ns}/cstep/reward"))
                for ns, node, odom in rigs
            }

        start = time.monotonic()
        while time.monotonic() < start + args.wait:
            executor.spin_once(timeout_sec=0.05)
            if all(min(counts) >= 1 for counts in seen().values()):
                return time.monotonic() - start, ""
        return None, f"(odom subscribers, reward publishers) per namespace: {seen()}"
    finally:
        for proc in nodes:
            proc.terminate()
            proc.wait(timeout=10)
        context.try_shutdown()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--domain", type=int, default=52)
    parser.add_argument("--nodes", type=int, choices=(1, 2), default=2)
    parser.add_argument("--wait", type=float, default=20.0, help="seconds to wait per start")
    parser.add_argument("--rclpy-after", type=float, default=0.0, help="rclpy joins this late")
    parser.add_argument("--rclpy-before", type=float, default=0.0, help="rclpy is up this early")
    parser.add_argument(
        "--cstep",
        action="append",
        help="a cstep binary; given several times, the starts alternate between them",
    )
    args = parser.parse_args()
    os.environ.update(
        ROS_DOMAIN_ID=str(args.domain),
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
    )
    binaries = args.cstep or [None]
    found: dict[str | None, list[float]] = defaultdict(list)
    failed: dict[str | None, int] = defaultdict(int)
    for run in range(1, args.runs + 1):
        for binary in binaries:
            seconds, missing = one_start(args, binary)
            if seconds is None:
                failed[binary] += 1
                print(f"start {run} ({binary or 'cstep'}): not discovered: {missing}", flush=True)
            else:
                found[binary].append(seconds)
    for binary in binaries:
        times = found[binary]
        timing = (
            f"; discovered in {min(times):.2f}-{max(times):.2f} s, median "
            f"{statistics.median(times):.2f}"
            if times
            else ""
        )
        print(
            f"{binary or 'cstep'}: {failed[binary]} of {args.runs} starts left a node "
            f"undiscovered{timing}"
        )


if __name__ == "__main__":
    main()
