//! Refitting all output weights at once: ridge least squares for fixed centres and widths.
//!
//! Minimises `Σ_i |κ(ξ_i) − ζ_i|² + μ Σ_c |v_c|²` over every `v_c`, with the positions and
//! widths frozen. The design matrix `Φ_ic = M_c(ξ_i)` is sparse thanks to the activation cutoff
//! (divided by `Σ_c M_c(ξ_i)` with [`crate::OutputMode::Normalized`]). The penalty is relative:
//! `μ = ridge · mean(diag ΦᵀΦ)`, so `ridge` is dimensionless.
//!
//! **Assembly in bounded memory.** `Φ` is never stored whole: the samples are put in a
//! space-filling (Morton) order of their inputs and cut into chunks; a chunk's rows are found
//! with the network's spatial index, its share of the lower triangle of `ΦᵀΦ` is summed with a
//! dense accumulator column by column, and the shares are merged into the sparse `ΦᵀΦ` in chunk
//! order. Chunks are assembled in parallel (rayon) a few at a time; every sum is taken in an
//! order fixed by the samples alone, so the result does not depend on the thread count. Memory
//! is `ΦᵀΦ` (its nonzeros: pairs of cells whose supports meet at some sample) plus a few
//! chunks' rows, whatever the number of samples. Cost: `Σ_i a_i²/2` for `a_i` active cells
//! per sample (about 130 at 4000 cells in R⁴).
//!
//! **Solve.** `ΦᵀΦ + μ I` is symmetric positive definite; it is factorised by faer's sparse
//! Cholesky (`LLᵀ`, approximate-minimum-degree ordering, supernodal where the factor is dense
//! enough): exact to rounding, where conjugate gradients needed thousands of iterations on
//! these badly conditioned systems (overlapping Gaussians), and `ΦᵀΦ`'s nonzero pattern keeps
//! the factor small (the cells live on a low-dimensional surface). The ordering and symbolic
//! factorisation are computed once per system; each ridge costs one numeric factorisation.
//!
//! **Choosing the ridge** ([`RefitSystem`] with held-back samples): each candidate is fitted on
//! the fitting part and scored on the held-back part through the normal equations alone,
//! `|Φ_h v − z_h|² = vᵀ (Φ_hᵀΦ_h) v − 2 vᵀ Φ_hᵀ z_h + |z_h|²`, so no sample is visited again.
//! Overlapping Gaussians make `ΦᵀΦ` badly conditioned, and a tiny ridge fits the training
//! samples with large cancelling weights that generalise worse than the delta rule did.
//! Measured on the bump-and-ridge test function (400 cells, 20 samples per cell), held-out
//! relative L2 before 0.259; after a refit with ridge 1e-8: 0.62, 1e-6: 0.55, 1e-4: 0.22,
//! **1e-3: 0.19**, 1e-2: 0.20. Use about `1e-3` and check on held-out samples.

use std::ops::ControlFlow;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::linalg::matmul::triangular::{BlockStructure, matmul};
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Conj, Mat, MatMut, Par, Side};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{Network, SgcsError};

/// What [`Network::refit_outputs`] and [`Network::refit_with`] did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefitReport {
    /// Number of samples used.
    pub samples: usize,
    /// Nonzeros of the Cholesky factor (8 bytes each).
    pub factor_nonzeros: usize,
    /// Largest relative residual `|(ΦᵀΦ + μI) v − Φᵀz| / |Φᵀz|` over the output columns.
    pub relative_residual: f64,
    /// Root mean square training error before the refit.
    pub rms_before: f64,
    /// Root mean square training error after the refit.
    pub rms_after: f64,
}

/// Where a refit is (for a progress display).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefitStage {
    /// Assembling the normal equations: `done` of `total` samples.
    Assembling,
    /// Factorising: `done` of `total` solves (one per ridge tried, and the final one).
    Solving,
}

/// A progress report of a refit: the stage and how far it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RefitProgress {
    /// The stage.
    pub stage: RefitStage,
    /// Units done.
    pub done: usize,
    /// Units in all.
    pub total: usize,
}

/// Samples per assembly chunk: nearby samples (in Morton order), so their rows share most
/// cells and a chunk's `ΦᵀΦ` is one small dense product.
const CHUNK: usize = 128;
/// Chunks assembled at once (in parallel); bounds the memory in flight.
const WAVE: usize = 2;

/// Which samples a solve of a [`RefitSystem`] fits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RefitPart {
    /// The samples not held back.
    Fitting,
    /// Every sample.
    All,
}

