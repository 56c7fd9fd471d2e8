//! The uniform baseline: ζ piecewise constant on a g × g grid of (s, t) blocks.
//!
//! Block `(i, j)` covers `s ∈ [i/g, (i+1)/g)`, `t ∈ [j/g, (j+1)/g)` and holds the mean ζ of
//! `m` uniformly random points inside it (one seeded stream, so a run is reproducible and the
//! batch evaluation stays deterministic). It knows nothing about the scene: blocks straddle edge
//! boundaries and shadow edges alike, which is what makes it the floor every adaptive method must
//! beat.

use crate::{BaselineError, BaselineRun, BudgetNote, budget_tolerance, seeds};
use flatland_geom::Kernel;
use flatland_solve::{
    KernelRectangle, Mesh, RectangleOperator, Representation, SolveError, SolveParams, Stop,
    TransferOperator, inverse_source_weights,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

/// Settings of the uniform grid.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UniformParams {
    /// Rays (random ζ evaluations) averaged per block, `m ≥ 1`. Default 20, the per-link count
    /// the paper uses for hierarchical radiosity. Unused by the exact block values.
    pub rays_per_block: usize,
    /// What each block holds (default: the mean of `rays_per_block` random rays of ζ).
    #[serde(default)]
    pub block_value: BlockValue,
}

impl Default for UniformParams {
    fn default() -> Self {
        UniformParams {
            rays_per_block: 20,
            block_value: BlockValue::Rays,
        }
    }
}

/// What a block of the uniform grid holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BlockValue {
    /// The mean of ζ at `rays_per_block` random points of the block (the baseline of the
    /// paper's comparison).
    #[default]
    Rays,
    /// The exact mean of ζ over the block: the best any g × g piecewise-constant ζ can do in
    /// L2. No rays (integrated with the closed-form transfer and exact visibility).
    ExactZetaMean,
    /// The exact mean of k over the block; ζ̃ = E'(sender edge) · mean k. The best g × g
    /// piecewise-constant *kernel*: unlike a block of ζ, one that straddles an emitter's edge
    /// does not mix E' = 1 rows with 1 % rows, so `ζ̃ / E'` stays a block mean of k. No rays.
    ExactKernelMean,
}

impl UniformParams {
    /// The one place these values are checked.
    pub fn check(&self) -> Result<(), BaselineError> {
        if self.rays_per_block == 0 {
            return Err(BaselineError::InvalidParameter {
                name: "rays_per_block",
                value: self.rays_per_block.to_string(),
                valid: "at least 1",
            });
        }
        Ok(())
    }
}

/// A g × g piecewise-constant approximation of ζ.
#[derive(Clone, Debug, PartialEq)]
pub struct UniformGrid {
    g: usize,
    /// Row-major, row ↔ s.
    values: Vec<f64>,
    rays: u64,
    block_value: BlockValue,
    /// For [`BlockValue::ExactKernelMean`]: (end of a surface edge's s-interval, its E'), in
    /// order, so ζ̃ = E'(s) · value; empty otherwise.
    sender_weights: Vec<(f64, f64)>,
}

impl UniformGrid {
    /// Builds the grid with `g` blocks per axis, `params.rays_per_block` rays per block.
    pub fn build(
        kernel: &Kernel,
        g: usize,
        params: &UniformParams,
        seed: u64,
    ) -> Result<UniformGrid, BaselineError> {
        params.check()?;
        if g == 0 {
            return Err(BaselineError::InvalidParameter {
                name: "grid",
                value: g.to_string(),
                valid: "at least 1",
            });
        }
        if params.block_value != BlockValue::Rays {
            return Ok(exact_grid(kernel, g, params.block_value));
        }
        let points = sample_points(g, params.rays_per_block, seed);
        let zeta = kernel.zeta_batch(&points);
        let m = params.rays_per_block;
        let values: Vec<f64> = zeta
            .chunks_exact(m)
            .map(|c| c.iter().sum::<f64>() / m as f64)
            .collect();
        let rays = points
            .iter()
            .filter(|&&[s, t]| kernel.casts_ray(s, t))
            .count() as u64;
        Ok(UniformGrid {
            g,
            values,
            rays,
            block_value: BlockValue::Rays,
            sender_weights: Vec::new(),
        })
    }

