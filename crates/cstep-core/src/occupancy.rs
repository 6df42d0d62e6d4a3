//! The free space a 2D LiDAR scan shows, as a fast test for the robot's disk.
//!
//! A scan says three things about each direction: free up to the return, an obstacle at the
//! return, unknown behind it. This module turns that into a table over bearing bins around the
//! robot: for each bin, how far the centre of the robot's disk can travel along a straight line
//! from the sensor before the disk touches an obstacle or leaves the space the scan saw. The
//! free region is therefore the star-shaped set of disk centres visible from the sensor — a
//! conservative reading (nothing is assumed free that the scan did not show free), and unlike
//! the authors' prototype it accounts for the robot's size, every beam (not only the nearest to
//! the endpoint), the robot's heading, and the scan's own invalid and out-of-range values.
//!
//! Built once per scan in O(beams); each query is a bearing lookup and one comparison, so it
//! can run at every point of every rollout.

use nalgebra::UnitQuaternion;
use std::f64::consts::PI;

/// A 2D LiDAR scan in the robot's body frame (the sensor sits at the body origin), with the
/// semantics of `sensor_msgs/LaserScan` and REP 117: `+inf` = no return within range, `−inf` =
/// an object closer than `range_min`, NaN = an invalid measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// Bearing of the first beam, radians, counter-clockwise from the body x axis.
    pub angle_min: f64,
    /// Bearing step between consecutive beams, radians (negative for clockwise scans).
    pub angle_increment: f64,
    /// Shortest range the sensor measures, metres.
    pub range_min: f64,
    /// Longest range the sensor measures, metres.
    pub range_max: f64,
    /// One range per beam, metres.
    pub ranges: Vec<f32>,
}

/// The frame a scan's bearings are read in, which decides the attitude its beams are turned by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScanFrame {
    /// A LiDAR fixed to the body (every `sensor_msgs/LaserScan`): the beams turn and tilt
    /// with the robot's attitude.
    Body,
    /// Bearings already world-aligned and horizontal, as a point cloud becomes a scan
    /// ([`crate::cloud`]): read with the identity attitude.
    WorldAligned,
}

impl ScanFrame {
    /// The attitude (body → world) to read a scan in this frame with, for a robot at
    /// `attitude`.
    pub fn read_with(self, attitude: &UnitQuaternion<f64>) -> UnitQuaternion<f64> {
        match self {
            ScanFrame::Body => *attitude,
            ScanFrame::WorldAligned => UnitQuaternion::identity(),
        }
    }
}

/// What a scan says about one beam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Beam {
    /// An obstacle at this range (metres); `−inf` readings are placed at `range_min`.
    Hit(f64),
    /// Free up to `range_max`, nothing seen (`+inf` or beyond `range_max`).
    NoReturn,
    /// No usable information (NaN, or a finite reading below `range_min`).
    Invalid,
}

impl Scan {
    /// Reads beam `i` under REP 117.
    pub fn beam(&self, i: usize) -> Beam {
        let r = self.ranges[i] as f64;
        if r.is_nan() {
            Beam::Invalid
        } else if r == f64::NEG_INFINITY {
            Beam::Hit(self.range_min)
        } else if r > self.range_max {
            Beam::NoReturn
        } else if r < self.range_min {
            Beam::Invalid
        } else {
            Beam::Hit(r)
        }
    }

    /// Counts of each kind of beam, for status lines and diagnostics.
    pub fn summary(&self) -> ScanSummary {
        let mut summary = ScanSummary::default();
        for i in 0..self.ranges.len() {
            match self.beam(i) {
                Beam::Hit(_) => summary.hits += 1,
                Beam::NoReturn => summary.no_returns += 1,
                Beam::Invalid => summary.invalid += 1,
            }
        }
        summary
    }
}

/// How many beams of a scan returned, saw nothing, or were invalid.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ScanSummary {
    /// Beams with an obstacle return.
    pub hits: usize,
    /// Beams with no return within range.
    pub no_returns: usize,
    /// Beams with invalid readings.
    pub invalid: usize,
}

/// How space the scan says nothing about is treated: beyond `range_max` on beams without a
/// return, bearings the scan does not cover, and invalid beams.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnknownSpace {
    /// Unknown space is an obstacle (conservative; the default, as for a safety monitor).
    Occupied,
    /// Unknown space is free (optimistic; open-world experiments with a short-range sensor).
    Free,
}

impl UnknownSpace {
    /// The name used in configuration files.
    pub fn name(self) -> &'static str {
        match self {
            UnknownSpace::Occupied => "occupied",
            UnknownSpace::Free => "free",
        }
    }

    /// Parses a configuration name.
    pub fn from_name(name: &str) -> Option<Self> {
        [UnknownSpace::Occupied, UnknownSpace::Free]
            .into_iter()
            .find(|u| u.name() == name)
    }
}

/// The robot's geometry and the policies the free-space test applies.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyOptions {
    /// Radius of the robot's disk, metres: every obstacle stays at least this far from the
    /// robot's centre.
    pub robot_radius: f64,
    /// Height of the robot's collision shape, metres (against floor and ceiling).
    pub robot_height: f64,
    /// Treatment of space the scan does not describe.
    pub unknown_space: UnknownSpace,
    /// Floor height in the odometry frame, metres; `None` for no floor.
    pub floor: Option<f64>,
    /// Ceiling height in the odometry frame, metres; `None` for no ceiling.
    pub ceiling: Option<f64>,
}

