//! # cstep-core — continuous space-time empowerment (C-STEP) for mobile robots
//!
//! C-STEP scores how safe a robot's state is as the log-volume of the set of positions it can
//! still reach within a horizon `T` without colliding (Daubt & Redder, "C-STEP: Continuous
//! Space-Time Empowerment for Physics-informed Safe Reinforcement Learning of Mobile Agents").
//!
//! This crate is the core that the `cstep` node and the `cstep_scoring` Python extension both
//! build on. It knows nothing of ROS and depends on no DDS crate: a [`state::RobotState`] and a
//! [`occupancy::Scan`] go in, an [`estimator::Estimate`] and a [`reward::Reward`] come out.
//! [`input`] decides whether raw numbers describe a state, a scan and a goal. The pipeline, one
//! module a step:
//!
//! 1. [`model`] — robot dynamics behind the [`model::Dynamics`] trait (a URDF-derived quadrotor,
//!    the paper prototype's point mass);
//! 2. [`sampling`] — admissible control trajectories (Fourier, Chebyshev, bang-bang);
//! 3. [`rollout`] — batched RK4 integration with path-wise collision checks;
//! 4. [`occupancy`] — the free space seen by a 2D LiDAR scan, inflated by the robot's radius;
//! 5. [`volume`] — reachable and terminal volumes from the rollout endpoints;
//! 6. [`estimator`] — Algorithm 1 end to end;
//! 7. [`reward`] — the empowered reward `r_d · log(c · λ)`;
//! 8. [`scoring`] — one step, state + scan + goal + `c` → estimate + reward, the one path every
//!    front end (the node, its services, `cstep eval`) scores through.
//!
//! [`speed_limit`] maps a score to the speed limit Nav2 obeys (the node's optional output).
//!
//! [`parameters`] defines every parameter once (type, default, range, unit, description, live or
//! read-only) and reads the node's `ros__parameters` YAML and `-p` overrides against it into
//! [`parameters::Settings`]; [`input::file`] reads every file a user names, regular files of
//! bounded size only; [`suggest`] names the known name a misspelt one most likely meant;
//! [`excerpt`] quotes a long value in an error by its start and length. [`demo`] is the demo's
//! simulated world (walls, a LiDAR, the paper's arena), which benchmarks and tests score too.

pub mod cloud;
pub mod demo;
pub mod estimator;
pub mod excerpt;
pub mod input;
pub mod model;
pub mod occupancy;
pub mod parameters;
pub mod reward;
pub mod rollout;
pub mod sampling;
pub mod scoring;
pub mod speed_limit;
pub mod state;
pub mod suggest;
pub mod volume;
