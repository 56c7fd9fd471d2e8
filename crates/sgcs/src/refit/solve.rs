//! The ridge solve of an assembled system: one numeric sparse Cholesky factorisation.
//!
//! `ΦᵀΦ + μ I` is symmetric positive definite; it is factorised by faer's sparse Cholesky
//! (`LLᵀ`, approximate-minimum-degree ordering, supernodal where the factor is dense enough):
//! exact to rounding, where conjugate gradients needed thousands of iterations on these badly
//! conditioned systems (overlapping Gaussians), and `ΦᵀΦ`'s nonzero pattern keeps the factor
//! small (the cells live on a low-dimensional surface). The ordering and symbolic
//! factorisation are computed once per system; each ridge costs one numeric factorisation.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::{RefitPart, RefitSystem, check_ridge};
use crate::SgcsError;

impl RefitSystem {
    /// The ridge solution on the samples of `part`: the weights `v` (cell-major) minimising
    /// `|Φ v − z|² + μ |v|²`, `μ = ridge · mean(diag ΦᵀΦ)`, and the largest relative residual
    /// of the system solved.
    pub fn solve(&self, ridge: f64, part: RefitPart) -> Result<(Vec<f64>, f64), SgcsError> {
        check_ridge(ridge)?;
        let (values, rhs) = self.regularised(ridge, part);
        let x = self.cholesky_solve(&values, &rhs)?;
        let worst = self.largest_residual(&values, &x, &rhs);
        let weights = self.cell_major(&x);
        if weights.iter().any(|v| !v.is_finite()) {
            return Err(SgcsError::Refit(
                "the solve gave non-finite weights; use a larger ridge".into(),
            ));
        }
        Ok((weights, worst))
    }

    /// The system of `part` with `μ = ridge · mean(diag)` added to its diagonal: the lower
    /// triangle's values and the right-hand sides (permuted, as stored).
    fn regularised(&self, ridge: f64, part: RefitPart) -> (Vec<f64>, Vec<f64>) {
        let len = self.len;
        let mut values = self.values.clone();
        let mut rhs = self.rhs.clone();
        if part == RefitPart::Fitting {
            self.remove_held_back(&mut values, &mut rhs);
        }
        let diagonal = |c: usize| self.col_ptr[c] as usize; // the diagonal comes first
        let mean_diag = (0..len).map(|c| values[diagonal(c)]).sum::<f64>() / len as f64;
        let mu = ridge * mean_diag.max(f64::MIN_POSITIVE);
        for c in 0..len {
            values[diagonal(c)] += mu;
        }
        (values, rhs)
    }

    /// The lower triangle of the held-back samples' `Φ_hᵀΦ_h`, subtracted from `values`
    /// (permuted, as `values`), and their `Φ_hᵀ z_h` from `rhs`. Straight into place, sample by
    /// sample: each entry sees its samples in order, and nothing the size of `Φ_hᵀΦ_h` is held
    /// (collecting the entries first took 70 MB at 4000 cells).
    fn remove_held_back(&self, values: &mut [f64], rhs: &mut [f64]) {
        let (len, m) = (self.len, self.m);
        let mut row: Vec<(u32, f64)> = Vec::new();
        for h in 0..self.held_back() {
            row.clear();
            row.extend(
                self.held_row(h)
                    .iter()
                    .map(|&(c, a)| (self.position[c as usize], a)),
            );
            row.sort_unstable_by_key(|e| e.0);
            for (i, &(p, a)) in row.iter().enumerate() {
                let column =
                    self.col_ptr[p as usize] as usize..self.col_ptr[p as usize + 1] as usize;
                let mut k = column.start;
                // The rows at and after `p` are this column's entries of the sample, ascending.
                for &(q, b) in &row[i..] {
                    k += self.row_idx[k..column.end].partition_point(|&r| r < q);
                    debug_assert!(
                        k < column.end && self.row_idx[k] == q,
                        "held-back pattern is in the system"
                    );
                    values[k] -= a * b;
                }
                for j in 0..m {
                    rhs[j * len + p as usize] -= a * self.held_targets[h * m + j];
                }
            }
        }
    }

