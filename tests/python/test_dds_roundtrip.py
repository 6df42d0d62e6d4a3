"""cstep_msgs over real DDS (Fast DDS, localhost): this process and a peer process."""

import json
import math
import os

from builtin_interfaces.msg import Time
from conftest import wait_until
from cstep_msgs.msg import Empowerment
from cstep_msgs.srv import Evaluate
from geometry_msgs.msg import Point
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import LaserScan
from std_msgs.msg import Header

QOS = QoSProfile(
    depth=10,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)


def test_empowerment_reaches_another_process_with_exact_values(ros_context, start_peer):
    topic = f"/cstep_test/empowerment_{os.getpid()}"
    peer = start_peer("echo-empowerment", topic)

    node = Node("cstep_test_publisher", context=ros_context)
    try:
        publisher = node.create_publisher(Empowerment, topic, QOS)
        sent = Empowerment(
            header=Header(stamp=Time(sec=1_700_000_000, nanosec=999_999_999), frame_id="odom"),
            empowerment=math.log(1e-4),  # the documented floor
            reachable_volume=0.1 + 0.2,  # not exactly 0.3: every bit must survive
            terminal_volume=5e-324,  # smallest subnormal double
            free_volume=math.pi,
            safety_coefficient=1.7976931348623157e308,
            horizon=-0.0,
            num_trajectories=4_294_967_295,  # uint32 max
            num_colliding=2000,
            valid=True,
            status="ok — ünïcödé survives",
        )
        wait_until(lambda: publisher.get_subscription_count() >= 1, "the peer's subscription")
        assert peer.expect("ready") == ""
        publisher.publish(sent)
        got = json.loads(peer.expect("received ", timeout=30))
    finally:
        node.destroy_node()

    assert got["header"] == {
        "stamp": {"sec": 1_700_000_000, "nanosec": 999_999_999},
        "frame_id": "odom",
    }
    for name in Empowerment.get_fields_and_field_types():
        if name != "header":
            assert got[name] == getattr(sent, name), name
    assert math.copysign(1.0, got["horizon"]) == -1.0  # -0.0 kept its sign
    assert got["reachable_volume"] == 0.30000000000000004
    # The peer's exit is not waited for: all it does after printing is rclpy's and Fast DDS's
    # teardown, which once took over 10 s on a loaded CI machine; the fixture stops it.


def test_evaluate_service_round_trip_to_another_process(ros_context, executor, start_peer):
    service = f"/cstep_test/evaluate_{os.getpid()}"
    start_peer("serve-evaluate", service)

    node = Node("cstep_test_client", context=ros_context)
    executor.add_node(node)
    try:
        client = node.create_client(Evaluate, service)
        wait_until(client.service_is_ready, "the peer's Evaluate service", executor)

        odom = Odometry()
        odom.header = Header(stamp=Time(sec=5, nanosec=6), frame_id="odom")
        odom.child_frame_id = "base_link"
        odom.pose.pose.position.x = 1.25
        odom.pose.pose.orientation.w = 0.5
        odom.pose.covariance[35] = 0.125
        odom.twist.twist.linear.x = -2.5
        odom.twist.covariance[7] = 7.0
        scan = LaserScan(header=Header(stamp=Time(sec=5, nanosec=1), frame_id="laser"))
        scan.range_max = 3.5
        scan.ranges = [0.75, math.inf, math.nan, -math.inf, math.nan]
        request = Evaluate.Request(odom=odom, scan=scan, goal=Point(x=4.0, y=-1.0, z=1.5))
        request.has_goal = True

        future = client.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=30)
        assert future.done(), "no answer from the peer's Evaluate service within 30 s"
        response = future.result()
    finally:
        executor.remove_node(node)
        node.destroy_node()

    e, r = response.empowerment, response.reward
    assert e.header == scan.header and r.header == odom.header
    assert (e.empowerment, e.reachable_volume, e.terminal_volume) == (4.0, -1.0, 1.5)
    assert (e.free_volume, e.safety_coefficient, e.horizon) == (1.25, -2.5, 0.75)
    assert (e.num_trajectories, e.num_colliding) == (5, 2)  # both NaN beams arrived as NaN
    assert (e.valid, e.status) == (True, "base_link")
    assert (r.reward, r.task_reward, r.empowerment_term) == (0.5, 0.125, 3.5)
    assert (r.safety_coefficient, r.valid) == (7.0, False)
