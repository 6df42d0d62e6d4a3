//! Validated conversion from ROS messages to the core's inputs.
//!
//! A message that cannot describe a state or a scan (NaN positions, a zero quaternion, ranges
//! that do not match the angles) is rejected with an [`InputError`] naming the field and the
//! value; one that is well formed but says nothing useful (an empty scan) passes, and the
//! estimator answers it with `valid = false`.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use super::messages::{EmpoweredReward, Empowerment, Header, LaserScan, Odometry};
use crate::estimator::Estimate;
use crate::occupancy::Scan;
use crate::reward::Reward;
use crate::state::RobotState;

/// More beams than any real 2D LiDAR produces; larger scans are rejected, not processed.
pub const MAX_BEAMS: usize = 100_000;

/// A message field that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct InputError {
    /// The field at fault, as a dotted path (`pose.pose.orientation`).
    pub field: String,
    /// What is wrong with it, with the value.
    pub message: String,
}

impl InputError {
    fn new(field: &str, message: impl Into<String>) -> Self {
        Self {
            field: field.to_owned(),
            message: message.into(),
        }
    }
}

fn finite_vector(field: &str, v: [f64; 3]) -> Result<Vector3<f64>, InputError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(InputError::new(
            field,
            format!("must be finite, got ({}, {}, {})", v[0], v[1], v[2]),
        ))
    }
}

/// The robot state an odometry message describes, with the body-frame twist rotated into the
/// odometry frame.
pub fn odometry_to_state(odom: &Odometry) -> Result<RobotState, InputError> {
    let pose = &odom.pose.pose;
    let p = pose.position;
    let position = finite_vector("pose.pose.position", [p.x, p.y, p.z])?;
    let q = pose.orientation;
    let field = "pose.pose.orientation";
    let raw = Quaternion::new(q.w, q.x, q.y, q.z);
    if !raw.coords.iter().all(|c| c.is_finite()) {
        return Err(InputError::new(
            field,
            format!(
                "must be finite, got (x {}, y {}, z {}, w {})",
                q.x, q.y, q.z, q.w
            ),
        ));
    }
    if raw.norm() < 1e-6 {
        return Err(InputError::new(
            field,
            format!(
                "is not a rotation: zero quaternion (x {}, y {}, z {}, w {})",
                q.x, q.y, q.z, q.w
            ),
        ));
    }
    let attitude = UnitQuaternion::from_quaternion(raw);
    let t = &odom.twist.twist;
    let linear = finite_vector("twist.twist.linear", [t.linear.x, t.linear.y, t.linear.z])?;
    let body_rates = finite_vector(
        "twist.twist.angular",
        [t.angular.x, t.angular.y, t.angular.z],
    )?;
    Ok(RobotState {
        position,
        velocity: attitude * linear,
        attitude,
        body_rates,
    })
}

/// The scan a `LaserScan` message describes.
pub fn laser_scan_to_scan(msg: &LaserScan) -> Result<Scan, InputError> {
    for (field, value) in [
        ("angle_min", msg.angle_min),
        ("angle_max", msg.angle_max),
        ("angle_increment", msg.angle_increment),
        ("range_min", msg.range_min),
        ("range_max", msg.range_max),
    ] {
        if !value.is_finite() {
            return Err(InputError::new(
                field,
                format!("must be finite, got {value}"),
            ));
        }
    }
    if msg.angle_increment == 0.0 {
        return Err(InputError::new(
            "angle_increment",
            "must not be zero (beams would all share one bearing)",
        ));
    }
    if msg.range_min < 0.0 || msg.range_max <= msg.range_min {
        return Err(InputError::new(
            "range_max",
            format!(
                "must exceed range_min ≥ 0, got range_min {} and range_max {}",
                msg.range_min, msg.range_max
            ),
        ));
    }
    if msg.ranges.len() > MAX_BEAMS {
        return Err(InputError::new(
            "ranges",
            format!(
                "has {} beams, more than the {MAX_BEAMS} accepted",
                msg.ranges.len()
            ),
        ));
    }
    let span = msg.angle_max as f64 - msg.angle_min as f64;
    let expected = (span / msg.angle_increment as f64).round() + 1.0;
    if !(0.0..=MAX_BEAMS as f64).contains(&expected) {
        return Err(InputError::new(
            "angle_increment",
            format!(
                "{} does not step from angle_min {} to angle_max {}",
                msg.angle_increment, msg.angle_min, msg.angle_max
            ),
        ));
    }
    // One beam of slack: drivers differ on whether a full circle repeats its first bearing.
    if !msg.ranges.is_empty() && (msg.ranges.len() as f64 - expected).abs() > 1.0 {
        return Err(InputError::new(
            "ranges",
            format!(
                "has {} values but angle_min {}, angle_max {}, angle_increment {} describe {} beams",
                msg.ranges.len(),
                msg.angle_min,
                msg.angle_max,
                msg.angle_increment,
                expected
            ),
        ));
    }
    Ok(Scan {
        angle_min: msg.angle_min as f64,
        angle_increment: msg.angle_increment as f64,
        range_min: msg.range_min as f64,
        range_max: msg.range_max as f64,
        ranges: msg.ranges.clone(),
    })
}

