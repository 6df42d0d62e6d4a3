//! The node's DDS-side async tasks: taking inputs, answering the services, publishing
//! diagnostics and watching for rivals.

use std::cell::Cell;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use futures::StreamExt;
use ros2_client::{Message, Node, RmwRequestId, Server};
use tracing::warn;

use super::clock::NodeClock;
use super::diagnostics::{self, StatusIdentity};
use super::guard::Guard;
use super::ports::{Ports, SensorInput};
use super::rivals::{self, Verdict};
use super::service::{Job, Reply};
use super::shared::{PostedScan, Reading, Shared};
use crate::ros::convert::goal_position;

/// How long an answer waits for its client's response reader to be matched before it is
/// written anyway (see [`send_replies`]). Discovery takes 1-4 s on a loaded machine.
const REPLY_MATCH_WAIT: Duration = Duration::from_secs(10);

/// The DDS-side tasks: keep the newest odometry and goal, post scans, queue the services'
/// requests for the service worker and write its answers (`replies`), publish diagnostics,
/// watch for rivals ([`Guard`]); returns when Ctrl-C was pressed, or when a rival found at
/// start-up made the node refuse to run (the reason is in `Latest::refusal`).
pub(super) async fn serve(
    shared: &Arc<Shared>,
    ports: &Ports,
    node: &Node,
    guard: &Guard,
    status: &StatusIdentity,
    clock: &NodeClock,
    replies: (
        &smol::channel::Sender<Reply>,
        &smol::channel::Receiver<Reply>,
    ),
) {
    let (reply_sender, reply_receiver) = replies;
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
    // Posts a reading for the scoring thread, replacing one not yet scored; a reading nobody
    // wants a score of is counted and dropped.
    let post = move |reading: Reading| {
        // Matched readers of our writers, as the spinner records DDS matching.
        let scores_wanted = ports.empowerment.get_subscription_count(node) > 0
            || ports.reward.get_subscription_count(node) > 0
            || ports.speed_limit.as_ref().is_some_and(|l| l.wanted(node));
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
        let posted = PostedScan {
            reading,
            with_markers,
        };
        if mailbox.replace(posted).is_some() {
            shared.latest().skipped += 1;
        }
        shared.arrived.notify_one();
    };
    let readings = async move {
        match &ports.sensor {
            SensorInput::Scans(scans) => {
                scans
                    .async_stream()
                    .for_each(|received| async move {
                        match received {
                            Ok((scan, _)) => post(Reading::Scan(scan)),
                            Err(e) => shared.undecodable("scan", "message", &e),
                        }
                    })
                    .await
            }
            SensorInput::Clouds(clouds, input) => {
                clouds
                    .async_stream()
                    .for_each(|received| async move {
                        match received {
                            Ok((cloud, _)) => post(Reading::Cloud(cloud, input.clone())),
                            Err(e) => shared.undecodable("point cloud", "message", &e),
                        }
                    })
                    .await
            }
        }
    };
    let service = queue_requests(
        shared,
        &ports.evaluate,
        "evaluate",
        |id, request| Job::Evaluate(id, Box::new(request)),
        reply_sender,
    );
    let batch_service = queue_requests(
        shared,
        &ports.evaluate_batch,
        "evaluate_batch",
        Job::Batch,
        reply_sender,
    );
    let answers = send_replies(shared, ports, node, reply_receiver);
    let diagnostics = async {
        loop {
            smol::Timer::after(Duration::from_secs(1)).await;
            // Diagnostics are best effort: a full queue must not stop the node.
            let _ = ports
                .diagnostics
                .publish(diagnostics::report(shared, status, clock.now(node)));
        }
    };
    let rivals = async {
        loop {
            smol::Timer::after(rivals::CHECK_PERIOD).await;
            let (verdict, clash) = guard.check();
            let mut latest = shared.latest();
            if clash != latest.clash {
                if let Some(line) = &clash {
                    warn!("{line}");
                }
                latest.clash = clash;
            }
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
    // Releases the speed limit when scores stop coming (every 50 ms: within input_timeout
    // + 50 ms of the last score). Never ends when the output is off.
    let speed_limit_watch = async {
        let Some(limiter) = &ports.speed_limit else {
            return futures::future::pending::<()>().await;
        };
        loop {
            smol::Timer::after(Duration::from_millis(50)).await;
            if let Err(problem) = limiter.release_if_stale(shared.timeout(), || clock.now(node)) {
                shared.note_problem(|_| {}, &problem);
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
        Box::pin(readings),
        Box::pin(service),
        Box::pin(batch_service),
        Box::pin(answers),
        Box::pin(diagnostics),
        Box::pin(rivals),
        Box::pin(speed_limit_watch),
        Box::pin(stopped),
    ])
    .await;
}

/// Takes each request `server` receives off its DDS reader at once and queues it for the
/// service worker, by client ([`super::queue`]); a request the queue refuses is answered at once
/// with `valid = false` and the reason (through `replies`), never dropped. A request that cannot
/// be decoded is counted as rejected like an undecodable topic message (`name` says which
/// service's); it cannot be answered, as ros2-client drops its request id with the payload.
pub(super) async fn queue_requests<Req, Resp>(
    shared: &Shared,
    server: &Server<Req, Resp>,
    name: &str,
    job: impl Fn(RmwRequestId, Req) -> Job,
    replies: &smol::channel::Sender<Reply>,
) where
    Req: Message + Clone + 'static,
    Resp: Message + 'static,
{
    let job = &job;
    server
        .receive_request_stream()
        .for_each(|received| async move {
            match received {
                // The client is named by its response reader (rmw_fastrtps) or request writer.
                Ok((id, request)) => {
                    if let Err((full, refused)) =
                        shared.requests.push(id.writer_gid, job(id, request))
                    {
                        let _ = replies.send(refused.refuse(shared, full)).await;
                    }
                }
                Err(e) => shared.undecodable(name, "request", &e),
            }
        })
        .await;
}

/// Writes the answers the service worker (and the queue's refusals) hand over, each once its
/// client's response reader is matched ([`wait_for_client`]), many at a time, so that a client
/// not yet matched never holds up the others. At most `service_queue_total` replies wait at once
/// ([`WaitingReplies`]). A reply that cannot be written is counted and noted for diagnostics.
async fn send_replies(
    shared: &Shared,
    ports: &Ports,
    node: &Node,
    replies: &smol::channel::Receiver<Reply>,
) {
    let waiting = &WaitingReplies::new(shared.requests.limits().total);
    replies
        .clone()
        .for_each_concurrent(None, |reply| async move {
            let (id, result, name) = match reply {
                Reply::Evaluate(id, response) => {
                    if let Some(_place) = waiting.enter() {
                        wait_for_client(node, &ports.evaluate, &id).await;
                    }
                    let sent = ports.evaluate.async_send_response(id, response).await;
                    (id, sent, "evaluate")
                }
                Reply::Batch(id, response) => {
                    if let Some(_place) = waiting.enter() {
                        wait_for_client(node, &ports.evaluate_batch, &id).await;
                    }
                    let sent = ports.evaluate_batch.async_send_response(id, response).await;
                    (id, sent, "evaluate_batch")
                }
            };
            if let Err(e) = result {
                shared.note_problem(
                    |l| l.replies_failed += 1,
                    &format!("{name} reply to {id:?} failed: {e}"),
                );
            }
        })
        .await;
}

/// Places for replies waiting for their client's response reader ([`wait_for_client`]): as
/// many as requests may wait to be served (`service_queue_total`), so that a flood of requests
/// from clients the node never matches holds a bounded number of answers, each at most
/// [`REPLY_MATCH_WAIT`]. A reply that finds no place is written at once, as a server without
/// the wait writes it (a client matched by then gets it; one that is not, as before the wait).
struct WaitingReplies {
    waiting: Cell<usize>,
    limit: usize,
}

impl WaitingReplies {
    fn new(limit: usize) -> Self {
        Self {
            waiting: Cell::new(0),
            limit,
        }
    }

    /// A place to wait in, held until the guard drops; None when all `limit` are taken.
    fn enter(&self) -> Option<WaitingPlace<'_>> {
        let waiting = self.waiting.get();
        (waiting < self.limit).then(|| {
            self.waiting.set(waiting + 1);
            WaitingPlace(&self.waiting)
        })
    }
}

/// One reply's place among the [`WaitingReplies`], given back when dropped.
struct WaitingPlace<'a>(&'a Cell<usize>);

impl Drop for WaitingPlace<'_> {
    fn drop(&mut self) {
        self.0.set(self.0.get() - 1);
    }
}

