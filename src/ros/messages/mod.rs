//! Serde mirrors of the ROS 2 messages cstep reads and writes.
//!
//! Field names and order follow the `.msg` definitions exactly: the same structs serve JSON
//! (`cstep eval`, rosbridge-style, read by [`json`]) and CDR (the DDS wire format). Every
//! field has its ROS default so hand-written JSON may leave out what it does not need, and every
//! struct refuses a field it does not have (`deny_unknown_fields`), so a misspelt field is an
//! error rather than silently its default. CDR carries no field names and is unaffected.
//! [`yaml`] prints them as `ros2 topic echo` does (`cstep echo`).

pub mod json;
pub mod point_cloud;
pub mod yaml;

pub use point_cloud::{PointCloud2, PointField};

use ros2_client::{MessageTypeName, ServiceTypeName};
use serde::{Deserialize, Serialize};
use serde_big_array::BigArray;

/// `builtin_interfaces/Time`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Time {
    /// The system clock's time now (since the Unix epoch), as ROS's wall clock reads it: the
    /// stamp of diagnostics without sim time and of log lines.
    pub fn wall_clock_now() -> Self {
        let since_epoch = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        Self {
            sec: since_epoch.as_secs() as i32,
            nanosec: since_epoch.subsec_nanos(),
        }
    }

    /// The time in seconds.
    pub fn seconds(self) -> f64 {
        self.sec as f64 + self.nanosec as f64 * 1e-9
    }
}

/// `std_msgs/Header`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Header {
    /// Acquisition time.
    pub stamp: Time,
    /// Coordinate frame of the data.
    pub frame_id: String,
}

/// `geometry_msgs/Point`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Point {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// z, metres.
    pub z: f64,
}

/// `geometry_msgs/Vector3`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Vector3 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
}

/// `geometry_msgs/Quaternion`; defaults to the identity (w = 1) as in ROS 2.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Quaternion {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
    /// w (scalar) component.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }
    }
}

/// `geometry_msgs/Pose`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation (body → parent frame).
    pub orientation: Quaternion,
}

/// `geometry_msgs/PoseWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Row-major 6×6 covariance (x, y, z, rotation about x, y, z).
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

/// `geometry_msgs/Twist`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Twist {
    /// Linear velocity, m/s.
    pub linear: Vector3,
    /// Angular velocity, rad/s.
    pub angular: Vector3,
}

/// `geometry_msgs/TwistWithCovariance`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TwistWithCovariance {
    /// The twist.
    pub twist: Twist,
    /// Row-major 6×6 covariance.
    #[serde(with = "BigArray")]
    pub covariance: [f64; 36],
}

impl Default for PoseWithCovariance {
    fn default() -> Self {
        Self {
            pose: Pose::default(),
            covariance: [0.0; 36],
        }
    }
}

impl Default for TwistWithCovariance {
    fn default() -> Self {
        Self {
            twist: Twist::default(),
            covariance: [0.0; 36],
        }
    }
}

/// `nav_msgs/Odometry`: pose in `header.frame_id`, twist in `child_frame_id` (the body).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Odometry {
    /// Stamp and parent frame.
    pub header: Header,
    /// The body frame the twist is expressed in.
    pub child_frame_id: String,
    /// Pose in the parent frame.
    pub pose: PoseWithCovariance,
    /// Velocity in the body frame.
    pub twist: TwistWithCovariance,
}

/// `sensor_msgs/LaserScan`. In JSON, `null` (rosbridge's encoding of non-finite numbers) and
/// the strings `"inf"`, `"-inf"`, `"nan"` are accepted in `ranges` and `intensities`; `null`
/// reads as `+inf` (no return), the value rosbridge most often stands it in for. A number given
/// for an angle or range limit that no `float32` holds (`1e300`, `1e-50`) is refused naming the
/// field and the number as written, not narrowed to `inf` or 0 and reported as that.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LaserScan {
    /// Stamp of the first beam and the sensor frame.
    pub header: Header,
    /// Bearing of the first beam, radians.
    #[serde(deserialize_with = "float32::narrow")]
    pub angle_min: f32,
    /// Bearing of the last beam, radians.
    #[serde(deserialize_with = "float32::narrow")]
    pub angle_max: f32,
    /// Bearing step, radians.
    #[serde(deserialize_with = "float32::narrow")]
    pub angle_increment: f32,
    /// Time between beams, seconds.
    pub time_increment: f32,
    /// Time between scans, seconds.
    pub scan_time: f32,
    /// Shortest measurable range, metres.
    #[serde(deserialize_with = "float32::narrow")]
    pub range_min: f32,
    /// Longest measurable range, metres.
    #[serde(deserialize_with = "float32::narrow")]
    pub range_max: f32,
    /// Ranges, metres (REP 117 for non-finite values).
    #[serde(deserialize_with = "lenient_floats::deserialize")]
    pub ranges: Vec<f32>,
    /// Intensities, device units.
    #[serde(deserialize_with = "lenient_floats::deserialize")]
    pub intensities: Vec<f32>,
}

