//! Assembling the refit's normal equations in bounded memory, in an order fixed by the samples.
//!
//! `Φ` is never stored whole: the samples are put in a space-filling (Morton) order of their
//! inputs and cut into chunks; a chunk's rows are found with the network's spatial index, its
//! share of the lower triangle of `ΦᵀΦ` is summed with a dense accumulator column by column,
//! and the shares are merged into the sparse `ΦᵀΦ` in chunk order. Chunks are assembled in
//! parallel (rayon) a few at a time; every sum is taken in an order fixed by the samples
//! alone, so the result does not depend on the thread count. Memory is `ΦᵀΦ` (its nonzeros:
//! pairs of cells whose supports meet at some sample) plus a few chunks' rows, whatever the
//! number of samples. Cost: `Σ_i a_i²/2` for `a_i` active cells per sample (about 130 at 4000
//! cells in R⁴).

use std::ops::ControlFlow;

use faer::linalg::matmul::triangular::{BlockStructure, matmul};
use faer::{Accum, Mat, Par};
use rayon::prelude::*;

use super::pattern::{
    add_diagonals, fill_reducing_order, permuted_lower, permuted_rhs, symbolic_cholesky,
};
use super::{RefitProgress, RefitStage, RefitSystem};
use crate::{Network, SgcsError};

/// Samples per assembly chunk: nearby samples (in Morton order), so their rows share most
/// cells and a chunk's `ΦᵀΦ` is one small dense product.
const CHUNK: usize = 128;
/// Chunks assembled at once (in parallel); bounds the memory in flight.
const WAVE: usize = 2;

/// One row of `Φ`: `(cell, weight)`, cells ascending.
type Row = Vec<(u32, f64)>;

/// One chunk's share of the normal equations: the lower-triangle columns it touches
/// (ascending) with their entries (rows ascending), and its samples' rows (for `Φᵀz`).
struct ChunkShare {
    columns: Vec<(u32, Vec<u32>, Vec<f64>)>,
    /// Per sample (in chunk order): its index and its row of `Φ`.
    rows: Vec<(usize, Row)>,
}

/// The normal equations summed over every sample, in cell order: the lower-triangle columns
/// of `ΦᵀΦ` (rows ascending, and their values), `Φᵀz` (output-major), `|z|²` per output, and
/// the held-back samples' rows.
struct Sums {
    columns: Vec<(Vec<u32>, Vec<f64>)>,
    rhs: Vec<f64>,
    zz: Vec<f64>,
    held: Vec<(usize, Row)>,
}

impl Sums {
    /// Adds `share` (samples with `m` targets each in `targets`), keeping the rows of the
    /// samples `is_held` names.
    fn add(
        &mut self,
        share: ChunkShare,
        targets: &[f64],
        m: usize,
        is_held: impl Fn(usize) -> bool,
    ) {
        let len = self.columns.len();
        for (c, rows, values) in share.columns {
            merge_column(&mut self.columns[c as usize], &rows, &values);
        }
        for (i, row) in share.rows {
            for j in 0..m {
                let z = targets[i * m + j];
                self.zz[j] += z * z;
                let b = &mut self.rhs[j * len..(j + 1) * len];
                for &(c, a) in &row {
                    b[c as usize] += a * z;
                }
            }
            if is_held(i) {
                self.held.push((i, row));
            }
        }
    }
}

impl Network {
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
        let (m, len) = (self.output_dim(), self.len());
        let samples = self.refit_samples(inputs, targets, held_back)?;
        let Sums {
            mut columns,
            rhs,
            zz,
            held,
        } = self.sum_normal_equations(inputs, targets, held_back, samples, progress)?;
        let (held_rows, held_start, held_targets) = held_back_rows(held, targets, m);
        // Every column gets its diagonal; then a fill-reducing order, and the permuted lower
        // triangle.
        let nonzeros = add_diagonals(&mut columns)?;
        let position = fill_reducing_order(&columns)?;
        let (col_ptr, row_idx, values) = permuted_lower(columns, &position, nonzeros);
        let rhs = permuted_rhs(&rhs, &position, m);
        let symbolic = symbolic_cholesky(&col_ptr, &row_idx)?;
        Ok(RefitSystem {
            fingerprint: self.refit_fingerprint(),
            m,
            len,
            samples,
            col_ptr,
            row_idx,
            values,
            position,
            rhs,
            zz,
            held_rows,
            held_start,
            held_targets,
            symbolic,
        })
    }

    /// Sums the normal equations over the `samples` samples, wave by wave of chunks in
    /// Morton order (the chunks of a wave in parallel, merged in order); `progress` hears
    /// before each wave and may stop.
    fn sum_normal_equations(
        &self,
        inputs: &[f64],
        targets: &[f64],
        held_back: &[bool],
        samples: usize,
        progress: &mut dyn FnMut(RefitProgress) -> ControlFlow<()>,
    ) -> Result<Sums, SgcsError> {
        let (n, m, len) = (self.input_dim(), self.output_dim(), self.len());
        let is_held = |i: usize| held_back.get(i).copied().unwrap_or(false);
        let order = morton_order(inputs, n);
        let mut sums = Sums {
            columns: vec![(Vec::new(), Vec::new()); len],
            rhs: vec![0.0; m * len],
            zz: vec![0.0; m],
            held: Vec::new(),
        };
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
                sums.add(share, targets, m, is_held);
            }
            done += wave.len();
        }
        let _ = progress(RefitProgress {
            stage: RefitStage::Assembling,
            done: samples,
            total: samples,
        });
        Ok(sums)
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
}

/// The held-back samples' rows, concatenated in sample order (the caller's order reads
/// better than Morton order), with where each starts, and their targets (`m` each).
fn held_back_rows(
    mut held: Vec<(usize, Row)>,
    targets: &[f64],
    m: usize,
) -> (Row, Vec<usize>, Vec<f64>) {
    held.sort_unstable_by_key(|e| e.0);
    let mut held_rows = Vec::new();
    let mut held_start = vec![0];
    let mut held_targets = Vec::with_capacity(held.len() * m);
    for (i, row) in held {
        held_rows.extend_from_slice(&row);
        held_start.push(held_rows.len());
        held_targets.extend_from_slice(&targets[i * m..(i + 1) * m]);
    }
    (held_rows, held_start, held_targets)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::RefitPart;
    use crate::test_support::{bump_ridge_samples, grown_bump_ridge};

    /// The assembly sums in an order fixed by the samples: one thread or several, the same
    /// bits; and the progress callback can stop it.
    #[test]
    fn assembly_is_independent_of_threads_and_interruptible() {
        let net = grown_bump_ridge(120, 12);
        let (inputs, targets) = bump_ridge_samples(13, 20_000);
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
}