    /// What the blocks hold.
    pub fn block_value(&self) -> BlockValue {
        self.block_value
    }

    /// Blocks per axis.
    pub fn g(&self) -> usize {
        self.g
    }

    /// The block values, row-major (row ↔ s).
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Rays spent building the grid: of its g² · m kernel evaluations, those whose visibility
    /// geometry could not decide ([`Kernel::casts_ray`]).
    pub fn rays(&self) -> u64 {
        self.rays
    }

    fn block(&self, x: f64) -> usize {
        // `as usize` saturates negatives and NaN to 0; the min clamps s = 1.
        ((x * self.g as f64) as usize).min(self.g - 1)
    }
}

/// A grid of exact block means (no rays).
fn exact_grid(kernel: &Kernel, g: usize, block_value: BlockValue) -> UniformGrid {
    let weighted = block_value == BlockValue::ExactZetaMean;
    let values = flatland_solve::exact_block_means(kernel, g, weighted, &flatland_solve::never)
        .expect("never interrupted; the scene's own mesh");
    let scene = kernel.scene();
    let sender_weights = if weighted {
        Vec::new()
    } else {
        scene
            .surface_edges()
            .iter()
            .filter_map(|&e| Some((scene.edge_param_range(e)?.1, kernel.source_weight(e))))
            .collect()
    };
    UniformGrid {
        g,
        values,
        rays: 0,
        block_value,
        sender_weights,
    }
}

/// The `m` sample points of every block, block by block in row-major order: the ray plan of
/// [`UniformGrid::build`], exposed to tests so they can recompute the block means independently.
fn sample_points(g: usize, m: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seeds::item(seed, 0x756e_6966));
    let inv = 1.0 / g as f64;
    let mut points = Vec::with_capacity(g * g * m);
    for i in 0..g {
        for j in 0..g {
            for _ in 0..m {
                let s = (i as f64 + rng.random::<f64>()) * inv;
                let t = (j as f64 + rng.random::<f64>()) * inv;
                points.push([s.min(next_below(1.0)), t.min(next_below(1.0))]);
            }
        }
    }
    points
}

/// The largest f64 below `x > 0` (keeps rounded samples inside `[0, 1)`).
fn next_below(x: f64) -> f64 {
    f64::from_bits(x.to_bits() - 1)
}

/// The uniform grid: ζ̃ by block lookup; for a solve, each block is a rectangle. Blocks of ζ are
/// split where they straddle a sender edge (each part divided by its own E'); blocks of k
/// ([`BlockValue::ExactKernelMean`]) are used as they are.
impl Representation for UniformGrid {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        let value = self.values[self.block(s) * self.g + self.block(t)];
        if self.sender_weights.is_empty() {
            return value;
        }
        let k = self
            .sender_weights
            .partition_point(|&(end, _)| end <= s)
            .min(self.sender_weights.len() - 1);
        value * self.sender_weights[k].1
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(self.values.len())
    }

    /// The block values, and the sender weights of a grid of k.
    fn memory_bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<f64>()
            + self.sender_weights.len() * std::mem::size_of::<(f64, f64)>()
    }

    fn operator(
        &self,
        mesh: &Mesh,
        _: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        let g = self.g();
        let of_k = self.block_value() == BlockValue::ExactKernelMean;
        let inverse = if of_k {
            vec![1.0; mesh.edges().len()]
        } else {
            inverse_source_weights(mesh)?
        };
        if stop() {
            return Err(SolveError::Interrupted);
        }
        let mut rectangles = Vec::with_capacity(g * g * 2);
        for i in 0..g {
            let s = [i as f64 / g as f64, (i + 1) as f64 / g as f64];
            for (k, edge) in mesh.edges().iter().enumerate() {
                let part = [s[0].max(edge.s[0]), s[1].min(edge.s[1])];
                if part[1] <= part[0] {
                    continue;
                }
                for j in 0..g {
                    rectangles.push(KernelRectangle {
                        s: part,
                        t: [j as f64 / g as f64, (j + 1) as f64 / g as f64],
                        k: self.values()[i * g + j] * inverse[k],
                    });
                }
            }
        }
        Ok(Box::new(RectangleOperator::new(mesh, rectangles)))
    }
}

