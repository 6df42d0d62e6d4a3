//! The ROS 2 node: odometry and scans in, C-STEP scores and rewards out, over ros2-client.
//!
//! One evaluation per scan, from the newest odometry, stamped with the scan's stamp. Scans
//! arrive on the DDS thread and go into a one-slot mailbox; a worker thread scores whatever is
//! newest, so a slow evaluation never builds a queue — a scan replaced before it was scored is
//! counted as skipped. The `/cstep/evaluate` service scores a given state synchronously with the
//! configured seed, so identical requests get identical answers. Diagnostics report input ages,
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
use nalgebra::Vector3;
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{
    MessageTypeName, Name, Node, NodeName, NodeOptions, ParameterValue, Publisher, QosProfile,
    ServiceMapping, ServiceTypeName,
};

use super::args::RosArgs;
use super::context::{context_from_env, resolve};
use super::convert::{
    empowerment_message, goal_position, laser_scan_to_scan, odometry_to_state, reward_message,
};
use super::markers::rollout_markers;
use super::messages::{
    DiagnosticArray, DiagnosticStatus, EmpoweredReward, Empowerment, EvaluateRequest,
    EvaluateResponse, Header, KeyValue, LaserScan, MarkerArray, Odometry, PoseStamped, Time,
};
use super::stamps::{Order, StampOrder};
use crate::config::{load_all, NodeSettings, DEFAULT_NODE_NAME};
use crate::estimator::Estimator;
use crate::reward::{empowered_reward, task_reward};

/// Runs the node until `stop` is set: loads the parameters files and `--ros-args`, joins the
/// DDS domain `ROS_DOMAIN_ID` as far as `ROS_AUTOMATIC_DISCOVERY_RANGE` reaches
/// ([`super::context`]), and serves.
pub fn run(config: &[PathBuf], ros_args: &RosArgs, stop: Arc<AtomicBool>) -> Result<(), String> {
    let node_name = ros_args.node_name.as_deref().unwrap_or(DEFAULT_NODE_NAME);
    let paths: Vec<&std::path::Path> = config
        .iter()
        .chain(&ros_args.params_files)
        .map(PathBuf::as_path)
        .collect();
    let (settings, interface) =
        load_all(&paths, node_name, &ros_args.params).map_err(|e| e.to_string())?;
    let estimator = Estimator::from_settings(&settings).map_err(|e| e.to_string())?;
    let shared = Arc::new(Shared {
        estimator,
        safety_coefficient: Mutex::new(settings.safety_coefficient),
        timeout: Duration::from_secs_f64(interface.input_timeout),
        time_jump_tolerance: interface.time_jump_tolerance,
        latest: Mutex::default(),
        mailbox: Mutex::new(None),
        arrived: Condvar::new(),
        stopping: stop,
    });

    let context = context_from_env(true)?;
    let namespace = ros_args.namespace.as_deref().unwrap_or("/");
    let options = parameter_options(&shared, &settings);
    let mut node = context
        .new_node(
            NodeName::new(namespace, node_name).map_err(|e| format!("node name: {e:?}"))?,
            options,
        )
        .map_err(|e| format!("cannot create the node: {e:?}"))?;
    let ports = Ports::open(&mut node, &interface, ros_args, namespace)?;
    eprintln!(
        "cstep node {} on ROS_DOMAIN_ID {}: {} + {} -> {}, {} (markers on {} while subscribed); \
         service {}",
        node.fully_qualified_name(),
        context.domain_id(),
        ros_args.remap(&interface.odom_topic),
        ros_args.remap(&interface.scan_topic),
        ros_args.remap(&interface.empowerment_topic),
        ros_args.remap(&interface.reward_topic),
        ros_args.remap(&interface.markers_topic),
        ros_args.remap(&interface.evaluate_service),
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
    smol::block_on(executor.run(serve(&shared, &ports, &node)));
    shared.arrived.notify_all();
    worker
        .join()
        .map_err(|_| "the scoring thread failed".to_owned())?;
    eprintln!("cstep node stopped");
    Ok(())
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
    goal: Option<Vector3<f64>>,
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
}

/// The node's topics and service.
struct Ports {
    odom: ros2_client::Subscription<Odometry>,
    scan: ros2_client::Subscription<LaserScan>,
    goal: ros2_client::Subscription<PoseStamped>,
    empowerment: Arc<Publisher<Empowerment>>,
    reward: Arc<Publisher<EmpoweredReward>>,
    markers: Arc<Publisher<MarkerArray>>,
    diagnostics: Publisher<DiagnosticArray>,
    evaluate: ros2_client::Server<EvaluateRequest, EvaluateResponse>,
}

impl Ports {
    fn open(
        node: &mut Node,
        interface: &NodeSettings,
        args: &RosArgs,
        namespace: &str,
    ) -> Result<Self, String> {
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
            let name = resolve(namespace, args.remap(name));
            let parsed = Name::parse(&name).map_err(|e| format!("topic name \"{name}\": {e:?}"))?;
            node.create_topic(&parsed, MessageTypeName::new(package, kind), qos)
                .map_err(|e| format!("topic {name}: {e:?}"))
        };
        let odom_topic = topic(&interface.odom_topic, "nav_msgs", "Odometry", &sensor)?;
        let scan_topic = topic(&interface.scan_topic, "sensor_msgs", "LaserScan", &sensor)?;
        let goal_topic = topic(
            &interface.goal_topic,
            "geometry_msgs",
            "PoseStamped",
            &reliable,
        )?;
        let empowerment_topic = topic(
            &interface.empowerment_topic,
            "cstep_msgs",
            "Empowerment",
            &reliable,
        )?;
        let reward_topic = topic(
            &interface.reward_topic,
            "cstep_msgs",
            "EmpoweredReward",
            &reliable,
        )?;
        let markers_topic = topic(
            &interface.markers_topic,
            "visualization_msgs",
            "MarkerArray",
            &reliable,
        )?;
        let diagnostics_topic = topic(
            "/diagnostics",
            "diagnostic_msgs",
            "DiagnosticArray",
            &reliable,
        )?;
        let service_name = resolve(namespace, args.remap(&interface.evaluate_service));
        Ok(Self {
            odom: node
                .create_subscription(&odom_topic, Some(sensor.clone()))
                .map_err(failed("the odometry subscription"))?,
            scan: node
                .create_subscription(&scan_topic, Some(sensor.clone()))
                .map_err(failed("the scan subscription"))?,
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
                    &Name::parse(&service_name)
                        .map_err(|e| format!("service name \"{service_name}\": {e:?}"))?,
                    &ServiceTypeName::new("cstep_msgs", "Evaluate"),
                    reliable.clone(),
                    reliable,
                )
                .map_err(failed("the evaluate service"))?,
        })
    }
}

