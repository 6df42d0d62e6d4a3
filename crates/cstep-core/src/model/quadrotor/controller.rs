//! The quadrotor's flight controller: normalised world-frame acceleration commands in, four
//! saturated rotor speeds out. It runs once per integration step and is stateless (it reads only
//! the current state), so rollouts are deterministic; its output is held over the step.
//!
//! The cascade, per lane:
//!
//! 1. **Desired acceleration** `a = command × max_acceleration` per axis. With
//!    [`CommandAxes::Planar`] the z component is an altitude-hold PD loop on the height relative
//!    to the start (ω = 5 rad/s, ζ = 1: `a_z = −25·z − 10·v_z`).
//! 2. **Speed governor**: the component of `a` along the velocity is capped at
//!    `8 s⁻¹ × (max_speed − speed)` (zero at or above the URDF's maximum speed), so the speed
//!    approaches the limit smoothly (overshoot < 1 %) instead of overshooting it; the excess is
//!    removed, braking and turning are never touched. For the Crazyflie (8.33 m/s) the full
//!    17.3 m/s² is available along the velocity up to 6.2 m/s.
//! 3. **Desired specific force** `f = a + g·ẑ + drag compensation` (the drag at hover rotor
//!    speed, per world axis). It is then made feasible: the horizontal part is capped at the
//!    derived horizontal limit, the vertical part is raised if needed to keep the tilt within
//!    the altitude-holding tilt `θ_max = acos(1 / (0.9·t/w))` (60.4° for the Crazyflie), kept at
//!    least 0.1 % of g (the body z axis stays defined) and at most 90 % of the maximum
//!    specific thrust; the horizontal part then gets what thrust and tilt limits leave
//!    (vertical first: altitude safety before horizontal acceleration).
//! 4. **Collective thrust** `T = m·f·b₃` (projection on the current body z axis, so a drone
//!    still rotating towards the desired tilt does not throw itself sideways) and **desired body
//!    z axis** `f/|f|`.
//! 5. **Attitude**: reduced-attitude error `e = b₃ × b₃,des` in the body frame (roll and
//!    pitch), PD torques `τ = J·(k_p·e − k_d·ω)` with ω_n = 25 rad/s, ζ = 0.8
//!    (`k_p = 625 s⁻²`, `k_d = 40 s⁻¹`: tilt settles within ~0.2 s); yaw is held by damping the
//!    yaw rate (`τ_z = −10 s⁻¹ · J_z · r`): commands are in the world frame, so heading is free.
//! 6. **X mixer with attitude priority**: the per-rotor thrust differences for the torques are
//!    scaled down if their spread exceeds one rotor's maximum thrust, the collective share is
//!    moved into the range that keeps every rotor within `[0, max]`, and each rotor thrust is
//!    converted to rpm (`ω = √(f/kf)`) and clamped, so the rotor speeds never leave
//!    `[0, max_rpm]`.
//!
//! The lane loop is branch-free (min/max instead of `if`) and runs in [`CHUNK`]-lane blocks
//! ([`chunked`]) so it vectorises.

use super::{
    chunked, clamp, components, components_mut, max, min, Rotors, ACTUATION_COMPONENTS, CHUNK,
    STATE_COMPONENTS, THRUST_HEADROOM,
};
use crate::model::urdf::{RobotDescription, RPM_TO_RAD_PER_S};
use crate::model::{Batch, CommandAxes};

/// Attitude loop natural frequency, rad/s.
const ATTITUDE_FREQUENCY: f64 = 25.0;
/// Attitude loop damping ratio.
const ATTITUDE_DAMPING: f64 = 0.8;
/// Yaw-rate damping gain, 1/s.
const YAW_RATE_GAIN: f64 = 10.0;
/// Altitude-hold loop natural frequency, rad/s.
const ALTITUDE_FREQUENCY: f64 = 5.0;
/// Altitude-hold loop damping ratio.
const ALTITUDE_DAMPING: f64 = 1.0;
/// Speed-governor gain, 1/s: near the maximum speed the acceleration along the velocity is
/// at most this times the remaining speed margin (the speed closes in on the limit with a
/// 0.125-s time constant, slow enough for the attitude loop to follow: < 1 % overshoot; 10 s⁻¹
/// overshoots by 2 %).
const GOVERNOR_GAIN: f64 = 8.0;
/// Smallest vertical specific force the controller asks for, as a fraction of g.
const MIN_VERTICAL_FORCE: f64 = 1e-3;