/// Bearing bins around the robot: 0.5° each, finer than the 2° beams of the paper's LiDAR and
/// the 1° of common scanners.
const BINS: usize = 720;
const BIN_WIDTH: f64 = 2.0 * PI / BINS as f64;
const BINS_PER_RADIAN: f64 = BINS as f64 / (2.0 * PI);
/// Bins one step of a walk in [`inflate_points`] handles: a fixed-width, branch-free inner loop
/// that compiles to SIMD.
const LANES: usize = 8;
/// The most bins a walk from a point needs: a disk seen from outside spans at most a half
/// turn, a quarter on each side (`asin(r/ρ) ≤ π/2`), plus two bins for the point's offset in
/// its own bin and rounding.
const MAX_STEPS: usize = BINS / 4 + 2;
/// The longest walk, in whole steps of [`LANES`].
const MAX_WALK: usize = MAX_STEPS.div_ceil(LANES) * LANES;
/// Bins of padding on each side of the working table, so that walks never wrap around ±π.
const PAD: usize = MAX_WALK + 1;
const PADDED: usize = BINS + 2 * PAD;

/// The free-space test for one scan, in the rollout frame (world-aligned, centred on the robot).
#[derive(Debug, Clone)]
pub struct Occupancy {
    /// Per bearing bin, the squared distance at which a disk centre on that bearing collides.
    limit_sq: Vec<f32>,
    /// The smallest of them: every point closer than this to the sensor is free.
    inner_sq: f32,
    /// Lowest and highest admissible height of the robot's centre relative to its start.
    z_range: (f32, f32),
    in_collision: bool,
    summary: ScanSummary,
}

impl Occupancy {
    /// Builds the test from a scan taken at attitude `attitude` (body→world) and height
    /// `altitude` (odometry frame).
    pub fn build(
        scan: &Scan,
        attitude: &UnitQuaternion<f64>,
        altitude: f64,
        options: &OccupancyOptions,
    ) -> Self {
        let radius = options.robot_radius.max(0.0);
        let (beams, summary) = Beams::project(scan, attitude, options.unknown_space);
        let n = beams.len();
        let half_sector = 0.5 * scan.angle_increment.abs();
        // The working table: padded on both sides so that no walk of `inflate_points` wraps;
        // the padding folds back onto the bins it stands for at the end. NaN marks bins no
        // beam's sector covers.
        let mut limit = [f32::INFINITY; PADDED];
        let table = &mut limit[PAD..PAD + BINS];
        table.fill(f32::NAN);

        // Radially, the disk's centre stays `radius` inside what each beam's sector saw. Every
        // sector overlaps as many bins (at least one, at most all); where each starts and
        // what it allows comes first, for all beams at once (the loop vectorises).
        let sector_bins = (2.0 * half_sector * BINS_PER_RADIAN)
            .ceil()
            .clamp(0.0, BINS as f64 - 1.0) as usize
            + 1;
        let mut allowed = vec![0f32; n];
        let mut first = vec![0f64; n];
        let columns = allowed.iter_mut().zip(&mut first);
        for ((allowed, first), (&visible, &bearing)) in
            columns.zip(beams.visible.iter().zip(&beams.bearing))
        {
            *allowed = (visible - radius).max(0.0) as f32;
            // Bearings lie within [−π, π], so one turn brings a negative bin into the table.
            let bin = ((bearing - half_sector + PI) * BINS_PER_RADIAN).floor();
            *first = if bin < 0.0 { bin + BINS as f64 } else { bin };
        }
        for (&first, &allowed) in first.iter().zip(&allowed) {
            let first = (first as usize).min(BINS - 1);
            for bin in first..first + sector_bins {
                let l = &mut table[if bin < BINS { bin } else { bin - BINS }];
                // Takes `allowed` over the NaN of a bin no sector has covered yet.
                *l = if *l <= allowed { *l } else { allowed };
            }
        }
        let unknown_limit = match options.unknown_space {
            UnknownSpace::Occupied => 0.0,
            UnknownSpace::Free => f32::INFINITY,
        };
        for l in table.iter_mut() {
            *l = if l.is_nan() { unknown_limit } else { *l };
        }

        // Laterally, the disk must clear the surfaces the returns lie on and the corners where
        // the visible range steps down between sectors: gather those points, then inflate them.
        let mut in_collision = false;
        let mut points = Points::with_capacity(2 * n);
        let mut inflate = |x: f64, y: f64| {
            if x * x + y * y <= radius * radius {
                in_collision = true;
            } else {
                points.x.push(x as f32);
                points.y.push(y as f32);
            }
        };
        let full_circle = (n as f64 + 1.0) * scan.angle_increment.abs() >= 2.0 * PI;
        let pairs = if full_circle { n } else { n.saturating_sub(1) };
        let surfaces = Surfaces::find(&beams, pairs, scan.angle_increment, radius);
        for i in 0..n {
            let (x, y) = (surfaces.x[i], surfaces.y[i]);
            if !x.is_nan() {
                inflate(x, y);
            }
            if i >= pairs {
                continue;
            }
            let j = if i + 1 < n { i + 1 } else { 0 };
            let pieces = surfaces.pieces[i];
            if pieces >= 0.0 {
                // Walls are continuous between neighbouring returns: sample the segment
                // densely enough (half a radius) that the disk cannot slip through it.
                let (dx, dy) = (surfaces.x[j] - x, surfaces.y[j] - y);
                let step = 1.0 / pieces;
                for k in 1..pieces as usize {
                    let t = k as f64 * step;
                    inflate(x + t * dx, y + t * dy);
                }
            } else {
                let corner = beams.visible[i].min(beams.visible[j]);
                if corner > 0.0 && corner.is_finite() {
                    let (x, y) = beams.bisector(i, j);
                    inflate(corner * x, corner * y);
                }
            }
        }
        inflate_points(&mut limit, &points, radius);
        // Fold the padding back: padded bin `p` stands for bin `(p − PAD) mod BINS`.
        for p in 0..PAD {
            limit[p + BINS] = limit[p + BINS].min(limit[p]);
        }
        for p in PAD + BINS..PADDED {
            limit[p - BINS] = limit[p - BINS].min(limit[p]);
        }

        let half_height = 0.5 * options.robot_height.max(0.0);
        let z_low = options
            .floor
            .map_or(f64::NEG_INFINITY, |f| f - altitude + half_height);
        let z_high = options
            .ceiling
            .map_or(f64::INFINITY, |c| c - altitude - half_height);
        if z_low > 0.0 || z_high < 0.0 {
            in_collision = true;
        }
        let limit_sq: Vec<f32> = limit[PAD..PAD + BINS].iter().map(|l| l * l).collect();
        Self {
            inner_sq: limit_sq.iter().copied().fold(f32::INFINITY, f32::min),
            limit_sq,
            z_range: (z_low as f32, z_high as f32),
            in_collision,
            summary,
        }
    }

