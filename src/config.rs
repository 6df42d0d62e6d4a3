//! The node's parameters: ROS 2 `ros__parameters` YAML, validated on load with clear errors.
//!
//! Parameters are read into a [`ParameterSet`] (from a file, the built-in defaults, and
//! `-p name:=value` overrides), then each consumer takes the names it owns and checks them; any
//! name nobody took is reported as unknown, so a typo never silently falls back to a default.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_norway::Value;

use crate::model::CommandAxes;
use crate::occupancy::UnknownSpace;
use crate::sampling::{Controls, SamplerKind, CONTROL_SAMPLE_BUDGET_BYTES};
use crate::volume::{EstimatorKind, VolumeDims};

/// The node name whose parameters are read when none is given.
pub const DEFAULT_NODE_NAME: &str = "cstep_node";

/// The default parameter file, compiled in so the binary runs anywhere.
pub const BUILTIN_CONFIG: &str = include_str!("../config/cstep.yaml");

/// The Crazyflie 2.x URDF, compiled in for the built-in defaults.
pub const BUILTIN_URDF: &str = include_str!("../urdf/cf2x.urdf");

/// A parameter file or value that cannot be used, with where it came from.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{source_name}: {message}")]
pub struct ConfigError {
    /// The file (or "command line") the bad value came from.
    pub source_name: String,
    /// What is wrong, naming the parameter and the value.
    pub message: String,
}

impl ConfigError {
    fn new(source_name: &str, message: impl Into<String>) -> Self {
        Self {
            source_name: source_name.to_owned(),
            message: message.into(),
        }
    }
}

/// Parameter values by name, each remembering where it was set.
#[derive(Debug, Clone, Default)]
pub struct ParameterSet {
    values: BTreeMap<String, (Value, String)>,
}

impl ParameterSet {
    /// The built-in defaults (`config/cstep.yaml` as compiled in).
    pub fn builtin() -> Self {
        let mut set = Self::default();
        set.merge_yaml(BUILTIN_CONFIG, "built-in config", None, DEFAULT_NODE_NAME)
            .expect("the built-in config is valid");
        set.values.insert(
            "robot_description".into(),
            (
                Value::String(BUILTIN_URDF_PATH.into()),
                "built-in config".into(),
            ),
        );
        set
    }

    /// Overlays the parameters file `path`'s section for node `node_name`.
    pub fn merge_file(&mut self, path: &Path, node_name: &str) -> Result<(), ConfigError> {
        let source = path.display().to_string();
        let text = crate::input_file::read_to_string(path)
            .map_err(|e| ConfigError::new(&source, format!("cannot read the file: {e}")))?;
        self.merge_yaml(&text, &source, path.parent(), node_name)
    }

    /// Overlays one `name:=value` assignment from the command line (the value is read as YAML).
    pub fn assign(&mut self, assignment: &str) -> Result<(), ConfigError> {
        let source = "command line";
        let (name, value) = assignment.split_once(":=").ok_or_else(|| {
            ConfigError::new(
                source,
                format!("'{assignment}' is not a parameter assignment of the form name:=value"),
            )
        })?;
        let value: Value = serde_norway::from_str(value).map_err(|e| {
            ConfigError::new(source, format!("cannot read the value of '{name}': {e}"))
        })?;
        self.values
            .insert(name.trim().to_owned(), (value, source.to_owned()));
        Ok(())
    }

    /// Sets `name` to `value`, read from `source` (a file, whose directory `base_dir` relative
    /// paths are relative to, or the command line): for overrides gathered elsewhere, such as
    /// the node's `--ros-args` ([`crate::ros::param_overrides`]).
    pub fn insert(&mut self, name: &str, value: Value, source: &str, base_dir: Option<&Path>) {
        let value = if name == "robot_description" {
            resolve_path(value, base_dir)
        } else {
            value
        };
        self.values
            .insert(name.to_owned(), (value, source.to_owned()));
    }

