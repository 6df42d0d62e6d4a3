//! `cstep echo`: subscribe to one topic and print its messages as YAML documents, like
//! `ros2 topic echo`, on machines without the ROS command-line tools.
//!
//! The message type comes from `--type`, else from the topic's name for cstep's own outputs,
//! else from the publishers discovery finds on the topic. Only types cstep mirrors can be
//! decoded ([`EchoType`]); anything else is a one-line error naming the type and the ones
//! cstep knows. The DDS context is the node's ([`super::rcl::context`]): same `ROS_DOMAIN_ID`,
//! same localhost-only discovery.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use futures::StreamExt;
use ros2_client::dds::rustdds::policy::Reliability;
use ros2_client::dds::rustdds::Topic;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::QosProfile;
use ros2_client::{Context, Message, MessageTypeName, Name, Node, NodeName, NodeOptions};
use serde::Serialize;

use super::messages::yaml::{self, to_yaml};
use super::messages::{
    ros_type_of_dds, DiagnosticArray, EmpoweredReward, Empowerment, LaserScan, MarkerArray,
    Odometry, PointCloud2, PoseStamped, RosMessage, SpeedLimit,
};
use super::rcl::context::{context_from_env, resolve, ContextError};
use crate::excerpt::excerpt;

/// How long to look for a publisher when neither `--type` nor the topic's name tells the type
/// (discovery usually takes 1–2 s); `--timeout` shortens it.
pub const TYPE_DISCOVERY_WAIT: Duration = Duration::from_secs(5);

/// What to echo and for how long.
#[derive(Debug, Clone, PartialEq)]
pub struct EchoOptions {
    /// Topic name; a relative name is taken in the root namespace.
    pub topic: String,
    /// `pkg/msg/Name` (or `pkg/Name`), when the type cannot be told from the topic.
    pub type_name: Option<String>,
    /// Stop after this many messages (at least 1).
    pub count: Option<u64>,
    /// Give up after this long: an error unless `count` messages (or, without a count, at
    /// least one) arrived.
    pub timeout: Option<Duration>,
}

/// Why `cstep echo` could not print a topic: one line each, naming the topic or type.
#[derive(Debug, thiserror::Error)]
pub enum EchoError {
    /// `count` is 0.
    #[error("--count must be at least 1")]
    ZeroCount,
    /// The topic is not a valid ROS name.
    #[error("topic name \"{}\" is not a valid ROS name ({reason})", excerpt(topic))]
    TopicName {
        /// The topic, as given.
        topic: String,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::names::NameError,
    },
    /// `--type` names no type cstep can print.
    #[error(transparent)]
    Type(#[from] EchoTypeError),
    /// The DDS context could not be set up from the environment.
    #[error(transparent)]
    Context(#[from] ContextError),
    /// The echo node's name is not a valid ROS name.
    #[error("node name: {0}")]
    NodeName(#[source] ros2_client::names::NameError),
    /// ros2-client could not create the echo node.
    #[error("cannot create the echo node: {0}")]
    CreateNode(#[source] ros2_client::NodeCreateError),
    /// No `--type`, not one of cstep's topics, and no publisher found within `waited`.
    #[error(
        "cannot tell the type of {topic}: no publisher found within {:.0} s and it is not one of \
         cstep's topics; pass --type pkg/msg/Name (one of {})",
        waited.as_secs_f64(),
        EchoType::known_list()
    )]
    NoPublisher {
        /// The topic.
        topic: String,
        /// How long discovery was given.
        waited: Duration,
    },
    /// The topic's publishers publish a type cstep cannot print.
    #[error(
        "{topic} carries {type_name}, which cstep echo cannot decode (it knows {})",
        EchoType::known_list()
    )]
    Undecodable {
        /// The topic.
        topic: String,
        /// The publishers' type.
        type_name: String,
    },
    /// The topic's publishers publish different types, and `--type` did not choose.
    #[error("{topic} is published with several types ({}); pass --type", types.join(", "))]
    SeveralTypes {
        /// The topic.
        topic: String,
        /// The types.
        types: Vec<String>,
    },
    /// The DDS topic could not be created.
    #[error("topic {topic}: {reason}")]
    Topic {
        /// The topic.
        topic: String,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::CreateError,
    },
    /// The subscription could not be created.
    #[error("cannot subscribe to {topic}: {reason}")]
    Subscribe {
        /// The topic.
        topic: String,
        /// ros2-client's reason.
        #[source]
        reason: ros2_client::CreateError,
    },
    /// The Ctrl-C handler could not be installed (one is already, say).
    #[error("cannot install the Ctrl-C handler: {0}")]
    CtrlC(ctrlc::Error),
    /// The DDS spinner could not be started.
    #[error("cannot start the echo node's DDS event loop: {0}")]
    Spinner(#[source] ros2_client::CreateError),
    /// A received message could not be written as YAML.
    #[error("cannot print a message: {0}")]
    Print(yaml::Error),
    /// The topic's publishers publish other types than the one echoed (DDS would never match
    /// them).
    #[error("{topic} is published as {}, not {echoed}", published.join(", "))]
    WrongType {
        /// The topic.
        topic: String,
        /// The publishers' types.
        published: Vec<String>,
        /// The type echoed.
        echoed: String,
    },
    /// `timeout` passed before `count` messages arrived.
    #[error(
        "timed out after {} s: received {received} of {wanted} messages on {topic}",
        waited.as_secs_f64()
    )]
    TimedOut {
        /// The topic.
        topic: String,
        /// The timeout.
        waited: Duration,
        /// Messages printed.
        received: u64,
        /// Messages asked for.
        wanted: u64,
    },
    /// `timeout` passed without `count` and no message arrived.
    #[error(
        "no message on {topic} within {} s ({publishers} publisher(s) seen)",
        waited.as_secs_f64()
    )]
    NoMessage {
        /// The topic.
        topic: String,
        /// The timeout.
        waited: Duration,
        /// How many publishers discovery found on the topic.
        publishers: usize,
    },
}