/// The controller's constants, as f32 for the lane loops.
#[derive(Debug, Clone, Copy)]
pub(super) struct Controller {
    /// Command scale, m/s² per axis.
    max_acceleration: f32,
    gravity: f32,
    mass: f32,
    /// Altitude-hold gains (position, velocity).
    altitude_kp: f32,
    altitude_kd: f32,
    /// Maximum speed, m/s, and the governor's gain, 1/s.
    max_speed: f32,
    governor_gain: f32,
    /// Drag compensation per world axis: drag coefficient × hover rotor speed (rad/s) / mass.
    drag_compensation: [f32; 3],
    /// Largest horizontal specific force, m/s².
    horizontal_limit: f32,
    /// Largest specific thrust the controller plans with, m/s², and its square.
    force_limit: f32,
    force_limit_sq: f32,
    /// tan and cot of the tilt limit.
    tan_tilt: f32,
    cot_tilt: f32,
    /// Smallest vertical specific force, m/s².
    min_vertical: f32,
    /// Attitude gains and principal inertia.
    attitude_kp: f32,
    attitude_kd: f32,
    yaw_rate_gain: f32,
    inertia: [f32; 3],
    /// Mixer: 1 / (4 · arm/√2) and kf / (4 · km) turn torques into per-rotor thrust offsets.
    inv_four_lever: f32,
    inv_four_yaw_lever: f32,
    /// Maximum thrust of one rotor, N.
    max_motor_thrust: f32,
    /// 1 / kf, rpm²/N.
    inv_kf: f32,
    /// The rotor model: speed limit and rotor speeds → thrust and torques.
    rotors: Rotors,
}

impl Controller {
    /// The controller for `desc` driving `rotors`, scaling commands by `max_acceleration`;
    /// `horizontal_limit` is the largest horizontal acceleration sustainable at constant
    /// altitude.
    pub(super) fn new(
        desc: &RobotDescription,
        rotors: Rotors,
        max_acceleration: f64,
        horizontal_limit: f64,
    ) -> Self {
        let g = desc.gravity;
        let force_limit = THRUST_HEADROOM * desc.thrust_to_weight * g;
        let tan_tilt = horizontal_limit / g;
        let hover_rotor_rad = 4.0 * desc.hover_rpm() * RPM_TO_RAD_PER_S;
        let lever = desc.arm / std::f64::consts::SQRT_2;
        Self {
            max_acceleration: max_acceleration as f32,
            gravity: g as f32,
            mass: desc.mass as f32,
            altitude_kp: ALTITUDE_FREQUENCY.powi(2) as f32,
            altitude_kd: (2.0 * ALTITUDE_DAMPING * ALTITUDE_FREQUENCY) as f32,
            max_speed: desc.max_speed as f32,
            governor_gain: GOVERNOR_GAIN as f32,
            drag_compensation: desc
                .drag_coefficients
                .map(|c| (c * hover_rotor_rad / desc.mass) as f32)
                .into(),
            horizontal_limit: horizontal_limit as f32,
            force_limit: force_limit as f32,
            force_limit_sq: (force_limit * force_limit) as f32,
            tan_tilt: tan_tilt as f32,
            cot_tilt: (1.0 / tan_tilt.max(1e-6)) as f32,
            min_vertical: (MIN_VERTICAL_FORCE * g) as f32,
            attitude_kp: ATTITUDE_FREQUENCY.powi(2) as f32,
            attitude_kd: (2.0 * ATTITUDE_DAMPING * ATTITUDE_FREQUENCY) as f32,
            yaw_rate_gain: YAW_RATE_GAIN as f32,
            inertia: desc.inertia.map(|j| j as f32).into(),
            inv_four_lever: (1.0 / (4.0 * lever)) as f32,
            inv_four_yaw_lever: (desc.kf / (4.0 * desc.km)) as f32,
            max_motor_thrust: desc.max_motor_thrust() as f32,
            inv_kf: (1.0 / desc.kf) as f32,
            rotors,
        }
    }

