//! Every parameter cstep reads, defined once: name, type and accepted values, default, unit,
//! description, and whether it may change while the node runs.
//!
//! [`PARAMETERS`] drives the validation of parameter files and `-p` overrides
//! ([`super::config`]), the node's parameter declarations and their ROS 2 descriptors
//! (`cstep::ros::rcl::parameters`), and the table of `docs/parameters.md` and
//! `config/cstep.yaml`, which `tests/parameter_docs.rs` writes from it (`CSTEP_WRITE_DOCS=1`)
//! and otherwise checks, so none of them can drift from the table.

use serde_norway::Value as Yaml;

use super::robot::BUILTIN_URDF_PATH;
use crate::excerpt::excerpt;

/// A parameter value, typed as ROS 2 types parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A ROS `bool`.
    Bool(bool),
    /// A ROS `integer` (64-bit).
    Integer(i64),
    /// A ROS `double`.
    Double(f64),
    /// A ROS `string`.
    Text(String),
}

/// The ROS 2 parameter type a parameter has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `bool`.
    Bool,
    /// `integer`.
    Integer,
    /// `double`.
    Double,
    /// `string`.
    String,
}

impl Kind {
    /// The type's name as `ros2 param describe` prints it.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Bool => "bool",
            Kind::Integer => "integer",
            Kind::Double => "double",
            Kind::String => "string",
        }
    }
}

/// The values a parameter accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rule {
    /// `true` or `false`.
    Bool,
    /// A whole number in `min..=max`.
    Integer {
        /// The smallest accepted value.
        min: i64,
        /// The largest accepted value.
        max: i64,
    },
    /// A finite number greater than 0; with `optional`, `.nan` (or null) leaves it unset.
    Positive {
        /// Whether `.nan` means "not set" (the ROS idiom for an optional double).
        optional: bool,
    },
    /// Any finite number, or `.nan` (or null): unset.
    OptionalFinite,
    /// A finite number in `min..=max`; an infinite bound leaves that side open.
    Between {
        /// The smallest accepted value.
        min: f64,
        /// The largest accepted value.
        max: f64,
    },
    /// One of these words.
    Choice(&'static [&'static str]),
    /// A ROS topic or service name: not empty, no spaces.
    RosName,
    /// A file path, relative to the parameters file that sets it, or a `builtin:` name.
    Path,
}

impl Rule {
    /// The ROS 2 type of the values this rule accepts.
    pub fn kind(self) -> Kind {
        match self {
            Rule::Bool => Kind::Bool,
            Rule::Integer { .. } => Kind::Integer,
            Rule::Positive { .. } | Rule::OptionalFinite | Rule::Between { .. } => Kind::Double,
            Rule::Choice(_) | Rule::RosName | Rule::Path => Kind::String,
        }
    }

    /// The accepted values in words (`> 0`, `1 to 100000`, `quadrotor | point_mass`).
    pub fn constraint(self) -> String {
        match self {
            Rule::Bool => "true | false".into(),
            Rule::Integer { min, max } if max - min == 1 => format!("{min} | {max}"),
            Rule::Integer { min, max } => format!("{min} to {max}"),
            Rule::Positive { optional: false } => "> 0".into(),
            Rule::Positive { optional: true } => "> 0, or .nan: unset".into(),
            Rule::OptionalFinite => "finite, or .nan: unset".into(),
            Rule::Between { min, max } => match (min.is_finite(), max.is_finite()) {
                (true, true) => format!("{min:?} to {max:?}"),
                (true, false) => format!(">= {min:?}"),
                (false, true) => format!("<= {max:?}"),
                (false, false) => "finite".into(),
            },
            Rule::Choice(words) => words.join(" | "),
            Rule::RosName => "a ROS name, no spaces".into(),
            Rule::Path => {
                "a file path (relative to the parameters file), builtin:NAME, or URDF text".into()
            }
        }
    }
}