/// Why a type name names no type `cstep echo` can print.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EchoTypeError {
    /// Not `pkg/msg/Name` or `pkg/Name`; the name as given.
    #[error("message type \"{}\" is not of the form pkg/msg/Name", excerpt(.0))]
    Form(String),
    /// A type cstep does not mirror; its `pkg/msg/Name`.
    #[error("cstep echo cannot decode {0}: it knows {known}", known = EchoType::known_list())]
    Unknown(String),
}

/// A message type cstep mirrors, and so can decode and print.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EchoType {
    /// `cstep_msgs/msg/Empowerment`.
    Empowerment,
    /// `cstep_msgs/msg/EmpoweredReward`.
    EmpoweredReward,
    /// `diagnostic_msgs/msg/DiagnosticArray`.
    DiagnosticArray,
    /// `visualization_msgs/msg/MarkerArray`.
    MarkerArray,
    /// `nav_msgs/msg/Odometry`.
    Odometry,
    /// `sensor_msgs/msg/LaserScan`.
    LaserScan,
    /// `geometry_msgs/msg/PoseStamped`.
    PoseStamped,
    /// `sensor_msgs/msg/PointCloud2` (its `data` printed byte by byte, as `ros2 topic echo`
    /// does).
    PointCloud2,
    /// `nav2_msgs/msg/SpeedLimit`.
    SpeedLimit,
}

impl EchoType {
    /// Every type `cstep echo` can print.
    pub const ALL: [EchoType; 9] = [
        EchoType::Empowerment,
        EchoType::EmpoweredReward,
        EchoType::DiagnosticArray,
        EchoType::MarkerArray,
        EchoType::Odometry,
        EchoType::LaserScan,
        EchoType::PoseStamped,
        EchoType::PointCloud2,
        EchoType::SpeedLimit,
    ];

    /// Package and type name.
    pub fn parts(self) -> (&'static str, &'static str) {
        match self {
            EchoType::Empowerment => parts::<Empowerment>(),
            EchoType::EmpoweredReward => parts::<EmpoweredReward>(),
            EchoType::DiagnosticArray => parts::<DiagnosticArray>(),
            EchoType::MarkerArray => parts::<MarkerArray>(),
            EchoType::Odometry => parts::<Odometry>(),
            EchoType::LaserScan => parts::<LaserScan>(),
            EchoType::PoseStamped => parts::<PoseStamped>(),
            EchoType::PointCloud2 => parts::<PointCloud2>(),
            EchoType::SpeedLimit => parts::<SpeedLimit>(),
        }
    }

    /// The ROS name, `pkg/msg/Name`.
    pub fn name(self) -> String {
        let (package, kind) = self.parts();
        format!("{package}/msg/{kind}")
    }

    /// The type of cstep's own output topics, known by their default names in any namespace
    /// (`/cstep/empowerment`, `/drone1/cstep/empowerment`, ...).
    pub fn of_cstep_topic(topic: &str) -> Option<Self> {
        if topic == "/diagnostics" {
            return Some(EchoType::DiagnosticArray);
        }
        let (namespace, name) = topic.rsplit_once("/cstep/")?;
        if !(namespace.is_empty() || namespace.starts_with('/')) {
            return None;
        }
        match name {
            "empowerment" => Some(EchoType::Empowerment),
            "reward" => Some(EchoType::EmpoweredReward),
            "markers" => Some(EchoType::MarkerArray),
            _ => None,
        }
    }

