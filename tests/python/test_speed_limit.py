"""The speed limit Nav2 obeys: `cstep node -p publish_speed_limit:=true` publishes a
`nav2_msgs/msg/SpeedLimit` on `speed_limit` from each score, received here by an rclpy
subscriber typed and configured as Nav2's controller server's (``rclcpp::QoS(10)``: reliable,
volatile, depth 10), over real DDS on localhost in the test's own domain.

Nav2 is not installable from PyPI: `make test` builds a test-only `nav2_msgs` with just
SpeedLimit.msg (tests/interfaces/nav2_msgs) into the cargo target directory and passes its
prefix as ``CSTEP_TEST_INTERFACES`` (its libraries on ``LD_LIBRARY_PATH``).
"""

import signal
from itertools import pairwise

import pytest
from conftest import wait_until
from nav2_msgs_loader import speed_limit_type
from node_rig import (
    Rig,
    corridor_scan,
    cstep_eval,
    message_to_ordereddict,
    odometry,
    start_node,
    stop_gently,
)
from rclpy.qos import QoSProfile, ReliabilityPolicy

SpeedLimit = speed_limit_type()


@pytest.fixture(autouse=True)
def _nav2_msgs() -> None:
    """Fails (never skips) each test here where the test-only nav2_msgs is missing."""
    if SpeedLimit is None:
        pytest.fail(
            "CSTEP_TEST_INTERFACES is not set: run these tests with `make test-python`, which "
            "builds the test-only nav2_msgs (tests/interfaces/nav2_msgs) and sets it and "
            "LD_LIBRARY_PATH",
            pytrace=False,
        )


# Nav2's controller server: create_subscription<SpeedLimit>(speed_limit_topic, rclcpp::QoS(10)).
NAV2_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
FLOOR = 20.0  # speed_limit_floor's default


def percent(e: float, full_speed_at: float, span: float, floor: float = FLOOR) -> float:
    """The declared mapping (crates/cstep-core/src/speed_limit.rs), operation for operation."""
    t = min(max((e - (full_speed_at - span)) / span, 0.0), 1.0)
    return min(max(floor + (100.0 - floor) * t, floor), 100.0)


