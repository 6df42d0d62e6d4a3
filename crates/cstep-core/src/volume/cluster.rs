//! Clustering of terminal endpoints (paper Section 3.3: "convex hulls of clustered terminal
//! points").
//!
//! Clustering runs in position space only (metres; never mixed with angles or velocities).
//! Two terminal endpoints are linked when one is among the other's k nearest neighbours in the
//! *full* endpoint set, free endpoints included; clusters are the connected components of these
//! links (union-find flood fill). Because free endpoints take part in the neighbour lists, a
//! band of free endpoints between two terminal groups fills their neighbour lists and keeps
//! them apart, so a hull is never stretched across free space.

use super::neighbours::NeighbourGrid;

/// Number of neighbours `k` consulted per terminal endpoint: 8, in 2D and in 3D.
///
/// Larger k lets links reach over thin bands of free endpoints and merge separate obstacles
/// (whose hull then swallows the free band); smaller k fragments thin terminal layers into
/// pieces whose hulls leave gaps. 8 splits thin terminal layers least while free bands two
/// endpoint spacings wide still keep clusters apart; the ignored test `link_neighbours_study`
/// measures the trade-off (results in `experiments/protocol.md`, "Moved from the code's
/// comments").
pub(crate) const LINK_NEIGHBOURS: usize = 8;

/// Terminal endpoints grouped into clusters: each cluster is a list of endpoint indices.
#[derive(Debug, Clone, Default)]
pub(crate) struct Clusters {
    members: Vec<u32>,
    bounds: Vec<usize>,
}

impl Clusters {
    /// Number of clusters.
    pub(crate) fn len(&self) -> usize {
        self.bounds.len().saturating_sub(1)
    }

    /// The clusters, each as the indices of its endpoints.
    pub(crate) fn iter(&self) -> impl Iterator<Item = &[u32]> + '_ {
        self.bounds.windows(2).map(|w| &self.members[w[0]..w[1]])
    }
}

/// Clusters the terminal endpoints (`terminal[i]`) of the points bucketed in `grid`, linking
/// through `k` nearest neighbours (production: [`LINK_NEIGHBOURS`]); see the module docs.
pub(crate) fn cluster_terminal(
    grid: &NeighbourGrid,
    points: &[[f64; 3]],
    terminal: &[bool],
    k: usize,
) -> Clusters {
    let mut parent: Vec<u32> = (0..points.len() as u32).collect();
    for (i, p) in points.iter().enumerate() {
        if !terminal[i] {
            continue;
        }
        for j in grid.k_nearest(p, i, k) {
            if terminal[j] {
                union(&mut parent, i, j);
            }
        }
    }
    // Number components by root in order of first appearance, then lay them out contiguously.
    let mut id = vec![u32::MAX; points.len()];
    let mut sizes: Vec<usize> = Vec::new();
    for i in (0..points.len()).filter(|&i| terminal[i]) {
        let r = find(&mut parent, i);
        if id[r] == u32::MAX {
            id[r] = sizes.len() as u32;
            sizes.push(0);
        }
        sizes[id[r] as usize] += 1;
    }
    let mut bounds = Vec::with_capacity(sizes.len() + 1);
    bounds.push(0);
    for s in &sizes {
        bounds.push(bounds[bounds.len() - 1] + s);
    }
    let mut fill = bounds.clone();
    let mut members = vec![0; fill[sizes.len()]];
    for i in (0..points.len()).filter(|&i| terminal[i]) {
        let c = id[find(&mut parent, i)] as usize;
        members[fill[c]] = i as u32;
        fill[c] += 1;
    }
    Clusters { members, bounds }
}

fn find(parent: &mut [u32], mut i: usize) -> usize {
    while parent[i] as usize != i {
        let up = parent[parent[i] as usize];
        parent[i] = up;
        i = up as usize;
    }
    i
}

