//! Planar endpoints bucketed into vertical strips, and a band of neighbouring strips that
//! stays sorted along y as it slides across them.
//!
//! The 2D free-fraction estimator walks its columns left to right and, at each, needs the
//! endpoints near the column sorted along it. Gathering them afresh from a grid and sorting
//! them cost most of its time, although one column's near points are mostly the last one's.
//! Here each strip is one column wide and sorted along y once; moving to the next column drops
//! the strip that fell out of reach and merges in the one that came within it, so every column
//! costs one linear pass over its band and nothing is sorted twice.

/// An endpoint in a [`Band`]: where it is, which strip holds it, and its label.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Member {
    /// Coordinate along the columns.
    pub(crate) y: f64,
    /// Coordinate across them.
    pub(crate) x: f64,
    /// The strip that holds it.
    strip: u32,
    /// Whether its trajectory stayed collision-free.
    pub(crate) free: bool,
}

/// Endpoints in `count` strips of equal width over `[lo, lo + count · width)` in x (points
/// outside go to the nearest end strip), each strip's run sorted by y.
#[derive(Debug)]
pub(crate) struct Strips {
    lo: f64,
    width: f64,
    /// Members in strip order, by y within a strip.
    members: Vec<Member>,
    /// `start[s]..start[s + 1]` are the members of strip `s`.
    start: Vec<usize>,
}

impl Strips {
    /// Buckets `points` (x, y; z is ignored) with their `terminal` labels, pairwise, into
    /// `count ≥ 1` strips of `width > 0` starting at `lo`.
    pub(crate) fn new(
        points: &[[f64; 3]],
        terminal: &[bool],
        lo: f64,
        width: f64,
        count: usize,
    ) -> Self {
        let mut strips = Strips {
            lo,
            width,
            members: vec![Member::default(); points.len().min(terminal.len())],
            start: vec![0; count.max(1) + 1],
        };
        // Counting sort by strip (the strip found twice rather than stored: no second buffer
        // the size of the cloud), then each strip's run by y.
        for p in points.iter().take(strips.members.len()) {
            let strip = strips.strip_of(p[0]);
            strips.start[strip + 1] += 1;
        }
        for s in 1..strips.start.len() {
            strips.start[s] += strips.start[s - 1];
        }
        let mut fill = strips.start.clone();
        for (p, &terminal) in points.iter().zip(terminal) {
            let strip = strips.strip_of(p[0]);
            strips.members[fill[strip]] = Member {
                y: p[1],
                x: p[0],
                strip: strip as u32,
                free: !terminal,
            };
            fill[strip] += 1;
        }
        for s in 0..strips.count() {
            let run = strips.start[s]..strips.start[s + 1];
            strips.members[run].sort_unstable_by(|a, b| a.y.total_cmp(&b.y));
        }
        strips
    }

    /// Number of strips.
    pub(crate) fn count(&self) -> usize {
        self.start.len() - 1
    }

    /// The strip that holds `x`, or the nearest end strip for `x` outside them (NaN → 0). The
    /// division may round `x` next to an edge into the neighbouring strip; the edges
    /// themselves decide, so that distances to them bound the distances to the strips' points.
    fn strip_of(&self, x: f64) -> usize {
        // `as` saturates (−∞ and NaN → 0, +∞ → usize::MAX).
        let s = (((x - self.lo) / self.width).floor() as usize).min(self.count() - 1);
        if s > 0 && x < self.edge(s) {
            s - 1
        } else if s + 1 < self.count() && x >= self.edge(s + 1) {
            s + 1
        } else {
            s
        }
    }

    /// Left edge of strip `s` (`s = count` gives the right edge of the last).
    fn edge(&self, s: usize) -> f64 {
        self.lo + s as f64 * self.width
    }

    /// The members of strip `s`, sorted by y.
    fn run(&self, s: usize) -> &[Member] {
        &self.members[self.start[s]..self.start[s + 1]]
    }
}

/// The members of the strips `first..=last`, sorted by y: the endpoints near a column.
#[derive(Debug)]
pub(crate) struct Band<'a> {
    strips: &'a Strips,
    /// First and last strip held; `first > last` while the band is empty.
    first: usize,
    last: usize,
    members: Vec<Member>,
    scratch: Vec<Member>,
}

