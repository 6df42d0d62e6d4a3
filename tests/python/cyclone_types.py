"""The ROS 2 messages cstep speaks, as Eclipse Cyclone DDS (``cyclonedds`` Python) IDL types.

What ``rosidl`` generates for DDS, written out by hand: each message ``pkg/msg/Name`` is the
struct ``pkg::msg::dds_::Name_`` (a service's request and response ``pkg::srv::dds_::Name_Request_``
and ``Name_Response_``), fields in the order of the ``.msg`` / ``.srv`` file, plain (XCDR1) CDR.
A topic ``/a/b`` is the DDS topic ``rt/a/b``, a service ``/s`` the topics ``rq/sRequest`` and
``rr/sReply``. The cstep_msgs types follow ``msg/msg/*.msg`` and ``msg/srv/Evaluate.srv``.

:func:`ros_qos` is the QoS rmw gives a ROS profile. :func:`localhost_config` is a Cyclone
configuration that keeps a participant on this machine, on one domain.
"""

from dataclasses import dataclass

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import array, float32, float64, int32, int64, sequence, uint32, uint64
from cyclonedds.qos import Policy, Qos
from cyclonedds.util import duration


@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    sec: int32
    nanosec: uint32


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    stamp: Time
    frame_id: str


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    x: float64
    y: float64
    z: float64
    w: float64


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    x: float64
    y: float64
    z: float64


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    position: Point
    orientation: Quaternion


@dataclass
class PoseWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::PoseWithCovariance_"):
    pose: Pose
    covariance: array[float64, 36]


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    linear: Vector3
    angular: Vector3


@dataclass
class TwistWithCovariance(IdlStruct, typename="geometry_msgs::msg::dds_::TwistWithCovariance_"):
    twist: Twist
    covariance: array[float64, 36]


@dataclass
class Odometry(IdlStruct, typename="nav_msgs::msg::dds_::Odometry_"):
    header: Header
    child_frame_id: str
    pose: PoseWithCovariance
    twist: TwistWithCovariance


@dataclass
class LaserScan(IdlStruct, typename="sensor_msgs::msg::dds_::LaserScan_"):
    header: Header
    angle_min: float32
    angle_max: float32
    angle_increment: float32
    time_increment: float32
    scan_time: float32
    range_min: float32
    range_max: float32
    ranges: sequence[float32]
    intensities: sequence[float32]


@dataclass
class Empowerment(IdlStruct, typename="cstep_msgs::msg::dds_::Empowerment_"):
    header: Header
    empowerment: float64
    reachable_volume: float64
    terminal_volume: float64
    free_volume: float64
    safety_coefficient: float64
    horizon: float64
    num_trajectories: uint32
    num_colliding: uint32
    valid: bool
    status: str


@dataclass
class EmpoweredReward(IdlStruct, typename="cstep_msgs::msg::dds_::EmpoweredReward_"):
    header: Header
    reward: float64
    task_reward: float64
    empowerment_term: float64
    safety_coefficient: float64
    valid: bool


@dataclass
class EvaluateRequest(IdlStruct, typename="cstep_msgs::srv::dds_::Evaluate_Request_"):
    """The request as rmw_fastrtps and ros2-client's ``Enhanced`` mapping put it on the wire:
    the bare request; the request id travels outside the payload (see test_cyclone.py)."""

    odom: Odometry
    scan: LaserScan
    goal: Point
    has_goal: bool


@dataclass
class EvaluateResponse(IdlStruct, typename="cstep_msgs::srv::dds_::Evaluate_Response_"):
    """The response as the node sends it: the bare response."""

    empowerment: Empowerment
    reward: EmpoweredReward


@dataclass
class CycloneEvaluateRequest(IdlStruct, typename="cstep_msgs::srv::dds_::Evaluate_Request_"):
    """The request as rmw_cyclonedds writes it: its request header (``cdds_request_header_t``:
    the client's 64-bit id and a sequence number) in front of the request, in one CDR stream."""

    guid: uint64
    seq: int64
    odom: Odometry
    scan: LaserScan
    goal: Point
    has_goal: bool


@dataclass
class CycloneEvaluateResponse(IdlStruct, typename="cstep_msgs::srv::dds_::Evaluate_Response_"):
    """The response as an rmw_cyclonedds client expects it: the request's header, then the
    response."""

    guid: uint64
    seq: int64
    empowerment: Empowerment
    reward: EmpoweredReward


def ros_qos(reliable: bool = True, depth: int = 10) -> Qos:
    """The DDS QoS rmw_cyclonedds gives a ROS profile: KEEP_LAST ``depth``, VOLATILE, RELIABLE
    (the default profile, services' too) or BEST_EFFORT (sensor data: depth 5), and XCDR1, the
    only data representation ROS 2 uses."""
    reliability = (
        Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100))
        if reliable
        else Policy.Reliability.BestEffort
    )
    return Qos(
        reliability,
        Policy.Durability.Volatile,
        Policy.History.KeepLast(depth),
        Policy.DataRepresentation(use_cdrv0_representation=True),
    )


def localhost_config(domain_id: int) -> str:
    """A Cyclone configuration (the XML that ``CYCLONEDDS_URI`` would hold) for ``domain_id``
    that keeps its traffic on this machine: the loopback interface only, no multicast,
    discovery by unicast to the participant ports on 127.0.0.1 (as
    ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` does for the other side). Cyclone then
    advertises only 127.0.0.1 locators and sends from one socket bound to 127.0.0.1, so nothing
    it sends can leave the host. (Its two unicast receive sockets are still bound to 0.0.0.0, as
    ``ss -uanp`` shows: Cyclone binds receive sockets to the any-address.)"""
    return f"""<CycloneDDS><Domain Id="{domain_id}">
  <General>
    <Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>
    <AllowMulticast>false</AllowMulticast>
  </General>
  <Discovery>
    <ParticipantIndex>auto</ParticipantIndex>
    <MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>
    <Peers><Peer Address="127.0.0.1"/></Peers>
  </Discovery>
</Domain></CycloneDDS>"""
