//! Algorithm 1 of the paper end to end: sample controls, roll them out against the scan,
//! measure the reachable and terminal volumes, and take the log of the free volume.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use std::borrow::Cow;

use crate::model::diff_drive::DiffDrive;
use crate::model::point_mass::PointMass;
use crate::model::quadrotor::Quadrotor;
use crate::model::urdf::{RobotDescription, UrdfError};
use crate::model::wheeled::WheeledDescription;
use crate::model::{CommandAxes, Dynamics};
use crate::occupancy::{Occupancy, OccupancyOptions, Scan, ScanFrame};
use crate::parameters::{ModelKind, RobotSource, Settings, BUILTIN_ROBOTS};
use crate::rollout::{roll_out, Rollout};
use crate::sampling::{sample, Controls, SamplerKind};
use crate::state::RobotState;
use crate::volume::{self, EstimatorKind, VolumeDims, Volumes};

/// Free volumes below this (m² or m³) are clamped to it before the log: the smallest volume
/// the estimator reports, so the score never reaches −∞.
pub const MIN_FREE_VOLUME: f64 = 1e-4;

/// The empowerment floor, `ln(MIN_FREE_VOLUME)` ≈ −9.21 nats: published whenever the free
/// volume is zero or too small to measure, together with `valid = false` or a status.
pub const EMPOWERMENT_FLOOR: f64 = -9.210_340_371_976_184;

/// The point-mass acceleration bound when none is configured: the prototype's
/// `F_MAX / m = 9.81 + 0.6` m/s².
pub const POINT_MASS_DEFAULT_ACCELERATION: f64 = 10.41;

/// Why an estimate is, or is not, a measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// A measured score.
    Ok,
    /// Some trajectories are free but their volume is below [`MIN_FREE_VOLUME`]: the score is
    /// the floor, still valid.
    BelowFloor,
    /// Every sampled trajectory collides: the free volume is zero.
    AllColliding,
    /// The robot already overlaps an obstacle, the floor or the ceiling.
    InCollision,
    /// The scan has no beams.
    EmptyScan,
    /// No beam of the scan holds a usable reading.
    NoValidBeams,
    /// The input could not be scored (a malformed state, scan or goal); front ends publish
    /// the reason instead of this status's text.
    InvalidInput,
}

impl Status {
    /// Whether the score is a measurement (`Empowerment.valid`).
    pub fn is_valid(self) -> bool {
        matches!(self, Status::Ok | Status::BelowFloor)
    }

    /// The text published in `Empowerment.status`.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::BelowFloor => "free volume below the measurable floor",
            Status::AllColliding => "every sampled trajectory collides",
            Status::InCollision => "robot already in collision",
            Status::EmptyScan => "scan has no beams",
            Status::NoValidBeams => "scan has no valid beams",
            Status::InvalidInput => "invalid input",
        }
    }
}

/// The result of one evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// `ln(max(free volume, MIN_FREE_VOLUME))`, nats; always finite.
    pub empowerment: f64,
    /// Reachable, terminal and free volumes.
    pub volumes: Volumes,
    /// Horizon `T`, seconds.
    pub horizon: f64,
    /// Trajectories sampled.
    pub num_trajectories: usize,
    /// Trajectories that collided.
    pub num_colliding: usize,
    /// Whether the score is a measurement, and if not why.
    pub status: Status,
    /// Endpoints (relative to the robot, world-aligned) and their labels, for visualisation.
    pub rollout: Rollout,
    /// Wall-clock time the evaluation took.
    pub elapsed: Duration,
}

impl Estimate {
    /// Whether the score is a measurement.
    pub fn valid(&self) -> bool {
        self.status.is_valid()
    }
}

/// Everything about an evaluation that does not change from state to state.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimatorSettings {
    /// Horizon `T`, seconds.
    pub horizon: f64,
    /// Number of sampled trajectories.
    pub trajectories: usize,
    /// Integration steps per trajectory.
    pub steps: usize,
    /// Control sampler.
    pub sampler: SamplerKind,
    /// Seed of the control sample used by [`Estimator::evaluate`].
    pub seed: u64,
    /// Dimension of volumes and commands.
    pub volume_dims: VolumeDims,
    /// Free-volume estimator.
    pub estimator: EstimatorKind,
    /// Robot geometry and scan policies.
    pub occupancy: OccupancyOptions,
}

