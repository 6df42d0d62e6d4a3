//! The quadrotor model integrated with a local RK4 loop (the same scheme as the rollout
//! engine: `actuate` once per step, four `derivative` calls, `renormalize`).

use std::path::Path;
use std::time::Instant;

use approx::assert_relative_eq;
use cstep::model::quadrotor::{
    Quadrotor, ACTUATION_COMPONENTS, ATTITUDE, BODY_RATES, MOTOR_SPEEDS, ROTOR_SPEED_SUM,
    STATE_COMPONENTS, THRUST, TORQUE, VELOCITY,
};
use cstep::model::urdf::RobotDescription;
use cstep::model::{Batch, CommandAxes, Dynamics};
use cstep::state::RobotState;
use nalgebra::{UnitQuaternion, Vector3};

const G: f64 = 9.8;

fn description() -> RobotDescription {
    RobotDescription::load(Path::new("urdf/cf2x.urdf")).unwrap()
}

fn crazyflie() -> Quadrotor {
    Quadrotor::new(&description(), None)
}

/// `x + h·k`, written into `out`.
fn axpy(out: &mut Batch, x: &Batch, h: f32, k: &Batch) {
    for ((o, &a), &b) in out
        .as_mut_slice()
        .iter_mut()
        .zip(x.as_slice())
        .zip(k.as_slice())
    {
        *o = a + h * b;
    }
}

/// Scratch for one RK4 integration.
struct Rk4 {
    k: [Batch; 4],
    tmp: Batch,
}

impl Rk4 {
    fn new(lanes: usize) -> Self {
        Self {
            k: std::array::from_fn(|_| Batch::zeros(STATE_COMPONENTS, lanes)),
            tmp: Batch::zeros(STATE_COMPONENTS, lanes),
        }
    }

    /// One step of length `dt` under the held actuation `u`.
    fn step(&mut self, model: &Quadrotor, x: &mut Batch, u: &Batch, dt: f32) {
        let [k1, k2, k3, k4] = &mut self.k;
        model.derivative(x, u, k1);
        axpy(&mut self.tmp, x, 0.5 * dt, k1);
        model.derivative(&self.tmp, u, k2);
        axpy(&mut self.tmp, x, 0.5 * dt, k2);
        model.derivative(&self.tmp, u, k3);
        axpy(&mut self.tmp, x, dt, k3);
        model.derivative(&self.tmp, u, k4);
        let h = dt / 6.0;
        for ((((xi, &a), &b), &c), &d) in x
            .as_mut_slice()
            .iter_mut()
            .zip(k1.as_slice())
            .zip(k2.as_slice())
            .zip(k3.as_slice())
            .zip(k4.as_slice())
        {
            *xi += h * (a + 2.0 * (b + c) + d);
        }
        model.renormalize(x);
    }
}

/// Integrates `lanes` copies of `start` for `steps` steps of `dt` under constant commands
/// (axis-major, `axes.count()` blocks of `lanes`), calling `observe(step, state, actuation)`
/// after each step's actuation is computed (before the state is advanced). Returns the final
/// state.
fn simulate(
    model: &Quadrotor,
    start: &RobotState,
    commands: &[f32],
    axes: CommandAxes,
    dt: f32,
    steps: usize,
    mut observe: impl FnMut(usize, &Batch, &Batch),
) -> Batch {
    let lanes = commands.len() / axes.count();
    let mut x = Batch::zeros(STATE_COMPONENTS, lanes);
    let mut u = Batch::zeros(model.actuation_components(), lanes);
    let mut rk4 = Rk4::new(lanes);
    model.initial_state(start, &mut x);
    for step in 0..steps {
        model.actuate(&x, commands, axes, &mut u);
        observe(step, &x, &u);
        rk4.step(model, &mut x, &u, dt);
    }
    x
}