    /// The type named `pkg/msg/Name` or `pkg/Name`; an error lists the types cstep knows.
    pub fn parse(name: &str) -> Result<Self, EchoTypeError> {
        let canonical = match name.trim().split('/').collect::<Vec<_>>()[..] {
            [package, "msg", kind] | [package, kind] => format!("{package}/msg/{kind}"),
            _ => return Err(EchoTypeError::Form(name.to_owned())),
        };
        Self::ALL
            .into_iter()
            .find(|t| t.name() == canonical)
            .ok_or(EchoTypeError::Unknown(canonical))
    }

    fn known_list() -> String {
        Self::ALL.map(EchoType::name).join(", ")
    }

    fn type_name(self) -> MessageTypeName {
        let (package, kind) = self.parts();
        MessageTypeName::new(package, kind)
    }
}

/// The package and type name of message type `M`, as [`RosMessage`] defines them.
fn parts<M: RosMessage>() -> (&'static str, &'static str) {
    (M::PACKAGE, M::NAME)
}

/// What discovery knows of a topic's publishers.
struct Publishers {
    /// Their ROS type names, deduplicated.
    types: Vec<String>,
    /// How many there are, and how many of them are reliable.
    count: usize,
    reliable: usize,
}

fn publishers(context: &Context, topic: &str) -> Publishers {
    let dds_topic = format!("rt{topic}");
    let mut found = Publishers {
        types: Vec::new(),
        count: 0,
        reliable: 0,
    };
    for writer in context.domain_participant().discovered_writers() {
        let data = &writer.publication_topic_data;
        if data.topic_name != dds_topic {
            continue;
        }
        found.count += 1;
        if matches!(data.reliability, Some(Reliability::Reliable { .. })) {
            found.reliable += 1;
        }
        let name = ros_type_of_dds(&data.type_name).unwrap_or(data.type_name.clone());
        if !found.types.contains(&name) {
            found.types.push(name);
        }
    }
    found
}

/// Runs `cstep echo`: prints each message on the topic to `out` as a YAML document followed by
/// `---`, until `count` messages, the timeout, Ctrl-C, or a closed output.
pub fn echo(options: &EchoOptions, out: &mut dyn Write) -> Result<(), EchoError> {
    if options.count == Some(0) {
        return Err(EchoError::ZeroCount);
    }
    let topic = resolve("/", options.topic.trim());
    Name::parse(&topic).map_err(|reason| EchoError::TopicName {
        topic: options.topic.clone(),
        reason,
    })?;
    let given = options
        .type_name
        .as_deref()
        .map(EchoType::parse)
        .transpose()?;
    let started = Instant::now();

    let context = context_from_env(false)?;
    let node_name = format!("cstep_echo_{}", std::process::id());
    let mut node = context
        .new_node(
            NodeName::new("/", &node_name).map_err(EchoError::NodeName)?,
            NodeOptions::new().enable_rosout(false),
        )
        .map_err(EchoError::CreateNode)?;

    let kind = match given.or_else(|| EchoType::of_cstep_topic(&topic)) {
        Some(kind) => kind,
        None => discover_type(&context, &topic, options.timeout)?,
    };
    // Like `ros2 topic echo`: reliable when every publisher seen is, best effort (which matches
    // any publisher) when one is not; cstep's own outputs are reliable.
    let seen = publishers(&context, &topic);
    let reliable = if seen.count > 0 {
        seen.reliable == seen.count
    } else {
        EchoType::of_cstep_topic(&topic).is_some()
    };
    let qos = QosProfile::subscription_default()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 100 });
    let qos = if reliable {
        qos.reliability_reliable(WhenFull::Wait(Duration::from_millis(100)))
    } else {
        qos.reliability_best_effort()
    };
    let dds_topic = node
        .create_topic(
            &Name::parse(&topic).expect("checked"),
            kind.type_name(),
            &qos,
        )
        .map_err(|reason| EchoError::Topic {
            topic: topic.clone(),
            reason,
        })?;

    let run = Run {
        context: &context,
        topic: &topic,
        kind,
        options,
        deadline: options.timeout.map(|t| started + t),
    };
    match kind {
        EchoType::Empowerment => run.print::<Empowerment>(&mut node, &dds_topic, qos, out),
        EchoType::EmpoweredReward => run.print::<EmpoweredReward>(&mut node, &dds_topic, qos, out),
        EchoType::DiagnosticArray => run.print::<DiagnosticArray>(&mut node, &dds_topic, qos, out),
        EchoType::MarkerArray => run.print::<MarkerArray>(&mut node, &dds_topic, qos, out),
        EchoType::Odometry => run.print::<Odometry>(&mut node, &dds_topic, qos, out),
        EchoType::LaserScan => run.print::<LaserScan>(&mut node, &dds_topic, qos, out),
        EchoType::PoseStamped => run.print::<PoseStamped>(&mut node, &dds_topic, qos, out),
        EchoType::PointCloud2 => run.print::<PointCloud2>(&mut node, &dds_topic, qos, out),
        EchoType::SpeedLimit => run.print::<SpeedLimit>(&mut node, &dds_topic, qos, out),
    }
}

