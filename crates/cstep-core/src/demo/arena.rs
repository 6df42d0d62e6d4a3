//! The paper's drone arena — the inner 5 m × 2.5 m area, its walls, the obstacle block — and a
//! scripted flight past the block, for the demo and for tests that want the paper's setting.
//!
//! The arena's and the LiDAR's numbers live in `config/paper_world.json`, compiled in here and
//! read by the Python package's simulation too (its `data/paper_world.json` is that file), so
//! the two sides cannot drift apart.

use std::sync::LazyLock;

use nalgebra::{Vector2, Vector3};
use serde::Deserialize;

use crate::demo::scene::{Lidar, Scene};

/// `config/paper_world.json`, as compiled in.
pub const PAPER_WORLD_JSON: &str = include_str!("../../../../config/paper_world.json");

/// The paper's world as `config/paper_world.json` states it.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PaperWorld {
    /// The arena's geometry.
    pub arena: ArenaSpec,
    /// The drone's scanner.
    pub lidar: Lidar,
}

/// The arena's geometry in `config/paper_world.json` (metres, world frame).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArenaSpec {
    /// Inner area `(x_min, y_min, x_max, y_max)`.
    pub bounds: [f64; 4],
    /// The block's extent along x.
    pub block_x: [f64; 2],
    /// The block's lateral (y) extent: the prototype's blocks are 0.5 m wide.
    pub block_width: f64,
    /// The walls' height.
    pub height: f64,
    /// Flight altitude (the paper's 1 m).
    pub altitude: f64,
    /// The fixed arena's start `(x, y)` (the Python env's default episode).
    pub start: [f64; 2],
    /// The fixed arena's goal `(x, y)`.
    pub goal: [f64; 2],
    /// The ranges the prototype draws each episode's block y, start and goal from, uniformly.
    pub draws: ArenaDraws,
}

/// The uniform ranges `[low, high]` of the prototype's random arenas.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArenaDraws {
    /// The block's centre y.
    pub block_y: [f64; 2],
    /// The start's x.
    pub start_x: [f64; 2],
    /// The start's y.
    pub start_y: [f64; 2],
    /// The goal's x.
    pub goal_x: [f64; 2],
    /// The goal's y.
    pub goal_y: [f64; 2],
}

/// The paper's world, read once from [`PAPER_WORLD_JSON`].
pub static PAPER_WORLD: LazyLock<PaperWorld> = LazyLock::new(|| {
    serde_json::from_str(PAPER_WORLD_JSON).expect("config/paper_world.json is checked by the tests")
});

/// The arena with its obstacle block in one lateral position.
#[derive(Debug, Clone, PartialEq)]
pub struct Arena {
    /// Walls and block as wall segments.
    pub scene: Scene,
    /// Inner area `(x_min, y_min, x_max, y_max)`, metres.
    pub bounds: [f64; 4],
    /// The block `(x_min, y_min, x_max, y_max)`, metres.
    pub block: [f64; 4],
    /// Flight altitude, metres (the paper's 1 m).
    pub altitude: f64,
}

impl Arena {
    /// The arena of the authors' prototype: x ∈ [−0.5, 4.5], y ∈ [−1.75, 0.75], and its
    /// obstacle, two 1.0 m × 0.5 m blocks centred at (1, `block_y`) and (2, `block_y`): one
    /// 2 m × 0.5 m block spanning x ∈ [0.5, 2.5], y ∈ [`block_y` − 0.25, `block_y` + 0.25] (the
    /// prototype draws `block_y` from U(−1, 0.3) each episode).
    pub fn paper(block_y: f64) -> Self {
        let spec = &PAPER_WORLD.arena;
        let bounds = spec.bounds;
        let half_width = spec.block_width / 2.0;
        let block = [
            spec.block_x[0],
            block_y - half_width,
            spec.block_x[1],
            block_y + half_width,
        ];
        let scene = Scene::open()
            .boxed(bounds[0], bounds[1], bounds[2], bounds[3])
            .boxed(block[0], block[1], block[2], block[3]);
        Self {
            scene,
            bounds,
            block,
            altitude: spec.altitude,
        }
    }
}

