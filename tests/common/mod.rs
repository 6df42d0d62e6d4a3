//! Helpers shared by the integration tests: estimators from parameter overrides, scans of
//! simple scenes, and a FIFO to feed the CLI. (A live node to talk to over DDS is `live.rs`,
//! included by the tests that need it: the examples share this module and have no binary.)
#![allow(dead_code)]

use cstep::demo::arena::PAPER_WORLD;
use cstep::demo::scene::{Lidar, Scene};
use cstep::estimator::{Estimate, Estimator};
use cstep::occupancy::Scan;
use cstep::parameters::Settings;
use cstep::state::RobotState;
use nalgebra::{UnitQuaternion, Vector2, Vector3};

/// An estimator from the built-in defaults plus `name:=value` overrides.
pub fn estimator(overrides: &[&str]) -> Estimator {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let settings = Settings::load(None, "cstep_node", &overrides).expect("valid overrides");
    Estimator::from_settings(&settings).expect("the built-in robot loads")
}

/// A 360-beam, 10 m scan of `scene` from `position` (level, facing +x).
pub fn scan_of(scene: &Scene, position: Vector2<f64>) -> Scan {
    let lidar = Lidar {
        beams: 360,
        range_min: 0.02,
        range_max: 10.0,
    };
    scene.scan(position, &UnitQuaternion::identity(), &lidar)
}

/// The paper's LiDAR (180 beams, 3 m) scanning `scene` from `position`.
pub fn paper_scan(scene: &Scene, position: Vector2<f64>) -> Scan {
    scene.scan(position, &UnitQuaternion::identity(), &PAPER_WORLD.lidar)
}

/// A robot at rest at `(x, y)` at 1 m altitude.
pub fn at(x: f64, y: f64) -> RobotState {
    RobotState::at_rest(Vector3::new(x, y, 1.0))
}

/// Evaluates the paper's drone at rest at `(x, y)` in `scene` with the paper's LiDAR.
pub fn score(estimator: &Estimator, scene: &Scene, state: &RobotState) -> Estimate {
    let scan = paper_scan(scene, state.position.xy());
    estimator.evaluate(state, &scan)
}

/// A fresh FIFO at `path` (replacing any file there): an input that never ends, which the CLI must
/// refuse rather than block on.
pub fn make_fifo(path: &std::path::Path) {
    let _ = std::fs::remove_file(path);
    let made = std::process::Command::new("mkfifo").arg(path).status();
    assert!(
        made.expect("mkfifo runs").success(),
        "mkfifo {}",
        path.display()
    );
}
