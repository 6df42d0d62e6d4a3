//! A differential-drive (or skid-steer) ground robot built from its URDF
//! ([`WheeledDescription`]): two wheel sides whose rim speeds are the actuators, the unicycle
//! kinematics they drive, and a footprint of disks that turns with the heading.
//!
//! Controls are what the robot can realise: the two normalised commands of a step are the
//! left and right rims' accelerations, scaled by the acceleration bound and held over the step,
//! with each rim's speed kept within the speed bound (a rim at its top speed is not pushed
//! further). Piecewise-constant wheel accelerations at their bounds — the default bang-bang
//! sampler — are the drive's extreme controls, as for the drone. A skid steer (the Husky, four
//! wheels) is driven as a differential drive about the centroid of its wheels, its left wheels
//! at one speed, its right ones at another, on an effective track wider than the geometric one
//! ([`DiffDrive::effective_track`]): its wheels scrub sideways in a turn, so it turns slower
//! than its rims would without slip. That is how ros2_control's `diff_drive_controller` drives
//! and odometers a skid steer (its `wheel_separation_multiplier`; Clearpath calibrated 1.875
//! for the Husky); the turn's slip varies with its radius, which one multiplier cannot follow.
//!
//! Bounds: the rim speed from the wheel joints' `<limit velocity>` (times the radius), the rim
//! acceleration from their `<limit effort>` against the mass and yaw inertia
//! ([`WheeledDescription::max_rim_acceleration`]); where the URDF gives none (most, the Husky
//! included: continuous joints need no limit), from the parameters `wheel_max_speed` and
//! `wheel_max_acceleration` ([`Bound`] records which).
//!
//! State, per lane (f32, component-major in a [`Batch`]):
//!
//! | components | meaning |
//! |---|---|
//! | 0–2 ([`POSITION_COMPONENTS`]) | the root frame's origin relative to the start, m (z stays 0) |
//! | 3, 4 ([`HEADING`]) | cosine and sine of the heading (yaw) |
//! | 5, 6 ([`RIM_SPEEDS`]) | left and right rim speeds, m/s |
//!
//! The heading is kept as its cosine and sine so that neither the equations nor the footprint
//! checks evaluate a trigonometric function. Equations of motion, with `v = (v_l + v_r)/2`,
//! `ω = (v_r − v_l)/effective_track` and `(a_x, a_y)` the drive centre in the root frame:
//! `ṗ = v·(cos θ, sin θ) − ω·R(θ)·(−a_y, a_x)` (the root frame's origin moves with the drive
//! centre and around it), `(cos θ, sin θ)˙ = ω·(−sin θ, cos θ)`, `v̇_l = a_l`, `v̇_r = a_r`.

use super::footprint::Footprint;
use super::wheeled::WheeledDescription;
use super::{Batch, CommandAxes, Dynamics, POSITION_COMPONENTS};
use crate::state::RobotState;

/// State components holding the cosine and sine of the heading.
pub const HEADING: [usize; 2] = [3, 4];
/// State components holding the left and right rim speeds, m/s.
pub const RIM_SPEEDS: [usize; 2] = [5, 6];
/// Number of state components per lane.
pub const STATE_COMPONENTS: usize = 7;
/// Actuation components: the left and right rim accelerations held over a step, m/s².
pub const ACTUATION_COMPONENTS: usize = 2;

// The lane loops rely on this layout.
const _: () = assert!(
    POSITION_COMPONENTS[0] == 0
        && POSITION_COMPONENTS[2] == 2
        && HEADING[0] == 3
        && HEADING[1] == 4
        && RIM_SPEEDS[0] == 5
        && RIM_SPEEDS[1] == STATE_COMPONENTS - 1
);

/// Where a bound came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// From the wheel joints' `<limit>` elements.
    Urdf(f64),
    /// From a parameter, the URDF giving none.
    Parameter(f64),
}

impl Bound {
    /// The bound's value.
    pub fn value(self) -> f64 {
        match self {
            Bound::Urdf(v) | Bound::Parameter(v) => v,
        }
    }

