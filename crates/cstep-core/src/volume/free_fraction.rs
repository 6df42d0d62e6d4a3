//! The free share of the reachable hull by nearest-endpoint (1-NN / Voronoi) labelling.
//!
//! Hull subtraction assumes every terminal cluster is convex; next to a non-convex obstacle
//! (an L-shaped wall, a corner) the hull of its terminal endpoints swallows free space. Instead,
//! every point of R̂ takes the label of its nearest endpoint — the Voronoi cell of a free endpoint
//! counts as free — and the free share of R̂ is measured.
//!
//! The measurement integrates by columns, as [`super::union`] does: vertical lines through the
//! centres of [`COLUMNS_2D`] columns across the hull's x-extent (2D), or of a
//! [`COLUMNS_3D`]² grid over its (x, y) extent (3D). Along one line the nearest-endpoint label
//! is found *exactly*, not by probes: the squared distance to endpoint i is
//! `(t − tᵢ)² + aᵢ` (t along the line, aᵢ the squared distance across it), and the lower
//! envelope of these parabolas — a 1D Voronoi diagram, built in linear time — splits the hull's
//! chord into intervals owned by one endpoint each. Only endpoints near the line take part; the
//! band is widened until the envelope provably beats every endpoint outside it. In 2D the band
//! slides across the columns as a run of strips kept sorted along the line (`strips.rs`); in 3D
//! each line gathers its band from the neighbour grid. The only approximation is the midpoint
//! rule across columns.

use super::hull::{Polygon, Polyhedron};
use super::neighbours::NeighbourGrid;
use super::strips::{Band, Strips};

/// Columns across a 2D hull. The free length along a column is a continuous, piecewise smooth
/// function of the column position, so the midpoint rule converges fast: against a
/// 4096-column reference, 32 columns err by at most 0.004 in the free fraction on the test
/// scenes (`column_count_converges`). That matches a 32 × 32 probe lattice across and is exact
/// along each column; the columns are most of the volumes' cost
/// (`cargo run --release --example profile_stages`).
pub(crate) const COLUMNS_2D: usize = 32;

/// Columns per axis across a 3D hull (24² = 576 lines): at most 0.003 off a 256²-column
/// reference (16²: 0.0065, 32²: 0.0023).
pub(crate) const COLUMNS_3D: usize = 24;

/// Share of `hull` whose nearest endpoint among `points` is free (`!terminal[i]`); `None` if
/// no column met the hull (cannot happen for a hull with positive area).
pub(crate) fn free_fraction_2d(
    hull: &Polygon,
    points: &[[f64; 3]],
    terminal: &[bool],
) -> Option<f64> {
    free_fraction_2d_with(hull, points, terminal, COLUMNS_2D)
}

fn free_fraction_2d_with(
    hull: &Polygon,
    points: &[[f64; 3]],
    terminal: &[bool],
    columns: usize,
) -> Option<f64> {
    let (lo, hi) = (hull.lo(), hull.hi());
    let dx = (hi[0] - lo[0]) / columns as f64;
    // One strip per column, centred on it.
    let strips = Strips::new(points, terminal, lo[0], dx, columns);
    let mut band = Band::new(&strips);
    let mut envelope = Vec::with_capacity(points.len());
    // A first reach that holds about two endpoints per reach² of the hull, as a grid cell does.
    let first_reach = (2.0 * hull.area() / points.len().max(1) as f64).sqrt();
    let mut tally = [0.0; 2];
    for i in 0..columns {
        let x = lo[0] + (i as f64 + 0.5) * dx;
        let Some([bottom, top]) = hull.boundary_at(x) else {
            continue;
        };
        let mut reach = first_reach;
        let mut covered_before = 0.0;
        loop {
            let covered = band.cover(x, reach);
            let near = band.members();
            let parabola = |k: usize| (near[k].y, (near[k].x - x) * (near[k].x - x));
            lower_envelope(near.len(), parabola, &mut envelope);
            let chord = measure_chord(&envelope, parabola, |k| near[k].free, bottom.y, top.y);
            if chord.worst <= covered * covered || covered == f64::INFINITY {
                tally[0] += chord.free;
                tally[1] += top.y - bottom.y;
                break;
            }
            // A band reaching past the worst point of this envelope holds an envelope no
            // higher anywhere, so the next pass is certain, up to rounding: should a pass not
            // widen the band (coordinates huge against the strips), the next takes them all.
            reach = if covered > covered_before {
                chord.worst.sqrt().max(covered * (1.0 + 1e-9))
            } else {
                f64::INFINITY
            };
            covered_before = covered;
        }
    }
    (tally[1] > 0.0).then(|| tally[0] / tally[1])
}

