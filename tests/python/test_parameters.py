"""Every parameter of a live `cstep node` over the standard ROS 2 parameter services, as rclpy's
own parameter client (what `ros2 param` uses) sees them over real DDS: listed, described from
the one table in crates/cstep-core/src/parameters/table.rs (via config/cstep.yaml, written from
it), read back as configured, read-only ones refusing a set with a reason, and live
`safety_coefficient` and `input_timeout` changes taking effect at the next scan."""

import math
import os
import subprocess
from pathlib import Path

import pytest
import yaml
from conftest import REPO, wait_until
from node_rig import CONFIG, corridor_scan, cstep_binary, odometry, stop_gently
from rcl_interfaces.msg import ParameterType
from rclpy.node import Node
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.parameter_client import AsyncParameterClient

# The one `-p` override the node is started with (config/cstep.yaml says seed: 0).
OVERRIDE = ("seed", 7)

TYPES = {
    "bool": ParameterType.PARAMETER_BOOL,
    "integer": ParameterType.PARAMETER_INTEGER,
    "double": ParameterType.PARAMETER_DOUBLE,
    "string": ParameterType.PARAMETER_STRING,
}


@pytest.fixture
def cstep_node(ros_domain):
    """node_rig's node (so the `rig` fixture drives this one) with one `-p` override."""
    log_path = Path(os.environ.get("TMPDIR", "/tmp")) / f"cstep-node-{ros_domain}.log"
    name, value = OVERRIDE
    command = [str(cstep_binary()), "node", "--config", str(CONFIG)]
    command += ["--ros-args", "-p", f"{name}:={value}"]
    with open(log_path, "w") as log:
        proc = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
        yield proc
        stop_gently(proc)


def shipped_parameters() -> dict[str, dict]:
    """config/cstep.yaml's parameters: value, and the comment above each, split into the
    description and the summary line (type, unit, accepted values; live or read-only)."""
    values = yaml.safe_load(CONFIG.read_text())["/**"]["ros__parameters"]
    shipped, comments = {}, []
    for line in CONFIG.read_text().splitlines():
        text = line.strip()
        if text.startswith("#") and line.startswith("    "):
            comments.append(text.removeprefix("#").strip())
        elif line.startswith("    ") and ":" in text:
            name = text.split(":")[0]
            shipped[name] = {
                "value": values[name],
                "description": " ".join(comments[:-1]),
                "summary": comments[-1],
            }
            comments = []
    assert shipped.keys() == values.keys()
    return shipped


def call(client_future, executor, what: str):
    wait_until(client_future.done, what, executor)
    return client_future.result()


@pytest.fixture
def parameters(cstep_node, ros_context, executor):
    """rclpy's parameter client for /cstep_node, its services ready."""
    node = Node("cstep_parameter_test", context=ros_context)
    executor.add_node(node)
    client = AsyncParameterClient(node, "/cstep_node")
    wait_until(client.services_are_ready, "the node's parameter services", executor)
    yield client
    node.destroy_node()


def same(a, b) -> bool:
    return (isinstance(a, float) and math.isnan(a) and math.isnan(b)) or a == b


def test_every_parameter_is_listed_described_and_read_as_configured(parameters, executor):
    shipped = shipped_parameters()
    listed = call(parameters.list_parameters(), executor, "list_parameters").result.names
    assert sorted(listed) == sorted(shipped), "every parameter in config/cstep.yaml, no other"

    names = list(shipped)
    described = call(parameters.describe_parameters(names), executor, "describe_parameters")
    for name, d in zip(names, described.descriptors, strict=True):
        kind, *_ = shipped[name]["summary"].split(",")
        assert d.name == name
        assert d.description == shipped[name]["description"], name
        assert d.type == TYPES[kind], name
        assert d.read_only == shipped[name]["summary"].endswith("read-only"), name
        assert d.additional_constraints, name
    by_name = dict(zip(names, described.descriptors, strict=True))
    assert not by_name["safety_coefficient"].read_only
    (c_range,) = by_name["safety_coefficient"].floating_point_range
    assert (c_range.from_value, c_range.to_value) == (0.0, math.inf)
    (count_range,) = by_name["trajectories"].integer_range
    assert (count_range.from_value, count_range.to_value, count_range.step) == (1, 100_000, 1)
    assert by_name["horizon"].additional_constraints == "> 0; unit: s"
    assert by_name["horizon"].read_only

    # The dump equivalent: every value as config/cstep.yaml sets it, but for the -p override.
    got = call(parameters.get_parameters(names), executor, "get_parameters")
    values = {n: parameter_value_to_python(v) for n, v in zip(names, got.values, strict=True)}
    expected = {name: p["value"] for name, p in shipped.items()}
    expected[OVERRIDE[0]] = OVERRIDE[1]
    urdf = CONFIG.parent / expected.pop("robot_description")
    assert Path(values.pop("robot_description")).resolve() == urdf.resolve()
    for name, value in expected.items():
        assert same(values[name], value), f"{name}: {values[name]!r} != {value!r}"