    /// `Urdf(v)` if the URDF gives `v`, else `Parameter(fallback)`.
    fn from(urdf: Option<f64>, fallback: f64) -> Self {
        urdf.map_or(Bound::Parameter(fallback), Bound::Urdf)
    }
}

/// The effective track over the geometric one for a skid steer whose calibration is not
/// given: Clearpath's figure for the Husky (`husky_control/config/control.yaml`,
/// `wheel_separation_multiplier: 1.875`).
pub const SKID_STEER_SEPARATION_MULTIPLIER: f64 = 1.875;

/// A differential drive whose geometry, mass and limits come from a URDF.
#[derive(Debug, Clone)]
pub struct DiffDrive {
    description: WheeledDescription,
    footprint: Footprint,
    max_speed: Bound,
    max_acceleration: Bound,
    separation_multiplier: f64,
    /// 1 / effective track, 1/m.
    inv_track: f32,
    /// The drive centre in the root frame, m.
    centre: [f32; 2],
}

impl DiffDrive {
    /// The model of `description`, with `max_speed` (m/s) and `max_acceleration` (m/s²) bounding
    /// each rim where the wheel joints' limits do not, turning on `separation_multiplier` times
    /// the geometric track (`None`: 1 for one wheel a side, [`SKID_STEER_SEPARATION_MULTIPLIER`]
    /// for more).
    ///
    /// # Panics
    /// If a fallback bound or the multiplier is not finite and positive.
    pub fn new(
        description: &WheeledDescription,
        max_speed: f64,
        max_acceleration: f64,
        separation_multiplier: Option<f64>,
    ) -> Self {
        let separation_multiplier =
            separation_multiplier.unwrap_or_else(|| default_separation_multiplier(description));
        for (name, value) in [
            ("max_speed", max_speed),
            ("max_acceleration", max_acceleration),
            ("separation_multiplier", separation_multiplier),
        ] {
            assert!(
                value.is_finite() && value > 0.0,
                "{name} must be finite and positive, got {value}"
            );
        }
        Self {
            footprint: Footprint::covering(&description.outline),
            max_speed: Bound::from(description.max_rim_speed(), max_speed),
            max_acceleration: Bound::from(description.max_rim_acceleration(), max_acceleration),
            separation_multiplier,
            inv_track: (1.0 / (description.track * separation_multiplier)) as f32,
            centre: description.drive_centre.map(|c| c as f32),
            description: description.clone(),
        }
    }

    /// The description this model was built from.
    pub fn description(&self) -> &WheeledDescription {
        &self.description
    }

    /// The footprint checked against the scan.
    pub fn footprint(&self) -> &Footprint {
        &self.footprint
    }

    /// Each rim's top speed, m/s, and where it came from.
    pub fn max_speed(&self) -> Bound {
        self.max_speed
    }

    /// Each rim's acceleration bound, m/s², and where it came from.
    pub fn max_acceleration(&self) -> Bound {
        self.max_acceleration
    }

    /// The effective track over the geometric one.
    pub fn separation_multiplier(&self) -> f64 {
        self.separation_multiplier
    }

    /// The track the drive turns on, m: `ω = (v_r − v_l) / effective_track`.
    pub fn effective_track(&self) -> f64 {
        self.description.track * self.separation_multiplier
    }
}

/// The effective track over the geometric one that `description`'s drive turns on unless a
/// calibration says otherwise: [`SKID_STEER_SEPARATION_MULTIPLIER`] for a skid steer, 1 for one
/// wheel a side.
pub fn default_separation_multiplier(description: &WheeledDescription) -> f64 {
    if description.is_skid_steer() {
        SKID_STEER_SEPARATION_MULTIPLIER
    } else {
        1.0
    }
}