    /// True when the robot already overlaps an obstacle, the floor or the ceiling: then no
    /// trajectory can be collision-free.
    pub fn in_collision_at_start(&self) -> bool {
        self.in_collision
    }

    /// The beam counts of the scan this was built from.
    pub fn summary(&self) -> ScanSummary {
        self.summary
    }

    /// Whether a robot centred at `(x, y, z)` (rollout frame) is clear of every obstacle.
    pub fn is_free(&self, x: f32, y: f32, z: f32) -> bool {
        let mut hit = [0u8];
        self.mark_collisions(&[x], &[y], &[z], &mut hit);
        hit[0] == 0
    }

    /// Sets `hit[i] = 1` for every point `i` where the robot would collide; leaves the others
    /// unchanged, so calling it at every step accumulates path-wise collisions.
    pub fn mark_collisions(&self, x: &[f32], y: &[f32], z: &[f32], hit: &mut [u8]) {
        let n = hit.len();
        let (x, y, z) = (&x[..n], &y[..n], &z[..n]);
        for first in (0..n).step_by(SLAB) {
            let end = (first + SLAB).min(n);
            let mut open = [0u8; SLAB];
            self.open_lanes(
                &x[first..end],
                &y[first..end],
                &z[first..end],
                &hit[first..end],
                &mut open,
            );
            let chunks = (end - first).div_ceil(CHECK_CHUNK);
            for (c, flags) in open.as_chunks::<CHECK_CHUNK>().0[..chunks]
                .iter()
                .enumerate()
            {
                // A chunk without an open lane needs no lookup: one 128-bit test.
                if u128::from_ne_bytes(*flags) == 0 {
                    continue;
                }
                let mut at = first + c * CHECK_CHUNK;
                if at + CHECK_CHUNK > n && n >= CHECK_CHUNK {
                    // The last lanes: the whole chunk that ends with them. Lanes it shares with
                    // the chunk before are checked twice, harmlessly (`hit` only accumulates,
                    // and a point's check always comes out the same).
                    at = n - CHECK_CHUNK;
                }
                if at + CHECK_CHUNK <= n {
                    let lanes = at..at + CHECK_CHUNK;
                    self.mark_chunk(
                        chunk_of(x, lanes.clone()),
                        chunk_of(y, lanes.clone()),
                        chunk_of(z, lanes.clone()),
                        (&mut hit[lanes]).try_into().expect("CHECK_CHUNK lanes"),
                    );
                } else {
                    // Fewer lanes than a chunk, padded to one so that the checks compile to the
                    // same SIMD code without a scalar remainder loop: padding lanes sit at the
                    // sensor and count as already terminal, and their results are dropped.
                    let width = n - at;
                    let pad = |values: &[f32]| {
                        let mut padded = [0f32; CHECK_CHUNK];
                        padded[..width].copy_from_slice(&values[at..]);
                        padded
                    };
                    let mut chunk = [1u8; CHECK_CHUNK];
                    chunk[..width].copy_from_slice(&hit[at..]);
                    self.mark_chunk(&pad(x), &pad(y), &pad(z), &mut chunk);
                    hit[at..].copy_from_slice(&chunk[..width]);
                }
            }
        }
    }

    /// Sets `open[i] = 1` for every lane that needs a lookup: not yet terminal, and outside
    /// the disk the scan shows free in every direction or outside the floor-to-ceiling band.
    /// Early in a rollout most lanes are inside, and later most are terminal.
    ///
    /// One loop over all lanes with non-short-circuit `&`, so that it compiles to 256-bit SIMD
    /// compares. (Per 16-lane chunk, a count of open lanes compiled to a ragged mix of vector
    /// and scalar code, and a 16-byte flag array to 512-bit arithmetic, which lowers this
    /// CPU's clock: both slower.)
    #[inline(always)]
    fn open_lanes(&self, x: &[f32], y: &[f32], z: &[f32], hit: &[u8], open: &mut [u8; SLAB]) {
        let (z_low, z_high) = self.z_range;
        let n = hit.len();
        let (x, y, z, open) = (&x[..n], &y[..n], &z[..n], &mut open[..n]);
        for i in 0..n {
            let inside =
                (x[i] * x[i] + y[i] * y[i] < self.inner_sq) & (z[i] >= z_low) & (z[i] <= z_high);
            open[i] = u8::from(!inside & (hit[i] == 0));
        }
    }

    /// Looks up one chunk of [`CHECK_CHUNK`] lanes for [`Occupancy::mark_collisions`].
    #[inline(always)]
    fn mark_chunk(
        &self,
        x: &[f32; CHECK_CHUNK],
        y: &[f32; CHECK_CHUNK],
        z: &[f32; CHECK_CHUNK],
        hit: &mut [u8; CHECK_CHUNK],
    ) {
        let (z_low, z_high) = self.z_range;
        let table: &[f32; BINS] = self.limit_sq[..BINS].try_into().expect("BINS entries");
        // Branch-free over lanes with an i32 bin index, so the loop compiles to SIMD gathers.
        for i in 0..CHECK_CHUNK {
            let (px, py, pz) = (x[i], y[i], z[i]);
            let d2 = px * px + py * py;
            let bin = bearing_bin(fast_atan2(py, px));
            // A point at the sensor itself is where the robot already is: never a collision.
            let blocked = (d2 >= table[bin]) & (d2 > 1e-12);
            let outside = (pz < z_low) | (pz > z_high);
            hit[i] |= (blocked | outside) as u8;
        }
    }
}

