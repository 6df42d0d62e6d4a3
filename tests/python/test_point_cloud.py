"""3-D input: `cstep node -p use_point_cloud:=true` scores `sensor_msgs/PointCloud2` from an
rclpy publisher over real DDS on localhost, in the test's own domain.

A cloud whose points lie on the bearings of the 720-bin scan it becomes must score exactly as
that scan does through `cstep eval` (the node's own scoring path, no DDS): the points outside
the height band, beyond the range and not finite are dropped and counted, and a cloud that
cannot be read is reported in diagnostics and skipped.
"""

import math

import numpy as np
import pytest
from conftest import wait_until
from cstep_msgs.msg import EmpoweredReward, Empowerment
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import Odometry
from node_rig import RELIABLE, cstep_eval, message_to_ordereddict, odometry, start_node, stop_gently
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import LaserScan, PointCloud2, PointField

BINS = 720  # crates/cstep-core/src/cloud.rs: CLOUD_BINS
INCREMENT = 2 * math.pi / BINS
RANGE_MIN, RANGE_MAX = 0.1, 3.0
WIDTH = 2.5  # a corridor along x, the robot in its middle
PARAMS = ("use_point_cloud:=true", f"cloud_range_min:={RANGE_MIN}", f"cloud_range_max:={RANGE_MAX}")


def corridor_points() -> np.ndarray:
    """The corridor's walls, one point per bin's centre bearing within range, at the robot's
    height (float32, as a LiDAR driver sends them)."""
    bearings = -math.pi + (np.arange(BINS) + 0.5) * INCREMENT
    s = np.abs(np.sin(bearings))
    r = np.divide(WIDTH / 2, s, out=np.full(BINS, np.inf), where=s > 1e-9)
    keep = r <= RANGE_MAX
    return np.stack(
        [r[keep] * np.cos(bearings[keep]), r[keep] * np.sin(bearings[keep]), np.zeros(keep.sum())],
        axis=1,
    ).astype(np.float32)


def expected_scan(points: np.ndarray) -> LaserScan:
    """The scan the node makes of ``points`` (level robot): per bin the nearest horizontal
    range, computed in double from the float32 coordinates and stored as float32; +inf where
    the bin has no point (free to the range)."""
    scan = LaserScan()
    scan.header.stamp.sec = 7
    scan.angle_min = -math.pi + 0.5 * INCREMENT
    scan.angle_increment = INCREMENT
    scan.angle_max = scan.angle_min + (BINS - 1) * INCREMENT
    scan.range_min, scan.range_max = RANGE_MIN, RANGE_MAX
    ranges = np.full(BINS, np.inf, dtype=np.float32)
    xy = points[:, :2].astype(np.float64)
    r = np.hypot(xy[:, 0], xy[:, 1])
    bins = np.minimum(
        ((np.arctan2(xy[:, 1], xy[:, 0]) + math.pi) / INCREMENT).astype(int), BINS - 1
    )
    np.minimum.at(ranges, bins, r.astype(np.float32))
    scan.ranges = ranges.tolist()
    return scan


def cloud_message(points: np.ndarray, sec: int, fields: str = "xyz") -> PointCloud2:
    """An unorganised cloud of ``points`` (float32 x, y, z, padded to 16 bytes as drivers do),
    with only the named ``fields`` declared."""
    cloud = PointCloud2()
    cloud.header.stamp.sec = sec
    cloud.header.frame_id = "base_link"
    cloud.height, cloud.width = 1, len(points)
    cloud.fields = [
        PointField(name=name, offset=4 * i, datatype=PointField.FLOAT32, count=1)
        for i, name in enumerate("xyz")
        if name in fields
    ]
    cloud.is_bigendian = False
    cloud.point_step = 16
    cloud.row_step = 16 * len(points)
    padded = np.zeros((len(points), 4), dtype=np.float32)
    padded[:, :3] = points
    cloud.data = padded.tobytes()
    cloud.is_dense = False
    return cloud


class CloudRig:
    """This test's rclpy side: a cloud and an odometry publisher, the score and diagnostics
    subscribers."""

    def __init__(self, context, executor):
        self.node = Node("cstep_cloud_rig", context=context)
        executor.add_node(self.node)
        self.executor = executor
        self.odom = self.node.create_publisher(Odometry, "odom", RELIABLE)
        self.cloud = self.node.create_publisher(PointCloud2, "cloud", qos_profile_sensor_data)
        self.empowerment: list[Empowerment] = []
        self.diagnostics: list[DiagnosticArray] = []
        self.node.create_subscription(
            Empowerment, "cstep/empowerment", self.empowerment.append, RELIABLE
        )
        self.node.create_subscription(EmpoweredReward, "cstep/reward", lambda _: None, RELIABLE)
        self.node.create_subscription(
            DiagnosticArray, "/diagnostics", self.diagnostics.append, RELIABLE
        )
        wait_until(
            lambda: (
                self.cloud.get_subscription_count() >= 1
                and self.odom.get_subscription_count() >= 1
                and self.node.count_publishers("/cstep/empowerment") >= 1
            ),
            "the node's point cloud and odometry subscriptions",
            executor,
        )

    def send_until_scored(self, cloud: PointCloud2) -> Empowerment:
        """Sends odometry and ``cloud`` until the cloud's score (by its stamp) arrives."""
        stamp = cloud.header.stamp.sec

        def scored() -> bool:
            self.odom.publish(odometry())
            self.cloud.publish(cloud)
            return any(e.header.stamp.sec == stamp for e in self.empowerment)

        wait_until(scored, f"the score of the cloud stamped {stamp}", self.executor)
        return next(e for e in self.empowerment if e.header.stamp.sec == stamp)

    def values(self, after: int) -> dict[str, str]:
        """The key-values of the first diagnostics after the first ``after`` received."""
        wait_until(lambda: len(self.diagnostics) > after, "diagnostics", self.executor, timeout=5)
        return {kv.key: kv.value for kv in self.diagnostics[after].status[0].values}


