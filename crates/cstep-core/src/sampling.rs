//! Admissible control trajectories: the "sample N control trajectories" step of Algorithm 1.
//!
//! Every sampler returns commands normalised to `[-1, 1]` per axis at each integration step
//! (held over the step); the robot model scales them by its own bound. Unlike the authors'
//! prototype — which bounded the *coefficients* of a Fourier series so the actual command peaked
//! at about five times the limit — every curve here is bounded where it matters, on the command.
//!
//! The choice of sampler matters more than the choice of volume estimator: random smooth
//! curves rarely hold full authority for long, so their endpoints cover only part of the true
//! reachable set, while bang-bang commands (the extreme points of the admissible set) cover it
//! almost entirely. [`SamplerKind::BangBang`] is therefore the default.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::model::CommandAxes;

/// Which family of control trajectories to draw.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SamplerKind {
    /// The paper's random Fourier series (5 sine + 5 cosine terms per axis), scaled so each
    /// curve peaks at the bound.
    Fourier,
    /// Random Chebyshev series of degree 5 on the horizon, scaled so each curve peaks at the bound.
    Chebyshev,
    /// Piecewise-constant commands at the bounds with zero, one or two switches per axis, drawn
    /// from a randomly shifted Halton sequence so the admissible set is covered evenly.
    BangBang,
}

impl SamplerKind {
    /// Every sampler, for listings and error messages.
    pub const ALL: [SamplerKind; 3] = [
        SamplerKind::Fourier,
        SamplerKind::Chebyshev,
        SamplerKind::BangBang,
    ];

    /// The name used in configuration files.
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Fourier => "fourier",
            SamplerKind::Chebyshev => "chebyshev",
            SamplerKind::BangBang => "bang_bang",
        }
    }

    /// Parses a configuration name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|kind| kind.name() == name)
    }
}

/// The most memory an evaluation's control sample may take, bytes (256 MiB).
///
/// The sample (`trajectories × steps × command axes` `f32`) is the only part of an evaluation
/// that grows with the product of trajectories and steps: the rollout keeps each block's model
/// state for one step at a time, and endpoints and volumes grow with the trajectories alone. So
/// this bounds what an evaluation allocates, and the configuration refuses settings beyond it up
/// front instead of letting the first evaluation abort the process. The default 150 × 100 takes
/// 117 KiB; 256 MiB still allows e.g. 100 000 trajectories × 335 steps in 2D.
pub const CONTROL_SAMPLE_BUDGET_BYTES: u64 = 256 << 20;

/// A batch of sampled control trajectories, laid out step-major so the commands of one step
/// for all trajectories are contiguous: `[step][axis][lane]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Controls {
    lanes: usize,
    steps: usize,
    axes: CommandAxes,
    data: Vec<f32>,
}

impl Controls {
    /// Bytes a sample of `lanes` trajectories of `steps` commands on `axes` takes (saturating),
    /// to check against [`CONTROL_SAMPLE_BUDGET_BYTES`] before drawing one.
    pub fn bytes(lanes: usize, steps: usize, axes: CommandAxes) -> u64 {
        let values = (lanes as u64)
            .saturating_mul(steps as u64)
            .saturating_mul(axes.count() as u64);
        values.saturating_mul(std::mem::size_of::<f32>() as u64)
    }

    /// Number of trajectories.
    pub fn lanes(&self) -> usize {
        self.lanes
    }

    /// Number of integration steps.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The command axes the trajectories drive.
    pub fn axes(&self) -> CommandAxes {
        self.axes
    }

    /// The commands of step `k` for every trajectory, axis-major (`axes × lanes` values), in the
    /// layout [`crate::model::Dynamics::actuate`] expects.
    pub fn at_step(&self, k: usize) -> &[f32] {
        let block = self.axes.count() * self.lanes;
        &self.data[k * block..(k + 1) * block]
    }