/// `cstep_msgs/Empowerment`: the C-STEP score of one state.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Empowerment {
    /// The scan's stamp and the odometry frame.
    pub header: Header,
    /// `log(free_volume)` in nats, clamped to a documented floor; never NaN or infinite.
    pub empowerment: f64,
    /// Volume of the estimated reachable set `R̂` (m² or m³).
    pub reachable_volume: f64,
    /// Volume of the estimated terminal set `T̂` inside `R̂`.
    pub terminal_volume: f64,
    /// `reachable_volume − terminal_volume` (as estimated).
    pub free_volume: f64,
    /// Safety coefficient `c` in effect.
    pub safety_coefficient: f64,
    /// Horizon `T`, seconds.
    pub horizon: f64,
    /// Trajectories sampled.
    pub num_trajectories: u32,
    /// Trajectories that collided.
    pub num_colliding: u32,
    /// False when the score is a floor value, not a measurement (see `status`).
    pub valid: bool,
    /// "ok", or why the score is not valid.
    pub status: String,
}

/// `cstep_msgs/EmpoweredReward`: the reward an RL agent receives for one state.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmpoweredReward {
    /// The scan's stamp and the odometry frame.
    pub header: Header,
    /// `task_reward · empowerment_term`.
    pub reward: f64,
    /// `exp(−‖p − goal‖)`, or 1 without a goal.
    pub task_reward: f64,
    /// `log(c · free_volume)`.
    pub empowerment_term: f64,
    /// Safety coefficient `c` in effect.
    pub safety_coefficient: f64,
    /// Same as the matching `Empowerment.valid`.
    pub valid: bool,
}

/// `geometry_msgs/PoseStamped`: the optional goal input.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The goal pose.
    pub pose: Pose,
}

/// `cstep_msgs/srv/Evaluate` request: one state to score, synchronously.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EvaluateRequest {
    /// The robot's state.
    pub odom: Odometry,
    /// What its LiDAR sees.
    pub scan: LaserScan,
    /// Goal position for the task reward (used when `has_goal`).
    pub goal: Point,
    /// Whether `goal` is set.
    pub has_goal: bool,
}

/// `cstep_msgs/srv/Evaluate` response.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvaluateResponse {
    /// The score.
    pub empowerment: Empowerment,
    /// The reward.
    pub reward: EmpoweredReward,
}

/// `cstep_msgs/srv/EvaluateBatch` request: K states to score in one call, each as
/// [`EvaluateRequest`] would score it alone.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EvaluateBatchRequest {
    /// The K robot states.
    pub odom: Vec<Odometry>,
    /// The K scans, `scan[i]` taken at `odom[i]`.
    pub scan: Vec<LaserScan>,
    /// Empty, or K goal positions (`goal[i]` used when `has_goal[i]`).
    pub goal: Vec<Point>,
    /// Empty (no goals), or K flags.
    pub has_goal: Vec<bool>,
    /// Empty, or K flags: the caller knows state `i` is in collision.
    pub in_collision: Vec<bool>,
}

/// `cstep_msgs/srv/EvaluateBatch` response: one score and reward per requested state.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvaluateBatchResponse {
    /// The scores, in request order.
    pub empowerment: Vec<Empowerment>,
    /// The rewards, in request order.
    pub reward: Vec<EmpoweredReward>,
}

/// `diagnostic_msgs/KeyValue`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyValue {
    /// Name of the value.
    pub key: String,
    /// The value, as text.
    pub value: String,
}

/// `diagnostic_msgs/DiagnosticStatus`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiagnosticStatus {
    /// [`DiagnosticStatus::OK`], [`DiagnosticStatus::WARN`], [`DiagnosticStatus::ERROR`] or
    /// [`DiagnosticStatus::STALE`].
    pub level: u8,
    /// Component name.
    pub name: String,
    /// Human-readable summary.
    pub message: String,
    /// Hardware identifier.
    pub hardware_id: String,
    /// Details.
    pub values: Vec<KeyValue>,
}

