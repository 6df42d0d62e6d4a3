//! Conversion between ROS messages and the core's inputs and outputs. Whether a message can be
//! scored is decided by the core's [`crate::input`] (shared with the Python scorer); this module
//! reads the message fields into it, and checks what only a message has (a stamp's
//! nanoseconds). Fields cstep does not read (covariances, `child_frame_id`, `intensities`,
//! `time_increment`, `scan_time`, a goal's orientation) are not checked.

use nalgebra::{UnitQuaternion, Vector3};

use super::messages::point_cloud::cloud_points;
use super::messages::{
    EmpoweredReward, Empowerment, Header, LaserScan, Odometry, Point, PointCloud2, Time,
};
use crate::cloud::{CloudInput, CloudScan};
use crate::estimator::Estimate;
pub use crate::input::InputError;
use crate::input::{self, ScanGeometry};
use crate::occupancy::Scan;
use crate::reward::Reward;
use crate::state::RobotState;

/// The robot state an odometry message describes, with the body-frame twist rotated into the
/// odometry frame.
pub fn odometry_to_state(odom: &Odometry) -> Result<RobotState, InputError> {
    let pose = &odom.pose.pose;
    let (p, q) = (pose.position, pose.orientation);
    let t = &odom.twist.twist;
    input::robot_state(
        [p.x, p.y, p.z],
        [q.x, q.y, q.z, q.w],
        [t.linear.x, t.linear.y, t.linear.z],
        [t.angular.x, t.angular.y, t.angular.z],
    )
}

/// The goal position of a task reward (a `/cstep/evaluate` request's `goal`, a `goal_pose`
/// message's position, `cstep eval --goal`): see [`input::goal_position`].
pub fn goal_position(goal: &Point) -> Result<Vector3<f64>, InputError> {
    input::goal_position([goal.x, goal.y, goal.z])
}

/// A stamp whose nanoseconds lie within the second (`builtin_interfaces/Time`).
fn stamp(field: &str, t: Time) -> Result<(), InputError> {
    if t.nanosec >= 1_000_000_000 {
        return Err(InputError::new(
            field,
            format!(
                "nanosec {} is not within the second (sec {})",
                t.nanosec, t.sec
            ),
        ));
    }
    Ok(())
}

/// The scan a `LaserScan` message describes.
pub fn laser_scan_to_scan(msg: &LaserScan) -> Result<Scan, InputError> {
    stamp("header.stamp", msg.header.stamp)?;
    let geometry = ScanGeometry {
        angle_min: msg.angle_min,
        angle_max: msg.angle_max,
        angle_increment: msg.angle_increment,
        range_min: msg.range_min,
        range_max: msg.range_max,
    };
    input::scan(&geometry, &msg.ranges)
}

