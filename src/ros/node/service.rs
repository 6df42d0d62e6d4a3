//! The `/cstep/evaluate` and `/cstep/evaluate_batch` services' answers.

use std::sync::atomic::Ordering;
use std::time::Duration;

use rayon::prelude::*;
use ros2_client::RmwRequestId;

use super::queue::Full;
use super::scoring::{Query, Sensed};
use super::shared::Shared;
use crate::ros::convert::{empowerment_message, reward_message};
use crate::ros::messages::{
    EmpoweredReward, Empowerment, EvaluateBatchRequest, EvaluateBatchResponse, EvaluateRequest,
    EvaluateResponse, Header,
};
use crate::scoring::{unscorable, Score};

/// A request waiting for the service worker: which service's, and the id to answer it under.
pub(super) enum Job {
    /// A `/cstep/evaluate` request (boxed: a scan and an odometry, larger than a batch's
    /// vectors).
    Evaluate(RmwRequestId, Box<EvaluateRequest>),
    /// A `/cstep/evaluate_batch` request.
    Batch(RmwRequestId, EvaluateBatchRequest),
}

/// An answer ready to be written to DDS.
pub(super) enum Reply {
    /// To a `/cstep/evaluate` request.
    Evaluate(RmwRequestId, EvaluateResponse),
    /// To a `/cstep/evaluate_batch` request.
    Batch(RmwRequestId, EvaluateBatchResponse),
}

impl Job {
    /// Scores the request (a malformed one is answered `valid = false` with the reason).
    fn answer(self, shared: &Shared) -> Reply {
        match self {
            Job::Evaluate(id, request) => Reply::Evaluate(id, evaluate(shared, &request)),
            Job::Batch(id, request) => Reply::Batch(id, evaluate_batch(shared, &request)),
        }
    }

    /// The answer to a request that the queue refused (`full`): every state unscored,
    /// `valid = false`, the reason as status; counted as refused, and said by the next
    /// diagnostics.
    pub(super) fn refuse(self, shared: &Shared, full: Full) -> Reply {
        let reason = full.reason();
        shared.note_problem(|l| l.requests_refused += 1, &reason);
        let c = shared.safety_coefficient();
        match self {
            Job::Evaluate(id, request) => {
                let (empowerment, reward) = rejected(shared, request.scan.header, reason, c);
                Reply::Evaluate(
                    id,
                    EvaluateResponse {
                        empowerment,
                        reward,
                    },
                )
            }
            Job::Batch(id, request) => {
                let states = request.odom.len().max(request.scan.len());
                let (empowerment, reward) = (0..states)
                    .map(|i| {
                        let header = request.scan.get(i).map(|s| s.header.clone());
                        rejected(shared, header.unwrap_or_default(), reason.clone(), c)
                    })
                    .unzip();
                Reply::Batch(
                    id,
                    EvaluateBatchResponse {
                        empowerment,
                        reward,
                    },
                )
            }
        }
    }
}

/// The service worker: takes the queued requests in turn ([`super::queue::FairQueue::pop`]),
/// answers each, and hands the answer to the DDS side through `replies`; returns when the node
/// stops or the DDS side is gone. Runs on a thread of its own, so that a long batch never
/// holds up the DDS side taking the next requests off the readers.
pub(super) fn answer_queued(shared: &Shared, replies: &smol::channel::Sender<Reply>) {
    while !shared.stopping.load(Ordering::SeqCst) {
        let Some(job) = shared.requests.pop_timeout(Duration::from_millis(100)) else {
            continue;
        };
        let reply = job.answer(shared);
        shared.latest().requests_answered += 1;
        if replies.send_blocking(reply).is_err() {
            return;
        }
    }
}

/// The service answer for one state: its score, or for a malformed one the floor with
/// `valid = false` and the reason (counted as rejected).
fn answer(shared: &Shared, query: &Query, c: f64) -> (Empowerment, EmpoweredReward) {
    match query.score(shared, c, false) {
        Ok((empowerment, reward, _)) => (empowerment, reward),
        Err(problem) => {
            shared.note_problem(|l| l.rejected += 1, &problem);
            rejected(shared, query.sensed.header(), problem, c)
        }
    }
}

