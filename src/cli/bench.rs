//! `cstep bench`: evaluation speed on a fixed scene, as medians over repeated runs.
//!
//! The scene is [`cstep::demo::scene::benchmark_case`]; by default one core, as the targets in
//! docs/measurements.md are stated.

use std::time::{Duration, Instant};

use serde::Serialize;

use cstep::estimator::Estimator;
use cstep::occupancy::ScanFrame;
use cstep::parameters::{Settings, BUILTIN_HUSKY_PATH};

use super::{CliError, Format};

/// Arguments of `cstep bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Output format.
    #[arg(long, value_enum, default_value = "text")]
    format: Format,
    /// Model to measure (quadrotor | point_mass | diff_drive); default: the standard rows.
    #[arg(long)]
    model: Option<String>,
    /// Trajectories per evaluation.
    #[arg(long)]
    trajectories: Option<usize>,
    /// Integration steps per trajectory.
    #[arg(long)]
    steps: Option<usize>,
    /// Threads for the rollout (the targets are for one core).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Seconds to spend measuring each row.
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
    /// Draw a new control sample every evaluation instead of reusing the seed's (the node reuses it).
    #[arg(long)]
    fresh_samples: bool,
    /// Parameter override, `name:=value` (repeatable), e.g. `-p estimator:=free_fraction`.
    #[arg(short = 'p', long = "param", value_name = "NAME:=VALUE")]
    params: Vec<String>,
}

/// One row of the speed table (the JSON contract).
#[derive(Debug, Serialize)]
struct Row {
    model: String,
    trajectories: usize,
    steps: usize,
    median_us: f64,
    p99_us: f64,
    evals_per_s: f64,
}

/// Runs `cstep bench`.
pub fn run(args: BenchArgs) -> Result<(), CliError> {
    let rows: Vec<(String, usize, usize)> =
        if args.model.is_none() && args.trajectories.is_none() && args.steps.is_none() {
            vec![
                ("point_mass".into(), 150, 100),
                ("quadrotor".into(), 150, 100),
                ("quadrotor".into(), 2000, 100),
                ("diff_drive".into(), 150, 100),
            ]
        } else {
            vec![(
                args.model.clone().unwrap_or_else(|| "quadrotor".into()),
                args.trajectories.unwrap_or(150),
                args.steps.unwrap_or(100),
            )]
        };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.max(1))
        .build()
        .map_err(|source| CliError::ThreadPool {
            threads: args.threads,
            source,
        })?;
    let mut table = Vec::new();
    for (model, trajectories, steps) in rows {
        let mut overrides = vec![
            format!("model:={model}"),
            format!("trajectories:={trajectories}"),
            format!("steps:={steps}"),
        ];
        if model == "diff_drive" {
            // The built-in Crazyflie has no wheels; `-p robot_description:=…` still wins.
            overrides.push(format!("robot_description:={BUILTIN_HUSKY_PATH}"));
        }
        overrides.extend(args.params.iter().cloned());
        let settings = Settings::load(None, "cstep_node", &overrides)?;
        let estimator = Estimator::from_settings(&settings)?;
        let row = pool.install(|| measure(&estimator, &model, &args));
        if args.format == Format::Text {
            eprintln!(
                "  {model} {trajectories}×{steps}: {} evaluations",
                (row.evals_per_s * args.seconds).round()
            );
        }
        table.push(row);
    }
    match args.format {
        Format::Json => println!(
            "{}",
            serde_json::to_string_pretty(&table).map_err(CliError::Json)?
        ),
        Format::Text => {
            println!(
                "{:<11} {:>12} {:>6} {:>10} {:>10} {:>12}",
                "model", "trajectories", "steps", "median_us", "p99_us", "evals_per_s"
            );
            for r in &table {
                println!(
                    "{:<11} {:>12} {:>6} {:>10.1} {:>10.1} {:>12.0}",
                    r.model, r.trajectories, r.steps, r.median_us, r.p99_us, r.evals_per_s
                );
            }
            println!(
                "scene: 2.5 m corridor closed 2.5 m ahead, 360-beam scan, 1 m/s toward the wall (diff_drive: the built-in Husky); {} thread(s); {}",
                args.threads,
                if args.fresh_samples { "fresh control sample each evaluation" } else { "control sample reused per seed, as in the node" }
            );
        }
    }
    Ok(())
}

fn measure(estimator: &Estimator, model: &str, args: &BenchArgs) -> Row {
    let (state, scan) = cstep::demo::scene::benchmark_case();
    let budget = Duration::from_secs_f64(args.seconds.max(0.1));
    let mut seed = estimator.settings().seed;
    let mut evaluate = || {
        if args.fresh_samples {
            seed = seed.wrapping_add(1);
        }
        let started = Instant::now();
        std::hint::black_box(estimator.evaluate_with_seed(&state, &scan, ScanFrame::Body, seed));
        started.elapsed()
    };
    for _ in 0..5 {
        evaluate();
    }
    let started = Instant::now();
    let mut samples = Vec::new();
    while (started.elapsed() < budget || samples.len() < 20) && samples.len() < 200_000 {
        samples.push(evaluate().as_secs_f64() * 1e6);
    }
    let total = started.elapsed().as_secs_f64();
    samples.sort_by(f64::total_cmp);
    let quantile = |q: f64| samples[((samples.len() - 1) as f64 * q).round() as usize];
    let s = estimator.settings();
    Row {
        model: model.to_owned(),
        trajectories: s.trajectories,
        steps: s.steps,
        median_us: quantile(0.5),
        p99_us: quantile(0.99),
        evals_per_s: samples.len() as f64 / total,
    }
}
