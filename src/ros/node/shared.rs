//! The state the node's threads share — the DDS side, the scoring thread and the service
//! worker: the estimator, the live safety coefficient and input timeout, the newest inputs and
//! running counts, the one-slot scan mailbox and the services' request queue.
//!
//! Only the state and its bookkeeping live here (the one `impl Shared`); what each thread does
//! with it is a concept of its own, in its own file: scoring a state ([`super::scoring`]),
//! answering the services ([`super::service`]) and reporting health ([`super::diagnostics`]).

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use super::queue::{Limits, SharedQueue};
use super::service::Job;
use super::stamps::{Order, StampOrder};
use crate::cloud::{CloudInput, CloudSummary};
use crate::estimator::Estimator;
use crate::ros::messages::{LaserScan, Odometry, Point, PointCloud2, Time};

/// What the DDS side and the scoring thread share.
pub(super) struct Shared {
    pub(super) estimator: Estimator,
    pub(super) safety_coefficient: Mutex<f64>,
    /// `input_timeout`: odometry older than this when a scan arrives is stale (live).
    pub(super) timeout: Mutex<Duration>,
    /// Seconds a scan stamp may lie behind the newest scored before it means time jumped back.
    pub(super) time_jump_tolerance: f64,
    pub(super) latest: Mutex<Latest>,
    /// The newest scan not yet scored.
    pub(super) mailbox: Mutex<Option<PostedScan>>,
    pub(super) arrived: Condvar,
    pub(super) stopping: Arc<AtomicBool>,
    /// The services' requests waiting for the service worker, by client.
    pub(super) requests: SharedQueue<ros2_client::Gid, Job>,
}

/// A reading waiting to be scored.
pub(super) struct PostedScan {
    pub(super) reading: Reading,
    /// Whether `/cstep/markers` had a matched subscriber when the reading arrived.
    pub(super) with_markers: bool,
}

/// What the node scores a state from: a scan, or a point cloud and how to read it as one
/// (`use_point_cloud`).
pub(super) enum Reading {
    Scan(LaserScan),
    Cloud(PointCloud2, CloudInput),
}

/// Newest inputs and running counts, for scoring and diagnostics.
#[derive(Default)]
pub(super) struct Latest {
    pub(super) odom: Option<(Odometry, Instant)>,
    pub(super) goal: Option<Point>,
    pub(super) last_scan: Option<Instant>,
    pub(super) last_score: Option<(f64, bool, Duration)>,
    /// What the newest point cloud scored held (with `use_point_cloud`).
    pub(super) last_cloud: Option<CloudSummary>,
    pub(super) scored: u64,
    pub(super) skipped: u64,
    /// Scans that arrived while nobody subscribed to the scores, so were not scored.
    pub(super) unwatched: u64,
    /// Whether the newest scan was one of those.
    pub(super) last_scan_unwatched: bool,
    pub(super) stale: u64,
    pub(super) rejected: u64,
    pub(super) markers_published: u64,
    /// Service requests answered (scored, or rejected as malformed).
    pub(super) requests_answered: u64,
    /// Service requests refused unscored because the request queue was full (answered with
    /// `valid = false` and the reason).
    pub(super) requests_refused: u64,
    /// Service answers that could not be written to DDS.
    pub(super) replies_failed: u64,
    pub(super) last_problem: Option<String>,
    /// The newest scored scan's stamp: an older one arriving later is late, or time jumped back.
    pub(super) order: StampOrder,
    /// Backward time jumps seen (each reset the ordering).
    pub(super) time_jumps: u64,
    /// The newest time jump, until a diagnostics message has said so (once, whatever other
    /// problem or staleness comes with it).
    pub(super) time_jump: Option<String>,
    /// Another participant answering under this node's names, found after the start-up window:
    /// the warning, while it lasts (diagnostics are ERROR meanwhile).
    pub(super) rival: Option<String>,
    /// Topics this node writes that the graph uses with another type (a remapping onto a topic
    /// in use): the warning, while it lasts (diagnostics are WARN meanwhile).
    pub(super) clash: Option<String>,
    /// Another participant answering under this node's names, found at start: why the node
    /// stopped.
    pub(super) refusal: Option<String>,
}

impl Shared {
    /// The shared state of a node scoring with `estimator`, safety coefficient `c` until a
    /// parameter change, odometry older than `timeout` counted stale, and a scan stamped more
    /// than `time_jump_tolerance` seconds before the newest scored taken for a jump back in time.
    pub(super) fn new(
        estimator: Estimator,
        c: f64,
        timeout: Duration,
        time_jump_tolerance: f64,
        stopping: Arc<AtomicBool>,
    ) -> Self {
        Self {
            estimator,
            safety_coefficient: Mutex::new(c),
            timeout: Mutex::new(timeout),
            time_jump_tolerance,
            latest: Mutex::default(),
            mailbox: Mutex::new(None),
            arrived: Condvar::new(),
            stopping,
            requests: SharedQueue::new(Limits {
                per_client: 16,
                total: 128,
            }),
        }
    }

    /// The same, with the services' request queue holding at most `limits`.
    pub(super) fn with_request_limits(mut self, limits: Limits) -> Self {
        self.requests = SharedQueue::new(limits);
        self
    }

    pub(super) fn latest(&self) -> std::sync::MutexGuard<'_, Latest> {
        self.latest.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Records a scan stamped `stamp` as scored; if its `order` says time jumped back, counts
    /// the jump and has the next diagnostics say so.
    pub(super) fn scored(&self, stamp: Time, order: Order) {
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
    pub(super) fn safety_coefficient(&self) -> f64 {
        *self
            .safety_coefficient
            .lock()
            .unwrap_or_else(|e| e.into_inner())
    }

    /// The input timeout in effect now.
    pub(super) fn timeout(&self) -> Duration {
        *self.timeout.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Counts a `what` (a message, a request) that `input` could not decode (malformed CDR: a
    /// length past the end of the buffer, a truncated buffer) as rejected, and has the next
    /// diagnostics say so: it is dropped like any malformed input, not silently.
    pub(super) fn undecodable(&self, input: &str, what: &str, error: &ros2_client::ReadError) {
        self.note_problem(
            |l| l.rejected += 1,
            &format!("{input}: undecodable {what} dropped: {error}"),
        );
    }

    pub(super) fn note_problem(&self, count: impl FnOnce(&mut Latest), problem: &str) {
        let mut latest = self.latest();
        count(&mut latest);
        latest.last_problem = Some(problem.to_owned());
    }
}