    /// Reads a `ros__parameters` file's section for `node_name` (or the `/**` wildcard) into the
    /// set; nested maps become dotted names as in ROS 2.
    fn merge_yaml(
        &mut self,
        text: &str,
        source: &str,
        base_dir: Option<&Path>,
        node_name: &str,
    ) -> Result<(), ConfigError> {
        let document: Value = serde_norway::from_str(text)
            .map_err(|e| ConfigError::new(source, format!("not valid YAML: {e}")))?;
        let Value::Mapping(nodes) = document else {
            return Err(ConfigError::new(
                source,
                "expected a mapping of node names to `ros__parameters`",
            ));
        };
        let bare = node_name.trim_start_matches('/');
        let mut found = false;
        for (key, section) in &nodes {
            let key = key.as_str().unwrap_or_default();
            let matches = key == "/**" || key.trim_start_matches('/') == bare;
            if !matches {
                continue;
            }
            let parameters = section.get("ros__parameters").ok_or_else(|| {
                ConfigError::new(
                    source,
                    format!("node '{key}' has no `ros__parameters` section"),
                )
            })?;
            let Value::Mapping(parameters) = parameters else {
                return Err(ConfigError::new(
                    source,
                    format!("`{key}.ros__parameters` must be a mapping"),
                ));
            };
            found = true;
            let mut flat = Vec::new();
            flatten("", parameters, &mut flat);
            for (name, mut value) in flat {
                if name == "robot_description" {
                    value = resolve_path(value, base_dir);
                }
                self.values.insert(name, (value, source.to_owned()));
            }
        }
        if found {
            Ok(())
        } else {
            Err(ConfigError::new(
                source,
                format!("no parameters for node '{bare}' (expected a '{bare}:' or '/**:' section)"),
            ))
        }
    }

    fn take(&mut self, name: &str) -> Option<(Value, String)> {
        self.values.remove(name)
    }

    /// Takes a number; `None` when unset, null or NaN (the ROS idiom for "not set").
    pub fn take_f64(&mut self, name: &str) -> Result<Option<f64>, ConfigError> {
        let Some((value, source)) = self.take(name) else {
            return Ok(None);
        };
        match value {
            Value::Null => Ok(None),
            Value::Number(n) => Ok(n.as_f64().filter(|v| !v.is_nan())),
            other => Err(ConfigError::new(
                &source,
                format!("'{name}' must be a number, got {}", show(&other)),
            )),
        }
    }

    /// Takes a non-negative integer.
    pub fn take_u64(&mut self, name: &str) -> Result<Option<u64>, ConfigError> {
        let Some((value, source)) = self.take(name) else {
            return Ok(None);
        };
        match &value {
            Value::Null => Ok(None),
            Value::Number(n) if n.as_u64().is_some() => Ok(n.as_u64()),
            other => Err(ConfigError::new(
                &source,
                format!("'{name}' must be a whole number ≥ 0, got {}", show(other)),
            )),
        }
    }

    /// Takes a string (numbers are accepted and read as text, as `volume_dims: 2` is).
    pub fn take_string(&mut self, name: &str) -> Result<Option<(String, String)>, ConfigError> {
        let Some((value, source)) = self.take(name) else {
            return Ok(None);
        };
        match value {
            Value::Null => Ok(None),
            Value::String(s) => Ok(Some((s, source))),
            Value::Number(n) => Ok(Some((n.to_string(), source))),
            other => Err(ConfigError::new(
                &source,
                format!("'{name}' must be a string, got {}", show(&other)),
            )),
        }
    }

    /// Fails on the first parameter no consumer took.
    pub fn finish(self, known: &[&str]) -> Result<(), ConfigError> {
        match self.values.into_iter().next() {
            None => Ok(()),
            Some((name, (_, source))) => Err(ConfigError::new(
                &source,
                format!("unknown parameter '{name}' (known: {})", known.join(", ")),
            )),
        }
    }
}

/// The marker path the built-in config uses for the compiled-in URDF.
pub const BUILTIN_URDF_PATH: &str = "builtin:cf2x.urdf";

