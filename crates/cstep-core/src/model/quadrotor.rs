//! A 6-DoF quadrotor (X configuration) built from a [`RobotDescription`]: rigid-body dynamics
//! driven by four rotor speeds, and the cascaded controller that turns C-STEP's normalised
//! acceleration commands into those rotor speeds.
//!
//! The controller runs once per integration step and reads only the current state: desired
//! world-frame acceleration (command × [`Quadrotor::max_acceleration`]; altitude hold on z for
//! [`CommandAxes::Planar`]) → speed governor → feasible specific force (tilt ≤ 60.4°, at most
//! [`THRUST_HEADROOM`] of the maximum thrust, vertical first) → collective thrust and desired
//! body z axis → PD attitude torques (ω_n = 25 rad/s, ζ = 0.8) with yaw-rate damping → X mixer
//! with attitude priority → rotor speeds clamped to `[0, max_rpm]`. The design and gains are
//! documented in `src/model/quadrotor/controller.rs`.
//!
//! State, per lane (f32, component-major in a [`Batch`]):
//!
//! | components | meaning |
//! |---|---|
//! | 0–2 ([`POSITION_COMPONENTS`]) | position relative to the start, world frame, m |
//! | 3–5 ([`VELOCITY`]) | velocity, world frame, m/s |
//! | 6–9 ([`ATTITUDE`]) | attitude quaternion (w, x, y, z), body → world |
//! | 10–12 ([`BODY_RATES`]) | angular velocity, body frame, rad/s |
//!
//! The actuation held over one integration step ([`ACTUATION_COMPONENTS`] per lane) is the four
//! rotor speeds in rpm ([`MOTOR_SPEEDS`]), saturated to `[0, max_rpm]` so every rollout respects
//! the actuator limits, followed by what they produce — collective thrust ([`THRUST`]), body
//! torques ([`TORQUE`]) and the rotor-speed sum that scales the drag ([`ROTOR_SPEED_SUM`]) —
//! computed once per step from the clamped speeds so the four derivative evaluations of an RK4
//! step need not redo it. [`Quadrotor::actuation_for_motor_speeds`] fills an actuation from
//! given rotor speeds (open-loop experiments, tests).
//!
//! Rotor layout (body x forward, y left, z up), arm length `L`, `d = L/√2`:
//!
//! | rotor | position | spin (seen from above) | yaw reaction torque |
//! |---|---|---|---|
//! | 0 | front-right (+d, −d) | clockwise | +km·ω² |
//! | 1 | rear-right (−d, −d) | counter-clockwise | −km·ω² |
//! | 2 | rear-left (−d, +d) | clockwise | +km·ω² |
//! | 3 | front-left (+d, +d) | counter-clockwise | −km·ω² |
//!
//! Equations of motion: thrust kf·ω² per rotor along body z; roll/pitch torques from the rotor
//! positions; Euler's equations J·ω̇ = τ − ω × Jω with the diagonal inertia; gravity; and the
//! gym-pybullet-drones drag model, evaluated in the body frame: F_drag = −c ∘ (Σ ω_i in rad/s) ∘
//! v_body, rotated back to the world frame. With equal x and y coefficients (a multirotor is
//! symmetric about its z axis; the URDF has one horizontal coefficient) this is exactly
//! `−Σω · (c_xy·v + (c_z − c_xy)·(b₃·v)·b₃)` with b₃ the body z axis, which needs no full
//! rotation; the model uses the mean of the x and y coefficients. Ground effect is not modelled
//! (rollouts know no floor distance).

mod controller;

use crate::model::urdf::{RobotDescription, RPM_TO_RAD_PER_S};
use crate::model::{Batch, CommandAxes, Dynamics, POSITION_COMPONENTS};
use crate::state::RobotState;

/// State components holding the world-frame velocity, m/s.
pub const VELOCITY: [usize; 3] = [3, 4, 5];
/// State components holding the attitude quaternion (w, x, y, z), body → world.
pub const ATTITUDE: [usize; 4] = [6, 7, 8, 9];
/// State components holding the body-frame angular velocity, rad/s.
pub const BODY_RATES: [usize; 3] = [10, 11, 12];
/// Number of state components per lane.
pub const STATE_COMPONENTS: usize = 13;
/// Actuation components holding the speeds of rotors 0–3, rpm (see the module docs for the
/// layout).
pub const MOTOR_SPEEDS: [usize; 4] = [0, 1, 2, 3];
/// Actuation component holding the collective thrust of the four rotors, N.
pub const THRUST: usize = 4;
/// Actuation components holding the body-frame torques (roll, pitch, yaw), N·m.
pub const TORQUE: [usize; 3] = [5, 6, 7];
/// Actuation component holding the sum of the four rotor speeds, rad/s (scales the drag).
pub const ROTOR_SPEED_SUM: usize = 8;
/// Number of actuation components per lane.
pub const ACTUATION_COMPONENTS: usize = 9;

