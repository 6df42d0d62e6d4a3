//! Reachable, terminal and free volumes from labelled trajectory endpoints (paper Section 3.3).
//!
//! Algorithm 1 of the paper rolls out sampled control trajectories and keeps each final
//! position, labelled *terminal* if its trajectory collided. From these endpoints this module
//! estimates λ(R̂) (everything reachable), λ(T̂) (the part whose trajectories collide) and the
//! free volume λ(R̂) − λ(T̂), whose logarithm is C-STEP. Three estimators ([`EstimatorKind`]):
//!
//! - **Hull** — the paper: R̂ = convex hull of *all* endpoints (free and terminal), T̂ = the
//!   *union* of the convex hulls of clustered terminal endpoints. Clusters live in position
//!   space only and are linked through the full endpoint set, so they never bridge free space
//!   (`cluster.rs`); overlapping hulls are united, not summed (`union.rs`).
//! - **Efron** — Hull with the hull's sampling bias removed by Efron's identity: the hull of n
//!   uniform samples misses a share v/(n+1) of the body (v hull vertices); −12 % for a disk and
//!   −32 % for a ball at n = 150 without it.
//! - **FreeFraction** — the reachable volume (the raw hull) times the share of R̂ whose nearest
//!   endpoint is free (`free_fraction.rs`); unlike hull subtraction it handles non-convex
//!   obstacles, and terminal regions that surround the free one. It takes the raw hull because
//!   the default bang-bang sampler reaches the extreme points of the reachable set: measured on
//!   the point mass's exact box, the raw hull is within 0.05 % at n = 150 while Efron's
//!   correction, which assumes uniform samples, over-shoots by +3 %.
//!
//! Conventions: endpoints are in metres; [`VolumeDims::Two`] uses only x and y. Endpoints with
//! a non-finite coordinate (among those used) are dropped before anything else — a diverged
//! rollout carries no position information — and `terminal` labels go with the points they
//! index (a point without a label counts as free). Every output is finite and ≥ 0 with
//! `free ≤ reachable`; clouds that span no volume (empty, too few points, all equal, collinear
//! in 2D, coplanar in 3D — thinner than 1e-9 of their width, see `frame.rs`) give all zeros. Nothing here panics.

mod cluster;
mod frame;
mod free_fraction;
mod hull;
mod neighbours;
mod strips;
#[cfg(test)]
mod test_points;
mod union;

use hull::{efron_factor, Polygon, Polyhedron};
use neighbours::NeighbourGrid;

/// Counter-clockwise vertices of the convex hull of the points' `x, y` coordinates — the
/// outline of a planar reachable set, as `/cstep/markers` draws it; `None` when the points span
/// no area (the same degenerate cases as the volumes). Non-finite points must be dropped first.
pub fn planar_hull(points: &[[f64; 3]]) -> Option<Vec<[f64; 2]>> {
    Polygon::hull(points).map(|polygon| polygon.vertices().to_vec())
}

/// Dimension in which volumes are measured: areas of (x, y) for robots flying at a fixed
/// altitude (the paper's drone experiment), volumes of (x, y, z) otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum VolumeDims {
    /// Areas in the horizontal plane (m²).
    #[serde(rename = "2")]
    Two,
    /// Volumes in space (m³).
    #[serde(rename = "3")]
    Three,
}

impl VolumeDims {
    /// Number of coordinates measured (2 or 3).
    pub fn count(self) -> usize {
        match self {
            VolumeDims::Two => 2,
            VolumeDims::Three => 3,
        }
    }
}

/// How free volume is estimated from labelled endpoints; see the module documentation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EstimatorKind {
    /// The paper's estimator: hull of all endpoints minus the union of terminal-cluster hulls.
    Hull,
    /// [`EstimatorKind::Hull`] de-biased by Efron's identity (same terminal share).
    Efron,
    /// Reachable volume (raw hull) × the free share of R̂ by nearest-endpoint labelling.
    FreeFraction,
}

impl EstimatorKind {
    /// Every estimator, in a fixed order (for benchmarks and comparison tables).
    pub const ALL: [EstimatorKind; 3] = [
        EstimatorKind::Hull,
        EstimatorKind::Efron,
        EstimatorKind::FreeFraction,
    ];

