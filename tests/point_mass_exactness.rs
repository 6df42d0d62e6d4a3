//! The point mass against its exact reachable set: from velocity v with |a_i| ≤ A per axis,
//! the positions reachable at T form the box v·T ± A·T²/2. A wall cutting the box leaves
//! exactly the part of the box on the near side (from rest, every endpoint on the near side is
//! reached by a monotone path, so path-wise checks remove nothing else).

mod common;

use common::{at, estimator, scan_of};
use cstep::demo::scene::Scene;
use nalgebra::{Vector2, Vector3};

const A: f64 = 2.0;
const SEEDS: [u64; 5] = [0, 1, 2, 3, 4];

fn free_volume(
    estimator_name: &str,
    trajectories: usize,
    scene: &Scene,
    velocity: Vector3<f64>,
    seed: u64,
) -> (f64, f64) {
    let e = estimator(&[
        "model:=point_mass",
        "max_acceleration:=2.0",
        "unknown_space:=free",
        "sampler:=bang_bang",
        &format!("estimator:={estimator_name}"),
        &format!("trajectories:={trajectories}"),
        &format!("seed:={seed}"),
    ]);
    let state = at(0.0, 0.0).with_velocity(velocity);
    let estimate = e.evaluate(&state, &scan_of(scene, Vector2::zeros()));
    (estimate.volumes.reachable, estimate.volumes.free)
}

fn worst_relative_error(
    estimator_name: &str,
    trajectories: usize,
    scene: &Scene,
    velocity: Vector3<f64>,
    exact_reachable: f64,
    exact_free: f64,
) -> (f64, f64) {
    SEEDS.iter().fold((0.0f64, 0.0f64), |(wr, wf), &seed| {
        let (reachable, free) = free_volume(estimator_name, trajectories, scene, velocity, seed);
        (
            wr.max((reachable / exact_reachable - 1.0).abs()),
            wf.max((free / exact_free - 1.0).abs()),
        )
    })
}

#[test]
fn open_space_reachable_area_converges_to_the_exact_box() {
    // Side A·T² = 2 m, area 4 m², wherever the initial velocity moves the box.
    let exact = (A * 1.0 * 1.0).powi(2);
    for velocity in [Vector3::zeros(), Vector3::new(1.2, -0.7, 0.0)] {
        for (trajectories, tolerance) in [(150, 0.05), (2000, 0.01)] {
            let (reachable, free) =
                worst_relative_error("hull", trajectories, &Scene::open(), velocity, exact, exact);
            assert!(
                reachable < tolerance,
                "N = {trajectories}: reachable off by {:.2} %",
                reachable * 100.0
            );
            assert!(
                free < tolerance,
                "N = {trajectories}: free off by {:.2} %",
                free * 100.0
            );
        }
    }
}

#[test]
fn a_wall_cutting_the_box_leaves_the_exact_near_side() {
    // Wall at x = 0.4; the Crazyflie's 6 cm radius keeps its centre at x ≤ 0.34.
    let scene = Scene::open().wall(0.4, -20.0, 0.4, 20.0);
    let exact_reachable = 4.0;
    let exact_free = 2.0 * (0.34 + 1.0);
    for (estimator_name, trajectories, tolerance) in [
        ("hull", 2000, 0.03),
        ("free_fraction", 2000, 0.02),
        ("free_fraction", 500, 0.04),
    ] {
        let (_, free) = worst_relative_error(
            estimator_name,
            trajectories,
            &scene,
            Vector3::zeros(),
            exact_reachable,
            exact_free,
        );
        assert!(
            free < tolerance,
            "{estimator_name} at N = {trajectories}: free area off by {:.2} %",
            free * 100.0
        );
    }
}
