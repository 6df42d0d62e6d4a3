//! Validated input: whether the numbers a front end received describe a robot state, a scan
//! and a goal, and the core's [`RobotState`], [`Scan`] and goal position when they do. The one
//! place that decides whether an input can be scored, shared by the node's topics and services
//! (through its message conversion), `cstep eval` and the Python scorer, so all refuse the same
//! input with the same words.
//!
//! Fields are named as in the ROS messages every front end describes (`nav_msgs/Odometry`,
//! `sensor_msgs/LaserScan`, `geometry_msgs/Point`). An input that cannot describe a state or a
//! scan is rejected with an [`InputError`] naming the field and the value: NaN or infinite
//! numbers, a quaternion that is not a rotation, ranges that do not match the angles, and
//! numbers beyond the physically meaningful bounds below (finite in `f64` but meaningless, or
//! not even finite once the rollouts narrow them to `f32`). One that is well formed but says
//! nothing useful (an empty scan) passes, and the estimator answers it with `valid = false`.
//! Individual `ranges` values are never malformed: REP 117 gives every `f32` a meaning (a hit,
//! no return, or invalid), and the occupancy reads them so.
//!
//! [`file`](mod@file) reads the files a user names (parameters, URDF, messages): regular files
//! of bounded size only.

pub mod file;

use std::f32::consts::TAU;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::occupancy::Scan;
use crate::state::RobotState;

/// More beams than any real 2D LiDAR produces; larger scans are rejected, not processed.
pub const MAX_BEAMS: usize = 100_000;

/// Largest |x|, |y| or |z| of a position or a goal, metres: 10 000 km from the frame's origin
/// covers any frame a robot uses on Earth (UTM northings and ECEF coordinates included).
pub const MAX_COORDINATE: f64 = 1e7;

/// Largest speed, the length of `twist.linear`, m/s: three times the speed of sound, beyond any
/// robot cstep models (a racing drone flies at 50 m/s).
pub const MAX_SPEED: f64 = 1e3;

/// Largest angular rate, the length of `twist.angular`, rad/s: 16 turns a second, well beyond
/// the 35–70 rad/s at which MEMS gyroscopes saturate.
pub const MAX_ANGULAR_RATE: f64 = 100.0;

/// How far from 1 the squared norm of an orientation quaternion may be: tf2 and RViz reject
/// transforms beyond the same tolerance (`QUATERNION_NORMALIZATION_TOLERANCE`, 10e-3). Within
/// it the quaternion is normalised; beyond it is not a rotation but a bug upstream.
pub const QUATERNION_NORM_TOLERANCE: f64 = 0.01;

/// Largest `range_max`, metres: beyond the longest-range LiDARs made.
pub const MAX_RANGE: f32 = 1e4;

/// Largest |angle_min|, |angle_max| and |angle_increment| of a scan, radians: one turn (as an
/// `f32`, which rounds 2π up). A scan spans at most one turn plus one increment (drivers differ
/// on whether a full circle repeats its first bearing).
pub const MAX_SCAN_ANGLE: f32 = TAU;

/// An input field that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct InputError {
    /// The field at fault, as a dotted path (`pose.pose.orientation`).
    pub field: String,
    /// What is wrong with it, with the value.
    pub message: String,
}

impl InputError {
    /// The error for `field`, saying `message` about its value.
    pub fn new(field: &str, message: impl Into<String>) -> Self {
        Self {
            field: field.to_owned(),
            message: message.into(),
        }
    }
}

/// A vector as `(x, y, z)`, each number as short as reads back exactly (`1e-160`, not 160
/// digits).
fn show(v: [f64; 3]) -> String {
    format!("({:?}, {:?}, {:?})", v[0], v[1], v[2])
}

fn finite(field: &str, v: [f64; 3]) -> Result<Vector3<f64>, InputError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(InputError::new(
            field,
            format!("must be finite, got {}", show(v)),
        ))
    }
}

/// A position: finite, every coordinate within ±[`MAX_COORDINATE`].
fn position(field: &str, v: [f64; 3]) -> Result<Vector3<f64>, InputError> {
    let p = finite(field, v)?;
    if p.amax() > MAX_COORDINATE {
        return Err(InputError::new(
            field,
            format!(
                "{} m is beyond the ±{MAX_COORDINATE:e} m a position may have",
                show(v)
            ),
        ));
    }
    Ok(p)
}

/// A rate (`unit` per second): finite, its length at most `limit`.
fn rate(field: &str, v: [f64; 3], limit: f64, unit: &str) -> Result<Vector3<f64>, InputError> {
    let r = finite(field, v)?;
    // Components near f64::MAX overflow the norm to inf, which is above any limit too.
    if r.norm() > limit {
        return Err(InputError::new(
            field,
            format!(
                "{} {unit}/s is faster than the {limit:?} {unit}/s accepted",
                show(v)
            ),
        ));
    }
    Ok(r)
}

/// The robot state an odometry describes: `position` (m) and `orientation` (quaternion
/// `[x, y, z, w]`) in the odometry frame, `linear` (m/s) and `angular` (rad/s) velocities in
/// the body frame, the linear one rotated here into the odometry frame.
pub fn robot_state(
    position_xyz: [f64; 3],
    orientation_xyzw: [f64; 4],
    linear: [f64; 3],
    angular: [f64; 3],
) -> Result<RobotState, InputError> {
    let position = position("pose.pose.position", position_xyz)?;
    let attitude = rotation("pose.pose.orientation", orientation_xyzw)?;
    let linear = rate("twist.twist.linear", linear, MAX_SPEED, "m")?;
    let body_rates = rate("twist.twist.angular", angular, MAX_ANGULAR_RATE, "rad")?;
    Ok(RobotState {
        position,
        velocity: attitude * linear,
        attitude,
        body_rates,
    })
}

