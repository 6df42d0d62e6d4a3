//! Everything that knows about ROS. The core (`cstep_core`, re-exported at the crate root) sees
//! only a [`crate::state::RobotState`] and an [`crate::occupancy::Scan`]; this module speaks ROS
//! around it:
//!
//! - [`messages`] — serde mirrors of the messages cstep reads and writes (CDR on the wire), read
//!   strictly from JSON ([`messages::json`], `cstep eval`) and printed as YAML
//!   ([`messages::yaml`], `cstep echo`);
//! - [`convert`] — messages to the core's inputs, and its results to `cstep_msgs` messages;
//! - [`node`] — the node: its topics and services, scoring, diagnostics, markers, the speed
//!   limit and the watch for rival nodes;
//! - [`echo`] — `cstep echo`: one topic's messages printed as they arrive;
//! - [`rcl`] — what rcl gives every node and ros2-client does not: `--ros-args`, the DDS context
//!   from the environment, logging and parameter descriptors.

pub mod convert;
pub mod echo;
pub mod messages;
pub mod node;
pub mod rcl;