/// Lanes whose open flags [`Occupancy::mark_collisions`] works out at once (a multiple of
/// [`CHECK_CHUNK`]; a rollout block is 160).
const SLAB: usize = 256;

/// Lanes checked together by [`Occupancy::mark_collisions`]: one AVX-512 register of `f32`.
const CHECK_CHUNK: usize = 16;

/// Lanes `lanes` (exactly [`CHECK_CHUNK`] of them) of `values`, as an array reference.
fn chunk_of(values: &[f32], lanes: std::ops::Range<usize>) -> &[f32; CHECK_CHUNK] {
    values[lanes].try_into().expect("CHECK_CHUNK lanes")
}

/// The table bin of a bearing in `[−π, π]` (clamped to the table; NaN → bin 0), written so
/// that a loop over lanes stays SIMD.
///
/// A float-to-integer `as` cast saturates and maps NaN to zero, which LLVM lowers to scalar code
/// lane by lane (it made the collision checks three times slower). Here the bin is floored and
/// clamped as a float (`max` also turns NaN into 0), and adding 2²³ puts that whole number
/// into the low mantissa bits, read off with one integer subtraction.
#[inline(always)]
fn bearing_bin(bearing: f32) -> usize {
    const TWO_POW_23: f32 = 8_388_608.0;
    let scale = BINS_PER_RADIAN as f32;
    let bin = ((bearing + std::f32::consts::PI) * scale)
        .floor()
        .max(0.0)
        .min((BINS - 1) as f32);
    // The clamp restates the range for the compiler, so indexing needs no bounds check.
    ((bin + TWO_POW_23).to_bits() as i32 - TWO_POW_23.to_bits() as i32).clamp(0, BINS as i32 - 1)
        as usize
}

/// The scan's beams in the world-aligned horizontal plane, one column per quantity (so that
/// arithmetic over beams vectorises).
struct Beams {
    /// Horizontal range of each beam's return; NaN for a beam without one.
    hit: Vec<f64>,
    /// Horizontal range each beam shows free: its return's, or what the unknown-space policy
    /// makes of a beam without one.
    visible: Vec<f64>,
    /// Bearing of each beam's horizontal projection, radians.
    bearing: Vec<f64>,
    /// Unit direction of that projection (zero for a vertical beam), x and y.
    x: Vec<f64>,
    y: Vec<f64>,
}

impl Beams {
    /// Projects the beams of `scan`, taken at `attitude`, and counts them by kind.
    fn project(
        scan: &Scan,
        attitude: &UnitQuaternion<f64>,
        unknown_space: UnknownSpace,
    ) -> (Self, ScanSummary) {
        let n = scan.ranges.len();
        let (mut x, mut y) = beam_directions(scan.angle_min, scan.angle_increment, n);
        // Only the horizontal part of a rotated beam matters: two rows of the rotation matrix.
        // Column by column, so that the loop vectorises.
        let m = attitude.to_rotation_matrix().into_inner();
        let (xx, xy, yx, yy) = (m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]);
        let mut scales = vec![0.0; n];
        let mut bearing = vec![0.0; n];
        let columns = x.iter_mut().zip(&mut y).zip(&mut scales).zip(&mut bearing);
        for (((x, y), scale), bearing) in columns {
            let (wx, wy) = (xx * *x + xy * *y, yx * *x + yy * *y);
            *scale = (wx * wx + wy * wy).sqrt();
            let inv = if *scale > 0.0 { 1.0 / *scale } else { 0.0 };
            (*x, *y) = (wx * inv, wy * inv);
            *bearing = fast_atan2(wy as f32, wx as f32) as f64;
        }
        let unknown = match unknown_space {
            UnknownSpace::Occupied => 0.0,
            UnknownSpace::Free => f64::INFINITY,
        };
        let mut summary = ScanSummary::default();
        let mut hit = vec![f64::NAN; n];
        let mut visible = vec![0.0; n];
        for (i, ((hit, visible), &scale)) in
            hit.iter_mut().zip(&mut visible).zip(&scales).enumerate()
        {
            *visible = match scan.beam(i) {
                Beam::Hit(range) => {
                    summary.hits += 1;
                    *hit = range * scale;
                    *hit
                }
                Beam::NoReturn => {
                    summary.no_returns += 1;
                    match unknown_space {
                        UnknownSpace::Occupied => scale * scan.range_max,
                        UnknownSpace::Free => f64::INFINITY,
                    }
                }
                Beam::Invalid => {
                    summary.invalid += 1;
                    unknown
                }
            };
        }
        let beams = Self {
            hit,
            visible,
            bearing,
            x,
            y,
        };
        (beams, summary)
    }

    fn len(&self) -> usize {
        self.hit.len()
    }

    /// The horizontal unit direction halfway between beams `i` and `j`: their directions'
    /// normalised sum, or from their bearings where that sum is short (beams more than 120°
    /// apart, or vertical ones).
    fn bisector(&self, i: usize, j: usize) -> (f64, f64) {
        let (x, y) = (self.x[i] + self.x[j], self.y[i] + self.y[j]);
        let norm_sq = x * x + y * y;
        if norm_sq >= 1.0 {
            let inv = 1.0 / norm_sq.sqrt();
            (x * inv, y * inv)
        } else {
            let turn = wrap_angle(self.bearing[j] - self.bearing[i]);
            let (sin, cos) = (self.bearing[i] + 0.5 * turn).sin_cos();
            (cos, sin)
        }
    }
}

