//! The ROS 2 node: odometry and scans in, C-STEP scores and rewards out, over ros2-client.
//!
//! One evaluation per scan, from the newest odometry, stamped with the scan's stamp. Scans
//! arrive on the DDS thread and go into a one-slot mailbox; a worker thread scores whatever is
//! newest, so a slow evaluation never builds a queue — a scan replaced before it was scored is
//! counted as skipped. The `/cstep/evaluate` service scores a given state synchronously with the
//! configured seed, so identical requests get identical answers; `/cstep/evaluate_batch` scores
//! K states in one call, in parallel, each exactly as `/cstep/evaluate` would, and scores a state
//! its caller reports in collision at the floor without rolling out. Diagnostics report input ages,
//! counts of skipped, stale and rejected inputs, and the last score, once a second.
//! Scans are scored only while someone subscribes to the scores (`/cstep/empowerment` or
//! `/cstep/reward`), as lazy ROS publishers do: a simulation that takes its rewards from the
//! service and publishes `/scan` for observers would otherwise pay for every evaluation twice.
//! Likewise `/cstep/markers` (the sampled endpoints and their hull, [`super::markers`]) is built
//! and published with a score only while a subscriber is matched. Both are decided per scan, as
//! it arrives, from the matches the DDS side has recorded.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use futures::StreamExt;
use rayon::prelude::*;
use ros2_client::dds::rustdds::RTPSEntity;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    Message, MessageTypeName, Name, Node, NodeName, NodeOptions, ParameterValue, Publisher,
    QosProfile, Server, ServiceMapping, ServiceTypeName,
};
use tracing::{debug, info, warn};

use super::args::{NameKind, RosArgs};
use super::context::context_from_env;
use super::convert::{
    empowerment_message, goal_position, laser_scan_to_scan, odometry_to_state, reward_message,
};
use super::logging;
use super::markers::rollout_markers;
use super::messages::{
    Clock, DiagnosticArray, DiagnosticStatus, EmpoweredReward, Empowerment, EvaluateBatchRequest,
    EvaluateBatchResponse, EvaluateRequest, EvaluateResponse, Header, KeyValue, LaserScan,
    MarkerArray, Odometry, Point, PoseStamped, Time,
};
use super::rivals::{self, Claims, Verdict};
use super::stamps::{Order, StampOrder};
use crate::config::{validate, NodeSettings, ParameterSet, Parameters, DEFAULT_NODE_NAME};
use crate::estimator::{robot_description, Estimator, EMPOWERMENT_FLOOR};
use crate::param_overrides::{ParamOverrides, ParamSource};
use crate::parameters::Value;
use crate::reward::{empowered_reward, floor_reward, task_reward};

/// Runs the node until `stop` is set: loads the parameters files and `--ros-args`, joins the
/// DDS domain `ROS_DOMAIN_ID` as far as `ROS_AUTOMATIC_DISCOVERY_RANGE` reaches
/// ([`super::context`]), and serves. An error if another node already answers under its names
/// on that domain ([`super::rivals`]): the node then stops within its first seconds.
pub fn run(config: &[PathBuf], ros_args: &RosArgs, stop: Arc<AtomicBool>) -> Result<(), String> {
    let node_name = ros_args.node_name(DEFAULT_NODE_NAME);
    let namespace = ros_args.namespace(&node_name);
    let rosout = logging::init(ros_args, &logging::logger_name(&namespace, &node_name))?;
    refuse_security(ros_args)?;
    let fqn = format!("{}/{node_name}", namespace.trim_end_matches('/'));
    let (settings, interface, parameters) = load_parameters(config, ros_args, &fqn)?;
    let estimator = Estimator::from_settings(&settings).map_err(|e| e.to_string())?;
    let status = StatusIdentity {
        // diagnostic_updater's convention: "<node's fully qualified name>: <task>".
        name: format!("{fqn}: empowerment"),
        hardware_id: robot_description(&settings)
            .map_err(|e| e.to_string())?
            .name,
    };
    let shared = Arc::new(Shared::new(
        estimator,
        settings.safety_coefficient,
        Duration::from_secs_f64(interface.input_timeout),
        interface.time_jump_tolerance,
        stop,
    ));

    let context = context_from_env(true)?;
    let options =
        parameter_options(&shared, &parameters).enable_rosout(ros_args.rosout_logs != Some(false));
    let mut node = context
        .new_node(
            NodeName::new(&namespace, &node_name).map_err(|e| format!("node name: {e:?}"))?,
            options,
        )
        .map_err(|e| format!("cannot create the node: {e:?}"))?;
    rosout.attach(node.logging_handle());
    let names = Names::resolve(&interface, ros_args, &node_name, &namespace)?;
    let ports = Ports::open(&mut node, &names)?;
    let guard = Guard {
        claims: Claims::new()
            .topic(&names.empowerment)
            .topic(&names.reward)
            .service(&names.evaluate)
            .service(&names.evaluate_batch),
        participant: context.domain_participant(),
        started: Instant::now(),
        node: node.fully_qualified_name(),
        domain: context.domain_id(),
    };
    info!(
        "cstep node {} on ROS_DOMAIN_ID {}: {} + {} -> {}, {} (markers on {} while subscribed); \
         services {}, {}",
        node.fully_qualified_name(),
        context.domain_id(),
        names.odom,
        names.scan,
        names.empowerment,
        names.reward,
        names.markers,
        names.evaluate,
        names.evaluate_batch,
    );

    let worker = {
        let shared = shared.clone();
        let outputs = Outputs {
            empowerment: ports.empowerment.clone(),
            reward: ports.reward.clone(),
            markers: ports.markers.clone(),
        };
        std::thread::spawn(move || score_scans(&shared, &outputs))
    };
    let executor = smol::LocalExecutor::new();
    executor
        .spawn(node.spinner().map_err(|e| format!("{e:?}"))?.spin())
        .detach();
    let clock = NodeClock::default();
    smol::block_on(executor.run(serve(&shared, &ports, &node, &guard, &status, &clock)));
    shared.stopping.store(true, Ordering::SeqCst);
    shared.arrived.notify_all();
    worker
        .join()
        .map_err(|_| "the scoring thread failed".to_owned())?;
    if let Some(refusal) = shared.latest().refusal.take() {
        return Err(refusal);
    }
    info!("cstep node stopped");
    Ok(())
}