// `initial_state` and the lane loops rely on this layout.
const _: () = assert!(
    POSITION_COMPONENTS[0] == 0
        && POSITION_COMPONENTS[1] == 1
        && POSITION_COMPONENTS[2] == 2
        && VELOCITY[0] == 3
        && ATTITUDE[0] == 6
        && BODY_RATES[0] == 10
        && BODY_RATES[2] == STATE_COMPONENTS - 1
        && THRUST == 4
        && TORQUE[0] == 5
        && ROTOR_SPEED_SUM == ACTUATION_COMPONENTS - 1
);

/// Share of the maximum thrust the controller plans with; the rest is headroom for attitude
/// control. It also fixes the derived acceleration bound and the tilt limit.
pub const THRUST_HEADROOM: f64 = 0.9;

/// A quadrotor whose rigid-body dynamics and actuator limits come from a URDF.
#[derive(Debug, Clone)]
pub struct Quadrotor {
    description: RobotDescription,
    max_acceleration: f64,
    physics: Physics,
    rotors: Rotors,
    control: controller::Controller,
}

/// The rotors: rotor speeds → thrust, torques and speed sum, as f32 for the lane loops.
#[derive(Debug, Clone, Copy)]
struct Rotors {
    /// Thrust coefficient, N/rpm².
    kf: f32,
    /// kf · L/√2: roll/pitch torque per rpm² of one rotor, N·m/rpm².
    kf_lever: f32,
    /// Yaw reaction torque coefficient, N·m/rpm².
    km: f32,
    /// rpm → rad/s.
    rpm_to_rad: f32,
    /// Highest rotor speed, rpm.
    max_rpm: f32,
}

impl Rotors {
    fn new(desc: &RobotDescription) -> Self {
        Self {
            kf: desc.kf as f32,
            kf_lever: (desc.kf * desc.arm / std::f64::consts::SQRT_2) as f32,
            km: desc.km as f32,
            rpm_to_rad: RPM_TO_RAD_PER_S as f32,
            max_rpm: desc.max_rpm() as f32,
        }
    }

    /// Collective thrust (N), roll, pitch and yaw torques (N·m) and rotor-speed sum (rad/s)
    /// produced by rotor speeds `u` (rpm): the actuation components after [`MOTOR_SPEEDS`].
    #[inline(always)]
    fn wrench(&self, [u0, u1, u2, u3]: [f32; 4]) -> [f32; 5] {
        let (s0, s1, s2, s3) = (u0 * u0, u1 * u1, u2 * u2, u3 * u3);
        [
            self.kf * (s0 + s1 + s2 + s3),
            self.kf_lever * ((s2 + s3) - (s0 + s1)),
            self.kf_lever * ((s1 + s2) - (s0 + s3)),
            self.km * ((s0 + s2) - (s1 + s3)),
            self.rpm_to_rad * (u0 + u1 + u2 + u3),
        ]
    }
}

/// The rigid-body constants of the equations of motion, as f32 for the lane loops.
#[derive(Debug, Clone, Copy)]
struct Physics {
    inv_mass: f32,
    gravity: f32,
    /// Horizontal drag coefficient (mean of x and y) and the vertical excess c_z − c_xy.
    drag_xy: f32,
    drag_z_excess: f32,
    /// Principal moments of inertia (x, y, z) and their inverses.
    inertia: [f32; 3],
    inv_inertia: [f32; 3],
}