/// The uniform baseline at a budget of basis functions: `g = round(√budget)` (at least 1), so the
/// count is the nearest square, reported in the run; [`BaselineRun::note`] says so when that is
/// outside [`budget_tolerance`] of the budget (small budgets between squares, such as 7 → 9).
pub fn run_uniform(
    kernel: &Kernel,
    budget: usize,
    seed: u64,
    params: &UniformParams,
) -> Result<BaselineRun<UniformGrid>, BaselineError> {
    if budget == 0 {
        return Err(BaselineError::InvalidParameter {
            name: "budget",
            value: budget.to_string(),
            valid: "at least 1 basis function",
        });
    }
    let g = ((budget as f64).sqrt().round() as usize).max(1);
    let start = Instant::now();
    let grid = UniformGrid::build(kernel, g, params, seed)?;
    let wall = start.elapsed();
    let rays = grid.rays;
    let built = g * g;
    let note = (built.abs_diff(budget) > budget_tolerance(budget)).then_some(BudgetNote::Square {
        asked: budget,
        built,
    });
    Ok(BaselineRun::new(grid, rays, wall, note))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{blocker_kernel, box_kernel};
    use flatland_geom::EdgeId;
    use flatland_solve::{Reference, grid_point};

    #[test]
    fn error_falls_with_g() {
        let kernel = blocker_kernel();
        let reference = Reference::new(&kernel, 96, 4000, 3);
        let params = UniformParams {
            rays_per_block: 16,
            ..UniformParams::default()
        };
        let errors: Vec<f64> = [4, 8, 16, 32]
            .iter()
            .map(|&g| {
                reference
                    .errors(&UniformGrid::build(&kernel, g, &params, 11).unwrap())
                    .grid
            })
            .collect();
        for w in errors.windows(2) {
            assert!(w[1] < w[0], "uniform error must fall with g: {errors:?}");
        }
    }

    #[test]
    fn values_and_errors_match_an_independent_recomputation() {
        let kernel = blocker_kernel();
        let params = UniformParams {
            rays_per_block: 5,
            ..UniformParams::default()
        };
        let (g, seed) = (7, 42);
        let grid = UniformGrid::build(&kernel, g, &params, seed).unwrap();

        // Block means from single evaluations, not the batch API.
        let points = sample_points(g, params.rays_per_block, seed);
        for (b, chunk) in points.chunks_exact(params.rays_per_block).enumerate() {
            let (i, j) = (b / g, b % g);
            for &[s, t] in chunk {
                assert!((i as f64 / g as f64..(i + 1) as f64 / g as f64).contains(&s));
                assert!((j as f64 / g as f64..(j + 1) as f64 / g as f64).contains(&t));
            }
            let mean =
                chunk.iter().map(|&[s, t]| kernel.zeta(s, t)).sum::<f64>() / chunk.len() as f64;
            let stored = grid.values()[b];
            assert!(
                (mean - stored).abs() <= 1e-12 * mean.abs().max(1.0),
                "block {b}: {mean} vs {stored}"
            );
        }

        // The reported error from the saved values, by hand.
        let res = 64;
        let reference = Reference::new(&kernel, res, 500, 9);
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..res * res {
            let (s, t) = grid_point(res, k);
            let exact = kernel.zeta(s, t);
            let (i, j) = ((s * g as f64) as usize, (t * g as f64) as usize);
            let approx = grid.values()[i * g + j];
            num += (approx - exact) * (approx - exact);
            den += exact * exact;
        }
        let by_hand = (num / den).sqrt();
        let reported = reference.errors(&grid).grid;
        assert!(
            (by_hand - reported).abs() < 1e-9,
            "by hand {by_hand} vs reported {reported}"
        );
    }

    #[test]
    fn rays_and_counts_are_reported() {
        // In a closed box without occluders geometry decides every visibility: no ray at all.
        let three = UniformParams {
            rays_per_block: 3,
            ..UniformParams::default()
        };
        let run = run_uniform(&box_kernel(), 400, 1, &three).unwrap();
        assert_eq!(run.basis_functions, 400);
        assert_eq!(run.rays, 0);
        assert_eq!(run.memory_bytes, 400 * 8);
        // With a blocker, the evaluations on the pairs it shadows cost one ray each.
        let kernel = blocker_kernel();
        let run = run_uniform(&kernel, 400, 1, &three).unwrap();
        let points = sample_points(20, 3, 1);
        let expected = points
            .iter()
            .filter(|&&[s, t]| kernel.casts_ray(s, t))
            .count();
        assert!(expected > 0 && expected < 400 * 3);
        assert_eq!(run.rays, expected as u64);
        // 50 is not a square: the nearest one (49) is used and reported, within tolerance.
        let run = run_uniform(&kernel, 50, 1, &UniformParams::default()).unwrap();
        assert_eq!(run.basis_functions, 49);
        assert_eq!(run.note, None);
        // 7 is 2 from the nearest square, past the tolerance of 1: the note says so.
        let run = run_uniform(&kernel, 7, 1, &UniformParams::default()).unwrap();
        assert_eq!(run.basis_functions, 9);
        let note = run.note.expect("a note for 9 blocks instead of 7");
        assert_eq!(
            note.to_string(),
            "the uniform grid is g × g blocks: built 9 (3 × 3) instead of 7"
        );
        assert!(
            run.approx
                .values()
                .iter()
                .all(|v| v.is_finite() && *v >= 0.0)
        );
    }

    #[test]
    fn same_seed_same_grid_and_bad_params_rejected() {
        let kernel = box_kernel();
        let p = UniformParams::default();
        assert_eq!(
            UniformGrid::build(&kernel, 5, &p, 3).unwrap(),
            UniformGrid::build(&kernel, 5, &p, 3).unwrap()
        );
        let err = UniformGrid::build(
            &kernel,
            5,
            &UniformParams {
                rays_per_block: 0,
                ..UniformParams::default()
            },
            3,
        )
        .unwrap_err();
        assert!(err.to_string().contains("rays_per_block"), "{err}");
        assert!(run_uniform(&kernel, 0, 1, &p).is_err());
    }

    #[test]
    fn exact_block_values_cast_no_rays_and_beat_random_ones() {
        let kernel = blocker_kernel();
        let reference = Reference::new(&kernel, 96, 2000, 3);
        let of = |block_value| {
            let params = UniformParams {
                block_value,
                ..UniformParams::default()
            };
            UniformGrid::build(&kernel, 8, &params, 11).unwrap()
        };
        let (rays, zeta, k) = (
            of(BlockValue::Rays),
            of(BlockValue::ExactZetaMean),
            of(BlockValue::ExactKernelMean),
        );
        assert_eq!((zeta.rays(), k.rays()), (0, 0));
        // The exact block means are the L2 projection of ζ: no 8 × 8 grid of ζ does better.
        let (e_rays, e_zeta) = (reference.errors(&rays).grid, reference.errors(&zeta).grid);
        assert!(e_zeta < e_rays, "exact {e_zeta} vs rays {e_rays}");
        // Means of k times E' of the sender edge: ζ̃ = E'·mean k, so where a block holds a
        // single sender edge it is that edge's E' times the block's mean k.
        assert_eq!(k.block_value(), BlockValue::ExactKernelMean);
        let (s, t) = (0.1, 0.6); // the emitting floor is s ∈ [0, 0.25)
        let block = (s * 8.0) as usize * 8 + (t * 8.0) as usize;
        assert_eq!(
            k.zeta(s, t),
            k.values()[block] * kernel.source_weight(EdgeId::new(0))
        );
        assert_eq!(
            k.zeta(0.4, t),
            k.values()[3 * 8 + 4] * kernel.source_weight(EdgeId::new(1))
        );
    }
}