/// One-lane, 1-s, dt = 0.01 rollout; returns the final state as f64.
fn endpoint(model: &Quadrotor, start: &RobotState, command: &[f32], axes: CommandAxes) -> Lane {
    Lane::of(
        &simulate(model, start, command, axes, 0.01, 100, |_, _, _| {}),
        0,
    )
}

/// One lane of a state batch, as f64.
#[derive(Debug, Clone, Copy)]
struct Lane {
    p: Vector3<f64>,
    v: Vector3<f64>,
    q: UnitQuaternion<f64>,
    w: Vector3<f64>,
}

impl Lane {
    fn of(x: &Batch, lane: usize) -> Self {
        let c = |i: usize| f64::from(x.component(i)[lane]);
        Self {
            p: Vector3::new(c(0), c(1), c(2)),
            v: Vector3::new(c(VELOCITY[0]), c(VELOCITY[1]), c(VELOCITY[2])),
            q: UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                c(ATTITUDE[0]),
                c(ATTITUDE[1]),
                c(ATTITUDE[2]),
                c(ATTITUDE[3]),
            )),
            w: Vector3::new(c(BODY_RATES[0]), c(BODY_RATES[1]), c(BODY_RATES[2])),
        }
    }

    /// Angle between the body z axis and the world z axis, degrees.
    fn tilt_deg(&self) -> f64 {
        (self.q * Vector3::z())
            .z
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }
}

fn rest() -> RobotState {
    RobotState::at_rest(Vector3::new(1.0, -2.0, 1.0))
}

#[test]
fn model_metadata() {
    let model = crazyflie();
    assert_eq!(model.name(), "quadrotor");
    assert_eq!(model.state_components(), 13);
    assert_eq!(model.actuation_components(), ACTUATION_COMPONENTS);
    assert_relative_eq!(model.collision_radius(), 0.06, max_relative = 1e-12);
    assert_relative_eq!(model.collision_height(), 0.025, max_relative = 1e-12);
    assert_eq!(model.description(), &description());
}

#[test]
fn derived_max_acceleration_holds_altitude_with_headroom() {
    let model = crazyflie();
    // g·√((0.9 · 2.25)² − 1) = 17.257 m/s².
    assert_relative_eq!(model.max_acceleration(), 17.257, max_relative = 1e-4);
    let d = description();
    let needed = d.mass * (model.max_acceleration().powi(2) + G * G).sqrt();
    assert_relative_eq!(needed, 0.9 * d.max_thrust(), max_relative = 1e-9);
    assert_eq!(Quadrotor::new(&d, Some(5.0)).max_acceleration(), 5.0);
}

#[test]
fn initial_state_is_centred_and_carries_the_motion() {
    let model = crazyflie();
    let attitude = UnitQuaternion::from_euler_angles(0.1, -0.2, 0.7);
    let mut start = rest()
        .with_velocity(Vector3::new(1.0, 2.0, -0.5))
        .with_attitude(attitude);
    start.body_rates = Vector3::new(0.3, -0.4, 0.5);
    let mut x = Batch::zeros(STATE_COMPONENTS, 3);
    model.initial_state(&start, &mut x);
    for lane in 0..3 {
        let s = Lane::of(&x, lane);
        assert_eq!(s.p, Vector3::zeros());
        assert_relative_eq!(s.v, start.velocity, epsilon = 1e-6);
        assert!(s.q.angle_to(&attitude) < 1e-6);
        assert_relative_eq!(s.w, start.body_rates, epsilon = 1e-6);
    }
}

