"""Measures a discovery defect between RustDDS and Fast DDS (not a test: run it by hand).

Two `cstep node`s in two namespaces, started within milliseconds of each other and of an rclpy
(Fast DDS) participant, used to stay partly or wholly undiscovered by Fast DDS for good now and
then: rclpy never listed a node, or listed it without its subscriptions, although Fast DDS
acknowledged all of the node's SEDP samples (seen on the loopback interface). The fix holds a
discovery writer's pushes until the remote reader has acknacked (vendor/rustdds/CSTEP_PATCH.md,
section 4, with the figures). Measured before it on 2 cores with 3 busy loops beside it
(`sh -c 'while :; do :; done'`): 3 of 24 starts (2 of 25 with this script); 0 of 25 when rclpy
joins 3 s after the nodes (``--rclpy-after 3``); 1 of 25 when rclpy is up 3 s before them
(``--rclpy-before 3``); 0 of 40 with one node (``--nodes 1``). With it: 0 of 40, three times.

    .venv/bin/python tests/python/repro_simultaneous_start.py --runs 20

Localhost-only discovery on a domain of its own (``--domain``, default 52).
"""

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent.parent / "py_bridge"))

ROBOTS = (("/drone1", 0.5), ("/drone2", 2.0))


def one_start(args) -> str | None:
    """One start of the nodes and the rclpy side; None when every node is fully discovered
    within ``args.wait`` seconds, else what rclpy saw of each namespace."""
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
            [str(cstep_binary()), "node", "--config", str(config_file()), "--ros-args"]
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

        deadline = time.monotonic() + args.wait
        while time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
            if all(min(counts) >= 1 for counts in seen().values()):
                return None
        return f"(odom subscribers, reward publishers) per namespace: {seen()}"
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
    args = parser.parse_args()
    os.environ.update(
        ROS_DOMAIN_ID=str(args.domain),
        ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
        RMW_IMPLEMENTATION="rmw_fastrtps_cpp",
    )
    failures = 0
    for run in range(1, args.runs + 1):
        missing = one_start(args)
        if missing:
            failures += 1
            print(f"start {run}: not discovered: {missing}", flush=True)
    print(f"{failures} of {args.runs} starts left a node undiscovered")


if __name__ == "__main__":
    main()