/// Refuses `ROS_SECURITY_ENABLE=true`: RustDDS is built here without DDS Security, so the node
/// would run unencrypted where its user asked for security. Without it an enclave (`-e`) is
/// unused, as rcl leaves it unused, and the node says so.
fn refuse_security(ros_args: &RosArgs) -> Result<(), String> {
    if std::env::var("ROS_SECURITY_ENABLE").as_deref() == Ok("true") {
        return Err(
            "ROS_SECURITY_ENABLE=true, but cstep cannot run secured (its DDS, RustDDS, \
             is built without DDS Security); refusing to run unsecured"
                .into(),
        );
    }
    if let Some(enclave) = &ros_args.enclave {
        info!("enclave {enclave} unused: ROS_SECURITY_ENABLE is not true");
    }
    Ok(())
}

/// The node's parameters: the built-in defaults, then the `--config` files and `--ros-args`
/// overrides that apply to node `fqn` ([`crate::param_overrides`]), validated.
fn load_parameters(
    config: &[PathBuf],
    ros_args: &RosArgs,
    fqn: &str,
) -> Result<(crate::config::Settings, NodeSettings, Parameters), String> {
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
    validate(set).map_err(|e| e.to_string())
}

/// The node's topic and service names, fully qualified after namespace and remapping.
struct Names {
    odom: String,
    scan: String,
    goal: String,
    empowerment: String,
    reward: String,
    markers: String,
    diagnostics: String,
    clock: String,
    evaluate: String,
    evaluate_batch: String,
}

impl Names {
    /// Resolves the configured names for node `node` in `namespace` by rcl's rules
    /// ([`RosArgs::resolve`]).
    fn resolve(
        interface: &NodeSettings,
        args: &RosArgs,
        node: &str,
        namespace: &str,
    ) -> Result<Self, String> {
        let topic = |name: &str| args.resolve(name, NameKind::Topic, node, namespace);
        let service = |name: &str| args.resolve(name, NameKind::Service, node, namespace);
        Ok(Self {
            odom: topic(&interface.odom_topic)?,
            scan: topic(&interface.scan_topic)?,
            goal: topic(&interface.goal_topic)?,
            empowerment: topic(&interface.empowerment_topic)?,
            reward: topic(&interface.reward_topic)?,
            markers: topic(&interface.markers_topic)?,
            diagnostics: topic("/diagnostics")?,
            clock: topic("/clock")?,
            evaluate: service(&interface.evaluate_service)?,
            evaluate_batch: service(&interface.evaluate_batch_service)?,
        })
    }
}

/// Who the diagnostics status is about: its name and hardware.
struct StatusIdentity {
    /// `<fully qualified node name>: empowerment`.
    name: String,
    /// The robot, as its URDF names it.
    hardware_id: String,
}

/// The node's clock, for the diagnostics' stamps: the system clock, or while the node's
/// `use_sim_time` parameter is true the newest `/clock` (zero until one arrives, as in rclcpp).
/// `use_sim_time` is live, so the choice is made at each stamp from the node's parameter store,
/// the one place that sees its sets (ros2-client handles them itself and calls no set action for
/// it); the newest `/clock` is kept either way, so a switch to sim time stamps with it at once,
/// as rclcpp's time source does.
#[derive(Default)]
struct NodeClock {
    /// The newest `/clock` time.
    newest: Mutex<Time>,
}

impl NodeClock {
    /// Now, on the clock `node`'s `use_sim_time` asks for.
    fn now(&self, node: &Node) -> Time {
        if node.get_parameter("use_sim_time") == Some(ParameterValue::Boolean(true)) {
            return *self.newest.lock().unwrap_or_else(|e| e.into_inner());
        }
        Time::wall_clock_now()
    }

    /// Takes a `/clock` message.
    fn tick(&self, clock: &Clock) {
        *self.newest.lock().unwrap_or_else(|e| e.into_inner()) = clock.clock;
    }
}

/// Watches DDS discovery for another participant answering under this node's names
/// ([`super::rivals`]).
struct Guard {
    claims: Claims,
    participant: ros2_client::dds::rustdds::DomainParticipant,
    started: Instant,
    /// This node's fully qualified name and domain, for the messages.
    node: String,
    domain: u16,
}

impl Guard {
    /// The verdict on the writers discovery has reported so far.
    fn check(&self) -> Verdict {
        let own = format!("{:?}", self.participant.guid().prefix);
        let writers = self.participant.discovered_writers();
        let rivals = self.claims.rivals(
            writers.iter().map(|w| {
                (
                    w.publication_topic_data.topic_name.as_str(),
                    format!("{:?}", w.writer_proxy.remote_writer_guid.prefix),
                )
            }),
            &own,
        );
        rivals::verdict(&rivals, self.started.elapsed(), &self.node, self.domain)
    }
}

/// What the DDS side and the scoring thread share.
struct Shared {
    estimator: Estimator,
    safety_coefficient: Mutex<f64>,
    timeout: Duration,
    /// Seconds a scan stamp may lie behind the newest scored before it means time jumped back.
    time_jump_tolerance: f64,
    latest: Mutex<Latest>,
    /// The newest scan not yet scored.
    mailbox: Mutex<Option<PostedScan>>,
    arrived: Condvar,
    stopping: Arc<AtomicBool>,
}