    /// The command of trajectory `lane` on `axis` at step `k`.
    pub fn get(&self, k: usize, axis: usize, lane: usize) -> f32 {
        self.at_step(k)[axis * self.lanes + lane]
    }
}

/// Draws `lanes` control trajectories of `steps` held commands each, ordered by the heading of
/// their commands (neighbouring lanes fly alike, which the collision checks exploit); the same
/// arguments always give bit-identical controls.
pub fn sample(
    kind: SamplerKind,
    lanes: usize,
    steps: usize,
    axes: CommandAxes,
    seed: u64,
) -> Controls {
    let mut controls = draw(kind, lanes, steps, axes, seed);
    order_by_heading(&mut controls);
    controls
}

/// The trajectories of [`sample`] in the order the sampler draws them.
fn draw(kind: SamplerKind, lanes: usize, steps: usize, axes: CommandAxes, seed: u64) -> Controls {
    let mut controls = Controls {
        lanes,
        steps,
        axes,
        data: vec![0.0; lanes * steps * axes.count()],
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut curve = vec![0.0f64; steps];
    match kind {
        SamplerKind::Fourier | SamplerKind::Chebyshev => {
            let basis = smooth_basis(kind, steps);
            let terms = basis.len() / steps.max(1);
            for lane in 0..lanes {
                for axis in 0..axes.count() {
                    curve.fill(0.0);
                    for term in 0..terms {
                        let coefficient: f64 = rng.random_range(-1.0..=1.0);
                        let row = &basis[term * steps..(term + 1) * steps];
                        for (u, b) in curve.iter_mut().zip(row) {
                            *u += coefficient * b;
                        }
                    }
                    scale_to_unit_peak(&mut curve);
                    write_curve(&mut controls, axis, lane, &curve);
                }
            }
        }
        SamplerKind::BangBang => {
            let dims = BANG_BANG_DIMS_PER_AXIS * axes.count();
            let shift: Vec<f64> = (0..dims).map(|_| rng.random::<f64>()).collect();
            for lane in 0..lanes {
                for axis in 0..axes.count() {
                    let coordinate = |d: usize| {
                        let dim = axis * BANG_BANG_DIMS_PER_AXIS + d;
                        (radical_inverse(lane as u64 + 1, PRIMES[dim]) + shift[dim]).fract()
                    };
                    bang_bang_curve(
                        [coordinate(0), coordinate(1), coordinate(2), coordinate(3)],
                        &mut curve,
                    );
                    write_curve(&mut controls, axis, lane, &curve);
                }
            }
        }
    }
    controls
}

/// Reorders the lanes by the heading of the displacement their commands alone would produce
/// (each step's command weighted by the time left after it), so that neighbouring lanes fly
/// in similar directions: they leave the free disk around the robot and meet obstacles at
/// similar steps, and the path-wise collision checks skip whole chunks of lanes that are all
/// inside or all terminal. The set of trajectories, and so every volume, is unchanged.
fn order_by_heading(controls: &mut Controls) {
    let (lanes, steps) = (controls.lanes, controls.steps);
    let heading = |lane: usize| {
        let mut d = [0.0f64; 2];
        for k in 0..steps {
            // The command of step k acts for the rest of the horizon (its middle, on average).
            let weight = (steps - k) as f64 - 0.5;
            for (axis, d) in d.iter_mut().enumerate() {
                *d += weight * controls.get(k, axis, lane) as f64;
            }
        }
        d[1].atan2(d[0])
    };
    let mut order: Vec<(f64, usize)> = (0..lanes).map(|lane| (heading(lane), lane)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut drawn = vec![0.0; lanes];
    for row in controls.data.chunks_exact_mut(lanes.max(1)) {
        drawn.copy_from_slice(row);
        for (to, &(_, lane)) in row.iter_mut().zip(&order) {
            *to = drawn[lane];
        }
    }
}

/// Harmonics in the Fourier sampler (the paper prototype's 5 sine + 5 cosine terms).
const FOURIER_HARMONICS: usize = 5;
/// Terms (degrees 0..=5) in the Chebyshev sampler.
const CHEBYSHEV_TERMS: usize = 6;
/// Low-discrepancy coordinates one bang-bang axis consumes: sign, switch count, two switch times.
const BANG_BANG_DIMS_PER_AXIS: usize = 4;
/// Halton bases, one per coordinate (up to 3 axes × 4 coordinates).
const PRIMES: [u64; 12] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37];

/// Basis functions evaluated at the step start times, term-major (`terms × steps`).
fn smooth_basis(kind: SamplerKind, steps: usize) -> Vec<f64> {
    let times = (0..steps).map(|k| k as f64 / steps as f64);
    match kind {
        SamplerKind::Fourier => {
            let mut basis = Vec::with_capacity(2 * FOURIER_HARMONICS * steps);
            for harmonic in 1..=FOURIER_HARMONICS {
                let w = std::f64::consts::TAU * harmonic as f64;
                basis.extend(times.clone().map(|t| (w * t).sin()));
                basis.extend(times.clone().map(|t| (w * t).cos()));
            }
            basis
        }
        SamplerKind::Chebyshev => {
            let mut basis = Vec::with_capacity(CHEBYSHEV_TERMS * steps);
            for degree in 0..CHEBYSHEV_TERMS {
                // T_n(cos θ) = cos(n θ) on τ = 2t − 1 ∈ [−1, 1].
                basis.extend(
                    times
                        .clone()
                        .map(|t| (degree as f64 * (2.0 * t - 1.0).clamp(-1.0, 1.0).acos()).cos()),
                );
            }
            basis
        }
        SamplerKind::BangBang => Vec::new(),
    }
}

/// Scales a curve so its largest magnitude is exactly 1 (a zero curve stays zero).
fn scale_to_unit_peak(curve: &mut [f64]) {
    let peak = curve.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    if peak > 0.0 {
        curve.iter_mut().for_each(|u| *u /= peak);
    }
}

/// A bang-bang curve from four unit coordinates: the starting sign, how many switches (0 with
/// probability 1/5, 1 with 2/5, 2 with 2/5) and the switch times as fractions of the horizon.
fn bang_bang_curve(coordinates: [f64; 4], curve: &mut [f64]) {
    let [sign, count, first, second] = coordinates;
    let start = if sign < 0.5 { -1.0 } else { 1.0 };
    let switches: &[f64] = &match count {
        c if c < 0.2 => [2.0, 2.0],
        c if c < 0.6 => [first, 2.0],
        _ => [first.min(second), first.max(second)],
    };
    let steps = curve.len() as f64;
    for (k, u) in curve.iter_mut().enumerate() {
        let t = k as f64 / steps;
        let flips = switches.iter().filter(|&&s| t >= s).count();
        *u = if flips % 2 == 0 { start } else { -start };
    }
}

fn write_curve(controls: &mut Controls, axis: usize, lane: usize, curve: &[f64]) {
    let block = controls.axes.count() * controls.lanes;
    for (k, &u) in curve.iter().enumerate() {
        controls.data[k * block + axis * controls.lanes + lane] = u as f32;
    }
}

/// The van der Corput radical inverse of `index` in `base`: the Halton sequence's coordinate.
fn radical_inverse(mut index: u64, base: u64) -> f64 {
    let inverse_base = 1.0 / base as f64;
    let mut scale = inverse_base;
    let mut value = 0.0;
    while index > 0 {
        value += (index % base) as f64 * scale;
        index /= base;
        scale *= inverse_base;
    }
    value
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all_commands(controls: &Controls) -> impl Iterator<Item = f32> + '_ {
        (0..controls.steps()).flat_map(move |k| controls.at_step(k).iter().copied())
    }

    #[test]
    fn every_sampler_respects_the_bound_and_reaches_it() {
        for kind in SamplerKind::ALL {
            let controls = sample(kind, 64, 100, CommandAxes::Spatial, 7);
            assert!(all_commands(&controls).all(|u| (-1.0..=1.0).contains(&u)));
            for lane in 0..64 {
                let peak = (0..100)
                    .map(|k| controls.get(k, 0, lane).abs())
                    .fold(0.0f32, f32::max);
                assert!(
                    (peak - 1.0).abs() < 1e-6,
                    "{kind:?} lane {lane} peaks at {peak}"
                );
            }
        }
    }

    #[test]
    fn same_seed_same_controls_other_seed_other_controls() {
        for kind in SamplerKind::ALL {
            let a = sample(kind, 150, 100, CommandAxes::Planar, 42);
            let b = sample(kind, 150, 100, CommandAxes::Planar, 42);
            let c = sample(kind, 150, 100, CommandAxes::Planar, 43);
            assert_eq!(a, b);
            assert_ne!(a, c);
        }
    }

    #[test]
    fn bang_bang_uses_every_switch_count_and_both_signs() {
        let controls = sample(SamplerKind::BangBang, 500, 100, CommandAxes::Planar, 1);
        let mut by_switches = [0usize; 3];
        let mut positive_start = 0;
        for lane in 0..500 {
            let switches = (1..100)
                .filter(|&k| controls.get(k, 0, lane) != controls.get(k - 1, 0, lane))
                .count();
            by_switches[switches.min(2)] += 1;
            positive_start += usize::from(controls.get(0, 0, lane) > 0.0);
        }
        // Expected shares 1/5, 2/5, 2/5 (two switches in the same step merge into none).
        assert!(by_switches.iter().all(|&n| n > 60), "{by_switches:?}");
        assert!((200..300).contains(&positive_start), "{positive_start}");
    }

    #[test]
    fn lanes_come_ordered_by_heading_with_the_trajectories_drawn() {
        for kind in SamplerKind::ALL {
            let drawn = draw(kind, 150, 100, CommandAxes::Spatial, 9);
            let sampled = sample(kind, 150, 100, CommandAxes::Spatial, 9);
            let curve = |c: &Controls, lane: usize| -> Vec<u32> {
                (0..100)
                    .flat_map(|k| (0..3).map(move |a| (k, a)))
                    .map(|(k, a)| c.get(k, a, lane).to_bits())
                    .collect()
            };
            let mut want: Vec<Vec<u32>> = (0..150).map(|l| curve(&drawn, l)).collect();
            let mut got: Vec<Vec<u32>> = (0..150).map(|l| curve(&sampled, l)).collect();
            // Headings of the displacement the commands alone give, lane by lane.
            let headings: Vec<f64> = (0..150)
                .map(|lane| {
                    let d = |a: usize| -> f64 {
                        (0..100)
                            .map(|k| (99.5 - k as f64) * sampled.get(k, a, lane) as f64)
                            .sum()
                    };
                    d(1).atan2(d(0))
                })
                .collect();
            assert!(
                headings.windows(2).all(|w| w[0] <= w[1] + 1e-9),
                "{kind:?}: {headings:?}"
            );
            want.sort_unstable();
            got.sort_unstable();
            assert_eq!(got, want, "{kind:?}: not the same trajectories");
        }
    }

    #[test]
    fn radical_inverse_matches_van_der_corput() {
        assert_eq!(radical_inverse(1, 2), 0.5);
        assert_eq!(radical_inverse(3, 2), 0.75);
        assert!((radical_inverse(5, 3) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-12);
    }

    #[test]
    fn names_round_trip() {
        for kind in SamplerKind::ALL {
            assert_eq!(SamplerKind::from_name(kind.name()), Some(kind));
        }
        assert_eq!(SamplerKind::from_name("uniform"), None);
    }
}
