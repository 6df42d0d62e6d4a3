//! The paper's drone arena — the inner 5 m × 2.5 m area, its walls, the obstacle block — and a
//! scripted flight past the block, for the demo and for tests that want the paper's setting.

use nalgebra::{Vector2, Vector3};

use crate::scene::Scene;

/// Half the obstacle block's lateral (y) extent, metres: the prototype's blocks are 0.5 m wide.
pub const BLOCK_HALF_WIDTH: f64 = 0.25;

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
        let bounds = [-0.5, -1.75, 4.5, 0.75];
        let block = [
            0.5,
            block_y - BLOCK_HALF_WIDTH,
            2.5,
            block_y + BLOCK_HALF_WIDTH,
        ];
        let scene = Scene::open()
            .boxed(bounds[0], bounds[1], bounds[2], bounds[3])
            .boxed(block[0], block[1], block[2], block[3]);
        Self {
            scene,
            bounds,
            block,
            altitude: 1.0,
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
    /// The demo's flight through the arena with the block centred at y = 0: from the start
    /// region, down through the 1.5 m gap beside the block, up to the goal region, at 0.8 m/s.
    pub fn past_the_block() -> Self {
        Self {
            waypoints: [(-0.2, -0.4), (0.3, -1.1), (2.7, -1.1), (3.9, -0.3)]
                .iter()
                .map(|&(x, y)| Vector2::new(x, y))
                .collect(),
            speed: 0.8,
        }
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
