//! The node's clock for its diagnostics' stamps: wall time, or simulated time while
//! `use_sim_time` is set.

use std::sync::Mutex;

use ros2_client::{Node, ParameterValue};

use crate::ros::messages::{Clock, Time};

/// The node's clock, for the diagnostics' stamps: the system clock, or while the node's
/// `use_sim_time` parameter is true the newest `/clock` (zero until one arrives, as in rclcpp).
/// `use_sim_time` is live, so the choice is made at each stamp from the node's parameter store,
/// the one place that sees its sets (ros2-client handles them itself and calls no set action for
/// it); the newest `/clock` is kept either way, so a switch to sim time stamps with it at once,
/// as rclcpp's time source does.
#[derive(Default)]
pub(super) struct NodeClock {
    /// The newest `/clock` time.
    newest: Mutex<Time>,
}

impl NodeClock {
    /// Now, on the clock `node`'s `use_sim_time` asks for.
    pub(super) fn now(&self, node: &Node) -> Time {
        if node.get_parameter("use_sim_time") == Some(ParameterValue::Boolean(true)) {
            return *self.newest.lock().unwrap_or_else(|e| e.into_inner());
        }
        Time::wall_clock_now()
    }

    /// Takes a `/clock` message.
    pub(super) fn tick(&self, clock: &Clock) {
        *self.newest.lock().unwrap_or_else(|e| e.into_inner()) = clock.clock;
    }
}