/// An error mapper for creating the named entity.
fn failed<E: std::fmt::Debug>(what: &'static str) -> impl FnOnce(E) -> String {
    move |e| format!("cannot create {what}: {e:?}")
}

/// Declares the live parameter: a `safety_coefficient` change takes effect at the next score.
/// The others are fixed for the node's life (they shape the control sample and the model).
fn parameter_options(shared: &Arc<Shared>, settings: &crate::config::Settings) -> NodeOptions {
    let live = shared.clone();
    NodeOptions::new()
        .enable_rosout(false)
        .start_parameter_services(true)
        .declare_parameter(
            "safety_coefficient",
            ParameterValue::Double(settings.safety_coefficient),
        )
        .parameter_validator(Box::new(|name, value| match (name, value) {
            ("safety_coefficient", ParameterValue::Double(c)) if c.is_finite() && *c > 0.0 => {
                Ok(())
            }
            ("safety_coefficient", other) => Err(format!(
                "safety_coefficient must be a positive double, got {other:?}"
            )),
            (other, _) => Err(format!("'{other}' cannot be changed while the node runs")),
        }))
        .parameter_set_action(Box::new(move |name, value| {
            if let ("safety_coefficient", ParameterValue::Double(c)) = (name, value) {
                *live
                    .safety_coefficient
                    .lock()
                    .unwrap_or_else(|e| e.into_inner()) = *c;
            }
            Ok(())
        }))
}

