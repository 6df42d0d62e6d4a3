//! Structure-of-arrays storage for a batch of trajectories.

/// A batch of `lanes` vectors of `components` numbers each, stored component-major
/// (`data[c * lanes + i]` is component `c` of lane `i`).
///
/// Every per-step loop in the rollout runs over lanes for one component at a time, so the
/// compiler can vectorise it; `f32` doubles the SIMD width over `f64` and is ample for positions
/// within tens of metres of the robot integrated over a few hundred steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Batch {
    lanes: usize,
    components: usize,
    data: Vec<f32>,
}

impl Batch {
    /// A zero-filled batch.
    pub fn zeros(components: usize, lanes: usize) -> Self {
        Self {
            lanes,
            components,
            data: vec![0.0; components * lanes],
        }
    }

    /// Number of lanes (trajectories).
    pub fn lanes(&self) -> usize {
        self.lanes
    }

    /// Number of components per lane.
    pub fn components(&self) -> usize {
        self.components
    }

    /// All lanes of component `c`.
    pub fn component(&self, c: usize) -> &[f32] {
        &self.data[c * self.lanes..(c + 1) * self.lanes]
    }

    /// All lanes of component `c`, mutably.
    pub fn component_mut(&mut self, c: usize) -> &mut [f32] {
        &mut self.data[c * self.lanes..(c + 1) * self.lanes]
    }

    /// Every component as its own mutable slice, for loops that write several at once.
    pub fn components_mut(&mut self) -> Vec<&mut [f32]> {
        self.data.chunks_exact_mut(self.lanes.max(1)).collect()
    }

    /// Every component as its own slice.
    pub fn components_ref(&self) -> Vec<&[f32]> {
        self.data.chunks_exact(self.lanes.max(1)).collect()
    }

    /// Sets component `c` of every lane to `value`.
    pub fn fill_component(&mut self, c: usize, value: f32) {
        self.component_mut(c).fill(value);
    }

    /// The whole buffer, component-major.
    pub fn as_slice(&self) -> &[f32] {
        &self.data
    }

    /// The whole buffer, component-major, mutably.
    pub fn as_mut_slice(&mut self) -> &mut [f32] {
        &mut self.data
    }
}
