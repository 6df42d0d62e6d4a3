//! The node's parameters: loading them at start-up, declaring them to ROS, and acting on the
//! live ones.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use ros2_client::NodeOptions;
use tracing::{debug, warn};

use super::shared::Shared;
use super::NodeError;
use crate::parameters::overrides::{ParamOverrides, ParamSource};
use crate::parameters::Value;
use crate::parameters::{validate, NodeSettings, ParameterSet, Parameters};
use crate::ros::rcl::args::RosArgs;

/// The node's parameters: the built-in defaults, then the `--config` files and `--ros-args`
/// overrides that apply to node `fqn` ([`crate::parameters::overrides`]), validated.
pub(super) fn load_parameters(
    config: &[PathBuf],
    ros_args: &RosArgs,
    fqn: &str,
) -> Result<(crate::parameters::Settings, NodeSettings, Parameters), NodeError> {
    let sources: Vec<ParamSource> = config
        .iter()
        .cloned()
        .map(ParamSource::File)
        .chain(ros_args.params.iter().cloned())
        .collect();
    let overrides = ParamOverrides::read(&sources)?;
    for warning in overrides.unmatched_files(fqn) {
        warn!("{warning}");
    }
    let mut set = ParameterSet::builtin();
    for o in overrides.for_node(fqn) {
        debug!(
            "parameter override {} = {} ({})",
            o.name,
            serde_json::to_string(&o.value).unwrap_or_default(),
            o.source
        );
        set.insert(&o.name, o.value, &o.source, o.base_dir.as_deref());
    }
    Ok(validate(set)?)
}

/// Declares every parameter ([`crate::ros::rcl::parameters`]); a `safety_coefficient` or
/// `input_timeout` change takes effect at the next scan. The others are read-only (they shape
/// the control sample, the model and the topics), but `use_sim_time`, which ros2-client keeps
/// itself ([`NodeClock`] reads it).
pub(super) fn parameter_options(shared: &Arc<Shared>, parameters: &Parameters) -> NodeOptions {
    let live = shared.clone();
    let options = NodeOptions::new().start_parameter_services(true);
    crate::ros::rcl::parameters::declare(options, parameters, move |p, value| {
        match (p.name, value) {
            ("safety_coefficient", Value::Double(c)) => {
                *live
                    .safety_coefficient
                    .lock()
                    .unwrap_or_else(|e| e.into_inner()) = *c;
            }
            ("input_timeout", Value::Double(t)) => {
                *live.timeout.lock().unwrap_or_else(|e| e.into_inner()) =
                    Duration::from_secs_f64(*t);
            }
            _ => {}
        }
    })
}
