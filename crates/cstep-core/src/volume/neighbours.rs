//! Neighbour queries over the endpoints with a uniform bucket grid.
//!
//! Clustering asks for the k nearest endpoints of every terminal endpoint, and the free-fraction
//! estimator for the endpoints near each of its integration lines; brute force would cost O(n)
//! per query (2000 endpoints: milliseconds per estimate). The grid holds about two endpoints per
//! cell and stores their coordinates in cell order, so that one grid row is one contiguous run
//! of memory. A k-nearest query visits rings of cells around its own and stops as soon as no
//! unvisited cell can hold a closer point: exact, O(1) expected time for spread-out clouds.

/// The most neighbours one query can return.
pub(crate) const MAX_K: usize = 8;

/// Endpoints bucketed by cell (counting sort): coordinates are copied in cell order so that
/// the cells of one grid row form one contiguous run of memory.
#[derive(Debug)]
pub(crate) struct NeighbourGrid {
    /// Points in cell order (x fastest, then y, then z).
    sorted: Vec<[f64; 3]>,
    /// Caller's index of `sorted[s]`.
    ids: Vec<u32>,
    /// `start[c]..start[c + 1]` are the slots of cell `c`.
    start: Vec<u32>,
    lo: [f64; 3],
    cell: f64,
    inv_cell: f64,
    cells: [usize; 3],
}

/// The result of a k-nearest query: up to [`MAX_K`] `(squared distance, caller's index)`
/// pairs, closest first.
#[derive(Debug, Clone, Copy)]
struct Nearest {
    found: [(f64, u32); MAX_K],
    len: usize,
    k: usize,
    /// Squared distance a candidate must beat to enter (∞ until `k` are found).
    bound: f64,
}

impl Nearest {
    fn new(k: usize) -> Self {
        Nearest {
            found: [(f64::INFINITY, 0); MAX_K],
            len: 0,
            k: k.clamp(1, MAX_K),
            bound: f64::INFINITY,
        }
    }

    /// Inserts a candidate closer than `bound` (insertion into a short sorted array).
    #[inline]
    fn offer(&mut self, d2: f64, id: u32) {
        let mut at = if self.len < self.k {
            self.len += 1;
            self.len - 1
        } else {
            self.k - 1
        };
        while at > 0 && self.found[at - 1].0 > d2 {
            self.found[at] = self.found[at - 1];
            at -= 1;
        }
        self.found[at] = (d2, id);
        if self.len == self.k {
            self.bound = self.found[self.k - 1].0;
        }
    }
}

