//! Nearest-neighbour queries over the endpoints with a uniform bucket grid.
//!
//! Clustering asks for the k nearest endpoints of every terminal endpoint and the free-fraction
//! estimator for the nearest endpoint of ~1000–4000 probes; brute force would cost O(n) per query
//! (2000 endpoints: milliseconds). The grid holds about two endpoints per cell, so a query visits
//! a few rings of cells around its own and stops as soon as no unvisited cell can hold a closer
//! point — exact results in O(1) expected time per query for spread-out clouds.

/// The most neighbours one query can return.
pub(crate) const MAX_K: usize = 8;

/// Endpoints bucketed by cell (counting sort, CSR layout).
#[derive(Debug)]
pub(crate) struct NeighbourGrid<'a> {
    points: &'a [[f64; 3]],
    lo: [f64; 3],
    cell: f64,
    inv_cell: f64,
    cells: [usize; 3],
    /// `start[c]..start[c + 1]` indexes `members` for cell `c` (x fastest, then y, then z).
    start: Vec<u32>,
    members: Vec<u32>,
}

/// The result of a k-nearest query: up to [`MAX_K`] `(squared distance, point index)` pairs,
/// closest first.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Nearest {
    found: [(f64, u32); MAX_K],
    len: usize,
    k: usize,
}

impl Nearest {
    /// Indices of the neighbours found, closest first.
    pub(crate) fn indices(&self) -> impl Iterator<Item = usize> + '_ {
        self.found[..self.len].iter().map(|&(_, i)| i as usize)
    }

    /// Keeps the `k` closest candidates seen so far (insertion into a short sorted array).
    fn offer(&mut self, d2: f64, i: u32) {
        let mut at = if self.len < self.k {
            self.len += 1;
            self.len - 1
        } else if d2 < self.found[self.k - 1].0 {
            self.k - 1
        } else {
            return;
        };
        while at > 0 && self.found[at - 1].0 > d2 {
            self.found[at] = self.found[at - 1];
            at -= 1;
        }
        self.found[at] = (d2, i);
    }

    fn is_full(&self) -> bool {
        self.len == self.k
    }

    fn worst(&self) -> f64 {
        self.found[self.k - 1].0
    }
}

impl<'a> NeighbourGrid<'a> {
    /// Buckets `points`, of which the first `dims` coordinates count (the rest must be equal
    /// for all points, e.g. 0 in 2D). Cells are cubes sized for about two points each; the cell
    /// count stays O(n) however elongated the cloud is.
    pub(crate) fn new(points: &'a [[f64; 3]], dims: usize) -> Self {
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
            points,
            lo,
            cell,
            inv_cell: 1.0 / cell,
            cells,
            start: vec![0; cells.iter().product::<usize>() + 1],
            members: vec![0; points.len()],
        };
        for p in points {
            let c = grid.cell_index(grid.cell_of(p));
            grid.start[c + 1] += 1;
        }
        for c in 1..grid.start.len() {
            grid.start[c] += grid.start[c - 1];
        }
        let mut fill = grid.start.clone();
        for (i, p) in points.iter().enumerate() {
            let c = grid.cell_index(grid.cell_of(p));
            grid.members[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        grid
    }

    /// The `k` (≤ [`MAX_K`]) points nearest to `q`, leaving out the point with index `skip`
    /// (pass `usize::MAX` to keep all). Ties are broken arbitrarily.
    pub(crate) fn k_nearest(&self, q: &[f64; 3], skip: usize, k: usize) -> Nearest {
        let mut best = Nearest {
            found: [(f64::INFINITY, 0); MAX_K],
            len: 0,
            k: k.clamp(1, MAX_K),
        };
        if self.points.is_empty() {
            return best;
        }
        let c = self.cell_of(q);
        for r in 0.. {
            self.visit_ring(c, r, |i| {
                if i as usize != skip {
                    let p = &self.points[i as usize];
                    let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
                    best.offer(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], i);
                }
            });
            match self.clearance(q, c, r) {
                None => break,
                Some(g) if best.is_full() && best.worst() <= g * g => break,
                Some(_) => {}
            }
        }
        best
    }

    /// Index of the point nearest to `q` (`None` only for an empty grid).
    pub(crate) fn nearest(&self, q: &[f64; 3]) -> Option<usize> {
        self.k_nearest(q, usize::MAX, 1).indices().next()
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

    /// Calls `f` with every point in the cells at Chebyshev distance exactly `r` from cell `c`.
    fn visit_ring(&self, c: [usize; 3], r: usize, mut f: impl FnMut(u32)) {
        let r = r as isize;
        let c = c.map(|x| x as isize);
        let span = |a: usize| {
            (
                (c[a] - r).max(0),
                (c[a] + r).min(self.cells[a] as isize - 1),
            )
        };
        let (x0, x1) = span(0);
        let (y0, y1) = span(1);
        let (z0, z1) = span(2);
        let mut visit = |x: isize, y: isize, z: isize| {
            let id = self.cell_index([x as usize, y as usize, z as usize]);
            let (s, e) = (self.start[id] as usize, self.start[id + 1] as usize);
            self.members[s..e].iter().for_each(|&i| f(i));
        };
        for z in z0..=z1 {
            let z_face = (z - c[2]).abs() == r;
            for y in y0..=y1 {
                if z_face || (y - c[1]).abs() == r {
                    (x0..=x1).for_each(|x| visit(x, y, z));
                } else {
                    if c[0] - r >= 0 {
                        visit(c[0] - r, y, z);
                    }
                    if c[0] + r < self.cells[0] as isize {
                        visit(c[0] + r, y, z);
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
                    let got = grid.k_nearest(p, i, k);
                    let want = brute(&pts, p, i, k);
                    let got_d: Vec<f64> = got.found[..got.len].iter().map(|x| x.0).collect();
                    assert_eq!(got_d, want, "dims {dims} n {n} point {i}");
                }
                for _ in 0..50 {
                    let q = [rng.random::<f64>() * 9.0 - 0.5, rng.random::<f64>(), 0.0];
                    let q = if dims == 3 {
                        [q[0], q[1], rng.random::<f64>()]
                    } else {
                        q
                    };
                    let i = grid.nearest(&q).expect("non-empty");
                    let d: f64 = (0..3).map(|a| (pts[i][a] - q[a]).powi(2)).sum();
                    assert_eq!(d, brute(&pts, &q, usize::MAX, 1)[0]);
                }
            }
        }
    }

    #[test]
    fn empty_and_coincident_points() {
        let none: [[f64; 3]; 0] = [];
        assert!(NeighbourGrid::new(&none, 2).nearest(&[0.0; 3]).is_none());
        let same = [[1.0, 1.0, 0.0]; 6];
        let grid = NeighbourGrid::new(&same, 2);
        assert_eq!(grid.k_nearest(&same[0], 0, 8).indices().count(), 5);
    }
}