/// The normal equations of a refit for one sample set and one state of the centres and
/// widths: the lower triangle of `ΦᵀΦ` over all samples (in a fill-reducing order), `Φᵀz` and
/// `|z|²`, and the rows of the held-back samples, which are few (they score fits, and are
/// subtracted again to fit without them); plus the symbolic Cholesky factorisation. Build it
/// once with [`Network::refit_system`] (or [`Network::refit_system_split`]); then each ridge
/// costs one numeric factorisation ([`RefitSystem::solve`]) and no sample is visited again.
pub struct RefitSystem {
    /// `(steps, len, cutoff bits)` of the network it was built for.
    fingerprint: (u64, usize, u64),
    m: usize,
    len: usize,
    /// Samples: all, held back.
    samples: usize,
    /// Lower triangle of `ΦᵀΦ` in compressed columns, rows and columns in the fill-reducing
    /// order (`position[c]` is cell `c`'s place), rows ascending, diagonal first.
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
    position: Vec<u32>,
    /// `Φᵀ z_j` over all samples, output-major in the fill-reducing order.
    rhs: Vec<f64>,
    /// `|z_j|²` over all samples.
    zz: Vec<f64>,
    /// The held-back samples' rows (cells ascending) and targets.
    held_rows: Vec<(u32, f64)>,
    held_start: Vec<usize>,
    held_targets: Vec<f64>,
    symbolic: SymbolicCholesky<u32>,
}

impl std::fmt::Debug for RefitSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RefitSystem")
            .field("cells", &self.len)
            .field("samples", &self.samples)
            .field("held_back", &self.held_back())
            .field("nonzeros", &self.row_idx.len())
            .finish()
    }
}

impl RefitSystem {
    /// Number of samples (held back included).
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Number of held-back samples.
    pub fn held_back(&self) -> usize {
        self.held_start.len() - 1
    }

    /// Nonzeros of the lower triangle of `ΦᵀΦ`.
    pub fn nonzeros(&self) -> usize {
        self.row_idx.len()
    }

    /// Nonzeros of the Cholesky factor.
    pub fn factor_nonzeros(&self) -> usize {
        self.symbolic.len_val()
    }

    fn held_row(&self, h: usize) -> &[(u32, f64)] {
        &self.held_rows[self.held_start[h]..self.held_start[h + 1]]
    }

    /// `y = G x` for the symmetric `G` of which `values` is the lower triangle (permuted).
    fn sym_matvec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for c in 0..self.len {
            let (a, b) = (self.col_ptr[c] as usize, self.col_ptr[c + 1] as usize);
            for k in a..b {
                let d = self.row_idx[k] as usize;
                let v = values[k];
                y[d] += v * x[c];
                if d != c {
                    y[c] += v * x[d];
                }
            }
        }
    }

    /// `Σ |Φ_h v − z_h|²` over the held-back samples, `v` cell-major.
    fn held_squared_error(&self, weights: &[f64]) -> f64 {
        let m = self.m;
        let mut total = 0.0;
        for h in 0..self.held_back() {
            for j in 0..m {
                let predicted: f64 = self
                    .held_row(h)
                    .iter()
                    .map(|&(c, a)| a * weights[c as usize * m + j])
                    .sum();
                total += (predicted - self.held_targets[h * m + j]).powi(2);
            }
        }
        total
    }

    /// `Σ_i |Φ_i v − z_i|²` over all samples from the normal equations:
    /// `vᵀ G v − 2 vᵀ b + |z|²` per output, `v` cell-major (as the network stores it).
    fn squared_error(&self, weights: &[f64]) -> f64 {
        let (len, m) = (self.len, self.m);
        let mut x = vec![0.0; len];
        let mut gx = vec![0.0; len];
        let mut total = 0.0;
        for j in 0..m {
            for c in 0..len {
                x[self.position[c] as usize] = weights[c * m + j];
            }
            self.sym_matvec(&self.values, &x, &mut gx);
            let b = &self.rhs[j * len..(j + 1) * len];
            let quadratic: f64 = x.iter().zip(&gx).map(|(a, b)| a * b).sum();
            let linear: f64 = x.iter().zip(b).map(|(a, b)| a * b).sum();
            total += quadratic - 2.0 * linear + self.zz[j];
        }
        // Rounding can leave a tiny negative for a near-perfect fit.
        total.max(0.0)
    }

    /// Relative L2 error `|Φ_h v − z_h| / |z_h|` of the weights `v` (cell-major, as
    /// [`Network::outputs`] stores them) on the held-back samples; `None` when none was held
    /// back.
    pub fn validation_error(&self, weights: &[f64]) -> Option<f64> {
        if self.held_back() == 0 {
            return None;
        }
        let zz: f64 = self.held_targets.iter().map(|z| z * z).sum();
        let e = self.held_squared_error(weights);
        Some(if zz > 0.0 { (e / zz).sqrt() } else { e.sqrt() })
    }

    /// The root mean square error of `weights` over all samples.
    fn rms(&self, weights: &[f64]) -> f64 {
        (self.squared_error(weights) / (self.samples * self.m).max(1) as f64).sqrt()
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

    /// The ridge solution on the samples of `part`: the weights `v` (cell-major) minimising
    /// `|Φ v − z|² + μ |v|²`, `μ = ridge · mean(diag ΦᵀΦ)`, and the largest relative residual
    /// of the system solved.
    pub fn solve(&self, ridge: f64, part: RefitPart) -> Result<(Vec<f64>, f64), SgcsError> {
        check_ridge(ridge)?;
        let (len, m) = (self.len, self.m);
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
        let pattern =
            SymbolicSparseColMatRef::new_checked(len, len, &self.col_ptr, None, &self.row_idx);
        let matrix = SparseColMatRef::new(pattern, &values);
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
        let mut x = rhs.clone(); // column-major len × m
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut x, len, m),
            Par::Seq,
            stack,
        );
        drop(factor);
        let mut worst = 0.0f64;
        let mut gx = vec![0.0; len];
        for j in 0..m {
            let xj = &x[j * len..(j + 1) * len];
            let b = &rhs[j * len..(j + 1) * len];
            self.sym_matvec(&values, xj, &mut gx);
            let r: f64 = gx.iter().zip(b).map(|(g, b)| (g - b).powi(2)).sum();
            let bn: f64 = b.iter().map(|b| b * b).sum();
            if bn > 0.0 {
                worst = worst.max((r / bn).sqrt());
            }
        }
        let mut weights = vec![0.0; len * m];
        for c in 0..len {
            for j in 0..m {
                weights[c * m + j] = x[j * len + self.position[c] as usize];
            }
        }
        if weights.iter().any(|v| !v.is_finite()) {
            return Err(SgcsError::Refit(
                "the solve gave non-finite weights; use a larger ridge".into(),
            ));
        }
        Ok((weights, worst))
    }
}

