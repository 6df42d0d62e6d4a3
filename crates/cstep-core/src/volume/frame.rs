//! Principal-axes frame of a point cloud ("whitening") and the flatness rule.
//!
//! Convex-hull code is numerically fragile on clouds that are thin along one direction or that
//! sit far from the origin: parry's quickhull works with absolute tolerances, so a 1 m × 1 m ×
//! 1 µm slab — or the same slab rotated — comes out with a wrong volume. Mapping the cloud onto
//! its principal axes (eigenvectors of its covariance), each scaled to unit extent, makes every
//! hull input well conditioned. Volumes and hull vertex counts are affine invariant up to the
//! map's determinant, so hulls are built in the unit frame and volumes scaled back.

use nalgebra::{Matrix2, Matrix3};

/// A cloud whose thinnest principal extent is at most this share of its widest is flat: it
/// spans no volume in the measured dimension and its hull volume is 0.
///
/// Why 1e-9: coordinates carry a relative rounding error of ~1e-16 and the principal axes of a
/// well-spread cloud are accurate to about the same share, so a thickness of 1e-9 of the width is
/// still resolved to ~1e-7 relative accuracy, while no reachable set of a robot is a billion
/// times wider than it is deep. A 1 × 1 × 1e-6 slab keeps its true volume; a 1 × 1 × 1e-12 one
/// counts as flat.
pub(crate) const FLAT_RATIO: f64 = 1e-9;

/// An affine map from world coordinates onto a cloud's principal axes, centred on the cloud's
/// bounding box in that frame and scaled so the cloud spans `[-1/2, 1/2]` along every axis.
#[derive(Debug, Clone)]
pub(crate) struct Frame {
    dims: usize,
    mean: [f64; 3],
    /// Unit principal axes; only the first `dims` entries (and components) are used.
    axes: [[f64; 3]; 3],
    /// Centre of the cloud along each axis, relative to `mean`.
    centre: [f64; 3],
    /// Width of the cloud along each axis.
    extent: [f64; 3],
}

impl Frame {
    /// Fits the frame to the first `dims` (2 or 3) coordinates of `points`. `None` when the
    /// cloud spans no volume: fewer than `dims + 1` points, all points equal, collinear (2D) or
    /// coplanar (3D) within [`FLAT_RATIO`], or coordinates so large that their spread overflows.
    pub(crate) fn fit(points: &[[f64; 3]], dims: usize) -> Option<Frame> {
        if points.len() < dims + 1 {
            return None;
        }
        // Sums over all three axes, the ones past `dims` taken as 0: with a fixed count the
        // sums stay in registers, where loops to `dims` kept them in memory as a store-to-load
        // chain through every point.
        let used = |p: &[f64; 3]| [p[0], p[1], if dims == 3 { p[2] } else { 0.0 }];
        let inv_n = 1.0 / points.len() as f64;
        let mut mean = [0.0; 3];
        for p in points {
            let q = used(p);
            for a in 0..3 {
                mean[a] += q[a];
            }
        }
        mean.iter_mut().for_each(|m| *m *= inv_n);
        let mut cov = [[0.0; 3]; 3];
        for p in points {
            let q = used(p);
            let d = [q[0] - mean[0], q[1] - mean[1], q[2] - mean[2]];
            for r in 0..3 {
                for c in r..3 {
                    cov[r][c] += d[r] * d[c];
                }
            }
        }
        if !cov.iter().flatten().all(|v| v.is_finite()) {
            return None;
        }
        Self::with_axes(points, dims, mean, principal_axes(&cov, dims))
    }

    /// The same cloud in a frame aligned with the coordinate axes (only translated and scaled):
    /// the fallback for the rare clouds on which quickhull fails in the rotated principal frame
    /// (many coplanar points, see [`super::hull::Polyhedron::hull`]).
    pub(crate) fn axis_aligned(&self, points: &[[f64; 3]]) -> Option<Frame> {
        let mut axes = [[0.0; 3]; 3];
        for (a, axis) in axes.iter_mut().enumerate() {
            axis[a] = 1.0;
        }
        Self::with_axes(points, self.dims, self.mean, axes)
    }

