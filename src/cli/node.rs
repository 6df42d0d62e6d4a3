//! `cstep node`: run the ROS 2 node.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use cstep::ros::args::RosArgs;

/// Arguments of `cstep node`.
#[derive(Debug, clap::Args)]
pub struct NodeArgs {
    /// Parameters file (ros__parameters YAML); the built-in defaults apply without one.
    #[arg(long)]
    config: Option<PathBuf>,
    /// ROS arguments: `--ros-args [--params-file F] [-p name:=value] [-r from:=to] [--]`.
    #[arg(
        trailing_var_arg = true,
        allow_hyphen_values = true,
        value_name = "ROS_ARGS"
    )]
    ros_args: Vec<String>,
}

/// Runs `cstep node` until Ctrl-C.
pub fn run(args: NodeArgs) -> Result<(), String> {
    if let Some(first) = args.ros_args.first() {
        if first != "--ros-args" {
            return Err(format!(
                "unexpected argument \"{first}\" (ROS arguments follow --ros-args)"
            ));
        }
    }
    let ros_args = RosArgs::parse(&args.ros_args)?;
    cstep::ros::node::run(args.config.as_slice(), &ros_args, stop_on_ctrl_c()?)
}

/// A flag that Ctrl-C (SIGINT) or SIGTERM sets, so the node can leave the DDS domain cleanly.
pub fn stop_on_ctrl_c() -> Result<Arc<AtomicBool>, String> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))
        .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))?;
    Ok(stop)
}