impl DiagnosticStatus {
    /// `diagnostic_msgs/DiagnosticStatus` `OK`.
    pub const OK: u8 = 0;
    /// `WARN`.
    pub const WARN: u8 = 1;
    /// `ERROR`.
    pub const ERROR: u8 = 2;
    /// `STALE`.
    pub const STALE: u8 = 3;
}

/// `diagnostic_msgs/DiagnosticArray`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiagnosticArray {
    /// Stamp.
    pub header: Header,
    /// One status per component.
    pub status: Vec<DiagnosticStatus>,
}

/// `builtin_interfaces/Duration`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Duration {
    /// The duration closest to `seconds` (non-negative, finite; anything else reads as zero).
    pub fn from_seconds(seconds: f64) -> Self {
        if !(seconds.is_finite() && seconds > 0.0) {
            return Self::default();
        }
        let whole = seconds.floor().min(i32::MAX as f64);
        let nanosec = ((seconds - whole) * 1e9).round().min(999_999_999.0) as u32;
        Self {
            sec: whole as i32,
            nanosec,
        }
    }
}

/// `std_msgs/ColorRGBA`, each channel 0–1.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ColorRGBA {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
    /// Opacity.
    pub a: f32,
}

/// `sensor_msgs/CompressedImage` (a marker's texture).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CompressedImage {
    /// Acquisition time and frame.
    pub header: Header,
    /// Image format ("jpeg", "png", …).
    pub format: String,
    /// The compressed image bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/UVCoordinate`: a texture coordinate.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UVCoordinate {
    /// Horizontal texture coordinate.
    pub u: f32,
    /// Vertical texture coordinate.
    pub v: f32,
}

/// `visualization_msgs/MeshFile`: a mesh sent inline.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeshFile {
    /// The file name, whose extension tells the format.
    pub filename: String,
    /// The file's bytes.
    pub data: Vec<u8>,
}

/// `visualization_msgs/Marker` with every field of ROS 2 Humble and later, in `.msg` order
/// (RViz cannot decode a marker without the texture and mesh-file fields).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Marker {
    /// Stamp and the frame the pose and points are in.
    pub header: Header,
    /// Namespace: with `id`, names the marker.
    pub ns: String,
    /// Identifier within `ns`.
    pub id: i32,
    /// Shape, one of the `Marker::` type constants.
    #[serde(rename = "type")]
    pub kind: i32,
    /// [`Marker::ADD`], [`Marker::DELETE`] or [`Marker::DELETEALL`].
    pub action: i32,
    /// Pose of the marker (of the points' frame, for point and line types).
    pub pose: Pose,
    /// Size; for points the point width and height, for lines the line width (x).
    pub scale: Vector3,
    /// Colour of the whole marker (points and lines use `colors` when it is not empty).
    pub color: ColorRGBA,
    /// How long the marker lives; zero is forever.
    pub lifetime: Duration,
    /// Whether the marker follows its frame as it moves.
    pub frame_locked: bool,
    /// Points of point, line and list types.
    pub points: Vec<Point>,
    /// Per-point colours (empty, or as many as `points`).
    pub colors: Vec<ColorRGBA>,
    /// Texture file (URI), for mesh and triangle types.
    pub texture_resource: String,
    /// Inline texture.
    pub texture: CompressedImage,
    /// Texture coordinates, one per point.
    pub uv_coordinates: Vec<UVCoordinate>,
    /// Text of `TEXT_VIEW_FACING` markers.
    pub text: String,
    /// Mesh file (URI) of `MESH_RESOURCE` markers.
    pub mesh_resource: String,
    /// Inline mesh.
    pub mesh_file: MeshFile,
    /// Whether a mesh uses its own materials.
    pub mesh_use_embedded_materials: bool,
}

impl Marker {
    /// Connected line through `points`.
    pub const LINE_STRIP: i32 = 4;
    /// A sphere at each of `points`.
    pub const SPHERE_LIST: i32 = 7;
    /// A square dot at each of `points`.
    pub const POINTS: i32 = 8;
    /// Add or replace the marker `ns`/`id`.
    pub const ADD: i32 = 0;
    /// Remove the marker `ns`/`id`.
    pub const DELETE: i32 = 2;
    /// Remove every marker (of `ns`, when set).
    pub const DELETEALL: i32 = 3;
}

/// `visualization_msgs/MarkerArray`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MarkerArray {
    /// The markers, applied in order.
    pub markers: Vec<Marker>,
}