    /// Completes a frame from its origin and unit axes: the cloud's extent along each axis,
    /// and the flatness rule.
    fn with_axes(
        points: &[[f64; 3]],
        dims: usize,
        mean: [f64; 3],
        axes: [[f64; 3]; 3],
    ) -> Option<Frame> {
        // Over all three axes, for the reason given in `fit`; those past `dims` are unused.
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            let d = [p[0] - mean[0], p[1] - mean[1], p[2] - mean[2]];
            for a in 0..3 {
                let u = dot(&axes[a], &d);
                lo[a] = lo[a].min(u);
                hi[a] = hi[a].max(u);
            }
        }
        let mut centre = [0.0; 3];
        let mut extent = [1.0; 3];
        for a in 0..dims {
            centre[a] = 0.5 * (lo[a] + hi[a]);
            extent[a] = hi[a] - lo[a];
        }
        let widest = extent[..dims].iter().fold(0.0_f64, |m, &e| m.max(e));
        let thinnest = extent[..dims].iter().fold(f64::INFINITY, |m, &e| m.min(e));
        if !(widest.is_finite() && widest > 0.0 && thinnest > FLAT_RATIO * widest) {
            return None;
        }
        Some(Frame {
            dims,
            mean,
            axes,
            centre,
            extent,
        })
    }

    /// World point → unit-frame coordinates (components past `dims` are 0).
    pub(crate) fn to_unit(&self, p: &[f64; 3]) -> [f64; 3] {
        let d = [
            p[0] - self.mean[0],
            p[1] - self.mean[1],
            p[2] - self.mean[2],
        ];
        let mut u = [0.0; 3];
        for (a, ua) in u.iter_mut().enumerate().take(self.dims) {
            *ua = (dot(&self.axes[a], &d) - self.centre[a]) / self.extent[a];
        }
        u
    }

    /// Unit-frame coordinates → world point (inverse of [`Frame::to_unit`]).
    pub(crate) fn to_world(&self, u: &[f64; 3]) -> [f64; 3] {
        let mut p = self.mean;
        for (a, axis) in self.axes.iter().enumerate().take(self.dims) {
            let s = u[a] * self.extent[a] + self.centre[a];
            for (pc, axis_c) in p.iter_mut().zip(axis) {
                *pc += s * axis_c;
            }
        }
        p
    }

    /// Volume of one unit-frame unit in world units: world volume = unit volume × `det()`.
    pub(crate) fn det(&self) -> f64 {
        self.extent[..self.dims].iter().product()
    }
}

/// Unit eigenvectors of the symmetric `dims × dims` matrix stored in the upper triangle of `cov`.
fn principal_axes(cov: &[[f64; 3]; 3], dims: usize) -> [[f64; 3]; 3] {
    let mut axes = [[0.0; 3]; 3];
    if dims == 2 {
        let m = Matrix2::new(cov[0][0], cov[0][1], cov[0][1], cov[1][1]);
        let v = m.symmetric_eigen().eigenvectors;
        for (a, axis) in axes.iter_mut().enumerate().take(2) {
            *axis = [v[(0, a)], v[(1, a)], 0.0];
        }
    } else {
        let m = Matrix3::new(
            cov[0][0], cov[0][1], cov[0][2], cov[0][1], cov[1][1], cov[1][2], cov[0][2], cov[1][2],
            cov[2][2],
        );
        let v = m.symmetric_eigen().eigenvectors;
        for (a, axis) in axes.iter_mut().enumerate() {
            *axis = [v[(0, a)], v[(1, a)], v[(2, a)]];
        }
    }
    axes
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_determinant() {
        let pts = [
            [10.0, 5.0, 1.0],
            [12.0, 5.5, 1.0],
            [11.0, 7.0, 2.0],
            [10.5, 6.0, 3.0],
            [11.5, 6.5, 1.5],
        ];
        let f = Frame::fit(&pts, 3).expect("non-flat");
        for p in &pts {
            let u = f.to_unit(p);
            assert!(u.iter().all(|c| c.abs() <= 0.5 + 1e-12));
            let q = f.to_world(&u);
            for a in 0..3 {
                assert!((p[a] - q[a]).abs() < 1e-12);
            }
        }
        assert!(f.det() > 0.0);
    }

    #[test]
    fn flat_clouds_have_no_frame() {
        let line = [
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [2.0, 2.0, 0.0],
            [3.0, 3.0, 0.0],
        ];
        assert!(Frame::fit(&line, 2).is_none());
        let same = [[1.0, 2.0, 3.0]; 5];
        assert!(Frame::fit(&same, 3).is_none());
        let plane = [
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
            [1.0, 1.0, 1.0],
        ];
        assert!(Frame::fit(&plane, 3).is_none());
        assert!(Frame::fit(&plane[..2], 2).is_none());
        let huge = [[1e300, 0.0, 0.0], [-1e300, 1.0, 0.0], [0.0, -1e300, 0.0]];
        assert!(Frame::fit(&huge, 2).is_none());
    }
}