impl Quadrotor {
    /// Builds the model from a validated description.
    ///
    /// `max_acceleration` scales the normalised commands (m/s² per axis). `None` derives it
    /// from the URDF: the largest horizontal acceleration the robot sustains while holding its
    /// altitude with [`THRUST_HEADROOM`] of its maximum thrust, `g·√((0.9·t/w)² − 1)` —
    /// 17.26 m/s² for the Crazyflie 2.x (thrust-to-weight 2.25), at a tilt of 60.4°. `Some(a)`
    /// uses `a`; the rollouts stay physically saturated either way.
    ///
    /// # Panics
    /// If `max_acceleration` is `Some` of a value that is not finite and positive.
    pub fn new(desc: &RobotDescription, max_acceleration: Option<f64>) -> Self {
        let horizontal_limit = derived_max_acceleration(desc);
        let max_acceleration = match max_acceleration {
            Some(a) => {
                assert!(
                    a.is_finite() && a > 0.0,
                    "max_acceleration must be finite and positive, got {a}"
                );
                a
            }
            None => horizontal_limit,
        };
        let drag = desc.drag_coefficients;
        let drag_xy = 0.5 * (drag.x + drag.y);
        let physics = Physics {
            inv_mass: (1.0 / desc.mass) as f32,
            gravity: desc.gravity as f32,
            drag_xy: drag_xy as f32,
            drag_z_excess: (drag.z - drag_xy) as f32,
            inertia: desc.inertia.map(|j| j as f32).into(),
            inv_inertia: desc.inertia.map(|j| (1.0 / j) as f32).into(),
        };
        let rotors = Rotors::new(desc);
        Self {
            description: desc.clone(),
            max_acceleration,
            physics,
            rotors,
            control: controller::Controller::new(desc, rotors, max_acceleration, horizontal_limit),
        }
    }

    /// The bound that scales the normalised commands, m/s² per axis.
    pub fn max_acceleration(&self) -> f64 {
        self.max_acceleration
    }

    /// The description this model was built from.
    pub fn description(&self) -> &RobotDescription {
        &self.description
    }

    /// Fills every lane of `actuation` with rotor speeds `rpm` (clamped to `[0, max_rpm]`)
    /// and the thrust, torques and speed sum they produce: open-loop actuation for experiments
    /// and tests, bypassing the controller.
    pub fn actuation_for_motor_speeds(&self, rpm: [f32; 4], actuation: &mut Batch) {
        let rpm = rpm.map(|u| u.clamp(0.0, self.rotors.max_rpm));
        let wrench = self.rotors.wrench(rpm);
        for (c, value) in rpm.into_iter().chain(wrench).enumerate() {
            actuation.fill_component(c, value);
        }
    }
}

/// Actuation components the equations of motion read: collective thrust, the three body
/// torques and the rotor-speed sum ([`THRUST`] to [`ROTOR_SPEED_SUM`]).
const WRENCH: usize = ACTUATION_COMPONENTS - THRUST;

/// One [`CHUNK`]-lane block of an RK4 step: the state and held wrench (thrust, torques,
/// rotor-speed sum) of its lanes, and the scratch — the stage state, the latest slope and the
/// running weighted sum of slopes. Local fixed-size arrays alias nothing, so the loops over
/// them compile to straight SIMD code.
struct Rk4Chunk {
    x: [[f32; CHUNK]; STATE_COMPONENTS],
    wrench: [[f32; CHUNK]; WRENCH],
    stage: [[f32; CHUNK]; STATE_COMPONENTS],
    slope: [[f32; CHUNK]; STATE_COMPONENTS],
    sum: [[f32; CHUNK]; STATE_COMPONENTS],
}

impl Default for Rk4Chunk {
    fn default() -> Self {
        let zeros = [[0.0; CHUNK]; STATE_COMPONENTS];
        Self {
            x: zeros,
            wrench: [[0.0; CHUNK]; WRENCH],
            stage: zeros,
            slope: zeros,
            sum: zeros,
        }
    }
}