/// One chunk's share of the normal equations: the lower-triangle columns it touches
/// (ascending) with their entries (rows ascending), and its samples' rows (for `Φᵀz`).
struct ChunkShare {
    columns: Vec<(u32, Vec<u32>, Vec<f64>)>,
    /// Per sample (in chunk order): its index and its row of `Φ`.
    rows: Vec<(usize, Vec<(u32, f64)>)>,
}

impl Network {
    /// Ridge least-squares refit of every output weight over the samples `inputs` (flat,
    /// `N · input_dim`) and `targets` (flat, `N · output_dim`), centres and widths fixed.
    /// `ridge > 0` is relative to the mean diagonal of `ΦᵀΦ` (see the module docs). Keeps the
    /// old weights, and reports so, when the refit would not lower the training error.
    /// The same as [`Network::refit_system`] then [`Network::refit_with`].
    pub fn refit_outputs(
        &mut self,
        inputs: &[f64],
        targets: &[f64],
        ridge: f64,
    ) -> Result<RefitReport, SgcsError> {
        check_ridge(ridge)?;
        let system = self.refit_system(inputs, targets)?;
        self.refit_with(&system, ridge)
    }

    fn refit_fingerprint(&self) -> (u64, usize, u64) {
        (
            self.steps(),
            self.len(),
            self.params().activation_cutoff.to_bits(),
        )
    }

    /// Assembles the refit's normal equations over all samples (none held back).
    pub fn refit_system(&self, inputs: &[f64], targets: &[f64]) -> Result<RefitSystem, SgcsError> {
        self.refit_system_split(inputs, targets, &[], &mut |_| ControlFlow::Continue(()))
    }

