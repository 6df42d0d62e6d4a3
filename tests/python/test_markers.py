"""`/cstep/markers` from a live `cstep node`, received by real rclpy (localhost, own domain)."""

import math
from itertools import pairwise

import pytest
from node_rig import RELIABLE
from visualization_msgs.msg import Marker, MarkerArray

# The robot of node_rig.odometry(): at (0, 0, 1) in "odom".
ROBOT = (0.0, 0.0, 1.0)
# The node's colours (src/ros/node/markers.rs): green = free, red = terminal (collided).
FREE = (0.1, 0.8, 0.1, 1.0)
TERMINAL = (0.9, 0.1, 0.1, 1.0)


def rgba(color) -> tuple[float, float, float, float]:
    return (color.r, color.g, color.b, color.a)


def same_color(color, expected) -> bool:
    return all(math.isclose(a, b, abs_tol=1e-6) for a, b in zip(rgba(color), expected, strict=True))


def shoelace(points) -> float:
    """Signed area of the closed polygon ``points`` (last == first)."""
    return 0.5 * sum(a.x * b.y - b.x * a.y for a, b in pairwise(points))


def inside_convex(polygon, p, eps=1e-9) -> bool:
    """Whether ``p`` lies in the closed counter-clockwise convex ``polygon`` (last == first)."""
    return all(
        (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x) >= -eps for a, b in pairwise(polygon)
    )


def test_markers_show_every_endpoint_coloured_by_outcome_and_their_hull(rig):
    markers: list[MarkerArray] = []
    rig.node.create_subscription(MarkerArray, "/cstep/markers", markers.append, RELIABLE)
    rig.feed_until(lambda: len(markers) >= 5, "five marker arrays", first_sec=7000)
    rig.spin_for(0.3)
    scores = {m.header.stamp.sec: m for m in rig.empowerment}

    checked = 0
    for array in markers:
        endpoints, hull = array.markers
        sec = endpoints.header.stamp.sec
        assert sec >= 7000, "markers stamped with the scan's stamp"
        score = scores.get(sec)
        if score is None:
            continue  # its score arrived before the rig's warm-up cleared the lists
        checked += 1
        for m in (endpoints, hull):
            assert m.header == score.header  # scan stamp, odometry frame
            assert m.header.frame_id == "odom"
            assert m.action == Marker.ADD
        assert (endpoints.ns, endpoints.type) == ("cstep/endpoints", Marker.POINTS)
        assert len(endpoints.points) == len(endpoints.colors) == score.num_trajectories == 150
        reds = sum(same_color(c, TERMINAL) for c in endpoints.colors)
        greens = sum(same_color(c, FREE) for c in endpoints.colors)
        assert reds + greens == 150, "every endpoint is green or red"
        assert reds == score.num_colliding
        assert 0 < reds < 150, "the corridor makes some trajectories collide, not all"
        for p in endpoints.points:
            assert all(math.isfinite(v) for v in (p.x, p.y, p.z))
            # Endpoints are the robot's position plus at most A*T^2/2 + v*T = 3 m of travel.
            assert math.dist((p.x, p.y, p.z), ROBOT) < 3.5

        assert (hull.ns, hull.type) == ("cstep/hull", Marker.LINE_STRIP)
        outline = hull.points
        assert len(outline) >= 4 and outline[0] == outline[-1], "a closed outline"
        assert all(p.z == ROBOT[2] for p in outline), "drawn at the robot's height"
        assert all(inside_convex(outline, p) for p in endpoints.points)
        # The outline encloses exactly the reachable area the score reports (2D volumes).
        assert shoelace(outline) == pytest.approx(score.reachable_volume, rel=1e-9)
    assert checked >= 3, f"only {checked} marker arrays matched a score"


def test_markers_are_published_only_while_someone_subscribes(rig):
    # Nobody subscribes: scores flow, no markers are built or sent.
    rig.feed(10, first_sec=8000)
    values = rig.next_diagnostics()
    assert int(values["scans_scored"]) >= 10
    assert values["markers_published"] == "0"

    markers: list[MarkerArray] = []
    subscription = rig.node.create_subscription(
        MarkerArray, "/cstep/markers", markers.append, RELIABLE
    )
    rig.feed_until(lambda: len(markers) >= 3, "markers once subscribed", first_sec=8100)
    assert int(rig.next_diagnostics()["markers_published"]) >= 3

    # The subscriber leaves: the node notices and stops, while it keeps scoring.
    rig.node.destroy_subscription(subscription)
    rig.spin_for(1.0)
    before = rig.next_diagnostics()
    rig.feed(10, first_sec=8200)
    after = rig.next_diagnostics(2)
    assert int(after["scans_scored"]) >= int(before["scans_scored"]) + 9
    assert after["markers_published"] == before["markers_published"]