impl Quadrotor {
    /// The equations of motion for one block of [`CHUNK`] lanes: the state `x` (all
    /// [`STATE_COMPONENTS`]) under the held `wrench` (thrust, torques, rotor-speed sum) gives
    /// the time derivative `out`. See the module docs for the model.
    #[inline(always)]
    fn slope(
        &self,
        x: &[[f32; CHUNK]; STATE_COMPONENTS],
        wrench: &[[f32; CHUNK]; WRENCH],
        out: &mut [[f32; CHUNK]; STATE_COMPONENTS],
    ) {
        let Physics {
            inv_mass,
            gravity,
            drag_xy,
            drag_z_excess,
            inertia: [jx, jy, jz],
            inv_inertia: [ix, iy, iz],
        } = self.physics;
        let [_, _, _, vx, vy, vz, qw, qx, qy, qz, wx, wy, wz] = x;
        let [thrust, tau_x, tau_y, tau_z, rotor_sum] = wrench;
        let [dpx, dpy, dpz, dvx, dvy, dvz, dqw, dqx, dqy, dqz, dwx, dwy, dwz] = out;
        for i in 0..CHUNK {
            // Body z axis in the world frame (third column of the rotation matrix).
            let (w, x, y, z) = (qw[i], qx[i], qy[i], qz[i]);
            let (x2, y2) = (x + x, y + y);
            let bx = x2 * z + y2 * w;
            let by = y2 * z - x2 * w;
            let bz = 1.0 - (x2 * x + y2 * y);

            // Thrust along b₃; drag −Σω·(c_xy·v + (c_z − c_xy)·(b₃·v)·b₃).
            let (v0, v1, v2) = (vx[i], vy[i], vz[i]);
            let along = thrust[i] - drag_z_excess * rotor_sum[i] * (bx * v0 + by * v1 + bz * v2);
            let damping = drag_xy * rotor_sum[i];
            dpx[i] = v0;
            dpy[i] = v1;
            dpz[i] = v2;
            dvx[i] = (along * bx - damping * v0) * inv_mass;
            dvy[i] = (along * by - damping * v1) * inv_mass;
            dvz[i] = (along * bz - damping * v2) * inv_mass - gravity;

            // q̇ = ½ q ⊗ (0, ω).
            let (p, q, r) = (wx[i], wy[i], wz[i]);
            dqw[i] = -0.5 * (x * p + y * q + z * r);
            dqx[i] = 0.5 * (w * p + y * r - z * q);
            dqy[i] = 0.5 * (w * q + z * p - x * r);
            dqz[i] = 0.5 * (w * r + x * q - y * p);

            // Euler's equations with the diagonal inertia.
            dwx[i] = (tau_x[i] - (jz - jy) * q * r) * ix;
            dwy[i] = (tau_y[i] - (jx - jz) * r * p) * iy;
            dwz[i] = (tau_z[i] - (jy - jx) * p * q) * iz;
        }
    }

    /// One RK4 step of length `dt` for one block of lanes, in place, then the quaternion
    /// renormalised: `x ← x + dt/6 · (k1 + 2 k2 + 2 k3 + k4)`, each slope folded into the sum
    /// as the next stage is built — the rollout's generic RK4 and [`Dynamics::renormalize`],
    /// operation for operation, so the result is bit-identical.
    #[inline(always)]
    fn rk4_chunk(&self, chunk: &mut Rk4Chunk, dt: f32) {
        let Rk4Chunk {
            x,
            wrench,
            stage,
            slope,
            sum,
        } = chunk;
        let half = 0.5 * dt;
        // The per-component loops run over the flattened blocks: one contiguous loop that
        // vectorises along memory (nested loops over components and lanes got vectorised
        // across components, with gathers).
        self.slope(x, wrench, slope);
        for ((sum, stage), (&x, &k)) in sum
            .as_flattened_mut()
            .iter_mut()
            .zip(stage.as_flattened_mut())
            .zip(x.as_flattened().iter().zip(slope.as_flattened()))
        {
            *sum = k;
            *stage = x + half * k;
        }
        for advance in [half, dt] {
            self.slope(stage, wrench, slope);
            for ((sum, stage), (&x, &k)) in sum
                .as_flattened_mut()
                .iter_mut()
                .zip(stage.as_flattened_mut())
                .zip(x.as_flattened().iter().zip(slope.as_flattened()))
            {
                *sum += 2.0 * k;
                *stage = x + advance * k;
            }
        }
        self.slope(stage, wrench, slope);
        for (x, (&sum, &k)) in x
            .as_flattened_mut()
            .iter_mut()
            .zip(sum.as_flattened().iter().zip(slope.as_flattened()))
        {
            *x += dt / 6.0 * (sum + k);
        }
        let [_, _, _, _, _, _, qw, qx, qy, qz, _, _, _] = x;
        for i in 0..CHUNK {
            [qw[i], qx[i], qy[i], qz[i]] = normalized([qw[i], qx[i], qy[i], qz[i]]);
        }
    }
}