#[test]
fn rotor_torques_have_the_documented_signs() {
    let model = crazyflie();
    let hover = description().hover_rpm() as f32;
    let mut x = Batch::zeros(STATE_COMPONENTS, 1);
    model.initial_state(&rest(), &mut x);
    let mut out = Batch::zeros(STATE_COMPONENTS, 1);
    let rates = |speeds: [f32; 4], out: &mut Batch| {
        let mut u = Batch::zeros(ACTUATION_COMPONENTS, 1);
        model.actuation_for_motor_speeds(speeds, &mut u);
        model.derivative(&x, &u, out);
        BODY_RATES.map(|c| out.component(c)[0])
    };
    let (up, down) = (hover * 1.05, hover * 0.95);
    // At hover the body neither accelerates nor turns.
    let still = rates([hover; 4], &mut out);
    assert!(still.iter().all(|r| r.abs() < 1e-3), "{still:?}");
    assert!(out.component(VELOCITY[2])[0].abs() < 1e-3);
    // Left rotors (2, 3) faster: positive roll.
    let roll = rates([down, down, up, up], &mut out);
    assert!(
        roll[0] > 1.0 && roll[1].abs() < 1e-3 && roll[2].abs() < 1e-3,
        "{roll:?}"
    );
    // Rear rotors (1, 2) faster: positive pitch (nose down, thrust tilts towards +x).
    let pitch = rates([down, up, up, down], &mut out);
    assert!(pitch[1] > 1.0 && pitch[0].abs() < 1e-3, "{pitch:?}");
    // Clockwise rotors (0, 2) faster: positive yaw.
    let yaw = rates([up, down, up, down], &mut out);
    assert!(
        yaw[2] > 0.1 && yaw[0].abs() < 1e-3 && yaw[1].abs() < 1e-3,
        "{yaw:?}"
    );
}

#[test]
fn hover_holds_position_at_hover_rpm() {
    let model = crazyflie();
    let hover = description().hover_rpm();
    for axes in [CommandAxes::Planar, CommandAxes::Spatial] {
        let commands = vec![0.0; axes.count()];
        let end = simulate(&model, &rest(), &commands, axes, 0.01, 100, |_, _, u| {
            for c in MOTOR_SPEEDS {
                let rpm = f64::from(u.component(c)[0]);
                assert!((rpm - hover).abs() < 1.0, "{axes:?} rotor {c}: {rpm} rpm");
            }
        });
        let end = Lane::of(&end, 0);
        assert!(end.p.norm() < 0.01, "{axes:?}: drifted to {:?}", end.p);
        assert!(end.v.norm() < 0.01, "{axes:?}: {:?}", end.v);
    }
}

#[test]
fn motors_off_free_fall() {
    let model = crazyflie();
    let (dt, steps) = (0.01_f32, 100);
    let mut x = Batch::zeros(STATE_COMPONENTS, 1);
    model.initial_state(&rest(), &mut x);
    let mut off = Batch::zeros(ACTUATION_COMPONENTS, 1);
    model.actuation_for_motor_speeds([0.0; 4], &mut off);
    let mut rk4 = Rk4::new(1);
    for _ in 0..steps {
        rk4.step(&model, &mut x, &off, dt);
    }
    let end = Lane::of(&x, 0);
    let expected = -0.5 * G * 1.0;
    assert_relative_eq!(end.p.z, expected, max_relative = 0.01);
    assert_relative_eq!(end.v.z, -G, max_relative = 0.01);
    assert!(end.p.xy().norm() < 1e-6);
}

#[test]
fn full_down_command_cuts_thrust_to_free_fall() {
    let model = crazyflie();
    let mut peak_rpm: f32 = 0.0;
    // 0.6 s: the fall stays below 7.1 m/s, where the speed governor (8 s⁻¹ × the margin to
    // 8.33 m/s) still allows more than g along the velocity and so does not brake the fall.
    let end = simulate(
        &model,
        &rest(),
        &[0.0, 0.0, -1.0],
        CommandAxes::Spatial,
        0.01,
        60,
        |_, _, u| {
            for c in MOTOR_SPEEDS {
                peak_rpm = peak_rpm.max(u.component(c)[0]);
            }
        },
    );
    let end = Lane::of(&end, 0);
    // The 0.1 % of g the controller keeps on the rotors is far inside the 1 % tolerance.
    assert_relative_eq!(end.p.z, -0.5 * G * 0.36, max_relative = 0.01);
    assert!(end.p.xy().norm() < 1e-3, "{:?}", end.p);
    assert!(
        f64::from(peak_rpm) < 0.05 * description().hover_rpm(),
        "{peak_rpm}"
    );
    // Held for a full second, the fall is braked at the maximum speed.
    let end = endpoint(&model, &rest(), &[0.0, 0.0, -1.0], CommandAxes::Spatial);
    let max_speed = description().max_speed;
    assert!(
        end.v.z < -0.9 * max_speed && end.v.z > -1.03 * max_speed,
        "{:?}",
        end.v
    );
}