/// Nested parameter maps as dotted names (`limits: {speed: 2}` is `limits.speed`), as in ROS 2.
pub fn flatten(prefix: &str, mapping: &serde_norway::Mapping, out: &mut Vec<(String, Value)>) {
    for (key, value) in mapping {
        let key = match key {
            Value::String(s) => s.clone(),
            other => show(other),
        };
        let name = if prefix.is_empty() {
            key
        } else {
            format!("{prefix}.{key}")
        };
        match value {
            Value::Mapping(inner) => flatten(&name, inner, out),
            other => out.push((name, other.clone())),
        }
    }
}

fn resolve_path(value: Value, base_dir: Option<&Path>) -> Value {
    match (&value, base_dir) {
        (Value::String(s), Some(dir))
            if Path::new(s).is_relative() && !s.starts_with("builtin:") =>
        {
            Value::String(dir.join(s).display().to_string())
        }
        _ => value,
    }
}

/// A value as it reads in a one-line error: scalars as YAML (`soon`, `true`), lists and maps in
/// flow style (`[1,2]`), never the block YAML that would span lines.
fn show(value: &Value) -> String {
    let text = match value {
        Value::Sequence(_) | Value::Mapping(_) | Value::Tagged(_) => {
            serde_json::to_string(value).ok()
        }
        _ => serde_norway::to_string(value).ok(),
    };
    text.map(|s| s.trim().to_owned())
        .filter(|s| !s.contains('\n'))
        .unwrap_or_else(|| format!("{value:?}"))
}

/// Which dynamics model rolls out the trajectories.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// The URDF-derived 6-DoF quadrotor with motors and an attitude controller.
    Quadrotor,
    /// The paper prototype's double integrator.
    PointMass,
}

impl ModelKind {
    /// The name used in configuration files.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Quadrotor => "quadrotor",
            ModelKind::PointMass => "point_mass",
        }
    }

    /// Parses a configuration name.
    pub fn from_name(name: &str) -> Option<Self> {
        [ModelKind::Quadrotor, ModelKind::PointMass]
            .into_iter()
            .find(|m| m.name() == name)
    }
}

/// Where the robot's URDF comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RobotSource {
    /// The compiled-in Crazyflie 2.x.
    Builtin,
    /// A URDF file.
    File(PathBuf),
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
    /// Treatment of space the scan does not describe.
    pub unknown_space: UnknownSpace,
    /// Floor height (odometry frame), metres.
    pub floor_height: Option<f64>,
    /// Ceiling height (odometry frame), metres.
    pub ceiling_height: Option<f64>,
}

/// The parameter names [`Settings`] owns — a contract with users' parameter files.
pub const SETTINGS_PARAMETERS: [&str; 15] = [
    "robot_description",
    "model",
    "horizon",
    "trajectories",
    "steps",
    "sampler",
    "seed",
    "safety_coefficient",
    "volume_dims",
    "estimator",
    "robot_radius",
    "max_acceleration",
    "unknown_space",
    "floor_height",
    "ceiling_height",
];