impl Quadrotor {
    /// [`Quadrotor::rk4_chunk`] for the `width` (at most [`CHUNK`]) lanes from `start` of the
    /// component-major `state` and `wrench` (the actuation from [`THRUST`] on), copied into the
    /// scratch chunk and back.
    /// With fewer lanes than a chunk, the chunk's other lanes hold what an earlier call left
    /// there (or zeros) and are integrated along and dropped: lanes are independent, so the
    /// lanes kept see the same arithmetic.
    #[inline(always)]
    fn rk4_lanes(
        &self,
        state: &mut [f32],
        wrench: &[f32],
        start: usize,
        width: usize,
        dt: f32,
        scratch: &mut Rk4Chunk,
    ) {
        let n = state.len() / STATE_COMPONENTS;
        for (c, x) in scratch.x.iter_mut().enumerate() {
            x[..width].copy_from_slice(&state[c * n + start..][..width]);
        }
        for (c, w) in scratch.wrench.iter_mut().enumerate() {
            w[..width].copy_from_slice(&wrench[c * n + start..][..width]);
        }
        self.rk4_chunk(scratch, dt);
        for (c, x) in scratch.x.iter().enumerate() {
            state[c * n + start..][..width].copy_from_slice(&x[..width]);
        }
    }
}

/// The quaternion `q` scaled to unit length (after each step, against the drift of
/// integrating `q̇`).
#[inline(always)]
fn normalized(q: [f32; 4]) -> [f32; 4] {
    let [w, x, y, z] = q;
    let inv = 1.0 / (w * w + x * x + y * y + z * z).sqrt();
    [w * inv, x * inv, y * inv, z * inv]
}

/// The largest horizontal acceleration sustainable at constant altitude with
/// [`THRUST_HEADROOM`] of the maximum thrust, m/s² (zero if that thrust cannot carry the weight).
fn derived_max_acceleration(desc: &RobotDescription) -> f64 {
    let specific_thrust = THRUST_HEADROOM * desc.thrust_to_weight * desc.gravity;
    (specific_thrust.powi(2) - desc.gravity.powi(2))
        .max(0.0)
        .sqrt()
}

/// The first `K` components of `batch`, each exactly `lanes` long.
fn components<const K: usize>(batch: &Batch) -> [&[f32]; K] {
    let lanes = batch.lanes();
    assert!(batch.components() >= K, "batch has too few components");
    let mut chunks = batch.as_slice().chunks_exact(lanes);
    std::array::from_fn(|_| chunks.next().expect("component count checked above"))
}

/// The first `K` components of `batch`, mutably, each exactly `lanes` long.
fn components_mut<const K: usize>(batch: &mut Batch) -> [&mut [f32]; K] {
    let lanes = batch.lanes();
    assert!(batch.components() >= K, "batch has too few components");
    let mut chunks = batch.as_mut_slice().chunks_exact_mut(lanes);
    std::array::from_fn(|_| chunks.next().expect("component count checked above"))
}

/// The larger of `a` and `b` (`b` if either is NaN): one SIMD `max` instruction, where
/// [`f32::max`]'s NaN rules cost a compare and a blend more per call.
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// The smaller of `a` and `b` (`b` if either is NaN): one SIMD `min` instruction.
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// `value` limited to `[low, high]` (`low` if `value` is NaN), with [`max`] and [`min`].
#[inline(always)]
fn clamp(value: f32, low: f32, high: f32) -> f32 {
    min(max(value, low), high)
}

/// Lanes per kernel call: a few SIMD registers' worth, so the per-chunk bookkeeping is spread
/// over enough lanes while the chunk's outputs stay in L1.
const CHUNK: usize = 32;

/// Runs `kernel` over the first `n` lanes of `inputs`, [`CHUNK`] lanes at a time, and writes
/// its results to `outputs`.
///
/// A plain `for i in 0..n` loop over a dozen input and output slices does not vectorise: the
/// compiler cannot prove the output slices (carved out of one buffer) disjoint from the inputs,
/// and the runtime overlap checks it would need exceed its budget. The kernel instead writes to
/// a local fixed-size buffer, which provably aliases nothing, and reads fixed-size input
/// chunks, so its per-lane loop becomes straight SIMD code. A partial last chunk is computed
/// as the last full chunk (overlapping the previous one; the kernel is per-lane, so the
/// overlap is rewritten with identical values), or, with fewer than [`CHUNK`] lanes in all,
/// from zero-padded copies whose padded results are discarded.
#[inline(always)]
fn chunked<const I: usize, const O: usize>(
    n: usize,
    inputs: [&[f32]; I],
    mut outputs: [&mut [f32]; O],
    kernel: impl Fn([&[f32; CHUNK]; I], &mut [[f32; CHUNK]; O]),
) {
    let mut buffer = [[0.0; CHUNK]; O];
    if n < CHUNK {
        let mut padded = [[0.0; CHUNK]; I];
        for (dst, src) in padded.iter_mut().zip(&inputs) {
            dst[..n].copy_from_slice(&src[..n]);
        }
        kernel(padded.each_ref(), &mut buffer);
        for (dst, src) in outputs.iter_mut().zip(&buffer) {
            dst[..n].copy_from_slice(&src[..n]);
        }
        return;
    }
    let mut start = 0;
    loop {
        let chunk = inputs.map(|s| {
            s[start..start + CHUNK]
                .try_into()
                .expect("slice of CHUNK lanes")
        });
        kernel(chunk, &mut buffer);
        for (dst, src) in outputs.iter_mut().zip(&buffer) {
            dst[start..start + CHUNK].copy_from_slice(src);
        }
        if start + CHUNK == n {
            return;
        }
        start = (start + CHUNK).min(n - CHUNK);
    }
}