/// The type of `topic`'s publishers, once discovery finds one (within the discovery wait).
fn discover_type(
    context: &Context,
    topic: &str,
    timeout: Option<Duration>,
) -> Result<EchoType, EchoError> {
    let wait = timeout.map_or(TYPE_DISCOVERY_WAIT, |t| t.min(TYPE_DISCOVERY_WAIT));
    let deadline = Instant::now() + wait;
    loop {
        let seen = publishers(context, topic);
        match &seen.types[..] {
            [] if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(100)),
            [] => {
                return Err(EchoError::NoPublisher {
                    topic: topic.to_owned(),
                    waited: wait,
                })
            }
            [one] => {
                return EchoType::parse(one).map_err(|_| EchoError::Undecodable {
                    topic: topic.to_owned(),
                    type_name: one.clone(),
                })
            }
            several => {
                return Err(EchoError::SeveralTypes {
                    topic: topic.to_owned(),
                    types: several.to_vec(),
                })
            }
        }
    }
}

/// One echo run: where, what, until when.
struct Run<'a> {
    context: &'a Context,
    topic: &'a str,
    kind: EchoType,
    options: &'a EchoOptions,
    deadline: Option<Instant>,
}

impl Run<'_> {
    fn print<M: Message + Serialize + 'static>(
        &self,
        node: &mut Node,
        topic: &Topic,
        qos: QosProfile,
        out: &mut dyn Write,
    ) -> Result<(), EchoError> {
        let subscription = node
            .create_subscription::<M>(topic, Some(qos))
            .map_err(|reason| EchoError::Subscribe {
                topic: self.topic.to_owned(),
                reason,
            })?;
        let stop = Arc::new(AtomicBool::new(false));
        {
            let stop = stop.clone();
            ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst))
                .map_err(EchoError::CtrlC)?;
        }
        let executor = smol::LocalExecutor::new();
        executor
            .spawn(node.spinner().map_err(EchoError::Spinner)?.spin())
            .detach();

        let mut received: u64 = 0;
        let wanted = self.options.count;
        let ending: Result<Ending, EchoError> = smol::block_on(executor.run(async {
            let messages = subscription.async_stream();
            futures::pin_mut!(messages);
            let mut tick = smol::Timer::interval(Duration::from_millis(100));
            let mut next_type_check = Instant::now() + Duration::from_secs(1);
            loop {
                futures::select! {
                    received_message = messages.select_next_some() => match received_message {
                        Ok((message, _)) => {
                            if received == 0 {
                                // A mismatched --type may decode into nonsense: check first.
                                self.check_publisher_types()?;
                            }
                            let document = to_yaml(&message).map_err(EchoError::Print)?;
                            if out
                                .write_all(document.as_bytes())
                                .and_then(|()| out.write_all(b"---\n"))
                                .and_then(|()| out.flush())
                                .is_err()
                            {
                                return Ok(Ending::OutputClosed);
                            }
                            received += 1;
                            if wanted.is_some_and(|n| received >= n) {
                                return Ok(Ending::Done);
                            }
                        }
                        Err(e) => eprintln!(
                            "cstep echo: skipped a message on {} that is not a {}: {e}",
                            self.topic,
                            self.kind.name()
                        ),
                    },
                    _ = futures::FutureExt::fuse(tick.next()) => {
                        if stop.load(Ordering::SeqCst) {
                            return Ok(Ending::Interrupted);
                        }
                        if self.deadline.is_some_and(|d| Instant::now() >= d) {
                            return Ok(Ending::TimedOut);
                        }
                        if received == 0 && Instant::now() >= next_type_check {
                            next_type_check = Instant::now() + Duration::from_secs(1);
                            self.check_publisher_types()?;
                        }
                    }
                }
            }
        }));
        match ending? {
            Ending::TimedOut => {
                let waited = self.options.timeout.unwrap_or_default();
                match wanted {
                    Some(n) if received < n => Err(EchoError::TimedOut {
                        topic: self.topic.to_owned(),
                        waited,
                        received,
                        wanted: n,
                    }),
                    None if received == 0 => Err(EchoError::NoMessage {
                        topic: self.topic.to_owned(),
                        waited,
                        publishers: publishers(self.context, self.topic).count,
                    }),
                    _ => Ok(()),
                }
            }
            Ending::Done | Ending::Interrupted | Ending::OutputClosed => Ok(()),
        }
    }

    /// Fails when the topic has publishers and none of them publishes this run's type (DDS
    /// would never match them, and the echo would wait in silence).
    fn check_publisher_types(&self) -> Result<(), EchoError> {
        let seen = publishers(self.context, self.topic);
        let ours = self.kind.name();
        if !seen.types.is_empty() && !seen.types.contains(&ours) {
            return Err(EchoError::WrongType {
                topic: self.topic.to_owned(),
                published: seen.types,
                echoed: ours,
            });
        }
        Ok(())
    }
}