/// The 3D counterpart of [`free_fraction_2d`].
pub(crate) fn free_fraction_3d(
    hull: &Polyhedron,
    points: &[[f64; 3]],
    terminal: &[bool],
) -> Option<f64> {
    let grid = NeighbourGrid::new(points, 3);
    free_fraction_3d_with(hull, &grid, terminal, COLUMNS_3D)
}

fn free_fraction_3d_with(
    hull: &Polyhedron,
    grid: &NeighbourGrid,
    terminal: &[bool],
    columns: usize,
) -> Option<f64> {
    let (lo, hi) = (hull.lo(), hull.hi());
    let d = [0, 1].map(|a| (hi[a] - lo[a]) / columns as f64);
    let mut line = Line::new(grid, terminal);
    let mut tally = [0.0; 2];
    for iy in 0..columns {
        let y = lo[1] + (iy as f64 + 0.5) * d[1];
        for ix in 0..columns {
            let x = lo[0] + (ix as f64 + 0.5) * d[0];
            if let Some((bottom, top)) = hull.chord_at(x, y) {
                line.add(&[x, y, 0.0], bottom, top, &mut tally);
            }
        }
    }
    (tally[1] > 0.0).then(|| tally[0] / tally[1])
}

/// Nearest-endpoint labelling along vertical lines through the neighbour grid (the 3D
/// columns), with buffers reused between lines.
struct Line<'a> {
    grid: &'a NeighbourGrid,
    terminal: &'a [bool],
    /// Endpoints near the current line: (along, squared distance across, index), sorted.
    near: Vec<(f64, f64, u32)>,
    /// Lower envelope: (start of the interval, entry of `near` owning it), in order.
    envelope: Vec<(f64, usize)>,
}

impl<'a> Line<'a> {
    fn new(grid: &'a NeighbourGrid, terminal: &'a [bool]) -> Self {
        // Sized for every endpoint once, so that no line's band reallocates them.
        Line {
            grid,
            terminal,
            near: Vec::with_capacity(terminal.len()),
            envelope: Vec::with_capacity(terminal.len()),
        }
    }

    /// Adds to `tally` (free length, total length) the chord `[bottom, top]` of the vertical
    /// line through `at` (its z is ignored).
    fn add(&mut self, at: &[f64; 3], bottom: f64, top: f64, tally: &mut [f64; 2]) {
        let mut reach = self.grid.cell();
        loop {
            let complete = self
                .grid
                .near_line(at, 2, [bottom, top], reach, &mut self.near);
            let near = &self.near;
            let parabola = |k: usize| (near[k].0, near[k].1);
            lower_envelope(near.len(), parabola, &mut self.envelope);
            let chord = measure_chord(
                &self.envelope,
                parabola,
                |k| !self.terminal[near[k].2 as usize],
                bottom,
                top,
            );
            if complete || chord.worst <= reach * reach {
                tally[0] += chord.free;
                tally[1] += top - bottom;
                return;
            }
            reach *= 2.0;
        }
    }
}

/// What the lower envelope of a line's parabolas says about its chord `[bottom, top]`.
struct Chord {
    /// Length of the chord owned by free endpoints.
    free: f64,
    /// The envelope's largest value on the chord: every point of the chord has an endpoint of
    /// the band within this squared distance. The envelope is exact wherever it lies below
    /// every endpoint left out of the band, so it is exact on the whole chord when every
    /// endpoint left out is farther than this.
    worst: f64,
}

