//! Scoring: one state (odometry, scan, goal) to its score, reward and markers, and the thread
//! that scores the newest scan.

use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;

use nalgebra::UnitQuaternion;
use ros2_client::Publisher;
use tracing::debug;

use super::markers::rollout_markers;
use super::shared::{PostedScan, Reading, Shared};
use super::speed_limit::SpeedLimiter;
use super::stamps::Order;
use crate::cloud::CloudInput;
use crate::occupancy::ScanFrame;
use crate::ros::convert::{
    empowerment_message, goal_position, laser_scan_to_scan, odometry_to_state, point_cloud_to_scan,
    reward_message,
};
use crate::ros::messages::{
    EmpoweredReward, Empowerment, EvaluateBatchRequest, Header, LaserScan, MarkerArray, Odometry,
    Point, PointCloud2, Time,
};
use crate::scoring::{admit, score, Score};

/// What the scoring thread publishes to.
pub(super) struct Outputs {
    pub(super) empowerment: Arc<Publisher<Empowerment>>,
    pub(super) reward: Arc<Publisher<EmpoweredReward>>,
    pub(super) markers: Arc<Publisher<MarkerArray>>,
    /// The speed-limit output, when `publish_speed_limit` is on.
    pub(super) speed_limit: Option<Arc<SpeedLimiter>>,
}

/// The scoring thread: waits for a scan, scores it against the newest odometry, publishes the
/// speed limit (if on) and the score, then the markers if someone subscribes to them.
pub(super) fn score_scans(shared: &Shared, outputs: &Outputs) {
    loop {
        let PostedScan {
            reading,
            with_markers,
        } = {
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
        if seen.elapsed() > shared.timeout() {
            shared.note_problem(|l| l.stale += 1, "odometry is stale");
            continue;
        }
        let sensed = match &reading {
            Reading::Scan(scan) => Sensed::Scan(scan),
            Reading::Cloud(cloud, input) => Sensed::Cloud(cloud, input),
        };
        let stamp = sensed.stamp();
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
            sensed,
            goal: goal.as_ref(),
            in_collision: false,
        };
        match query.score(shared, shared.safety_coefficient(), with_markers) {
            Ok((e, r, markers)) => {
                debug!(
                    "scan {}.{:09}: empowerment {:.4} (valid: {}, {})",
                    stamp.sec, stamp.nanosec, e.empowerment, e.valid, e.status
                );
                shared.scored(stamp, order);
                if let Some(limiter) = &outputs.speed_limit {
                    if let Err(problem) = limiter.scored(&e.header, e.empowerment) {
                        shared.note_problem(|_| {}, &problem);
                    }
                }
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
/// request, or a scan (or point cloud) with the newest odometry and goal.
pub(super) struct Query<'a> {
    pub(super) odom: &'a Odometry,
    /// What the robot's sensor saw.
    pub(super) sensed: Sensed<'a>,
    /// Goal of the task reward; None for a task reward of 1.
    pub(super) goal: Option<&'a Point>,
    /// The caller reports the robot in collision: scored at the floor without rolling out.
    pub(super) in_collision: bool,
}

impl<'a> Query<'a> {
    /// The states of a batch request, or why its arrays cannot describe K states: `scan` must
    /// hold as many entries as `odom`, `goal` and `has_goal` none or as many (both alike), and
    /// `in_collision` none or as many. The reason is a String: it is the `status` published
    /// for every state of the refused batch.
    pub(super) fn batch(request: &'a EvaluateBatchRequest) -> Result<Vec<Self>, String> {
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
                sensed: Sensed::Scan(&request.scan[i]),
                goal: (request.has_goal.get(i) == Some(&true)).then(|| &request.goal[i]),
                in_collision: request.in_collision.get(i) == Some(&true),
            })
            .collect())
    }

    /// Scores this state with safety coefficient `c` on the node's estimator, with the markers
    /// of the evaluation if asked; a malformed input is an error naming the field, a String
    /// because it is the `status` published in the rejected answer.
    pub(super) fn score(
        &self,
        shared: &Shared,
        c: f64,
        with_markers: bool,
    ) -> Result<(Empowerment, EmpoweredReward, Option<MarkerArray>), String> {
        let state = odometry_to_state(self.odom);
        let (scan, frame, cloud) = match self.sensed {
            Sensed::Scan(scan) => (laser_scan_to_scan(scan), ScanFrame::Body, None),
            Sensed::Cloud(cloud, input) => {
                // Without a usable attitude the odometry's own error is reported (by `admit`).
                let attitude = state
                    .as_ref()
                    .map_or_else(|_| UnitQuaternion::identity(), |s| s.attitude);
                match point_cloud_to_scan(cloud, &attitude, input) {
                    Ok(read) => (Ok(read.scan), ScanFrame::WorldAligned, Some(read.summary)),
                    Err(e) => (Err(e), ScanFrame::WorldAligned, None),
                }
            }
        };
        let (state, scan, goal) = admit(state, scan, self.goal.map(goal_position).transpose())?;
        let Score { estimate, reward } = score(
            &shared.estimator,
            &state,
            (&scan, frame),
            goal.as_ref(),
            c,
            self.in_collision,
        );
        let header = Header {
            stamp: self.sensed.stamp(),
            frame_id: self.odom.header.frame_id.clone(),
        };
        {
            let mut latest = shared.latest();
            latest.scored += 1;
            latest.last_score = Some((estimate.empowerment, estimate.valid(), estimate.elapsed));
            if cloud.is_some() {
                latest.last_cloud = cloud;
            }
        }
        let markers = with_markers.then(|| {
            rollout_markers(
                &header,
                &state.position,
                &estimate.rollout,
                shared.timeout().as_secs_f64(),
            )
        });
        Ok((
            empowerment_message(header.clone(), &estimate, c),
            reward_message(header, &reward, c, estimate.valid()),
            markers,
        ))
    }
}

/// What a robot's sensor saw, for [`Query`]: a scan, or a point cloud with how to read it.
#[derive(Clone, Copy)]
pub(super) enum Sensed<'a> {
    Scan(&'a LaserScan),
    Cloud(&'a PointCloud2, &'a CloudInput),
}

impl Sensed<'_> {
    /// The stamp of the reading.
    pub(super) fn stamp(self) -> Time {
        match self {
            Sensed::Scan(scan) => scan.header.stamp,
            Sensed::Cloud(cloud, _) => cloud.header.stamp,
        }
    }

    /// The header of the reading, for an answer that cannot be scored.
    pub(super) fn header(self) -> Header {
        match self {
            Sensed::Scan(scan) => scan.header.clone(),
            Sensed::Cloud(cloud, _) => cloud.header.clone(),
        }
    }
}
