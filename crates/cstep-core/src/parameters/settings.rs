//! What an evaluation and the node run with, read from the checked [`Parameters`]:
//! [`Settings`] for an evaluation, [`NodeSettings`] for the node's ROS interface. Only the
//! limits that span parameters are checked here (the control sample's memory, the ceiling above
//! the floor); each value on its own was checked against the table.

use std::path::{Path, PathBuf};

use super::config::{ConfigError, ParameterSet, Parameters, DEFAULT_NODE_NAME};
use super::robot::{is_urdf_text, RobotSource, BUILTIN_ROBOTS};
use crate::cloud::{CloudInput, CloudOptions};
use crate::model::CommandAxes;
use crate::occupancy::UnknownSpace;
use crate::sampling::{Controls, SamplerKind, CONTROL_SAMPLE_BUDGET_BYTES};
use crate::speed_limit::{SpeedLimitMapping, SpeedLimitOutput};
use crate::volume::{EstimatorKind, VolumeDims};

/// Which dynamics model rolls out the trajectories.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// The URDF-derived 6-DoF quadrotor with motors and an attitude controller.
    Quadrotor,
    /// The paper prototype's double integrator.
    PointMass,
    /// The URDF-derived differential drive (or skid steer) on the ground.
    DiffDrive,
}

impl ModelKind {
    /// The name used in configuration files.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Quadrotor => "quadrotor",
            ModelKind::PointMass => "point_mass",
            ModelKind::DiffDrive => "diff_drive",
        }
    }

    /// Parses a configuration name.
    pub fn from_name(name: &str) -> Option<Self> {
        [
            ModelKind::Quadrotor,
            ModelKind::PointMass,
            ModelKind::DiffDrive,
        ]
        .into_iter()
        .find(|m| m.name() == name)
    }
}

/// Everything an evaluation needs, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// The robot's URDF.
    pub robot_description: RobotSource,
    /// The dynamics model.
    pub model: ModelKind,
    /// Horizon `T`, seconds.
    pub horizon: f64,
    /// Number of sampled control trajectories `N`.
    pub trajectories: usize,
    /// RK4 steps per trajectory (points per trajectory).
    pub steps: usize,
    /// The control sampler.
    pub sampler: SamplerKind,
    /// Seed of the control sample.
    pub seed: u64,
    /// Safety coefficient `c > 0`.
    pub safety_coefficient: f64,
    /// Dimension of the volumes (and of the commands: 2 = at held altitude).
    pub volume_dims: VolumeDims,
    /// The free-volume estimator.
    pub estimator: EstimatorKind,
    /// Robot disk radius override, metres.
    pub robot_radius: Option<f64>,
    /// Commanded acceleration bound override, m/s².
    pub max_acceleration: Option<f64>,
    /// Each wheel rim's top speed where the wheel joints give no `<limit velocity>`, m/s.
    pub wheel_max_speed: f64,
    /// Each wheel rim's acceleration bound where the wheel joints give no `<limit effort>`, m/s².
    pub wheel_max_acceleration: f64,
    /// The drive's effective track over its geometric one; `None`: the drive's own default.
    pub wheel_separation_multiplier: Option<f64>,
    /// Treatment of space the scan does not describe.
    pub unknown_space: UnknownSpace,
    /// Floor height (odometry frame), metres.
    pub floor_height: Option<f64>,
    /// Ceiling height (odometry frame), metres.
    pub ceiling_height: Option<f64>,
}

impl Settings {
    /// The built-in defaults: the paper's settings with the Crazyflie 2.x.
    pub fn builtin() -> Self {
        Self::load(None, DEFAULT_NODE_NAME, &[]).expect("the built-in config is valid")
    }

    /// Loads a parameters file for node `node_name`, applies `-p` overrides, and validates.
    pub fn load(
        path: Option<&Path>,
        node_name: &str,
        overrides: &[String],
    ) -> Result<Self, ConfigError> {
        let paths: Vec<&Path> = path.into_iter().collect();
        load_all(&paths, node_name, overrides).map(|(settings, ..)| settings)
    }