    /// Assembles the refit's normal equations for the current centres and widths, holding
    /// back the samples `i` with `held_back[i]` (empty: none) to score fits with
    /// ([`RefitSystem::validation_error`]). `progress` hears how far the assembly is and may
    /// stop it ([`SgcsError::Interrupted`]).
    pub fn refit_system_split(
        &self,
        inputs: &[f64],
        targets: &[f64],
        held_back: &[bool],
        progress: &mut dyn FnMut(RefitProgress) -> ControlFlow<()>,
    ) -> Result<RefitSystem, SgcsError> {
        let (n, m, len) = (self.input_dim(), self.output_dim(), self.len());
        let samples = self.refit_samples(inputs, targets, held_back)?;
        let is_held = |i: usize| held_back.get(i).copied().unwrap_or(false);

        let order = morton_order(inputs, n);
        // Lower-triangle columns as they are merged: rows ascending, and their values.
        let mut columns: Vec<(Vec<u32>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); len];
        let mut rhs = vec![0.0; m * len];
        let mut zz = vec![0.0; m];
        let mut held: Vec<(usize, Vec<(u32, f64)>)> = Vec::new();
        let mut done = 0;
        for wave in order.chunks(CHUNK * WAVE) {
            if progress(RefitProgress {
                stage: RefitStage::Assembling,
                done,
                total: samples,
            })
            .is_break()
            {
                return Err(SgcsError::Interrupted);
            }
            let shares: Vec<ChunkShare> = wave
                .par_chunks(CHUNK)
                .map(|chunk| self.chunk_share(inputs, chunk))
                .collect();
            for share in shares {
                for (c, rows, values) in share.columns {
                    merge_column(&mut columns[c as usize], &rows, &values);
                }
                for (i, row) in share.rows {
                    for j in 0..m {
                        let z = targets[i * m + j];
                        zz[j] += z * z;
                        let b = &mut rhs[j * len..(j + 1) * len];
                        for &(c, a) in &row {
                            b[c as usize] += a * z;
                        }
                    }
                    if is_held(i) {
                        held.push((i, row));
                    }
                }
            }
            done += wave.len();
        }
        let _ = progress(RefitProgress {
            stage: RefitStage::Assembling,
            done: samples,
            total: samples,
        });
        // Held-back rows in sample order (their sums must not depend on the Morton order's
        // ties... they do not, but the order is the caller's, which reads better).
        held.sort_unstable_by_key(|e| e.0);
        let mut held_rows = Vec::new();
        let mut held_start = vec![0];
        let mut held_targets = Vec::with_capacity(held.len() * m);
        for (i, row) in held {
            held_rows.extend_from_slice(&row);
            held_start.push(held_rows.len());
            held_targets.extend_from_slice(&targets[i * m..(i + 1) * m]);
        }