/// |a + g ẑ| for every lane of `x` under `u`: the specific force the rotors (and drag) exert.
fn specific_forces(model: &Quadrotor, x: &Batch, u: &Batch) -> Vec<f64> {
    let mut dx = Batch::zeros(STATE_COMPONENTS, x.lanes());
    model.derivative(x, u, &mut dx);
    (0..x.lanes())
        .map(|i| {
            let a = VELOCITY.map(|c| f64::from(dx.component(c)[i]));
            Vector3::new(a[0], a[1], a[2] + G).norm()
        })
        .collect()
}

#[test]
fn forward_command_accelerates_within_the_physical_limit() {
    let model = crazyflie();
    let d = description();
    let thrust_limit = d.max_thrust() / d.mass;
    let mut max_force: f64 = 0.0;
    let mut velocities = Vec::new();
    let end = simulate(
        &model,
        &rest(),
        &[1.0, 0.0],
        CommandAxes::Planar,
        0.01,
        100,
        |_, x, u| {
            max_force = specific_forces(&model, x, u)
                .into_iter()
                .fold(max_force, f64::max);
            velocities.push(f64::from(x.component(VELOCITY[0])[0]));
        },
    );
    let end = Lane::of(&end, 0);
    assert!(
        max_force <= thrust_limit * (1.0 + 1e-5),
        "{max_force} > {thrust_limit}"
    );
    // x velocity grows steadily until the speed governor takes over (from about 6 m/s).
    let early = velocities.iter().take_while(|&&v| v < 4.0).count();
    assert!(early > 10 && velocities[..early].windows(2).all(|w| w[1] >= w[0] - 1e-6));
    assert!(end.v.x > 5.0, "{:?}", end.v);
    // Bounded by A·T²/2 (A = 17.26 m/s²); the attitude lag and the speed governor cost some.
    let bound = 0.5 * model.max_acceleration();
    assert!(end.p.x > 0.5 * bound && end.p.x < bound, "x = {}", end.p.x);
    assert!(end.p.y.abs() < 0.01 && end.p.z.abs() < 0.05, "{:?}", end.p);
}

#[test]
fn initial_velocity_shifts_the_endpoint() {
    let model = crazyflie();
    // Commands gentle enough that the speed governor stays out of the way.
    for command in [[0.0, 0.0], [0.15, -0.1], [-0.12, 0.12]] {
        let still = endpoint(&model, &rest(), &command, CommandAxes::Planar);
        let v = Vector3::new(1.5, -1.0, 0.0);
        let moving = endpoint(
            &model,
            &rest().with_velocity(v),
            &command,
            CommandAxes::Planar,
        );
        let shift = moving.p - still.p;
        assert!((shift - v).norm() < 0.05, "{command:?}: shift {shift:?}");
    }
}

