//! A robot's footprint as a row of equal disks along its body x axis, checked against the scan
//! one disk centre at a time.
//!
//! Why disks and not the polygon: the free-space test ([`crate::occupancy`]) is built once per
//! scan for one disk radius, after which a check is one table lookup per point — cheap enough
//! for every step of every rollout. A polygon would need a test against every return at every
//! step. One disk around a long robot wastes its width: the Husky's circumscribed disk has a
//! radius of 0.61 m against a half-width of 0.34 m, so a 1.2 m corridor it drives through
//! would read as a collision. A row of `k` disks covering the outline (each covers a
//! `L/k × W` cell, `k = ⌈L/W⌉`) follows the heading and stays within 0.08 m of the Husky's
//! sides (two disks of 0.425 m), for `k` lookups per point. It never lets through what the
//! polygon would stop: every point of the outline lies in a disk.

use super::wheeled::Outline;

/// Disks of one radius whose union covers a rectangle, centres in the body frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Footprint {
    radius: f64,
    centres: Vec<[f32; 2]>,
}

impl Footprint {
    /// The row of `⌈L/W⌉` disks (`L` × `W` the outline's length and width) spaced evenly along
    /// the outline's length, centred on its width, each just covering its cell.
    pub fn covering(outline: &Outline) -> Self {
        let length = outline.x[1] - outline.x[0];
        let width = outline.y[1] - outline.y[0];
        let disks = (length / width).ceil().max(1.0);
        let cell = length / disks;
        let y = 0.5 * (outline.y[0] + outline.y[1]);
        Self {
            radius: (0.5 * cell).hypot(0.5 * width),
            centres: (0..disks as usize)
                .map(|k| [(outline.x[0] + (k as f64 + 0.5) * cell) as f32, y as f32])
                .collect(),
        }
    }

    /// The disks' radius, m.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The disks' centres in the body frame (x forward, y left), m.
    pub fn centres(&self) -> &[[f32; 2]] {
        &self.centres
    }

    /// Writes the world-aligned position of disk `k`'s centre for every lane into `out_x` and
    /// `out_y`, for robots at `x`, `y` with heading cosine `cos` and sine `sin`.
    pub fn place(
        &self,
        k: usize,
        [x, y, cos, sin]: [&[f32]; 4],
        out_x: &mut [f32],
        out_y: &mut [f32],
    ) {
        let [dx, dy] = self.centres[k];
        for i in 0..out_x.len().min(out_y.len()) {
            out_x[i] = x[i] + dx * cos[i] - dy * sin[i];
            out_y[i] = y[i] + dx * sin[i] + dy * cos[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disks_cover_every_point_of_the_outline() {
        let outline = Outline {
            x: [-0.5, 0.7],
            y: [-0.3, 0.2],
            z: [0.0, 0.3],
        };
        let footprint = Footprint::covering(&outline);
        assert_eq!(footprint.centres().len(), 3);
        let r = footprint.radius() + 1e-6;
        for i in 0..=60 {
            for j in 0..=25 {
                let (x, y) = (-0.5 + 1.2 * i as f64 / 60.0, -0.3 + 0.5 * j as f64 / 25.0);
                let covered = footprint
                    .centres()
                    .iter()
                    .any(|c| (x - c[0] as f64).hypot(y - c[1] as f64) <= r);
                assert!(covered, "({x}, {y})");
            }
        }
    }

    #[test]
    fn placing_turns_the_centres_with_the_heading() {
        let footprint = Footprint::covering(&Outline {
            x: [-1.0, 1.0],
            y: [-0.5, 0.5],
            z: [0.0, 0.1],
        });
        assert_eq!(footprint.centres(), &[[-0.5, 0.0], [0.5, 0.0]]);
        let (mut px, mut py) = ([0.0f32; 1], [0.0f32; 1]);
        // Facing +y from (1, 2): the front disk sits at (1, 2.5).
        footprint.place(1, [&[1.0], &[2.0], &[0.0], &[1.0]], &mut px, &mut py);
        assert_eq!((px[0], py[0]), (1.0, 2.5));
    }
}