/// A scan waiting to be scored.
struct PostedScan {
    scan: LaserScan,
    /// Whether `/cstep/markers` had a matched subscriber when the scan arrived.
    with_markers: bool,
}

/// Newest inputs and running counts, for scoring and diagnostics.
#[derive(Default)]
struct Latest {
    odom: Option<(Odometry, Instant)>,
    goal: Option<Point>,
    last_scan: Option<Instant>,
    last_score: Option<(f64, bool, Duration)>,
    scored: u64,
    skipped: u64,
    /// Scans that arrived while nobody subscribed to the scores, so were not scored.
    unwatched: u64,
    /// Whether the newest scan was one of those.
    last_scan_unwatched: bool,
    stale: u64,
    rejected: u64,
    markers_published: u64,
    last_problem: Option<String>,
    /// The newest scored scan's stamp: an older one arriving later is late, or time jumped back.
    order: StampOrder,
    /// Backward time jumps seen (each reset the ordering).
    time_jumps: u64,
    /// The newest time jump, until a diagnostics message has said so (once, whatever other
    /// problem or staleness comes with it).
    time_jump: Option<String>,
    /// Another participant answering under this node's names, found after the start-up window:
    /// the warning, while it lasts (diagnostics are ERROR meanwhile).
    rival: Option<String>,
    /// Another participant answering under this node's names, found at start: why the node
    /// stopped.
    refusal: Option<String>,
}

/// The node's topics and services.
struct Ports {
    odom: ros2_client::Subscription<Odometry>,
    scan: ros2_client::Subscription<LaserScan>,
    goal: ros2_client::Subscription<PoseStamped>,
    clock: ros2_client::Subscription<Clock>,
    empowerment: Arc<Publisher<Empowerment>>,
    reward: Arc<Publisher<EmpoweredReward>>,
    markers: Arc<Publisher<MarkerArray>>,
    diagnostics: Publisher<DiagnosticArray>,
    evaluate: Server<EvaluateRequest, EvaluateResponse>,
    evaluate_batch: Server<EvaluateBatchRequest, EvaluateBatchResponse>,
}

impl Ports {
    fn open(node: &mut Node, names: &Names) -> Result<Self, String> {
        let reliable = QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Wait(Duration::from_millis(10)))
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 10 });
        // REP 2003 sensor data: best effort, small queue; matches reliable publishers too.
        let sensor = QosProfile::subscription_default()
            .reliability_best_effort()
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth: 5 });
        let topic = |name: &str, package: &str, kind: &str, qos: &QosProfile| {
            let parsed = Name::parse(name).map_err(|e| format!("topic name \"{name}\": {e:?}"))?;
            node.create_topic(&parsed, MessageTypeName::new(package, kind), qos)
                .map_err(|e| format!("topic {name}: {e:?}"))
        };
        let odom_topic = topic(&names.odom, "nav_msgs", "Odometry", &sensor)?;
        let scan_topic = topic(&names.scan, "sensor_msgs", "LaserScan", &sensor)?;
        let goal_topic = topic(&names.goal, "geometry_msgs", "PoseStamped", &reliable)?;
        let clock_topic = topic(&names.clock, "rosgraph_msgs", "Clock", &sensor)?;
        let empowerment_topic = topic(&names.empowerment, "cstep_msgs", "Empowerment", &reliable)?;
        let reward_topic = topic(&names.reward, "cstep_msgs", "EmpoweredReward", &reliable)?;
        let markers_topic = topic(
            &names.markers,
            "visualization_msgs",
            "MarkerArray",
            &reliable,
        )?;
        let diagnostics_topic = topic(
            &names.diagnostics,
            "diagnostic_msgs",
            "DiagnosticArray",
            &reliable,
        )?;
        let service = |name: &str, kind: &str| {
            let parsed =
                Name::parse(name).map_err(|e| format!("service name \"{name}\": {e:?}"))?;
            Ok::<_, String>((parsed, ServiceTypeName::new("cstep_msgs", kind)))
        };
        let (evaluate_name, evaluate_type) = service(&names.evaluate, "Evaluate")?;
        let (batch_name, batch_type) = service(&names.evaluate_batch, "EvaluateBatch")?;
        Ok(Self {
            odom: node
                .create_subscription(&odom_topic, Some(sensor.clone()))
                .map_err(failed("the odometry subscription"))?,
            scan: node
                .create_subscription(&scan_topic, Some(sensor.clone()))
                .map_err(failed("the scan subscription"))?,
            clock: node
                .create_subscription(&clock_topic, Some(sensor.clone()))
                .map_err(failed("the /clock subscription"))?,
            goal: node
                .create_subscription(&goal_topic, Some(reliable.clone()))
                .map_err(failed("the goal subscription"))?,
            empowerment: Arc::new(
                node.create_publisher(&empowerment_topic, Some(reliable.clone()))
                    .map_err(failed("the empowerment publisher"))?,
            ),
            reward: Arc::new(
                node.create_publisher(&reward_topic, Some(reliable.clone()))
                    .map_err(failed("the reward publisher"))?,
            ),
            markers: Arc::new(
                node.create_publisher(&markers_topic, Some(reliable.clone()))
                    .map_err(failed("the markers publisher"))?,
            ),
            diagnostics: node
                .create_publisher(&diagnostics_topic, Some(reliable.clone()))
                .map_err(failed("the diagnostics publisher"))?,
            evaluate: node
                .create_server(
                    ServiceMapping::Enhanced,
                    &evaluate_name,
                    &evaluate_type,
                    reliable.clone(),
                    reliable.clone(),
                )
                .map_err(failed("the evaluate service"))?,
            evaluate_batch: node
                .create_server(
                    ServiceMapping::Enhanced,
                    &batch_name,
                    &batch_type,
                    reliable.clone(),
                    reliable,
                )
                .map_err(failed("the evaluate_batch service"))?,
        })
    }
}