    /// Reads this struct's parameters from the checked values; fails only on the limits that
    /// span parameters (the control sample's memory, the ceiling above the floor).
    pub fn from_parameters(p: &Parameters) -> Result<Self, ConfigError> {
        let robot_description = match p.text("robot_description") {
            xml if is_urdf_text(xml) => RobotSource::Text(xml.to_owned()),
            path => match BUILTIN_ROBOTS.iter().find(|(name, _)| *name == path) {
                Some((name, _)) => RobotSource::Builtin(name),
                None => RobotSource::File(PathBuf::from(path)),
            },
        };
        let count = |name: &str| {
            usize::try_from(p.integer(name)).expect("the table bounds counts to 1..=100000")
        };
        let (trajectories, steps) = (count("trajectories"), count("steps"));
        let volume_dims = match p.integer("volume_dims") {
            3 => VolumeDims::Three,
            _ => VolumeDims::Two,
        };
        within_budget(
            trajectories,
            steps,
            volume_dims,
            [p.source("trajectories"), p.source("steps")],
        )?;
        let model = p.choice("model", ModelKind::from_name);
        if model == ModelKind::DiffDrive && volume_dims == VolumeDims::Three {
            return Err(ConfigError::new(
                &p.source("volume_dims"),
                "'volume_dims' must be 2 with 'model' diff_drive: a ground robot's reachable \
                 set is an area",
            ));
        }
        let floor_height = p.double("floor_height");
        let ceiling_height = p.double("ceiling_height");
        if let (Some(floor), Some(ceiling)) = (floor_height, ceiling_height) {
            if ceiling <= floor {
                return Err(ConfigError::new(
                    &p.source("ceiling_height"),
                    format!("'ceiling_height' ({ceiling}) must be above 'floor_height' ({floor})"),
                ));
            }
        }
        Ok(Self {
            robot_description,
            model,
            horizon: p.required_double("horizon"),
            trajectories,
            steps,
            sampler: p.choice("sampler", SamplerKind::from_name),
            seed: u64::try_from(p.integer("seed")).expect("the table bounds the seed to ≥ 0"),
            safety_coefficient: p.required_double("safety_coefficient"),
            volume_dims,
            estimator: p.choice("estimator", EstimatorKind::from_name),
            robot_radius: p.double("robot_radius"),
            max_acceleration: p.double("max_acceleration"),
            wheel_max_speed: p.required_double("wheel_max_speed"),
            wheel_max_acceleration: p.required_double("wheel_max_acceleration"),
            wheel_separation_multiplier: p.double("wheel_separation_multiplier"),
            unknown_space: p.choice("unknown_space", UnknownSpace::from_name),
            floor_height,
            ceiling_height,
        })
    }
}

/// Refuses `trajectories × steps` whose control sample would exceed
/// [`CONTROL_SAMPLE_BUDGET_BYTES`], naming the values, the size and the budget; `sources` are
/// where the two counts were set.
fn within_budget(
    trajectories: usize,
    steps: usize,
    volume_dims: VolumeDims,
    sources: [String; 2],
) -> Result<(), ConfigError> {
    let axes = CommandAxes::for_volume_dims(volume_dims);
    let bytes = Controls::bytes(trajectories, steps, axes);
    if bytes <= CONTROL_SAMPLE_BUDGET_BYTES {
        return Ok(());
    }
    let mut sources = sources.to_vec();
    sources.dedup();
    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    // As few decimals as tell the need from the budget: 100 000 × 336 needs 256.3 MiB, which
    // whole MiB print as the budget's own 256. Seven resolve a byte, less than any excess.
    let (need, budget) = (0..=7)
        .map(|decimals| {
            let show = |b| format!("{:.*}", decimals, mib(b));
            (show(bytes), show(CONTROL_SAMPLE_BUDGET_BYTES))
        })
        .find(|(need, budget)| need != budget)
        .expect("seven decimals of a MiB tell apart any two byte counts");
    Err(ConfigError::new(
        &sources.join(" and "),
        format!(
            "'trajectories' × 'steps' ({trajectories} × {steps}, {} command axes) needs \
             {need} MiB of control samples, more than the {budget} MiB an evaluation may allocate",
            axes.count(),
        ),
    ))
}

