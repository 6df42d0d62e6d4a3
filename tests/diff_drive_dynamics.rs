//! The differential drive (the Husky from its URDF, 1 m/s and 3 m/s² per rim) against closed
//! forms — driving straight, braking and reversing, spinning on the spot, pivoting about one
//! wheel — and its reachable set in open space against a dense reference computed here, in
//! f64, from the unicycle's equations.

mod common;

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use approx::assert_relative_eq;
use common::estimator;
use cstep::model::diff_drive::{DiffDrive, HEADING, RIM_SPEEDS, SKID_STEER_SEPARATION_MULTIPLIER};
use cstep::model::wheeled::WheeledDescription;
use cstep::model::{Batch, CommandAxes, Dynamics};
use cstep::occupancy::{Occupancy, OccupancyOptions, Scan, UnknownSpace};
use cstep::state::RobotState;
use nalgebra::{UnitQuaternion, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Rim speed and acceleration bounds, m/s and m/s² (the parameters' defaults).
const V: f64 = 1.0;
const A: f64 = 3.0;
/// The Husky's effective track, m: its geometric one (the wheel joints at y = ±0.2854) times
/// the skid steer's default multiplier.
const TRACK: f64 = 2.0 * 0.2854 * SKID_STEER_SEPARATION_MULTIPLIER;

fn husky() -> DiffDrive {
    let d = WheeledDescription::load(Path::new("urdf/husky.urdf")).unwrap();
    DiffDrive::new(&d, V, A, None)
}

/// The distance a rim covers in `t` seconds from rest at full acceleration, capped at `V`.
fn rim_distance(t: f64) -> f64 {
    let ramp = V / A;
    if t <= ramp {
        0.5 * A * t * t
    } else {
        V * t - V * V / (2.0 * A)
    }
}

/// The state after `steps` RK4 steps of `dt` under constant commands `[left, right]`, as the
/// rollout integrates it (actuate once per step, four derivatives, renormalise); one lane.
fn drive(model: &DiffDrive, start: &RobotState, command: [f32; 2], steps: usize) -> Vec<f64> {
    let dt = 0.01f32;
    let n = model.state_components();
    let mut x = Batch::zeros(n, 1);
    model.initial_state(start, &mut x);
    let mut u = Batch::zeros(model.actuation_components(), 1);
    let (mut k, mut stage, mut sum) = (Batch::zeros(n, 1), Batch::zeros(n, 1), Batch::zeros(n, 1));
    for _ in 0..steps {
        model.actuate(&x, &command, CommandAxes::Planar, &mut u);
        model.derivative(&x, &u, &mut k);
        sum.as_mut_slice().copy_from_slice(k.as_slice());
        for (weight, advance) in [(2.0, 0.5 * dt), (2.0, 0.5 * dt), (1.0, dt)] {
            for ((s, &x), &k) in stage
                .as_mut_slice()
                .iter_mut()
                .zip(x.as_slice())
                .zip(k.as_slice())
            {
                *s = x + advance * k;
            }
            model.derivative(&stage, &u, &mut k);
            for (s, &k) in sum.as_mut_slice().iter_mut().zip(k.as_slice()) {
                *s += weight * k;
            }
        }
        // `sum` holds k1 + 2 k2 + 2 k3 + k4.
        for (x, &s) in x.as_mut_slice().iter_mut().zip(sum.as_slice()) {
            *x += dt / 6.0 * s;
        }
        model.renormalize(&mut x);
    }
    x.as_slice().iter().map(|&v| v as f64).collect()
}

fn rest() -> RobotState {
    RobotState::at_rest(Vector3::zeros())
}

#[test]
fn full_drive_straight_ahead_covers_the_closed_form_distance() {
    let model = husky();
    for (command, sign) in [([1.0, 1.0], 1.0), ([-1.0, -1.0], -1.0)] {
        let x = drive(&model, &rest(), command, 100);
        assert_relative_eq!(x[0], sign * rim_distance(1.0), epsilon = 2e-4);
        assert!(x[1].abs() < 1e-6, "{x:?}");
        assert_eq!([x[HEADING[0]], x[HEADING[1]]], [1.0, 0.0]);
        assert_eq!([x[RIM_SPEEDS[0]], x[RIM_SPEEDS[1]]], [sign * V, sign * V]);
    }
}

#[test]
fn braking_from_full_speed_and_reversing_follows_the_closed_form() {
    // Facing +y at 1 m/s: stops after V/A (V²/2A ahead), reverses to −V in another V/A
    // (V²/2A back) and drives the rest of the second backwards: −(1 − 2V/A)·V net.
    let model = husky();
    let start = rest()
        .with_velocity(Vector3::new(0.0, V, 0.0))
        .with_attitude(UnitQuaternion::from_euler_angles(0.0, 0.0, FRAC_PI_2));
    let x = drive(&model, &start, [-1.0, -1.0], 100);
    assert!(x[0].abs() < 1e-5, "{x:?}");
    assert_relative_eq!(x[1], -(1.0 - 2.0 * V / A) * V, epsilon = 2e-4);
    // Held at top speed, it covers V·T.
    let x = drive(&model, &start, [1.0, 1.0], 100);
    assert_relative_eq!(x[1], V, epsilon = 1e-5);
}

#[test]
fn opposite_rims_spin_the_robot_on_the_spot() {
    // Each rim covers s(T); the heading turns by 2·s(T)/track and the centre stays put.
    let model = husky();
    let x = drive(&model, &rest(), [-1.0, 1.0], 100);
    let turned = 2.0 * rim_distance(1.0) / TRACK;
    assert!(x[0].abs() < 1e-5 && x[1].abs() < 1e-5, "{x:?}");
    // 2.9 rad turned; the step in which the rims reach top speed overshoots it by up to A·dt
    // before `renormalize` clamps them: 2e-4 rad of heading.
    assert_relative_eq!(x[HEADING[0]], turned.cos(), epsilon = 5e-4);
    assert_relative_eq!(x[HEADING[1]], turned.sin(), epsilon = 5e-4);
}

#[test]
fn one_rim_pivots_the_robot_about_the_other_wheel() {
    // The left rim stays still; the centre swings on a circle of radius track/2 about the left
    // side's instantaneous centre (the effective track's, not the wheel's), through s(T)/track.
    let model = husky();
    let x = drive(&model, &rest(), [0.0, 1.0], 100);
    let angle = rim_distance(1.0) / TRACK;
    let radius = TRACK / 2.0;
    assert_relative_eq!(x[0], radius * angle.sin(), epsilon = 2e-4);
    assert_relative_eq!(x[1], radius * (1.0 - angle.cos()), epsilon = 2e-4);
    assert_relative_eq!(x[HEADING[1]], angle.sin(), epsilon = 2e-4);
    assert_eq!(x[RIM_SPEEDS[0]], 0.0);
}

/// The endpoint at `T` of the unicycle with rim accelerations ±A switching at the given times
/// (each side starts at `first` and flips at each switch), integrated in f64 with 1-ms steps.
fn reference_endpoint(sides: [(f64, &[f64]); 2], horizon: f64) -> Vector2<f64> {
    let steps = (horizon / 1e-3).round() as usize;
    let dt = horizon / steps as f64;
    let (mut p, mut heading, mut speeds) = (Vector2::zeros(), 0.0f64, [0.0f64; 2]);
    for k in 0..steps {
        let t = (k as f64 + 0.5) * dt;
        let before = speeds;
        for (speed, (first, switches)) in speeds.iter_mut().zip(sides) {
            let flips = switches.iter().filter(|&&s| s < t).count();
            let a = if flips % 2 == 0 { first } else { -first } * A;
            *speed = (*speed + a * dt).clamp(-V, V);
        }
        // Speeds change linearly over the step: Simpson's rule on the heading and position.
        let v = |s: [f64; 2]| 0.5 * (s[0] + s[1]);
        let w = |s: [f64; 2]| (s[1] - s[0]) / TRACK;
        let mid = [0.5 * (before[0] + speeds[0]), 0.5 * (before[1] + speeds[1])];
        let h_mid = heading + 0.5 * dt * (0.75 * w(before) + 0.25 * w(speeds));
        let h_end = heading + 0.5 * dt * (w(before) + w(speeds));
        let dir = |h: f64| Vector2::new(h.cos(), h.sin());
        p += dt / 6.0
            * (v(before) * dir(heading) + 4.0 * v(mid) * dir(h_mid) + v(speeds) * dir(h_end));
        heading = h_end;
    }
    p
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise.
fn hull(points: &[Vector2<f64>]) -> Vec<Vector2<f64>> {
    let mut pts = points.to_vec();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| (a - o).perp(&(b - o));
    let mut chain: Vec<Vector2<f64>> = Vec::new();
    for pass in 0..2 {
        let start = chain.len();
        for &p in &pts {
            while chain.len() >= start + 2
                && cross(chain[chain.len() - 2], chain[chain.len() - 1], p) <= 0.0
            {
                chain.pop();
            }
            chain.push(p);
        }
        chain.pop();
        if pass == 0 {
            pts.reverse();
        }
    }
    chain
}

fn area(polygon: &[Vector2<f64>]) -> f64 {
    let n = polygon.len();
    0.5 * (0..n)
        .map(|i| polygon[i].perp(&polygon[(i + 1) % n]))
        .sum::<f64>()
}

/// Distance by which `point` lies outside the counter-clockwise convex `polygon` (≤ 0 inside).
fn outside(polygon: &[Vector2<f64>], point: Vector2<f64>) -> f64 {
    let n = polygon.len();
    (0..n)
        .map(|i| {
            let (a, b) = (polygon[i], polygon[(i + 1) % n]);
            -(b - a).perp(&(point - a)) / (b - a).norm()
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

fn open_space() -> Scan {
    Scan {
        angle_min: -std::f64::consts::PI,
        angle_increment: std::f64::consts::PI / 180.0,
        range_min: 0.05,
        range_max: 10.0,
        ranges: vec![f32::INFINITY; 360],
    }
}

#[test]
fn the_reachable_area_in_open_space_matches_a_dense_reference() {
    // Reference: 20 000 bang-bang rim profiles with up to three switches per side at uniform
    // times, integrated in f64; the hull of their endpoints is the reachable set's hull.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut endpoints = Vec::new();
    for _ in 0..20_000 {
        let mut side = || {
            let first = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
            let mut switches: Vec<f64> = (0..rng.random_range(0..=3))
                .map(|_| rng.random_range(0.0..1.0))
                .collect();
            switches.sort_by(f64::total_cmp);
            (first, switches)
        };
        let (left, right) = (side(), side());
        endpoints.push(reference_endpoint(
            [(left.0, &left.1), (right.0, &right.1)],
            1.0,
        ));
    }
    let reference = hull(&endpoints);
    let reference_area = area(&reference);
    // Its extent along the heading is the closed form: full drive straight ahead or back.
    let xs = reference.iter().map(|p| p.x);
    assert_relative_eq!(
        xs.clone().fold(f64::NEG_INFINITY, f64::max),
        rim_distance(1.0),
        epsilon = 1e-3
    );
    assert_relative_eq!(
        xs.fold(f64::INFINITY, f64::min),
        -rim_distance(1.0),
        epsilon = 1e-3
    );

    // The estimator's 150 trajectories (defaults: bang-bang, free-fraction estimator), and
    // 2000: its bang-bang sample reaches the extremes, so what it misses is the shortfall of a
    // finite sample's hull, which shrinks as the sample grows (measured −9.7 % and −1.1 %).
    for (trajectories, tolerance) in [(150, 0.12), (2000, 0.03)] {
        let e = estimator(&[
            "model:=diff_drive",
            "robot_description:=builtin:husky.urdf",
            "unknown_space:=free",
            &format!("trajectories:={trajectories}"),
        ]);
        let estimate = e.evaluate(&rest(), &open_space());
        assert!(estimate.valid(), "{estimate:?}");
        assert_eq!(estimate.num_colliding, 0);
        for end in &estimate.rollout.endpoints {
            let point = Vector2::new(end[0], end[1]);
            // Nowhere the unicycle cannot reach, and never farther than a rim can travel.
            assert!(outside(&reference, point) < 5e-3, "{end:?}");
            assert!(point.norm() <= rim_distance(1.0) + 2e-4, "{end:?}");
            assert_eq!(end[2], 0.0);
        }
        let relative = estimate.volumes.free / reference_area - 1.0;
        println!(
            "{trajectories} trajectories: reference {reference_area:.4} m², estimate {:.4} m² \
             ({:+.1} %)",
            estimate.volumes.free,
            100.0 * relative
        );
        assert!(relative.abs() < tolerance, "{trajectories}: {relative}");
    }
}

#[test]
fn the_footprint_turns_with_the_heading() {
    // A wall across x = 0.6: facing it, the Husky's front disk (reaching 0.68 m) already
    // overlaps it; turned along it, the disks reach 0.43 m sideways and it may drive away.
    let scene = cstep::demo::scene::Scene::open().wall(0.6, -20.0, 0.6, 20.0);
    let e = estimator(&["model:=diff_drive", "robot_description:=builtin:husky.urdf"]);
    let lidar = cstep::demo::scene::Lidar {
        beams: 360,
        range_min: 0.02,
        range_max: 10.0,
    };
    let facing = UnitQuaternion::identity();
    let along = UnitQuaternion::from_euler_angles(0.0, 0.0, FRAC_PI_2);
    let score = |attitude: UnitQuaternion<f64>| {
        let scan = scene.scan(Vector2::zeros(), &attitude, &lidar);
        e.evaluate(&rest().with_attitude(attitude), &scan)
    };
    let (into, beside) = (score(facing), score(along));
    assert!(!into.valid(), "{into:?}");
    assert_eq!(into.num_colliding, into.num_trajectories);
    // Beside it, only the trajectories that turn the front towards it collide (88 of 150).
    assert!(beside.valid() && beside.num_colliding < into.num_colliding);

    // The same test the rollout makes: the front disk's centre against the occupancy.
    let occupancy = Occupancy::build(
        &scene.scan(Vector2::zeros(), &facing, &lidar),
        &facing,
        0.0,
        &OccupancyOptions {
            robot_radius: husky().collision_radius(),
            robot_height: 0.0,
            unknown_space: UnknownSpace::Occupied,
            floor: None,
            ceiling: None,
        },
    );
    assert!(!occupancy.in_collision_at_start());
    let front = husky().footprint().centres()[1];
    assert!(!occupancy.is_free(front[0], front[1], 0.0));
}