/// The DDS-side tasks: keep the newest odometry and goal, post scans, answer the service,
/// publish diagnostics; returns when Ctrl-C was pressed.
async fn serve(shared: &Arc<Shared>, ports: &Ports, node: &Node) {
    let odometry = ports.odom.async_stream().for_each(|received| async move {
        if let Ok((odom, _)) = received {
            shared.latest().odom = Some((odom, Instant::now()));
        }
    });
    let goals = ports.goal.async_stream().for_each(|received| async move {
        if let Ok((goal, _)) = received {
            match goal_position(&goal.pose.position) {
                Ok(goal) => shared.latest().goal = Some(goal),
                Err(e) => shared.note_problem(|l| l.rejected += 1, &format!("goal_pose: {e}")),
            }
        }
    });
    let scans = ports.scan.async_stream().for_each(|received| async move {
        if let Ok((scan, _)) = received {
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
        }
    });
    let service = ports
        .evaluate
        .receive_request_stream()
        .for_each(|received| async move {
            if let Ok((id, request)) = received {
                let response = shared.evaluate_request(&request);
                if let Err(e) = ports.evaluate.async_send_response(id, response).await {
                    shared.latest().last_problem = Some(format!("evaluate reply failed: {e:?}"));
                }
            }
        });
    let diagnostics = async {
        loop {
            smol::Timer::after(Duration::from_secs(1)).await;
            // Diagnostics are best effort: a full queue must not stop the node.
            let _ = ports.diagnostics.publish(shared.diagnostics());
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
        Box::pin(scans),
        Box::pin(service),
        Box::pin(diagnostics),
        Box::pin(stopped),
    ])
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
        match shared.score(&odom, &scan, goal, with_markers) {
            Ok((e, r, markers)) => {
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

impl Shared {
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

    fn note_problem(&self, count: impl FnOnce(&mut Latest), problem: &str) {
        let mut latest = self.latest();
        count(&mut latest);
        latest.last_problem = Some(problem.to_owned());
    }

    /// Scores one odometry and scan pair, with the markers of the evaluation if asked; a
    /// malformed input is an error naming the field.
    fn score(
        &self,
        odom: &Odometry,
        scan: &LaserScan,
        goal: Option<Vector3<f64>>,
        with_markers: bool,
    ) -> Result<(Empowerment, EmpoweredReward, Option<MarkerArray>), String> {
        let state = odometry_to_state(odom).map_err(|e| format!("odometry: {e}"))?;
        let scan_in = laser_scan_to_scan(scan).map_err(|e| format!("scan: {e}"))?;
        let estimate = self.estimator.evaluate(&state, &scan_in);
        let c = *self
            .safety_coefficient
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        let reward = empowered_reward(
            estimate.empowerment,
            c,
            task_reward(&state.position, goal.as_ref()),
        );
        let header = Header {
            stamp: scan.header.stamp,
            frame_id: odom.header.frame_id.clone(),
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

    /// Answers `/cstep/evaluate`; a malformed request gets `valid = false` and the reason.
    fn evaluate_request(&self, request: &EvaluateRequest) -> EvaluateResponse {
        let goal = request
            .has_goal
            .then(|| goal_position(&request.goal))
            .transpose()
            .map_err(|e| e.to_string());
        match goal.and_then(|goal| self.score(&request.odom, &request.scan, goal, false)) {
            Ok((empowerment, reward, _)) => EvaluateResponse {
                empowerment,
                reward,
            },
            Err(problem) => {
                self.note_problem(|l| l.rejected += 1, &problem);
                let c = *self
                    .safety_coefficient
                    .lock()
                    .unwrap_or_else(|e| e.into_inner());
                EvaluateResponse {
                    empowerment: Empowerment {
                        header: request.scan.header.clone(),
                        empowerment: crate::estimator::EMPOWERMENT_FLOOR,
                        safety_coefficient: c,
                        horizon: self.estimator.settings().horizon,
                        num_trajectories: self.estimator.settings().trajectories as u32,
                        valid: false,
                        status: problem,
                        ..Default::default()
                    },
                    reward: EmpoweredReward {
                        header: request.scan.header.clone(),
                        empowerment_term: c.ln() + crate::estimator::EMPOWERMENT_FLOOR,
                        safety_coefficient: c,
                        valid: false,
                        ..Default::default()
                    },
                }
            }
        }
    }

    /// The once-a-second health report.
    fn diagnostics(&self) -> DiagnosticArray {
        let mut latest = self.latest();
        let age = |t: Option<Instant>| t.map(|t| t.elapsed().as_secs_f64());
        let odom_age = age(latest.odom.as_ref().map(|(_, t)| *t));
        let scan_age = age(latest.last_scan);
        let fresh = |a: Option<f64>| a.is_some_and(|a| a <= self.timeout.as_secs_f64());
        let jump = latest.time_jump.take();
        let (level, message) = if !fresh(odom_age) || !fresh(scan_age) {
            let stale = "inputs stale: no score";
            (
                3,
                jump.map_or_else(|| stale.to_owned(), |jump| format!("{stale}; {jump}")),
            )
        } else if let Some(jump) = jump {
            (1, jump)
        } else if let Some(problem) = latest.last_problem.take() {
            (1, problem)
        } else if latest.last_scan_unwatched {
            (
                0,
                "no subscriber to the scores: scans not scored".to_owned(),
            )
        } else {
            (0, "scoring".to_owned())
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
            header: Header::default(),
            status: vec![DiagnosticStatus {
                level,
                name: "cstep: empowerment".into(),
                message,
                hardware_id: "cstep".into(),
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