/// Unit directions (cos, sin) of the `n` beam angles `angle_min + i·angle_increment`, by
/// rotation rather than a sine and cosine each: the first [`ROTATION_BLOCK`] step by step,
/// then whole blocks at once, each a rotation of the first block (a loop that vectorises, where
/// stepping every beam from the previous one would be a chain of dependent products).
fn beam_directions(angle_min: f64, angle_increment: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
    let (step_sin, step_cos) = angle_increment.sin_cos();
    let (mut sin, mut cos) = angle_min.sin_cos();
    let mut first = [(0.0, 0.0); ROTATION_BLOCK];
    for direction in &mut first {
        *direction = (cos, sin);
        (sin, cos) = (
            sin * step_cos + cos * step_sin,
            cos * step_cos - sin * step_sin,
        );
    }
    let (block_sin, block_cos) = (ROTATION_BLOCK as f64 * angle_increment).sin_cos();
    let (mut sin, mut cos) = (0.0, 1.0);
    let (mut xs, mut ys) = (vec![0.0; n], vec![0.0; n]);
    for (xs, ys) in xs
        .chunks_mut(ROTATION_BLOCK)
        .zip(ys.chunks_mut(ROTATION_BLOCK))
    {
        for ((x, y), &(x0, y0)) in xs.iter_mut().zip(ys.iter_mut()).zip(&first) {
            (*x, *y) = (x0 * cos - y0 * sin, y0 * cos + x0 * sin);
        }
        (sin, cos) = (
            sin * block_cos + cos * block_sin,
            cos * block_cos - sin * block_sin,
        );
    }
    (xs, ys)
}

/// Beams whose directions [`beam_directions`] rotates at once.
const ROTATION_BLOCK: usize = 8;

/// The returns of a scan and the surfaces between them, worked out for all beams at once (the
/// loops vectorise).
struct Surfaces {
    /// Each beam's return, x and y; NaN for a beam without one.
    x: Vec<f64>,
    y: Vec<f64>,
    /// For each pair of neighbouring beams `i` and `i + 1` (the last with the first on a full
    /// circle), the pieces into which the segment between their returns is sampled, every half
    /// radius at most (and at most [`MAX_PIECES`] pieces), where both returns lie on one
    /// surface; −1 where they do not.
    pieces: Vec<f64>,
}

/// The most pieces one segment between neighbouring returns is sampled into. Half a radius
/// apart, that is a segment 512 radii long (30 m for a 6 cm robot), between returns hundreds of
/// metres away; only absurd ranges (a scan may report up to 3.4e38 m) make longer ones, which
/// are then sampled more sparsely rather than without end.
const MAX_PIECES: f64 = 1024.0;

impl Surfaces {
    fn find(beams: &Beams, pairs: usize, angle_increment: f64, radius: f64) -> Self {
        let x: Vec<f64> = beams.hit.iter().zip(&beams.x).map(|(h, x)| h * x).collect();
        let y: Vec<f64> = beams.hit.iter().zip(&beams.y).map(|(h, y)| h * y).collect();
        let breakpoints = Breakpoints::new(angle_increment);
        let pieces_per_metre = 2.0 / radius.max(1e-3);
        let split = |(a, b): (f64, f64), (ax, bx): (f64, f64), (ay, by): (f64, f64)| {
            // Branch-free, so that the loop vectorises; NaN (no return) fails the test.
            let length = ((bx - ax).powi(2) + (by - ay).powi(2)).sqrt();
            let pieces = (length * pieces_per_metre).ceil().min(MAX_PIECES);
            if breakpoints.same_surface(a, b) {
                pieces
            } else {
                -1.0
            }
        };
        let n = beams.len();
        let m = n.saturating_sub(1);
        let mut pieces = vec![0.0; m];
        let (a, b) = (&beams.hit[..m], &beams.hit[n - m..]);
        let (ax, bx) = (&x[..m], &x[n - m..]);
        let (ay, by) = (&y[..m], &y[n - m..]);
        let ends = a
            .iter()
            .zip(b)
            .zip(ax.iter().zip(bx))
            .zip(ay.iter().zip(by));
        for (pieces, ((a, x), y)) in pieces.iter_mut().zip(ends) {
            *pieces = split((*a.0, *a.1), (*x.0, *x.1), (*y.0, *y.1));
        }
        if pairs == n && n > 0 {
            let last = n - 1;
            pieces.push(split(
                (beams.hit[last], beams.hit[0]),
                (x[last], x[0]),
                (y[last], y[0]),
            ));
        }
        Self { x, y, pieces }
    }
}

/// The adaptive breakpoint test (Borges & Aldon, 2004) for neighbouring returns of a scan:
/// they lie on one surface when their gap is no larger than a surface seen at 10° incidence
/// would leave, plus three times a 1 cm range noise.
struct Breakpoints {
    /// Cosine of the angle between neighbouring beams.
    cos_step: f64,
    /// The largest gap per metre of the nearer range, at the smallest incidence.
    gap_per_metre: f64,
}

impl Breakpoints {
    const MIN_INCIDENCE: f64 = 10.0 * PI / 180.0;
    const RANGE_SIGMA: f64 = 0.01;

    fn new(angle_increment: f64) -> Self {
        let step = angle_increment.abs();
        Self {
            cos_step: step.cos(),
            gap_per_metre: step.sin() / (Self::MIN_INCIDENCE - step).sin().max(1e-6),
        }
    }

    /// Whether neighbouring returns at ranges `a` and `b` lie on one surface.
    fn same_surface(&self, a: f64, b: f64) -> bool {
        let gap_sq = a * a + b * b - 2.0 * a * b * self.cos_step;
        let allowed = a.min(b) * self.gap_per_metre + 3.0 * Self::RANGE_SIGMA;
        gap_sq <= allowed * allowed
    }
}

/// Unit directions of the bin edges of the padded table, x and y apart so that walks load
/// them as vectors: edge `p` is the bearing `−π + (p − PAD)·BIN_WIDTH`, the lower edge of
/// padded bin `p`.
struct Edges {
    x: [f32; PADDED + 1],
    y: [f32; PADDED + 1],
}