/// The answer for a state that could not be scored: its [`unscorable`] score, `problem` as
/// the status, stamped with `header`; its reward is the lowest a collision can score, so
/// malformed input never pays better than hitting a wall.
fn rejected(
    shared: &Shared,
    header: Header,
    problem: String,
    c: f64,
) -> (Empowerment, EmpoweredReward) {
    let Score { estimate, reward } = unscorable(&shared.estimator, c);
    let empowerment = Empowerment {
        status: problem,
        ..empowerment_message(header.clone(), &estimate, c)
    };
    (
        empowerment,
        reward_message(header, &reward, c, estimate.valid()),
    )
}

/// Answers `/cstep/evaluate`; a malformed request gets `valid = false` and the reason.
fn evaluate(shared: &Shared, request: &EvaluateRequest) -> EvaluateResponse {
    let query = Query {
        odom: &request.odom,
        sensed: Sensed::Scan(&request.scan),
        goal: request.has_goal.then_some(&request.goal),
        in_collision: false,
    };
    let (empowerment, reward) = answer(shared, &query, shared.safety_coefficient());
    EvaluateResponse {
        empowerment,
        reward,
    }
}

/// Answers `/cstep/evaluate_batch`: each state exactly as [`evaluate`] would
/// answer it alone (one safety coefficient for the whole batch), the states scored in
/// parallel on rayon's pool. When the request's arrays disagree in length, every state
/// (as many as the longer of `odom` and `scan`) is answered `valid = false` with the reason.
fn evaluate_batch(shared: &Shared, request: &EvaluateBatchRequest) -> EvaluateBatchResponse {
    let c = shared.safety_coefficient();
    let answers: Vec<_> = match Query::batch(request) {
        Ok(queries) => queries.par_iter().map(|q| answer(shared, q, c)).collect(),
        Err(problem) => {
            shared.note_problem(|l| l.rejected += 1, &problem);
            let states = request.odom.len().max(request.scan.len());
            (0..states)
                .map(|i| {
                    let header = request.scan.get(i).map(|s| s.header.clone());
                    rejected(shared, header.unwrap_or_default(), problem.clone(), c)
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

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::time::Duration;

    use super::*;
    use crate::demo::scene::{Lidar, Scene};
    use crate::estimator::{Estimator, EMPOWERMENT_FLOOR};
    use crate::parameters::Settings;
    use crate::ros::convert::scan_to_laser_scan;
    use crate::ros::messages::{LaserScan, Odometry, Point, Time};
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
        let answer = evaluate_batch(&node, &request);
        assert_eq!(answer.empowerment.len(), 4);
        for i in 0..4 {
            let alone = evaluate(&node, &single(&request, i));
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
        let answer = evaluate_batch(&node, &request);
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
        let alone = evaluate(&node, &single(&request, 2));
        assert_eq!(answer.empowerment[2], alone.empowerment);
    }

    #[test]
    fn a_malformed_entry_is_rejected_alone_and_never_nan() {
        let node = shared(1.0);
        let mut request = batch();
        request.scan[1].angle_increment = 0.0;
        request.odom[2].pose.pose.orientation.w = 0.0;
        request.goal[3].x = f64::NAN;
        let answer = evaluate_batch(&node, &request);
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
        // Regression: a malformed request answered reward 0.0, better than the
        // floor a robot touching a wall scores, so bad input paid.
        for c in [0.2, 1.0, 3.0, 5e4] {
            let node = shared(c);
            let mut request = batch();
            request.in_collision = vec![true, true, false, false];
            request.scan[2].angle_increment = 0.0;
            request.odom[3].pose.pose.position.x = f64::NAN;
            let answer = evaluate_batch(&node, &request);
            let mut single = single(&request, 3);
            single.scan.range_max = -1.0;
            let alone = evaluate(&node, &single).reward;
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
            let answer = evaluate_batch(&node, &request);
            assert_eq!(answer.empowerment.len(), 4, "{status}");
            assert_eq!(answer.reward.len(), 4, "{status}");
            for e in &answer.empowerment {
                assert!(!e.valid && e.status.starts_with(status), "{}", e.status);
                assert_eq!(e.empowerment, EMPOWERMENT_FLOOR);
            }
        }
        let empty = evaluate_batch(&node, &EvaluateBatchRequest::default());
        assert!(empty.empowerment.is_empty() && empty.reward.is_empty());
    }
}
