//! Profiling aid: `cargo run --release --example profile_stages [model] [iterations]` times the
//! stages of one evaluation on the benchmark scene (run under callgrind for a per-function view).
use std::time::Instant;

use cstep::demo::scene::benchmark_case;
use cstep::estimator::Estimator;
use cstep::occupancy::Occupancy;
use cstep::parameters::Settings;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model = args.get(1).map_or("point_mass", |s| s.as_str());
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2000);
    let (state, scan) = benchmark_case();
    let settings = Settings::load(None, "cstep_node", &[format!("model:={model}")]).unwrap();
    let e = Estimator::from_settings(&settings).unwrap();
    let opts = &e.settings().occupancy;
    let time = |f: &mut dyn FnMut()| {
        let t = Instant::now();
        for _ in 0..n {
            f();
        }
        t.elapsed().as_secs_f64() * 1e6 / n as f64
    };
    rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| {
        let estimate = e.evaluate(&state, &scan);
        let occupancy_us = time(&mut || {
            std::hint::black_box(Occupancy::build(&scan, &state.attitude, 1.0, opts));
        });
        let occupancy = Occupancy::build(&scan, &state.attitude, 1.0, opts);
        let xs: Vec<f32> = (0..150).map(|i| (i as f32 * 0.37).sin() * 2.0).collect();
        let ys: Vec<f32> = (0..150).map(|i| (i as f32 * 0.53).cos() * 2.0).collect();
        let zs = vec![0.0f32; 150];
        let mut hit = vec![0u8; 150];
        let checks_us = time(&mut || {
            for _ in 0..100 {
                occupancy.mark_collisions(&xs, &ys, &zs, std::hint::black_box(&mut hit));
            }
        });
        println!("collision checks, 150 points × 100 steps: {checks_us:.1} µs");
        let volumes_us = time(&mut || {
            std::hint::black_box(cstep::volume::estimate(
                &estimate.rollout.endpoints,
                &estimate.rollout.terminal,
                e.settings().volume_dims,
                e.settings().estimator,
            ));
        });
        let total_us = time(&mut || {
            std::hint::black_box(e.evaluate(&state, &scan));
        });
        println!(
            "{model}: total {total_us:.1} µs = occupancy {occupancy_us:.1} + volumes {volumes_us:.1} + rollout and the rest {:.1}; {} of {} collide",
            total_us - occupancy_us - volumes_us,
            estimate.num_colliding,
            estimate.num_trajectories
        );
    });
}
