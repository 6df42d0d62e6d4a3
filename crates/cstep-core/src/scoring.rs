//! One C-STEP step: a state, its scan, an optional goal and a safety coefficient `c` in, the
//! estimate and its empowered reward out.
//!
//! The node's scans, its `/cstep/evaluate` and `/cstep/evaluate_batch` services, `cstep eval`
//! and the Python scorer all score through [`score`]; the services and the Python scorer admit
//! a state with [`admit`] and answer input they cannot score with [`unscorable`], so that every
//! front end pays the same reward for the same step — in particular, malformed input never
//! earns more than a collision.

use nalgebra::Vector3;

use crate::estimator::{Estimate, Estimator};
use crate::input::InputError;
use crate::occupancy::{Scan, ScanFrame};
use crate::reward::{empowered_reward, floor_reward, task_reward, Reward};
use crate::state::RobotState;

/// An estimate and the reward it earns.
#[derive(Debug, Clone, PartialEq)]
pub struct Score {
    /// C-STEP of the state.
    pub estimate: Estimate,
    /// The empowered reward `r_d · log(c · λ)` of that estimate.
    pub reward: Reward,
}

/// Scores `state` seen through `scan` (bearings in `frame`) with `estimator` (its configured
/// seed) and safety coefficient `c`; the task reward decays with the distance to `goal`, or is
/// 1 without one. A state its caller reports `in_collision` (a simulator that saw contact)
/// scores the floor without reading the scan or rolling out ([`Estimator::known_collision`]).
pub fn score(
    estimator: &Estimator,
    state: &RobotState,
    (scan, frame): (&Scan, ScanFrame),
    goal: Option<&Vector3<f64>>,
    c: f64,
    in_collision: bool,
) -> Score {
    let estimate = if in_collision {
        estimator.known_collision()
    } else {
        estimator.evaluate_in(state, scan, frame)
    };
    let reward = empowered_reward(estimate.empowerment, c, task_reward(&state.position, goal));
    Score { estimate, reward }
}

/// A state, its scan and its goal as [`crate::input`] checked them, or why they cannot be
/// scored: the first bad one's error, prefixed `odometry: ` or `scan: ` (a goal's names itself),
/// as the services report it in `status`.
pub fn admit(
    state: Result<RobotState, InputError>,
    scan: Result<Scan, InputError>,
    goal: Result<Option<Vector3<f64>>, InputError>,
) -> Result<(RobotState, Scan, Option<Vector3<f64>>), String> {
    let state = state.map_err(|e| format!("odometry: {e}"))?;
    let scan = scan.map_err(|e| format!("scan: {e}"))?;
    let goal = goal.map_err(|e| e.to_string())?;
    Ok((state, scan, goal))
}

/// The score of input that cannot be scored (a malformed state, scan or goal): the floor
/// estimate ([`Estimator::invalid_input`]) with the lowest reward any state can earn with
/// safety coefficient `c` ([`floor_reward`]).
pub fn unscorable(estimator: &Estimator, c: f64) -> Score {
    Score {
        estimate: estimator.invalid_input(),
        reward: floor_reward(c),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimator::EMPOWERMENT_FLOOR;
    use crate::parameters::Settings;

    #[test]
    fn unscorable_input_never_scores_better_than_a_known_collision() {
        let estimator = Estimator::from_settings(&Settings::builtin()).unwrap();
        let state = RobotState::at_rest(Vector3::new(1.0, 2.0, 1.0));
        let scan = Scan {
            angle_min: 0.0,
            angle_increment: 0.1,
            range_min: 0.1,
            range_max: 3.0,
            ranges: vec![],
        };
        for c in [0.2, 1.0, 3.0, 5e4] {
            let bad = unscorable(&estimator, c);
            assert!(!bad.estimate.valid());
            assert_eq!(bad.estimate.empowerment, EMPOWERMENT_FLOOR);
            assert_eq!(bad.estimate.num_colliding, 0, "nothing was rolled out");
            for goal in [None, Some(Vector3::new(4.0, 6.0, 1.0))] {
                let seen = (&scan, ScanFrame::Body);
                let hit = score(&estimator, &state, seen, goal.as_ref(), c, true);
                assert_eq!(hit.estimate, estimator.known_collision());
                assert!(
                    bad.reward.reward <= hit.reward.reward,
                    "c {c}, goal {goal:?}"
                );
            }
        }
    }
}