/// Whether a parameter may change while the node runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Change {
    /// Settable through the parameter services; takes effect at the next scan.
    Live,
    /// Fixed for the node's life: set it in a parameters file or with `-p` at start.
    ReadOnly,
}

/// One parameter's definition.
#[derive(Debug, Clone, Copy)]
pub struct Parameter {
    /// The name in parameter files, `-p` overrides and the parameter services.
    pub name: &'static str,
    /// The values it accepts (and so its ROS type).
    pub rule: Rule,
    /// The default, as it reads in a parameters file (`1.0`, `.nan`, `quadrotor`).
    pub default: &'static str,
    /// The unit of a number (`s`, `m`, `m/s²`), if it has one.
    pub unit: Option<&'static str>,
    /// What it means, for people: `docs/parameters.md`, `config/cstep.yaml`,
    /// `ros2 param describe`.
    pub description: &'static str,
    /// Whether it may change while the node runs.
    pub change: Change,
}

/// Largest accepted trajectory count: beyond it an evaluation takes seconds.
const MAX_TRAJECTORIES: i64 = 100_000;
/// Largest accepted step count: beyond it an evaluation takes seconds.
const MAX_STEPS: i64 = 10_000;

/// Every parameter, in the order `docs/parameters.md` and `config/cstep.yaml` list them: the
/// evaluation's first, then the node's ROS interface. The names are a contract with users' parameter files.
pub const PARAMETERS: &[Parameter] = &[
    Parameter {
        name: "robot_description",
        rule: Rule::Path,
        default: BUILTIN_URDF_PATH,
        unit: None,
        description: "The robot: a URDF as a file path or as the URDF text itself (as launch \
            files pass robot_description to robot_state_publisher). The quadrotor and the point \
            mass read a multirotor URDF with a <properties> element (arm, kf, km, \
            thrust2weight, ...); diff_drive reads a wheeled robot's URDF as its maker ships it. \
            builtin:cf2x.urdf is the compiled-in Crazyflie 2.x (urdf/cf2x.urdf), \
            builtin:husky.urdf the compiled-in Clearpath Husky (urdf/husky.urdf).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "model",
        rule: Rule::Choice(&["quadrotor", "point_mass", "diff_drive"]),
        default: "quadrotor",
        unit: None,
        description: "Dynamics: quadrotor (6-DoF rigid body, motors, attitude controller), \
            point_mass (the paper prototype's double integrator) or diff_drive (a differential \
            drive or skid steer on the ground, wheels, mass and footprint from the URDF; \
            volume_dims 2).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "horizon",
        rule: Rule::Positive { optional: false },
        default: "1.0",
        unit: Some("s"),
        description: "Horizon T. The paper's heuristic: the worst-case stopping time from \
            maximum speed.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "trajectories",
        rule: Rule::Integer {
            min: 1,
            max: MAX_TRAJECTORIES,
        },
        default: "150",
        unit: None,
        description: "Sampled control trajectories N (the paper: 150).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "steps",
        rule: Rule::Integer {
            min: 1,
            max: MAX_STEPS,
        },
        default: "100",
        unit: None,
        description: "RK4 steps per trajectory (the paper: 100 points). With trajectories, the \
            control sample (trajectories × steps × volume_dims floats of 4 bytes) must fit the \
            256 MiB an evaluation may allocate, e.g. 100000 × 335 in 2D; beyond it cstep eval, \
            bench and node refuse to start, naming the values and the budget.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "sampler",
        rule: Rule::Choice(&["bang_bang", "fourier", "chebyshev"]),
        default: "bang_bang",
        unit: None,
        description: "Control sampler: bang_bang (covers the admissible set), fourier (the \
            paper's prototype) or chebyshev.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "seed",
        rule: Rule::Integer {
            min: 0,
            max: i64::MAX,
        },
        default: "0",
        unit: None,
        description: "Seed of the control sample. The same sample is reused for every \
            evaluation (common random numbers), so consecutive scores differ only because the \
            robot and its surroundings did.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "safety_coefficient",
        rule: Rule::Positive { optional: false },
        default: "1.0",
        unit: None,
        description: "Safety coefficient c of the reward r = r_d · log(c · free_volume): \
            smaller is more cautious.",
        change: Change::Live,
    },
    Parameter {
        name: "volume_dims",
        rule: Rule::Integer { min: 2, max: 3 },
        default: "2",
        unit: None,
        description: "Volumes in 2 dimensions (areas at a held altitude, as in the paper's \
            drone experiment) or 3.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "estimator",
        rule: Rule::Choice(&["free_fraction", "hull", "efron"]),
        default: "free_fraction",
        unit: None,
        description: "Free-volume estimator: free_fraction (de-biased hull of all endpoints \
            times the share of it nearest to free endpoints; right also when terminal endpoints \
            surround the free ones, as they do whenever the robot can reach past what its scan \
            shows), hull (the paper: hull of all endpoints minus the union of hulls of clustered \
            terminal endpoints; collapses to zero in that case) or efron (hull, de-biased).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "robot_radius",
        rule: Rule::Positive { optional: true },
        default: ".nan",
        unit: Some("m"),
        description: "Robot disk radius for collision checks; .nan: from the URDF's collision \
            geometry (0.06 m for the Crazyflie; for diff_drive, the radius of each disk of the \
            row that covers the chassis and wheels, 0.425 m for the Husky).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "max_acceleration",
        rule: Rule::Positive { optional: true },
        default: "5.0",
        unit: Some("m/s²"),
        description: "Bound on the commanded acceleration per axis; it sets how far the \
            horizon reaches (A·T²/2 each way). 5.0 reaches ±2.5 m in 1 s, matching the paper's \
            3 m LiDAR: at the Crazyflie's full authority (17.3 m/s², ±8 m) nearly every \
            trajectory leaves the sensed space and the score stops telling states apart. .nan: \
            the model's own bound (quadrotor: full authority from the URDF; point mass: the \
            prototype's 10.41 = 9.81 + 0.6). diff_drive reads wheel_max_acceleration instead.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "wheel_max_speed",
        rule: Rule::Positive { optional: false },
        default: "1.0",
        unit: Some("m/s"),
        description: "diff_drive: each wheel rim's top speed, so the top speed driving \
            straight, where the wheel joints' <limit velocity> (rad/s, times the wheel radius) \
            does not give it. 1.0: the Clearpath Husky's published maximum speed (Husky \
            datasheet, clearpathrobotics.com).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "wheel_max_acceleration",
        rule: Rule::Positive { optional: false },
        default: "3.0",
        unit: Some("m/s²"),
        description: "diff_drive: the bound on each wheel rim's acceleration where the wheel \
            joints' <limit effort> (N·m, against the mass and yaw inertia) does not give it. \
            3.0: the linear acceleration limit Clearpath ships for the Husky's drive \
            controller (husky_control/config/control.yaml, linear.x.max_acceleration).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "wheel_separation_multiplier",
        rule: Rule::Positive { optional: true },
        default: ".nan",
        unit: None,
        description: "diff_drive: the track the drive turns on, as a multiple of the wheels' \
            geometric one (ros2_control's diff_drive_controller parameter of the same name): a \
            skid steer's wheels scrub sideways in a turn, so it turns slower than its rims \
            would without slip. .nan: 1.0 for one wheel a side; 1.875 for a skid steer (more \
            than one wheel a side), the figure Clearpath calibrated for the Husky \
            (husky_control/config/control.yaml). Set your robot's own calibration.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "unknown_space",
        rule: Rule::Choice(&["occupied", "free"]),
        default: "occupied",
        unit: None,
        description: "Space the scan says nothing about (beyond range, unseen bearings, \
            invalid beams): occupied (conservative) or free.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "floor_height",
        rule: Rule::OptionalFinite,
        default: ".nan",
        unit: Some("m"),
        description: "Floor height (odometry frame) for 3D checks; .nan: none.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "ceiling_height",
        rule: Rule::OptionalFinite,
        default: ".nan",
        unit: Some("m"),
        description: "Ceiling height (odometry frame) for 3D checks; .nan: none.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "odom_topic",
        rule: Rule::RosName,
        default: "odom",
        unit: None,
        description: "nav_msgs/Odometry input. Names without a leading / are relative to the \
            node's namespace; every topic and service name can also be remapped with -r.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "scan_topic",
        rule: Rule::RosName,
        default: "scan",
        unit: None,
        description: "sensor_msgs/LaserScan input (sensor-data QoS); one evaluation per scan.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "use_point_cloud",
        rule: Rule::Bool,
        default: "false",
        unit: None,
        description: "Score sensor_msgs/PointCloud2 from cloud_topic (a 3-D LiDAR, a depth \
            camera) instead of scans from scan_topic. The points between cloud_min_height and \
            cloud_max_height above the robot's origin (world-aligned, after the odometry's \
            attitude), at horizontal ranges from cloud_range_min to cloud_range_max, become a \
            720-bearing scan keeping each bearing's nearest point, as pointcloud_to_laserscan \
            does; bearings within cloud_field_of_view without a point are free to \
            cloud_range_max, the others unknown (unknown_space). The cloud is read in the \
            body frame with the sensor at its origin, as scans are (no TF).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "cloud_topic",
        rule: Rule::RosName,
        default: "cloud",
        unit: None,
        description: "sensor_msgs/PointCloud2 input (with use_point_cloud; sensor-data QoS); \
            one evaluation per cloud.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "cloud_min_height",
        rule: Rule::Between {
            min: f64::NEG_INFINITY,
            max: f64::INFINITY,
        },
        default: "-0.2",
        unit: Some("m"),
        description: "Lowest point of a cloud that counts, above the robot's origin \
            (world-aligned): set it above the ground a ground robot's sensor sees.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "cloud_max_height",
        rule: Rule::Between {
            min: f64::NEG_INFINITY,
            max: f64::INFINITY,
        },
        default: "0.2",
        unit: Some("m"),
        description: "Highest point of a cloud that counts, above the robot's origin \
            (world-aligned); above cloud_min_height.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "cloud_range_min",
        rule: Rule::Between {
            min: 0.0,
            max: f64::INFINITY,
        },
        default: "0.1",
        unit: Some("m"),
        description: "Points of a cloud nearer than this horizontally are dropped (the robot's \
            own body).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "cloud_range_max",
        rule: Rule::Positive { optional: false },
        default: "10.0",
        unit: Some("m"),
        description: "Points of a cloud farther than this horizontally are dropped; a bearing \
            without a point is free up to it. Above cloud_range_min.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "cloud_field_of_view",
        rule: Rule::Positive { optional: false },
        default: "6.283185307179586",
        unit: Some("rad"),
        description: "The sensor's horizontal field of view, centred on the body's x axis: 2π \
            (or more) for a spinning LiDAR, less for a camera.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "cloud_max_points",
        rule: Rule::Integer {
            min: 1,
            max: 16_777_216,
        },
        default: "300000",
        unit: None,
        description: "The most points read of one cloud; a larger cloud is read every k-th \
            point for the smallest k within it, which bounds the work a cloud costs (a \
            128-ring LiDAR sends ~262 000).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "goal_topic",
        rule: Rule::RosName,
        default: "goal_pose",
        unit: None,
        description: "Optional geometry_msgs/PoseStamped goal for the task reward.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "empowerment_topic",
        rule: Rule::RosName,
        default: "cstep/empowerment",
        unit: None,
        description: "cstep_msgs/Empowerment output.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "reward_topic",
        rule: Rule::RosName,
        default: "cstep/reward",
        unit: None,
        description: "cstep_msgs/EmpoweredReward output.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "markers_topic",
        rule: Rule::RosName,
        default: "cstep/markers",
        unit: None,
        description: "visualization_msgs/MarkerArray of the sampled endpoints and their hull, \
            in the odometry frame; built and published only while someone subscribes.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "publish_speed_limit",
        rule: Rule::Bool,
        default: "false",
        unit: None,
        description: "Publish a nav2_msgs/SpeedLimit on speed_limit_topic from each score \
            (Nav2's controller server hands it to every controller plugin): 100 % at and above \
            speed_limit_full_speed_at, speed_limit_floor at and below speed_limit_full_speed_at \
            - speed_limit_span, linear between. At most speed_limit_rate per second, stamped \
            with the scan's stamp; released (speed_limit 0.0, Nav2's \"no limit\") when no \
            score came for input_timeout and when the node stops cleanly. While on, a subscriber \
            of speed_limit_topic has scans scored like one of the scores.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "speed_limit_topic",
        rule: Rule::RosName,
        default: "speed_limit",
        unit: None,
        description: "nav2_msgs/SpeedLimit output (with publish_speed_limit); speed_limit is the \
            topic Nav2's controller server reads (its speed_limit_topic parameter).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "speed_limit_full_speed_at",
        rule: Rule::OptionalFinite,
        default: ".nan",
        unit: Some("nats"),
        description: "Empowerment at and above which the speed limit is 100 %. .nan: the \
            model's own. quadrotor and point_mass: 1.5, a free reachable area of e^1.5 = \
            4.5 m² within the horizon (the Crazyflie in the paper's arena scores 1.38 at \
            0.35 m from a wall and 1.86 in the open). diff_drive: -1.05, where 95 % of the \
            Husky's states at its top speed in the open score (experiments/husky/\
            speed_limit_scores.md: -1.04).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "speed_limit_span",
        rule: Rule::Positive { optional: true },
        default: ".nan",
        unit: Some("nats"),
        description: "Empowerment below speed_limit_full_speed_at over which the limit falls \
            linearly to speed_limit_floor. .nan: the model's own. quadrotor and point_mass: \
            1.5, the floor at 0 nats, a free reachable area of 1 m². diff_drive: 0.7, the \
            floor at -1.75, where the Husky scores at top speed within 0.6 m of an obstacle \
            (median -1.72).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "speed_limit_floor",
        rule: Rule::Between {
            min: 1.0,
            max: 100.0,
        },
        default: "20.0",
        unit: Some("%"),
        description: "The lowest speed limit, percent of full speed, however low the score \
            (invalid scores and scores of a robot in collision included). Not below 1: Nav2 \
            reads 0 as no limit at all.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "speed_limit_max_speed",
        rule: Rule::Positive { optional: true },
        default: ".nan",
        unit: Some("m/s"),
        description: ".nan: limits are percentages of each Nav2 controller's own maximum speed \
            (percentage true). Set: absolute limits in m/s, the mapping's percentage of this \
            speed (percentage false).",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "speed_limit_rate",
        rule: Rule::Positive { optional: false },
        default: "10.0",
        unit: Some("Hz"),
        description: "At most this many speed limits per second of scan time (the scans' \
            stamps): a score within 1/rate of the last limit published changes nothing, so a \
            40 Hz LiDAR does not reconfigure Nav2's controllers 40 times a second. Releases are \
            not held back.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "evaluate_service",
        rule: Rule::RosName,
        default: "cstep/evaluate",
        unit: None,
        description: "cstep_msgs/srv/Evaluate: one state in, its score out, synchronously.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "evaluate_batch_service",
        rule: Rule::RosName,
        default: "cstep/evaluate_batch",
        unit: None,
        description: "cstep_msgs/srv/EvaluateBatch: K states per call, scored in parallel; one \
            round trip per vector step for RL loops with several simulations.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "service_queue_per_client",
        rule: Rule::Integer { min: 1, max: 4096 },
        default: "16",
        unit: Some("requests"),
        description: "Requests of one client that the services hold waiting at once; they are \
            served round-robin across clients. A request past this (or service_queue_total) is \
            answered at once with valid false and the reason, never dropped.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "service_queue_total",
        rule: Rule::Integer { min: 1, max: 65536 },
        default: "128",
        unit: Some("requests"),
        description: "Requests the services hold waiting at once, all clients together: bounds \
            the node's memory under any number of clients.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "input_timeout",
        rule: Rule::Positive { optional: false },
        default: "0.5",
        unit: Some("s"),
        description: "Odometry older than this when a scan arrives is stale: no score, \
            diagnostics STALE.",
        change: Change::Live,
    },
    Parameter {
        name: "time_jump_tolerance",
        rule: Rule::Positive { optional: false },
        default: "1.0",
        unit: Some("s"),
        description: "A scan stamped more than this before the newest one scored means time \
            jumped back (a simulation reset, a bag replayed): the stamp ordering is reset and \
            scoring goes on. Up to it, an older scan is a late delivery and skipped.",
        change: Change::ReadOnly,
    },
    Parameter {
        name: "use_sim_time",
        rule: Rule::Bool,
        default: "false",
        unit: None,
        description: "Use the /clock topic's time for the node's clock (simulation), which \
            stamps the diagnostics. Scores carry their scan's stamp either way.",
        change: Change::Live,
    },
];