impl<'a> Band<'a> {
    /// An empty band over `strips`, its buffers sized for every endpoint once.
    pub(crate) fn new(strips: &'a Strips) -> Self {
        let n = strips.members.len();
        Band {
            strips,
            first: 1,
            last: 0,
            members: Vec::with_capacity(n),
            scratch: Vec::with_capacity(n),
        }
    }

    /// The members held, sorted by y.
    pub(crate) fn members(&self) -> &[Member] {
        &self.members
    }

    /// Makes the band hold every endpoint within `reach` (in x, up to rounding) of the line
    /// `x = at`, dropping strips on its left that lie wholly farther away than that; returns
    /// the distance from the line within which the band now holds every endpoint (∞ where it
    /// holds all of them). Lines are expected left to right: strips on the right are never
    /// dropped, so a band widened for one line still serves the next.
    pub(crate) fn cover(&mut self, at: f64, reach: f64) -> f64 {
        let strips = self.strips;
        let last_strip = strips.count() - 1;
        let want_first = strips.strip_of(at - reach);
        let want_last = strips.strip_of(at + reach);
        if self.first > self.last || self.last < want_first {
            // Empty, or every strip held is out of reach: start again from one strip.
            self.first = want_first;
            self.last = want_first;
            self.members.clear();
            self.members.extend_from_slice(strips.run(want_first));
        } else if want_first > self.first {
            let keep = want_first as u32;
            self.members.retain(|m| m.strip >= keep);
            self.first = want_first;
        }
        while self.first > want_first {
            self.first -= 1;
            self.merge(self.first);
        }
        while self.last < want_last {
            self.last += 1;
            self.merge(self.last);
        }
        // Every endpoint outside the band lies beyond the band's outer strip edges.
        let left = if self.first == 0 {
            f64::INFINITY
        } else {
            at - strips.edge(self.first)
        };
        let right = if self.last == last_strip {
            f64::INFINITY
        } else {
            strips.edge(self.last + 1) - at
        };
        left.min(right)
    }

    /// Merges strip `s`'s sorted run into the sorted members.
    fn merge(&mut self, s: usize) {
        let run = self.strips.run(s);
        if run.is_empty() {
            return;
        }
        let held = &self.members;
        self.scratch.clear();
        let (mut i, mut j) = (0, 0);
        while i < held.len() && j < run.len() {
            if run[j].y < held[i].y {
                self.scratch.push(run[j]);
                j += 1;
            } else {
                self.scratch.push(held[i]);
                i += 1;
            }
        }
        self.scratch.extend_from_slice(&held[i..]);
        self.scratch.extend_from_slice(&run[j..]);
        std::mem::swap(&mut self.members, &mut self.scratch);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::test_points::uniform_in_cube;

    #[test]
    fn a_sliding_band_holds_exactly_its_strips_sorted_along_y() {
        let points = uniform_in_cube(300, 2, 5);
        let terminal: Vec<bool> = points.iter().map(|p| p[1] > 0.2).collect();
        let strips = Strips::new(&points, &terminal, -1.0, 0.125, 16);
        let mut band = Band::new(&strips);
        for (c, reach) in [(0, 0.2), (1, 0.2), (2, 0.6), (3, 0.2), (9, 0.3), (15, 0.1)] {
            let at = -1.0 + (c as f64 + 0.5) * 0.125;
            let covered = band.cover(at, reach);
            assert!(covered >= reach, "line {c}: covers {covered} < {reach}");
            let held = band.members();
            assert!(held.windows(2).all(|w| w[0].y <= w[1].y), "line {c}");
            // Exactly the points of the strips in [first, last], each once, with its label.
            let mut got: Vec<(u64, u64, bool)> = held
                .iter()
                .map(|m| (m.x.to_bits(), m.y.to_bits(), m.free))
                .collect();
            let strip = |x: f64| (((x + 1.0) / 0.125).floor()).clamp(0.0, 15.0) as usize;
            let mut want: Vec<(u64, u64, bool)> = points
                .iter()
                .zip(&terminal)
                .filter(|(p, _)| (band.first..=band.last).contains(&strip(p[0])))
                .map(|(p, &t)| (p[0].to_bits(), p[1].to_bits(), !t))
                .collect();
            got.sort_unstable();
            want.sort_unstable();
            assert_eq!(got, want, "line {c}");
            // Everything left out lies farther than `covered` from the line.
            for p in &points {
                if !(band.first..=band.last).contains(&strip(p[0])) {
                    assert!((p[0] - at).abs() >= covered, "line {c}: {p:?}");
                }
            }
        }
    }
}