/// Measures the chord `[bottom, top]` under `envelope` (from [`lower_envelope`] over
/// `parabola`); `free(k)` is the label of parabola `k`.
fn measure_chord(
    envelope: &[(f64, usize)],
    parabola: impl Fn(usize) -> (f64, f64),
    free: impl Fn(usize) -> bool,
    bottom: f64,
    top: f64,
) -> Chord {
    let mut chord = Chord {
        free: 0.0,
        // Without an endpoint in the band nothing bounds the distance to the nearest one.
        worst: if envelope.is_empty() {
            f64::INFINITY
        } else {
            0.0
        },
    };
    for (k, &(start, owner)) in envelope.iter().enumerate() {
        let end = envelope.get(k + 1).map_or(f64::INFINITY, |e| e.0);
        let (s0, s1) = (start.max(bottom), end.min(top));
        if s1 <= s0 {
            continue;
        }
        let (t, across) = parabola(owner);
        if free(owner) {
            chord.free += s1 - s0;
        }
        // Each piece of the envelope is convex, so its largest value is at an end.
        let worst = ((s0 - t) * (s0 - t)).max((s1 - t) * (s1 - t)) + across;
        chord.worst = chord.worst.max(worst);
    }
    chord
}

/// Lower envelope of the `count` parabolas `(t − tᵢ)² + aᵢ`, `(tᵢ, aᵢ) = parabola(i)` sorted
/// by `tᵢ`, as the start of each envelope interval and the parabola owning it (the first
/// starts at −∞).
///
/// Two such parabolas cross once, at `(tᵢ + tⱼ)/2 + (aⱼ − aᵢ) / (2(tⱼ − tᵢ))`; scanning in
/// order of `tᵢ` and popping parabolas that a newer one overtakes before their interval starts
/// gives the envelope in linear time (Felzenszwalb & Huttenlocher's distance transform).
fn lower_envelope(
    count: usize,
    parabola: impl Fn(usize) -> (f64, f64),
    envelope: &mut Vec<(f64, usize)>,
) {
    envelope.clear();
    for j in 0..count {
        let (tj, aj) = parabola(j);
        loop {
            let Some(&(start, i)) = envelope.last() else {
                envelope.push((f64::NEG_INFINITY, j));
                break;
            };
            let (ti, ai) = parabola(i);
            if tj == ti {
                // Same position along the line: the one closer to it wins everywhere.
                if aj < ai {
                    envelope.pop();
                    continue;
                }
                break;
            }
            // cross ≤ start, multiplied through by 2(tj − ti) > 0 to avoid a division.
            let gap = 2.0 * (tj - ti);
            let lhs = 0.5 * (ti + tj) * gap + (aj - ai);
            if lhs <= start * gap {
                envelope.pop();
                continue;
            }
            envelope.push((lhs / gap, j));
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::test_points::uniform_in_cube;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn envelope_matches_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for m in [1, 2, 5, 40] {
            let mut near: Vec<(f64, f64, u32)> = (0..m)
                .map(|i| {
                    // Coarse positions so that equal tᵢ occur.
                    let t = (rng.random::<f64>() * 8.0).round() / 4.0;
                    (t, rng.random::<f64>(), i)
                })
                .collect();
            near.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut env = Vec::new();
            lower_envelope(near.len(), |k| (near[k].0, near[k].1), &mut env);
            assert!(env.windows(2).all(|w| w[0].0 < w[1].0));
            for k in 0..=400 {
                let t = -0.5 + 3.0 * k as f64 / 400.0;
                let f = |c: &(f64, f64, u32)| (t - c.0).powi(2) + c.1;
                let best = near.iter().map(f).fold(f64::INFINITY, f64::min);
                let seg = env
                    .iter()
                    .rposition(|e| e.0 <= t)
                    .expect("first starts at -inf");
                assert!((f(&near[env[seg].1]) - best).abs() < 1e-12, "m {m} t {t}");
            }
        }
    }

    /// The 2D free fraction against the same measurement with every endpoint on every column
    /// (no band, nothing to prove): sparse, clustered, flat and tall clouds, where the band
    /// near a column is often empty or too narrow at first. Lattice clouds are left out: their
    /// ties between equidistant endpoints may fall either way.
    #[test]
    fn the_band_gives_what_every_endpoint_gives() {
        let reference = |hull: &Polygon, points: &[[f64; 3]], terminal: &[bool]| {
            let mut order: Vec<usize> = (0..points.len()).collect();
            order.sort_by(|&a, &b| points[a][1].total_cmp(&points[b][1]));
            let (lo, hi) = (hull.lo(), hull.hi());
            let dx = (hi[0] - lo[0]) / COLUMNS_2D as f64;
            let mut envelope = Vec::new();
            let mut tally = [0.0; 2];
            for i in 0..COLUMNS_2D {
                let x = lo[0] + (i as f64 + 0.5) * dx;
                let Some([bottom, top]) = hull.boundary_at(x) else {
                    continue;
                };
                let parabola = |k: usize| {
                    let p = points[order[k]];
                    (p[1], (p[0] - x) * (p[0] - x))
                };
                lower_envelope(order.len(), parabola, &mut envelope);
                let free = |k: usize| !terminal[order[k]];
                let chord = measure_chord(&envelope, parabola, free, bottom.y, top.y);
                tally[0] += chord.free;
                tally[1] += top.y - bottom.y;
            }
            tally[0] / tally[1]
        };
        // The smallest case that once went wrong: no endpoint near the middle columns.
        let three = [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.02, 0.0]];
        let labels = [false, false, true];
        let hull = Polygon::hull(&three).expect("hull");
        let got = free_fraction_2d(&hull, &three, &labels).expect("fraction");
        assert!(
            (got - reference(&hull, &three, &labels)).abs() < 1e-12,
            "{got}"
        );

        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut compared = 0;
        for n in [3, 4, 7, 20, 150] {
            for _ in 0..20 {
                let point = |rng: &mut ChaCha8Rng, shape: usize, k: usize| -> [f64; 3] {
                    let mut u = || rng.random::<f64>() * 2.0 - 1.0;
                    match shape {
                        // A tight blob with a few endpoints far out.
                        0 if !k.is_multiple_of(10) => [0.01 * u(), 0.01 * u(), 0.0],
                        0 => [10.0 * u(), 10.0 * u(), 0.0],
                        1 => [1e3 * u(), 1e-3 * u(), 0.0],
                        2 => [1e-3 * u(), 1e3 * u(), 0.0],
                        _ => [u(), u(), 0.0],
                    }
                };
                for shape in 0..4 {
                    let points: Vec<[f64; 3]> = (0..n).map(|k| point(&mut rng, shape, k)).collect();
                    let terminal: Vec<bool> = (0..n).map(|_| rng.random::<f64>() < 0.4).collect();
                    let Some(hull) = Polygon::hull(&points) else {
                        continue;
                    };
                    let got = free_fraction_2d(&hull, &points, &terminal).expect("fraction");
                    let want = reference(&hull, &points, &terminal);
                    assert!(
                        (got - want).abs() < 1e-9,
                        "n {n} shape {shape}: {got} vs {want}"
                    );
                    compared += 1;
                }
            }
        }
        assert!(compared > 300, "{compared}");
    }

    /// Uniform points in [-1, 1]² labelled terminal inside a wall (x > 0.6) or a round
    /// obstacle: the free fraction converges as the column count grows.
    #[test]
    fn column_count_converges() {
        for (dims, n, columns, tol) in [
            (2, 150, COLUMNS_2D, 5e-3),
            (2, 2000, COLUMNS_2D, 5e-3),
            (3, 150, COLUMNS_3D, 5e-3),
            (3, 2000, COLUMNS_3D, 5e-3),
        ] {
            let mut worst = 0.0_f64;
            for seed in 0..4 {
                let pts = uniform_in_cube(n, dims, seed);
                let terminal: Vec<bool> = pts
                    .iter()
                    .map(|p| p[0] > 0.6 || (p[0] + 0.5).powi(2) + (p[1] - 0.4).powi(2) < 0.09)
                    .collect();
                let (got, reference) = if dims == 2 {
                    let hull = Polygon::hull(&pts).expect("hull");
                    (
                        free_fraction_2d_with(&hull, &pts, &terminal, columns),
                        free_fraction_2d_with(&hull, &pts, &terminal, 4096),
                    )
                } else {
                    let grid = NeighbourGrid::new(&pts, dims);
                    let hull = Polyhedron::hull(&pts).expect("hull");
                    (
                        free_fraction_3d_with(&hull, &grid, &terminal, columns),
                        free_fraction_3d_with(&hull, &grid, &terminal, 256),
                    )
                };
                worst = worst.max((got.expect("fraction") - reference.expect("fraction")).abs());
            }
            eprintln!(
                "{dims}D n={n}: {columns} columns, worst |error| {worst:.1e} vs the reference"
            );
            assert!(worst < tol, "{dims}D n={n}: {worst}");
        }
    }
}
