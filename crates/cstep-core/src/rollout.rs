//! Batched integration of sampled control trajectories with path-wise collision checks.
//!
//! Trajectories are integrated together, one component array at a time (the batch is the
//! inner loop, as in Nav2's MPPI), with classic fourth-order Runge–Kutta: the model's
//! controller runs once at the start of each step and its actuation is held over the step.
//! After every step each trajectory's position is checked against the scan's free space, so a
//! trajectory that passes through an obstacle and comes out the other side is still terminal
//! (the prototype checked only the endpoint). Once a trajectory has collided its checks stop;
//! its integration continues to `T`, because the paper's reachable set `R̂` is the hull of all
//! endpoints, terminal ones included.

use rayon::prelude::*;

use crate::model::{Batch, Dynamics, POSITION_COMPONENTS};
use crate::occupancy::Occupancy;
use crate::sampling::Controls;
use crate::state::RobotState;

/// Trajectories integrated together in one cache-resident block; blocks run in parallel on
/// rayon's pool. A quadrotor lane keeps about 24 `f32` in play (state, actuation, commands; its
/// RK4 runs fused over 32-lane chunks), so 160 lanes (15 KiB) stay well within a 48 KiB L1 data
/// cache; blocks that spill to L2 are measurably slower. A multiple of the collision checks'
/// 16-lane chunks.
const BLOCK_LANES: usize = 160;

/// Where each trajectory ended and whether it collided on the way.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Rollout {
    /// Position at the horizon relative to the start (world-aligned axes), metres.
    pub endpoints: Vec<[f64; 3]>,
    /// Whether the trajectory collided at any step.
    pub terminal: Vec<bool>,
}

impl Rollout {
    /// Number of trajectories that collided.
    pub fn num_colliding(&self) -> usize {
        self.terminal.iter().filter(|&&t| t).count()
    }
}

/// Integrates every trajectory of `controls` over `horizon` seconds from `start`, checking each
/// step's position against `occupancy`.
pub fn roll_out(
    model: &dyn Dynamics,
    start: &RobotState,
    controls: &Controls,
    horizon: f64,
    occupancy: &Occupancy,
) -> Rollout {
    let lanes = controls.lanes();
    let blocks: Vec<(usize, usize)> = (0..lanes)
        .step_by(BLOCK_LANES)
        .map(|first| (first, (first + BLOCK_LANES).min(lanes)))
        .collect();
    let results: Vec<Rollout> = blocks
        .par_iter()
        .map(|&(first, end)| roll_out_block(model, start, controls, first..end, horizon, occupancy))
        .collect();
    let mut rollout = Rollout {
        endpoints: Vec::with_capacity(lanes),
        terminal: Vec::with_capacity(lanes),
    };
    for block in results {
        rollout.endpoints.extend(block.endpoints);
        rollout.terminal.extend(block.terminal);
    }
    rollout
}

fn roll_out_block(
    model: &dyn Dynamics,
    start: &RobotState,
    controls: &Controls,
    lanes: std::ops::Range<usize>,
    horizon: f64,
    occupancy: &Occupancy,
) -> Rollout {
    let n = lanes.len();
    let axes = controls.axes();
    let steps = controls.steps();
    let dt = (horizon / steps.max(1) as f64) as f32;
    let mut state = Batch::zeros(model.state_components(), n);
    // The generic RK4's scratch, made only for models without their own integrator.
    let mut integrator = None;
    let mut actuation = Batch::zeros(model.actuation_components(), n);
    let mut commands = if n < controls.lanes() {
        vec![0.0f32; axes.count() * n]
    } else {
        Vec::new()
    };
    let mut hit = vec![0u8; n];
    // Footprint disk centres, for models whose footprint turns with them.
    let mut centres = match model.oriented_footprint() {
        Some(_) => [vec![0f32; n], vec![0f32; n]],
        None => [Vec::new(), Vec::new()],
    };
    model.initial_state(start, &mut state);

    for k in 0..steps {
        let all = controls.at_step(k);
        // A block of every lane reads the step's commands in place; a block of some lanes
        // gathers its share of each axis.
        let commands = if n == controls.lanes() {
            all
        } else {
            for axis in 0..axes.count() {
                let from = axis * controls.lanes();
                commands[axis * n..(axis + 1) * n]
                    .copy_from_slice(&all[from + lanes.start..from + lanes.end]);
            }
            &commands
        };
        if !model.actuate_and_integrate(&mut state, commands, axes, dt) {
            model.actuate(&state, commands, axes, &mut actuation);
            if !model.integrate(&mut state, &actuation, dt) {
                integrator
                    .get_or_insert_with(|| Rk4::new(model.state_components(), n))
                    .step(model, &mut state, &actuation, dt);
            }
        }
        if hit.contains(&0) {
            mark_collisions(model, &state, occupancy, &mut hit, &mut centres);
        }
    }

    let [x, y, z] = POSITION_COMPONENTS.map(|c| state.component(c));
    Rollout {
        endpoints: (0..n)
            .map(|i| [x[i] as f64, y[i] as f64, z[i] as f64])
            .collect(),
        terminal: hit.iter().map(|&h| h != 0).collect(),
    }
}

