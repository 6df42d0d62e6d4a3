//! Timing of `volume::estimate` (not a pass/fail test). Run with
//! `cargo test --test volume_timing -- --ignored --nocapture` (the test profile is optimised).

use cstep::volume::{estimate, EstimatorKind, VolumeDims};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use std::time::Instant;

/// `n` endpoints uniform in the unit disk / ball, terminal behind a wall (x > 0.6) or inside a
/// round obstacle centred at (-0.5, 0.4): two terminal clusters, as near a corner of a room.
fn scene(n: usize, dims: usize, seed: u64) -> (Vec<[f64; 3]>, Vec<bool>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pts = Vec::with_capacity(n);
    while pts.len() < n {
        let p: [f64; 3] = std::array::from_fn(|a| {
            if a < dims {
                rng.random_range(-1.0..1.0)
            } else {
                0.0
            }
        });
        if p.iter().map(|c| c * c).sum::<f64>() <= 1.0 {
            pts.push(p);
        }
    }
    let terminal = pts
        .iter()
        .map(|p| p[0] > 0.6 || (p[0] + 0.5).powi(2) + (p[1] - 0.4).powi(2) < 0.09)
        .collect();
    (pts, terminal)
}

#[test]
#[ignore = "timing report, not a test"]
fn estimate_timings() {
    for (dims, n) in [
        (VolumeDims::Two, 150),
        (VolumeDims::Two, 2000),
        (VolumeDims::Three, 150),
        (VolumeDims::Three, 2000),
    ] {
        // `VOLUME_TIMING_SCENES=1` repeats one scene: the branch predictor then learns it and the
        // timings drop to what a warm, unchanging input would cost.
        let count = std::env::var("VOLUME_TIMING_SCENES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(16u64);
        let scenes: Vec<_> = (0..count).map(|s| scene(n, dims.count(), s)).collect();
        for kind in EstimatorKind::ALL {
            // `VOLUME_TIMING=2-150-hull` (dims-n-kind) times one case only, e.g. for profiling.
            let case = format!("{}-{n}-{}", dims.count(), kind.name());
            if std::env::var("VOLUME_TIMING").is_ok_and(|only| only != case) {
                continue;
            }
            let reps = if n > 1000 { 50 } else { 500 };
            let mut clusters = 0;
            // Warm up, then time batches; the fastest batch is the least disturbed by other load
            // on the machine.
            for (p, t) in &scenes {
                clusters += estimate(p, t, dims, kind).terminal_clusters;
            }
            let mut batches: Vec<f64> = (0..9)
                .map(|_| {
                    let start = Instant::now();
                    for r in 0..reps {
                        let (p, t) = &scenes[r % scenes.len()];
                        black_box(estimate(black_box(p), black_box(t), dims, kind));
                    }
                    start.elapsed().as_secs_f64() / reps as f64
                })
                .collect();
            batches.sort_by(f64::total_cmp);
            let (per, median) = (batches[0], batches[batches.len() / 2]);
            eprintln!(
                "{}D n={n:5} {:13}: {:8.1} µs/estimate (median batch {:8.1}; mean clusters {:.1})",
                dims.count(),
                kind.name(),
                per * 1e6,
                median * 1e6,
                clusters as f64 / scenes.len() as f64
            );
        }
    }
}
