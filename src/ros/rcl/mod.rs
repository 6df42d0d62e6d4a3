//! What rcl and rclcpp give every ROS 2 node and ros2-client does not, re-created by rcl's
//! rules so that cstep behaves as a C++ or Python node would:
//!
//! - [`args`] — the `--ros-args` command line: remapping, parameter overrides, log flags;
//! - [`context`] — the DDS context from `ROS_DOMAIN_ID`, `ROS_AUTOMATIC_DISCOVERY_RANGE` and
//!   `ROS_STATIC_PEERS`;
//! - [`logging`] — rcutils' console format and `/rosout`, at the levels `--ros-args` sets;
//! - [`parameters`] — the parameter table declared on the parameter services with
//!   `rcl_interfaces` descriptors.
//!
//! Nothing here knows what the node computes: [`super::node`] uses these as a C++ node uses
//! rclcpp.

pub mod args;
pub mod context;
pub mod logging;
pub mod parameters;