/// Why printing stopped.
enum Ending {
    Done,
    TimedOut,
    Interrupted,
    OutputClosed,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type_names_parse_in_both_spellings_and_unknown_ones_list_the_known() {
        assert_eq!(
            EchoType::parse("cstep_msgs/msg/Empowerment"),
            Ok(EchoType::Empowerment)
        );
        assert_eq!(EchoType::parse("nav_msgs/Odometry"), Ok(EchoType::Odometry));
        let err = EchoType::parse("std_msgs/msg/String")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("std_msgs/msg/String") && err.contains("sensor_msgs/msg/LaserScan"),
            "{err}"
        );
        assert_eq!(
            EchoType::parse("Odometry").unwrap_err().to_string(),
            "message type \"Odometry\" is not of the form pkg/msg/Name"
        );
        // A long argument is quoted by its start and length.
        assert_eq!(
            EchoType::parse(&"T".repeat(120_000))
                .unwrap_err()
                .to_string(),
            format!(
                "message type \"{}… (120000 characters)\" is not of the form pkg/msg/Name",
                "T".repeat(80)
            )
        );
    }

    #[test]
    fn every_type_round_trips_through_its_dds_name() {
        for kind in EchoType::ALL {
            let dds = kind.type_name().dds_msg_type();
            let ros = ros_type_of_dds(&dds).unwrap();
            assert_eq!(ros, kind.name());
            assert_eq!(EchoType::parse(&ros), Ok(kind));
        }
        assert_eq!(ros_type_of_dds("std_msgs::msg::String"), None);
    }

    #[test]
    fn cstep_topics_are_known_by_name() {
        assert_eq!(
            EchoType::of_cstep_topic("/cstep/markers"),
            Some(EchoType::MarkerArray)
        );
        assert_eq!(
            EchoType::of_cstep_topic("/diagnostics"),
            Some(EchoType::DiagnosticArray)
        );
        assert_eq!(EchoType::of_cstep_topic("/scan"), None);
        assert_eq!(
            EchoType::of_cstep_topic("/drone1/cstep/reward"),
            Some(EchoType::EmpoweredReward)
        );
        assert_eq!(EchoType::of_cstep_topic("drone1/cstep/reward"), None);
        assert_eq!(EchoType::of_cstep_topic("/cstep/evaluate"), None);
    }

    #[test]
    fn timeouts_read_in_seconds_as_they_always_did() {
        let topic = "/cstep/empowerment".to_owned();
        let timed_out = EchoError::TimedOut {
            topic: topic.clone(),
            waited: Duration::from_millis(1500),
            received: 1,
            wanted: 3,
        };
        assert_eq!(
            timed_out.to_string(),
            "timed out after 1.5 s: received 1 of 3 messages on /cstep/empowerment"
        );
        let silent = EchoError::NoMessage {
            topic: topic.clone(),
            waited: Duration::from_secs(3),
            publishers: 0,
        };
        assert_eq!(
            silent.to_string(),
            "no message on /cstep/empowerment within 3 s (0 publisher(s) seen)"
        );
        let unknown = EchoError::NoPublisher {
            topic,
            waited: TYPE_DISCOVERY_WAIT,
        };
        assert!(unknown
            .to_string()
            .contains("no publisher found within 5 s"));
    }
}
