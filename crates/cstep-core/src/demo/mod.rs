//! The demo's simulated world, which benchmarks and tests score too: walls and a simulated
//! LiDAR that scans them ([`scene`]), and the paper's arena with a scripted flight past its
//! block ([`arena`]). Nothing in the scoring pipeline uses it.

pub mod arena;
pub mod scene;