def test_read_only_and_invalid_sets_are_refused_with_a_reason(parameters, executor):
    read_only = "parameter '{}' cannot be set because it is read-only"
    refusals = [
        (Parameter("horizon", value=0.5), read_only.format("horizon")),
        (Parameter("scan_topic", value="/lidar"), read_only.format("scan_topic")),
        (
            Parameter("safety_coefficient", value=0.0),
            "'safety_coefficient' must be a positive number, got 0",
        ),
        (
            Parameter("safety_coefficient", value="high"),
            "Cannot change type of parameter 'safety_coefficient' from Double to String.",
        ),
    ]
    for parameter, reason in refusals:
        reply = call(parameters.set_parameters([parameter]), executor, "set_parameters")
        (result,) = reply.results
        assert not result.successful, parameter.name
        assert result.reason == reason
    got = call(parameters.get_parameters(["horizon", "safety_coefficient"]), executor, "get")
    assert [parameter_value_to_python(v) for v in got.values] == [1.0, 1.0]


def test_a_safety_coefficient_set_through_the_client_shows_in_the_next_score(rig, executor):
    client = AsyncParameterClient(rig.node, "/cstep_node")
    wait_until(client.services_are_ready, "the node's parameter services", executor)
    rig.feed(3)
    assert rig.empowerment[-1].safety_coefficient == 1.0
    reply = call(
        client.set_parameters([Parameter("safety_coefficient", value=0.25)]), executor, "set"
    )
    assert reply.results[0].successful, reply.results[0].reason
    rig.feed(3, first_sec=5000)
    after = [m for m in rig.empowerment if m.header.stamp.sec >= 5000]
    assert after and all(m.safety_coefficient == 0.25 for m in after)
    reward = next(m for m in rig.reward if m.header.stamp.sec >= 5000)
    assert reward.safety_coefficient == 0.25
    got = call(client.get_parameters(["safety_coefficient"]), executor, "get")
    assert parameter_value_to_python(got.values[0]) == 0.25


def test_an_input_timeout_set_through_the_client_judges_the_next_scan(rig, executor):
    """Odometry 1.5 s old is stale at the default 0.5 s and fresh at 5 s: scans alone are then
    scored (no score at the default), and the diagnostics stop saying STALE."""
    client = AsyncParameterClient(rig.node, "/cstep_node")
    wait_until(client.services_are_ready, "the node's parameter services", executor)

    def scans_after_old_odometry(first_sec: int) -> list[int]:
        rig.odom.publish(odometry())
        rig.spin_for(1.5)
        for k in range(5):
            rig.scan.publish(corridor_scan(first_sec + k))
            rig.spin_for(0.05)
        rig.spin_for(1.0)
        return [m.header.stamp.sec for m in rig.empowerment if m.header.stamp.sec >= first_sec]

    assert scans_after_old_odometry(6000) == []
    reply = call(client.set_parameters([Parameter("input_timeout", value=5.0)]), executor, "set")
    assert reply.results[0].successful, reply.results[0].reason
    assert scans_after_old_odometry(6100) == [6100, 6101, 6102, 6103, 6104]
    got = call(client.get_parameters(["input_timeout"]), executor, "get")
    assert parameter_value_to_python(got.values[0]) == 5.0
    refused = call(client.set_parameters([Parameter("input_timeout", value=-1.0)]), executor, "set")
    assert not refused.results[0].successful
    assert "'input_timeout' must be a positive number" in refused.results[0].reason
