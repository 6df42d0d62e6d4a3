//! The node's console log, through `tracing`, as rcutils prints it and as `--ros-args` sets it.
//!
//! Lines read `[INFO] [1733150000.123456789] [drone1.cstep_node]: message`, rcutils' default
//! format, on stderr (stdout with `RCUTILS_LOGGING_USE_STDOUT=1`). The node's logger is named as
//! rcl names a node's logger: the namespace with `.` for `/`, then the node name. Its level is
//! the `--log-level logger:=LEVEL` rule for it or its nearest ancestor (`drone1` covers
//! `drone1.cstep_node`), else `--log-level LEVEL`, else `info`, as rcutils resolves it.
//! `--disable-stdout-logs` silences the console. What cstep does not do — file logging (the
//! external library: `--log-file-name`, `--log-config-file`) and `/rosout` — is said once at
//! start-up rather than silently ignored.

use std::fmt;

use tracing::{Event, Level, Subscriber};
use tracing_subscriber::filter::{LevelFilter, Targets};
use tracing_subscriber::fmt::format::Writer;
use tracing_subscriber::fmt::writer::BoxMakeWriter;
use tracing_subscriber::fmt::{FmtContext, FormatEvent, FormatFields};
use tracing_subscriber::layer::SubscriberExt;
use tracing_subscriber::registry::LookupSpan;

use super::args::{LogLevel, RosArgs};
use super::messages::Time;

/// rcl's logger name for node `node` in `namespace`: `drone1.cstep_node`, or `cstep_node` in the
/// root namespace.
pub fn logger_name(namespace: &str, node: &str) -> String {
    let ns = namespace.trim_matches('/');
    if ns.is_empty() {
        node.to_owned()
    } else {
        format!("{}.{node}", ns.replace('/', "."))
    }
}

/// The level logger `logger` logs at: the nearest rule for it or an ancestor (a later rule for
/// the same name wins; `unset` defers to the parent), else the default level, else `info`.
pub fn level_of(args: &RosArgs, logger: &str) -> LogLevel {
    let mut name = logger;
    loop {
        let rule = args
            .logger_levels
            .iter()
            .rev()
            .find(|(n, level)| n == name && *level != LogLevel::Unset);
        if let Some((_, level)) = rule {
            return *level;
        }
        match name.rsplit_once('.') {
            Some((parent, _)) => name = parent,
            None => break,
        }
    }
    match args.log_level {
        Some(level) if level != LogLevel::Unset => level,
        _ => LogLevel::Info,
    }
}

/// The `tracing` filter for a level: `fatal` shows nothing the node logs (it logs no fatal
/// events), `unset` is `info`.
fn filter(level: LogLevel) -> LevelFilter {
    match level {
        LogLevel::Debug => LevelFilter::DEBUG,
        LogLevel::Unset | LogLevel::Info => LevelFilter::INFO,
        LogLevel::Warn => LevelFilter::WARN,
        LogLevel::Error => LevelFilter::ERROR,
        LogLevel::Fatal => LevelFilter::OFF,
    }
}

/// Starts the console log for the node's logger `logger` as `args` ask, then says which
/// logging arguments cstep cannot honour. Errors if a log was already started in this process.
pub fn init(args: &RosArgs, logger: &str) -> Result<(), String> {
    if args.stdout_logs == Some(false) {
        return Ok(());
    }
    let writer = if std::env::var("RCUTILS_LOGGING_USE_STDOUT").as_deref() == Ok("1") {
        BoxMakeWriter::new(std::io::stdout)
    } else {
        BoxMakeWriter::new(std::io::stderr)
    };
    // Only cstep's own events: the libraries' `log` records (RustDDS, ros2-client) are not
    // forwarded, as rcl leaves the middleware's own logging out of the node's console.
    let subscriber = tracing_subscriber::fmt()
        .event_format(RcutilsFormat {
            logger: logger.to_owned(),
        })
        .with_writer(writer)
        // The builder's own default ceiling is INFO; the level is the Targets filter's to set.
        .with_max_level(LevelFilter::TRACE)
        .finish()
        .with(Targets::new().with_target("cstep", filter(level_of(args, logger))));
    tracing::subscriber::set_global_default(subscriber)
        .map_err(|e| format!("cannot start the log: {e}"))?;
    if let Some(file) = &args.log_config_file {
        tracing::warn!(
            "--log-config-file {} ignored: cstep logs to the console only",
            file.display()
        );
    }
    if let Some(name) = &args.log_file_name {
        tracing::warn!("--log-file-name {name} ignored: cstep writes no log file");
    }
    if args.external_lib_logs == Some(true) {
        tracing::warn!("--enable-external-lib-logs ignored: cstep writes no log file");
    }
    if args.rosout_logs == Some(true) {
        tracing::warn!("--enable-rosout-logs ignored: cstep does not publish /rosout");
    }
    Ok(())
}

/// rcutils' default console format: `[SEVERITY] [seconds.nanoseconds] [logger]: message`.
struct RcutilsFormat {
    logger: String,
}

impl<S, N> FormatEvent<S, N> for RcutilsFormat
where
    S: Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &FmtContext<'_, S, N>,
        mut writer: Writer<'_>,
        event: &Event<'_>,
    ) -> fmt::Result {
        let severity = match *event.metadata().level() {
            Level::ERROR => "ERROR",
            Level::WARN => "WARN",
            Level::INFO => "INFO",
            Level::DEBUG | Level::TRACE => "DEBUG",
        };
        let now = Time::wall_clock_now();
        write!(
            writer,
            "[{severity}] [{}.{:09}] [{}]: ",
            now.sec, now.nanosec, self.logger
        )?;
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn args(line: &str) -> RosArgs {
        RosArgs::parse(
            &line
                .split_whitespace()
                .map(String::from)
                .collect::<Vec<_>>(),
        )
        .unwrap()
    }

    #[test]
    fn logger_names_follow_rcl() {
        assert_eq!(logger_name("/", "cstep_node"), "cstep_node");
        assert_eq!(logger_name("/drone1", "cstep_node"), "drone1.cstep_node");
        assert_eq!(logger_name("/a/b", "n"), "a.b.n");
    }

    #[test]
    fn the_nearest_rule_then_the_default_then_info_sets_the_level() {
        assert_eq!(level_of(&args("--ros-args"), "cstep_node"), LogLevel::Info);
        let a = args("--ros-args --log-level warn");
        assert_eq!(level_of(&a, "cstep_node"), LogLevel::Warn);
        let a = args("--ros-args --log-level warn --log-level cstep_node:=debug");
        assert_eq!(level_of(&a, "cstep_node"), LogLevel::Debug);
        // A rule for the bare node name does not reach the node in a namespace (rcutils).
        assert_eq!(level_of(&a, "drone1.cstep_node"), LogLevel::Warn);
        let a = args(
            "--ros-args --log-level drone1:=error --log-level drone1.cstep_node:=unset \
             --log-level other:=debug",
        );
        assert_eq!(level_of(&a, "drone1.cstep_node"), LogLevel::Error);
        let a = args("--ros-args --log-level x:=debug --log-level x:=fatal");
        assert_eq!(level_of(&a, "x"), LogLevel::Fatal);
        assert_eq!(filter(LogLevel::Fatal), LevelFilter::OFF);
    }
}
