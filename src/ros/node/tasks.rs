//! The node's DDS-side async tasks: taking inputs, answering the services, publishing
//! diagnostics and watching for rivals.

use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use futures::StreamExt;
use ros2_client::{Message, Node, Server};
use tracing::warn;

use super::clock::NodeClock;
use super::diagnostics::StatusIdentity;
use super::guard::Guard;
use super::ports::Ports;
use super::shared::{PostedScan, Shared};
use crate::ros::convert::goal_position;
use crate::ros::rivals::{self, Verdict};

/// The DDS-side tasks: keep the newest odometry and goal, post scans, answer the service,
/// publish diagnostics, watch for rivals ([`Guard`]); returns when Ctrl-C was pressed, or when a
/// rival found at start-up made the node refuse to run (the reason is in `Latest::refusal`).
pub(super) async fn serve(
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
pub(super) async fn answer_requests<Req, Resp>(
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