        // Every column gets its diagonal (0 for a cell no sample reaches, so a ridge can
        // always be put there); then a fill-reducing order, and the permuted lower triangle.
        let mut nonzeros = 0usize;
        for (c, (rows, values)) in columns.iter_mut().enumerate() {
            if rows.first().is_none_or(|&d| d as usize != c) {
                rows.insert(0, c as u32);
                values.insert(0, 0.0);
            }
            nonzeros += rows.len();
        }
        if u32::try_from(nonzeros).is_err() {
            return Err(SgcsError::Refit(
                "the normal equations have more than 2^32 nonzeros".into(),
            ));
        }
        let position = fill_reducing_order(&columns)?;
        let (col_ptr, row_idx, values) = permuted_lower(columns, &position, nonzeros);
        let mut permuted_rhs = vec![0.0; m * len];
        for j in 0..m {
            for c in 0..len {
                permuted_rhs[j * len + position[c] as usize] = rhs[j * len + c];
            }
        }
        // faer's symbolic analysis without an ordering reads the upper triangle.
        let (upper_ptr, upper_idx) = transposed_pattern(&col_ptr, &row_idx);
        let pattern = SymbolicSparseColMatRef::new_checked(len, len, &upper_ptr, None, &upper_idx);
        let symbolic = factorize_symbolic_cholesky(
            pattern,
            Side::Upper,
            SymmetricOrdering::Identity,
            Default::default(),
        )
        .map_err(|e| SgcsError::Refit(format!("analysing the normal equations failed: {e:?}")))?;
        Ok(RefitSystem {
            fingerprint: self.refit_fingerprint(),
            m,
            len,
            samples,
            col_ptr,
            row_idx,
            values,
            position,
            rhs: permuted_rhs,
            zz,
            held_rows,
            held_start,
            held_targets,
            symbolic,
        })
    }

    /// The number of samples in `inputs`, after checking that the refit's inputs agree in
    /// length and are finite.
    fn refit_samples(
        &self,
        inputs: &[f64],
        targets: &[f64],
        held_back: &[bool],
    ) -> Result<usize, SgcsError> {
        let (n, m) = (self.input_dim(), self.output_dim());
        if !inputs.len().is_multiple_of(n) || inputs.is_empty() {
            return Err(SgcsError::Refit(format!(
                "inputs has length {}, not a positive multiple of input_dim {n}",
                inputs.len()
            )));
        }
        let samples = inputs.len() / n;
        if targets.len() != samples * m {
            return Err(SgcsError::Refit(format!(
                "targets has length {}, expected {samples} samples x output_dim {m}",
                targets.len()
            )));
        }
        if !held_back.is_empty() && held_back.len() != samples {
            return Err(SgcsError::Refit(format!(
                "held_back has length {}, expected 0 or {samples}",
                held_back.len()
            )));
        }
        if let Some(x) = inputs.iter().chain(targets).find(|x| !x.is_finite()) {
            return Err(SgcsError::Refit(format!("non-finite sample value {x}")));
        }
        Ok(samples)
    }

    /// The rows of the samples `chunk` and their share of the lower triangle of `ΦᵀΦ`, as one
    /// dense product over the cells the chunk touches (a few hundred nearby samples share
    /// most of their cells, so the product wastes little and runs at full SIMD speed).
    fn chunk_share(&self, inputs: &[f64], chunk: &[u32]) -> ChunkShare {
        let n = self.input_dim();
        let normalized = self.params().output_mode == crate::OutputMode::Normalized;
        let (mut stack, mut ids, mut found) = (Vec::new(), Vec::new(), Vec::new());
        let mut rows = Vec::with_capacity(chunk.len());
        for &i in chunk {
            let i = i as usize;
            self.active_into(
                &inputs[i * n..(i + 1) * n],
                &mut stack,
                &mut ids,
                &mut found,
            );
            if normalized {
                // The output is Σ v M / Σ M: the design matrix holds the normalised weights.
                let sum: f64 = found.iter().map(|e| e.1).sum();
                if sum > 0.0 {
                    found.iter_mut().for_each(|e| e.1 /= sum);
                }
            }
            rows.push((i, found.clone()));
        }
        let mut cells: Vec<u32> = rows.iter().flat_map(|r| r.1.iter().map(|e| e.0)).collect();
        cells.sort_unstable();
        cells.dedup();
        let local = |c: u32| cells.binary_search(&c).unwrap_or_else(|_| unreachable!());
        let u = cells.len();
        let mut phi = Mat::<f64>::zeros(rows.len(), u);
        for (r, (_, row)) in rows.iter().enumerate() {
            for &(c, a) in row {
                phi[(r, local(c))] = a;
            }
        }
        let mut product = Mat::<f64>::zeros(u, u);
        matmul(
            product.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            phi.transpose(),
            BlockStructure::Rectangular,
            phi.as_ref(),
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        );
        drop(phi);
        let mut columns = Vec::with_capacity(u);
        for q in 0..u {
            let column = product.col(q);
            let (mut rows_q, mut values_q) = (Vec::new(), Vec::new());
            for p in q..u {
                let v = column[p];
                if v != 0.0 {
                    rows_q.push(cells[p]);
                    values_q.push(v);
                }
            }
            if !rows_q.is_empty() {
                columns.push((cells[q], rows_q, values_q));
            }
        }
        ChunkShare { columns, rows }
    }

    /// Solves `system` (from [`Network::refit_system`] on this network, or on a clone of it in
    /// the same state) on all its samples with penalty `ridge` and installs the weights; see
    /// [`Network::refit_outputs`]. Errors when the network has trained or grown since.
    pub fn refit_with(
        &mut self,
        system: &RefitSystem,
        ridge: f64,
    ) -> Result<RefitReport, SgcsError> {
        check_ridge(ridge)?;
        self.check_system(system)?;
        let rms_before = system.rms(self.outputs());
        let (weights, residual) = system.solve(ridge, RefitPart::All)?;
        let mut rms_after = system.rms(&weights);
        if rms_after.is_nan() || rms_after > rms_before {
            rms_after = rms_before;
        } else {
            self.outputs_mut().copy_from_slice(&weights);
        }
        Ok(RefitReport {
            samples: system.samples(),
            factor_nonzeros: system.factor_nonzeros(),
            relative_residual: residual,
            rms_before,
            rms_after,
        })
    }

    /// Installs refitted weights (cell-major, from [`RefitSystem::solve`] on a system built
    /// for this network's present state).
    pub fn set_outputs_from(
        &mut self,
        system: &RefitSystem,
        weights: &[f64],
    ) -> Result<(), SgcsError> {
        self.check_system(system)?;
        if weights.len() != self.len() * self.output_dim() {
            return Err(SgcsError::Dimension {
                what: "refitted weights",
                expected: self.len() * self.output_dim(),
                got: weights.len(),
            });
        }
        if let Some(&value) = weights.iter().find(|v| !v.is_finite() || v.abs() > 1e100) {
            return Err(SgcsError::NonFinite {
                what: "refitted weights",
                value,
            });
        }
        self.outputs_mut().copy_from_slice(weights);
        Ok(())
    }

    fn check_system(&self, system: &RefitSystem) -> Result<(), SgcsError> {
        if system.fingerprint != self.refit_fingerprint() || system.m != self.output_dim() {
            return Err(SgcsError::Refit(
                "the system was assembled for another state of the network".into(),
            ));
        }
        Ok(())
    }
}

