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

/// The 4 × 4 box room of `box.ron`'s kind with `n` short random blockers inside: a scene whose
/// edge count grows while the parameterization stays the same.
pub fn box_with_blockers(n: usize, seed: u64) -> Scene {
    use flatland_geom::{DVec2, Edge};
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let corners = [
        DVec2::new(0.0, 0.0),
        DVec2::new(4.0, 0.0),
        DVec2::new(4.0, 4.0),
        DVec2::new(0.0, 4.0),
    ];
    let mut edges: Vec<Edge> = (0..4)
        .map(|i| Edge::surface(corners[i], corners[(i + 1) % 4], 0.5))
        .collect();
    edges[2].emission = 1.0;
    // Blockers get shorter as they get more numerous, so about the same share of rays is hit.
    let size = 2.0 / (n as f64).sqrt();
    for _ in 0..n {
        let a = DVec2::new(rng.random_range(0.2..3.8), rng.random_range(0.2..3.8));
        let angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
        edges.push(Edge::blocker(
            a,
            a + DVec2::new(angle.cos(), angle.sin()) * size,
        ));
    }
    Scene::new(edges).expect("valid scene")
}
