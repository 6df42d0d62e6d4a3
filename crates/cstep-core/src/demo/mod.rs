//! The demo's simulated worlds, which benchmarks and tests score too: walls and a simulated
//! LiDAR that scans them ([`scene`]), the paper's arena with a scripted flight past its block
//! ([`arena`]), and a hall with pallets and a drive for a ground robot ([`aisle`]). Nothing in
//! the scoring pipeline uses them.

pub mod aisle;
pub mod arena;
pub mod scene;