impl NeighbourGrid {
    /// Buckets `points`, of which the first `dims` coordinates count (the rest must be equal
    /// for all points, e.g. 0 in 2D). Cells are cubes sized for about two points each; the cell
    /// count stays O(n) however elongated the cloud is.
    pub(crate) fn new(points: &[[f64; 3]], dims: usize) -> Self {
        let mut lo = points.first().copied().unwrap_or([0.0; 3]);
        let mut hi = lo;
        for p in points {
            for a in 0..dims {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let extent: [f64; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        let widest = extent[..dims].iter().fold(0.0_f64, |m, &e| m.max(e));
        let target = (points.len() / 2).max(1) as f64;
        let mut cell = (extent[..dims].iter().product::<f64>() / target).powf(1.0 / dims as f64);
        // At most ~2·target cells along the widest axis (also catches a NaN or zero product).
        cell = cell.max(widest / (2.0 * target));
        if !(cell.is_finite() && cell > 0.0) {
            cell = 1.0;
        }
        let max_cells = 4 * points.len() + 64;
        let mut cells = [1usize; 3];
        loop {
            for a in 0..dims {
                cells[a] = (extent[a] / cell) as usize + 1;
            }
            if cells.iter().product::<usize>() <= max_cells {
                break;
            }
            cell *= 1.25;
        }
        let mut grid = NeighbourGrid {
            sorted: vec![[0.0; 3]; points.len()],
            ids: vec![0; points.len()],
            start: vec![0; cells.iter().product::<usize>() + 1],
            lo,
            cell,
            inv_cell: 1.0 / cell,
            cells,
        };
        let cell_ids: Vec<u32> = points
            .iter()
            .map(|p| grid.cell_index(grid.cell_of(p)) as u32)
            .collect();
        for &c in &cell_ids {
            grid.start[c as usize + 1] += 1;
        }
        for c in 1..grid.start.len() {
            grid.start[c] += grid.start[c - 1];
        }
        let mut fill = grid.start.clone();
        for (i, (p, &c)) in points.iter().zip(&cell_ids).enumerate() {
            let s = fill[c as usize] as usize;
            grid.sorted[s] = *p;
            grid.ids[s] = i as u32;
            fill[c as usize] += 1;
        }
        grid
    }

    /// Caller's indices of the `k` (≤ [`MAX_K`]) points nearest to `q`, closest first, leaving
    /// out the point with index `skip` (`usize::MAX` keeps all). Ties are broken arbitrarily.
    pub(crate) fn k_nearest(
        &self,
        q: &[f64; 3],
        skip: usize,
        k: usize,
    ) -> impl Iterator<Item = usize> + '_ {
        let best = self.ring_search(q, skip, k);
        (0..best.len).map(move |i| best.found[i].1 as usize)
    }

    /// Side of the grid's cubic cells (about two points per cell).
    pub(crate) fn cell(&self) -> f64 {
        self.cell
    }

    /// Fills `out` with `(coordinate along axis, squared distance across the line, caller's
    /// index)` for every point closer than `reach` to the axis-parallel line through `at` along
    /// `axis` whose coordinate along the line lies within `reach` of `[from, to]`, sorted along
    /// the line. Returns `true` when the band covered the whole grid, in which case `out` holds
    /// every point, however far.
    pub(crate) fn near_line(
        &self,
        at: &[f64; 3],
        axis: usize,
        [from, to]: [f64; 2],
        reach: f64,
        out: &mut Vec<(f64, f64, u32)>,
    ) -> bool {
        let mut lo = self.cell_of(&at.map(|c| c - reach));
        let mut hi = self.cell_of(&at.map(|c| c + reach));
        let complete = (0..3).all(|a| a == axis || (lo[a] == 0 && hi[a] == self.cells[a] - 1));
        let (mut first, mut last) = (*at, *at);
        (first[axis], last[axis]) = (from - reach, to + reach);
        lo[axis] = if complete {
            0
        } else {
            self.cell_of(&first)[axis]
        };
        hi[axis] = if complete {
            self.cells[axis] - 1
        } else {
            self.cell_of(&last)[axis]
        };
        let reach2 = if complete {
            f64::INFINITY
        } else {
            reach * reach
        };
        // The two axes across the line.
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        out.clear();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let row = self.row(lo[0], hi[0], y, z);
                // Branch-free filter: write every point, advance only past those within reach
                // (a data-dependent branch here mispredicts about a third of the time).
                let mut len = out.len();
                out.resize(len + row.len(), (0.0, 0.0, 0));
                for (p, &id) in self.sorted[row.clone()].iter().zip(&self.ids[row]) {
                    let (du, dv) = (p[u] - at[u], p[v] - at[v]);
                    let across = du * du + dv * dv;
                    out[len] = (p[axis], across, id);
                    len += usize::from(across < reach2);
                }
                out.truncate(len);
            }
        }
        // Rows come in ascending cell order along the line (`axis` is the slowest-varying grid
        // axis in play), so the list is nearly sorted and insertion sort is linear in practice.
        for i in 1..out.len() {
            let item = out[i];
            let mut j = i;
            while j > 0 && out[j - 1].0 > item.0 {
                out[j] = out[j - 1];
                j -= 1;
            }
            out[j] = item;
        }
        complete
    }

    /// Exact k-nearest search: rings of cells around `q`'s cell until no unvisited cell can
    /// hold a closer point.
    fn ring_search(&self, q: &[f64; 3], skip: usize, k: usize) -> Nearest {
        let mut best = Nearest::new(k);
        if self.sorted.is_empty() {
            return best;
        }
        let c = self.cell_of(q);
        // Ring 0 alone rarely holds k points: start with the whole 3 × 3 (× 3) block, whose
        // rows are contiguous runs.
        let block = |a: usize| (c[a].saturating_sub(1), (c[a] + 1).min(self.cells[a] - 1));
        let ((x0, x1), (y0, y1), (z0, z1)) = (block(0), block(1), block(2));
        for z in z0..=z1 {
            for y in y0..=y1 {
                self.scan(self.row(x0, x1, y, z), q, skip, &mut best);
            }
        }
        for r in 1.. {
            if r > 1 {
                let reach2 = best.bound;
                self.visit_ring(c, r, q, reach2, |slots| {
                    self.scan(slots, q, skip, &mut best)
                });
            }
            match self.clearance(q, c, r) {
                None => break,
                Some(g) if best.bound <= g * g => break,
                Some(_) => {}
            }
        }
        best
    }