class Nav2Rig(Rig):
    """The rig with a subscriber of `speed_limit` as Nav2's controller server has one."""

    def __init__(self, context, executor):
        super().__init__(context, executor)
        self.limits: list[SpeedLimit] = []
        self.limit_subscription = self.node.create_subscription(
            SpeedLimit, "speed_limit", self.limits.append, NAV2_QOS
        )

    def matched(self) -> None:
        """Waits until the node's speed-limit publisher has matched the subscriber."""
        wait_until(
            lambda: self.limit_subscription.get_publisher_count() >= 1,
            "the node's speed_limit publisher",
            self.executor,
        )

    def feed_stamped(
        self, stamps_ns: list[int], width: float = 2.5, rate_hz: float = 20.0, vx: float = 0.5
    ):
        """Odometry at ``vx`` m/s and a corridor scan per stamp (nanoseconds), at ``rate_hz``."""
        for ns in stamps_ns:
            self.odom.publish(odometry(vx))
            self.scan.publish(corridor_scan(ns // 10**9, width=width, nanosec=ns % 10**9))
            self.spin_for(1.0 / rate_hz)


@pytest.fixture
def speed_limit_node(request, ros_domain):
    """A node with the speed limit on; ``request.param``: further ``name:=value`` parameters."""
    proc = start_node("publish_speed_limit:=true", *getattr(request, "param", ()))
    yield proc
    stop_gently(proc)


@pytest.fixture
def nav2(speed_limit_node, ros_context, executor):
    rig = Nav2Rig(ros_context, executor)
    rig.matched()
    rig.warm_up()
    yield rig
    rig.node.destroy_node()


def stamp_ns(message) -> int:
    return message.header.stamp.sec * 10**9 + message.header.stamp.nanosec


def test_speed_limit_is_off_by_default(rig):
    """Without publish_speed_limit there is no speed_limit publisher, and scans bring none."""
    limits: list[SpeedLimit] = []
    rig.node.create_subscription(SpeedLimit, "speed_limit", limits.append, NAV2_QOS)
    rig.feed(10, first_sec=4000)
    rig.spin_for(0.5)
    assert rig.empowerment, "the node scored the scans"
    assert rig.node.count_publishers("/speed_limit") == 0
    assert limits == []


# Known scans: corridors 1.2 m and 2.5 m wide; the mapping's parameters are set from their
# scores (cstep eval, the node's own scoring path) so that both fall inside its linear part.
WIDTHS = (1.2, 2.5)


def published_limits(ros_context, executor, params, widths, vx=0.5):
    """The limits a node started with ``params`` publishes for corridor scans of ``widths``,
    alternating, one a second of scan time (far enough apart for the 10 Hz rate limit), the
    odometry at ``vx`` m/s: ``(width, limit, score)`` each, ``score`` the node's own score of
    that scan where the rig received it (else None)."""
    proc = start_node("publish_speed_limit:=true", *params)
    try:
        rig = Nav2Rig(ros_context, executor)
        rig.matched()
        rig.warm_up()
        rig.limits.clear()
        sent = {(5000 + k) * 10**9: widths[k % len(widths)] for k in range(8)}
        for ns, width in sent.items():
            rig.feed_stamped([ns], width=width, rate_hz=10.0, vx=vx)
        wait_until(lambda: len(rig.limits) >= 6, "six speed limits", executor, timeout=10)
        rig.spin_for(0.3)
        scored = {stamp_ns(e): e.empowerment for e in rig.empowerment}
        for limit in rig.limits:
            assert limit.percentage is True
            assert limit.header.frame_id == "odom"
        # Each limit is stamped with its scan's stamp.
        return [(sent[stamp_ns(m)], m, scored.get(stamp_ns(m))) for m in rig.limits]
    finally:
        stop_gently(proc)


def test_speed_limit_is_what_the_mapping_says_for_known_scans(tmp_path, ros_context, executor):
    scores = {
        w: cstep_eval(tmp_path, odometry(), corridor_scan(1, width=w))["empowerment"]
        for w in WIDTHS
    }
    low, high = min(scores.values()), max(scores.values())
    assert high > low, f"the corridors must score apart: {scores}"
    full_speed_at, span = high + 0.25, (high - low) + 0.5
    expected = {w: percent(e, full_speed_at, span) for w, e in scores.items()}
    assert all(FLOOR < p < 100.0 for p in expected.values()), expected
    params = [f"speed_limit_full_speed_at:={full_speed_at!r}", f"speed_limit_span:={span!r}"]
    published = published_limits(ros_context, executor, params, WIDTHS)
    for width, limit, score in published:
        assert limit.speed_limit == expected[width], (width, scores[width], limit)
        assert score in (None, scores[width]), "the node scores as cstep eval does"
    assert sum(score is not None for _, _, score in published) >= 5
    assert {width for width, _, _ in published} == set(WIDTHS)


HUSKY = {"model": "diff_drive", "robot_description": "builtin:husky.urdf", "volume_dims": "2"}
"""A node scoring the Husky (its URDF as shipped), everything else its defaults."""


def test_a_wheeled_robot_gets_its_models_own_threshold_and_span(tmp_path, ros_context, executor):
    """Unset, the mapping is the model's own: diff_drive's −1.05 and 0.7 (measured on the
    Husky's scores). At its top speed the Husky gets full speed in a 4 m corridor (nothing within
    its reach) and less in a 1.4 m one (the demo's door); the drone's 1.5 would hold it at the floor in both."""
    widths = (1.4, 4.0)
    scores = {
        w: cstep_eval(tmp_path, odometry(vx=1.0), corridor_scan(1, width=w), params=HUSKY)[
            "empowerment"
        ]
        for w in widths
    }
    expected = {w: percent(e, -1.05, 0.7) for w, e in scores.items()}
    assert expected[4.0] == 100.0 and FLOOR < expected[1.4] < 100.0, (scores, expected)
    assert all(percent(e, 1.5, 1.5) == FLOOR for e in scores.values()), scores
    params = [f"{name}:={value}" for name, value in HUSKY.items()]
    published = published_limits(ros_context, executor, params, widths, vx=1.0)
    for width, limit, score in published:
        assert limit.speed_limit == expected[width], (width, scores[width], limit)
        assert score in (None, scores[width]), "the node scores as cstep eval does"
    assert {width for width, _, _ in published} == set(widths)


def test_echo_prints_the_limit_the_controller_server_receives(nav2, echo):
    """`cstep echo` knows nav2_msgs/SpeedLimit: found from the node's publisher, printed as
    the Nav2-typed subscriber received it."""
    nav2.limits.clear()
    e = echo("/speed_limit", "--once", "--timeout", "20")
    nav2.feed_until(lambda: not e.running(), "cstep echo to exit", first_sec=7000, timeout=30)
    assert e.finish() == 0, e.stderr
    nav2.spin_for(0.3)
    [document] = e.documents()
    received = {stamp_ns(m): m for m in nav2.limits}
    stamp = document["header"]["stamp"]
    assert document == message_to_ordereddict(received[stamp["sec"] * 10**9 + stamp["nanosec"]])


@pytest.mark.parametrize("speed_limit_node", [("speed_limit_max_speed:=0.8",)], indirect=True)
def test_a_max_speed_gives_absolute_limits(nav2):
    """With speed_limit_max_speed, the mapping's percentage of it in m/s, percentage false
    (the default mapping: 100 % at 1.5 nats, the floor at 0)."""
    nav2.limits.clear()
    nav2.feed(4, first_sec=6000, rate_hz=10.0)
    wait_until(lambda: len(nav2.limits) >= 3, "three speed limits", nav2.executor, timeout=10)
    nav2.spin_for(0.3)
    scored = {stamp_ns(e): e.empowerment for e in nav2.empowerment}
    for limit in nav2.limits:
        assert limit.percentage is False
        e = scored[stamp_ns(limit)]
        assert limit.speed_limit == percent(e, 1.5, 1.5) / 100.0 * 0.8, (e, limit)


@pytest.mark.parametrize("speed_limit_node", [("speed_limit_rate:=4.0",)], indirect=True)
def test_the_rate_limit_holds(nav2):
    """Scans every 50 ms of scan time, 4 limits per second: limits at least 250 ms apart."""
    nav2.limits.clear()
    nav2.empowerment.clear()
    start = 8000 * 10**9
    nav2.feed_stamped([start + k * 50_000_000 for k in range(60)], rate_hz=20.0)
    nav2.spin_for(0.3)
    stamps = [stamp_ns(m) for m in nav2.limits if m.speed_limit != 0.0]
    gaps = [b - a for a, b in pairwise(stamps)]
    assert all(g >= 250_000_000 for g in gaps), gaps
    # 3 s of scan time at 4 Hz: 12 limits at most (fewer if a loaded machine skipped scans).
    assert 4 <= len(stamps) <= 12, stamps
    assert len(nav2.empowerment) > len(stamps) + 5, "scores the gate held back"


def test_the_limit_is_released_when_inputs_go_stale(nav2):
    """No score for input_timeout (0.5 s): one speed_limit 0.0; scores again: limits again."""
    nav2.limits.clear()
    nav2.feed(3, first_sec=9000, rate_hz=10.0)
    wait_until(lambda: nav2.limits, "a speed limit", nav2.executor, timeout=10)
    assert nav2.limits[-1].speed_limit > 0.0
    nav2.spin_for(1.5)  # inputs stop
    releases = [m for m in nav2.limits if m.speed_limit == 0.0]
    assert len(releases) == 1, nav2.limits
    assert nav2.limits[-1].speed_limit == 0.0 and nav2.limits[-1].percentage is True
    nav2.feed(2, first_sec=9100, rate_hz=10.0)
    wait_until(
        lambda: nav2.limits[-1].speed_limit > 0.0, "a limit again", nav2.executor, timeout=10
    )


@pytest.mark.parametrize("speed_limit_node", [("input_timeout:=30.0",)], indirect=True)
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_the_limit_is_released_when_the_node_stops(nav2, speed_limit_node, sig):
    """Stopped cleanly while a limit is in force (inputs fresh: input_timeout 30 s), the node
    releases it before it leaves the domain."""
    nav2.limits.clear()
    nav2.feed(3, first_sec=9500, rate_hz=10.0)
    wait_until(lambda: nav2.limits, "a speed limit", nav2.executor, timeout=10)
    nav2.spin_for(0.2)
    assert all(m.speed_limit > 0.0 for m in nav2.limits)
    speed_limit_node.send_signal(sig)  # by PID
    speed_limit_node.wait(timeout=10)
    assert speed_limit_node.returncode == 0
    wait_until(lambda: nav2.limits[-1].speed_limit == 0.0, "the release", nav2.executor, timeout=5)
    assert sum(m.speed_limit == 0.0 for m in nav2.limits) == 1