/// An error mapper for creating the named entity.
fn failed<E: std::fmt::Debug>(what: &'static str) -> impl FnOnce(E) -> String {
    move |e| format!("cannot create {what}: {e:?}")
}

/// Declares every parameter ([`super::parameters`]); a `safety_coefficient` change takes effect
/// at the next score. The others are read-only (they shape the control sample, the model and
/// the topics), but `use_sim_time`, which ros2-client keeps itself ([`NodeClock`] reads it).
fn parameter_options(shared: &Arc<Shared>, parameters: &Parameters) -> NodeOptions {
    let live = shared.clone();
    let options = NodeOptions::new().start_parameter_services(true);
    super::parameters::declare(options, parameters, move |p, value| {
        if let ("safety_coefficient", Value::Double(c)) = (p.name, value) {
            *live
                .safety_coefficient
                .lock()
                .unwrap_or_else(|e| e.into_inner()) = *c;
        }
    })
}

/// The DDS-side tasks: keep the newest odometry and goal, post scans, answer the service,
/// publish diagnostics, watch for rivals ([`Guard`]); returns when Ctrl-C was pressed, or when a
/// rival found at start-up made the node refuse to run (the reason is in `Latest::refusal`).
async fn serve(
    shared: &Arc<Shared>,
    ports: &Ports,
    node: &Node,
    guard: &Guard,
    status: &StatusIdentity,
    clock: &NodeClock,
) {
    let odometry = ports.odom.async_stream().for_each(|received| async move {
        match received {
            Ok((odom, _)) => shared.latest().odom = Some((odom, Instant::now())),
            Err(e) => shared.undecodable("odometry", "message", &e),
        }
    });
    let clock_ticks = ports.clock.async_stream().for_each(|received| async move {
        match received {
            Ok((message, _)) => clock.tick(&message),
            Err(e) => shared.undecodable("/clock", "message", &e),
        }
    });
    let goals = ports.goal.async_stream().for_each(|received| async move {
        match received {
            Ok((goal, _)) => {
                let p = goal.pose.position;
                match goal_position(&p) {
                    Ok(_) => shared.latest().goal = Some(p),
                    Err(e) => shared.note_problem(|l| l.rejected += 1, &format!("goal_pose: {e}")),
                }
            }
            Err(e) => shared.undecodable("goal_pose", "message", &e),
        }
    });
    let scans = ports.scan.async_stream().for_each(|received| async move {
        let scan = match received {
            Ok((scan, _)) => scan,
            Err(e) => return shared.undecodable("scan", "message", &e),
        };
        // Matched readers of our writers, as the spinner records DDS matching.
        let scores_wanted = ports.empowerment.get_subscription_count(node) > 0
            || ports.reward.get_subscription_count(node) > 0;
        {
            let mut latest = shared.latest();
            latest.last_scan = Some(Instant::now());
            latest.last_scan_unwatched = !scores_wanted;
            if !scores_wanted {
                latest.unwatched += 1;
                return;
            }
        }
        let with_markers = ports.markers.get_subscription_count(node) > 0;
        let mut mailbox = shared.mailbox.lock().unwrap_or_else(|e| e.into_inner());
        if mailbox.replace(PostedScan { scan, with_markers }).is_some() {
            shared.latest().skipped += 1;
        }
        shared.arrived.notify_one();
    });
    let service = answer_requests(shared, &ports.evaluate, "evaluate", |request| {
        shared.evaluate_request(request)
    });
    let batch_service =
        answer_requests(shared, &ports.evaluate_batch, "evaluate_batch", |request| {
            shared.evaluate_batch(request)
        });
    let diagnostics = async {
        loop {
            smol::Timer::after(Duration::from_secs(1)).await;
            // Diagnostics are best effort: a full queue must not stop the node.
            let _ = ports
                .diagnostics
                .publish(shared.diagnostics(status, clock.now(node)));
        }
    };
    let rivals = async {
        loop {
            smol::Timer::after(rivals::CHECK_PERIOD).await;
            let verdict = guard.check();
            let mut latest = shared.latest();
            match verdict {
                Verdict::Alone => latest.rival = None,
                Verdict::Refuse(line) => {
                    latest.refusal = Some(line);
                    return;
                }
                Verdict::Warn(line) => {
                    if latest.rival.as_ref() != Some(&line) {
                        warn!("{line}");
                    }
                    latest.rival = Some(line);
                }
            }
        }
    };
    let stopped = async {
        while !shared.stopping.load(Ordering::SeqCst) {
            smol::Timer::after(Duration::from_millis(50)).await;
        }
    };
    futures::future::select_all([
        Box::pin(odometry) as std::pin::Pin<Box<dyn std::future::Future<Output = ()>>>,
        Box::pin(goals),
        Box::pin(clock_ticks),
        Box::pin(scans),
        Box::pin(service),
        Box::pin(batch_service),
        Box::pin(diagnostics),
        Box::pin(rivals),
        Box::pin(stopped),
    ])
    .await;
}