/// The approximate-minimum-degree order of the symmetric pattern whose lower triangle is
/// `columns`: `position[c]` is cell `c`'s place.
fn fill_reducing_order(columns: &[(Vec<u32>, Vec<f64>)]) -> Result<Vec<u32>, SgcsError> {
    let len = columns.len();
    let mut col_ptr = Vec::with_capacity(len + 1);
    col_ptr.push(0u32);
    let mut row_idx = Vec::new();
    for (rows, _) in columns {
        row_idx.extend_from_slice(rows);
        col_ptr.push(row_idx.len() as u32);
    }
    let pattern = SymbolicSparseColMatRef::new_checked(len, len, &col_ptr, None, &row_idx);
    let (mut fwd, mut inv) = (vec![0u32; len], vec![0u32; len]);
    let mut buffer = MemBuffer::new(amd::order_scratch::<u32>(len, row_idx.len()));
    amd::order(
        &mut fwd,
        &mut inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut buffer),
    )
    .map_err(|e| SgcsError::Refit(format!("ordering the normal equations failed: {e:?}")))?;
    Ok(inv)
}

/// The lower triangle `columns` with rows and columns moved to `position`, in compressed
/// columns (rows ascending, so each column starts at its diagonal). Consumes the columns as
/// it goes.
fn permuted_lower(
    columns: Vec<(Vec<u32>, Vec<f64>)>,
    position: &[u32],
    nonzeros: usize,
) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
    let len = columns.len();
    let mut counts = vec![0u32; len + 1];
    for (c, (rows, _)) in columns.iter().enumerate() {
        let pc = position[c];
        for &d in rows {
            counts[pc.min(position[d as usize]) as usize + 1] += 1;
        }
    }
    for c in 0..len {
        counts[c + 1] += counts[c];
    }
    let col_ptr = counts.clone();
    let mut next = counts;
    let mut row_idx = vec![0u32; nonzeros];
    let mut values = vec![0.0; nonzeros];
    for (c, (rows, vals)) in columns.into_iter().enumerate() {
        let pc = position[c];
        for (d, v) in rows.into_iter().zip(vals) {
            let pd = position[d as usize];
            let (col, row) = (pc.min(pd), pc.max(pd));
            let k = next[col as usize] as usize;
            row_idx[k] = row;
            values[k] = v;
            next[col as usize] += 1;
        }
    }
    for c in 0..len {
        let (a, b) = (col_ptr[c] as usize, col_ptr[c + 1] as usize);
        let mut entries: Vec<(u32, f64)> = row_idx[a..b]
            .iter()
            .copied()
            .zip(values[a..b].iter().copied())
            .collect();
        entries.sort_unstable_by_key(|e| e.0);
        for (k, (r, v)) in entries.into_iter().enumerate() {
            row_idx[a + k] = r;
            values[a + k] = v;
        }
    }
    (col_ptr, row_idx, values)
}

/// The pattern of the transpose of the compressed-column pattern `(col_ptr, row_idx)` (rows
/// ascending in each column).
fn transposed_pattern(col_ptr: &[u32], row_idx: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let len = col_ptr.len() - 1;
    let mut counts = vec![0u32; len + 1];
    for &r in row_idx {
        counts[r as usize + 1] += 1;
    }
    for c in 0..len {
        counts[c + 1] += counts[c];
    }
    let mut next = counts.clone();
    let mut rows = vec![0u32; row_idx.len()];
    for c in 0..len {
        for &r in &row_idx[col_ptr[c] as usize..col_ptr[c + 1] as usize] {
            rows[next[r as usize] as usize] = c as u32;
            next[r as usize] += 1;
        }
    }
    (counts, rows)
}

/// Adds the entries `(rows, values)` (rows ascending) to `column` (rows ascending).
fn merge_column(column: &mut (Vec<u32>, Vec<f64>), rows: &[u32], values: &[f64]) {
    let (have_rows, have_values) = column;
    if have_rows
        .last()
        .is_none_or(|&last| rows.first().is_none_or(|&r| r > last))
    {
        have_rows.extend_from_slice(rows);
        have_values.extend_from_slice(values);
        return;
    }
    let total = have_rows.len() + rows.len();
    let (mut merged_rows, mut merged_values) =
        (Vec::with_capacity(total), Vec::with_capacity(total));
    let (mut i, mut k) = (0, 0);
    while i < have_rows.len() || k < rows.len() {
        if k == rows.len() || (i < have_rows.len() && have_rows[i] < rows[k]) {
            merged_rows.push(have_rows[i]);
            merged_values.push(have_values[i]);
            i += 1;
        } else if i == have_rows.len() || rows[k] < have_rows[i] {
            merged_rows.push(rows[k]);
            merged_values.push(values[k]);
            k += 1;
        } else {
            merged_rows.push(have_rows[i]);
            merged_values.push(have_values[i] + values[k]);
            i += 1;
            k += 1;
        }
    }
    merged_rows.shrink_to_fit();
    merged_values.shrink_to_fit();
    *column = (merged_rows, merged_values);
}

