//! (stub: replaced by the volume branch)
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VolumeDims {
    Two,
    Three,
}
impl VolumeDims {
    pub fn count(self) -> usize {
        match self {
            VolumeDims::Two => 2,
            VolumeDims::Three => 3,
        }
    }
}
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EstimatorKind {
    Hull,
    Efron,
    FreeFraction,
}
impl EstimatorKind {
    pub const ALL: [EstimatorKind; 3] = [
        EstimatorKind::Hull,
        EstimatorKind::Efron,
        EstimatorKind::FreeFraction,
    ];
    pub fn name(self) -> &'static str {
        match self {
            EstimatorKind::Hull => "hull",
            EstimatorKind::Efron => "efron",
            EstimatorKind::FreeFraction => "free_fraction",
        }
    }
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == s)
    }
}
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Volumes {
    pub reachable: f64,
    pub terminal: f64,
    pub free: f64,
    pub hull_vertices: usize,
    pub terminal_clusters: usize,
}
pub fn estimate(
    _points: &[[f64; 3]],
    _terminal: &[bool],
    _dims: VolumeDims,
    _kind: EstimatorKind,
) -> Volumes {
    unimplemented!()
}