/// Largest accepted trajectory count and step count: beyond these an evaluation takes seconds.
const MAX_TRAJECTORIES: u64 = 100_000;
const MAX_STEPS: u64 = 10_000;

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
        load_all(&paths, node_name, overrides).map(|(settings, _)| settings)
    }

    /// Takes and validates this struct's parameters from `set`, leaving the others.
    pub fn take_from(set: &mut ParameterSet) -> Result<Self, ConfigError> {
        let robot_description = match set.take_string("robot_description")? {
            None => RobotSource::Builtin,
            Some((path, _)) if path == BUILTIN_URDF_PATH => RobotSource::Builtin,
            Some((path, _)) => RobotSource::File(PathBuf::from(path)),
        };
        let models = ["quadrotor", "point_mass"];
        let model = required("model", named(set, "model", ModelKind::from_name, &models)?)?;
        let horizon = required_positive(set, "horizon")?;
        let count_source = |name: &str| set.values.get(name).map(|(_, s)| s.clone());
        let sample_source = [count_source("trajectories"), count_source("steps")];
        let trajectories = required(
            "trajectories",
            bounded_count(set, "trajectories", 1, MAX_TRAJECTORIES)?,
        )?;
        let steps = required("steps", bounded_count(set, "steps", 1, MAX_STEPS)?)?;
        let samplers: Vec<_> = SamplerKind::ALL.iter().map(|s| s.name()).collect();
        let sampler = required(
            "sampler",
            named(set, "sampler", SamplerKind::from_name, &samplers)?,
        )?;
        let seed = required("seed", set.take_u64("seed")?)?;
        let safety_coefficient = required_positive(set, "safety_coefficient")?;
        let volume_dims = required(
            "volume_dims",
            named(
                set,
                "volume_dims",
                |s| match s {
                    "2" => Some(VolumeDims::Two),
                    "3" => Some(VolumeDims::Three),
                    _ => None,
                },
                &["2", "3"],
            )?,
        )?;
        within_budget(trajectories, steps, volume_dims, sample_source)?;
        let estimators: Vec<_> = EstimatorKind::ALL.iter().map(|e| e.name()).collect();
        let estimator = required(
            "estimator",
            named(set, "estimator", EstimatorKind::from_name, &estimators)?,
        )?;
        let robot_radius = positive(set, "robot_radius")?;
        let max_acceleration = positive(set, "max_acceleration")?;
        let policies = ["occupied", "free"];
        let unknown_space = required(
            "unknown_space",
            named(set, "unknown_space", UnknownSpace::from_name, &policies)?,
        )?;
        let ceiling_source = set.values.get("ceiling_height").map(|(_, s)| s.clone());
        let floor_height = finite(set, "floor_height")?;
        let ceiling_height = finite(set, "ceiling_height")?;
        if let (Some(floor), Some(ceiling)) = (floor_height, ceiling_height) {
            if ceiling <= floor {
                return Err(ConfigError::new(
                    &ceiling_source.unwrap_or_default(),
                    format!("'ceiling_height' ({ceiling}) must be above 'floor_height' ({floor})"),
                ));
            }
        }
        Ok(Self {
            robot_description,
            model,
            horizon,
            trajectories,
            steps,
            sampler,
            seed,
            safety_coefficient,
            volume_dims,
            estimator,
            robot_radius,
            max_acceleration,
            unknown_space,
            floor_height,
            ceiling_height,
        })
    }
}

/// A parameter every evaluation needs: the built-in config always sets it, so it is missing
/// only when a file or override cleared it (`name: ~`).
fn required<T>(name: &str, value: Option<T>) -> Result<T, ConfigError> {
    value.ok_or_else(|| {
        ConfigError::new(
            "parameters",
            format!("'{name}' must be set (the built-in config sets it; a file or -p cleared it)"),
        )
    })
}

/// Refuses `trajectories × steps` whose control sample would exceed
/// [`CONTROL_SAMPLE_BUDGET_BYTES`], naming the values, the size and the budget; `sources` are
/// where the two counts were set.
fn within_budget(
    trajectories: usize,
    steps: usize,
    volume_dims: VolumeDims,
    sources: [Option<String>; 2],
) -> Result<(), ConfigError> {
    let axes = CommandAxes::for_volume_dims(volume_dims);
    let bytes = Controls::bytes(trajectories, steps, axes);
    if bytes <= CONTROL_SAMPLE_BUDGET_BYTES {
        return Ok(());
    }
    let mut sources: Vec<String> = sources.into_iter().flatten().collect();
    sources.dedup();
    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    Err(ConfigError::new(
        &sources.join(" and "),
        format!(
            "'trajectories' × 'steps' ({trajectories} × {steps}, {} command axes) needs \
             {:.0} MiB of control samples, more than the {:.0} MiB an evaluation may allocate",
            axes.count(),
            mib(bytes),
            mib(CONTROL_SAMPLE_BUDGET_BYTES),
        ),
    ))
}

