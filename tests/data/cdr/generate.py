"""Generate the CDR fixtures in this folder with real rclpy (ROS 2 Jazzy, Fast DDS).

Each ``NAME.cdr`` is what ``rclpy.serialization.serialize_message`` returns for the message
built by ``NAME`` below: the 4-byte encapsulation header (``00 01 00 00``: plain CDR,
little-endian) followed by the CDR body, with one normalisation: the alignment padding bytes
are set to zero. Fast CDR (behind rmw_fastrtps) does not write its padding bytes, so they hold
whatever the buffer held before and differ from run to run; CDR gives them no meaning and
readers skip them. ``zero_padding`` finds them by walking the message's layout from rclpy's own
type introspection (``SLOT_TYPES``) and checks the walk ends exactly at the end of the bytes.

``tests/cdr_roundtrip.rs`` decodes each file with the Rust mirrors in ``src/ros/messages/mod.rs``,
checks the values set here, re-encodes and expects the same bytes; ``tests/python/
test_cdr_fixtures.py`` regenerates them and expects the committed files, so the fixtures
provably come from rclpy.

Regenerate after changing a message (``make test-python`` first, for the test-only nav2_msgs):
    CSTEP_TEST_INTERFACES=target/test-interfaces/install \
    LD_LIBRARY_PATH=target/test-interfaces/install/lib .venv/bin/python tests/data/cdr/generate.py
"""

import importlib
import math
import struct
import sys
from pathlib import Path

from builtin_interfaces.msg import Duration, Time
from cstep_msgs.msg import EmpoweredReward, Empowerment
from cstep_msgs.srv import Evaluate, EvaluateBatch
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Odometry
from rclpy.serialization import serialize_message
from rosidl_parser.definition import (
    AbstractNestedType,
    AbstractString,
    AbstractWString,
    Array,
    BasicType,
    NamespacedType,
)
from sensor_msgs.msg import CompressedImage, LaserScan, PointCloud2, PointField
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray, MeshFile, UVCoordinate

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "python"))
from nav2_msgs_loader import speed_limit_type  # tests/python, just put on the path

# The encapsulation header rclpy puts before the body: CDR (XCDR1), little-endian, no options.
ENCAPSULATION_CDR_LE = b"\x00\x01\x00\x00"

# Size (= CDR alignment) of each rosidl basic type.
BASIC_SIZES = {
    "boolean": 1, "octet": 1, "char": 1, "int8": 1, "uint8": 1,
    "int16": 2, "uint16": 2, "wchar": 2,
    "float": 4, "int32": 4, "uint32": 4,
    "double": 8, "int64": 8, "uint64": 8,
}  # fmt: skip


class _Walker:
    """Walks a CDR body along a rosidl type, collecting the alignment padding offsets."""

    def __init__(self, body: bytes) -> None:
        self.body = body
        self.pos = 0
        self.padding: list[int] = []

    def align(self, n: int) -> None:
        while self.pos % n:
            self.padding.append(self.pos)
            self.pos += 1

    def take(self, n: int) -> None:
        if self.pos + n > len(self.body):
            raise ValueError(f"CDR body ends at {len(self.body)}, field needs {self.pos + n}")
        self.pos += n

    def u32(self) -> int:
        self.align(4)
        (value,) = struct.unpack_from("<I", self.body, self.pos)
        self.take(4)
        return value

    def walk(self, slot) -> None:
        if isinstance(slot, BasicType):
            size = BASIC_SIZES[slot.typename]
            self.align(size)
            self.take(size)
        elif isinstance(slot, AbstractString):
            self.take(self.u32())  # length includes the terminating NUL
        elif isinstance(slot, AbstractWString):
            self.take(2 * self.u32())
        elif isinstance(slot, AbstractNestedType):
            count = slot.size if isinstance(slot, Array) else self.u32()
            for _ in range(count):
                self.walk(slot.value_type)
        elif isinstance(slot, NamespacedType):
            module = importlib.import_module(".".join(slot.namespaces))
            for field in getattr(module, slot.name).SLOT_TYPES:
                self.walk(field)
        else:
            raise TypeError(f"no CDR layout for {slot!r}")


