//! `cargo bench`: one full C-STEP evaluation on the benchmark scene, one core, per model and size.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

use cstep::demo::scene::benchmark_case;
use cstep::estimator::Estimator;
use cstep::parameters::{Settings, BUILTIN_HUSKY_PATH};

fn evaluate(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let (state, scan) = benchmark_case();
    let mut group = c.benchmark_group("evaluate");
    let rows = [
        ("point_mass", 150),
        ("quadrotor", 150),
        ("quadrotor", 2000),
        ("diff_drive", 150),
    ];
    for (model, trajectories) in rows {
        let mut overrides = vec![
            format!("model:={model}"),
            format!("trajectories:={trajectories}"),
        ];
        if model == "diff_drive" {
            overrides.push(format!("robot_description:={BUILTIN_HUSKY_PATH}"));
        }
        let settings = Settings::load(None, "cstep_node", &overrides).unwrap();
        let estimator = Estimator::from_settings(&settings).unwrap();
        group.bench_with_input(BenchmarkId::new(model, trajectories), &estimator, |b, e| {
            pool.install(|| b.iter(|| e.evaluate(&state, &scan)))
        });
    }
    group.finish();
}

criterion_group!(benches, evaluate);
criterion_main!(benches);