fn bin_edges() -> &'static Edges {
    static EDGES: std::sync::OnceLock<Edges> = std::sync::OnceLock::new();
    EDGES.get_or_init(|| {
        let mut edges = Edges {
            x: [0.0; PADDED + 1],
            y: [0.0; PADDED + 1],
        };
        for p in 0..=PADDED {
            let (s, c) = (-PI + (p as f64 - PAD as f64) * BIN_WIDTH).sin_cos();
            (edges.x[p], edges.y[p]) = (c as f32, s as f32);
        }
        edges
    })
}

/// Obstacle points the robot's disk must clear, x and y apart for the vectorised passes of
/// [`inflate_points`].
struct Points {
    x: Vec<f32>,
    y: Vec<f32>,
}

impl Points {
    fn with_capacity(capacity: usize) -> Self {
        Self {
            x: Vec::with_capacity(capacity),
            y: Vec::with_capacity(capacity),
        }
    }
}

/// Lowers the limits of the bins whose rays bring the robot's disk onto any of the obstacle
/// `points` (each farther than `radius` from the sensor) in the padded table `limit`. Along a
/// ray of direction `u`, the disk's centre first touches a point `p` at `t − sqrt(r² − s²)`
/// with `t = p·u` and `s = p × u`; within a bin the worst ray is the edge nearest the point, so
/// each bin costs two products and a square root, no trigonometry. Rays within `asin(r/ρ)` of
/// the point can touch it: walks on both sides of the point's own bin cover that bound in
/// fixed-width steps, and rays that miss leave their bins as they are.
fn inflate_points(limit: &mut [f32; PADDED], points: &Points, radius: f64) {
    use std::f32::consts::{FRAC_PI_2, PI};
    let n = points.x.len().min(points.y.len());
    let (xs, ys) = (&points.x[..n], &points.y[..n]);
    let r = radius as f32;
    let per_radian = BINS_PER_RADIAN as f32;
    // First, for all points at once (the loop vectorises): the padded bin each lies in, the
    // limit it sets there, and the length of its walks — whole numbers, kept as floats since
    // saturating conversions to integers would not vectorise.
    let mut homes = vec![0f32; n];
    let mut reaches = vec![0f32; n];
    let mut walks = vec![0f32; n];
    for i in 0..n {
        let (x, y) = (xs[i], ys[i]);
        let rho_sq = x * x + y * y;
        // Between PAD − 1 and PAD + BINS, since fast_atan2 is within f32 rounding of ±π.
        let home = ((fast_atan2(y, x) + PI) * per_radian + PAD as f32).floor();
        homes[i] = home.max(PAD as f32 - 1.0).min((PAD + BINS) as f32);
        reaches[i] = (rho_sq.sqrt() - r).max(0.0);
        // tan(asin(r/ρ)) = r/sqrt(ρ² − r²) bounds the angle from above (NaN → a quarter turn).
        let spread = (r / (rho_sq - r * r).sqrt()).min(FRAC_PI_2);
        let steps = ((spread * per_radian).floor() + 2.0).min(MAX_STEPS as f32);
        walks[i] = (steps * (1.0 / LANES as f32)).ceil() * LANES as f32;
    }
    let edges = bin_edges();
    for i in 0..n {
        let (x, y, home, walk) = (xs[i], ys[i], homes[i] as usize, walks[i] as usize);
        limit[home] = limit[home].min(reaches[i]);
        // Walking up, a bin's nearest edge is its lower one; walking down, its upper one.
        let up = home + 1..home + 1 + walk;
        lower_bins(
            &mut limit[up.clone()],
            &edges.x[up.clone()],
            &edges.y[up],
            x,
            y,
            r,
        );
        let down = home - walk..home;
        let edge = home + 1 - walk..home + 1;
        lower_bins(
            &mut limit[down],
            &edges.x[edge.clone()],
            &edges.y[edge],
            x,
            y,
            r,
        );
    }
}

/// Lowers each bin of `limit` to where the disk, its centre moving along the matching edge
/// direction `(ux, uy)`, first touches the point `(x, y)` — where that ray passes ahead and
/// within `r` of it. The slices' length is a multiple of [`LANES`].
#[inline(always)]
fn lower_bins(limit: &mut [f32], ux: &[f32], uy: &[f32], x: f32, y: f32, r: f32) {
    let (limit, _) = limit.as_chunks_mut::<LANES>();
    let (ux, _) = ux.as_chunks::<LANES>();
    let (uy, _) = uy.as_chunks::<LANES>();
    for ((limit, ux), uy) in limit.iter_mut().zip(ux).zip(uy) {
        for i in 0..LANES {
            let t = x * ux[i] + y * uy[i];
            let s = (x * uy[i] - y * ux[i]).abs();
            // r² − s², factored to stay accurate where the ray grazes the disk (s ≈ r).
            let gap = (r - s) * (r + s);
            let reach = (t - gap.max(0.0).sqrt()).max(0.0);
            let touches = (gap > 0.0) & (t > 0.0) & (reach < limit[i]);
            limit[i] = if touches { reach } else { limit[i] };
        }
    }
}