/// The `LaserScan` message for a scan (the inverse of [`laser_scan_to_scan`]).
pub fn scan_to_laser_scan(scan: &Scan, header: super::messages::Header) -> LaserScan {
    let beams = scan.ranges.len().max(1) as f64;
    LaserScan {
        header,
        angle_min: scan.angle_min as f32,
        angle_max: (scan.angle_min + scan.angle_increment * (beams - 1.0)) as f32,
        angle_increment: scan.angle_increment as f32,
        range_min: scan.range_min as f32,
        range_max: scan.range_max as f32,
        ranges: scan.ranges.clone(),
        ..Default::default()
    }
}

/// The `cstep_msgs/Empowerment` for an estimate made with safety coefficient `c`.
pub fn empowerment_message(header: Header, estimate: &Estimate, c: f64) -> Empowerment {
    Empowerment {
        header,
        empowerment: estimate.empowerment,
        reachable_volume: estimate.volumes.reachable,
        terminal_volume: estimate.volumes.terminal,
        free_volume: estimate.volumes.free,
        safety_coefficient: c,
        horizon: estimate.horizon,
        num_trajectories: estimate.num_trajectories as u32,
        num_colliding: estimate.num_colliding as u32,
        valid: estimate.valid(),
        status: estimate.status.as_str().to_owned(),
    }
}

/// The `cstep_msgs/EmpoweredReward` for a reward computed with safety coefficient `c`.
pub fn reward_message(header: Header, reward: &Reward, c: f64, valid: bool) -> EmpoweredReward {
    EmpoweredReward {
        header,
        reward: reward.reward,
        task_reward: reward.task_reward,
        empowerment_term: reward.empowerment_term,
        safety_coefficient: c,
        valid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::messages::Quaternion as QuaternionMsg;

    fn scan(beams: usize) -> LaserScan {
        let increment = std::f32::consts::TAU / beams as f32;
        LaserScan {
            angle_min: -std::f32::consts::PI,
            angle_max: -std::f32::consts::PI + increment * (beams - 1) as f32,
            angle_increment: increment,
            range_min: 0.1,
            range_max: 3.0,
            ranges: vec![1.0; beams],
            ..Default::default()
        }
    }

    #[test]
    fn body_frame_twist_is_rotated_into_the_odometry_frame() {
        let mut odom = Odometry::default();
        let yaw = std::f64::consts::FRAC_PI_2;
        odom.pose.pose.orientation = QuaternionMsg {
            x: 0.0,
            y: 0.0,
            z: (yaw / 2.0).sin(),
            w: (yaw / 2.0).cos(),
        };
        odom.twist.twist.linear.x = 2.0; // forward, in the body frame
        let state = odometry_to_state(&odom).unwrap();
        assert!((state.velocity - Vector3::new(0.0, 2.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn unnormalised_quaternions_are_normalised_and_zero_ones_rejected() {
        let mut odom = Odometry::default();
        odom.pose.pose.orientation = QuaternionMsg {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 3.0,
        };
        assert_eq!(
            odometry_to_state(&odom).unwrap().attitude,
            UnitQuaternion::identity()
        );
        odom.pose.pose.orientation.w = 0.0;
        let err = odometry_to_state(&odom).unwrap_err();
        assert_eq!(err.field, "pose.pose.orientation");
        assert!(err.message.contains("zero quaternion"));
    }

    #[test]
    fn non_finite_odometry_fields_are_named() {
        let mut odom = Odometry::default();
        odom.pose.pose.position.y = f64::NAN;
        assert_eq!(
            odometry_to_state(&odom).unwrap_err().field,
            "pose.pose.position"
        );
        let mut odom = Odometry::default();
        odom.twist.twist.angular.z = f64::INFINITY;
        assert_eq!(
            odometry_to_state(&odom).unwrap_err().field,
            "twist.twist.angular"
        );
    }

    #[test]
    fn malformed_scans_are_rejected_with_the_field() {
        assert!(laser_scan_to_scan(&scan(360)).is_ok());
        let mut s = scan(360);
        s.ranges.truncate(300);
        let err = laser_scan_to_scan(&s).unwrap_err();
        assert_eq!(err.field, "ranges");
        assert!(err.message.contains("300 values"), "{err}");
        let mut s = scan(360);
        s.angle_increment = 0.0;
        assert_eq!(laser_scan_to_scan(&s).unwrap_err().field, "angle_increment");
        let mut s = scan(360);
        s.range_max = 0.05;
        assert_eq!(laser_scan_to_scan(&s).unwrap_err().field, "range_max");
        let mut s = scan(360);
        s.angle_min = f32::NAN;
        assert_eq!(laser_scan_to_scan(&s).unwrap_err().field, "angle_min");
        let mut s = scan(10);
        s.ranges = vec![1.0; MAX_BEAMS + 1];
        assert_eq!(laser_scan_to_scan(&s).unwrap_err().field, "ranges");
    }

    #[test]
    fn an_empty_scan_is_well_formed() {
        let mut s = scan(360);
        s.ranges.clear();
        assert_eq!(laser_scan_to_scan(&s).unwrap().ranges.len(), 0);
    }
}
