"""`cstep echo` prints what real publishers send, as YAML `ros2 topic echo` would (localhost,
a private domain per test)."""

import math
import os
import struct
import time

from conftest import DISCOVERY_TIMEOUT_S
from node_rig import Echo, corridor_scan, message_to_ordereddict, odometry


def feed_while_running(rig, process: Echo, first_sec: int) -> int:
    """Feed the node until ``process`` exits; the next unused stamp."""
    return rig.feed_until(
        lambda: not process.running(), "cstep echo to exit", first_sec, timeout=30
    )


def as_float32(value: float) -> float:
    return struct.unpack("f", struct.pack("f", value))[0]


def test_echo_prints_three_empowerment_messages_equal_to_what_rclpy_received(rig, echo):
    e = echo("/cstep/empowerment", "--count", "3", "--timeout", "30")
    last = feed_while_running(rig, e, first_sec=6000)
    assert e.finish() == 0, e.stderr
    rig.spin_for(0.5)
    documents = e.documents()
    assert len(documents) == 3, e.stdout
    assert e.stdout.count("\n---\n") == 3
    received = {m.header.stamp.sec: m for m in rig.empowerment}
    stamps = [d["header"]["stamp"]["sec"] for d in documents]
    assert stamps == sorted(stamps) and len(set(stamps)) == 3
    for document in documents:
        sec = document["header"]["stamp"]["sec"]
        assert 6000 <= sec < last
        assert document["header"]["frame_id"] == "odom"
        assert document["valid"] is True and document["status"] == "ok"
        assert math.isfinite(document["empowerment"]) and document["num_trajectories"] == 150
        # Field for field, bit for bit: the YAML floats read back to the values rclpy got.
        assert document == message_to_ordereddict(received[sec])


def test_echo_finds_the_type_of_other_topics_from_their_publishers(rig, echo):
    # `odom` (relative: /odom) is nav_msgs/Odometry from the rig's reliable publisher.
    e = echo("odom", "--once", "--timeout", "20")
    feed_while_running(rig, e, first_sec=6100)
    assert e.finish() == 0, e.stderr
    [odom] = e.documents()
    assert odom == message_to_ordereddict(odometry())
    assert len(odom["pose"]["covariance"]) == 36

    # /scan is a best-effort publisher: echo must subscribe best effort to hear it; REP 117
    # infinities print as .inf, and float32 values with the fewest digits that read back to
    # the same float32.
    e = echo("/scan", "--type", "sensor_msgs/msg/LaserScan", "--once", "--timeout", "20")
    feed_while_running(rig, e, first_sec=6200)
    assert e.finish() == 0, e.stderr
    [scan] = e.documents()
    sent = corridor_scan(scan["header"]["stamp"]["sec"])
    assert len(scan["ranges"]) == len(sent.ranges) == 180
    assert any(math.isinf(r) for r in scan["ranges"])
    assert [as_float32(r) for r in scan["ranges"]] == [as_float32(r) for r in sent.ranges]
    assert as_float32(scan["angle_increment"]) == as_float32(sent.angle_increment)
    assert scan["intensities"] == []


def test_echo_prints_diagnostics_and_markers_by_their_names(rig, echo):
    e = echo("/diagnostics", "--once", "--timeout", "20")
    assert e.finish(timeout=25) == 0, e.stderr
    [diagnostics] = e.documents()
    [status] = diagnostics["status"]
    assert status["name"] == "/cstep_node: empowerment" and status["hardware_id"] == "cf2x"
    keys = [kv["key"] for kv in status["values"]]
    assert "scans_scored" in keys and "markers_published" in keys

    # Echo is a subscriber like any other: the node publishes markers for it.
    e = echo("/cstep/markers", "--once", "--timeout", "20")
    feed_while_running(rig, e, first_sec=6300)
    assert e.finish() == 0, e.stderr
    [array] = e.documents()
    endpoints, hull = array["markers"]
    assert (endpoints["ns"], endpoints["type"], len(endpoints["points"])) == (
        "cstep/endpoints",
        8,
        150,
    )
    assert hull["type"] == 4 and hull["points"][0] == hull["points"][-1]
    # The Humble+ fields are all there, in order.
    assert list(endpoints)[-9:] == [
        "points",
        "colors",
        "texture_resource",
        "texture",
        "uv_coordinates",
        "text",
        "mesh_resource",
        "mesh_file",
        "mesh_use_embedded_materials",
    ]


def one_line_error(e: Echo) -> str:
    assert e.stdout == ""
    lines = e.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cstep: error: "), e.stderr
    assert "panicked" not in e.stderr
    return lines[0]


def test_echo_explains_unknown_types_and_topics_in_one_line(rig, echo):
    e = echo("/chatter", "--type", "std_msgs/msg/String")
    assert e.finish() != 0
    line = one_line_error(e)
    assert "cannot decode std_msgs/msg/String" in line and "cstep_msgs/msg/Empowerment" in line

    e = echo("/nobody/publishes/this", "--timeout", "2")
    assert e.finish() != 0
    line = one_line_error(e)
    assert "cannot tell the type of /nobody/publishes/this" in line and "--type" in line

    # A topic published with another type than asked: the node's rewards are not Empowerment.
    e = echo("/cstep/reward", "--type", "cstep_msgs/msg/Empowerment", "--timeout", "20")
    feed_while_running(rig, e, first_sec=6400)
    assert e.finish() != 0
    assert "published as cstep_msgs/msg/EmpoweredReward, not cstep_msgs/msg/Empowerment" in (
        e.stderr
    )
    assert e.stdout == ""

    e = echo("/cstep/empowerment", "--count", "0")
    assert e.finish() != 0 and "--count" in e.stderr


def test_echo_listens_on_ros_domain_id_only(cstep_node, second_domain, echo):
    # The node publishes diagnostics every second on this test's domain: on another domain, echo
    # hears nothing and says so; on this one it hears them.
    other = dict(os.environ, ROS_DOMAIN_ID=str(second_domain))
    start = time.monotonic()
    e = echo("/diagnostics", "--timeout", "3", env=other)
    assert e.finish() != 0
    assert "no message on /diagnostics within 3 s" in one_line_error(e)
    assert time.monotonic() - start < DISCOVERY_TIMEOUT_S

    e = echo("/diagnostics", "--once", "--timeout", "20")
    assert e.finish(timeout=25) == 0, e.stderr
    assert len(e.documents()) == 1