/// The node's ROS interface: topic and service names, and input staleness.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeSettings {
    /// `nav_msgs/Odometry` input.
    pub odom_topic: String,
    /// `sensor_msgs/LaserScan` input (sensor-data QoS), unless `use_point_cloud`.
    pub scan_topic: String,
    /// `sensor_msgs/PointCloud2` input (sensor-data QoS), with `use_point_cloud`.
    pub cloud_topic: String,
    /// How clouds are read when `use_point_cloud` is on (and scans are not); `None`: scans.
    pub cloud: Option<CloudInput>,
    /// Optional `geometry_msgs/PoseStamped` goal for the task reward.
    pub goal_topic: String,
    /// `cstep_msgs/Empowerment` output.
    pub empowerment_topic: String,
    /// `cstep_msgs/EmpoweredReward` output.
    pub reward_topic: String,
    /// `visualization_msgs/MarkerArray` output (published only while subscribed).
    pub markers_topic: String,
    /// `nav2_msgs/SpeedLimit` output (with `publish_speed_limit`).
    pub speed_limit_topic: String,
    /// The speed limit's mapping and rate when `publish_speed_limit` is on; `None`: off.
    pub speed_limit: Option<SpeedLimitOutput>,
    /// `cstep_msgs/srv/Evaluate` service.
    pub evaluate_service: String,
    /// `cstep_msgs/srv/EvaluateBatch` service: K states per call, scored in parallel.
    pub evaluate_batch_service: String,
    /// Requests of one client the services hold waiting at once.
    pub service_queue_per_client: usize,
    /// Requests the services hold waiting at once, all clients together.
    pub service_queue_total: usize,
    /// Odometry older than this when a scan arrives is stale, seconds.
    pub input_timeout: f64,
    /// A scan stamped more than this many seconds before the newest one scored means that time
    /// jumped back (a simulation reset, a bag replayed): the stamp ordering is reset. Up to it,
    /// the scan is a late delivery and skipped.
    pub time_jump_tolerance: f64,
    /// Stamp outputs and measure ages with `/clock`.
    pub use_sim_time: bool,
}

impl NodeSettings {
    /// Reads this struct's parameters from the checked values; fails only on the limits that
    /// span parameters (a cloud's height band and range interval).
    pub fn from_parameters(p: &Parameters) -> Result<Self, ConfigError> {
        // The table's ranges start at 1, so every checked count converts.
        let count = |n: i64| usize::try_from(n).unwrap_or(usize::MAX);
        let name = |key: &str| p.text(key).to_owned();
        let cloud = if p.flag("use_point_cloud") {
            let options = CloudOptions {
                band: ordered(p, "cloud_min_height", "cloud_max_height")?,
                range_min: p.required_double("cloud_range_min"),
                range_max: p.required_double("cloud_range_max"),
                field_of_view: p.required_double("cloud_field_of_view"),
            };
            ordered(p, "cloud_range_min", "cloud_range_max")?;
            Some(CloudInput {
                options,
                max_points: count(p.integer("cloud_max_points")),
            })
        } else {
            None
        };
        let speed_limit_defaults =
            SpeedLimitMapping::model_defaults(p.choice("model", ModelKind::from_name));
        Ok(Self {
            odom_topic: name("odom_topic"),
            scan_topic: name("scan_topic"),
            cloud_topic: name("cloud_topic"),
            cloud,
            goal_topic: name("goal_topic"),
            empowerment_topic: name("empowerment_topic"),
            reward_topic: name("reward_topic"),
            markers_topic: name("markers_topic"),
            speed_limit_topic: name("speed_limit_topic"),
            speed_limit: p.flag("publish_speed_limit").then(|| SpeedLimitOutput {
                mapping: SpeedLimitMapping {
                    full_speed_at: p
                        .double("speed_limit_full_speed_at")
                        .unwrap_or(speed_limit_defaults.full_speed_at),
                    span: p
                        .double("speed_limit_span")
                        .unwrap_or(speed_limit_defaults.span),
                    floor: p.required_double("speed_limit_floor"),
                    max_speed: p.double("speed_limit_max_speed"),
                },
                rate_hz: p.required_double("speed_limit_rate"),
            }),
            evaluate_service: name("evaluate_service"),
            evaluate_batch_service: name("evaluate_batch_service"),
            service_queue_per_client: count(p.integer("service_queue_per_client")),
            service_queue_total: count(p.integer("service_queue_total")),
            input_timeout: p.required_double("input_timeout"),
            time_jump_tolerance: p.required_double("time_jump_tolerance"),
            use_sim_time: p.flag("use_sim_time"),
        })
    }
}