fn union(parent: &mut [u32], a: usize, b: usize) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        parent[ra.max(rb)] = ra.min(rb) as u32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::test_points::uniform_in_cube;

    fn clusters_of(points: &[[f64; 3]], terminal: &[bool]) -> Vec<Vec<u32>> {
        let grid = NeighbourGrid::new(points, 2);
        let c = cluster_terminal(&grid, points, terminal, LINK_NEIGHBOURS);
        c.iter().map(|m| m.to_vec()).collect()
    }

    /// A regular grid of points over `[0, w) × [0, h)` with spacing `s`.
    fn lattice(w: usize, h: usize, s: f64) -> Vec<[f64; 3]> {
        (0..h)
            .flat_map(|j| (0..w).map(move |i| [i as f64 * s, j as f64 * s, 0.0]))
            .collect()
    }

    #[test]
    fn two_separated_groups_form_two_clusters() {
        let pts = lattice(20, 10, 0.1);
        // Terminal: columns 0..3 and columns 16..20; free in between.
        let terminal: Vec<bool> = pts.iter().map(|p| p[0] < 0.25 || p[0] > 1.55).collect();
        let c = clusters_of(&pts, &terminal);
        assert_eq!(c.len(), 2);
        assert_eq!(
            c[0].len() + c[1].len(),
            terminal.iter().filter(|&&t| t).count()
        );
        assert!(c[0].iter().all(|&i| pts[i as usize][0] < 0.25));
        assert!(c[1].iter().all(|&i| pts[i as usize][0] > 1.55));
    }

    #[test]
    fn free_band_keeps_terminal_groups_apart() {
        // Terminal columns at x = 0 and x = 0.3, with two free columns (0.1, 0.2) between:
        // Euclidean distance alone (0.3) is small, but the free points fill the neighbour lists
        // (a point's 8 nearest reach 0.2 away at most).
        let pts = lattice(4, 30, 0.1);
        let terminal: Vec<bool> = pts.iter().map(|p| p[0] < 0.05 || p[0] > 0.25).collect();
        assert_eq!(clusters_of(&pts, &terminal).len(), 2);
        // Without the free points the two terminal columns are one cluster: the links are
        // blocked by the free points, not by the distance.
        let only: Vec<[f64; 3]> = pts
            .iter()
            .zip(&terminal)
            .filter(|(_, &t)| t)
            .map(|(p, _)| *p)
            .collect();
        assert_eq!(clusters_of(&only, &vec![true; only.len()]).len(), 1);
    }

    #[test]
    fn all_terminal_is_one_cluster_and_none_is_empty() {
        let pts = lattice(10, 10, 0.1);
        assert_eq!(clusters_of(&pts, &vec![true; pts.len()]).len(), 1);
        assert!(clusters_of(&pts, &vec![false; pts.len()]).is_empty());
    }

    /// `n` uniform points in [-1, 1]^dims labelled by `is_terminal`: cluster sizes, largest first.
    fn cluster_sizes(
        n: usize,
        dims: usize,
        k: usize,
        seed: u64,
        is_terminal: impl Fn(&[f64; 3]) -> bool,
    ) -> Vec<usize> {
        let pts = uniform_in_cube(n, dims, seed);
        let terminal: Vec<bool> = pts.iter().map(is_terminal).collect();
        let grid = NeighbourGrid::new(&pts, dims);
        let mut sizes: Vec<usize> = cluster_terminal(&grid, &pts, &terminal, k)
            .iter()
            .map(<[u32]>::len)
            .collect();
        sizes.sort_unstable_by(|a, b| b.cmp(a));
        sizes
    }

    /// The measurement behind [`LINK_NEIGHBOURS`] (run with `--ignored --nocapture`).
    #[test]
    #[ignore = "study, prints a table"]
    fn link_neighbours_study() {
        let (n, runs) = (3000, 40);
        for dims in [2, 3] {
            let s = (2f64.powi(dims as i32) / n as f64).powf(1.0 / dims as f64);
            for k in [4, 6, 8] {
                let (mut splits, mut extra) = (0, 0);
                for seed in 0..runs {
                    for thick in [3.0, 5.0] {
                        let sizes =
                            cluster_sizes(n, dims, k, seed, |p| p[0].abs() < thick * s / 2.0);
                        extra += sizes.len() - 1;
                        splits += usize::from(sizes.len() > 1 && sizes[1] > 5);
                    }
                }
                let merged: Vec<String> = [1.5, 2.0, 3.0]
                    .iter()
                    .map(|band| {
                        let m = (0..runs)
                            .filter(|&seed| {
                                let sizes = cluster_sizes(n, dims, k, seed, |p| {
                                    p[0].abs() > band * s / 2.0
                                });
                                sizes[0] > sizes.iter().sum::<usize>() * 3 / 4
                            })
                            .count();
                        format!("{band} s: {m}/{runs}")
                    })
                    .collect();
                eprintln!(
                    "{dims}D k={k}: split {splits}/{}, extra clusters/run {:.2}, merged {}",
                    2 * runs,
                    extra as f64 / runs as f64,
                    merged.join(", ")
                );
            }
        }
    }
}