def zero_padding(data: bytes, msg_type) -> bytes:
    """``data`` (encapsulation header + CDR body of a ``msg_type``) with its padding zeroed."""
    if data[:4] != ENCAPSULATION_CDR_LE:
        raise ValueError(f"expected the CDR little-endian header, got {data[:4].hex()}")
    walker = _Walker(data[4:])
    for slot in msg_type.SLOT_TYPES:
        walker.walk(slot)
    if walker.pos != len(walker.body):
        raise ValueError(f"layout ends at {walker.pos}, the body has {len(walker.body)} bytes")
    body = bytearray(walker.body)
    for offset in walker.padding:
        body[offset] = 0
    return ENCAPSULATION_CDR_LE + bytes(body)


def serialize(msg) -> bytes:
    """rclpy's CDR bytes of ``msg``, padding zeroed."""
    return zero_padding(serialize_message(msg), type(msg))


def header() -> Header:
    # A 9-byte frame_id (with its NUL) leaves the next field unaligned: padding gets exercised.
    return Header(stamp=Time(sec=1_700_000_123, nanosec=456_789_012), frame_id="base_scan")


def odometry() -> Odometry:
    msg = Odometry()
    msg.header = Header(stamp=Time(sec=42, nanosec=500_000_000), frame_id="odom")
    msg.child_frame_id = "base_link"
    msg.pose.pose.position.x = 1.25
    msg.pose.pose.position.y = -0.1
    msg.pose.pose.position.z = 0.75
    half = math.pi / 8.0  # yaw of pi/4 about z
    msg.pose.pose.orientation.z = math.sin(half)
    msg.pose.pose.orientation.w = math.cos(half)
    msg.pose.covariance = [0.01 * i for i in range(36)]
    msg.twist.twist.linear.x = 1.0
    msg.twist.twist.linear.y = -0.5
    msg.twist.twist.linear.z = 0.05
    msg.twist.twist.angular.z = 0.3
    msg.twist.covariance = [-1.0 * i for i in range(36)]
    return msg


def laser_scan() -> LaserScan:
    msg = LaserScan()
    msg.header = Header(stamp=Time(sec=42, nanosec=499_000_000), frame_id="laser")
    msg.angle_min = -math.pi
    msg.angle_max = math.pi - 2.0 * math.pi / 8.0
    msg.angle_increment = 2.0 * math.pi / 8.0
    msg.time_increment = 1.0e-4
    msg.scan_time = 0.025
    msg.range_min = 0.05
    msg.range_max = 3.5
    # REP 117: +inf no return, NaN invalid, -inf too close to measure.
    msg.ranges = [0.5, math.inf, math.nan, -math.inf, 1.25, 3.0, 0.1, 2.75]
    msg.intensities = [100.0, 0.0, 0.0, 0.0, 57.5, 12.0, 255.0, 1.5]
    return msg


def laser_scan_empty() -> LaserScan:
    # No beams and an empty frame_id: empty sequences and strings are encoded too.
    return LaserScan(header=Header(stamp=Time(sec=0, nanosec=0), frame_id=""))


def empowerment() -> Empowerment:
    return Empowerment(
        header=Header(stamp=Time(sec=42, nanosec=499_000_000), frame_id="odom"),
        empowerment=math.log(3.25),
        reachable_volume=4.0,
        terminal_volume=0.75,
        free_volume=3.25,
        safety_coefficient=0.5,
        horizon=1.0,
        num_trajectories=150,
        num_colliding=27,
        valid=True,
        status="ok",
    )


def empowered_reward() -> EmpoweredReward:
    return EmpoweredReward(
        header=Header(stamp=Time(sec=42, nanosec=499_000_000), frame_id="odom"),
        reward=math.exp(-2.0) * math.log(0.5 * 3.25),
        task_reward=math.exp(-2.0),
        empowerment_term=math.log(0.5 * 3.25),
        safety_coefficient=0.5,
        valid=True,
    )


def evaluate_request() -> Evaluate.Request:
    return Evaluate.Request(
        odom=odometry(),
        scan=laser_scan(),
        goal=Point(x=4.0, y=0.0, z=1.0),
        has_goal=True,
    )


