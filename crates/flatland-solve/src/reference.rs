//! Error measures against references the learner never trained on.
//!
//! Relative L2 of ζ over the unit square (docs/ALGORITHM.md §5):
//! `sqrt(∫∫ (ζ̃ − ζ)² ds dt / ∫∫ ζ² ds dt)`, estimated two independent ways:
//! on the midpoint grid `s = (i + ½)/R, t = (j + ½)/R` (the convention of `flatland kernel`) and on
//! held-out uniform random `(s, t)` drawn from a seed stream that training never uses.

use flatland_geom::Kernel;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::Representation;

/// The errors of one approximation against a [`Reference`].
///
/// Relative L2 is the paper's measure. Where a light meets another surface at a corner, ζ ~ 1/r
/// and `∫∫ ζ²` diverges (slowly), so an L2 estimate depends on the few points nearest such
/// corners: the held-out one comes with a bootstrap interval. Relative L1 (`∫∫ |ζ̃ − ζ| / ∫∫ ζ`)
/// is finite everywhere: the share of the first-shot energy sent to the wrong place.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Errors {
    /// Relative L2 on the reference grid.
    pub grid: f64,
    /// Relative L2 on the held-out random samples.
    pub heldout: f64,
    /// Relative L1 on the reference grid.
    #[serde(default)]
    pub l1_grid: f64,
    /// Relative L1 on the held-out random samples.
    #[serde(default)]
    pub l1_heldout: f64,
    /// The 5th and 95th percentiles of the held-out relative L2 over bootstrap resamples of the
    /// held-out points ([`BOOTSTRAP_RESAMPLES`], seeded): how much it rests on a few points.
    #[serde(default)]
    pub heldout_spread: [f64; 2],
}

/// Bootstrap resamples behind [`Errors::heldout_spread`].
pub const BOOTSTRAP_RESAMPLES: usize = 200;

/// The exact ζ on a reference grid and on held-out random points: what errors are measured against.
#[derive(Clone, Debug)]
pub struct Reference {
    res: usize,
    grid: Vec<f64>,
    heldout_points: Vec<[f64; 2]>,
    heldout_values: Vec<f64>,
    /// Wall time [`Reference::new`] took, seconds.
    build_s: f64,
}

impl Reference {
    /// Evaluates ζ on a `res × res` grid and at `heldout` random points (seeded), in parallel.
    pub fn new(kernel: &Kernel, res: usize, heldout: usize, seed: u64) -> Reference {
        let started = std::time::Instant::now();
        let grid = kernel.grid(res, true);
        let mut rng = crate::seeds::heldout(seed);
        let heldout_points: Vec<[f64; 2]> = (0..heldout)
            .map(|_| [rng.random::<f64>(), rng.random::<f64>()])
            .collect();
        let heldout_values = kernel.zeta_batch(&heldout_points);
        Reference {
            res,
            grid,
            heldout_points,
            heldout_values,
            build_s: started.elapsed().as_secs_f64(),
        }
    }

