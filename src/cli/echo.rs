//! `cstep echo`: print a topic's messages as YAML, like `ros2 topic echo`.

use std::time::Duration;

use cstep::ros::echo::{echo, EchoOptions};

use super::CliError;

/// Arguments of `cstep echo`.
#[derive(Debug, clap::Args)]
pub struct EchoArgs {
    /// Topic to print, e.g. /cstep/empowerment (a relative name is taken as /NAME).
    topic: String,
    /// Message type as pkg/msg/Name, for topics other than cstep's own
    /// (/cstep/empowerment, /cstep/reward, /cstep/markers, /diagnostics); found from the
    /// topic's publishers when left out.
    #[arg(long = "type", value_name = "PKG/msg/NAME")]
    type_name: Option<String>,
    /// Print one message and exit (the same as --count 1).
    #[arg(long, conflicts_with = "count")]
    once: bool,
    /// Print N messages and exit.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    count: Option<u64>,
    /// Give up after S seconds: exit 1 unless --count messages (or, without --count, at least
    /// one) were printed.
    #[arg(long, value_name = "S", value_parser = parse_seconds)]
    timeout: Option<Duration>,
}

/// `--timeout`'s value parser: a positive, finite number of seconds. Its error stays a String,
/// the usual clap value-parser error: clap prints the text inside its own line
/// (`invalid value '…' for '--timeout <S>': …`, exit 2) and nothing else reads it.
fn parse_seconds(text: &str) -> Result<Duration, String> {
    text.parse::<f64>()
        .ok()
        .filter(|s| s.is_finite() && *s > 0.0)
        .map(Duration::from_secs_f64)
        .ok_or_else(|| format!("expected a positive number of seconds, got \"{text}\""))
}

/// Runs `cstep echo` until the count, the timeout or Ctrl-C.
pub fn run(args: EchoArgs) -> Result<(), CliError> {
    let options = EchoOptions {
        topic: args.topic,
        type_name: args.type_name,
        count: if args.once { Some(1) } else { args.count },
        timeout: args.timeout,
    };
    Ok(echo(&options, &mut std::io::stdout().lock())?)
}
