//! A 2D world of wall segments and a simulated LiDAR that scans it.
//!
//! Tests, benchmarks and the demo need scans of known places (open space, corridors, the
//! paper's arena); ray casting a handful of segments is all that takes, so it is written here
//! rather than pulled in from a physics engine.

use nalgebra::{UnitQuaternion, Vector2, Vector3};
use serde::Deserialize;

use crate::occupancy::Scan;
use crate::state::RobotState;

/// A straight wall between two points, metres (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    /// One end.
    pub a: Vector2<f64>,
    /// The other end.
    pub b: Vector2<f64>,
}

/// A set of walls.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// The walls.
    pub walls: Vec<Wall>,
}

/// The scanner: beams evenly spread over a full turn, as the paper's 2D LiDAR.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lidar {
    /// Number of beams over 360°.
    pub beams: usize,
    /// Shortest range, metres.
    pub range_min: f64,
    /// Longest range, metres; farther returns read `+inf`.
    pub range_max: f64,
}

impl Scene {
    /// An empty world.
    pub fn open() -> Self {
        Self::default()
    }

    /// Adds a wall from `(x0, y0)` to `(x1, y1)`.
    pub fn wall(mut self, x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        self.walls.push(Wall {
            a: Vector2::new(x0, y0),
            b: Vector2::new(x1, y1),
        });
        self
    }

    /// Adds the outline of the axis-aligned box `[x0, x1] × [y0, y1]`.
    pub fn boxed(self, x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        self.wall(x0, y0, x1, y0)
            .wall(x1, y0, x1, y1)
            .wall(x1, y1, x0, y1)
            .wall(x0, y1, x0, y0)
    }

    /// A corridor along x of the given width centred on y = 0, `length` long each way.
    pub fn corridor(width: f64, length: f64) -> Self {
        let h = width / 2.0;
        Self::open()
            .wall(-length, h, length, h)
            .wall(-length, -h, length, -h)
    }

    /// Distance from `origin` along the unit vector `direction` to the nearest wall.
    pub fn ray_cast(&self, origin: Vector2<f64>, direction: Vector2<f64>) -> Option<f64> {
        self.walls
            .iter()
            .filter_map(|w| {
                let edge = w.b - w.a;
                let denom = direction.perp(&edge);
                if denom.abs() < 1e-12 {
                    return None;
                }
                let offset = w.a - origin;
                let t = offset.perp(&edge) / denom;
                let u = offset.perp(&direction) / denom;
                (t >= 0.0 && (0.0..=1.0).contains(&u)).then_some(t)
            })
            .min_by(f64::total_cmp)
    }

    /// Distance from `point` to the nearest wall.
    pub fn clearance(&self, point: Vector2<f64>) -> f64 {
        self.walls
            .iter()
            .map(|w| {
                let edge = w.b - w.a;
                let t = ((point - w.a).dot(&edge) / edge.norm_squared()).clamp(0.0, 1.0);
                (w.a + t * edge - point).norm()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The scan a level LiDAR at `position` facing `attitude`'s heading would see (body-frame
    /// bearings from −π, counter-clockwise).
    pub fn scan(
        &self,
        position: Vector2<f64>,
        attitude: &UnitQuaternion<f64>,
        lidar: &Lidar,
    ) -> Scan {
        let yaw = attitude.euler_angles().2;
        let increment = std::f64::consts::TAU / lidar.beams as f64;
        let angle_min = -std::f64::consts::PI;
        let ranges = (0..lidar.beams)
            .map(|i| {
                let bearing = yaw + angle_min + i as f64 * increment;
                let direction = Vector2::new(bearing.cos(), bearing.sin());
                match self.ray_cast(position, direction) {
                    Some(r) if r <= lidar.range_max => r.max(lidar.range_min) as f32,
                    _ => f32::INFINITY,
                }
            })
            .collect();
        Scan {
            angle_min,
            angle_increment: increment,
            range_min: lidar.range_min,
            range_max: lidar.range_max,
            ranges,
        }
    }
}

/// The fixed case `cstep bench` and `cargo bench` measure: a 2.5 m corridor closed 2.5 m ahead,
/// a 360-beam 3 m scan, the robot at 1 m altitude flying at 1 m/s toward the end wall — so
/// free and terminal trajectories both occur and every stage of an evaluation runs.
pub fn benchmark_case() -> (RobotState, Scan) {
    let scene = Scene::corridor(2.5, 20.0).wall(2.5, -1.25, 2.5, 1.25);
    let lidar = Lidar {
        beams: 360,
        range_min: 0.02,
        range_max: 3.0,
    };
    let state =
        RobotState::at_rest(Vector3::new(0.0, 0.3, 1.0)).with_velocity(Vector3::new(1.0, 0.0, 0.0));
    let scan = scene.scan(state.position.xy(), &state.attitude, &lidar);
    (state, scan)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_corridor_scan_sees_both_walls_and_nothing_along_it() {
        let scene = Scene::corridor(2.0, 10.0);
        let lidar = Lidar {
            beams: 360,
            range_min: 0.05,
            range_max: 3.0,
        };
        let scan = scene.scan(Vector2::new(0.0, 0.25), &UnitQuaternion::identity(), &lidar);
        let at = |deg: f64| scan.ranges[((deg + 180.0) / 360.0 * 360.0).round() as usize % 360];
        assert!((at(90.0) - 0.75).abs() < 1e-5);
        assert!((at(-90.0) - 1.25).abs() < 1e-5);
        assert_eq!(at(0.0), f32::INFINITY);
        assert!((scene.clearance(Vector2::new(0.0, 0.25)) - 0.75).abs() < 1e-12);
    }

    #[test]
    fn the_scan_turns_with_the_robot() {
        let scene = Scene::open().wall(1.0, -5.0, 1.0, 5.0);
        let lidar = Lidar {
            beams: 4,
            range_min: 0.05,
            range_max: 3.0,
        };
        let facing_x = scene.scan(Vector2::zeros(), &UnitQuaternion::identity(), &lidar);
        assert!((facing_x.ranges[2] - 1.0).abs() < 1e-6); // bearing 0
        let facing_y = UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2);
        let turned = scene.scan(Vector2::zeros(), &facing_y, &lidar);
        assert!((turned.ranges[1] - 1.0).abs() < 1e-6); // bearing −90° in the body frame
    }
}