/// The scan a `PointCloud2` becomes for a robot at `attitude` (body → world), its points read
/// as `input` says ([`CloudScan::from_points`]); the cloud is in the body frame with the sensor
/// at its origin, as a scan is. A cloud whose layout cannot be read is an error of the field
/// `point cloud`.
pub fn point_cloud_to_scan(
    msg: &PointCloud2,
    attitude: &UnitQuaternion<f64>,
    input: &CloudInput,
) -> Result<CloudScan, InputError> {
    stamp("header.stamp", msg.header.stamp)?;
    let points = cloud_points(msg, input.max_points)
        .map_err(|e| InputError::new("point cloud", e.to_string()))?;
    Ok(CloudScan::from_points(points, attitude, &input.options))
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
    use nalgebra::UnitQuaternion;

    use super::*;
    use crate::input::{
        MAX_ANGULAR_RATE, MAX_BEAMS, MAX_COORDINATE, MAX_RANGE, MAX_SCAN_ANGLE, MAX_SPEED,
    };
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
    fn nearly_unit_quaternions_are_normalised_others_rejected() {
        let mut odom = Odometry::default();
        // Squared norm 1.0099: within tf2's tolerance, normalised.
        odom.pose.pose.orientation.w = 1.0099f64.sqrt();
        assert_eq!(
            odometry_to_state(&odom).unwrap().attitude,
            UnitQuaternion::identity()
        );
        odom.pose.pose.orientation.w = 0.9901f64.sqrt();
        assert!(odometry_to_state(&odom).is_ok());
        // Just beyond it on either side, and far beyond: not a rotation.
        for w in [1.0101f64.sqrt(), 0.9899f64.sqrt(), 3.0] {
            odom.pose.pose.orientation.w = w;
            let err = odometry_to_state(&odom).unwrap_err();
            assert_eq!(err.field, "pose.pose.orientation");
            assert!(err.message.contains("squared norm"), "{err}");
        }
        odom.pose.pose.orientation.w = 0.0;
        let err = odometry_to_state(&odom).unwrap_err();
        assert_eq!(err.field, "pose.pose.orientation");
        assert!(err.message.contains("zero quaternion"));
        // Components whose squares overflow or underflow f64 are named with their values,
        // briefly.
        odom.pose.pose.orientation = QuaternionMsg {
            x: 1e155,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        };
        let err = odometry_to_state(&odom).unwrap_err();
        assert!(err.message.contains("x 1e155"), "{err}");
        odom.pose.pose.orientation = QuaternionMsg {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1e-160,
        };
        let err = odometry_to_state(&odom).unwrap_err();
        assert!(err.message.contains("w 1e-160"), "{err}");
        assert!(!err.message.contains("00000000"), "{err}");
    }

    /// Asserts that `result` is an error naming `field` and showing `value`.
    fn rejects<T: std::fmt::Debug>(result: Result<T, InputError>, field: &str, value: &str) {
        let err = result.unwrap_err();
        assert_eq!(err.field, field, "{err}");
        assert!(err.message.contains(value), "{err} should show {value}");
    }

    #[test]
    fn odometry_bounds_hold_on_both_sides() {
        let with = |edit: &dyn Fn(&mut Odometry)| {
            let mut odom = Odometry::default();
            edit(&mut odom);
            odometry_to_state(&odom)
        };
        // Positions: every coordinate within ±1e7 m.
        assert!(with(&|o| o.pose.pose.position.x = -MAX_COORDINATE).is_ok());
        assert!(with(&|o| o.pose.pose.position.z = MAX_COORDINATE).is_ok());
        rejects(
            with(&|o| o.pose.pose.position.y = 1.0000001e7),
            "pose.pose.position",
            "10000001.0",
        );
        rejects(
            with(&|o| o.pose.pose.position.x = -1e300),
            "pose.pose.position",
            "-1e300",
        );
        // Speed: the length of the linear twist, at most 1000 m/s.
        assert!(with(&|o| o.twist.twist.linear.x = MAX_SPEED).is_ok());
        assert!(with(&|o| {
            o.twist.twist.linear.x = 600.0;
            o.twist.twist.linear.y = -800.0;
        })
        .is_ok());
        rejects(
            with(&|o| {
                o.twist.twist.linear.x = 600.0;
                o.twist.twist.linear.y = -800.1;
            }),
            "twist.twist.linear",
            "-800.1",
        );
        rejects(
            with(&|o| o.twist.twist.linear.z = 1e39),
            "twist.twist.linear",
            "1e39",
        );
        rejects(
            with(&|o| o.twist.twist.linear.x = f64::MAX),
            "twist.twist.linear",
            "1.7976931348623157e308",
        );
        // Angular rate: the length of the angular twist, at most 100 rad/s.
        assert!(with(&|o| o.twist.twist.angular.z = -MAX_ANGULAR_RATE).is_ok());
        rejects(
            with(&|o| o.twist.twist.angular.z = 100.001),
            "twist.twist.angular",
            "100.001",
        );
        rejects(
            with(&|o| o.twist.twist.angular.x = 1e30),
            "twist.twist.angular",
            "1e30",
        );
    }

    #[test]
    fn goals_are_bounded_like_positions() {
        let goal = |x: f64| Point { x, y: -2.0, z: 0.5 };
        assert_eq!(
            goal_position(&goal(1.0)).unwrap(),
            Vector3::new(1.0, -2.0, 0.5)
        );
        assert!(goal_position(&goal(MAX_COORDINATE)).is_ok());
        rejects(goal_position(&goal(-1.0000001e7)), "goal", "-10000001.0");
        rejects(goal_position(&goal(f64::NAN)), "goal", "NaN");
        rejects(goal_position(&goal(f64::INFINITY)), "goal", "inf");
    }

    #[test]
    fn scan_bounds_hold_on_both_sides() {
        let with = |edit: &dyn Fn(&mut LaserScan)| {
            let mut s = scan(360);
            edit(&mut s);
            laser_scan_to_scan(&s)
        };
        // range_max up to 10 km.
        assert!(with(&|s| s.range_max = MAX_RANGE).is_ok());
        rejects(with(&|s| s.range_max = 10_001.0), "range_max", "10001.0");
        rejects(with(&|s| s.range_max = 1e30), "range_max", "1e30");
        // Bearings within one turn.
        let full = |s: &mut LaserScan| {
            s.angle_min = 0.0;
            s.angle_max = MAX_SCAN_ANGLE;
            s.angle_increment = MAX_SCAN_ANGLE / 360.0;
            s.ranges = vec![1.0; 361]; // the first bearing repeated at the end
        };
        assert!(with(&full).is_ok());
        rejects(
            with(&|s| {
                full(s);
                s.angle_max = MAX_SCAN_ANGLE.next_up();
            }),
            "angle_max",
            "6.283186",
        );
        rejects(with(&|s| s.angle_min = -7.0), "angle_min", "-7.0");
        rejects(
            with(&|s| {
                s.angle_min = -MAX_SCAN_ANGLE;
                s.angle_max = MAX_SCAN_ANGLE;
                s.angle_increment = MAX_SCAN_ANGLE / 180.0;
            }),
            "angle_max",
            "spans more than one turn",
        );
        // Increments within one turn: two beams a full turn apart pass, 1e30 apart do not.
        let two = |s: &mut LaserScan, increment: f32| {
            s.angle_min = -3.0;
            s.angle_max = -3.0 + increment;
            s.angle_increment = increment;
            s.ranges = vec![1.0; 2];
        };
        assert!(with(&|s| two(s, MAX_SCAN_ANGLE)).is_ok());
        rejects(
            with(&|s| two(s, MAX_SCAN_ANGLE.next_up())),
            "angle_increment",
            "6.283186",
        );
        rejects(
            with(&|s| {
                two(s, 1.0);
                s.angle_increment = 1e30;
            }),
            "angle_increment",
            "1e30",
        );
        // Stamps with nanoseconds within the second.
        assert!(with(&|s| s.header.stamp.nanosec = 999_999_999).is_ok());
        rejects(
            with(&|s| s.header.stamp.nanosec = 1_000_000_000),
            "header.stamp",
            "1000000000",
        );
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