    /// `x` with `G x = rhs` for the symmetric `G` of which `values` is the lower triangle
    /// (permuted; `rhs` and `x` column-major `len × m`), by one numeric factorisation.
    fn cholesky_solve(&self, values: &[f64], rhs: &[f64]) -> Result<Vec<f64>, SgcsError> {
        let (len, m) = (self.len, self.m);
        let pattern =
            SymbolicSparseColMatRef::new_checked(len, len, &self.col_ptr, None, &self.row_idx);
        let matrix = SparseColMatRef::new(pattern, values);
        let mut factor = vec![0.0; self.symbolic.len_val()];
        let scratch = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(self.symbolic.solve_in_place_scratch::<f64>(m, Par::Seq));
        let mut buffer = MemBuffer::new(scratch);
        let stack = MemStack::new(&mut buffer);
        let llt = self
            .symbolic
            .factorize_numeric_llt(
                &mut factor,
                matrix,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|e| {
                SgcsError::Refit(format!(
                    "the normal equations are not positive definite ({e}); use a larger ridge"
                ))
            })?;
        let mut x = rhs.to_vec(); // column-major len × m
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut x, len, m),
            Par::Seq,
            stack,
        );
        Ok(x)
    }

    /// The largest relative residual `|G x_j − b_j| / |b_j|` over the output columns.
    fn largest_residual(&self, values: &[f64], x: &[f64], rhs: &[f64]) -> f64 {
        let len = self.len;
        let mut worst = 0.0f64;
        let mut gx = vec![0.0; len];
        for j in 0..self.m {
            let xj = &x[j * len..(j + 1) * len];
            let b = &rhs[j * len..(j + 1) * len];
            self.sym_matvec(values, xj, &mut gx);
            let r: f64 = gx.iter().zip(b).map(|(g, b)| (g - b).powi(2)).sum();
            let bn: f64 = b.iter().map(|b| b * b).sum();
            if bn > 0.0 {
                worst = worst.max((r / bn).sqrt());
            }
        }
        worst
    }

    /// The solution `x` (permuted, column-major `len × m`) as cell-major weights.
    fn cell_major(&self, x: &[f64]) -> Vec<f64> {
        let (len, m) = (self.len, self.m);
        let mut weights = vec![0.0; len * m];
        for c in 0..len {
            for j in 0..m {
                weights[c * m + j] = x[j * len + self.position[c] as usize];
            }
        }
        weights
    }
}

#[cfg(test)]
mod tests {
    use std::ops::ControlFlow;

    use super::*;
    use crate::test_support::{assert_close, bump_ridge_samples, grown_bump_ridge};

    /// Held-back samples score a fit through the normal equations exactly as predicting them
    /// does, and the fitting part alone solves like a system of only those samples.
    #[test]
    fn held_back_samples_score_fits_and_stay_out_of_the_fitting_part() {
        let net = grown_bump_ridge(80, 10);
        let (inputs, targets) = bump_ridge_samples(11, 1_600);
        let held: Vec<bool> = (0..1_600).map(|i| i % 3 == 0).collect();
        let split = net
            .refit_system_split(&inputs, &targets, &held, &mut |_| ControlFlow::Continue(()))
            .unwrap();
        assert_eq!((split.samples(), split.held_back()), (1_600, 534));
        let (fit_x, fit_y): (Vec<f64>, Vec<f64>) = {
            let keep: Vec<usize> = (0..1_600).filter(|&i| !held[i]).collect();
            (
                keep.iter()
                    .flat_map(|&i| [inputs[2 * i], inputs[2 * i + 1]])
                    .collect(),
                keep.iter().map(|&i| targets[i]).collect(),
            )
        };
        let only_fit = net.refit_system(&fit_x, &fit_y).unwrap();
        let (a, _) = split.solve(1e-3, RefitPart::Fitting).unwrap();
        let (b, _) = only_fit.solve(1e-3, RefitPart::All).unwrap();
        let scale = b.iter().map(|v| v.abs()).fold(0.0, f64::max);
        for (x, y) in a.iter().zip(&b) {
            assert_close!(*x, *y, 1e-9 * scale);
        }
        let mut trial = net.clone();
        trial.set_outputs_from(&split, &a).unwrap();
        let (mut num, mut den) = (0.0, 0.0);
        for i in (0..1_600).filter(|&i| held[i]) {
            let e = trial.predict1(&inputs[2 * i..2 * i + 2]) - targets[i];
            num += e * e;
            den += targets[i] * targets[i];
        }
        let direct = (num / den).sqrt();
        assert_close!(split.validation_error(&a).unwrap(), direct, 1e-9 * direct);
        assert!(only_fit.validation_error(&b).is_none());
    }
}