/// The node's ROS interface: topic and service names, and input staleness.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeSettings {
    /// `nav_msgs/Odometry` input.
    pub odom_topic: String,
    /// `sensor_msgs/LaserScan` input (sensor-data QoS).
    pub scan_topic: String,
    /// Optional `geometry_msgs/PoseStamped` goal for the task reward.
    pub goal_topic: String,
    /// `cstep_msgs/Empowerment` output.
    pub empowerment_topic: String,
    /// `cstep_msgs/EmpoweredReward` output.
    pub reward_topic: String,
    /// `visualization_msgs/MarkerArray` output (published only while subscribed).
    pub markers_topic: String,
    /// `cstep_msgs/srv/Evaluate` service.
    pub evaluate_service: String,
    /// `cstep_msgs/srv/EvaluateBatch` service: K states per call, scored in parallel.
    pub evaluate_batch_service: String,
    /// Odometry older than this when a scan arrives is stale, seconds.
    pub input_timeout: f64,
    /// A scan stamped more than this many seconds before the newest one scored means that time
    /// jumped back (a simulation reset, a bag replayed): the stamp ordering is reset. Up to it,
    /// the scan is a late delivery and skipped.
    pub time_jump_tolerance: f64,
    /// Stamp outputs and measure ages with `/clock`.
    pub use_sim_time: bool,
}

/// The parameter names [`NodeSettings`] owns.
pub const NODE_PARAMETERS: [&str; 11] = [
    "odom_topic",
    "scan_topic",
    "goal_topic",
    "empowerment_topic",
    "reward_topic",
    "markers_topic",
    "evaluate_service",
    "evaluate_batch_service",
    "input_timeout",
    "time_jump_tolerance",
    "use_sim_time",
];

impl NodeSettings {
    /// Takes and validates this struct's parameters from `set`, leaving the others.
    pub fn take_from(set: &mut ParameterSet) -> Result<Self, ConfigError> {
        let mut name = |key: &str| -> Result<String, ConfigError> {
            let (value, source) = required(key, set.take_string(key)?)?;
            if value.is_empty() || value.contains(char::is_whitespace) {
                return Err(ConfigError::new(
                    &source,
                    format!("'{key}' must be a ROS name without spaces, got \"{value}\""),
                ));
            }
            Ok(value)
        };
        let odom_topic = name("odom_topic")?;
        let scan_topic = name("scan_topic")?;
        let goal_topic = name("goal_topic")?;
        let empowerment_topic = name("empowerment_topic")?;
        let reward_topic = name("reward_topic")?;
        let markers_topic = name("markers_topic")?;
        let evaluate_service = name("evaluate_service")?;
        let evaluate_batch_service = name("evaluate_batch_service")?;
        let input_timeout = required_positive(set, "input_timeout")?;
        let time_jump_tolerance = required_positive(set, "time_jump_tolerance")?;
        let use_sim_time = match set.take("use_sim_time") {
            None | Some((Value::Null, _)) => false,
            Some((Value::Bool(b), _)) => b,
            Some((other, source)) => {
                return Err(ConfigError::new(
                    &source,
                    format!("'use_sim_time' must be true or false, got {}", show(&other)),
                ))
            }
        };
        Ok(Self {
            odom_topic,
            scan_topic,
            goal_topic,
            empowerment_topic,
            reward_topic,
            markers_topic,
            evaluate_service,
            evaluate_batch_service,
            input_timeout,
            time_jump_tolerance,
            use_sim_time,
        })
    }
}

/// Loads the built-in defaults, then each parameters file in order, then the `-p` overrides,
/// for node `node_name`; validates everything and rejects unknown names.
pub fn load_all(
    paths: &[&Path],
    node_name: &str,
    overrides: &[String],
) -> Result<(Settings, NodeSettings), ConfigError> {
    let mut set = ParameterSet::builtin();
    for path in paths {
        set.merge_file(path, node_name)?;
    }
    for assignment in overrides {
        set.assign(assignment)?;
    }
    validate(set)
}

/// Validates a complete parameter set (the built-in defaults with overrides applied) into the
/// settings; rejects unknown names.
pub fn validate(mut set: ParameterSet) -> Result<(Settings, NodeSettings), ConfigError> {
    let node = NodeSettings::take_from(&mut set)?;
    let settings = Settings::take_from(&mut set)?;
    let known: Vec<&str> = SETTINGS_PARAMETERS
        .iter()
        .chain(&NODE_PARAMETERS)
        .copied()
        .collect();
    set.finish(&known)?;
    Ok((settings, node))
}