    /// Offers the points in `slots` (except index `skip`) to `best`.
    fn scan(&self, slots: std::ops::Range<usize>, q: &[f64; 3], skip: usize, best: &mut Nearest) {
        let ids = &self.ids[slots.clone()];
        for (p, &id) in self.sorted[slots].iter().zip(ids) {
            let d2 = dist2(p, q);
            if d2 < best.bound && id as usize != skip {
                best.offer(d2, id);
            }
        }
    }

    fn cell_of(&self, p: &[f64; 3]) -> [usize; 3] {
        // `as usize` saturates: below the grid → 0, NaN → 0; above is clamped to the last cell.
        std::array::from_fn(|a| {
            (((p[a] - self.lo[a]) * self.inv_cell) as usize).min(self.cells[a] - 1)
        })
    }

    fn cell_index(&self, c: [usize; 3]) -> usize {
        c[0] + self.cells[0] * (c[1] + self.cells[1] * c[2])
    }

    /// Slots of the cells `x0..=x1` of row `(y, z)`: one contiguous range.
    fn row(&self, x0: usize, x1: usize, y: usize, z: usize) -> std::ops::Range<usize> {
        self.start[self.cell_index([x0, y, z])] as usize
            ..self.start[self.cell_index([x1, y, z]) + 1] as usize
    }

    /// Calls `f` with the slot ranges of the cells at Chebyshev distance exactly `r` from `c`
    /// that come closer to `q` than `sqrt(reach2)` (rows are trimmed to those cells).
    fn visit_ring(
        &self,
        c: [usize; 3],
        r: usize,
        q: &[f64; 3],
        reach2: f64,
        mut f: impl FnMut(std::ops::Range<usize>),
    ) {
        let span = |a: usize| (c[a].saturating_sub(r), (c[a] + r).min(self.cells[a] - 1));
        let (x0, x1) = span(0);
        let (y0, y1) = span(1);
        let (z0, z1) = span(2);
        // Squared distance from q to the slab of cells `i` along axis `a`.
        let gap2 = |a: usize, i: usize| {
            let start = self.lo[a] + i as f64 * self.cell;
            let g = (start - q[a]).max(q[a] - start - self.cell).max(0.0);
            g * g
        };
        // Cells along x within reach, given the squared distance `used` across y and z.
        let x_span = |used: f64| {
            let room = (reach2 - used).sqrt();
            let lo = ((q[0] - room - self.lo[0]) * self.inv_cell)
                .floor()
                .max(0.0) as usize;
            let hi = ((q[0] + room - self.lo[0]) * self.inv_cell).floor();
            (lo.max(x0), (hi.max(0.0) as usize).min(x1))
        };
        for z in z0..=z1 {
            let z_face = z.abs_diff(c[2]) == r;
            let gz = gap2(2, z);
            for y in y0..=y1 {
                let used = gz + gap2(1, y);
                if used >= reach2 {
                    continue;
                }
                let (xa, xb) = x_span(used);
                if z_face || y.abs_diff(c[1]) == r {
                    if xa <= xb {
                        f(self.row(xa, xb, y, z));
                    }
                } else {
                    for x in [c[0].wrapping_sub(r), c[0] + r] {
                        if (xa..=xb).contains(&x) {
                            f(self.row(x, x, y, z));
                        }
                    }
                }
            }
        }
    }