#[test]
fn initial_tilt_changes_the_trajectory_and_recovers_quickly() {
    let model = crazyflie();
    // Rolled 30° about +x: the thrust first pushes the drone towards −y.
    let tilted = rest().with_attitude(UnitQuaternion::from_euler_angles(
        30f64.to_radians(),
        0.0,
        0.0,
    ));
    let mut tilt_at_02 = f64::NAN;
    let end = simulate(
        &model,
        &tilted,
        &[0.0, 0.0],
        CommandAxes::Planar,
        0.01,
        100,
        |step, x, _| {
            if step == 20 {
                tilt_at_02 = Lane::of(x, 0).tilt_deg();
            }
        },
    );
    let end = Lane::of(&end, 0);
    assert!(tilt_at_02 < 3.0, "tilt after 0.2 s: {tilt_at_02}°");
    assert!(end.tilt_deg() < 1.0, "{}", end.tilt_deg());
    assert!(end.p.y < -0.01, "{:?}", end.p);
    let level = endpoint(&model, &rest(), &[0.0, 0.0], CommandAxes::Planar);
    assert!((end.p - level.p).norm() > 0.01);
    assert!(end.p.z.abs() < 0.05, "{:?}", end.p);
}

#[test]
fn heading_does_not_affect_world_frame_commands() {
    let model = crazyflie();
    let command = [1.0, -0.5];
    let reference = endpoint(&model, &rest(), &command, CommandAxes::Planar);
    for yaw_deg in [37.0_f64, 90.0, 180.0, -120.0] {
        let start = rest().with_attitude(UnitQuaternion::from_euler_angles(
            0.0,
            0.0,
            yaw_deg.to_radians(),
        ));
        let end = endpoint(&model, &start, &command, CommandAxes::Planar);
        assert!(
            (end.p - reference.p).norm() < 0.02,
            "yaw {yaw_deg}°: {:?} vs {:?}",
            end.p,
            reference.p
        );
    }
}