/// Answers each request `server` receives with `answer`, until the request stream ends; a reply
/// that cannot be sent is noted for diagnostics (`name` says which service's). A request that
/// cannot be decoded is counted as rejected like an undecodable topic message; it cannot be
/// answered, as ros2-client drops its request id with the payload.
async fn answer_requests<Req, Resp>(
    shared: &Shared,
    server: &Server<Req, Resp>,
    name: &str,
    answer: impl Fn(&Req) -> Resp,
) where
    Req: Message + Clone + 'static,
    Resp: Message + 'static,
{
    let answer = &answer;
    server
        .receive_request_stream()
        .for_each(|received| async move {
            match received {
                Ok((id, request)) => {
                    if let Err(e) = server.async_send_response(id, answer(&request)).await {
                        shared.latest().last_problem = Some(format!("{name} reply failed: {e:?}"));
                    }
                }
                Err(e) => shared.undecodable(name, "request", &e),
            }
        })
        .await;
}

/// What the scoring thread publishes to.
struct Outputs {
    empowerment: Arc<Publisher<Empowerment>>,
    reward: Arc<Publisher<EmpoweredReward>>,
    markers: Arc<Publisher<MarkerArray>>,
}

/// The scoring thread: waits for a scan, scores it against the newest odometry, publishes the
/// score, then the markers if someone subscribes to them.
fn score_scans(shared: &Shared, outputs: &Outputs) {
    loop {
        let PostedScan { scan, with_markers } = {
            let mut mailbox = shared.mailbox.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                if shared.stopping.load(Ordering::SeqCst) {
                    return;
                }
                if let Some(next) = mailbox.take() {
                    break next;
                }
                // Wakes for each scan, and at least every 100 ms to notice a stop.
                mailbox = shared
                    .arrived
                    .wait_timeout(mailbox, Duration::from_millis(100))
                    .unwrap_or_else(|e| e.into_inner())
                    .0;
            }
        };
        let Some((odom, seen)) = shared.latest().odom.clone() else {
            shared.note_problem(|l| l.stale += 1, "no odometry received yet");
            continue;
        };
        if seen.elapsed() > shared.timeout {
            shared.note_problem(|l| l.stale += 1, "odometry is stale");
            continue;
        }
        let stamp = scan.header.stamp;
        let order = shared
            .latest()
            .order
            .check(stamp, shared.time_jump_tolerance);
        if order == Order::Late {
            shared.note_problem(
                |l| l.rejected += 1,
                "scan stamp older than an earlier scan's",
            );
            continue;
        }
        let goal = shared.latest().goal;
        let query = Query {
            odom: &odom,
            scan: &scan,
            goal: goal.as_ref(),
            in_collision: false,
        };
        match shared.score(&query, shared.safety_coefficient(), with_markers) {
            Ok((e, r, markers)) => {
                debug!(
                    "scan {}.{:09}: empowerment {:.4} (valid: {}, {})",
                    stamp.sec, stamp.nanosec, e.empowerment, e.valid, e.status
                );
                shared.scored(stamp, order);
                // A full queue or a lost subscriber is not the node's failure; diagnostics show it.
                if outputs.empowerment.publish(e).is_err() || outputs.reward.publish(r).is_err() {
                    shared.note_problem(|_| {}, "publishing a score failed");
                }
                if let Some(markers) = markers {
                    if outputs.markers.publish(markers).is_ok() {
                        shared.latest().markers_published += 1;
                    } else {
                        shared.note_problem(|_| {}, "publishing markers failed");
                    }
                }
            }
            Err(problem) => shared.note_problem(|l| l.rejected += 1, &problem),
        }
    }
}

/// One state to score: a `/cstep/evaluate` request, one entry of a `/cstep/evaluate_batch`
/// request, or a scan with the newest odometry and goal.
struct Query<'a> {
    odom: &'a Odometry,
    scan: &'a LaserScan,
    /// Goal of the task reward; None for a task reward of 1.
    goal: Option<&'a Point>,
    /// The caller reports the robot in collision: scored at the floor without rolling out.
    in_collision: bool,
}

impl<'a> Query<'a> {
    /// The states of a batch request, or why its arrays cannot describe K states: `scan` must
    /// hold as many entries as `odom`, `goal` and `has_goal` none or as many (both alike), and
    /// `in_collision` none or as many.
    fn batch(request: &'a EvaluateBatchRequest) -> Result<Vec<Self>, String> {
        let k = request.odom.len();
        let optional = [
            ("goal", request.goal.len()),
            ("has_goal", request.has_goal.len()),
            ("in_collision", request.in_collision.len()),
        ];
        if request.scan.len() != k {
            return Err(format!(
                "request: {} scans for {k} odometries (one scan per state)",
                request.scan.len()
            ));
        }
        if let Some((name, n)) = optional.into_iter().find(|&(_, n)| n != 0 && n != k) {
            return Err(format!(
                "request: {name} has {n} entries for {k} states (0 or {k})"
            ));
        }
        if request.goal.len() != request.has_goal.len() {
            return Err(format!(
                "request: goal has {} entries and has_goal {} (both or neither)",
                request.goal.len(),
                request.has_goal.len()
            ));
        }
        Ok((0..k)
            .map(|i| Query {
                odom: &request.odom[i],
                scan: &request.scan[i],
                goal: (request.has_goal.get(i) == Some(&true)).then(|| &request.goal[i]),
                in_collision: request.in_collision.get(i) == Some(&true),
            })
            .collect())
    }
}

impl Shared {
    /// The shared state of a node scoring with `estimator`, safety coefficient `c` until a
    /// parameter change, odometry older than `timeout` counted stale, and a scan stamped more
    /// than `time_jump_tolerance` seconds before the newest scored taken for a jump back in time.
    fn new(
        estimator: Estimator,
        c: f64,
        timeout: Duration,
        time_jump_tolerance: f64,
        stopping: Arc<AtomicBool>,
    ) -> Self {
        Self {
            estimator,
            safety_coefficient: Mutex::new(c),
            timeout,
            time_jump_tolerance,
            latest: Mutex::default(),
            mailbox: Mutex::new(None),
            arrived: Condvar::new(),
            stopping,
        }
    }