    /// Writes the rotor speeds (rpm) for `commands` into `actuation`, followed by the thrust,
    /// torques and rotor-speed sum they produce; see the module docs.
    pub(super) fn actuate(
        &self,
        state: &Batch,
        commands: &[f32],
        axes: CommandAxes,
        actuation: &mut Batch,
    ) {
        let n = state.lanes();
        if n == 0 {
            return;
        }
        assert!(
            commands.len() >= axes.count() * n,
            "expected {} command blocks of {n} lanes",
            axes.count()
        );
        match axes {
            CommandAxes::Planar => self.run::<false>(state, commands, actuation),
            CommandAxes::Spatial => self.run::<true>(state, commands, actuation),
        }
    }

    /// The lane loop; `SPATIAL` selects a commanded z acceleration over altitude hold.
    fn run<const SPATIAL: bool>(&self, state: &Batch, commands: &[f32], actuation: &mut Batch) {
        let n = state.lanes();
        let [_, _, pz, vx, vy, vz, qw, qx, qy, qz, wx, wy, wz] =
            components::<STATE_COMPONENTS>(state);
        let cx = &commands[..n];
        let cy = &commands[n..2 * n];
        // Planar rollouts read no z command; any block of the right length will do.
        let cz = if SPATIAL { &commands[2 * n..3 * n] } else { cx };
        let Self {
            max_acceleration,
            gravity,
            mass,
            altitude_kp,
            altitude_kd,
            max_speed,
            governor_gain,
            drag_compensation: [dcx, dcy, dcz],
            horizontal_limit,
            force_limit,
            force_limit_sq,
            tan_tilt,
            cot_tilt,
            min_vertical,
            attitude_kp,
            attitude_kd,
            yaw_rate_gain,
            inertia: [jx, jy, jz],
            inv_four_lever,
            inv_four_yaw_lever,
            max_motor_thrust,
            inv_kf,
            rotors,
        } = *self;
        let max_rpm = rotors.max_rpm;
        let inputs = [pz, vx, vy, vz, qw, qx, qy, qz, wx, wy, wz, cx, cy, cz];
        chunked(
            n,
            inputs,
            components_mut::<ACTUATION_COMPONENTS>(actuation),
            |inp, out| {
                let [pz, vx, vy, vz, qw, qx, qy, qz, wx, wy, wz, cx, cy, cz] = inp;
                let [m0, m1, m2, m3, thrust_out, tau_x_out, tau_y_out, tau_z_out, rotor_sum_out] =
                    out;
                for i in 0..CHUNK {
                    let (v0, v1, v2) = (vx[i], vy[i], vz[i]);

                    // 1. Desired acceleration.
                    let mut ax = clamp(cx[i], -1.0, 1.0) * max_acceleration;
                    let mut ay = clamp(cy[i], -1.0, 1.0) * max_acceleration;
                    let mut az = if SPATIAL {
                        clamp(cz[i], -1.0, 1.0) * max_acceleration
                    } else {
                        -altitude_kp * pz[i] - altitude_kd * v2
                    };

                    // 2. Speed governor: the acceleration along v may close at most the rate
                    //    governor_gain × (max_speed − speed); the excess is removed.
                    let speed = (v0 * v0 + v1 * v1 + v2 * v2).sqrt();
                    let inv_speed = 1.0 / max(speed, 1e-3);
                    let along = (ax * v0 + ay * v1 + az * v2) * inv_speed;
                    let allowed = governor_gain * max(max_speed - speed, 0.0);
                    let push = max(along - allowed, 0.0) * inv_speed;
                    ax -= push * v0;
                    ay -= push * v1;
                    az -= push * v2;

                    // 3. Desired specific force, made feasible (vertical first, tilt-limited).
                    let fx = ax + dcx * v0;
                    let fy = ay + dcy * v1;
                    let horizontal = (fx * fx + fy * fy).sqrt();
                    let tilt_floor = min(horizontal, horizontal_limit) * cot_tilt;
                    let fz = az + gravity + dcz * v2;
                    let fz = min(max(max(fz, tilt_floor), min_vertical), force_limit);
                    let horizontal_room =
                        min(max(force_limit_sq - fz * fz, 0.0).sqrt(), fz * tan_tilt);
                    let scale = min(horizontal_room / max(horizontal, 1e-6), 1.0);
                    let (fx, fy) = (fx * scale, fy * scale);
                    let inv_norm = 1.0 / (fx * fx + fy * fy + fz * fz).sqrt();
                    let (bx, by, bz) = (fx * inv_norm, fy * inv_norm, fz * inv_norm);

                    // Current body axes in the world frame (columns of the rotation matrix).
                    let (w, x, y, z) = (qw[i], qx[i], qy[i], qz[i]);
                    let (x2, y2, z2) = (x + x, y + y, z + z);
                    let (xx, yy, zz) = (x * x2, y * y2, z * z2);
                    let (xy, xz, yz) = (x * y2, x * z2, y * z2);
                    let (wxx, wyy, wzz) = (w * x2, w * y2, w * z2);
                    let (r11, r21, r31) = (1.0 - (yy + zz), xy + wzz, xz - wyy);
                    let (r12, r22, r32) = (xy - wzz, 1.0 - (xx + zz), yz + wxx);
                    let (r13, r23, r33) = (xz + wyy, yz - wxx, 1.0 - (xx + yy));

                    // 4. Collective thrust along the current body z axis.
                    let thrust = mass * (fx * r13 + fy * r23 + fz * r33);

                    // 5. Attitude: e = e₃ × (Rᵀ b₃,des) in the body frame, PD torques.
                    let err_x = -(r12 * bx + r22 * by + r32 * bz);
                    let err_y = r11 * bx + r21 * by + r31 * bz;
                    let tau_x = jx * (attitude_kp * err_x - attitude_kd * wx[i]);
                    let tau_y = jy * (attitude_kp * err_y - attitude_kd * wy[i]);
                    let tau_z = -jz * yaw_rate_gain * wz[i];

                    // 6. X mixer with attitude priority, rotor thrust clamped, converted to rpm.
                    let a = tau_x * inv_four_lever;
                    let b = tau_y * inv_four_lever;
                    let c = tau_z * inv_four_yaw_lever;
                    let (d0, d1, d2, d3) = (c - a - b, b - a - c, a + b + c, a - b - c);
                    let high = max(max(d0, d1), max(d2, d3));
                    let low = min(min(d0, d1), min(d2, d3));
                    let shrink = min(max_motor_thrust / max(high - low, 1e-12), 1.0);
                    let share = min(
                        max(0.25 * thrust, -low * shrink),
                        max_motor_thrust - high * shrink,
                    );
                    let rotor =
                        |d: f32| min((max(share + d * shrink, 0.0) * inv_kf).sqrt(), max_rpm);
                    let rpm = [rotor(d0), rotor(d1), rotor(d2), rotor(d3)];
                    [m0[i], m1[i], m2[i], m3[i]] = rpm;
                    [
                        thrust_out[i],
                        tau_x_out[i],
                        tau_y_out[i],
                        tau_z_out[i],
                        rotor_sum_out[i],
                    ] = rotors.wrench(rpm);
                }
            },
        );
    }
}