/// A flight along straight legs between waypoints at constant speed, then a hover at the end.
#[derive(Debug, Clone, PartialEq)]
pub struct Flight {
    waypoints: Vec<Vector2<f64>>,
    speed: f64,
}

impl Flight {
    /// Straight legs through `waypoints` (at least one) at `speed` m/s.
    pub fn new(waypoints: Vec<Vector2<f64>>, speed: f64) -> Self {
        Self { waypoints, speed }
    }

    /// The demo's flight through the arena with the block centred at y = 0: from the start
    /// region, down through the 1.5 m gap beside the block, up to the goal region, at 0.8 m/s.
    pub fn past_the_block() -> Self {
        Self::new(
            [(-0.2, -0.4), (0.3, -1.1), (2.7, -1.1), (3.9, -0.3)]
                .iter()
                .map(|&(x, y)| Vector2::new(x, y))
                .collect(),
            0.8,
        )
    }

    /// Seconds the legs take.
    pub fn duration(&self) -> f64 {
        self.waypoints
            .windows(2)
            .map(|w| (w[1] - w[0]).norm() / self.speed)
            .sum()
    }

    /// Position and velocity (horizontal) at time `t`; hovering at the last waypoint after the end.
    pub fn at(&self, t: f64) -> (Vector2<f64>, Vector2<f64>) {
        let mut left = t.max(0.0);
        for w in self.waypoints.windows(2) {
            let leg = w[1] - w[0];
            let time = leg.norm() / self.speed;
            if left < time {
                let direction = leg / leg.norm();
                return (w[0] + direction * self.speed * left, direction * self.speed);
            }
            left -= time;
        }
        (*self.waypoints.last().expect("waypoints"), Vector2::zeros())
    }

    /// The 3D position at time `t` at `altitude`.
    pub fn position(&self, t: f64, altitude: f64) -> Vector3<f64> {
        let (p, _) = self.at(t);
        Vector3::new(p.x, p.y, altitude)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_world_file_reads_and_holds_the_papers_setting() {
        let world = &*PAPER_WORLD;
        assert_eq!((world.lidar.beams, world.lidar.range_max), (180, 3.0)); // the paper's
        let draws = &world.arena.draws;
        for range in [
            draws.block_y,
            draws.start_x,
            draws.start_y,
            draws.goal_x,
            draws.goal_y,
        ] {
            assert!(range[0] < range[1], "{range:?}");
        }
        let [x0, y0, x1, y1] = world.arena.bounds;
        for [x, y] in [world.arena.start, world.arena.goal] {
            assert!(x0 < x && x < x1 && y0 < y && y < y1);
        }
    }

    #[test]
    fn the_flight_stays_clear_of_walls_and_block_by_more_than_the_drone_radius() {
        let arena = Arena::paper(0.0);
        let flight = Flight::past_the_block();
        let mut t = 0.0;
        while t <= flight.duration() + 1.0 {
            let (p, _) = flight.at(t);
            assert!(arena.scene.clearance(p) > 0.2, "t = {t}: {p:?}");
            t += 0.05;
        }
    }

    #[test]
    fn the_block_is_the_prototypes_two_one_by_half_metre_blocks() {
        let arena = Arena::paper(-0.6);
        assert_eq!(arena.block, [0.5, -0.85, 2.5, -0.35]);
        // Beside the block, 0.35 m above its upper face: that face is the nearest obstacle.
        let beside = Vector2::new(1.5, 0.0);
        assert!((arena.scene.clearance(beside) - 0.35).abs() < 1e-12);
    }

    #[test]
    fn the_flight_moves_at_its_speed_and_ends_at_rest() {
        let flight = Flight::past_the_block();
        let (_, v) = flight.at(1.0);
        assert!((v.norm() - 0.8).abs() < 1e-12);
        let (end, v_end) = flight.at(flight.duration() + 2.0);
        assert_eq!(v_end, Vector2::zeros());
        assert_eq!(end, Vector2::new(3.9, -0.3));
        let (a, _) = flight.at(2.0);
        let (b, _) = flight.at(2.1);
        assert!(((b - a).norm() - 0.08).abs() < 1e-9);
    }
}