    fn latest(&self) -> std::sync::MutexGuard<'_, Latest> {
        self.latest.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records a scan stamped `stamp` as scored; if its `order` says time jumped back, counts
    /// the jump and has the next diagnostics say so.
    fn scored(&self, stamp: Time, order: Order) {
        let mut latest = self.latest();
        latest.order.scored(stamp);
        if let Order::JumpedBack(by) = order {
            latest.time_jumps += 1;
            latest.time_jump = Some(format!(
                "time jumped back {by:.3} s (scan stamped {:.3} s): stamp ordering reset",
                stamp.seconds()
            ));
        }
    }

    /// The safety coefficient in effect now.
    fn safety_coefficient(&self) -> f64 {
        *self
            .safety_coefficient
            .lock()
            .unwrap_or_else(|e| e.into_inner())
    }

    /// Counts a `what` (a message, a request) that `input` could not decode (malformed CDR: a
    /// length past the end of the buffer, a truncated buffer) as rejected, and has the next
    /// diagnostics say so: it is dropped like any malformed input, not silently.
    fn undecodable(&self, input: &str, what: &str, error: &ros2_client::ReadError) {
        self.note_problem(
            |l| l.rejected += 1,
            &format!("{input}: undecodable {what} dropped: {error}"),
        );
    }

    fn note_problem(&self, count: impl FnOnce(&mut Latest), problem: &str) {
        let mut latest = self.latest();
        count(&mut latest);
        latest.last_problem = Some(problem.to_owned());
    }

    /// Scores one state with safety coefficient `c`, with the markers of the evaluation if
    /// asked; a malformed input is an error naming the field.
    fn score(
        &self,
        query: &Query,
        c: f64,
        with_markers: bool,
    ) -> Result<(Empowerment, EmpoweredReward, Option<MarkerArray>), String> {
        let state = odometry_to_state(query.odom).map_err(|e| format!("odometry: {e}"))?;
        let scan = laser_scan_to_scan(query.scan).map_err(|e| format!("scan: {e}"))?;
        let goal = query
            .goal
            .map(goal_position)
            .transpose()
            .map_err(|e| e.to_string())?;
        let estimate = if query.in_collision {
            self.estimator.known_collision()
        } else {
            self.estimator.evaluate(&state, &scan)
        };
        let reward = empowered_reward(
            estimate.empowerment,
            c,
            task_reward(&state.position, goal.as_ref()),
        );
        let header = Header {
            stamp: query.scan.header.stamp,
            frame_id: query.odom.header.frame_id.clone(),
        };
        {
            let mut latest = self.latest();
            latest.scored += 1;
            latest.last_score = Some((estimate.empowerment, estimate.valid(), estimate.elapsed));
        }
        let markers = with_markers.then(|| {
            rollout_markers(
                &header,
                &state.position,
                &estimate.rollout,
                self.timeout.as_secs_f64(),
            )
        });
        Ok((
            empowerment_message(header.clone(), &estimate, c),
            reward_message(header, &reward, c, estimate.valid()),
            markers,
        ))
    }

    /// The service answer for one state: its score, or for a malformed one the floor with
    /// `valid = false` and the reason (counted as rejected).
    fn answer(&self, query: &Query, c: f64) -> (Empowerment, EmpoweredReward) {
        match self.score(query, c, false) {
            Ok((empowerment, reward, _)) => (empowerment, reward),
            Err(problem) => {
                self.note_problem(|l| l.rejected += 1, &problem);
                self.rejected(query.scan.header.clone(), problem, c)
            }
        }
    }

    /// The answer for a state that could not be scored: the floor, `valid = false`, `problem`
    /// as the status, stamped with `header`; its reward is the lowest a collision can score
    /// ([`floor_reward`]), so malformed input never pays better than hitting a wall.
    fn rejected(&self, header: Header, problem: String, c: f64) -> (Empowerment, EmpoweredReward) {
        (
            Empowerment {
                header: header.clone(),
                empowerment: EMPOWERMENT_FLOOR,
                safety_coefficient: c,
                horizon: self.estimator.settings().horizon,
                num_trajectories: self.estimator.settings().trajectories as u32,
                valid: false,
                status: problem,
                ..Default::default()
            },
            reward_message(header, &floor_reward(c), c, false),
        )
    }

    /// Answers `/cstep/evaluate`; a malformed request gets `valid = false` and the reason.
    fn evaluate_request(&self, request: &EvaluateRequest) -> EvaluateResponse {
        let query = Query {
            odom: &request.odom,
            scan: &request.scan,
            goal: request.has_goal.then_some(&request.goal),
            in_collision: false,
        };
        let (empowerment, reward) = self.answer(&query, self.safety_coefficient());
        EvaluateResponse {
            empowerment,
            reward,
        }
    }

    /// Answers `/cstep/evaluate_batch`: each state exactly as [`Self::evaluate_request`] would
    /// answer it alone (one safety coefficient for the whole batch), the states scored in
    /// parallel on rayon's pool. When the request's arrays disagree in length, every state
    /// (as many as the longer of `odom` and `scan`) is answered `valid = false` with the reason.
    fn evaluate_batch(&self, request: &EvaluateBatchRequest) -> EvaluateBatchResponse {
        let c = self.safety_coefficient();
        let answers: Vec<_> = match Query::batch(request) {
            Ok(queries) => queries.par_iter().map(|q| self.answer(q, c)).collect(),
            Err(problem) => {
                self.note_problem(|l| l.rejected += 1, &problem);
                let states = request.odom.len().max(request.scan.len());
                (0..states)
                    .map(|i| {
                        let header = request.scan.get(i).map(|s| s.header.clone());
                        self.rejected(header.unwrap_or_default(), problem.clone(), c)
                    })
                    .collect()
            }
        };
        let (empowerment, reward) = answers.into_iter().unzip();
        EvaluateBatchResponse {
            empowerment,
            reward,
        }
    }