def evaluate_response() -> Evaluate.Response:
    floor = math.log(1e-4)
    return Evaluate.Response(
        empowerment=Empowerment(
            header=Header(stamp=Time(sec=7, nanosec=1), frame_id="map"),
            empowerment=floor,
            reachable_volume=2.5,
            terminal_volume=2.5,
            free_volume=0.0,
            safety_coefficient=1.0,
            horizon=1.5,
            num_trajectories=2000,
            num_colliding=2000,
            valid=False,
            status="every trajectory collides",
        ),
        reward=EmpoweredReward(
            header=Header(stamp=Time(sec=7, nanosec=1), frame_id="map"),
            reward=floor,
            task_reward=1.0,
            empowerment_term=floor,
            safety_coefficient=1.0,
            valid=False,
        ),
    )


def evaluate_batch_request() -> EvaluateBatch.Request:
    """Two states: the first with a goal, the second (an empty scan) reported in collision, so
    every sequence holds entries of its element type and the bool arrays differ."""
    second = odometry()
    second.pose.pose.position.x = -2.5
    return EvaluateBatch.Request(
        odom=[odometry(), second],
        scan=[laser_scan(), laser_scan_empty()],
        goal=[Point(x=4.0, y=0.0, z=1.0), Point()],
        has_goal=[True, False],
        in_collision=[False, True],
    )


def evaluate_batch_response() -> EvaluateBatch.Response:
    """The answers to two states: a measured one and one reported in collision."""
    floor = math.log(1e-4)
    collided = Empowerment(
        header=Header(stamp=Time(sec=0, nanosec=0), frame_id="odom"),
        empowerment=floor,
        safety_coefficient=0.5,
        horizon=1.0,
        num_trajectories=150,
        num_colliding=150,
        valid=False,
        status="robot already in collision",
    )
    collided_reward = EmpoweredReward(
        header=collided.header,
        reward=math.log(0.5) + floor,
        task_reward=1.0,
        empowerment_term=math.log(0.5) + floor,
        safety_coefficient=0.5,
        valid=False,
    )
    return EvaluateBatch.Response(
        empowerment=[empowerment(), collided], reward=[empowered_reward(), collided_reward]
    )


def marker_array() -> MarkerArray:
    """Two markers: the node's kind (points with per-point colours) and one with every Humble+
    field set, odd-length strings and byte arrays included, so each field's place and alignment
    in the layout is checked."""
    points = Marker(
        header=Header(stamp=Time(sec=42, nanosec=499_000_000), frame_id="odom"),
        ns="cstep/endpoints",
        id=0,
        type=Marker.POINTS,
        action=Marker.ADD,
        lifetime=Duration(sec=0, nanosec=500_000_000),
        points=[Point(x=1.25, y=-0.5, z=1.0), Point(x=-2.0, y=0.75, z=1.125)],
        colors=[ColorRGBA(r=0.1, g=0.8, b=0.1, a=1.0), ColorRGBA(r=0.9, g=0.1, b=0.1, a=1.0)],
    )
    points.scale.x = points.scale.y = 0.05
    points.color = ColorRGBA(r=0.1, g=0.8, b=0.1, a=1.0)
    everything = Marker(
        header=Header(stamp=Time(sec=-3, nanosec=7), frame_id="base"),
        ns="all",
        id=-17,
        type=Marker.TRIANGLE_LIST,
        action=Marker.DELETEALL,
        lifetime=Duration(sec=2, nanosec=1),
        frame_locked=True,
        points=[Point(x=0.5, y=0.25, z=-1.0)],
        colors=[],
        texture_resource="file://t.png",
        texture=CompressedImage(
            header=Header(stamp=Time(sec=1, nanosec=2), frame_id="cam"),
            format="png",
            data=bytes([137, 80, 78]),
        ),
        uv_coordinates=[UVCoordinate(u=0.25, v=0.75)],
        text="hi",
        mesh_resource="package://m.dae",
        mesh_file=MeshFile(filename="m.stl", data=bytes([1, 2, 3, 4, 5])),
        mesh_use_embedded_materials=True,
    )
    everything.pose.position.x = 3.0
    everything.pose.orientation.w = 0.5
    everything.scale.z = 2.5
    everything.color = ColorRGBA(r=0.2, g=0.5, b=1.0, a=0.25)
    return MarkerArray(markers=[points, everything])