/// Sets `hit` for every lane of `state` whose robot overlaps an obstacle: its position's disk,
/// or each disk of the model's oriented footprint placed by the lane's heading (`centres` is
/// scratch of one lane per lane for those).
fn mark_collisions(
    model: &dyn Dynamics,
    state: &Batch,
    occupancy: &Occupancy,
    hit: &mut [u8],
    centres: &mut [Vec<f32>; 2],
) {
    let [x, y, z] = POSITION_COMPONENTS.map(|c| state.component(c));
    let Some((footprint, [cos, sin])) = model.oriented_footprint() else {
        occupancy.mark_collisions(x, y, z, hit);
        return;
    };
    let [cx, cy] = centres;
    let pose = [x, y, state.component(cos), state.component(sin)];
    for k in 0..footprint.centres().len() {
        footprint.place(k, pose, cx, cy);
        occupancy.mark_collisions(cx, cy, z, hit);
    }
}

/// Scratch space for one classic RK4 step over a batch.
struct Rk4 {
    stage: Batch,
    slope: Batch,
    sum: Batch,
}

impl Rk4 {
    fn new(components: usize, lanes: usize) -> Self {
        Self {
            stage: Batch::zeros(components, lanes),
            slope: Batch::zeros(components, lanes),
            sum: Batch::zeros(components, lanes),
        }
    }