/// The definition of parameter `name`, if there is one.
pub fn find(name: &str) -> Option<&'static Parameter> {
    PARAMETERS.iter().find(|p| p.name == name)
}

impl Parameter {
    /// Checks a value read from a parameters file or `-p` against this parameter's rule:
    /// the typed value, `None` when an optional one is unset (null or `.nan`), or what is wrong
    /// in one line naming the parameter and the value.
    pub fn check(&self, value: &Yaml) -> Result<Option<Value>, String> {
        let name = self.name;
        let nan = matches!(value, Yaml::Number(n) if n.as_f64().is_some_and(f64::is_nan));
        if matches!(value, Yaml::Null) || nan {
            return match self.rule {
                Rule::Positive { optional: true } | Rule::OptionalFinite => Ok(None),
                Rule::Positive { optional: false } if nan => Err(format!(
                    "'{name}' must be a positive number, got NaN (not finite)"
                )),
                Rule::Between { .. } if nan => {
                    Err(format!("'{name}' must be a finite number, got NaN"))
                }
                _ => Err(format!(
                    "'{name}' must be set (the built-in default sets it; a file or -p cleared it)"
                )),
            };
        }
        match self.rule {
            Rule::Bool => match value {
                Yaml::Bool(b) => Ok(Some(Value::Bool(*b))),
                other => Err(format!(
                    "'{name}' must be true or false, got {}",
                    show(other)
                )),
            },
            Rule::Integer { min, max } => match value {
                Yaml::Number(n) if n.is_i64() || n.is_u64() => match n.as_i64() {
                    Some(v) if (min..=max).contains(&v) => Ok(Some(Value::Integer(v))),
                    _ if max - min == 1 => Err(format!(
                        "'{name}' must be one of {min} | {max}, got {}",
                        show(value)
                    )),
                    _ => Err(format!(
                        "'{name}' must be between {min} and {max}, got {}",
                        show(value)
                    )),
                },
                other => Err(format!(
                    "'{name}' must be a whole number ({}), got {}",
                    self.rule.constraint(),
                    show(other)
                )),
            },
            Rule::Positive { .. } | Rule::OptionalFinite | Rule::Between { .. } => {
                let Yaml::Number(n) = value else {
                    return Err(format!("'{name}' must be a number, got {}", show(value)));
                };
                let v = n.as_f64().unwrap_or(f64::NAN);
                match self.rule {
                    Rule::Positive { .. } if !(v.is_finite() && v > 0.0) => {
                        Err(format!("'{name}' must be a positive number, got {v}"))
                    }
                    Rule::OptionalFinite | Rule::Between { .. } if !v.is_finite() => {
                        Err(format!("'{name}' must be a finite number, got {v}"))
                    }
                    Rule::Between { min, max } if !(min..=max).contains(&v) => Err(format!(
                        "'{name}' must be a number in {}, got {v}",
                        self.rule.constraint()
                    )),
                    _ => Ok(Some(Value::Double(v))),
                }
            }
            Rule::Choice(words) => {
                let text = text(value)
                    .ok_or_else(|| format!("'{name}' must be a string, got {}", show(value)))?;
                if words.contains(&text.as_str()) {
                    Ok(Some(Value::Text(text)))
                } else {
                    Err(format!(
                        "'{name}' must be one of {}, got \"{}\"",
                        words.join(" | "),
                        excerpt(&text)
                    ))
                }
            }
            Rule::RosName => {
                let text = text(value)
                    .ok_or_else(|| format!("'{name}' must be a string, got {}", show(value)))?;
                if text.is_empty() || text.contains(char::is_whitespace) {
                    return Err(format!(
                        "'{name}' must be a ROS name without spaces, got \"{}\"",
                        excerpt(&text)
                    ));
                }
                Ok(Some(Value::Text(text)))
            }
            Rule::Path => text(value)
                .map(|t| Some(Value::Text(t)))
                .ok_or_else(|| format!("'{name}' must be a string, got {}", show(value))),
        }
    }

