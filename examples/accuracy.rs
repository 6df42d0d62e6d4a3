//! The estimator accuracy study: `cargo run --release --example accuracy`.
//!
//! The point mass (|a_i| ≤ 2 m/s², T = 1 s, bang-bang sampler) against its exact reachable set,
//! in open space (the 2 m × 2 m box, 4 m²) and with a wall at x = 0.4 m cutting it (the near
//! side, 2 × 1.34 = 2.68 m² for the Crazyflie's 6 cm radius). Prints a Markdown table of the
//! mean and worst relative error of the free area over 10 seeds for each estimator and size.

#[path = "../tests/common/mod.rs"]
mod common;

use common::{at, estimator, scan_of};
use cstep::demo::scene::Scene;
use nalgebra::Vector2;

fn main() {
    let cases = [
        ("open box", Scene::open(), 4.0),
        (
            "wall cut",
            Scene::open().wall(0.4, -20.0, 0.4, 20.0),
            2.0 * 1.34,
        ),
    ];
    println!("| case | estimator | N | mean error | worst error | time per evaluation (µs) |");
    println!("|---|---|---:|---:|---:|---:|");
    for (name, scene, exact) in &cases {
        let scan = scan_of(scene, Vector2::zeros());
        for kind in ["hull", "efron", "free_fraction"] {
            for n in [150, 500, 2000] {
                let (mut sum, mut worst, mut micros) = (0.0, 0.0f64, 0.0);
                let seeds = 10;
                for seed in 0..seeds {
                    let e = estimator(&[
                        "model:=point_mass",
                        "max_acceleration:=2.0",
                        "unknown_space:=free",
                        "sampler:=bang_bang",
                        &format!("estimator:={kind}"),
                        &format!("trajectories:={n}"),
                        &format!("seed:={seed}"),
                    ]);
                    e.evaluate(&at(0.0, 0.0), &scan); // draws and caches the control sample
                    let estimate = e.evaluate(&at(0.0, 0.0), &scan);
                    let error = estimate.volumes.free / exact - 1.0;
                    sum += error;
                    worst = if error.abs() > worst.abs() {
                        error
                    } else {
                        worst
                    };
                    micros += estimate.elapsed.as_secs_f64() * 1e6;
                }
                println!(
                    "| {name} | {kind} | {n} | {:+.2} % | {:+.2} % | {:.0} |",
                    100.0 * sum / seeds as f64,
                    100.0 * worst,
                    micros / seeds as f64
                );
            }
        }
    }
}