# File stem -> message factory. The Rust test reads the same names.
# The points of the cloud fixtures: (x, y, z, intensity); the NaN point is a missing return.
CLOUD_POINTS = [
    (1.5, 0.0, 0.1, 10.0),
    (-0.5, 2.25, -0.05, 20.0),
    (math.nan, math.nan, math.nan, 0.0),
]


def point_cloud(big_endian: bool) -> PointCloud2:
    """An unordered cloud of ``CLOUD_POINTS`` as FLOAT32 x, y, z, intensity (16 bytes a point),
    in the byte order given (sensor_msgs_py, which builds clouds in rclpy, has no PyPI wheel)."""
    order = ">" if big_endian else "<"
    msg = PointCloud2()
    msg.header = Header(stamp=Time(sec=7, nanosec=250_000_000), frame_id="lidar")
    msg.height, msg.width = 1, len(CLOUD_POINTS)
    msg.fields = [
        PointField(name=name, offset=4 * i, datatype=PointField.FLOAT32, count=1)
        for i, name in enumerate(("x", "y", "z", "intensity"))
    ]
    msg.is_bigendian = big_endian
    msg.point_step, msg.row_step = 16, 16 * len(CLOUD_POINTS)
    msg.data = b"".join(struct.pack(order + "4f", *p) for p in CLOUD_POINTS)
    msg.is_dense = False
    return msg


def point_cloud2() -> PointCloud2:
    return point_cloud(big_endian=False)


def point_cloud2_big_endian() -> PointCloud2:
    return point_cloud(big_endian=True)


def pose_stamped() -> PoseStamped:
    msg = PoseStamped()
    msg.header = Header(stamp=Time(sec=7, nanosec=1), frame_id="map")
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = 3.9, -0.3, 1.0
    msg.pose.orientation.w = 1.0
    return msg


def diagnostic_array() -> DiagnosticArray:
    status = DiagnosticStatus(
        level=DiagnosticStatus.STALE,
        name="cstep: empowerment",
        message="inputs stale: no score",
        hardware_id="cstep",
        values=[
            KeyValue(key="scans_scored", value="12"),
            KeyValue(key="odometry_age_s", value="never"),
        ],
    )
    return DiagnosticArray(
        header=Header(stamp=Time(sec=9, nanosec=0), frame_id=""), status=[status]
    )


def speed_limit():
    """Nav2's SpeedLimit as the node publishes it: a percentage, stamped with the scan, in the
    odometry frame. Needs the test-only nav2_msgs (``make test-python`` builds it)."""
    SpeedLimit = speed_limit_type()
    if SpeedLimit is None:
        raise RuntimeError(
            "the speed_limit fixture needs the test-only nav2_msgs: run `make test-python`, or set "
            "CSTEP_TEST_INTERFACES and LD_LIBRARY_PATH as it does"
        )
    return SpeedLimit(
        header=Header(stamp=Time(sec=5001, nanosec=250_000_000), frame_id="odom"),
        percentage=True,
        speed_limit=79.375,
    )


FIXTURES = {
    "header": header,
    "odometry": odometry,
    "laser_scan": laser_scan,
    "laser_scan_empty": laser_scan_empty,
    "empowerment": empowerment,
    "empowered_reward": empowered_reward,
    "evaluate_request": evaluate_request,
    "evaluate_response": evaluate_response,
    "evaluate_batch_request": evaluate_batch_request,
    "evaluate_batch_response": evaluate_batch_response,
    "pose_stamped": pose_stamped,
    "diagnostic_array": diagnostic_array,
    "marker_array": marker_array,
    "point_cloud2": point_cloud2,
    "point_cloud2_big_endian": point_cloud2_big_endian,
    "speed_limit": speed_limit,
}


def serialize_all() -> dict[str, bytes]:
    """Every fixture's bytes as rclpy serializes them (padding zeroed), by file name."""
    return {f"{name}.cdr": serialize(make()) for name, make in FIXTURES.items()}


def main() -> int:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else HERE
    for name, data in serialize_all().items():
        (out / name).write_bytes(data)
        print(f"{out / name}: {len(data)} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main())
