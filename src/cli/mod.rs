//! Command-line interface: one file per subcommand.

mod bench;
mod demo;
mod echo;
mod error;
mod eval;
mod node;

pub use error::CliError;

use clap::{Parser, Subcommand};

/// C-STEP: continuous space-time empowerment, a physics-informed safety score for mobile robots.
#[derive(Debug, Parser)]
#[command(name = "cstep", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Evaluate C-STEP once, offline, for an odometry and a scan message given as JSON.
    Eval(eval::EvalArgs),
    /// The node and a simulated drone flying the paper's arena, over real DDS on localhost.
    Demo(demo::DemoArgs),
    /// Run the ROS 2 node: odometry and scans in, empowerment and rewards out.
    Node(node::NodeArgs),
    /// Print a topic's messages as YAML documents, like `ros2 topic echo`.
    Echo(echo::EchoArgs),
    /// Measure evaluation speed on a fixed scene (one core unless --threads says otherwise).
    Bench(bench::BenchArgs),
}

/// Runs a parsed command line; the error is one line for the user.
pub fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Eval(args) => eval::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Node(args) => node::run(args),
        Command::Demo(args) => demo::run(args),
        Command::Echo(args) => echo::run(args),
    }
}

/// Output formats shared by the subcommands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Human-readable text.
    Text,
    /// Machine-readable JSON.
    Json,
}