/// Evaluates C-STEP for one robot; cheap to call repeatedly (the control sample is drawn once
/// per seed and reused).
#[derive(Debug)]
pub struct Estimator {
    model: Box<dyn Dynamics>,
    settings: EstimatorSettings,
    controls: Mutex<Option<(u64, Arc<Controls>)>>,
}

/// The URDF text the configuration names (a built-in robot, a file, or the text itself) and
/// the name messages give it.
fn urdf_text(settings: &Settings) -> Result<(Cow<'_, str>, String), UrdfError> {
    match &settings.robot_description {
        RobotSource::Builtin(name) => {
            let text = BUILTIN_ROBOTS
                .iter()
                .find(|(builtin, _)| builtin == name)
                .map(|(_, text)| *text)
                .unwrap_or_else(|| unreachable!("the configuration accepts only built-in names"));
            let short = name.trim_start_matches("builtin:");
            Ok((Cow::Borrowed(text), format!("built-in {short}")))
        }
        RobotSource::File(path) => {
            let file = path.display().to_string();
            crate::input::file::read_to_string(path)
                .map(|text| (Cow::Owned(text), file.clone()))
                .map_err(|error| UrdfError::Io { file, error })
        }
        RobotSource::Text(xml) => Ok((
            Cow::Borrowed(xml.as_str()),
            "robot_description (URDF text)".to_owned(),
        )),
    }
}

/// The multirotor description the configuration names (the quadrotor's and the point mass's).
pub fn robot_description(settings: &Settings) -> Result<RobotDescription, UrdfError> {
    let (xml, source) = urdf_text(settings)?;
    RobotDescription::from_str(&xml, &source)
}

/// The wheeled robot's description the configuration names (the differential drive's).
pub fn wheeled_description(settings: &Settings) -> Result<WheeledDescription, UrdfError> {
    let (xml, source) = urdf_text(settings)?;
    WheeledDescription::from_str(&xml, &source)
}

/// The `<robot name>` of the configured URDF, whichever model reads it: the hardware id the
/// node's diagnostics report.
pub fn robot_name(settings: &Settings) -> Result<String, UrdfError> {
    let (xml, source) = urdf_text(settings)?;
    let doc = crate::model::urdf::document(&xml, &source)?;
    Ok(doc
        .root_element()
        .attribute("name")
        .unwrap_or_default()
        .to_owned())
}

impl Estimator {
    /// An estimator for `model` with `settings`.
    pub fn new(model: Box<dyn Dynamics>, settings: EstimatorSettings) -> Self {
        Self {
            model,
            settings,
            controls: Mutex::new(None),
        }
    }

    /// Builds the model the configuration names (loading its URDF) and the estimator around it.
    pub fn from_settings(settings: &Settings) -> Result<Self, UrdfError> {
        let model: Box<dyn Dynamics> = match settings.model {
            ModelKind::Quadrotor => Box::new(Quadrotor::new(
                &robot_description(settings)?,
                settings.max_acceleration,
            )),
            ModelKind::PointMass => {
                let description = robot_description(settings)?;
                Box::new(PointMass::new(
                    settings
                        .max_acceleration
                        .unwrap_or(POINT_MASS_DEFAULT_ACCELERATION),
                    description.collision_radius,
                    description.collision_height,
                ))
            }
            ModelKind::DiffDrive => Box::new(DiffDrive::new(
                &wheeled_description(settings)?,
                settings.wheel_max_speed,
                settings.wheel_max_acceleration,
                settings.wheel_separation_multiplier,
            )),
        };
        let occupancy = OccupancyOptions {
            robot_radius: settings.robot_radius.unwrap_or(model.collision_radius()),
            robot_height: model.collision_height(),
            unknown_space: settings.unknown_space,
            floor: settings.floor_height,
            ceiling: settings.ceiling_height,
        };
        Ok(Self::new(
            model,
            EstimatorSettings {
                horizon: settings.horizon,
                trajectories: settings.trajectories,
                steps: settings.steps,
                sampler: settings.sampler,
                seed: settings.seed,
                volume_dims: settings.volume_dims,
                estimator: settings.estimator,
                occupancy,
            },
        ))
    }

