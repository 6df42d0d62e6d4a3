//! The empowered reward: a task reward weighted by the log of the scaled free volume.
//!
//! `r(x) = r_d(x) · log(c · λ(R_T,free(x)))` (the paper's Definition 4), with the navigation
//! task reward `r_d(x) = exp(−‖p − goal‖)` of its experiments. Smaller safety coefficients `c`
//! make an agent more cautious: the empowerment term is positive only where the free volume
//! exceeds `1/c`.

use nalgebra::Vector3;

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