/// A deterministic pseudo-random sequence in [−1, 1].
fn noise(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((s >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

/// The thrust, torques and speed sum stored in `u` are those of its rotor speeds (f64
/// reference computed from the URDF constants and the documented rotor layout).
fn assert_wrench_matches_motor_speeds(u: &Batch) {
    let d = description();
    let lever = d.arm / 2f64.sqrt();
    for i in 0..u.lanes() {
        let rpm = MOTOR_SPEEDS.map(|c| f64::from(u.component(c)[i]));
        let f = rpm.map(|w| d.kf * w * w);
        let y = rpm.map(|w| d.km * w * w);
        let expected = [
            (THRUST, f.iter().sum::<f64>(), d.max_thrust()),
            (
                TORQUE[0],
                lever * (f[2] + f[3] - f[0] - f[1]),
                d.max_roll_pitch_torque(),
            ),
            (
                TORQUE[1],
                lever * (f[1] + f[2] - f[0] - f[3]),
                d.max_roll_pitch_torque(),
            ),
            (TORQUE[2], y[0] + y[2] - y[1] - y[3], d.max_yaw_torque()),
            (
                ROTOR_SPEED_SUM,
                rpm.iter().sum::<f64>() * std::f64::consts::PI / 30.0,
                1.0,
            ),
        ];
        for (c, value, scale) in expected {
            let got = f64::from(u.component(c)[i]);
            assert!(
                (got - value).abs() <= 1e-5 * scale.max(value.abs()),
                "component {c}: {got} vs {value}"
            );
            if c != ROTOR_SPEED_SUM {
                assert!(
                    got.abs() <= scale * (1.0 + 1e-5),
                    "component {c}: {got} > {scale}"
                );
            }
        }
    }
}

#[test]
fn motor_speeds_stay_within_limits_under_aggressive_commands() {
    let model = crazyflie();
    let max_rpm = description().max_rpm() as f32;
    let lanes = 64;
    let mut rand = noise(7);
    let mut start = rest()
        .with_velocity(Vector3::new(3.0, -2.0, 1.0))
        .with_attitude(UnitQuaternion::from_euler_angles(0.6, -0.4, 1.0));
    start.body_rates = Vector3::new(4.0, -3.0, 2.0);
    let mut x = Batch::zeros(STATE_COMPONENTS, lanes);
    let mut u = Batch::zeros(ACTUATION_COMPONENTS, lanes);
    let mut rk4 = Rk4::new(lanes);
    model.initial_state(&start, &mut x);
    let mut saturated = 0;
    for _ in 0..100 {
        // Bang-bang commands, redrawn every step.
        let commands: Vec<f32> = (0..3 * lanes).map(|_| rand().signum()).collect();
        model.actuate(&x, &commands, CommandAxes::Spatial, &mut u);
        for &rpm in MOTOR_SPEEDS.iter().flat_map(|&c| u.component(c)) {
            assert!((0.0..=max_rpm).contains(&rpm), "{rpm} rpm");
            saturated += usize::from(rpm == max_rpm || rpm == 0.0);
        }
        assert_wrench_matches_motor_speeds(&u);
        rk4.step(&model, &mut x, &u, 0.01);
        assert!(x.as_slice().iter().all(|v| v.is_finite()));
    }
    assert!(
        saturated > 0,
        "the test should drive some rotors into their limits"
    );
}

#[test]
fn speed_governor_caps_speed_near_max_speed() {
    let model = crazyflie();
    let max_speed = description().max_speed;
    let mut peak: f64 = 0.0;
    let end = simulate(
        &model,
        &rest(),
        &[1.0, 1.0],
        CommandAxes::Planar,
        0.01,
        200,
        |_, x, _| peak = peak.max(Lane::of(x, 0).v.norm()),
    );
    let end = Lane::of(&end, 0);
    assert!(peak <= 1.02 * max_speed, "peak {peak} m/s");
    assert!(end.v.norm() >= 0.9 * max_speed, "{:?}", end.v);
    // Starting beyond the limit, a forward command does not add speed.
    let fast = rest().with_velocity(Vector3::new(1.1 * max_speed, 0.0, 0.0));
    let end = endpoint(&model, &fast, &[1.0, 0.0], CommandAxes::Planar);
    assert!(end.v.norm() <= 1.1 * max_speed, "{:?}", end.v);
}

#[test]
fn explicit_max_acceleration_scales_commands() {
    let d = description();
    let gentle = Quadrotor::new(&d, Some(2.0));
    let end = endpoint(&gentle, &rest(), &[1.0, 0.0], CommandAxes::Planar);
    // Close to A·T²/2 = 1 m, less the attitude lag.
    assert!(end.p.x > 0.85 && end.p.x < 1.0, "{:?}", end.p);
    // Beyond the physical limit the rollout saturates instead of following the command.
    let wild = Quadrotor::new(&d, Some(100.0));
    let end = endpoint(&wild, &rest(), &[1.0, 0.0], CommandAxes::Planar);
    assert!(
        end.p.x < 0.5 * crazyflie().max_acceleration(),
        "{:?}",
        end.p
    );
}

#[test]
fn stable_across_step_sizes() {
    let model = crazyflie();
    let start = rest()
        .with_velocity(Vector3::new(1.0, 0.5, 0.0))
        .with_attitude(UnitQuaternion::from_euler_angles(0.4, -0.3, 0.5));
    let run = |dt: f32| {
        let steps = (1.0 / dt).round() as usize;
        Lane::of(
            &simulate(
                &model,
                &start,
                &[-0.7, 0.4],
                CommandAxes::Planar,
                dt,
                steps,
                |_, _, _| {},
            ),
            0,
        )
    };
    let reference = run(0.002);
    assert!(reference.tilt_deg() < 45.0 && reference.w.norm() < 1.0);
    for dt in [0.005, 0.01, 0.02] {
        let end = run(dt);
        // The controller is sampled once per step, so the endpoint moves by O(dt): about
        // 3 cm per 0.01 s of step on this 4.5-m path, without any sign of instability.
        assert!(
            (end.p - reference.p).norm() < 4.0 * f64::from(dt),
            "dt {dt}: {:?} vs {:?}",
            end.p,
            reference.p
        );
        assert!(end.w.norm() < 1.0, "dt {dt}: body rates {:?}", end.w);
    }
}

#[test]
fn rollouts_are_deterministic() {
    let model = crazyflie();
    let lanes = 37;
    let mut rand = noise(11);
    let commands: Vec<f32> = (0..3 * lanes).map(|_| rand()).collect();
    let start = rest()
        .with_velocity(Vector3::new(0.3, -0.2, 0.1))
        .with_attitude(UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3));
    let run = || {
        simulate(
            &model,
            &start,
            &commands,
            CommandAxes::Spatial,
            0.01,
            100,
            |_, _, _| {},
        )
    };
    let (a, b) = (run(), run());
    assert!(a
        .as_slice()
        .iter()
        .zip(b.as_slice())
        .all(|(x, y)| x.to_bits() == y.to_bits()));
}

/// Times actuate + 4 derivatives (the model's share of an RK4 step) and the whole local RK4
/// step. Run with `cargo test --release --test quadrotor_dynamics -- --ignored --nocapture`.
#[test]
#[ignore = "timing; run explicitly"]
fn timing_per_lane_step() {
    let model = crazyflie();
    for lanes in [150, 2000] {
        let steps = 100;
        let mut rand = noise(3);
        let commands: Vec<f32> = (0..2 * lanes).map(|_| rand()).collect();
        let start = rest().with_velocity(Vector3::new(1.0, 0.5, 0.0));
        let mut x = Batch::zeros(STATE_COMPONENTS, lanes);
        let mut u = Batch::zeros(ACTUATION_COMPONENTS, lanes);
        let mut k = Batch::zeros(STATE_COMPONENTS, lanes);
        let mut rk4 = Rk4::new(lanes);
        model.initial_state(&start, &mut x);
        let reps = 200_000 / lanes;
        let mut best_model = f64::INFINITY;
        let mut best_rk4 = f64::INFINITY;
        for _ in 0..reps {
            let t = Instant::now();
            for _ in 0..steps {
                model.actuate(&x, &commands, CommandAxes::Planar, &mut u);
                for _ in 0..4 {
                    model.derivative(&x, &u, &mut k);
                }
            }
            best_model = best_model.min(t.elapsed().as_secs_f64());
            std::hint::black_box(&k);

            model.initial_state(&start, &mut x);
            let t = Instant::now();
            for _ in 0..steps {
                model.actuate(&x, &commands, CommandAxes::Planar, &mut u);
                rk4.step(&model, &mut x, &u, 0.01);
            }
            best_rk4 = best_rk4.min(t.elapsed().as_secs_f64());
            std::hint::black_box(&x);
        }
        let per = |t: f64| t * 1e9 / (lanes * steps) as f64;
        println!(
            "{lanes} lanes x {steps} steps: actuate + 4 derivatives {:.2} ns/lane-step \
             ({:.0} us total); full local RK4 step {:.2} ns/lane-step ({:.0} us total)",
            per(best_model),
            best_model * 1e6,
            per(best_rk4),
            best_rk4 * 1e6
        );
    }
}

#[test]
fn recovers_from_steep_tilt() {
    let model = crazyflie();
    for roll_deg in [90.0_f64, 150.0, 179.0] {
        let start = rest().with_attitude(UnitQuaternion::from_euler_angles(
            roll_deg.to_radians(),
            0.0,
            0.0,
        ));
        let mut tilt_at_07 = f64::NAN;
        let end = simulate(
            &model,
            &start,
            &[0.0, 0.0],
            CommandAxes::Planar,
            0.01,
            100,
            |step, x, _| {
                if step == 70 {
                    tilt_at_07 = Lane::of(x, 0).tilt_deg();
                }
            },
        );
        assert!(end.as_slice().iter().all(|v| v.is_finite()));
        assert!(
            tilt_at_07 < 5.0,
            "{roll_deg}°: tilt after 0.7 s {tilt_at_07}°"
        );
        assert!(Lane::of(&end, 0).w.norm() < 0.5);
    }
}
