//! # cstep — C-STEP (continuous space-time empowerment) as a ROS 2 node
//!
//! The ROS side of C-STEP: [`ros`] holds the message mirrors, the node and what rcl would give
//! it ([`ros::rcl`]). Everything else — dynamics, sampling, rollouts, occupancy, volumes, the
//! estimator, the reward, the scoring step and the one parameter table — is the ROS-free core,
//! `cstep-core`, re-exported here whole so that `cstep::parameters`, `cstep::scoring` and the
//! rest name the same items as `cstep_core::…`.

pub use cstep_core::*;

pub mod ros;