/// The rotation an orientation quaternion `[x, y, z, w]` describes: finite, its squared norm
/// within [`QUATERNION_NORM_TOLERANCE`] of 1, then normalised.
fn rotation(field: &str, [x, y, z, w]: [f64; 4]) -> Result<UnitQuaternion<f64>, InputError> {
    let shown = format!("(x {x:?}, y {y:?}, z {z:?}, w {w:?})");
    let raw = Quaternion::new(w, x, y, z);
    if !raw.coords.iter().all(|c| c.is_finite()) {
        return Err(InputError::new(
            field,
            format!("must be finite, got {shown}"),
        ));
    }
    // Components beyond 1e154 overflow the squared norm to inf; below 1e-154 it underflows to 0.
    let squared = raw.norm_squared();
    if squared == 0.0 {
        return Err(InputError::new(
            field,
            format!("is not a rotation: zero quaternion {shown}"),
        ));
    }
    if (squared - 1.0).abs() >= QUATERNION_NORM_TOLERANCE {
        return Err(InputError::new(
            field,
            format!(
                "is not a rotation: squared norm {squared:?}, not within \
                 {QUATERNION_NORM_TOLERANCE} of 1 (as tf2 requires), {shown}"
            ),
        ));
    }
    Ok(UnitQuaternion::from_quaternion(raw))
}

/// The goal position of a task reward (a service request's `goal`, a `goal_pose` message's
/// position, `cstep eval --goal`, a Python scorer's goal): finite, within ±[`MAX_COORDINATE`]
/// like a position, so the task reward `exp(−‖p − goal‖)` is never NaN.
pub fn goal_position(goal: [f64; 3]) -> Result<Vector3<f64>, InputError> {
    position("goal", goal)
}

/// How a 2D LiDAR's beams are laid out, as `sensor_msgs/LaserScan` gives it (radians, metres,
/// single precision as the message carries them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanGeometry {
    /// Bearing of the first beam, rad.
    pub angle_min: f32,
    /// Bearing of the last beam, rad.
    pub angle_max: f32,
    /// Bearing step between beams, rad.
    pub angle_increment: f32,
    /// Shortest range the LiDAR measures, m.
    pub range_min: f32,
    /// Longest range the LiDAR measures, m.
    pub range_max: f32,
}

/// The scan that `ranges` laid out by `geometry` describe.
pub fn scan(geometry: &ScanGeometry, ranges: &[f32]) -> Result<Scan, InputError> {
    let g = geometry;
    for (field, value) in [
        ("angle_min", g.angle_min),
        ("angle_max", g.angle_max),
        ("angle_increment", g.angle_increment),
        ("range_min", g.range_min),
        ("range_max", g.range_max),
    ] {
        if !value.is_finite() {
            return Err(InputError::new(
                field,
                format!("must be finite, got {value:?}"),
            ));
        }
    }
    for (field, value) in [
        ("angle_min", g.angle_min),
        ("angle_max", g.angle_max),
        ("angle_increment", g.angle_increment),
    ] {
        if value.abs() > MAX_SCAN_ANGLE {
            return Err(InputError::new(
                field,
                format!("{value:?} rad is more than one turn (±{MAX_SCAN_ANGLE:?})"),
            ));
        }
    }
    if g.angle_increment == 0.0 {
        return Err(InputError::new(
            "angle_increment",
            "must not be zero (beams would all share one bearing)",
        ));
    }
    if g.range_min < 0.0 || g.range_max <= g.range_min {
        return Err(InputError::new(
            "range_max",
            format!(
                "must exceed range_min ≥ 0, got range_min {:?} and range_max {:?}",
                g.range_min, g.range_max
            ),
        ));
    }
    if g.range_max > MAX_RANGE {
        return Err(InputError::new(
            "range_max",
            format!(
                "{:?} m is beyond the {MAX_RANGE:e} m any LiDAR reaches",
                g.range_max
            ),
        ));
    }
    if ranges.len() > MAX_BEAMS {
        return Err(InputError::new(
            "ranges",
            format!(
                "has {} beams, more than the {MAX_BEAMS} accepted",
                ranges.len()
            ),
        ));
    }
    let span = g.angle_max as f64 - g.angle_min as f64;
    let increment = g.angle_increment as f64;
    if span.abs() > MAX_SCAN_ANGLE as f64 + increment.abs() {
        return Err(InputError::new(
            "angle_max",
            format!(
                "angle_min {:?} to angle_max {:?} spans more than one turn",
                g.angle_min, g.angle_max
            ),
        ));
    }
    let expected = (span / increment).round() + 1.0;
    if !(0.0..=MAX_BEAMS as f64).contains(&expected) {
        return Err(InputError::new(
            "angle_increment",
            format!(
                "{:?} does not step from angle_min {:?} to angle_max {:?}",
                g.angle_increment, g.angle_min, g.angle_max
            ),
        ));
    }
    // One beam of slack: drivers differ on whether a full circle repeats its first bearing.
    if !ranges.is_empty() && (ranges.len() as f64 - expected).abs() > 1.0 {
        return Err(InputError::new(
            "ranges",
            format!(
                "has {} values but angle_min {:?}, angle_max {:?}, angle_increment {:?} describe {} beams",
                ranges.len(),
                g.angle_min,
                g.angle_max,
                g.angle_increment,
                expected
            ),
        ));
    }
    Ok(Scan {
        angle_min: g.angle_min as f64,
        angle_increment: increment,
        range_min: g.range_min as f64,
        range_max: g.range_max as f64,
        ranges: ranges.to_vec(),
    })
}