    /// The model rolled out.
    pub fn model(&self) -> &dyn Dynamics {
        self.model.as_ref()
    }

    /// The settings in effect.
    pub fn settings(&self) -> &EstimatorSettings {
        &self.settings
    }

    /// C-STEP of `state` given `scan` from a LiDAR fixed to the body, with the configured
    /// seed.
    pub fn evaluate(&self, state: &RobotState, scan: &Scan) -> Estimate {
        self.evaluate_in(state, scan, ScanFrame::Body)
    }

    /// C-STEP of `state` given `scan` with bearings in `frame`, with the configured seed.
    pub fn evaluate_in(&self, state: &RobotState, scan: &Scan, frame: ScanFrame) -> Estimate {
        self.evaluate_with_seed(state, scan, frame, self.settings.seed)
    }

    /// C-STEP of `state` given `scan` with bearings in `frame`, with the control sample of
    /// `seed`.
    pub fn evaluate_with_seed(
        &self,
        state: &RobotState,
        scan: &Scan,
        frame: ScanFrame,
        seed: u64,
    ) -> Estimate {
        let started = Instant::now();
        let s = &self.settings;
        let mut estimate = self.floor(Status::Ok);
        let attitude = frame.read_with(&state.attitude);
        let occupancy = Occupancy::build(scan, &attitude, state.position.z, &s.occupancy);
        let summary = occupancy.summary();
        estimate.status = if scan.ranges.is_empty() {
            Status::EmptyScan
        } else if summary.hits + summary.no_returns == 0 {
            Status::NoValidBeams
        } else if occupancy.in_collision_at_start() {
            Status::InCollision
        } else {
            let controls = self.controls(seed);
            let rollout = roll_out(self.model.as_ref(), state, &controls, s.horizon, &occupancy);
            estimate.num_colliding = rollout.num_colliding();
            estimate.volumes = volume::estimate(
                &rollout.endpoints,
                &rollout.terminal,
                s.volume_dims,
                s.estimator,
            );
            estimate.rollout = rollout;
            if estimate.num_colliding == s.trajectories {
                estimate.volumes.free = 0.0;
                Status::AllColliding
            } else if estimate.volumes.free < MIN_FREE_VOLUME {
                Status::BelowFloor
            } else {
                estimate.empowerment = estimate.volumes.free.ln();
                Status::Ok
            }
        };
        estimate.elapsed = started.elapsed();
        estimate
    }

    /// The estimate of a state its caller knows to be in collision (a simulator that saw
    /// contact): the floor with [`Status::InCollision`], as for a robot whose scan shows it
    /// overlapping an obstacle, without reading a scan or rolling out.
    pub fn known_collision(&self) -> Estimate {
        self.floor(Status::InCollision)
    }

    /// The estimate of input that could not be scored: the floor with [`Status::InvalidInput`],
    /// no trajectory counted as colliding (none was rolled out).
    pub fn invalid_input(&self) -> Estimate {
        Estimate {
            num_colliding: 0,
            ..self.floor(Status::InvalidInput)
        }
    }

    /// The floor estimate with `status`: zero volumes, every trajectory counted as colliding,
    /// no rollout.
    fn floor(&self, status: Status) -> Estimate {
        let s = &self.settings;
        Estimate {
            empowerment: EMPOWERMENT_FLOOR,
            volumes: Volumes {
                reachable: 0.0,
                terminal: 0.0,
                free: 0.0,
                hull_vertices: 0,
                terminal_clusters: 0,
            },
            horizon: s.horizon,
            num_trajectories: s.trajectories,
            num_colliding: s.trajectories,
            status,
            rollout: Rollout::default(),
            elapsed: Duration::ZERO,
        }
    }

    /// The control sample for `seed`, drawn once and kept while the seed stays the same.
    fn controls(&self, seed: u64) -> Arc<Controls> {
        let mut cache = self.controls.lock().unwrap_or_else(|e| e.into_inner());
        match cache.as_ref() {
            Some((cached, controls)) if *cached == seed => controls.clone(),
            _ => {
                let s = &self.settings;
                let axes = CommandAxes::for_volume_dims(s.volume_dims);
                let controls = Arc::new(sample(s.sampler, s.trajectories, s.steps, axes, seed));
                *cache = Some((seed, controls.clone()));
                controls
            }
        }
    }
}
