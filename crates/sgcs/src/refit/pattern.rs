//! The sparse structure of the normal equations: fill-reducing order, symbolic factorisation.

use faer::Side;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};

use crate::SgcsError;

/// Gives every column of the lower triangle `columns` its diagonal (0 for a cell no sample
/// reaches, so a ridge can always be put there); returns the number of nonzeros, which must
/// fit in `u32`.
pub(super) fn add_diagonals(columns: &mut [(Vec<u32>, Vec<f64>)]) -> Result<usize, SgcsError> {
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
    Ok(nonzeros)
}

/// The approximate-minimum-degree order of the symmetric pattern whose lower triangle is
/// `columns`: `position[c]` is cell `c`'s place.
pub(super) fn fill_reducing_order(columns: &[(Vec<u32>, Vec<f64>)]) -> Result<Vec<u32>, SgcsError> {
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
pub(super) fn permuted_lower(
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

/// The right-hand sides `rhs` (output-major, `m` columns of `position.len()` cells) with
/// each cell moved to `position`.
pub(super) fn permuted_rhs(rhs: &[f64], position: &[u32], m: usize) -> Vec<f64> {
    let len = position.len();
    let mut permuted = vec![0.0; m * len];
    for j in 0..m {
        for c in 0..len {
            permuted[j * len + position[c] as usize] = rhs[j * len + c];
        }
    }
    permuted
}

/// The symbolic Cholesky factorisation of the symmetric matrix whose lower triangle has the
/// compressed-column pattern `(col_ptr, row_idx)`, already in its fill-reducing order.
pub(super) fn symbolic_cholesky(
    col_ptr: &[u32],
    row_idx: &[u32],
) -> Result<SymbolicCholesky<u32>, SgcsError> {
    let len = col_ptr.len() - 1;
    // faer's symbolic analysis without an ordering reads the upper triangle.
    let (upper_ptr, upper_idx) = transposed_pattern(col_ptr, row_idx);
    let pattern = SymbolicSparseColMatRef::new_checked(len, len, &upper_ptr, None, &upper_idx);
    factorize_symbolic_cholesky(
        pattern,
        Side::Upper,
        SymmetricOrdering::Identity,
        Default::default(),
    )
    .map_err(|e| SgcsError::Refit(format!("analysing the normal equations failed: {e:?}")))
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