/// The samples in Morton (Z-curve) order of their inputs, quantised over their bounding box
/// (ties by index): nearby samples share active cells, so a chunk touches few columns.
fn morton_order(inputs: &[f64], n: usize) -> Vec<u32> {
    let samples = inputs.len() / n;
    let dims = n.min(64);
    let bits = (64 / dims).min(21) as u32;
    let mut lo = vec![f64::INFINITY; dims];
    let mut hi = vec![f64::NEG_INFINITY; dims];
    for x in inputs.chunks(n) {
        for d in 0..dims {
            lo[d] = lo[d].min(x[d]);
            hi[d] = hi[d].max(x[d]);
        }
    }
    let scale: Vec<f64> = (0..dims)
        .map(|d| {
            let span = hi[d] - lo[d];
            if span > 0.0 {
                ((1u64 << bits) - 1) as f64 / span
            } else {
                0.0
            }
        })
        .collect();
    let mut keyed: Vec<(u64, u32)> = inputs
        .chunks(n)
        .enumerate()
        .map(|(i, x)| {
            let q: Vec<u64> = (0..dims)
                .map(|d| ((x[d] - lo[d]) * scale[d]) as u64)
                .collect();
            let mut key = 0u64;
            for b in (0..bits).rev() {
                for &q in &q {
                    key = (key << 1) | ((q >> b) & 1);
                }
            }
            (key, i as u32)
        })
        .collect();
    debug_assert_eq!(keyed.len(), samples);
    keyed.sort_unstable();
    keyed.into_iter().map(|e| e.1).collect()
}