    /// `x ← x + dt/6 · (k1 + 2 k2 + 2 k3 + k4)` with the actuation held over the step; each
    /// slope is folded into the running sum in the same pass that builds the next stage.
    fn step(&mut self, model: &dyn Dynamics, state: &mut Batch, actuation: &Batch, dt: f32) {
        model.derivative(state, actuation, &mut self.slope);
        for (first, advance) in [(true, 0.5 * dt), (false, 0.5 * dt), (false, dt)] {
            for ((stage, sum), (&x, &k)) in self
                .stage
                .as_mut_slice()
                .iter_mut()
                .zip(self.sum.as_mut_slice())
                .zip(state.as_slice().iter().zip(self.slope.as_slice()))
            {
                // The first slope starts the sum (weight 1) instead of a separate zeroing pass.
                *sum = if first { k } else { *sum + 2.0 * k };
                *stage = x + advance * k;
            }
            model.derivative(&self.stage, actuation, &mut self.slope);
        }
        for (x, (&sum, &k)) in state
            .as_mut_slice()
            .iter_mut()
            .zip(self.sum.as_slice().iter().zip(self.slope.as_slice()))
        {
            *x += dt / 6.0 * (sum + k);
        }
        model.renormalize(state);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::point_mass::PointMass;
    use crate::model::quadrotor::Quadrotor;
    use crate::model::urdf::RobotDescription;
    use crate::model::CommandAxes;
    use crate::occupancy::{OccupancyOptions, Scan, UnknownSpace};
    use crate::sampling::{sample, SamplerKind};
    use nalgebra::{UnitQuaternion, Vector3};

    fn open_space() -> Occupancy {
        let scan = Scan {
            angle_min: -std::f64::consts::PI,
            angle_increment: std::f64::consts::PI / 180.0,
            range_min: 0.05,
            range_max: 10.0,
            ranges: vec![f32::INFINITY; 360],
        };
        Occupancy::build(
            &scan,
            &UnitQuaternion::identity(),
            1.0,
            &optimistic_options(),
        )
    }

    /// A 5 cm robot for which unseen space is free.
    fn optimistic_options() -> OccupancyOptions {
        OccupancyOptions {
            robot_radius: 0.05,
            robot_height: 0.0,
            unknown_space: UnknownSpace::Free,
            floor: None,
            ceiling: None,
        }
    }

    #[test]
    fn constant_acceleration_lands_where_kinematics_says() {
        // Bang-bang lanes that never switch hold ±A all the way: x(T) = v T ± A T² / 2.
        let model = PointMass::new(2.0, 0.05, 0.0);
        let controls = sample(SamplerKind::BangBang, 300, 50, CommandAxes::Planar, 3);
        let start =
            RobotState::at_rest(Vector3::zeros()).with_velocity(Vector3::new(0.5, -1.0, 0.0));
        let rollout = roll_out(&model, &start, &controls, 1.0, &open_space());
        let mut checked = 0;
        for lane in 0..300 {
            let constant = (1..50).all(|k| {
                controls.get(k, 0, lane) == controls.get(0, 0, lane)
                    && controls.get(k, 1, lane) == controls.get(0, 1, lane)
            });
            if constant {
                let [ax, ay] = [0, 1].map(|a| 2.0 * controls.get(0, a, lane) as f64);
                let end = rollout.endpoints[lane];
                assert!((end[0] - (0.5 + ax / 2.0)).abs() < 1e-5, "{end:?}");
                assert!((end[1] - (-1.0 + ay / 2.0)).abs() < 1e-5, "{end:?}");
                checked += 1;
            }
        }
        assert!(checked > 5, "only {checked} constant lanes");
        assert_eq!(rollout.num_colliding(), 0);
    }

    #[test]
    fn a_trajectory_that_crosses_a_wall_and_comes_back_is_terminal() {
        // Wall 0.5 m ahead; a lane that accelerates at it and then reverses ends near the start
        // but crossed the wall on the way.
        let mut ranges = vec![f32::INFINITY; 360];
        for (i, r) in ranges.iter_mut().enumerate() {
            let a = -std::f64::consts::PI + i as f64 * std::f64::consts::PI / 180.0;
            if a.cos() > 0.0 {
                *r = (0.5 / a.cos()) as f32;
            }
        }
        let scan = Scan {
            angle_min: -std::f64::consts::PI,
            angle_increment: std::f64::consts::PI / 180.0,
            range_min: 0.05,
            range_max: 100.0,
            ranges,
        };
        let occupancy = Occupancy::build(
            &scan,
            &UnitQuaternion::identity(),
            1.0,
            &optimistic_options(),
        );
        let model = PointMass::new(4.0, 0.05, 0.0);
        let controls = sample(SamplerKind::BangBang, 500, 100, CommandAxes::Planar, 9);
        let rollout = roll_out(
            &model,
            &RobotState::at_rest(Vector3::zeros()),
            &controls,
            1.0,
            &occupancy,
        );
        let mut crossed_and_returned = 0;
        for lane in 0..500 {
            let end = rollout.endpoints[lane];
            if end[0] > 0.45 {
                assert!(rollout.terminal[lane], "lane {lane} ends beyond the wall");
            }
            // Peak x along the path, from the same controls integrated exactly.
            let (mut x, mut v, mut peak) = (0.0f64, 0.0f64, 0.0f64);
            for k in 0..100 {
                let a = 4.0 * controls.get(k, 0, lane) as f64;
                x += v * 0.01 + 0.5 * a * 1e-4;
                v += a * 0.01;
                peak = peak.max(x);
            }
            if peak > 0.5 && end[0] < 0.4 {
                assert!(
                    rollout.terminal[lane],
                    "lane {lane} crossed the wall and came back"
                );
                crossed_and_returned += 1;
            }
            if peak < 0.4 {
                assert!(!rollout.terminal[lane] || end[1].abs() > 2.0, "lane {lane}");
            }
        }
        assert!(crossed_and_returned > 0);
    }

    #[test]
    fn the_quadrotors_fused_rk4_matches_the_generic_one_bit_for_bit() {
        let description =
            RobotDescription::from_str(crate::parameters::BUILTIN_URDF, "built-in cf2x.urdf")
                .unwrap();
        let model = Quadrotor::new(&description, None);
        let start = RobotState::at_rest(Vector3::zeros())
            .with_velocity(Vector3::new(0.8, -1.5, 0.3))
            .with_attitude(UnitQuaternion::from_euler_angles(0.3, -0.2, 1.0));
        // Fewer lanes than one chunk, and whole chunks with a partial one after them.
        for lanes in [20, 70] {
            let steps = 40;
            let controls = sample(SamplerKind::Fourier, lanes, steps, CommandAxes::Spatial, 4);
            let mut generic = Batch::zeros(model.state_components(), lanes);
            model.initial_state(&start, &mut generic);
            let mut fused = generic.clone();
            let mut actuation = Batch::zeros(model.actuation_components(), lanes);
            let mut rk4 = Rk4::new(model.state_components(), lanes);
            for k in 0..steps {
                model.actuate(
                    &generic,
                    controls.at_step(k),
                    CommandAxes::Spatial,
                    &mut actuation,
                );
                rk4.step(&model, &mut generic, &actuation, 0.01);
                assert!(model.integrate(&mut fused, &actuation, 0.01));
                let same = generic
                    .as_slice()
                    .iter()
                    .zip(fused.as_slice())
                    .all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "{lanes} lanes, step {k}");
            }
        }
    }

    #[test]
    fn blocks_and_threads_do_not_change_the_result() {
        let model = PointMass::new(3.0, 0.05, 0.0);
        let controls = sample(SamplerKind::Fourier, 1000, 40, CommandAxes::Spatial, 5);
        let start = RobotState::at_rest(Vector3::zeros());
        let parallel = roll_out(&model, &start, &controls, 1.0, &open_space());
        let single = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| roll_out(&model, &start, &controls, 1.0, &open_space()));
        assert_eq!(parallel, single);
    }
}