/// The values of `low` and `high`, refused unless `low` is below `high`.
fn ordered(p: &Parameters, low: &str, high: &str) -> Result<(f64, f64), ConfigError> {
    let (a, b) = (p.required_double(low), p.required_double(high));
    if a < b {
        Ok((a, b))
    } else {
        Err(ConfigError::new(
            &p.source(high),
            format!("'{high}' ({b}) must be above '{low}' ({a})"),
        ))
    }
}

/// Loads the built-in defaults, then each parameters file in order, then the `-p` overrides,
/// for node `node_name`, and checks them with [`validate`].
pub fn load_all(
    paths: &[&Path],
    node_name: &str,
    overrides: &[String],
) -> Result<(Settings, NodeSettings, Parameters), ConfigError> {
    let mut set = ParameterSet::builtin();
    for path in paths {
        set.merge_file(path, node_name)?;
    }
    for assignment in overrides {
        set.assign(assignment)?;
    }
    validate(set)
}

/// Checks a complete parameter set (the built-in defaults with files and overrides applied,
/// however they were gathered: [`load_all`] here, the node's `--ros-args` in
/// [`super::overrides`]) against [`super::PARAMETERS`], rejects unknown names, and reads the
/// evaluation's and the node's settings. The checked values come back too: the node declares
/// them.
pub fn validate(set: ParameterSet) -> Result<(Settings, NodeSettings, Parameters), ConfigError> {
    let parameters = set.check()?;
    let settings = Settings::from_parameters(&parameters)?;
    let node = NodeSettings::from_parameters(&parameters)?;
    Ok((settings, node, parameters))
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;
    use crate::model::urdf::RobotDescription;
    use crate::parameters::BUILTIN_URDF_PATH;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn temp_dir(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("cstep-config-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn table_choices_are_the_names_the_code_parses() {
        type Parses = fn(&str) -> bool;
        let parsers: [(&str, Parses); 4] = [
            ("model", |w| ModelKind::from_name(w).is_some()),
            ("sampler", |w| SamplerKind::from_name(w).is_some()),
            ("estimator", |w| EstimatorKind::from_name(w).is_some()),
            ("unknown_space", |w| UnknownSpace::from_name(w).is_some()),
        ];
        for p in crate::parameters::PARAMETERS {
            let crate::parameters::Rule::Choice(words) = p.rule else {
                continue;
            };
            let (_, parses) = parsers
                .iter()
                .find(|(name, _)| *name == p.name)
                .unwrap_or_else(|| panic!("'{}' is a choice no setting reads", p.name));
            for &word in words {
                assert!(parses(word), "'{}': the table allows {word}", p.name);
            }
        }
    }

    #[test]
    fn builtin_defaults_are_the_papers_settings() {
        let s = Settings::builtin();
        assert_eq!(s.model, ModelKind::Quadrotor);
        assert_eq!((s.horizon, s.trajectories, s.steps), (1.0, 150, 100));
        assert_eq!(s.volume_dims, VolumeDims::Two);
        assert_eq!(s.robot_description, RobotSource::Builtin(BUILTIN_URDF_PATH));
        assert_eq!(s.robot_radius, None);
    }

    #[test]
    fn point_clouds_are_off_by_default_and_read_whole_when_on() {
        let (_, node, _) = load_all(&[], DEFAULT_NODE_NAME, &[]).unwrap();
        assert_eq!((node.cloud, node.cloud_topic.as_str()), (None, "cloud"));
        let on = [
            "use_point_cloud:=true",
            "cloud_min_height:=0.05",
            "cloud_max_height:=0.6",
            "cloud_range_max:=8.0",
            "cloud_field_of_view:=1.5",
            "cloud_max_points:=1000",
        ]
        .map(String::from);
        let (_, node, _) = load_all(&[], DEFAULT_NODE_NAME, &on).unwrap();
        let options = CloudOptions {
            band: (0.05, 0.6),
            range_min: 0.1,
            range_max: 8.0,
            field_of_view: 1.5,
        };
        assert_eq!(
            node.cloud,
            Some(CloudInput {
                options,
                max_points: 1000
            })
        );
        for (bad, says) in [
            (
                ["cloud_min_height:=0.3", "cloud_max_height:=0.3"],
                "'cloud_max_height' (0.3) must be above 'cloud_min_height' (0.3)",
            ),
            (
                ["cloud_range_min:=2", "cloud_range_max:=1"],
                "'cloud_range_max' (1) must be above 'cloud_range_min' (2)",
            ),
        ] {
            let mut assignments = vec!["use_point_cloud:=true".to_owned()];
            assignments.extend(bad.map(String::from));
            let error = load_all(&[], DEFAULT_NODE_NAME, &assignments)
                .unwrap_err()
                .to_string();
            assert!(error.contains(says), "{error}");
        }
    }

    #[test]
    fn the_speed_limit_is_off_by_default_and_read_whole_when_on() {
        let (_, node, _) = load_all(&[], DEFAULT_NODE_NAME, &[]).unwrap();
        assert_eq!(node.speed_limit, None);
        assert_eq!(node.speed_limit_topic, "speed_limit");
        let on = [
            "publish_speed_limit:=true",
            "speed_limit_floor:=5",
            "speed_limit_max_speed:=0.8",
        ]
        .map(String::from);
        let (_, node, _) = load_all(&[], DEFAULT_NODE_NAME, &on).unwrap();
        let mapping = SpeedLimitMapping {
            full_speed_at: 1.5,
            span: 1.5,
            floor: 5.0,
            max_speed: Some(0.8),
        };
        assert_eq!(
            node.speed_limit,
            Some(SpeedLimitOutput {
                mapping,
                rate_hz: 10.0
            })
        );
        // A wheeled robot scores on another scale (the Husky: −1.04 at top speed in the open):
        // its threshold and span are its model's own unless set.
        let wheeled = [
            "publish_speed_limit:=true",
            "model:=diff_drive",
            "volume_dims:=2",
        ]
        .map(String::from);
        let (_, node, _) = load_all(&[], DEFAULT_NODE_NAME, &wheeled).unwrap();
        let mapping = node.speed_limit.unwrap().mapping;
        assert_eq!((mapping.full_speed_at, mapping.span), (-1.05, 0.7));
        let set = [&wheeled[..], &["speed_limit_full_speed_at:=-2".into()]].concat();
        let (_, node, _) = load_all(&[], DEFAULT_NODE_NAME, &set).unwrap();
        let mapping = node.speed_limit.unwrap().mapping;
        assert_eq!((mapping.full_speed_at, mapping.span), (-2.0, 0.7));
        let error = load_all(&[], DEFAULT_NODE_NAME, &["speed_limit_floor:=0".into()])
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("'speed_limit_floor' must be a number in 1.0 to 100.0, got 0"),
            "{error}"
        );
    }

    #[test]
    fn the_shipped_config_file_loads_and_resolves_the_urdf_next_to_it() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../config/cstep.yaml");
        let s = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap();
        let RobotSource::File(urdf) = &s.robot_description else {
            panic!()
        };
        assert!(urdf.exists(), "{}", urdf.display());
    }

    #[test]
    fn urdf_text_in_robot_description_is_the_robot_not_a_path() {
        // launch files pass robot_description as the URDF text (launch_ros writes it into a
        // parameters file as a YAML string); it must not be taken for a relative path.
        let urdf_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../urdf/cf2x.urdf");
        let urdf = std::fs::read_to_string(&urdf_path).unwrap();
        let dir = temp_dir("urdf-text");
        let file: BTreeMap<&str, BTreeMap<&str, BTreeMap<&str, &str>>> = BTreeMap::from([(
            "/**",
            BTreeMap::from([(
                "ros__parameters",
                BTreeMap::from([("robot_description", urdf.as_str())]),
            )]),
        )]);
        let path = write(&dir, "p.yaml", &serde_norway::to_string(&file).unwrap());
        let s = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap();
        assert_eq!(s.robot_description, RobotSource::Text(urdf));
        let from_text = crate::estimator::robot_description(&s).unwrap();
        let from_file = RobotDescription::load(&urdf_path).unwrap();
        assert_eq!(
            RobotDescription {
                source: from_file.source.clone(),
                ..from_text
            },
            from_file
        );
        let broken = write(
            &dir,
            "broken.yaml",
            "/**:\n  ros__parameters:\n    robot_description: \"<robot name='x'>\"\n",
        );
        let s = Settings::load(Some(&broken), DEFAULT_NODE_NAME, &[]).unwrap();
        let error = crate::estimator::robot_description(&s)
            .unwrap_err()
            .to_string();
        assert!(error.contains("robot_description (URDF text)"), "{error}");
    }

    #[test]
    fn overrides_and_wildcard_sections_apply() {
        let dir = temp_dir("wild");
        let path = write(
            &dir,
            "p.yaml",
            "/**:\n  ros__parameters:\n    horizon: 0.5\n",
        );
        let s = Settings::load(
            Some(&path),
            "anything",
            &["trajectories:=2000".into(), "model:=point_mass".into()],
        )
        .unwrap();
        assert_eq!(s.horizon, 0.5);
        assert_eq!(s.trajectories, 2000);
        assert_eq!(s.model, ModelKind::PointMass);
    }

    #[test]
    fn a_parameters_file_means_what_it_means_to_the_node() {
        // `cstep eval --config` read only `name:` and `/**:` sections; the node reads rcl's
        // whole table (fully qualified and nested keys, `*` and `**`): one file, one meaning.
        let dir = temp_dir("rcl");
        let load = |name: &str, text: &str| {
            Settings::load(Some(&write(&dir, name, text)), DEFAULT_NODE_NAME, &[])
        };
        let nested = "/**/cstep_node:\n  ros__parameters:\n    horizon: 0.5\n\
                      /cstep_node:\n  ros__parameters:\n    trajectories: 300\n";
        let s = load("nested.yaml", nested).unwrap();
        assert_eq!((s.horizon, s.trajectories), (0.5, 300));
        let s = load("star.yaml", "/*:\n  ros__parameters:\n    horizon: 0.7\n").unwrap();
        assert_eq!(s.horizon, 0.7);
        // A section for the node in a namespace is not the root namespace's node's.
        let other = "drone1:\n  cstep_node:\n    ros__parameters:\n      horizon: 0.5\n";
        let err = load("ns.yaml", other).unwrap_err();
        assert!(
            err.to_string()
                .contains("no parameters for node 'cstep_node'"),
            "{err}"
        );
    }

    #[test]
    fn evaluations_beyond_the_memory_budget_are_refused_naming_values_and_budget() {
        // Regression: 100 000 × 10 000 validated, then the first evaluation asked for
        // 7.5 GiB and the allocator aborted the process.
        let dir = temp_dir("budget");
        let path = write(
            &dir,
            "big.yaml",
            "cstep_node:\n  ros__parameters:\n    trajectories: 100000\n    steps: 10000\n",
        );
        let err = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap_err();
        assert_eq!(
            err.to_string(),
            format!(
                "{}: 'trajectories' × 'steps' (100000 × 10000, 2 command axes) needs 7629 MiB \
                 of control samples, more than the 256 MiB an evaluation may allocate",
                path.display()
            )
        );
        let overrides = |t: u64, s: u64, dims: u64| {
            vec![
                format!("trajectories:={t}"),
                format!("steps:={s}"),
                format!("volume_dims:={dims}"),
            ]
        };
        // At the budget (2 axes × 4 bytes × 100 000 × 335 ≤ 256 MiB) it loads; one step more
        // does not, and 3D commands take a third more.
        assert!(Settings::load(None, DEFAULT_NODE_NAME, &overrides(100_000, 335, 2)).is_ok());
        // Just past the budget, the need is printed finely enough to differ from it.
        let err = Settings::load(None, DEFAULT_NODE_NAME, &overrides(100_000, 336, 2));
        assert_eq!(
            err.unwrap_err().to_string(),
            "command line: 'trajectories' × 'steps' (100000 × 336, 2 command axes) needs 256.3 \
             MiB of control samples, more than the 256.0 MiB an evaluation may allocate"
        );
        assert!(Settings::load(None, DEFAULT_NODE_NAME, &overrides(100_000, 223, 3)).is_ok());
        assert!(Settings::load(None, DEFAULT_NODE_NAME, &overrides(100_000, 224, 3)).is_err());
    }

    #[test]
    fn errors_quote_a_long_value_or_name_by_its_start_and_length() {
        // Regression: a 15 MiB string value gave a 15.7 MB error line, a 120 KB `-p` value a
        // 120 KB line.
        let dir = temp_dir("excerpt");
        let long = "x".repeat(1 << 20);
        let path = write(
            &dir,
            "long.yaml",
            &format!("cstep_node:\n  ros__parameters:\n    sampler: \"{long}\"\n"),
        );
        let err = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap_err();
        assert_eq!(
            err.message,
            format!(
                "'sampler' must be one of bang_bang | fourier | chebyshev, got \"{}… (1048576 \
                 characters)\"",
                "x".repeat(80)
            )
        );
        let list = format!("[{}1]", "1,".repeat(60_000));
        let cases = [
            format!("horizon:={list}"),
            format!("{}:=1", "y".repeat(120_000)),
            "z".repeat(120_000),
            format!("odom_topic:=\"a {}\"", "b".repeat(120_000)),
        ];
        for assignment in &cases {
            let err = Settings::load(None, DEFAULT_NODE_NAME, std::slice::from_ref(assignment));
            let text = err.unwrap_err().to_string();
            assert!(text.len() < 1024, "{} bytes: {:.200}", text.len(), text);
            assert!(text.contains(" characters)"), "{text}");
        }
    }

    #[test]
    fn bad_values_name_the_file_the_parameter_and_the_value() {
        let dir = temp_dir("bad");
        let cases = [
            ("horizon: -1", "'horizon' must be a positive number, got -1"),
            ("horizon: soon", "'horizon' must be a number, got soon"),
            (
                "trajectories: 0",
                "'trajectories' must be between 1 and 100000, got 0",
            ),
            (
                "sampler: uniform",
                "'sampler' must be one of bang_bang | fourier | chebyshev, got \"uniform\"",
            ),
            (
                "volume_dims: 4",
                "'volume_dims' must be one of 2 | 3, got 4",
            ),
            // A misspelling names the parameter meant.
            (
                "horizn: 1.0",
                "unknown parameter 'horizn', did you mean 'horizon'?",
            ),
            (
                "colour: 1.0",
                "unknown parameter 'colour' (known: robot_description, model, ",
            ),
            // Regression: NaN said "must be set (... a file or -p cleared it)", and a
            // list gave a three-line error.
            (
                "horizon: .nan",
                "'horizon' must be a positive number, got NaN (not finite)",
            ),
            ("horizon: [1, 2]", "'horizon' must be a number, got [1,2]"),
            (
                "safety_coefficient: 0",
                "'safety_coefficient' must be a positive number, got 0",
            ),
        ];
        for (line, expected) in cases {
            let path = write(
                &dir,
                "bad.yaml",
                &format!("cstep_node:\n  ros__parameters:\n    {line}\n"),
            );
            let err = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap_err();
            let text = err.to_string();
            assert!(text.starts_with(&path.display().to_string()), "{text}");
            assert_eq!(text.lines().count(), 1, "{text}");
            assert!(text.contains(expected), "{text} lacks {expected}");
        }
        let err = Settings::load(
            None,
            DEFAULT_NODE_NAME,
            &["safety_coefficient:=.nan".into()],
        );
        assert_eq!(
            err.unwrap_err().to_string(),
            "command line: 'safety_coefficient' must be a positive number, got NaN (not finite)"
        );
        let err = Settings::load(None, DEFAULT_NODE_NAME, &["seed=3".into()]).unwrap_err();
        assert!(err.to_string().contains("name:=value"));
        let path = write(
            &dir,
            "other.yaml",
            "other_node:\n  ros__parameters:\n    seed: 1\n",
        );
        let err = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap_err();
        assert!(
            err.to_string()
                .contains("no parameters for node 'cstep_node'"),
            "{err}"
        );
        let path = write(&dir, "broken.yaml", "cstep_node: [unclosed\n");
        let err = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap_err();
        assert!(err.to_string().contains("not valid YAML"), "{err}");
        let err =
            Settings::load(Some(&dir.join("missing.yaml")), DEFAULT_NODE_NAME, &[]).unwrap_err();
        assert!(err.to_string().contains("cannot read the file"), "{err}");
    }
}