    /// After visiting rings `0..=r` around cell `c`: the distance from `q` within which every
    /// point has been seen, or `None` once the rings cover the whole grid.
    fn clearance(&self, q: &[f64; 3], c: [usize; 3], r: usize) -> Option<f64> {
        let mut g = f64::INFINITY;
        let mut bounded = false;
        for a in 0..3 {
            if c[a] > r {
                bounded = true;
                g = g.min(q[a] - (self.lo[a] + (c[a] - r) as f64 * self.cell));
            }
            if c[a] + r + 1 < self.cells[a] {
                bounded = true;
                g = g.min(self.lo[a] + (c[a] + r + 1) as f64 * self.cell - q[a]);
            }
        }
        bounded.then_some(g.max(0.0))
    }
}

fn dist2(p: &[f64; 3], q: &[f64; 3]) -> f64 {
    let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn brute(points: &[[f64; 3]], q: &[f64; 3], skip: usize, k: usize) -> Vec<f64> {
        let mut d: Vec<f64> = points
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != skip)
            .map(|(_, p)| (0..3).map(|a| (p[a] - q[a]).powi(2)).sum())
            .collect();
        d.sort_by(f64::total_cmp);
        d.truncate(k);
        d
    }

    #[test]
    fn matches_brute_force_in_2d_and_3d() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for dims in [2, 3] {
            for n in [1, 5, 37, 400] {
                // An elongated, clumpy cloud to exercise uneven cells.
                let pts: Vec<[f64; 3]> = (0..n)
                    .map(|_| {
                        let clump = if rng.random::<bool>() { 5.0 } else { 0.0 };
                        let z = if dims == 3 { rng.random::<f64>() } else { 0.0 };
                        [
                            clump + 3.0 * rng.random::<f64>(),
                            0.3 * rng.random::<f64>(),
                            z,
                        ]
                    })
                    .collect();
                let grid = NeighbourGrid::new(&pts, dims);
                for (i, p) in pts.iter().enumerate() {
                    let k = 2 * dims + 2;
                    let want = brute(&pts, p, i, k);
                    let got: Vec<f64> =
                        grid.k_nearest(p, i, k).map(|j| dist2(&pts[j], p)).collect();
                    assert_eq!(got, want, "dims {dims} n {n} point {i}");
                }
                for _ in 0..50 {
                    let q = [rng.random::<f64>() * 9.0 - 0.5, rng.random::<f64>(), 0.0];
                    let q = if dims == 3 {
                        [q[0], q[1], rng.random::<f64>()]
                    } else {
                        q
                    };
                    let want = brute(&pts, &q, usize::MAX, 1)[0];
                    let i = grid.k_nearest(&q, usize::MAX, 1).next().expect("non-empty");
                    assert_eq!(dist2(&pts[i], &q), want);
                }
                // Points near a line: exactly those within reach, sorted along it.
                let q = pts[n / 2];
                let mut near = Vec::new();
                let reach = 0.2;
                let complete = grid.near_line(&q, dims - 1, [-9.0, 9.0], reach, &mut near);
                let across =
                    |p: &[f64; 3]| -> f64 { (0..dims - 1).map(|a| (p[a] - q[a]).powi(2)).sum() };
                let want: Vec<usize> = (0..n)
                    .filter(|&i| complete || across(&pts[i]) < reach * reach)
                    .collect();
                assert!(near.windows(2).all(|w| w[0].0 <= w[1].0));
                let mut got: Vec<usize> = near.iter().map(|c| c.2 as usize).collect();
                got.sort_unstable();
                assert_eq!(got, want);
            }
        }
    }

    #[test]
    fn empty_and_coincident_points() {
        let none: [[f64; 3]; 0] = [];
        assert!(NeighbourGrid::new(&none, 2)
            .k_nearest(&[0.0; 3], usize::MAX, 1)
            .next()
            .is_none());
        let mut near = vec![(0.0, 0.0, 0)];
        assert!(NeighbourGrid::new(&none, 2).near_line(&[0.0; 3], 1, [0.0, 1.0], 1.0, &mut near));
        assert!(near.is_empty());
        assert_eq!(
            NeighbourGrid::new(&none, 2)
                .k_nearest(&[0.0; 3], 0, 3)
                .count(),
            0
        );
        let same = [[1.0, 1.0, 0.0]; 6];
        let grid = NeighbourGrid::new(&same, 2);
        assert_eq!(grid.k_nearest(&same[0], 0, 8).count(), 5);
    }
}
