//! The empowered reward: a task reward weighted by the log of the scaled free volume.
//!
//! `r(x) = r_d(x) · log(c · λ(R_T,free(x)))` (the paper's Definition 4), with the navigation
//! task reward `r_d(x) = exp(−‖p − goal‖)` of its experiments. Smaller safety coefficients `c`
//! make an agent more cautious: the empowerment term is positive only where the free volume
//! exceeds `1/c`.

use nalgebra::Vector3;

use crate::estimator::EMPOWERMENT_FLOOR;

/// The three numbers an RL loop needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reward {
    /// `r_d · empowerment_term`.
    pub reward: f64,
    /// `r_d ∈ [0, 1]`: `exp(−‖p − goal‖)`, or 1 without a goal (pure empowerment).
    pub task_reward: f64,
    /// `log(c · free_volume) = log c + empowerment`.
    pub empowerment_term: f64,
}

/// The navigation task reward of the paper's experiments; 1 when there is no goal, so the
/// reward reduces to the (scaled) empowerment.
pub fn task_reward(position: &Vector3<f64>, goal: Option<&Vector3<f64>>) -> f64 {
    goal.map_or(1.0, |g| (-(position - g).norm()).exp())
}

/// The empowered reward for an empowerment value (natural log of the free volume, already
/// clamped to a finite floor by the estimator) and safety coefficient `c > 0`.
pub fn empowered_reward(empowerment: f64, safety_coefficient: f64, task_reward: f64) -> Reward {
    let empowerment_term = safety_coefficient.ln() + empowerment;
    Reward {
        reward: task_reward * empowerment_term,
        task_reward,
        empowerment_term,
    }
}

/// The lowest reward any state can score with safety coefficient `c`: the empowerment floor
/// (a robot in collision) with the task reward in `[0, 1]` that makes it lowest — 1 while the
/// floor's empowerment term is negative (`c` below `1 / MIN_FREE_VOLUME`), else 0. It answers
/// input that cannot be scored, so that a malformed request never earns an agent more than a
/// collision does.
pub fn floor_reward(safety_coefficient: f64) -> Reward {
    let at_floor =
        |task_reward| empowered_reward(EMPOWERMENT_FLOOR, safety_coefficient, task_reward);
    let (full, none) = (at_floor(1.0), at_floor(0.0));
    if full.reward <= none.reward {
        full
    } else {
        none
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_reward_decays_with_distance_to_goal() {
        let p = Vector3::new(1.0, 2.0, 1.0);
        assert_eq!(task_reward(&p, None), 1.0);
        assert_eq!(task_reward(&p, Some(&p)), 1.0);
        let goal = Vector3::new(4.0, 6.0, 1.0); // 5 m away
        assert!((task_reward(&p, Some(&goal)) - (-5.0f64).exp()).abs() < 1e-15);
    }

    #[test]
    fn the_floor_reward_is_at_most_any_collision_score() {
        for c in [1e-3, 0.5, 1.0, 9999.0, 1e4, 1e6] {
            let floor = floor_reward(c);
            assert_eq!(floor.empowerment_term, c.ln() + EMPOWERMENT_FLOOR);
            assert_eq!(floor.reward, floor.task_reward * floor.empowerment_term);
            for task in [0.0, 1e-9, 0.3, 1.0] {
                let collision = empowered_reward(EMPOWERMENT_FLOOR, c, task);
                assert!(floor.reward <= collision.reward, "c {c}, task {task}");
            }
        }
    }

    #[test]
    fn reward_is_task_reward_times_log_of_scaled_volume() {
        let free_volume: f64 = 6.0;
        let r = empowered_reward(free_volume.ln(), 0.5, 0.25);
        assert!((r.empowerment_term - 3.0f64.ln()).abs() < 1e-12);
        assert!((r.reward - 0.25 * 3.0f64.ln()).abs() < 1e-12);
        // Positive exactly when the free volume exceeds 1/c.
        assert!(empowered_reward(1.9f64.ln(), 0.5, 1.0).reward < 0.0);
        assert!(empowered_reward(2.1f64.ln(), 0.5, 1.0).reward > 0.0);
    }
}
