//! `cstep node`: run the ROS 2 node.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use cstep::ros::rcl::args::RosArgs;

use super::CliError;

/// Arguments of `cstep node`.
#[derive(Debug, clap::Args)]
pub struct NodeArgs {
    /// Parameters file (ros__parameters YAML); the built-in defaults apply without one.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Stop when the process that started this one ends, however it ends (a crash or a kill
    /// included): for programs that start a private node, such as the Python bridge, so that
    /// none is left behind. Linux only.
    #[arg(long)]
    exit_with_parent: bool,
    /// ROS arguments, as rcl reads them: `--ros-args [--params-file F] [-p [node:]name:=value]
    /// [-r [node:]from:=to] [--log-level [logger:=]LEVEL] [-e ENCLAVE] [...] [--]`.
    #[arg(
        trailing_var_arg = true,
        allow_hyphen_values = true,
        value_name = "ROS_ARGS"
    )]
    ros_args: Vec<String>,
}

/// Runs `cstep node` until Ctrl-C.
pub fn run(args: NodeArgs) -> Result<(), CliError> {
    let ros_args = RosArgs::parse(&args.ros_args)?;
    let stop = stop_on_ctrl_c()?;
    if args.exit_with_parent {
        exit_with_parent()?;
    }
    Ok(cstep::ros::node::run(
        args.config.as_slice(),
        &ros_args,
        stop,
    )?)
}

/// Has the kernel send SIGTERM, which stops the node cleanly, when the parent process ends.
#[cfg(target_os = "linux")]
fn exit_with_parent() -> Result<(), CliError> {
    // SAFETY: getppid and prctl(PR_SET_PDEATHSIG, signal) take plain integers and touch no memory.
    let parent = unsafe { libc::getppid() };
    if unsafe { libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) } != 0 {
        return Err(CliError::ParentDeathSignal(std::io::Error::last_os_error()));
    }
    // A parent that ended before the request took effect sends nothing: it has been replaced.
    if unsafe { libc::getppid() } != parent {
        return Err(CliError::ParentGone);
    }
    Ok(())
}

/// Without the parent-death signal there is no reliable way to follow the parent.
#[cfg(not(target_os = "linux"))]
fn exit_with_parent() -> Result<(), CliError> {
    Err(CliError::ExitWithParentUnsupported)
}

/// A flag that Ctrl-C (SIGINT) or SIGTERM sets, so the node can leave the DDS domain cleanly.
pub fn stop_on_ctrl_c() -> Result<Arc<AtomicBool>, CliError> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)).map_err(CliError::CtrlC)?;
    Ok(stop)
}
