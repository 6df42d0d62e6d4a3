//! A warehouse hall for a ground robot — 10 m × 4 m, two pallet stacks leaving a 1.4 m door
//! between them — and a scripted drive through the door to a corner, for `cstep demo --robot
//! husky`.
//!
//! The drive keeps at least 0.7 m between the robot's centre and every wall and pallet, more
//! than the Husky's half-width (0.34 m) where it passes the door square, and its half-diagonal
//! (0.6 m) everywhere: it never touches, but the door and the corner crowd it enough for its
//! score to dip there.

use std::sync::LazyLock;

use nalgebra::Vector2;
use serde::Deserialize;

use crate::demo::arena::Flight;
use crate::demo::scene::{Lidar, Scene};

/// `config/husky_hall.json`, as compiled in: the hall's, the drive's and the LiDAR's numbers,
/// read by the Python package's Husky world too (its `data/husky_hall.json` is that file).
pub const HUSKY_HALL_JSON: &str = include_str!("../../../../config/husky_hall.json");

/// The hall world as `config/husky_hall.json` states it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HallWorld {
    /// The hall's geometry.
    pub hall: HallSpec,
    /// The demo's scripted drive.
    pub drive: DriveSpec,
    /// The ground robot's scanner.
    pub lidar: Lidar,
    /// How the Python env draws its tasks.
    pub draws: HallDraws,
}

/// The hall's geometry (metres, world frame).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HallSpec {
    /// The hall `(x_min, y_min, x_max, y_max)`.
    pub bounds: [f64; 4],
    /// The pallet stacks `(x_min, y_min, x_max, y_max)`, one from each side wall, the door
    /// between.
    pub pallets: Vec<[f64; 4]>,
    /// The walls' height (the simulation's boxes; the scan is planar).
    pub wall_height: f64,
    /// The pallet stacks' height (likewise).
    pub pallet_height: f64,
}

/// The demo's drive: waypoints `(x, y)` through the door toward the far corner, and its speed.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveSpec {
    /// The route's waypoints.
    pub route: Vec<[f64; 2]>,
    /// Driving speed, m/s: the Husky's top speed (1.0 m/s, Clearpath's figure).
    pub speed: f64,
}

/// How the Python env draws starts and goals in the hall.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HallDraws {
    /// The least distance from a drawn start or goal to every wall and pallet, metres.
    pub margin: f64,
}

/// The hall world, read once from [`HUSKY_HALL_JSON`].
pub static HUSKY_HALL: LazyLock<HallWorld> = LazyLock::new(|| {
    serde_json::from_str(HUSKY_HALL_JSON).expect("config/husky_hall.json is checked by the tests")
});

/// A hall with its pallets.
#[derive(Debug, Clone, PartialEq)]
pub struct Aisle {
    /// Walls and pallets as wall segments.
    pub scene: Scene,
    /// The hall `(x_min, y_min, x_max, y_max)`, metres.
    pub bounds: [f64; 4],
    /// The pallets, each `(x_min, y_min, x_max, y_max)`, metres.
    pub pallets: Vec<[f64; 4]>,
}

impl Aisle {
    /// The demo's hall.
    pub fn hall() -> Self {
        let spec = &HUSKY_HALL.hall;
        let [x0, y0, x1, y1] = spec.bounds;
        let scene = spec
            .pallets
            .iter()
            .fold(Scene::open().boxed(x0, y0, x1, y1), |scene, p| {
                scene.boxed(p[0], p[1], p[2], p[3])
            });
        Self {
            scene,
            bounds: spec.bounds,
            pallets: spec.pallets.clone(),
        }
    }

    /// The drive weaving past the pallets at the Husky's top speed.
    pub fn drive() -> Flight {
        let drive = &HUSKY_HALL.drive;
        Flight::new(
            drive
                .route
                .iter()
                .map(|&[x, y]| Vector2::new(x, y))
                .collect(),
            drive.speed,
        )
    }

    /// A 2-D LiDAR as ground robots carry: one beam a degree, 0.1–10 m.
    pub fn lidar() -> Lidar {
        HUSKY_HALL.lidar
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drive_passes_the_door_in_its_middle_and_keeps_clear_of_everything() {
        let aisle = Aisle::hall();
        let drive = Aisle::drive();
        let mut closest = f64::INFINITY;
        let mut t = 0.0;
        while t <= drive.duration() + 1.0 {
            let (p, _) = drive.at(t);
            closest = closest.min(aisle.scene.clearance(p));
            t += 0.02;
        }
        assert!((closest - 0.7).abs() < 1e-9, "closest approach {closest} m");
    }

    #[test]
    fn the_lidar_sees_the_pallet_beside_the_route() {
        let aisle = Aisle::hall();
        let (p, _) = Aisle::drive().at(3.5);
        let scan = aisle
            .scene
            .scan(p, &nalgebra::UnitQuaternion::identity(), &Aisle::lidar());
        assert_eq!(scan.ranges.len(), 360);
        assert!(scan.ranges.iter().all(|r| r.is_finite()), "a closed hall");
        // Straight down (beam 90 of 360, from −π): the lower stack's top face at y = −0.7.
        assert!(
            (f64::from(scan.ranges[90]) - (p.y + 0.7)).abs() < 1e-5,
            "{p:?}"
        );
    }
}
