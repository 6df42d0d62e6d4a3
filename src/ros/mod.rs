//! Everything that knows about ROS: message mirrors and their conversion to the core's types.
//!
//! The core ([`crate::estimator`] and below) sees only [`crate::state::RobotState`] and
//! [`crate::occupancy::Scan`]; this module reads `nav_msgs/Odometry` and
//! `sensor_msgs/LaserScan` (as JSON for `cstep eval`, strictly: [`json`]; as CDR on the wire
//! for the node),
//! validates them, and writes `cstep_msgs` results.

pub mod args;
pub mod context;
pub mod convert;
pub mod echo;
pub mod json;
pub mod logging;
pub mod markers;
pub mod messages;
pub mod node;
pub mod parameters;
pub mod rivals;
pub mod stamps;
pub mod yaml;