    /// Wall time its construction took (the exact kernel on the grid and the held-out
    /// points), seconds.
    pub fn build_s(&self) -> f64 {
        self.build_s
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
    pub fn approximate_grid(&self, approx: &dyn Representation) -> Vec<f64> {
        let res = self.res;
        (0..res * res)
            .into_par_iter()
            .map(|k| {
                let (s, t) = grid_point(res, k);
                approx.zeta(s, t)
            })
            .collect()
    }

    /// Every error measure of `approx`.
    pub fn errors(&self, approx: &dyn Representation) -> Errors {
        let grid = self.approximate_grid(approx);
        let predicted: Vec<f64> = self
            .heldout_points
            .par_iter()
            .map(|&[s, t]| approx.zeta(s, t))
            .collect();
        Errors {
            grid: relative_l2(&grid, &self.grid),
            heldout: relative_l2(&predicted, &self.heldout_values),
            l1_grid: relative_l1(&grid, &self.grid),
            l1_heldout: relative_l1(&predicted, &self.heldout_values),
            heldout_spread: bootstrap_l2(&predicted, &self.heldout_values),
        }
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
    let scale = largest_finite(approx, exact);
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

/// The largest finite magnitude in `a` and `b` (0 if none): what the relative errors divide by
/// first, so squares neither overflow nor underflow.
pub(crate) fn largest_finite(a: &[f64], b: &[f64]) -> f64 {
    b.iter().chain(a).fold(
        0.0_f64,
        |m, v| if v.is_finite() { m.max(v.abs()) } else { m },
    )
}

/// `Σ |a − b| / Σ |b|`: the relative L1 error, scale-free; the absolute mean error when the
/// reference is identically zero (like [`relative_l2`]).
pub fn relative_l1(approx: &[f64], exact: &[f64]) -> f64 {
    assert_eq!(approx.len(), exact.len(), "relative_l1: length mismatch");
    let scale = largest_finite(approx, exact);
    if scale == 0.0 {
        return 0.0;
    }
    let (mut num, mut den) = (0.0_f64, 0.0_f64);
    for (a, e) in approx.iter().zip(exact) {
        num += ((a - e) / scale).abs();
        den += (e / scale).abs();
    }
    if den == 0.0 {
        return num / exact.len() as f64 * scale;
    }
    num / den
}

/// The 5th and 95th percentiles of [`relative_l2`] over [`BOOTSTRAP_RESAMPLES`] resamples (with
/// replacement, seeded) of the point pairs.
pub fn bootstrap_l2(approx: &[f64], exact: &[f64]) -> [f64; 2] {
    assert_eq!(approx.len(), exact.len(), "bootstrap_l2: length mismatch");
    let n = exact.len();
    if n == 0 {
        return [0.0; 2];
    }
    let scale = largest_finite(approx, exact);
    if scale == 0.0 {
        return [0.0; 2];
    }
    let mut rng = ChaCha8Rng::seed_from_u64(BOOTSTRAP_SEED);
    let mut values: Vec<f64> = (0..BOOTSTRAP_RESAMPLES)
        .map(|_| {
            let (mut num, mut den) = (0.0_f64, 0.0_f64);
            for _ in 0..n {
                let i = rng.random_range(0..n);
                let (a, e) = (approx[i] / scale, exact[i] / scale);
                num += (a - e) * (a - e);
                den += e * e;
            }
            if den > 0.0 {
                (num / den).sqrt()
            } else {
                (num / n as f64).sqrt() * scale
            }
        })
        .collect();
    values.sort_by(f64::total_cmp);
    let at = |q: f64| values[((values.len() - 1) as f64 * q).round() as usize];
    [at(0.05), at(0.95)]
}

/// Seed of the bootstrap resampling (fixed: the same errors give the same interval).
const BOOTSTRAP_SEED: u64 = 0xb007;

/// Grid cells of `grid` (R × R, row ↔ s) next to a jump of the function: some 4-neighbour
/// differs by more than `jump` (absolute), dilated by `radius` cells. These are the kernel's
/// discontinuities that matter — shadow and emission boundaries — at the scale of `jump`.
pub fn discontinuity_mask(grid: &[f64], res: usize, jump: f64, radius: usize) -> Vec<bool> {
    assert_eq!(
        grid.len(),
        res * res,
        "discontinuity_mask: grid is not res × res"
    );
    let mut edge = vec![false; res * res];
    for i in 0..res {
        for j in 0..res {
            let v = grid[i * res + j];
            let right = j + 1 < res && (grid[i * res + j + 1] - v).abs() > jump;
            let down = i + 1 < res && (grid[(i + 1) * res + j] - v).abs() > jump;
            if right {
                edge[i * res + j] = true;
                edge[i * res + j + 1] = true;
            }
            if down {
                edge[i * res + j] = true;
                edge[(i + 1) * res + j] = true;
            }
        }
    }
    let r = radius as isize;
    let mut mask = vec![false; res * res];
    for (k, _) in edge.iter().enumerate().filter(|(_, e)| **e) {
        let (i, j) = ((k / res) as isize, (k % res) as isize);
        for di in -r..=r {
            for dj in -r..=r {
                let (y, x) = (i + di, j + dj);
                if (0..res as isize).contains(&y) && (0..res as isize).contains(&x) {
                    mask[y as usize * res + x as usize] = true;
                }
            }
        }
    }
    mask
}

/// Points per unit area inside `mask` divided by points per unit area outside it (paper R1:
/// cells concentrate near discontinuities). `None` when either region is empty.
pub fn density_ratio(mask: &[bool], res: usize, points: &[[f64; 2]]) -> Option<f64> {
    let inside_area = mask.iter().filter(|m| **m).count() as f64;
    let outside_area = mask.len() as f64 - inside_area;
    if inside_area == 0.0 || outside_area == 0.0 || points.is_empty() {
        return None;
    }
    let cell = |v: f64| ((v * res as f64) as usize).min(res - 1);
    let inside = points
        .iter()
        .filter(|[s, t]| mask[cell(*s) * res + cell(*t)])
        .count() as f64;
    let outside = points.len() as f64 - inside;
    (outside > 0.0).then(|| (inside / inside_area) / (outside / outside_area))
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn relative_l2_is_scale_free_and_finite() {
        let exact = [1.0, 2.0, 3.0];
        let approx = [1.1, 1.9, 3.0];
        let e = relative_l2(&approx, &exact);
        let scaled: Vec<f64> = approx.iter().map(|v| v * 1e300).collect();
        let exact_scaled: Vec<f64> = exact.iter().map(|v| v * 1e300).collect();
        assert_close!(relative_l2(&scaled, &exact_scaled), e, 1e-12);
        let tiny: Vec<f64> = approx.iter().map(|v| v * 1e-300).collect();
        let exact_tiny: Vec<f64> = exact.iter().map(|v| v * 1e-300).collect();
        assert_close!(relative_l2(&tiny, &exact_tiny), e, 1e-9);
        assert_eq!(relative_l2(&[0.0; 3], &[0.0; 3]), 0.0);
        assert_close!(relative_l2(&[0.0, 0.0], &[3.0, 4.0]), 1.0, 1e-15);
    }

    #[test]
    fn relative_l1_and_the_bootstrap_interval() {
        let exact = [1.0, 2.0, 3.0, 4.0];
        let approx = [1.5, 2.0, 2.0, 4.0];
        assert_close!(relative_l1(&approx, &exact), 1.5 / 10.0, 1e-15);
        let scaled: Vec<f64> = approx.iter().map(|v| v * 1e-300).collect();
        let exact_scaled: Vec<f64> = exact.iter().map(|v| v * 1e-300).collect();
        assert_close!(relative_l1(&scaled, &exact_scaled), 0.15, 1e-12);
        assert_eq!(relative_l1(&[0.0; 3], &[0.0; 3]), 0.0);
        // The interval brackets the estimate and is empty of spread for a perfect fit.
        let exact: Vec<f64> = (0..500).map(|i| 1.0 + (i % 7) as f64).collect();
        let approx: Vec<f64> = exact
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i % 50 == 0 { 3.0 } else { 0.0 })
            .collect();
        let [lo, hi] = bootstrap_l2(&approx, &exact);
        let e = relative_l2(&approx, &exact);
        assert!(lo < e && e < hi, "{lo} {e} {hi}");
        assert_eq!(bootstrap_l2(&exact, &exact), [0.0, 0.0]);
        assert_eq!(bootstrap_l2(&approx, &exact), [lo, hi], "seeded");
    }

    #[test]
    fn step_function_mask_and_density() {
        // A step at column 8 of a 16 × 16 grid: the mask is the two columns beside it, dilated.
        let res = 16;
        let grid: Vec<f64> = (0..res * res)
            .map(|k| if k % res < 8 { 0.0 } else { 1.0 })
            .collect();
        let mask = discontinuity_mask(&grid, res, 0.5, 1);
        for i in 0..res {
            for j in 0..res {
                assert_eq!(mask[i * res + j], (6..=9).contains(&j), "({i}, {j})");
            }
        }
        // Half the points in the 4-column band (a quarter of the area): density ratio 3.
        let points: Vec<[f64; 2]> = (0..40)
            .map(|k| {
                let t = if k % 2 == 0 { 7.5 / 16.0 } else { 1.5 / 16.0 };
                [(k as f64 + 0.5) / 40.0, t]
            })
            .collect();
        let ratio = density_ratio(&mask, res, &points).unwrap();
        assert_close!(ratio, 3.0, 1e-12);
    }
}
