"""cstep_msgs as built into .venv/: rclpy imports it, and its definitions keep the contract."""

import math
import re

import pytest
from builtin_interfaces.msg import Time
from conftest import REPO
from cstep_msgs.msg import EmpoweredReward, Empowerment
from cstep_msgs.srv import Evaluate, EvaluateBatch
from geometry_msgs.msg import Point
from nav_msgs.msg import Odometry
from rclpy.utilities import get_rmw_implementation_identifier
from sensor_msgs.msg import LaserScan
from std_msgs.msg import Header

MSG_DIR = REPO / "msg"

# The contract: field names, types and order (src/ros/messages/mod.rs mirrors them in this order).
EMPOWERMENT_FIELDS = [
    ("header", "std_msgs/Header"),
    ("empowerment", "double"),
    ("reachable_volume", "double"),
    ("terminal_volume", "double"),
    ("free_volume", "double"),
    ("safety_coefficient", "double"),
    ("horizon", "double"),
    ("num_trajectories", "uint32"),
    ("num_colliding", "uint32"),
    ("valid", "boolean"),
    ("status", "string"),
]
EMPOWERED_REWARD_FIELDS = [
    ("header", "std_msgs/Header"),
    ("reward", "double"),
    ("task_reward", "double"),
    ("empowerment_term", "double"),
    ("safety_coefficient", "double"),
    ("valid", "boolean"),
]
EVALUATE_REQUEST_FIELDS = [
    ("odom", "nav_msgs/Odometry"),
    ("scan", "sensor_msgs/LaserScan"),
    ("goal", "geometry_msgs/Point"),
    ("has_goal", "boolean"),
]
EVALUATE_RESPONSE_FIELDS = [
    ("empowerment", "cstep_msgs/Empowerment"),
    ("reward", "cstep_msgs/EmpoweredReward"),
]
EVALUATE_BATCH_REQUEST_FIELDS = [
    ("odom", "sequence<nav_msgs/Odometry>"),
    ("scan", "sequence<sensor_msgs/LaserScan>"),
    ("goal", "sequence<geometry_msgs/Point>"),
    ("has_goal", "sequence<boolean>"),
    ("in_collision", "sequence<boolean>"),
]
EVALUATE_BATCH_RESPONSE_FIELDS = [
    ("empowerment", "sequence<cstep_msgs/Empowerment>"),
    ("reward", "sequence<cstep_msgs/EmpoweredReward>"),
]


@pytest.mark.parametrize(
    ("msg_type", "fields"),
    [
        (Empowerment, EMPOWERMENT_FIELDS),
        (EmpoweredReward, EMPOWERED_REWARD_FIELDS),
        (Evaluate.Request, EVALUATE_REQUEST_FIELDS),
        (Evaluate.Response, EVALUATE_RESPONSE_FIELDS),
        (EvaluateBatch.Request, EVALUATE_BATCH_REQUEST_FIELDS),
        (EvaluateBatch.Response, EVALUATE_BATCH_RESPONSE_FIELDS),
    ],
    ids=[
        "Empowerment",
        "EmpoweredReward",
        "Evaluate.Request",
        "Evaluate.Response",
        "EvaluateBatch.Request",
        "EvaluateBatch.Response",
    ],
)
def test_fields_names_types_and_order(msg_type, fields):
    assert list(msg_type.get_fields_and_field_types().items()) == fields


def test_rclpy_runs_on_fast_dds():
    assert get_rmw_implementation_identifier() == "rmw_fastrtps_cpp"


def test_empowerment_constructs_with_every_field():
    stamp = Time(sec=12, nanosec=345)
    msg = Empowerment(
        header=Header(stamp=stamp, frame_id="odom"),
        empowerment=math.log(2.0),
        reachable_volume=3.0,
        terminal_volume=1.0,
        free_volume=2.0,
        safety_coefficient=0.5,
        horizon=1.0,
        num_trajectories=150,
        num_colliding=40,
        valid=True,
        status="ok",
    )
    assert msg.header.stamp == stamp
    assert msg.empowerment == math.log(2.0)
    assert (msg.num_trajectories, msg.num_colliding, msg.valid, msg.status) == (150, 40, True, "ok")


def test_empowered_reward_constructs_with_every_field():
    msg = EmpoweredReward(
        header=Header(frame_id="odom"),
        reward=-0.25,
        task_reward=0.5,
        empowerment_term=-0.5,
        safety_coefficient=2.0,
        valid=False,
    )
    assert (msg.reward, msg.task_reward, msg.empowerment_term) == (-0.25, 0.5, -0.5)
    assert (msg.safety_coefficient, msg.valid) == (2.0, False)


def test_evaluate_request_and_response_construct():
    odom = Odometry(child_frame_id="base_link")
    odom.pose.pose.position.x = 1.0
    scan = LaserScan(ranges=[1.0, math.inf, math.nan, -math.inf])
    request = Evaluate.Request(odom=odom, scan=scan, goal=Point(x=4.0, z=1.0), has_goal=True)
    assert request.odom.pose.pose.position.x == 1.0
    assert request.scan.ranges[1] == math.inf and math.isnan(request.scan.ranges[2])
    assert (request.goal.x, request.goal.z, request.has_goal) == (4.0, 1.0, True)
    response = Evaluate.Response(
        empowerment=Empowerment(status="ok", valid=True), reward=EmpoweredReward(reward=1.5)
    )
    assert response.empowerment.status == "ok" and response.reward.reward == 1.5
    # The service type ties the two together, as rclpy clients and servers use it.
    assert Evaluate.Request is type(request) and Evaluate.Response is type(response)


@pytest.mark.parametrize(
    "path",
    ["msg/Empowerment.msg", "msg/EmpoweredReward.msg", "srv/Evaluate.srv", "srv/EvaluateBatch.srv"],
)
def test_every_field_is_documented(path):
    """Each field line in the definition follows a comment line (its documentation)."""
    lines = (MSG_DIR / path).read_text(encoding="utf-8").splitlines()
    fields = 0
    for i, line in enumerate(lines):
        if not line.strip() or line.startswith("#") or line == "---":
            continue
        assert re.fullmatch(r"[\w/]+(\[\d*\])? \w+", line), f"{path}:{i + 1}: {line!r}"
        assert i > 0 and lines[i - 1].startswith("# "), f"{path}:{i + 1}: no comment above"
        fields += 1
    assert fields > 0