    /// Name used in configs and reports: `hull`, `efron` or `free_fraction`.
    pub fn name(self) -> &'static str {
        match self {
            EstimatorKind::Hull => "hull",
            EstimatorKind::Efron => "efron",
            EstimatorKind::FreeFraction => "free_fraction",
        }
    }

    /// Inverse of [`EstimatorKind::name`]; `None` for an unknown name.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// Volumes estimated from one set of endpoints, in m² ([`VolumeDims::Two`]) or m³.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Volumes {
    /// λ(R̂): everything reachable within the horizon, colliding or not.
    pub reachable: f64,
    /// λ(T̂): the part of R̂ reached only by colliding trajectories.
    pub terminal: f64,
    /// λ(R̂) − λ(T̂), the volume whose logarithm is C-STEP; `0 ≤ free ≤ reachable`.
    pub free: f64,
    /// Vertices of the hull of all endpoints (Efron's `v`; 0 if the endpoints span no volume).
    pub hull_vertices: usize,
    /// Connected clusters of terminal endpoints, including those too small to span a volume
    /// (which contribute nothing). 0 for [`EstimatorKind::FreeFraction`], which does not cluster.
    pub terminal_clusters: usize,
}

impl Volumes {
    const ZERO: Volumes = Volumes {
        reachable: 0.0,
        terminal: 0.0,
        free: 0.0,
        hull_vertices: 0,
        terminal_clusters: 0,
    };
}

/// Estimates reachable, terminal and free volume from trajectory endpoints.
///
/// `points` are endpoints in metres (x, y, z; in 2D only x and y are used); `terminal[i]` says
/// endpoint `i` came from a colliding trajectory. See the module documentation for the
/// estimators and the handling of degenerate and non-finite input.
pub fn estimate(
    points: &[[f64; 3]],
    terminal: &[bool],
    dims: VolumeDims,
    kind: EstimatorKind,
) -> Volumes {
    let cloud = Cloud::gather(points, terminal, dims.count());
    match dims {
        VolumeDims::Two => estimate_with::<Polygon>(&cloud, kind),
        VolumeDims::Three => estimate_with::<Polyhedron>(&cloud, kind),
    }
}

/// Finite endpoints with their labels, translated to the centre of their bounding box (volumes
/// are translation invariant; centred coordinates keep hull arithmetic precise far from the
/// origin). In 2D the z coordinate is set to 0.
struct Cloud {
    points: Vec<[f64; 3]>,
    terminal: Vec<bool>,
    dims: usize,
}

impl Cloud {
    fn gather(points: &[[f64; 3]], terminal: &[bool], dims: usize) -> Cloud {
        let mut kept = Vec::with_capacity(points.len());
        let mut labels = Vec::with_capacity(points.len());
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (i, p) in points.iter().enumerate() {
            if p[..dims].iter().all(|c| c.is_finite()) {
                let q = if dims == 2 { [p[0], p[1], 0.0] } else { *p };
                kept.push(q);
                labels.push(terminal.get(i).copied().unwrap_or(false));
            }
        }
        // The bounding box over all three axes (those past `dims` are 0 and unused): with a
        // fixed count the bounds stay in registers, where a loop to `dims` kept them in memory
        // as a store-to-load chain through every point.
        for q in &kept {
            for a in 0..3 {
                lo[a] = lo[a].min(q[a]);
                hi[a] = hi[a].max(q[a]);
            }
        }
        if !kept.is_empty() {
            let centre: [f64; 3] =
                std::array::from_fn(|a| if a < dims { 0.5 * (lo[a] + hi[a]) } else { 0.0 });
            for q in &mut kept {
                for a in 0..dims {
                    q[a] -= centre[a];
                }
            }
        }
        Cloud {
            points: kept,
            terminal: labels,
            dims,
        }
    }
}