fn check_ridge(ridge: f64) -> Result<(), SgcsError> {
    if ridge > 0.0 && ridge.is_finite() {
        Ok(())
    } else {
        Err(SgcsError::InvalidParam {
            name: "ridge",
            range: "(0, ∞)".to_owned(),
            value: ridge.to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::test_support::{assert_close, bump_ridge, relative_l2, rng, unit_square_points};
    use crate::{OutputMode, Params};

    fn grown(cells: usize, seed: u64) -> Network {
        let p = Params {
            lambda: 100,
            max_cells: cells,
            ..Params::default()
        };
        let simplex = vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]];
        let mut net = Network::new(p, 2, 1, &simplex).unwrap();
        let mut r = rng(seed);
        while net.len() < cells {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            net.step(&[x, y], &[bump_ridge(x, y)]);
        }
        net
    }

    fn samples(seed: u64, count: usize) -> (Vec<f64>, Vec<f64>) {
        let pts = unit_square_points(seed, count);
        let inputs = pts.iter().flatten().copied().collect();
        let targets = pts.iter().map(|p| bump_ridge(p[0], p[1])).collect();
        (inputs, targets)
    }

    /// Solves the dense SPD system `a x = b` by Cholesky (test reference).
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for j in 0..n {
            for k in 0..j {
                let l = a[j][k];
                for i in j..n {
                    a[i][j] -= a[i][k] * l;
                }
            }
            let d = a[j][j].sqrt();
            for i in j..n {
                a[i][j] /= d;
            }
        }
        for i in 0..n {
            for k in 0..i {
                b[i] -= a[i][k] * b[k];
            }
            b[i] /= a[i][i];
        }
        for i in (0..n).rev() {
            for k in i + 1..n {
                b[i] -= a[k][i] * b[k];
            }
            b[i] /= a[i][i];
        }
        b
    }

    #[test]
    fn refit_solves_the_ridge_normal_equations() {
        let mut net = grown(30, 1);
        let (inputs, targets) = samples(2, 600);
        let len = net.len();
        let mut g = vec![vec![0.0; len]; len];
        let mut b = vec![0.0; len];
        for (i, xi) in inputs.chunks(2).enumerate() {
            let acts = net.activations(xi);
            for &(c, mc) in &acts {
                b[c] += mc * targets[i];
                for &(d, md) in &acts {
                    g[c][d] += mc * md;
                }
            }
        }
        let ridge = 1e-3;
        let mu = ridge * (0..len).map(|c| g[c][c]).sum::<f64>() / len as f64;
        for c in 0..len {
            g[c][c] += mu;
        }
        let expect = dense_solve(g, b);
        let report = net.refit_outputs(&inputs, &targets, ridge).unwrap();
        assert!(report.relative_residual <= 1e-9, "{report:?}");
        assert!(report.rms_after < report.rms_before, "{report:?}");
        let scale = expect.iter().map(|v| v.abs()).fold(0.0, f64::max);
        for c in 0..len {
            assert_close!(net.output(c)[0], expect[c], 1e-4 * scale);
        }
    }

    #[test]
    fn refit_lowers_the_held_out_error() {
        let mut net = grown(400, 3);
        let (inputs, targets) = samples(4, 8_000);
        let held_out = unit_square_points(5, 2_000);
        let before = relative_l2(&held_out, |x, y| net.predict1(&[x, y]), bump_ridge);
        let report = net.refit_outputs(&inputs, &targets, 1e-3).unwrap();
        let after = relative_l2(&held_out, |x, y| net.predict1(&[x, y]), bump_ridge);
        net.check_invariants().unwrap();
        // Measured 0.26 -> 0.19 (see the module docs).
        assert!(
            after < 0.9 * before,
            "held-out {before} -> {after}, {report:?}"
        );
    }

    #[test]
    fn one_system_serves_several_ridges_and_refuses_a_changed_network() {
        let net = grown(60, 8);
        let (inputs, targets) = samples(9, 1_200);
        let system = net.refit_system(&inputs, &targets).unwrap();
        assert_eq!(system.samples(), 1_200);
        for ridge in [1e-4, 1e-2] {
            let (mut a, mut b) = (net.clone(), net.clone());
            let ra = a.refit_with(&system, ridge).unwrap();
            let rb = b.refit_outputs(&inputs, &targets, ridge).unwrap();
            assert_eq!(ra, rb);
            assert_eq!(a.to_json(), b.to_json());
        }
        let mut moved = net.clone();
        moved.step(&[0.5, 0.5], &[1.0]);
        assert!(moved.refit_with(&system, 1e-3).is_err());
    }

    /// Held-back samples score a fit through the normal equations exactly as predicting them
    /// does, and the fitting part alone solves like a system of only those samples.
    #[test]
    fn held_back_samples_score_fits_and_stay_out_of_the_fitting_part() {
        let net = grown(80, 10);
        let (inputs, targets) = samples(11, 1_600);
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

    /// The assembly sums in an order fixed by the samples: one thread or several, the same
    /// bits; and the progress callback can stop it.
    #[test]
    fn assembly_is_independent_of_threads_and_interruptible() {
        let net = grown(120, 12);
        let (inputs, targets) = samples(13, 20_000);
        let solve_in = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let system = net.refit_system(&inputs, &targets).unwrap();
                system.solve(1e-4, RefitPart::All).unwrap().0
            })
        };
        let one = solve_in(1);
        assert_eq!(one, solve_in(3));
        let mut calls = 0;
        let stopped = net.refit_system_split(&inputs, &targets, &[], &mut |p| {
            assert_eq!((p.stage, p.total), (RefitStage::Assembling, 20_000));
            calls += 1;
            if p.done > 0 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        assert!(
            matches!(stopped, Err(SgcsError::Interrupted)),
            "{stopped:?}"
        );
        assert_eq!(calls, 2);
    }

    #[test]
    fn refit_rejects_bad_input() {
        let mut net = grown(10, 6);
        let before = net.to_json();
        let (inputs, targets) = samples(7, 50);
        for (i, t, ridge) in [
            (&inputs[..99], &targets[..], 1e-3),
            (&inputs[..], &targets[..49], 1e-3),
            (&inputs[..], &targets[..], 0.0),
            (&inputs[..], &targets[..], f64::NAN),
            (&[][..], &[][..], 1e-3),
        ] {
            assert!(net.refit_outputs(i, t, ridge).is_err());
        }
        let mut bad = inputs.clone();
        bad[3] = f64::INFINITY;
        assert!(net.refit_outputs(&bad, &targets, 1e-3).is_err());
        assert_eq!(net.to_json(), before);
        let err = net
            .refit_outputs(&inputs, &targets, -1.0)
            .unwrap_err()
            .to_string();
        assert!(err.contains("ridge"), "{err}");
    }

    /// The refit of a normalised network fits the normalised output.
    #[test]
    fn refit_of_a_normalized_network_lowers_its_training_error() {
        let params = Params {
            output_mode: OutputMode::Normalized,
            lambda: 50,
            ..Params::default()
        };
        let mut net = crate::test_support::grown(params, 10_000, 8, bump_ridge);
        let points = unit_square_points(9, 3_000);
        let inputs: Vec<f64> = points.iter().flatten().copied().collect();
        let targets: Vec<f64> = points.iter().map(|p| bump_ridge(p[0], p[1])).collect();
        let report = net.refit_outputs(&inputs, &targets, 1e-6).unwrap();
        assert!(report.rms_after < 0.9 * report.rms_before, "{report:?}");
        let rms: f64 = (points
            .iter()
            .map(|p| (net.predict1(p) - bump_ridge(p[0], p[1])).powi(2))
            .sum::<f64>()
            / points.len() as f64)
            .sqrt();
        assert_close!(rms, report.rms_after, 1e-9);
    }
}
