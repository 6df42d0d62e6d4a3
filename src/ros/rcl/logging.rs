//! The node's log, through `tracing`, as rcutils prints it, as rcl publishes it on `/rosout`,
//! and as `--ros-args` sets both.
//!
//! Console lines read `[INFO] [1733150000.123456789] [drone1.cstep_node]: message`, rcutils'
//! default format, on stderr (stdout with `RCUTILS_LOGGING_USE_STDOUT=1`). The node's logger is
//! named as rcl names a node's logger: the namespace with `.` for `/`, then the node name. Its
//! level is the `--log-level logger:=LEVEL` rule for it or its nearest ancestor (`drone1` covers
//! `drone1.cstep_node`), else `--log-level LEVEL`, else `info`, as rcutils resolves it; it
//! applies to the console and `/rosout` alike. `--disable-stdout-logs` silences the console,
//! `--disable-rosout-logs` the topic (both on by default, as in rcl). `/rosout` carries every
//! record (`rcl_interfaces/msg/Log`: wall-clock stamp, level, logger name, message, source file,
//! module, line) with rcl's QoS for it; unlike rcl, the records logged before the node existed
//! (start-up: parameter overrides, ignored arguments) are held and published when it does.
//! What cstep does not do — file logging (the external library: `--log-file-name`,
//! `--log-config-file`) — is said once at start-up rather than silently ignored.

use std::collections::VecDeque;
use std::fmt::{self, Write as _};
use std::sync::{Arc, Mutex};

use ros2_client::builtin_interfaces::Time;
use ros2_client::log::LogLevel as RosLevel;
use ros2_client::{NodeLoggingHandle, RosoutRaw};
use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::filter::{LevelFilter, Targets};
use tracing_subscriber::fmt::format::Writer;
use tracing_subscriber::fmt::writer::BoxMakeWriter;
use tracing_subscriber::fmt::{FmtContext, FormatEvent, FormatFields};
use tracing_subscriber::layer::{Context, Layer, SubscriberExt};
use tracing_subscriber::registry::LookupSpan;

use super::args::{LogLevel, RosArgs};

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

/// Where the log's `/rosout` records go: held from the start until [`Rosout::attach`] gives
/// the node's handle, then published in order (so the start-up's records — parameter overrides,
/// ignored arguments — reach `/rosout` too, with their own stamps), then each as it comes.
#[derive(Clone)]
pub struct Rosout {
    logger: String,
    sink: Arc<Mutex<Sink>>,
}

/// Records waiting for the node, or the node's handle.
enum Sink {
    Waiting(VecDeque<Record>),
    Attached(NodeLoggingHandle),
}

/// One `rcl_interfaces/msg/Log` record, but the logger name.
struct Record {
    stamp: Time,
    level: RosLevel,
    message: String,
    file: &'static str,
    module: &'static str,
    line: u32,
}

/// The most records held before the node exists: rcl's `/rosout` history depth.
const HELD: usize = 1000;

impl Rosout {
    fn new(logger: &str) -> Self {
        Rosout {
            logger: logger.to_owned(),
            sink: Arc::new(Mutex::new(Sink::Waiting(VecDeque::new()))),
        }
    }

    /// Publishes the held records through `handle` (a no-op when the node was created without
    /// a `/rosout` publisher), then every later one. The first handle stays.
    pub fn attach(&self, handle: NodeLoggingHandle) {
        let mut sink = self.sink.lock().unwrap_or_else(|e| e.into_inner());
        if let Sink::Waiting(held) = &mut *sink {
            for record in held.drain(..) {
                self.publish(&handle, record);
            }
            *sink = Sink::Attached(handle);
        }
    }

    fn take(&self, record: Record) {
        let mut sink = self.sink.lock().unwrap_or_else(|e| e.into_inner());
        match &mut *sink {
            Sink::Attached(handle) => self.publish(handle, record),
            Sink::Waiting(held) => {
                if held.len() == HELD {
                    held.pop_front();
                }
                held.push_back(record);
            }
        }
    }

