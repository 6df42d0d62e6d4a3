//! The robot state that an evaluation starts from.

use nalgebra::{UnitQuaternion, Vector3};

/// A rigid body's state in the odometry (world) frame: where the robot is, how it moves and how
/// it is oriented. C-STEP is "physics-informed" because all of it — not only the position —
/// shapes the reachable set.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotState {
    /// Position in the world frame, metres.
    pub position: Vector3<f64>,
    /// Linear velocity in the world frame, m/s (odometry gives it in the body frame; the ROS
    /// layer rotates it).
    pub velocity: Vector3<f64>,
    /// Attitude: rotation from the body frame to the world frame.
    pub attitude: UnitQuaternion<f64>,
    /// Angular velocity in the body frame, rad/s.
    pub body_rates: Vector3<f64>,
}

impl RobotState {
    /// A robot at rest, level, at `position`.
    pub fn at_rest(position: Vector3<f64>) -> Self {
        Self {
            position,
            velocity: Vector3::zeros(),
            attitude: UnitQuaternion::identity(),
            body_rates: Vector3::zeros(),
        }
    }

    /// The same state moving with world-frame `velocity`.
    pub fn with_velocity(mut self, velocity: Vector3<f64>) -> Self {
        self.velocity = velocity;
        self
    }

    /// The same state with attitude `attitude`.
    pub fn with_attitude(mut self, attitude: UnitQuaternion<f64>) -> Self {
        self.attitude = attitude;
        self
    }

    /// True when every component is a finite number.
    pub fn is_finite(&self) -> bool {
        self.position.iter().all(|v| v.is_finite())
            && self.velocity.iter().all(|v| v.is_finite())
            && self.attitude.coords.iter().all(|v| v.is_finite())
            && self.body_rates.iter().all(|v| v.is_finite())
    }
}