/// `nav2_msgs/SpeedLimit`: the speed limit Nav2's controller server hands to every controller
/// plugin, from the score ([`crate::speed_limit`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpeedLimit {
    /// The scan's stamp (a release: the node's clock), the odometry frame.
    pub header: Header,
    /// Whether `speed_limit` is a percentage of the controllers' maximum speed (else m/s).
    pub percentage: bool,
    /// The limit; 0.0 means no limit.
    pub speed_limit: f64,
}

/// `rosgraph_msgs/Clock`: the simulation time on `/clock` (ros2-client's own `/clock` reader
/// expects `builtin_interfaces/Time`, a type rclcpp and rclpy never publish there).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Clock {
    /// The simulation time.
    pub clock: Time,
}

/// A message type cstep exchanges over DDS, with its ROS type name (`package/msg/Name`) given
/// once, by the type: topics are created from it, so no caller spells the name again.
pub trait RosMessage: ros2_client::Message {
    /// The ROS package, e.g. `nav_msgs`.
    const PACKAGE: &'static str;
    /// The type's name in its package, e.g. `Odometry`.
    const NAME: &'static str;

    /// The type name ros2-client creates topics with.
    fn type_name() -> MessageTypeName {
        MessageTypeName::new(Self::PACKAGE, Self::NAME)
    }

    /// The type as ROS tools print it (`nav_msgs/msg/Odometry`), for messages to the user.
    fn ros_type() -> String {
        format!("{}/msg/{}", Self::PACKAGE, Self::NAME)
    }

    /// The type's name on DDS (`nav_msgs::msg::dds_::Odometry_`), as discovery reports it.
    fn dds_type() -> String {
        Self::type_name().dds_msg_type()
    }
}

/// A service cstep serves, with its ROS type name (`package/srv/Name`) given once.
pub trait RosService {
    /// The request message.
    type Request: ros2_client::Message;
    /// The response message.
    type Response: ros2_client::Message;
    /// The ROS package, `cstep_msgs`.
    const PACKAGE: &'static str;
    /// The service's name in its package, e.g. `Evaluate`.
    const NAME: &'static str;

    /// The type name ros2-client creates servers and clients with.
    fn type_name() -> ServiceTypeName {
        ServiceTypeName::new(Self::PACKAGE, Self::NAME)
    }

    /// The type as ROS tools print it (`cstep_msgs/srv/Evaluate`), for messages to the user.
    fn ros_type() -> String {
        format!("{}/srv/{}", Self::PACKAGE, Self::NAME)
    }

    /// The DDS type of the service's replies (`cstep_msgs::srv::dds_::Evaluate_Response_`), as
    /// discovery reports its servers' reply writers (the rmw naming, which ros2-client follows).
    fn dds_response_type() -> String {
        format!("{}::srv::dds_::{}_Response_", Self::PACKAGE, Self::NAME)
    }
}

/// The ROS name of a DDS type name (`pkg::msg::dds_::Name_` → `pkg/msg/Name`), if it is one.
pub fn ros_type_of_dds(dds: &str) -> Option<String> {
    match dds.split("::").collect::<Vec<_>>()[..] {
        [package, prefix, "dds_", kind] => {
            Some(format!("{package}/{prefix}/{}", kind.strip_suffix('_')?))
        }
        _ => None,
    }
}

/// `cstep_msgs/srv/Evaluate`: one state scored ([`EvaluateRequest`] → [`EvaluateResponse`]).
#[derive(Debug, Clone, Copy)]
pub enum Evaluate {}

/// `cstep_msgs/srv/EvaluateBatch`: K states scored in one call ([`EvaluateBatchRequest`] →
/// [`EvaluateBatchResponse`]).
#[derive(Debug, Clone, Copy)]
pub enum EvaluateBatch {}

/// Every topic type here travels over DDS with ros2-client, under the ROS type name given.
macro_rules! ros_messages {
    ($($t:ty => $package:literal / $name:literal),* $(,)?) => { $(
        impl ros2_client::Message for $t {}
        impl RosMessage for $t {
            const PACKAGE: &'static str = $package;
            const NAME: &'static str = $name;
        }
    )* };
}
ros_messages!(
    Clock => "rosgraph_msgs" / "Clock",
    Odometry => "nav_msgs" / "Odometry",
    LaserScan => "sensor_msgs" / "LaserScan",
    PointCloud2 => "sensor_msgs" / "PointCloud2",
    PoseStamped => "geometry_msgs" / "PoseStamped",
    Empowerment => "cstep_msgs" / "Empowerment",
    EmpoweredReward => "cstep_msgs" / "EmpoweredReward",
    DiagnosticArray => "diagnostic_msgs" / "DiagnosticArray",
    MarkerArray => "visualization_msgs" / "MarkerArray",
    SpeedLimit => "nav2_msgs" / "SpeedLimit",
);