fn wrap_angle(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// atan2 to within 1e-5 rad (far below the 8.7e-3 rad bin width), written without branches so
/// the per-point loop vectorises; std's atan2 is a library call per point.
#[inline(always)]
fn fast_atan2(y: f32, x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let a = ax.min(ay) / ax.max(ay).max(f32::MIN_POSITIVE);
    let s = a * a;
    let mut r = a
        * (0.999_977_26
            + s * (-0.332_623_47
                + s * (0.193_543_46 + s * (-0.116_432_87 + s * (0.052_653_32 - 0.011_721_2 * s)))));
    r = if ay > ax { FRAC_PI_2 - r } else { r };
    r = if x < 0.0 { PI - r } else { r };
    if y < 0.0 {
        -r
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(range: f32, beams: usize) -> Scan {
        Scan {
            angle_min: -PI,
            angle_increment: 2.0 * PI / beams as f64,
            range_min: 0.05,
            range_max: 10.0,
            ranges: vec![range; beams],
        }
    }

    fn options(radius: f64) -> OccupancyOptions {
        OccupancyOptions {
            robot_radius: radius,
            robot_height: 0.0,
            unknown_space: UnknownSpace::Occupied,
            floor: None,
            ceiling: None,
        }
    }

    fn level() -> UnitQuaternion<f64> {
        UnitQuaternion::identity()
    }

    #[test]
    fn fast_atan2_matches_std_everywhere() {
        for i in 0..3600 {
            let a = -PI + i as f64 * PI / 1800.0;
            for r in [1e-3f64, 1.0, 100.0] {
                let (y, x) = ((r * a.sin()) as f32, (r * a.cos()) as f32);
                let err = (fast_atan2(y, x) - y.atan2(x)).abs();
                assert!(
                    err < 1e-5 || (err - 2.0 * std::f32::consts::PI).abs() < 1e-5,
                    "{a} {r} {err}"
                );
            }
        }
    }

    #[test]
    fn beam_directions_match_sin_and_cos() {
        let scans = [
            (-PI, 2.0 * PI / 360.0, 360),
            (1.0, -0.0123, 1000),
            (0.3, 0.5, 3),
            (-2.0, 1e-4, 20_000),
            (0.0, 0.1, 0),
        ];
        for (angle_min, increment, n) in scans {
            let (xs, ys) = beam_directions(angle_min, increment, n);
            assert_eq!((xs.len(), ys.len()), (n, n));
            for i in 0..n {
                let (sin, cos) = (angle_min + i as f64 * increment).sin_cos();
                let err = (xs[i] - cos).abs().max((ys[i] - sin).abs());
                assert!(err < 1e-12, "{angle_min} {increment} beam {i}: {err}");
            }
        }
    }

    #[test]
    fn a_ring_of_returns_frees_a_disk_shrunk_by_the_robot_radius() {
        let occupancy = Occupancy::build(&ring(2.0, 360), &level(), 1.0, &options(0.1));
        for i in 0..100 {
            let a = i as f32 * 0.0628;
            assert!(occupancy.is_free(1.85 * a.cos(), 1.85 * a.sin(), 0.0));
            assert!(!occupancy.is_free(1.91 * a.cos(), 1.91 * a.sin(), 0.0));
        }
    }

    #[test]
    fn a_single_return_blocks_a_disk_around_it_and_its_shadow() {
        let mut scan = ring(f32::INFINITY, 360);
        scan.ranges[180] = 1.0; // bearing 0: straight ahead
        let mut opts = options(0.2);
        opts.unknown_space = UnknownSpace::Free;
        let occupancy = Occupancy::build(&scan, &level(), 1.0, &opts);
        assert!(!occupancy.is_free(0.85, 0.0, 0.0));
        assert!(!occupancy.is_free(0.9, 0.15, 0.0), "beside the return");
        assert!(!occupancy.is_free(1.5, 0.1, 0.0), "behind it");
        assert!(occupancy.is_free(0.75, 0.0, 0.0));
        assert!(occupancy.is_free(1.0, 0.5, 0.0), "well beside it");
        assert!(
            occupancy.is_free(-5.0, 0.0, 0.0),
            "unknown space is free here"
        );
    }

    #[test]
    fn heading_rotates_the_scan_into_the_rollout_frame() {
        let mut scan = ring(f32::INFINITY, 360);
        scan.ranges[180] = 1.0; // straight ahead in the body frame
        let mut opts = options(0.1);
        opts.unknown_space = UnknownSpace::Free;
        let facing_y = UnitQuaternion::from_euler_angles(0.0, 0.0, PI / 2.0);
        let occupancy = Occupancy::build(&scan, &facing_y, 1.0, &opts);
        assert!(!occupancy.is_free(0.0, 0.95, 0.0));
        assert!(occupancy.is_free(0.95, 0.0, 0.0));
    }

    #[test]
    fn unknown_space_policy_applies_beyond_range_and_to_invalid_beams() {
        let mut scan = ring(f32::INFINITY, 360);
        scan.range_max = 3.0;
        scan.ranges[0] = f32::NAN; // bearing −π: behind
        let occupied = Occupancy::build(&scan, &level(), 1.0, &options(0.1));
        assert!(occupied.is_free(2.85, 0.0, 0.0));
        assert!(!occupied.is_free(2.95, 0.0, 0.0));
        assert!(!occupied.is_free(-0.5, 0.0, 0.0), "invalid beam is unknown");
        let mut opts = options(0.1);
        opts.unknown_space = UnknownSpace::Free;
        let free = Occupancy::build(&scan, &level(), 1.0, &opts);
        assert!(free.is_free(5.0, 0.0, 0.0));
        assert!(free.is_free(-0.5, 0.0, 0.0));
    }

    #[test]
    fn an_oblique_wall_keeps_the_disk_a_radius_away_even_between_sparse_beams() {
        // Wall x = 1 seen by 90 beams (4° apart): returns up to 30 cm apart along the wall.
        let scene = crate::demo::scene::Scene::open().wall(1.0, -50.0, 1.0, 50.0);
        let lidar = crate::demo::scene::Lidar {
            beams: 90,
            range_min: 0.02,
            range_max: 10.0,
        };
        let scan = scene.scan(nalgebra::Vector2::zeros(), &level(), &lidar);
        let radius = 0.1;
        let mut opts = options(radius);
        opts.unknown_space = UnknownSpace::Free;
        let occupancy = Occupancy::build(&scan, &level(), 1.0, &opts);
        let (mut free_near, mut free_far, mut far) = (0, 0, 0);
        for i in 0..400 {
            for j in 0..400 {
                let (x, y) = (-1.0 + i as f32 * 0.005, -2.0 + j as f32 * 0.01);
                let free = occupancy.is_free(x, y, 0.0);
                let gap = 1.0 - x;
                if gap < radius as f32 * 0.97 {
                    free_near += usize::from(free);
                }
                if gap > radius as f32 + 0.03 {
                    far += 1;
                    free_far += usize::from(free);
                }
            }
        }
        assert_eq!(
            free_near, 0,
            "disk centres closer than the radius to the wall"
        );
        assert!(
            free_far as f64 > 0.97 * far as f64,
            "{free_far} of {far} clear points free"
        );
    }

    #[test]
    fn no_disk_centre_comes_within_a_radius_of_a_pillar_or_a_corner() {
        let radius = 0.1;
        let scenes = [
            crate::demo::scene::Scene::open().boxed(0.8, -0.3, 1.2, 0.1),
            crate::demo::scene::Scene::open().boxed(-1.0, -1.5, 1.5, 1.0),
        ];
        for scene in scenes {
            let lidar = crate::demo::scene::Lidar {
                beams: 180,
                range_min: 0.02,
                range_max: 10.0,
            };
            let scan = scene.scan(nalgebra::Vector2::zeros(), &level(), &lidar);
            let mut opts = options(radius);
            opts.unknown_space = UnknownSpace::Free;
            let occupancy = Occupancy::build(&scan, &level(), 1.0, &opts);
            for i in 0..300 {
                for j in 0..300 {
                    let (x, y) = (-1.5 + i as f64 * 0.01, -1.5 + j as f64 * 0.01);
                    let clearance = scene.clearance(nalgebra::Vector2::new(x, y));
                    if clearance < 0.97 * radius {
                        assert!(!occupancy.is_free(x as f32, y as f32, 0.0), "({x}, {y})");
                    }
                }
            }
        }
    }

    #[test]
    fn corridor_walls_keep_the_disk_a_radius_away_at_any_heading() {
        // The benchmark's corridor and end wall, at headings that put the bins at different
        // offsets from the beams, for a small robot and a large one (long walks).
        let scene = crate::demo::scene::Scene::corridor(2.5, 20.0).wall(2.5, -1.25, 2.5, 1.25);
        let lidar = crate::demo::scene::Lidar {
            beams: 360,
            range_min: 0.02,
            range_max: 3.0,
        };
        let position = nalgebra::Vector2::new(0.0, 0.3);
        for heading in [0.0, 0.3, 1.234, -2.9] {
            let attitude = UnitQuaternion::from_euler_angles(0.0, 0.0, heading);
            let scan = scene.scan(position, &attitude, &lidar);
            for radius in [0.06, 0.3] {
                let occupancy = Occupancy::build(&scan, &attitude, 1.0, &options(radius));
                let mut free = 0;
                for i in 0..240 {
                    for j in 0..240 {
                        let (x, y) = (-3.0 + i as f64 * 0.025, -3.0 + j as f64 * 0.025);
                        if occupancy.is_free(x as f32, y as f32, 0.0) {
                            free += 1;
                            let at = position + nalgebra::Vector2::new(x, y);
                            let clearance = scene.clearance(at);
                            assert!(
                                clearance >= 0.97 * radius,
                                "heading {heading}, radius {radius}: ({x}, {y}) {clearance} m"
                            );
                        }
                    }
                }
                assert!(
                    free > 2000,
                    "heading {heading}, radius {radius}: {free} free"
                );
            }
        }
    }

    #[test]
    fn absurd_scans_build_without_panicking_or_stalling() {
        let huge = Scan {
            range_max: f64::MAX,
            ..ring(f32::MAX, 1440)
        };
        let mut mixed = ring(1e30, 720);
        mixed.range_max = 1e31;
        for (i, r) in mixed.ranges.iter_mut().enumerate() {
            *r = [1e-30, f32::NAN, f32::NEG_INFINITY, f32::INFINITY, 0.0, 1e30][i % 6];
        }
        let scans = [
            huge,
            mixed,
            ring(f32::NAN, 360),
            ring(1e-30, 360),
            Scan {
                ranges: Vec::new(),
                ..ring(1.0, 1)
            },
            Scan {
                angle_increment: f64::NAN,
                ..ring(1.0, 10)
            },
            Scan {
                angle_increment: 0.0,
                ..ring(1.0, 10)
            },
        ];
        for scan in &scans {
            for unknown_space in [UnknownSpace::Occupied, UnknownSpace::Free] {
                let mut opts = options(0.06);
                opts.unknown_space = unknown_space;
                let occupancy = Occupancy::build(scan, &level(), 1.0, &opts);
                occupancy.is_free(0.5, 0.5, 0.0);
            }
        }
    }

    #[test]
    fn rep117_values_are_read_as_specified() {
        let mut scan = ring(1.0, 4);
        scan.ranges = vec![f32::NEG_INFINITY, f32::INFINITY, f32::NAN, 0.01];
        assert_eq!(scan.beam(0), Beam::Hit(0.05));
        assert_eq!(scan.beam(1), Beam::NoReturn);
        assert_eq!(scan.beam(2), Beam::Invalid);
        assert_eq!(scan.beam(3), Beam::Invalid);
        assert_eq!(
            scan.summary(),
            ScanSummary {
                hits: 1,
                no_returns: 1,
                invalid: 2
            }
        );
    }

    #[test]
    fn touching_an_obstacle_floor_or_ceiling_is_a_collision_at_start() {
        let near = Occupancy::build(&ring(0.05, 360), &level(), 1.0, &options(0.1));
        assert!(near.in_collision_at_start());
        let mut opts = options(0.1);
        opts.robot_height = 0.2;
        opts.floor = Some(0.0);
        opts.ceiling = Some(2.0);
        let ok = Occupancy::build(&ring(2.0, 360), &level(), 1.0, &opts);
        assert!(!ok.in_collision_at_start());
        assert!(ok.is_free(0.0, 0.5, 0.85));
        assert!(!ok.is_free(0.0, 0.5, 0.95));
        assert!(!ok.is_free(0.0, 0.5, -0.95));
        let low = Occupancy::build(&ring(2.0, 360), &level(), 0.05, &opts);
        assert!(low.in_collision_at_start());
    }
}