impl Dynamics for DiffDrive {
    fn name(&self) -> &'static str {
        "diff_drive"
    }

    fn state_components(&self) -> usize {
        STATE_COMPONENTS
    }

    fn actuation_components(&self) -> usize {
        ACTUATION_COMPONENTS
    }

    /// The heading is the attitude's yaw; the forward speed is the drive centre's velocity
    /// along the heading and the turn rate the body's z rate, split over the two sides and
    /// limited to the rims' top speed. Sideways motion, which the wheels cannot make, is dropped.
    fn initial_state(&self, state: &RobotState, batch: &mut Batch) {
        let (_, _, yaw) = state.attitude.euler_angles();
        let (sin, cos) = yaw.sin_cos();
        let omega = state.body_rates.z;
        // The drive centre moves at ṗ + ω × R·a; along the heading that adds −ω·a_y.
        let forward = cos * state.velocity.x + sin * state.velocity.y
            - omega * self.description.drive_centre[1];
        let half_turn = 0.5 * omega * self.effective_track();
        let top = self.max_speed.value();
        let values = [
            0.0,
            0.0,
            0.0,
            cos,
            sin,
            (forward - half_turn).clamp(-top, top),
            (forward + half_turn).clamp(-top, top),
        ];
        for (c, value) in values.into_iter().enumerate() {
            batch.fill_component(c, value as f32);
        }
    }

    /// Rim accelerations `command × max_acceleration`, zero where a rim at its top speed would
    /// be pushed beyond it. The z command of [`CommandAxes::Spatial`] is ignored: the robot
    /// stays on the ground.
    fn actuate(&self, state: &Batch, commands: &[f32], _axes: CommandAxes, actuation: &mut Batch) {
        let n = state.lanes();
        let bound = self.max_acceleration.value() as f32;
        let top = self.max_speed.value() as f32;
        for side in 0..2 {
            let speeds = state.component(RIM_SPEEDS[side]);
            let commanded = &commands[side * n..(side + 1) * n];
            for (a, (&c, &v)) in actuation
                .component_mut(side)
                .iter_mut()
                .zip(commanded.iter().zip(speeds))
            {
                let push = bound * c.clamp(-1.0, 1.0);
                let saturated = (push > 0.0 && v >= top) || (push < 0.0 && v <= -top);
                *a = if saturated { 0.0 } else { push };
            }
        }
    }

    fn derivative(&self, state: &Batch, actuation: &Batch, out: &mut Batch) {
        let [_, _, _, cos, sin, left, right] = components(state);
        let [ax, ay] = self.centre;
        let inv_track = self.inv_track;
        let mut out = out.components_mut().into_iter();
        let mut next = || out.next().expect("seven state components");
        let (dx, dy, dz, dcos, dsin) = (next(), next(), next(), next(), next());
        for i in 0..state.lanes() {
            let v = 0.5 * (left[i] + right[i]);
            let omega = (right[i] - left[i]) * inv_track;
            let (c, s) = (cos[i], sin[i]);
            dx[i] = v * c + omega * (s * ax + c * ay);
            dy[i] = v * s - omega * (c * ax - s * ay);
            dcos[i] = -s * omega;
            dsin[i] = c * omega;
        }
        dz.fill(0.0);
        next().copy_from_slice(actuation.component(0));
        next().copy_from_slice(actuation.component(1));
    }

    /// Rescales the heading's cosine and sine to a unit vector and brings a rim that overshot
    /// its top speed within the step back to it.
    fn renormalize(&self, state: &mut Batch) {
        let top = self.max_speed.value() as f32;
        let mut parts = state.components_mut().into_iter().skip(HEADING[0]);
        let (cos, sin) = (parts.next().expect("cos"), parts.next().expect("sin"));
        for (c, s) in cos.iter_mut().zip(sin.iter_mut()) {
            let inv = 1.0 / (*c * *c + *s * *s).sqrt();
            *c *= inv;
            *s *= inv;
        }
        for speeds in parts {
            for v in speeds {
                *v = v.clamp(-top, top);
            }
        }
    }

    /// The radius of the footprint's disks.
    fn collision_radius(&self) -> f64 {
        self.footprint.radius()
    }

    /// The vertical extent of the chassis and wheels.
    fn collision_height(&self) -> f64 {
        let [low, high] = self.description.outline.z;
        high - low
    }

    fn oriented_footprint(&self) -> Option<(&Footprint, [usize; 2])> {
        Some((&self.footprint, HEADING))
    }
}

/// The seven state components of `batch`.
fn components(batch: &Batch) -> [&[f32]; STATE_COMPONENTS] {
    let parts = batch.components_ref();
    std::array::from_fn(|c| parts[c])
}
