//! A warehouse hall for a ground robot — 10 m × 4 m, two pallet stacks leaving a 1.4 m door
//! between them — and a scripted drive through the door to a corner, for `cstep demo --robot
//! husky`.
//!
//! The drive keeps at least 0.7 m between the robot's centre and every wall and pallet, more
//! than the Husky's half-width (0.34 m) where it passes the door square, and its half-diagonal
//! (0.6 m) everywhere: it never touches, but the door and the corner crowd it enough for its
//! score to dip there.

use nalgebra::Vector2;

use crate::demo::arena::Flight;
use crate::demo::scene::{Lidar, Scene};

/// The hall `(x_min, y_min, x_max, y_max)`, metres.
const HALL: [f64; 4] = [-1.0, -2.0, 9.0, 2.0];

/// The pallet stacks `(x_min, y_min, x_max, y_max)`, one from each side wall, the door between.
const PALLETS: [[f64; 4]; 2] = [[3.0, -2.0, 4.0, -0.7], [3.0, 0.7, 4.0, 2.0]];

/// The route's waypoints `(x, y)`: through the door, then toward the far corner.
const ROUTE: [(f64, f64); 3] = [(0.0, 0.0), (6.5, 0.0), (8.0, 1.0)];

/// Driving speed, m/s: the Husky's top speed (1.0 m/s, Clearpath's figure).
const SPEED: f64 = 1.0;

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
        let [x0, y0, x1, y1] = HALL;
        let scene = PALLETS
            .iter()
            .fold(Scene::open().boxed(x0, y0, x1, y1), |scene, p| {
                scene.boxed(p[0], p[1], p[2], p[3])
            });
        Self {
            scene,
            bounds: HALL,
            pallets: PALLETS.to_vec(),
        }
    }

    /// The drive weaving past the pallets at the Husky's top speed.
    pub fn drive() -> Flight {
        Flight::new(
            ROUTE.iter().map(|&(x, y)| Vector2::new(x, y)).collect(),
            SPEED,
        )
    }

    /// A 2-D LiDAR as ground robots carry: one beam a degree, 0.1–10 m.
    pub fn lidar() -> Lidar {
        Lidar {
            beams: 360,
            range_min: 0.1,
            range_max: 10.0,
        }
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