/// A convex hull in the measured dimension, so that the estimators run unchanged in 2D
/// ([`Polygon`]) and 3D ([`Polyhedron`]).
trait ConvexBody: Sized {
    /// Hull of `points`, `None` if they span no volume.
    fn hull(points: &[[f64; 3]]) -> Option<Self>;
    /// Volume (area in 2D).
    fn measure(&self) -> f64;
    /// Number of hull vertices.
    fn vertex_count(&self) -> usize;
    /// Volume of the union of `bodies`.
    fn union_measure(bodies: &[Self]) -> f64;
    /// Free share of the body by nearest-endpoint labelling of `points`; `None` if
    /// unmeasurable.
    fn free_fraction(&self, points: &[[f64; 3]], terminal: &[bool]) -> Option<f64>;
}

impl ConvexBody for Polygon {
    fn hull(points: &[[f64; 3]]) -> Option<Self> {
        Polygon::hull(points)
    }
    fn measure(&self) -> f64 {
        self.area()
    }
    fn vertex_count(&self) -> usize {
        Polygon::vertex_count(self)
    }
    fn union_measure(bodies: &[Self]) -> f64 {
        union::union_area(bodies)
    }
    fn free_fraction(&self, points: &[[f64; 3]], terminal: &[bool]) -> Option<f64> {
        free_fraction::free_fraction_2d(self, points, terminal)
    }
}

impl ConvexBody for Polyhedron {
    fn hull(points: &[[f64; 3]]) -> Option<Self> {
        Polyhedron::hull(points)
    }
    fn measure(&self) -> f64 {
        self.volume()
    }
    fn vertex_count(&self) -> usize {
        Polyhedron::vertex_count(self)
    }
    fn union_measure(bodies: &[Self]) -> f64 {
        union::union_volume(bodies)
    }
    fn free_fraction(&self, points: &[[f64; 3]], terminal: &[bool]) -> Option<f64> {
        free_fraction::free_fraction_3d(self, points, terminal)
    }
}

fn estimate_with<B: ConvexBody>(cloud: &Cloud, kind: EstimatorKind) -> Volumes {
    let points = &cloud.points;
    let Some(reach) = B::hull(points) else {
        return Volumes::ZERO;
    };
    let raw = reach.measure();
    let hull_vertices = reach.vertex_count();
    let terminal_count = cloud.terminal.iter().filter(|&&t| t).count();
    match kind {
        EstimatorKind::Hull | EstimatorKind::Efron => {
            let (terminal_raw, terminal_clusters) = if terminal_count == 0 {
                (0.0, 0)
            } else {
                terminal_union::<B>(cloud)
            };
            let terminal_raw = terminal_raw.clamp(0.0, raw);
            let (reachable, terminal) = if kind == EstimatorKind::Hull {
                (raw, terminal_raw)
            } else {
                let corrected = raw * efron_factor(hull_vertices, points.len());
                (corrected, corrected * (terminal_raw / raw))
            };
            Volumes {
                reachable,
                terminal,
                free: (reachable - terminal).max(0.0),
                hull_vertices,
                terminal_clusters,
            }
        }
        EstimatorKind::FreeFraction => {
            let endpoint_share = 1.0 - terminal_count as f64 / points.len() as f64;
            let free_share = if terminal_count == 0 || terminal_count == points.len() {
                endpoint_share
            } else {
                reach
                    .free_fraction(points, &cloud.terminal)
                    .unwrap_or(endpoint_share)
            };
            Volumes {
                reachable: raw,
                terminal: raw * (1.0 - free_share),
                free: raw * free_share,
                hull_vertices,
                terminal_clusters: 0,
            }
        }
    }
}

/// Volume of the union of the terminal clusters' hulls, and the number of clusters.
fn terminal_union<B: ConvexBody>(cloud: &Cloud) -> (f64, usize) {
    let grid = NeighbourGrid::new(&cloud.points, cloud.dims);
    let clusters = cluster::cluster_terminal(
        &grid,
        &cloud.points,
        &cloud.terminal,
        cluster::LINK_NEIGHBOURS,
    );
    let mut scratch = Vec::new();
    let mut hulls = Vec::new();
    for members in clusters.iter() {
        if members.len() > cloud.dims {
            scratch.clear();
            scratch.extend(members.iter().map(|&i| cloud.points[i as usize]));
            hulls.extend(B::hull(&scratch));
        }
    }
    (B::union_measure(&hulls), clusters.len())
}