    /// The once-a-second health report.
    fn diagnostics(&self, status: &StatusIdentity, stamp: Time) -> DiagnosticArray {
        let mut latest = self.latest();
        let age = |t: Option<Instant>| t.map(|t| t.elapsed().as_secs_f64());
        let odom_age = age(latest.odom.as_ref().map(|(_, t)| *t));
        let scan_age = age(latest.last_scan);
        let fresh = |a: Option<f64>| a.is_some_and(|a| a <= self.timeout.as_secs_f64());
        let jump = latest.time_jump.take();
        let (level, message) = if let Some(rival) = &latest.rival {
            (
                DiagnosticStatus::ERROR,
                jump.map_or_else(|| rival.clone(), |jump| format!("{rival}; {jump}")),
            )
        } else if !fresh(odom_age) || !fresh(scan_age) {
            let stale = "inputs stale: no score";
            (
                DiagnosticStatus::STALE,
                jump.map_or_else(|| stale.to_owned(), |jump| format!("{stale}; {jump}")),
            )
        } else if let Some(jump) = jump {
            (DiagnosticStatus::WARN, jump)
        } else if let Some(problem) = latest.last_problem.take() {
            (DiagnosticStatus::WARN, problem)
        } else if latest.last_scan_unwatched {
            (
                DiagnosticStatus::OK,
                "no subscriber to the scores: scans not scored".to_owned(),
            )
        } else {
            (DiagnosticStatus::OK, "scoring".to_owned())
        };
        let show = |a: Option<f64>| a.map_or("never".to_owned(), |a| format!("{a:.3}"));
        let (score, valid, elapsed) =
            latest
                .last_score
                .unwrap_or((f64::NAN, false, Duration::ZERO));
        let values = [
            ("odometry_age_s", show(odom_age)),
            ("scan_age_s", show(scan_age)),
            (
                "last_empowerment",
                if score.is_finite() {
                    format!("{score:.4}")
                } else {
                    "none".into()
                },
            ),
            ("last_valid", valid.to_string()),
            (
                "evaluation_time_us",
                format!("{:.0}", elapsed.as_secs_f64() * 1e6),
            ),
            ("scans_scored", latest.scored.to_string()),
            ("scans_skipped", latest.skipped.to_string()),
            ("scans_unwatched", latest.unwatched.to_string()),
            ("scans_stale", latest.stale.to_string()),
            ("inputs_rejected", latest.rejected.to_string()),
            ("time_jumps", latest.time_jumps.to_string()),
            ("markers_published", latest.markers_published.to_string()),
        ];
        DiagnosticArray {
            header: Header {
                stamp,
                frame_id: String::new(),
            },
            status: vec![DiagnosticStatus {
                level,
                name: status.name.clone(),
                message,
                hardware_id: status.hardware_id.clone(),
                values: values
                    .into_iter()
                    .map(|(key, value)| KeyValue {
                        key: key.into(),
                        value,
                    })
                    .collect(),
            }],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Settings;
    use crate::ros::convert::scan_to_laser_scan;
    use crate::scene::{Lidar, Scene};
    use nalgebra::{UnitQuaternion, Vector2};

    fn shared(c: f64) -> Shared {
        let estimator = Estimator::from_settings(&Settings::builtin()).unwrap();
        Shared::new(estimator, c, Duration::from_secs(1), 1.0, Arc::default())
    }

    /// The robot at (x, y, 1) in a 2.5 m corridor flying along it at `speed`, and its scan.
    fn state(x: f64, y: f64, speed: f64) -> (Odometry, LaserScan) {
        let mut odom = Odometry::default();
        odom.header.frame_id = "odom".into();
        odom.pose.pose.position = Point { x, y, z: 1.0 };
        odom.twist.twist.linear.x = speed;
        let lidar = Lidar {
            beams: 180,
            range_min: 0.02,
            range_max: 3.0,
        };
        let scan = Scene::corridor(2.5, 20.0).scan(
            Vector2::new(x, y),
            &UnitQuaternion::identity(),
            &lidar,
        );
        let header = Header {
            stamp: Time {
                sec: (10.0 * x) as i32,
                nanosec: 7,
            },
            frame_id: "base_link".into(),
        };
        (odom, scan_to_laser_scan(&scan, header))
    }

    /// Four states, the second and fourth with goals.
    fn batch() -> EvaluateBatchRequest {
        let states: Vec<_> = [
            (0.0, 0.0, 0.0),
            (1.0, 0.8, 1.5),
            (2.0, -0.9, -1.0),
            (3.0, 0.2, 3.0),
        ]
        .iter()
        .map(|&(x, y, v)| state(x, y, v))
        .collect();
        EvaluateBatchRequest {
            odom: states.iter().map(|s| s.0.clone()).collect(),
            scan: states.iter().map(|s| s.1.clone()).collect(),
            goal: (0..4)
                .map(|i| Point {
                    x: 4.0 + i as f64,
                    y: 0.0,
                    z: 1.0,
                })
                .collect(),
            has_goal: vec![false, true, false, true],
            in_collision: vec![],
        }
    }

    /// Entry `i` of a batch as its own `/cstep/evaluate` request.
    fn single(batch: &EvaluateBatchRequest, i: usize) -> EvaluateRequest {
        EvaluateRequest {
            odom: batch.odom[i].clone(),
            scan: batch.scan[i].clone(),
            goal: batch.goal[i],
            has_goal: batch.has_goal[i],
        }
    }

    #[test]
    fn a_batch_answers_each_state_as_the_single_service_does() {
        let node = shared(0.7);
        let request = batch();
        let answer = node.evaluate_batch(&request);
        assert_eq!(answer.empowerment.len(), 4);
        for i in 0..4 {
            let alone = node.evaluate_request(&single(&request, i));
            assert_eq!(answer.empowerment[i], alone.empowerment, "state {i}");
            assert_eq!(answer.reward[i], alone.reward, "state {i}");
            assert!(alone.empowerment.valid, "{:?}", alone.empowerment);
        }
        let distinct: std::collections::HashSet<u64> = answer
            .empowerment
            .iter()
            .map(|e| e.empowerment.to_bits())
            .collect();
        assert_eq!(distinct.len(), 4, "the states differ, so do their scores");
    }

    #[test]
    fn a_state_reported_in_collision_scores_the_floor_without_rolling_out() {
        let c = 0.5;
        let node = shared(c);
        let mut request = batch();
        request.in_collision = vec![false, true, false, false];
        let answer = node.evaluate_batch(&request);
        let (e, r) = (&answer.empowerment[1], &answer.reward[1]);
        assert_eq!(e.empowerment, EMPOWERMENT_FLOOR);
        assert!(!e.valid && !r.valid);
        assert_eq!(e.status, "robot already in collision");
        assert_eq!((e.free_volume, e.num_colliding), (0.0, e.num_trajectories));
        let task = (-4.0_f64.hypot(0.8)).exp(); // goal (5, 0, 1), robot at (1, 0.8, 1)
        assert!((r.task_reward - task).abs() < 1e-12);
        assert_eq!(r.empowerment_term, c.ln() + EMPOWERMENT_FLOOR);
        assert_eq!(r.reward, r.task_reward * r.empowerment_term);
        // The other states are untouched by their neighbour's collision.
        let alone = node.evaluate_request(&single(&request, 2));
        assert_eq!(answer.empowerment[2], alone.empowerment);
    }

    #[test]
    fn a_malformed_entry_is_rejected_alone_and_never_nan() {
        let node = shared(1.0);
        let mut request = batch();
        request.scan[1].angle_increment = 0.0;
        request.odom[2].pose.pose.orientation.w = 0.0;
        request.goal[3].x = f64::NAN;
        let answer = node.evaluate_batch(&request);
        assert!(answer.empowerment[0].valid);
        for (i, field) in [
            (1, "scan: angle_increment"),
            (2, "odometry: pose.pose.orientation"),
            (3, "goal"),
        ] {
            let (e, r) = (&answer.empowerment[i], &answer.reward[i]);
            assert!(!e.valid && !r.valid, "state {i}");
            assert!(e.status.starts_with(field), "state {i}: {}", e.status);
            assert_eq!(e.header, request.scan[i].header);
            for v in [e.empowerment, r.reward, r.task_reward, r.empowerment_term] {
                assert!(v.is_finite(), "state {i}: {v}");
            }
        }
        assert_eq!(node.latest().rejected, 3);
    }

    #[test]
    fn a_malformed_request_never_scores_better_than_a_collision() {
        // Issue 12, failure 9: a malformed request answered reward 0.0, better than the
        // floor a robot touching a wall scores, so bad input paid.
        for c in [0.2, 1.0, 3.0, 5e4] {
            let node = shared(c);
            let mut request = batch();
            request.in_collision = vec![true, true, false, false];
            request.scan[2].angle_increment = 0.0;
            request.odom[3].pose.pose.position.x = f64::NAN;
            let answer = node.evaluate_batch(&request);
            let mut single = single(&request, 3);
            single.scan.range_max = -1.0;
            let alone = node.evaluate_request(&single).reward;
            let collisions = &answer.reward[..2];
            for (i, r) in answer.reward[2..].iter().chain([&alone]).enumerate() {
                assert!(!r.valid);
                for hit in collisions {
                    assert!(
                        r.reward <= hit.reward,
                        "c {c}, rejected {i}: {r:?} vs {hit:?}"
                    );
                }
                assert_eq!(r.reward, r.task_reward * r.empowerment_term, "{r:?}");
                assert_eq!(r.empowerment_term, c.ln() + EMPOWERMENT_FLOOR);
            }
        }
    }

    #[test]
    fn arrays_of_disagreeing_lengths_reject_every_state_with_the_reason() {
        let node = shared(1.0);
        type Spoil = fn(&mut EvaluateBatchRequest);
        let cases: [(Spoil, &str); 4] = [
            (|r| r.scan.truncate(3), "request: 3 scans for 4 odometries"),
            (
                |r| r.in_collision = vec![true],
                "request: in_collision has 1 entries for 4 states",
            ),
            (
                |r| r.goal.clear(),
                "request: goal has 0 entries and has_goal 4",
            ),
            (
                |r| r.has_goal.truncate(3),
                "request: has_goal has 3 entries for 4 states",
            ),
        ];
        for (spoil, status) in cases {
            let mut request = batch();
            spoil(&mut request);
            let answer = node.evaluate_batch(&request);
            assert_eq!(answer.empowerment.len(), 4, "{status}");
            assert_eq!(answer.reward.len(), 4, "{status}");
            for e in &answer.empowerment {
                assert!(!e.valid && e.status.starts_with(status), "{}", e.status);
                assert_eq!(e.empowerment, EMPOWERMENT_FLOOR);
            }
        }
        let empty = node.evaluate_batch(&EvaluateBatchRequest::default());
        assert!(empty.empowerment.is_empty() && empty.reward.is_empty());
    }
}