/// Every service here, with its request and response (which travel over DDS too).
macro_rules! ros_services {
    ($($s:ty => $package:literal / $name:literal: $request:ty, $response:ty);* $(;)?) => { $(
        impl ros2_client::Message for $request {}
        impl ros2_client::Message for $response {}
        impl RosService for $s {
            type Request = $request;
            type Response = $response;
            const PACKAGE: &'static str = $package;
            const NAME: &'static str = $name;
        }
    )* };
}
ros_services!(
    Evaluate => "cstep_msgs" / "Evaluate": EvaluateRequest, EvaluateResponse;
    EvaluateBatch => "cstep_msgs" / "EvaluateBatch": EvaluateBatchRequest, EvaluateBatchResponse;
);

/// Scalar `float32` fields that refuse, in JSON, a number no `float32` holds: a finite number
/// beyond ±`f32::MAX` or a non-zero one that rounds to zero ([`json`] names the field);
/// binary formats (CDR) carry a `float32` already and pass through.
mod float32 {
    use serde::de::{Deserializer, Error};
    use serde::Deserialize;

    /// The `f32` the JSON number is, or why it is none.
    pub fn narrow<'de, D: Deserializer<'de>>(deserializer: D) -> Result<f32, D::Error> {
        if !deserializer.is_human_readable() {
            return f32::deserialize(deserializer);
        }
        let wide = f64::deserialize(deserializer)?;
        let narrow = wide as f32;
        if narrow.is_infinite() && wide.is_finite() || narrow == 0.0 && wide != 0.0 {
            return Err(D::Error::custom(format_args!(
                "{wide:?} does not fit the message's float32 (magnitudes {:e} to {:e})",
                f32::from_bits(1),
                f32::MAX
            )));
        }
        Ok(narrow)
    }
}

/// Float arrays that read JSON's stand-ins for non-finite numbers and pass binary formats
/// through untouched. `cdr-encoding` (the DDS wire format) reports `is_human_readable() ==
/// false`, so CDR sees a plain `sequence<float32>`, NaN bits and all (`tests/cdr_roundtrip.rs`).
/// Writing needs nothing special: serde_json already writes non-finite floats as `null`.
mod lenient_floats {
    use serde::de::{self, Deserializer, Visitor};
    use serde::Deserialize;

    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Vec<f32>, D::Error> {
        if deserializer.is_human_readable() {
            let values = Vec::<Lenient>::deserialize(deserializer)?;
            Ok(values.into_iter().map(|v| v.0).collect())
        } else {
            Vec::<f32>::deserialize(deserializer)
        }
    }

    struct Lenient(f32);

    impl<'de> Deserialize<'de> for Lenient {
        fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
            deserializer.deserialize_any(LenientVisitor)
        }
    }

    struct LenientVisitor;

    impl Visitor<'_> for LenientVisitor {
        type Value = Lenient;

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number, null, or one of \"inf\", \"-inf\", \"nan\"")
        }

        fn visit_f64<E: de::Error>(self, v: f64) -> Result<Lenient, E> {
            Ok(Lenient(v as f32))
        }

        fn visit_i64<E: de::Error>(self, v: i64) -> Result<Lenient, E> {
            Ok(Lenient(v as f32))
        }

        fn visit_u64<E: de::Error>(self, v: u64) -> Result<Lenient, E> {
            Ok(Lenient(v as f32))
        }

        fn visit_unit<E: de::Error>(self) -> Result<Lenient, E> {
            Ok(Lenient(f32::INFINITY))
        }

        fn visit_none<E: de::Error>(self) -> Result<Lenient, E> {
            Ok(Lenient(f32::INFINITY))
        }

        fn visit_str<E: de::Error>(self, v: &str) -> Result<Lenient, E> {
            match v.to_ascii_lowercase().as_str() {
                "inf" | "+inf" | "infinity" | "+infinity" => Ok(Lenient(f32::INFINITY)),
                "-inf" | "-infinity" => Ok(Lenient(f32::NEG_INFINITY)),
                "nan" => Ok(Lenient(f32::NAN)),
                _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
            }
        }
    }
}
