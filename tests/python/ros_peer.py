"""A second ROS process for the end-to-end tests, so data really crosses DDS between processes.

It inherits the test's ``ROS_DOMAIN_ID`` and ``ROS_AUTOMATIC_DISCOVERY_RANGE`` and speaks on
stdout, one line per event:

    ros_peer.py echo-empowerment TOPIC
        Subscribes to TOPIC (cstep_msgs/Empowerment, reliable, transient-local), prints
        ``ready`` once it sees a publisher, then ``received {json}`` for the first message
        (exact values: floats as ``repr``-exact JSON numbers) and exits.
    ros_peer.py serve-evaluate SERVICE
        Serves SERVICE (cstep_msgs/srv/Evaluate) with an answer derived field by field from the
        request (see ``answer``), prints ``ready`` and ``served N`` after each call; runs until
        killed or interrupted (SIGINT: it leaves the domain cleanly).
    ros_peer.py serve-evaluate-batch SERVICE
        Serves SERVICE (cstep_msgs/srv/EvaluateBatch) with an empty answer; prints ``ready``.

Not a stand-in for cstep: it checks the interface package and the transport, nothing more.
"""

import json
import math
import sys
import time

import rclpy
from cstep_msgs.msg import Empowerment
from cstep_msgs.srv import Evaluate, EvaluateBatch
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

QOS = QoSProfile(
    depth=10,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
TIMEOUT_S = 60.0


def say(line: str) -> None:
    print(line, flush=True)


def empowerment_dict(msg: Empowerment) -> dict:
    return {
        "header": {
            "stamp": {"sec": msg.header.stamp.sec, "nanosec": msg.header.stamp.nanosec},
            "frame_id": msg.header.frame_id,
        },
        **{
            name: getattr(msg, name)
            for name in msg.get_fields_and_field_types()
            if name != "header"
        },
    }


def echo_empowerment(node: Node, topic: str) -> int:
    received: list[Empowerment] = []
    node.create_subscription(Empowerment, topic, received.append, QOS)
    deadline = time.monotonic() + TIMEOUT_S
    while node.count_publishers(topic) == 0:
        if time.monotonic() > deadline:
            say("error: no publisher")
            return 1
        rclpy.spin_once(node, timeout_sec=0.05)
    say("ready")
    while not received:
        if time.monotonic() > deadline:
            say("error: no message")
            return 1
        rclpy.spin_once(node, timeout_sec=0.05)
    say("received " + json.dumps(empowerment_dict(received[0]), ensure_ascii=False))
    return 0


def answer(request: Evaluate.Request, response: Evaluate.Response) -> Evaluate.Response:
    """Copy request fields into the response, so the test sees each one arrived intact."""
    e = response.empowerment
    e.header = request.scan.header
    e.empowerment = request.goal.x
    e.reachable_volume = request.goal.y
    e.terminal_volume = request.goal.z
    e.free_volume = request.odom.pose.pose.position.x
    e.safety_coefficient = request.odom.twist.twist.linear.x
    e.horizon = float(request.scan.ranges[0]) if len(request.scan.ranges) else -1.0
    e.num_trajectories = len(request.scan.ranges)
    e.num_colliding = sum(1 for r in request.scan.ranges if math.isnan(r))
    e.valid = request.has_goal
    e.status = request.odom.child_frame_id
    r = response.reward
    r.header = request.odom.header
    r.reward = request.odom.pose.pose.orientation.w
    r.task_reward = request.odom.pose.covariance[35]
    r.empowerment_term = float(request.scan.range_max)
    r.safety_coefficient = request.odom.twist.covariance[7]
    r.valid = not request.has_goal
    return response


def serve_evaluate(node: Node, service: str) -> int:
    served = 0

    def callback(request: Evaluate.Request, response: Evaluate.Response) -> Evaluate.Response:
        nonlocal served
        served += 1
        result = answer(request, response)
        say(f"served {served}")
        return result

    node.create_service(Evaluate, service, callback)
    say("ready")
    spin(node)
    return 0


def serve_evaluate_batch(node: Node, service: str) -> int:
    node.create_service(EvaluateBatch, service, lambda _request, response: response)
    say("ready")
    spin(node)
    return 0


def spin(node: Node) -> None:
    """Spins until killed or interrupted; on SIGINT, returns so the node is destroyed."""
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


def main() -> int:
    mode, name = sys.argv[1], sys.argv[2]
    rclpy.init()
    node = rclpy.create_node("cstep_test_peer")
    try:
        if mode == "echo-empowerment":
            return echo_empowerment(node, name)
        if mode == "serve-evaluate":
            return serve_evaluate(node, name)
        if mode == "serve-evaluate-batch":
            return serve_evaluate_batch(node, name)
        say(f"error: unknown mode {mode}")
        return 2
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