fn named<T>(
    set: &mut ParameterSet,
    name: &str,
    parse: impl Fn(&str) -> Option<T>,
    choices: &[&str],
) -> Result<Option<T>, ConfigError> {
    let Some((text, source)) = set.take_string(name)? else {
        return Ok(None);
    };
    parse(&text).map(Some).ok_or_else(|| {
        ConfigError::new(
            &source,
            format!(
                "'{name}' must be one of {}, got \"{text}\"",
                choices.join(" | ")
            ),
        )
    })
}

fn positive(set: &mut ParameterSet, name: &str) -> Result<Option<f64>, ConfigError> {
    let source = set.values.get(name).map(|(_, s)| s.clone());
    match set.take_f64(name)? {
        Some(v) if !(v.is_finite() && v > 0.0) => Err(ConfigError::new(
            &source.unwrap_or_default(),
            format!("'{name}' must be a positive number, got {v}"),
        )),
        other => Ok(other),
    }
}

/// A positive number every evaluation needs. NaN, which leaves an optional number unset (the ROS
/// idiom), is refused here as not finite rather than reported as cleared.
fn required_positive(set: &mut ParameterSet, name: &str) -> Result<f64, ConfigError> {
    if let Some((Value::Number(n), source)) = set.values.get(name) {
        if n.as_f64().is_some_and(f64::is_nan) {
            return Err(ConfigError::new(
                source,
                format!("'{name}' must be a positive number, got NaN (not finite)"),
            ));
        }
    }
    required(name, positive(set, name)?)
}

fn finite(set: &mut ParameterSet, name: &str) -> Result<Option<f64>, ConfigError> {
    let source = set.values.get(name).map(|(_, s)| s.clone());
    match set.take_f64(name)? {
        Some(v) if !v.is_finite() => Err(ConfigError::new(
            &source.unwrap_or_default(),
            format!("'{name}' must be a finite number, got {v}"),
        )),
        other => Ok(other),
    }
}

fn bounded_count(
    set: &mut ParameterSet,
    name: &str,
    min: u64,
    max: u64,
) -> Result<Option<usize>, ConfigError> {
    let source = set.values.get(name).map(|(_, s)| s.clone());
    match set.take_u64(name)? {
        Some(v) if v < min || v > max => Err(ConfigError::new(
            &source.unwrap_or_default(),
            format!("'{name}' must be between {min} and {max}, got {v}"),
        )),
        other => Ok(other.map(|v| v as usize)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn builtin_defaults_are_the_papers_settings() {
        let s = Settings::builtin();
        assert_eq!(s.model, ModelKind::Quadrotor);
        assert_eq!((s.horizon, s.trajectories, s.steps), (1.0, 150, 100));
        assert_eq!(s.volume_dims, VolumeDims::Two);
        assert_eq!(s.robot_description, RobotSource::Builtin);
        assert_eq!(s.robot_radius, None);
    }

    #[test]
    fn the_shipped_config_file_loads_and_resolves_the_urdf_next_to_it() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/cstep.yaml");
        let s = Settings::load(Some(&path), DEFAULT_NODE_NAME, &[]).unwrap();
        let RobotSource::File(urdf) = &s.robot_description else {
            panic!()
        };
        assert!(urdf.exists(), "{}", urdf.display());
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
    fn evaluations_beyond_the_memory_budget_are_refused_naming_values_and_budget() {
        // Issue 12, failure 6: 100 000 × 10 000 validated, then the first evaluation asked for
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
        let err = Settings::load(None, DEFAULT_NODE_NAME, &overrides(100_000, 336, 2));
        assert!(err.unwrap_err().to_string().starts_with("command line: "));
        assert!(Settings::load(None, DEFAULT_NODE_NAME, &overrides(100_000, 223, 3)).is_ok());
        assert!(Settings::load(None, DEFAULT_NODE_NAME, &overrides(100_000, 224, 3)).is_err());
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
                "'sampler' must be one of fourier | chebyshev | bang_bang, got \"uniform\"",
            ),
            (
                "volume_dims: 4",
                "'volume_dims' must be one of 2 | 3, got \"4\"",
            ),
            ("horizn: 1.0", "unknown parameter 'horizn'"),
            // Issue 12, failure 9: NaN said "must be set (... a file or -p cleared it)", and a
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