    fn publish(&self, handle: &NodeLoggingHandle, r: Record) {
        handle.rosout_raw(
            r.stamp,
            r.level,
            &self.logger,
            &r.message,
            r.file,
            r.module,
            r.line,
        );
    }
}

/// Why the log could not be started.
#[derive(Debug, thiserror::Error)]
pub enum LoggingError {
    /// A log was already started in this process (`tracing` has one global subscriber).
    #[error("cannot start the log: {0}")]
    AlreadyStarted(tracing::subscriber::SetGlobalDefaultError),
}

/// Starts the log for the node's logger `logger` as `args` ask — the console unless
/// `--disable-stdout-logs`, `/rosout` (through the returned [`Rosout`], once attached) unless
/// `--disable-rosout-logs` — then says which logging arguments cstep cannot honour. Errors if a
/// log was already started in this process.
pub fn init(args: &RosArgs, logger: &str) -> Result<Rosout, LoggingError> {
    let writer = if std::env::var("RCUTILS_LOGGING_USE_STDOUT").as_deref() == Ok("1") {
        BoxMakeWriter::new(std::io::stdout)
    } else {
        BoxMakeWriter::new(std::io::stderr)
    };
    let console = (args.stdout_logs != Some(false)).then(|| {
        tracing_subscriber::fmt::layer()
            .event_format(RcutilsFormat {
                logger: logger.to_owned(),
            })
            .with_writer(writer)
    });
    let rosout = Rosout::new(logger);
    let topic = (args.rosout_logs != Some(false)).then(|| RosoutLayer(rosout.clone()));
    // Only cstep's own events: the libraries' `log` records (RustDDS, ros2-client) are not
    // forwarded, as rcl leaves the middleware's own logging out of the node's log.
    let subscriber = tracing_subscriber::registry()
        .with(console)
        .with(topic)
        .with(Targets::new().with_target("cstep", filter(level_of(args, logger))));
    tracing::subscriber::set_global_default(subscriber).map_err(LoggingError::AlreadyStarted)?;
    if let Some(file) = &args.log_config_file {
        tracing::warn!(
            "--log-config-file {} ignored: cstep logs to the console and /rosout only",
            file.display()
        );
    }
    if let Some(name) = &args.log_file_name {
        tracing::warn!("--log-file-name {name} ignored: cstep writes no log file");
    }
    if args.external_lib_logs == Some(true) {
        tracing::warn!("--enable-external-lib-logs ignored: cstep writes no log file");
    }
    Ok(rosout)
}

/// Publishes each record on `/rosout` as rcl does: wall-clock stamp, level, logger name,
/// message (with the event's other fields as ` key=value`), source file, module and line.
struct RosoutLayer(Rosout);

impl<S: Subscriber> Layer<S> for RosoutLayer {
    fn on_event(&self, event: &Event<'_>, _: Context<'_, S>) {
        let mut text = MessageText::default();
        event.record(&mut text);
        let meta = event.metadata();
        self.0.take(Record {
            stamp: Time::now(),
            level: match *meta.level() {
                Level::ERROR => RosLevel::Error,
                Level::WARN => RosLevel::Warn,
                Level::INFO => RosLevel::Info,
                Level::DEBUG | Level::TRACE => RosLevel::Debug,
            },
            message: text.0,
            file: meta.file().unwrap_or_default(),
            module: meta.module_path().unwrap_or_default(),
            line: meta.line().unwrap_or_default(),
        });
    }
}

/// An event's text: its `message`, then its other fields as ` key=value` (as the console
/// shows them).
#[derive(Default)]
struct MessageText(String);

impl Visit for MessageText {
    fn record_debug(&mut self, field: &Field, value: &dyn fmt::Debug) {
        if field.name() == "message" {
            let _ = write!(self.0, "{value:?}");
        } else {
            let _ = write!(self.0, " {}={value:?}", field.name());
        }
    }

    fn record_str(&mut self, field: &Field, value: &str) {
        if field.name() == "message" {
            self.0.push_str(value);
        } else {
            let _ = write!(self.0, " {}={value}", field.name());
        }
    }
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
        let now = crate::ros::messages::Time::wall_clock_now();
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
