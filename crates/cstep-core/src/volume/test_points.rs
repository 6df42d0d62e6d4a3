//! Seeded random point clouds shared by the volume module's unit tests.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `n` points uniform in `[-1, 1]^dims` (unused coordinates 0), reproducible from `seed`.
pub(crate) fn uniform_in_cube(n: usize, dims: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            std::array::from_fn(|a| {
                if a < dims {
                    rng.random_range(-1.0..1.0)
                } else {
                    0.0
                }
            })
        })
        .collect()
}