/// Waits until `server`'s response writer has matched the response reader that the request
/// `id` names, at most [`REPLY_MATCH_WAIT`]. A client's request can reach the node before the
/// node has discovered that client's response reader; written then, the answer would never be
/// delivered (the writer is volatile: a reader matched later is owed nothing written before).
/// rmw_fastrtps servers wait likewise. Returns at once for an id that names no reader
/// (ros2-client clients name their request writer).
async fn wait_for_client<Req, Resp>(node: &Node, server: &Server<Req, Resp>, id: &RmwRequestId)
where
    Req: Message + 'static,
    Resp: Message + 'static,
{
    let Some(reader) = Server::<Req, Resp>::response_reader(id) else {
        return;
    };
    let writer = server.response_writer_guid();
    if node.is_reader_matched(writer, reader) {
        return;
    }
    smol::future::or(node.wait_for_reader_match(writer, reader), async {
        smol::Timer::after(REPLY_MATCH_WAIT).await;
    })
    .await;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_most_the_limit_of_replies_wait_and_a_place_comes_back_when_dropped() {
        let waiting = WaitingReplies::new(2);
        let first = waiting.enter();
        let second = waiting.enter();
        assert!(first.is_some() && second.is_some());
        assert!(
            waiting.enter().is_none(),
            "a third reply is written at once"
        );
        drop(first);
        assert!(waiting.enter().is_some(), "a place freed is taken again");
        drop(second);
        assert_eq!(waiting.waiting.get(), 0);
    }
}
