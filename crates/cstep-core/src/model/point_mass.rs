//! The paper prototype's robot: a point mass under bounded acceleration (a double integrator).
//!
//! Kept for comparison with the authors' prototype and because its reachable set is known
//! exactly: from velocity `v` with `|a_i| ≤ A` per axis, the positions reachable at `T` form the
//! box `v·T ± A·T²/2` — the reference the estimator tests are checked against.

use super::{Batch, CommandAxes, Dynamics};
use crate::state::RobotState;

/// A double integrator with a per-axis acceleration bound.
#[derive(Debug, Clone, PartialEq)]
pub struct PointMass {
    max_acceleration: f64,
    radius: f64,
    height: f64,
}

impl PointMass {
    /// A point mass whose acceleration is bounded by `max_acceleration` (m/s²) per axis, with a
    /// collision disk of `radius` and a collision height of `height` (metres).
    pub fn new(max_acceleration: f64, radius: f64, height: f64) -> Self {
        Self {
            max_acceleration,
            radius,
            height,
        }
    }

    /// The per-axis acceleration bound, m/s².
    pub fn max_acceleration(&self) -> f64 {
        self.max_acceleration
    }
}

const VX: usize = 3;

impl Dynamics for PointMass {
    fn name(&self) -> &'static str {
        "point_mass"
    }

    fn state_components(&self) -> usize {
        6
    }

    fn actuation_components(&self) -> usize {
        3
    }

    fn initial_state(&self, state: &RobotState, batch: &mut Batch) {
        for axis in 0..3 {
            batch.fill_component(axis, 0.0);
            batch.fill_component(VX + axis, state.velocity[axis] as f32);
        }
    }

    fn actuate(&self, state: &Batch, commands: &[f32], axes: CommandAxes, actuation: &mut Batch) {
        let bound = self.max_acceleration as f32;
        // Commands and actuation are both axis-major with `lanes` per axis, so the commanded
        // axes are one contiguous run: one loop over all of them, then zeros for the rest.
        let (commanded, rest) = actuation
            .as_mut_slice()
            .split_at_mut(axes.count() * state.lanes());
        for (a, &c) in commanded.iter_mut().zip(commands) {
            *a = bound * c.clamp(-1.0, 1.0);
        }
        rest.fill(0.0);
    }

    fn derivative(&self, state: &Batch, actuation: &Batch, out: &mut Batch) {
        for axis in 0..3 {
            out.component_mut(axis)
                .copy_from_slice(state.component(VX + axis));
            out.component_mut(VX + axis)
                .copy_from_slice(actuation.component(axis));
        }
    }

    /// Under a held acceleration a double integrator moves exactly by `v·dt + a·dt²/2`, which is
    /// also what RK4 computes (it is exact for polynomials of this degree) at a quarter of the work.
    fn integrate(&self, state: &mut Batch, actuation: &Batch, dt: f32) -> bool {
        // Positions, velocities and accelerations are each three axis blocks of `lanes`, in
        // the same order: one loop over all three axes at once.
        let lanes = state.lanes();
        let (positions, velocities) = state.as_mut_slice().split_at_mut(VX * lanes);
        for ((p, v), &a) in positions
            .iter_mut()
            .zip(velocities)
            .zip(actuation.as_slice())
        {
            *p += dt * (*v + 0.5 * dt * a);
            *v += dt * a;
        }
        true
    }

    /// [`Dynamics::actuate`] and [`Dynamics::integrate`] fused: the same arithmetic, lane by
    /// lane, without the actuation batch in between (half the memory traffic of a step).
    fn actuate_and_integrate(
        &self,
        state: &mut Batch,
        commands: &[f32],
        axes: CommandAxes,
        dt: f32,
    ) -> bool {
        let bound = self.max_acceleration as f32;
        let lanes = state.lanes();
        let commanded = axes.count() * lanes;
        let (positions, velocities) = state.as_mut_slice().split_at_mut(VX * lanes);
        let (positions, idle_positions) = positions.split_at_mut(commanded);
        let (velocities, idle_velocities) = velocities.split_at_mut(commanded);
        for ((p, v), &c) in positions.iter_mut().zip(velocities).zip(commands) {
            let a = bound * c.clamp(-1.0, 1.0);
            *p += dt * (*v + 0.5 * dt * a);
            *v += dt * a;
        }
        // The axes without commands, under the zero acceleration `actuate` writes for them
        // (the same expressions, so that signed zeros come out as they would there).
        let a = 0.0;
        for (p, v) in idle_positions.iter_mut().zip(idle_velocities) {
            *p += dt * (*v + 0.5 * dt * a);
            *v += dt * a;
        }
        true
    }

    fn collision_radius(&self) -> f64 {
        self.radius
    }

    fn collision_height(&self) -> f64 {
        self.height
    }
}