    /// The default, checked like any other value (the table's tests prove each passes).
    pub fn default_value(&self) -> Result<Option<Value>, String> {
        let yaml: Yaml = serde_norway::from_str(self.default)
            .map_err(|e| format!("'{}': default {}: {e}", self.name, self.default))?;
        self.check(&yaml)
    }
}

/// A string value; numbers are read as text too (`sampler: 2` reads "2").
fn text(value: &Yaml) -> Option<String> {
    match value {
        Yaml::String(s) => Some(s.clone()),
        Yaml::Number(n) => Some(n.to_string()),
        _ => None,
    }
}

/// A value as it reads in a one-line error: scalars as YAML (`soon`, `true`), lists and maps in
/// flow style (`[1,2]`), never the block YAML that would span lines; of a long value, its start
/// and length ([`excerpt`]).
pub fn show(value: &Yaml) -> String {
    let text = match value {
        Yaml::Sequence(_) | Yaml::Mapping(_) | Yaml::Tagged(_) => serde_json::to_string(value).ok(),
        _ => serde_norway::to_string(value).ok(),
    };
    let line = text
        .map(|s| s.trim().to_owned())
        .filter(|s| !s.contains('\n'))
        .unwrap_or_else(|| format!("{value:?}"));
    excerpt(&line).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_default_passes_its_own_rule_and_has_its_type() {
        for p in PARAMETERS {
            let value = p.default_value().unwrap_or_else(|e| panic!("{e}"));
            let kind = value.as_ref().map(|v| match v {
                Value::Bool(_) => Kind::Bool,
                Value::Integer(_) => Kind::Integer,
                Value::Double(_) => Kind::Double,
                Value::Text(_) => Kind::String,
            });
            assert!(kind.is_none_or(|k| k == p.rule.kind()), "{}", p.name);
        }
    }

    #[test]
    fn names_are_unique_and_every_parameter_is_described() {
        let mut names: Vec<_> = PARAMETERS.iter().map(|p| p.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), PARAMETERS.len());
        for p in PARAMETERS {
            assert!(p.description.ends_with('.'), "{}", p.name);
            assert!(!p.description.contains("  "), "{}", p.name);
            assert_eq!(find(p.name).map(|f| f.name), Some(p.name));
        }
        assert!(find("horizn").is_none());
    }

    #[test]
    fn each_rule_accepts_its_values_and_refuses_others_naming_both() {
        let yaml = |s: &str| -> Yaml { serde_norway::from_str(s).unwrap() };
        let check = |name: &str, value: &str| find(name).unwrap().check(&yaml(value));
        assert_eq!(check("horizon", "0.5"), Ok(Some(Value::Double(0.5))));
        assert_eq!(check("trajectories", "7"), Ok(Some(Value::Integer(7))));
        assert_eq!(check("volume_dims", "3"), Ok(Some(Value::Integer(3))));
        assert_eq!(check("robot_radius", ".nan"), Ok(None));
        assert_eq!(check("floor_height", "-1.5"), Ok(Some(Value::Double(-1.5))));
        assert_eq!(check("use_sim_time", "true"), Ok(Some(Value::Bool(true))));
        assert_eq!(
            check("speed_limit_full_speed_at", "-2"),
            Ok(Some(Value::Double(-2.0)))
        );
        assert_eq!(
            check("model", "point_mass"),
            Ok(Some(Value::Text("point_mass".into())))
        );
        let refusals = [
            (
                "horizon",
                "-1",
                "'horizon' must be a positive number, got -1",
            ),
            ("horizon", "soon", "'horizon' must be a number, got soon"),
            (
                "horizon",
                ".nan",
                "'horizon' must be a positive number, got NaN (not finite)",
            ),
            ("horizon", "[1, 2]", "'horizon' must be a number, got [1,2]"),
            (
                "horizon",
                "~",
                "'horizon' must be set (the built-in default sets it; a file or -p cleared it)",
            ),
            (
                "trajectories",
                "0",
                "'trajectories' must be between 1 and 100000, got 0",
            ),
            (
                "trajectories",
                "1.5",
                "'trajectories' must be a whole number (1 to 100000), got 1.5",
            ),
            (
                "seed",
                "-1",
                "'seed' must be between 0 and 9223372036854775807, got -1",
            ),
            (
                "seed",
                "18446744073709551615",
                "'seed' must be between 0 and 9223372036854775807, got 18446744073709551615",
            ),
            (
                "volume_dims",
                "4",
                "'volume_dims' must be one of 2 | 3, got 4",
            ),
            (
                "sampler",
                "uniform",
                "'sampler' must be one of bang_bang | fourier | chebyshev, got \"uniform\"",
            ),
            (
                "floor_height",
                ".inf",
                "'floor_height' must be a finite number, got inf",
            ),
            (
                "use_sim_time",
                "yes please",
                "'use_sim_time' must be true or false, got yes please",
            ),
            (
                "scan_topic",
                "'my scan'",
                "'scan_topic' must be a ROS name without spaces, got \"my scan\"",
            ),
            (
                "speed_limit_floor",
                "100.5",
                "'speed_limit_floor' must be a number in 1.0 to 100.0, got 100.5",
            ),
            (
                "cloud_min_height",
                ".nan",
                "'cloud_min_height' must be a finite number, got NaN",
            ),
            (
                "cloud_min_height",
                "-.inf",
                "'cloud_min_height' must be a finite number, got -inf",
            ),
            (
                "speed_limit_full_speed_at",
                "-.inf",
                "'speed_limit_full_speed_at' must be a finite number, got -inf",
            ),
            // A line break is escaped: an error stays one line (found by tests/yaml_fuzz.rs).
            (
                "sampler",
                "|\n  x\n  y\n",
                "'sampler' must be one of bang_bang | fourier | chebyshev, got \"x\\ny\\n\"",
            ),
        ];
        for (name, value, expected) in refusals {
            assert_eq!(
                check(name, value),
                Err(expected.to_owned()),
                "{name}: {value}"
            );
        }
    }
}
