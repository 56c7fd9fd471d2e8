//! Shared bench helpers: bundled scenes and one seeded generator of `(s, t)` samples.

use flatland_geom::Scene;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The bundled scene `scenes/NAME.ron`.
pub fn scene(name: &str) -> Scene {
    Scene::load(format!("{}/scenes/{name}.ron", env!("CARGO_MANIFEST_DIR"))).expect("bundled scene")
}

/// `n` uniformly random `(s, t)` in `[0, 1)²`, the same on every run.
pub fn samples(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| [rng.random_range(0.0..1.0), rng.random_range(0.0..1.0)])
        .collect()
}
