//! Error measures against references the learner never trained on.
//!
//! Relative L2 of ζ over the unit square (SPEC §5):
//! `sqrt(∫∫ (ζ̃ − ζ)² ds dt / ∫∫ ζ² ds dt)`, estimated two independent ways:
//! on the midpoint grid `s = (i + ½)/R, t = (j + ½)/R` (the convention of `flatland kernel`) and on
//! held-out uniform random `(s, t)` drawn from a seed stream that training never uses.

use flatland_geom::Kernel;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Anything that approximates the learning target ζ(s, t) over `[0, 1)²`: the SGCS network,
/// the hierarchical-radiosity and uniform baselines.
pub trait Approximation: Sync {
    /// The approximated ζ at `(s, t)`.
    fn zeta(&self, s: f64, t: f64) -> f64;
    /// Number of basis functions (cells, links, blocks) the representation holds.
    fn basis_functions(&self) -> usize;
    /// Bytes the representation needs in memory (its payload, not allocator slack).
    fn memory_bytes(&self) -> usize;
}

/// Relative L2 errors of one approximation, both estimates.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Errors {
    /// On the reference grid.
    pub grid: f64,
    /// On the held-out random samples.
    pub heldout: f64,
}

/// The exact ζ on a reference grid and on held-out random points: what errors are measured against.
#[derive(Clone, Debug)]
pub struct Reference {
    res: usize,
    grid: Vec<f64>,
    heldout_points: Vec<[f64; 2]>,
    heldout_values: Vec<f64>,
}

/// Seed-stream offset for held-out points, so they never coincide with a training stream.
const HELDOUT_STREAM: u64 = 0x9e37_79b9_7f4a_7c15;

impl Reference {
    /// Evaluates ζ on a `res × res` grid and at `heldout` random points (seeded), in parallel.
    pub fn new(kernel: &Kernel, res: usize, heldout: usize, seed: u64) -> Reference {
        let grid = kernel.grid(res, true);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ HELDOUT_STREAM);
        let heldout_points: Vec<[f64; 2]> = (0..heldout)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        let heldout_values = kernel.zeta_batch(&heldout_points);
        Reference { res, grid, heldout_points, heldout_values }
    }

    /// Grid resolution R.
    pub fn res(&self) -> usize {
        self.res
    }

    /// The exact ζ grid, row-major, row ↔ s.
    pub fn grid(&self) -> &[f64] {
        &self.grid
    }

    /// The held-out points and their exact ζ.
    pub fn heldout(&self) -> (&[[f64; 2]], &[f64]) {
        (&self.heldout_points, &self.heldout_values)
    }

    /// Evaluates an approximation on the reference grid (row-major, row ↔ s), in parallel.
    pub fn approximate_grid(&self, approx: &dyn Approximation) -> Vec<f64> {
        let res = self.res;
        (0..res * res)
            .into_par_iter()
            .map(|k| {
                let (s, t) = grid_point(res, k);
                approx.zeta(s, t)
            })
            .collect()
    }

    /// Both relative L2 errors of `approx`.
    pub fn errors(&self, approx: &dyn Approximation) -> Errors {
        let grid = relative_l2(&self.approximate_grid(approx), &self.grid);
        let predicted: Vec<f64> = self
            .heldout_points
            .par_iter()
            .map(|&[s, t]| approx.zeta(s, t))
            .collect();
        Errors { grid, heldout: relative_l2(&predicted, &self.heldout_values) }
    }
}

/// The `(s, t)` at flat index `k` of the midpoint grid of resolution `res`.
pub fn grid_point(res: usize, k: usize) -> (f64, f64) {
    let (i, j) = (k / res, k % res);
    ((i as f64 + 0.5) / res as f64, (j as f64 + 0.5) / res as f64)
}

/// `sqrt(Σ (a − b)² / Σ b²)`, with compensated-free but scale-safe accumulation.
///
/// Returns 0 when both are identically zero and +∞ never: an all-zero reference with a non-zero
/// approximation gives the absolute RMS instead, so a number is always finite and comparable.
pub fn relative_l2(approx: &[f64], exact: &[f64]) -> f64 {
    assert_eq!(approx.len(), exact.len(), "relative_l2: length mismatch");
    // Scale by the largest magnitude first so squares neither overflow nor underflow.
    let scale = exact
        .iter()
        .chain(approx)
        .fold(0.0_f64, |m, v| if v.is_finite() { m.max(v.abs()) } else { m });
    if scale == 0.0 {
        return 0.0;
    }
    let (mut num, mut den) = (0.0_f64, 0.0_f64);
    for (a, e) in approx.iter().zip(exact) {
        let d = (a - e) / scale;
        num += d * d;
        den += (e / scale) * (e / scale);
    }
    if den == 0.0 {
        return (num / exact.len() as f64).sqrt() * scale;
    }
    (num / den).sqrt()
}
