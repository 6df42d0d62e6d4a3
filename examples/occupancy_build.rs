//! Timing probe for `Occupancy::build` alone on the benchmark scene:
//! `cargo run --release --example occupancy_build [batches] [builds per batch]` prints the
//! median and the fastest batch's time per build (and runs nothing else, so it can go under
//! callgrind as it is).
use std::time::Instant;

use cstep::demo::scene::benchmark_case;
use cstep::estimator::Estimator;
use cstep::occupancy::Occupancy;
use cstep::parameters::Settings;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let batches: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(51);
    let per_batch: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(200);
    let (state, scan) = benchmark_case();
    let settings = Settings::load(None, "cstep_node", &["model:=point_mass".to_string()]).unwrap();
    let estimator = Estimator::from_settings(&settings).unwrap();
    let options = &estimator.settings().occupancy;
    let mut times: Vec<f64> = (0..batches.max(1))
        .map(|_| {
            let start = Instant::now();
            for _ in 0..per_batch {
                std::hint::black_box(Occupancy::build(
                    &scan,
                    &state.attitude,
                    state.position.z,
                    options,
                ));
            }
            start.elapsed().as_secs_f64() * 1e6 / per_batch.max(1) as f64
        })
        .collect();
    times.sort_by(f64::total_cmp);
    println!(
        "occupancy build: median {:.2} µs, fastest batch {:.2} µs ({} batches of {per_batch})",
        times[times.len() / 2],
        times[0],
        times.len()
    );
}