impl Dynamics for Quadrotor {
    fn name(&self) -> &'static str {
        "quadrotor"
    }

    fn state_components(&self) -> usize {
        STATE_COMPONENTS
    }

    fn actuation_components(&self) -> usize {
        ACTUATION_COMPONENTS
    }

    fn initial_state(&self, state: &RobotState, batch: &mut Batch) {
        let q = state.attitude.quaternion();
        let values = [
            0.0,
            0.0,
            0.0,
            state.velocity.x,
            state.velocity.y,
            state.velocity.z,
            q.w,
            q.i,
            q.j,
            q.k,
            state.body_rates.x,
            state.body_rates.y,
            state.body_rates.z,
        ];
        for (c, value) in values.into_iter().enumerate() {
            batch.fill_component(c, value as f32);
        }
    }

    fn actuate(&self, state: &Batch, commands: &[f32], axes: CommandAxes, actuation: &mut Batch) {
        self.control.actuate(state, commands, axes, actuation);
    }

    fn derivative(&self, state: &Batch, actuation: &Batch, out: &mut Batch) {
        let n = state.lanes();
        if n == 0 {
            return;
        }
        let x = components::<STATE_COMPONENTS>(state);
        let [_, _, _, _, thrust, tau_x, tau_y, tau_z, rotor_sum] =
            components::<ACTUATION_COMPONENTS>(actuation);
        let wrench = [thrust, tau_x, tau_y, tau_z, rotor_sum];
        let inputs: [&[f32]; STATE_COMPONENTS + WRENCH] = std::array::from_fn(|c| {
            if c < STATE_COMPONENTS {
                x[c]
            } else {
                wrench[c - STATE_COMPONENTS]
            }
        });
        chunked(
            n,
            inputs,
            components_mut::<STATE_COMPONENTS>(out),
            |inp, out| {
                self.slope(
                    &std::array::from_fn(|c| *inp[c]),
                    &std::array::from_fn(|c| *inp[STATE_COMPONENTS + c]),
                    out,
                )
            },
        );
    }

    /// Classic RK4 (the rollout's scheme, bit for bit: the same operations in the same order)
    /// fused over `CHUNK`-lane blocks: each block's state, stages, slopes and running sum stay
    /// in local arrays through all four slope evaluations and the renormalisation, instead of
    /// passing over the whole batch about a dozen times per step.
    fn integrate(&self, state: &mut Batch, actuation: &Batch, dt: f32) -> bool {
        let n = state.lanes();
        // Component `c` of lane `i` is at `c * n + i` in both batches (component-major).
        let (state, wrench) = (state.as_mut_slice(), &actuation.as_slice()[THRUST * n..]);
        let mut scratch = Rk4Chunk::default();
        for start in (0..n).step_by(CHUNK) {
            // Whole chunks pass a constant width, so that their copies in and out compile to
            // inline moves rather than `memcpy` calls.
            match n - start {
                width if width >= CHUNK => {
                    self.rk4_lanes(state, wrench, start, CHUNK, dt, &mut scratch)
                }
                width => self.rk4_lanes(state, wrench, start, width, dt, &mut scratch),
            }
        }
        true
    }

    fn renormalize(&self, state: &mut Batch) {
        let n = state.lanes();
        if n == 0 {
            return;
        }
        let [_, _, _, _, _, _, qw, qx, qy, qz] = components_mut::<10>(state);
        for i in 0..n {
            [qw[i], qx[i], qy[i], qz[i]] = normalized([qw[i], qx[i], qy[i], qz[i]]);
        }
    }

    fn collision_radius(&self) -> f64 {
        self.description.collision_radius
    }

    fn collision_height(&self) -> f64 {
        self.description.collision_height
    }
}
