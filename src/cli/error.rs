//! What a `cstep` subcommand can fail with: the typed errors of the layers below it, wrapped as
//! they are, and the command line's own. Each prints as the one line `main` writes after
//! `cstep: error: `, in the words the user has always read.

use cstep::model::urdf::UrdfError;
use cstep::parameters::ConfigError;
use cstep::ros::echo::EchoError;
use cstep::ros::node::NodeError;
use cstep::ros::rcl::args::ArgsError;

use super::demo::DemoError;
use super::eval::EvalError;

/// Why a subcommand failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// `cstep node`'s `--ros-args` cannot be read.
    #[error(transparent)]
    Args(#[from] ArgsError),
    /// The node could not start, or stopped on an error.
    #[error(transparent)]
    Node(#[from] NodeError),
    /// `cstep echo` could not print the topic.
    #[error(transparent)]
    Echo(#[from] EchoError),
    /// The parameters (`--config`, `-p`) do not validate.
    #[error(transparent)]
    Config(#[from] ConfigError),
    /// The robot description cannot be loaded.
    #[error(transparent)]
    Robot(#[from] UrdfError),
    /// `cstep demo`'s own failures: its arguments, its simulated drone, its plot.
    #[error(transparent)]
    Demo(#[from] DemoError),
    /// `cstep eval`'s own failures: its input files and `--goal`.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// The Ctrl-C (SIGINT, SIGTERM) handler could not be installed.
    #[error("cannot install the Ctrl-C handler: {0}")]
    CtrlC(ctrlc::Error),
    /// `--exit-with-parent`: the kernel refused the parent-death signal.
    #[cfg(target_os = "linux")]
    #[error("--exit-with-parent: prctl failed: {0}")]
    ParentDeathSignal(std::io::Error),
    /// `--exit-with-parent`: the parent ended before the request took effect.
    #[cfg(target_os = "linux")]
    #[error("--exit-with-parent: the parent process has already ended")]
    ParentGone,
    /// `--exit-with-parent` where there is no parent-death signal to follow the parent with.
    #[cfg(not(target_os = "linux"))]
    #[error("--exit-with-parent is supported on Linux only")]
    ExitWithParentUnsupported,
    /// `cstep bench` could not start its `--threads` worker threads.
    #[error("cannot start {threads} threads: {source}")]
    ThreadPool {
        /// The threads asked for.
        threads: usize,
        /// rayon's reason.
        source: rayon::ThreadPoolBuildError,
    },
    /// `--format json` output could not be written as JSON.
    #[error("{0}")]
    Json(serde_json::Error),
}
