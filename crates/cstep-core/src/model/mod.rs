//! Robot dynamics: one trait, one file per robot.
//!
//! A model turns normalised commands into motion. The rollout engine ([`crate::rollout`]) owns
//! the integration loop (RK4, batch as the inner loop); a model supplies the two pieces that
//! differ between robots: [`Dynamics::actuate`] (controller and actuator limits, evaluated once
//! per step and held over it) and [`Dynamics::derivative`] (the continuous-time equations of
//! motion). Adding a robot means adding one file that implements this trait: the quadrotor
//! ([`quadrotor`], from a multirotor URDF read by [`urdf`]), the point mass ([`point_mass`]) and
//! the differential drive ([`diff_drive`], from a wheeled URDF read by [`wheeled`], with a
//! [`footprint`] of disks that turns with its heading).

mod batch;
pub mod diff_drive;
pub mod footprint;
pub mod point_mass;
pub mod quadrotor;
pub mod urdf;
pub mod wheeled;

pub use batch::Batch;
pub use footprint::Footprint;

use crate::state::RobotState;
use crate::volume::VolumeDims;

/// The state components every model stores first, in this order: world-frame position relative
/// to the robot's start, metres. The rollout reads them for collision checks and endpoints.
pub const POSITION_COMPONENTS: [usize; 3] = [0, 1, 2];

/// How the sampled commands drive the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommandAxes {
    /// Horizontal commands (x, y); the model holds its starting altitude (the paper's drone
    /// experiment flies at a fixed altitude and measures 2D areas).
    Planar,
    /// Commands in x, y and z; volumes are 3D.
    Spatial,
}

impl CommandAxes {
    /// Number of command axes.
    pub fn count(self) -> usize {
        match self {
            CommandAxes::Planar => 2,
            CommandAxes::Spatial => 3,
        }
    }

    /// The axes that measure volumes of `dims`: planar commands for areas at a held altitude,
    /// spatial ones for 3D volumes.
    pub fn for_volume_dims(dims: VolumeDims) -> Self {
        match dims {
            VolumeDims::Two => CommandAxes::Planar,
            VolumeDims::Three => CommandAxes::Spatial,
        }
    }
}

/// Robot dynamics integrated in batches by the rollout engine.
///
/// Commands are desired accelerations in the world frame, normalised to `[-1, 1]` per axis:
/// the model scales them by its own bound and is responsible for making every rollout
/// physically admissible (actuator saturation, attitude dynamics).
pub trait Dynamics: Send + Sync + std::fmt::Debug {
    /// Short name used in configs and benchmark tables (`quadrotor`, `point_mass`).
    fn name(&self) -> &'static str;

    /// Number of state components per lane; the first three are [`POSITION_COMPONENTS`].
    fn state_components(&self) -> usize;

    /// Number of actuation components held constant over one integration step.
    fn actuation_components(&self) -> usize;

    /// Writes `state` into every lane of `batch`, with the position set to zero: rollouts run in
    /// a world-aligned frame centred on the robot.
    fn initial_state(&self, state: &RobotState, batch: &mut Batch);

    /// Turns the commands for this step into the actuation held over it.
    ///
    /// `commands` holds `axes.count()` blocks of `state.lanes()` values in `[-1, 1]`, axis-major
    /// (x block, y block, then z block for [`CommandAxes::Spatial`]).
    fn actuate(&self, state: &Batch, commands: &[f32], axes: CommandAxes, actuation: &mut Batch);

    /// The time derivative of the state under a held actuation, written into `out`.
    fn derivative(&self, state: &Batch, actuation: &Batch, out: &mut Batch);

    /// Advances `state` by `dt` under the held `actuation` with the model's own integrator —
    /// a closed form where the equations allow it, or RK4 fused over blocks of lanes, which
    /// saves the generic integrator's passes over the whole batch. Returns `false` (the
    /// default) to have the rollout integrate with its generic RK4 ([`Dynamics::derivative`],
    /// [`Dynamics::renormalize`]). A model that returns `true` must produce what RK4 would, up
    /// to rounding.
    fn integrate(&self, _state: &mut Batch, _actuation: &Batch, _dt: f32) -> bool {
        false
    }

    /// Actuates and advances `state` by `dt` in one pass, for models whose actuation depends
    /// on the commands alone (no feedback from the state): the rollout then skips writing the
    /// actuation batch and reading it back every step. Returns `false` (the default) to have
    /// the rollout call [`Dynamics::actuate`] and then integrate. A model that returns `true`
    /// must produce exactly what [`Dynamics::actuate`] followed by [`Dynamics::integrate`]
    /// would. `commands` is laid out as for [`Dynamics::actuate`].
    fn actuate_and_integrate(
        &self,
        _state: &mut Batch,
        _commands: &[f32],
        _axes: CommandAxes,
        _dt: f32,
    ) -> bool {
        false
    }

    /// Restores invariants after a step (e.g. unit quaternions). Does nothing by default.
    fn renormalize(&self, _state: &mut Batch) {}

    /// Radius of the disk that must stay clear of obstacles, metres.
    fn collision_radius(&self) -> f64;

    /// Height of the robot's collision shape, metres (used against floor and ceiling).
    fn collision_height(&self) -> f64;

    /// The robot's footprint where one disk around its position would not do: disks of
    /// [`Dynamics::collision_radius`] at body-frame centres ([`Footprint`]), and the state
    /// components holding the cosine and sine of the heading that turn them into the rollout
    /// frame. `None` (the default): one disk centred on the position, whatever the heading.
    fn oriented_footprint(&self) -> Option<(&Footprint, [usize; 2])> {
        None
    }
}