@pytest.fixture
def cloud_rig(ros_domain, ros_context, executor):
    proc = start_node(*PARAMS)
    rig = CloudRig(ros_context, executor)
    yield rig
    rig.node.destroy_node()
    stop_gently(proc)


def test_a_cloud_scores_exactly_as_the_scan_of_its_points(cloud_rig, tmp_path):
    walls = corridor_points()
    # Dropped: a point 1 m above the band, one beyond the range, one inside range_min, a NaN.
    extra = np.array(
        [[0.0, 1.0, 1.0], [3.5, 0.0, 0.0], [0.05, 0.0, 0.0], [np.nan, 0.0, 0.0]], np.float32
    )
    score = cloud_rig.send_until_scored(cloud_message(np.vstack([walls, extra]), sec=7))
    expected = cstep_eval(tmp_path, odometry(), expected_scan(walls))
    assert score.valid and expected["valid"]
    assert score.empowerment == expected["empowerment"]
    assert score.num_colliding == expected["num_colliding"]
    # A narrower corridor scores lower: the cloud is read, not ignored.
    narrower = cloud_message(walls * np.array([1.0, 0.6, 1.0], np.float32), sec=8)
    assert cloud_rig.send_until_scored(narrower).empowerment < score.empowerment
    values = cloud_rig.values(after=len(cloud_rig.diagnostics))
    assert values["cloud_points"] == str(len(walls))
    assert values["cloud_points_used"] == str(len(walls))
    seen = cloud_message(np.vstack([walls, extra]), sec=9)
    cloud_rig.send_until_scored(seen)
    values = cloud_rig.values(after=len(cloud_rig.diagnostics))
    assert (
        values["cloud_points"],
        values["cloud_points_used"],
        values["cloud_points_outside_band"],
        values["cloud_points_out_of_range"],
        values["cloud_points_not_finite"],
    ) == (str(len(walls) + 4), str(len(walls)), "1", "2", "1")


def test_a_cloud_that_cannot_be_read_is_reported_and_skipped(cloud_rig):
    walls = corridor_points()
    cloud_rig.send_until_scored(cloud_message(walls, sec=20))
    # A sensor that keeps sending clouds without z, with fresh odometry (diagnostics say STALE
    # instead once the inputs go stale, so the bad clouds keep coming while it is checked).
    bad = iter(range(21, 10_000))

    def reported() -> bool:
        cloud_rig.odom.publish(odometry())
        cloud_rig.cloud.publish(cloud_message(walls, sec=next(bad), fields="xy"))
        return any(
            "no 'z' field" in d.status[0].message and d.status[0].level == b"\x01"
            for d in cloud_rig.diagnostics
        )

    wait_until(reported, "a WARN naming the missing field", cloud_rig.executor, timeout=10)
    last_bad = next(bad)
    assert not [e for e in cloud_rig.empowerment if 21 <= e.header.stamp.sec < last_bad]
    assert int(cloud_rig.values(after=len(cloud_rig.diagnostics))["inputs_rejected"]) >= 1
    # The node goes on scoring readable clouds.
    assert cloud_rig.send_until_scored(cloud_message(walls, sec=last_bad + 1)).valid


def test_echo_prints_a_cloud_field_for_field(ros_context, executor, echo):
    node = Node("cloud_publisher", context=ros_context)
    executor.add_node(node)
    publisher = node.create_publisher(PointCloud2, "/lidar/points", qos_profile_sensor_data)
    sent = cloud_message(corridor_points()[:5], sec=3)
    # The type is found from the publisher; its data prints byte by byte.
    e = echo("/lidar/points", "--once", "--timeout", "20")

    def printed() -> bool:
        publisher.publish(sent)
        executor.spin_once(timeout_sec=0.05)
        return not e.running()

    wait_until(printed, "cstep echo to print the cloud", timeout=25)
    assert e.finish() == 0, e.stderr
    [document] = e.documents()
    assert document == message_to_ordereddict(sent)
    assert len(document["data"]) == 5 * 16
    node.destroy_node()
