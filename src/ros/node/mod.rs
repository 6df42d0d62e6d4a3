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
//! Likewise `/cstep/markers` (the sampled endpoints and their hull, `markers.rs`) is built
//! and published with a score only while a subscriber is matched. Both are decided per scan, as
//! it arrives, from the matches the DDS side has recorded.

mod clock;
mod diagnostics;
mod error;
mod guard;
mod markers;
mod parameters;
mod ports;
mod queue;
mod rivals;
mod scoring;
mod service;
mod shared;
mod speed_limit;
mod stamps;
mod tasks;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use ros2_client::NodeName;
use tracing::{info, warn};

use super::messages::{EmpoweredReward, Empowerment, Evaluate, EvaluateBatch};
use super::rcl::args::RosArgs;
use super::rcl::context::context_from_env;
use super::rcl::logging;
use crate::estimator::{robot_name, Estimator};
use crate::parameters::DEFAULT_NODE_NAME;

use clock::NodeClock;
use diagnostics::StatusIdentity;
pub use error::NodeError;
use guard::Guard;
use parameters::{load_parameters, parameter_options};
use ports::{Names, Ports};
use rivals::Claims;
use scoring::{score_scans, Outputs};
use shared::Shared;
use tasks::serve;

/// Runs the node until `stop` is set: loads the parameters files and `--ros-args`, joins the
/// DDS domain `ROS_DOMAIN_ID` as far as `ROS_AUTOMATIC_DISCOVERY_RANGE` reaches
/// ([`super::rcl::context`]), and serves. An error if another node already answers under its
/// names on that domain (`rivals.rs`): the node then stops within its first seconds.
pub fn run(config: &[PathBuf], ros_args: &RosArgs, stop: Arc<AtomicBool>) -> Result<(), NodeError> {
    let node_name = ros_args.node_name(DEFAULT_NODE_NAME);
    let namespace = ros_args.namespace(&node_name);
    let rosout = logging::init(ros_args, &logging::logger_name(&namespace, &node_name))?;
    refuse_security(ros_args)?;
    let fqn = format!("{}/{node_name}", namespace.trim_end_matches('/'));
    let (settings, interface, parameters) = load_parameters(config, ros_args, &fqn)?;
    // Before joining the domain: a name rcl would refuse, or two of the node's ports on one
    // name, stops it with nothing yet on the network.
    let names = Names::resolve(&interface, ros_args, &node_name, &namespace)?;
    let estimator = Estimator::from_settings(&settings)?;
    let status = StatusIdentity {
        // diagnostic_updater's convention: "<node's fully qualified name>: <task>".
        name: format!("{fqn}: empowerment"),
        hardware_id: robot_name(&settings)?,
    };
    // Ctrl-C or SIGTERM while the files were read: nothing to leave yet, so leave now.
    if stop.load(Ordering::SeqCst) {
        info!("cstep node stopped before joining the DDS domain");
        return Ok(());
    }
    let shared = Arc::new(
        Shared::new(
            estimator,
            settings.safety_coefficient,
            Duration::from_secs_f64(interface.input_timeout),
            interface.time_jump_tolerance,
            stop,
        )
        .with_request_limits(queue::Limits {
            per_client: interface.service_queue_per_client,
            total: interface.service_queue_total,
        }),
    );

    let context = context_from_env(true)?;
    let options =
        parameter_options(&shared, &parameters).enable_rosout(ros_args.rosout_logs != Some(false));
    let mut node = context
        .new_node(
            NodeName::new(&namespace, &node_name).map_err(NodeError::NodeName)?,
            options,
        )
        .map_err(NodeError::CreateNode)?;
    rosout.attach(node.logging_handle());
    let ports = Ports::open(&mut node, &names)?;
    let guard = Guard {
        claims: Claims::new()
            .topic::<Empowerment>(&names.empowerment)
            .topic::<EmpoweredReward>(&names.reward)
            .service::<Evaluate>(&names.evaluate)
            .service::<EvaluateBatch>(&names.evaluate_batch),
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
        names.cloud.as_ref().map_or(&names.scan, |(name, _)| name),
        names.empowerment,
        names.reward,
        names.markers,
        names.evaluate,
        names.evaluate_batch,
    );

    if let Some((name, output)) = &names.speed_limit {
        let m = output.mapping;
        info!(
            "speed limit on {name}: 100 % at empowerment >= {} nats, {} % at <= {} nats, at most \
             {} per second of scan time{}",
            m.full_speed_at,
            m.floor,
            m.full_speed_at - m.span,
            output.rate_hz,
            m.max_speed
                .map_or_else(String::new, |v| format!(", in m/s of {v} m/s")),
        );
    }
    let worker = {
        let shared = shared.clone();
        let outputs = Outputs {
            empowerment: ports.empowerment.clone(),
            reward: ports.reward.clone(),
            markers: ports.markers.clone(),
            speed_limit: ports.speed_limit.clone(),
        };
        std::thread::spawn(move || score_scans(&shared, &outputs))
    };
    // The services' answers go from their worker to the DDS side through this channel; every
    // one answers a request the queue holds, so its length is bounded by the queue's limits.
    let (reply_sender, reply_receiver) = smol::channel::unbounded();
    let service_worker = {
        let shared = shared.clone();
        let replies = reply_sender.clone();
        std::thread::spawn(move || service::answer_queued(&shared, &replies))
    };
    let executor = smol::LocalExecutor::new();
    executor
        .spawn(node.spinner().map_err(NodeError::Spinner)?.spin())
        .detach();
    let clock = NodeClock::default();
    smol::block_on(executor.run(serve(
        &shared,
        &ports,
        &node,
        &guard,
        &status,
        &clock,
        (&reply_sender, &reply_receiver),
    )));
    shared.stopping.store(true, Ordering::SeqCst);
    shared.arrived.notify_all();
    shared.requests.wake();
    drop(reply_receiver);
    worker.join().map_err(|_| NodeError::ScoringThread)?;
    service_worker
        .join()
        .map_err(|_| NodeError::ScoringThread)?;
    // The scoring thread has ended: no limit can follow the release.
    if let Some(limiter) = &ports.speed_limit {
        if let Err(problem) = limiter.release_at_stop(clock.now(&node)) {
            warn!("{problem}");
        }
    }
    if let Some(refusal) = shared.latest().refusal.take() {
        return Err(NodeError::Rival(refusal));
    }
    info!("cstep node stopped");
    Ok(())
}

/// Refuses `ROS_SECURITY_ENABLE=true`: RustDDS is built here without DDS Security, so the node
/// would run unencrypted where its user asked for security. Without it an enclave (`-e`) is
/// unused, as rcl leaves it unused, and the node says so.
fn refuse_security(ros_args: &RosArgs) -> Result<(), NodeError> {
    if std::env::var("ROS_SECURITY_ENABLE").as_deref() == Ok("true") {
        return Err(NodeError::SecurityRequested);
    }
    if let Some(enclave) = &ros_args.enclave {
        info!("enclave {enclave} unused: ROS_SECURITY_ENABLE is not true");
    }
    Ok(())
}
