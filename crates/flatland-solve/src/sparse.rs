//! A sparse transfer operator: each row holds only the elements its collocation point sees,
//! in compressed rows (CSR), kept in blocks of rows that are assembled and applied in parallel.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::{SolveError, Stop, TransferOperator};

/// Most non-zero numbers a sparse operator may hold: 2²⁸, about 3 GiB at 12 bytes each
/// (column and value). Past it the assembly stops with an error naming the element count.
pub const MAX_NONZEROS: usize = 1 << 28;

/// Rows per block: one rayon task assembles and applies one block.
const ROWS_PER_BLOCK: usize = 64;

/// A sparse N × N operator, row = receiver element, columns ascending in each row.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseOperator {
    n: usize,
    blocks: Vec<RowBlock>,
}

/// [`ROWS_PER_BLOCK`] consecutive rows (fewer in the last block) in CSR form.
#[derive(Clone, Debug, Default, PartialEq)]
struct RowBlock {
    /// Row `r` of the block is `columns[starts[r]..starts[r + 1]]`.
    starts: Vec<u32>,
    columns: Vec<u32>,
    values: Vec<f64>,
}

impl RowBlock {
    fn row(&self, r: usize) -> (&[u32], &[f64]) {
        let range = self.starts[r] as usize..self.starts[r + 1] as usize;
        (&self.columns[range.clone()], &self.values[range])
    }

    fn bytes(&self) -> usize {
        std::mem::size_of::<RowBlock>()
            + 4 * self.starts.capacity()
            + 4 * self.columns.capacity()
            + 8 * self.values.capacity()
    }
}

/// The non-zeros of the finer operator of a round on `next` elements, predicted from this
/// round's (`nonzeros` on `current`): rows grow with the elements and so does what each row
/// sees, so the count grows with the square of the ratio (an upper estimate when only some
/// elements are cut: a row sees the finer elements only where they are). Predicted before any
/// of it is built, so a round that cannot be held is never started.
#[must_use]
pub fn predicted_nonzeros(nonzeros: usize, current: usize, next: usize) -> usize {
    let ratio = next as f64 / current.max(1) as f64;
    (nonzeros as f64 * ratio * ratio)
        .ceil()
        .min(usize::MAX as f64) as usize
}

impl SparseOperator {
    /// Builds row `i` with `row(i, scratch, out)`: it appends `(column, value)` to `out`
    /// (empty on entry), columns strictly ascending and below `n`. Blocks of rows run in
    /// parallel, each with its own `scratch` from `init`, so the result does not depend on the
    /// thread count. `stop` is polled once per row. Errors: a value that is not finite (naming
    /// row and column), more than [`MAX_NONZEROS`] numbers in all, or `n` past `u32`.
    pub fn assemble<S>(
        n: usize,
        init: impl Fn() -> S + Sync + Send,
        row: impl Fn(usize, &mut S, &mut Vec<(u32, f64)>) + Sync,
        stop: &Stop,
    ) -> Result<SparseOperator, SolveError> {
        if u32::try_from(n).is_err() {
            return Err(too_many(n, "below 2³² (columns are u32)"));
        }
        let total = AtomicUsize::new(0);
        let blocks = (0..n.div_ceil(ROWS_PER_BLOCK))
            .into_par_iter()
            .map_init(
                || (init(), Vec::new()),
                |(scratch, out), b| {
                    let rows = b * ROWS_PER_BLOCK..((b + 1) * ROWS_PER_BLOCK).min(n);
                    let block = assemble_block(rows, scratch, out, &row, n, stop)?;
                    let held = total.fetch_add(block.values.len(), Ordering::Relaxed);
                    if held + block.values.len() > MAX_NONZEROS {
                        return Err(too_many(
                            n,
                            "few enough that the sparse operator holds at most 2²⁸ non-zero \
                             numbers (3 GiB)",
                        ));
                    }
                    Ok(block)
                },
            )
            .collect::<Result<Vec<RowBlock>, SolveError>>()?;
        Ok(SparseOperator { n, blocks })
    }

    /// Entry `K_ij` (0 where row `i` holds no column `j`).
    #[must_use]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (columns, values) = self.row(i);
        columns
            .binary_search(&(j as u32))
            .map_or(0.0, |k| values[k])
    }

    /// Row `i`: its columns (ascending) and their values.
    #[must_use]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        self.blocks[i / ROWS_PER_BLOCK].row(i % ROWS_PER_BLOCK)
    }

    /// Non-zero numbers held.
    #[must_use]
    pub fn nonzeros(&self) -> usize {
        self.blocks.iter().map(|b| b.values.len()).sum()
    }

    /// The transpose: row `j` of it is column `j` of this operator, `(i, K_ij)` with `i`
    /// ascending — what sends light from element `j`, for products with a vector that is
    /// non-zero on few elements ([`SparseOperator::gather_columns`]). Linear in the numbers
    /// held; the same numbers, so the same bytes.
    #[must_use]
    pub fn transposed(&self) -> SparseOperator {
        let n = self.n;
        let mut counts = vec![0u32; n];
        for block in &self.blocks {
            for &j in &block.columns {
                counts[j as usize] += 1;
            }
        }
        let mut blocks: Vec<RowBlock> = counts
            .chunks(ROWS_PER_BLOCK)
            .map(|counts| {
                let mut starts = Vec::with_capacity(counts.len() + 1);
                starts.push(0);
                let mut held = 0;
                for &c in counts {
                    held += c;
                    starts.push(held);
                }
                RowBlock {
                    starts,
                    columns: vec![0; held as usize],
                    values: vec![0.0; held as usize],
                }
            })
            .collect();
        // Where the next entry of each row of the transpose goes; rows of K in ascending
        // order fill each of its rows in ascending order.
        let mut next: Vec<u32> = blocks
            .iter()
            .flat_map(|b| b.starts[..b.starts.len() - 1].iter().copied())
            .collect();
        for i in 0..n {
            let (columns, values) = self.row(i);
            for (&j, &v) in columns.iter().zip(values) {
                let j = j as usize;
                let block = &mut blocks[j / ROWS_PER_BLOCK];
                let at = next[j] as usize;
                block.columns[at] = i as u32;
                block.values[at] = v;
                next[j] += 1;
            }
        }
        SparseOperator { n, blocks }
    }

    /// `out += Σ_j weight_j · (row j)` over `(j, weight_j)` in `weights`: on a transposed
    /// operator, `K x` for an `x` that is `weight_j` on the listed elements and 0 elsewhere,
    /// in the work of the columns listed only. Returns the numbers read.
    pub fn gather_columns(&self, weights: &[(u32, f64)], out: &mut [f64]) -> usize {
        let mut read = 0;
        for &(j, w) in weights {
            let (rows, values) = self.row(j as usize);
            read += rows.len();
            for (&i, v) in rows.iter().zip(values) {
                out[i as usize] += w * v;
            }
        }
        read
    }

    /// Bytes the operator holds in memory (indices and values, as allocated).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of::<SparseOperator>()
            + self.blocks.iter().map(RowBlock::bytes).sum::<usize>()
    }
}

/// The error of an operator with too many elements or numbers.
fn too_many(n: usize, valid: &'static str) -> SolveError {
    SolveError::InvalidParameter {
        name: "elements",
        value: n.to_string(),
        valid,
    }
}

/// Rows `rows` as one block.
fn assemble_block<S>(
    rows: std::ops::Range<usize>,
    scratch: &mut S,
    out: &mut Vec<(u32, f64)>,
    row: &impl Fn(usize, &mut S, &mut Vec<(u32, f64)>),
    n: usize,
    stop: &Stop,
) -> Result<RowBlock, SolveError> {
    let mut block = RowBlock {
        starts: Vec::with_capacity(rows.len() + 1),
        ..RowBlock::default()
    };
    block.starts.push(0);
    for i in rows {
        if stop() {
            return Err(SolveError::Interrupted);
        }
        out.clear();
        row(i, scratch, out);
        debug_assert!(
            out.windows(2).all(|w| w[0].0 < w[1].0) && out.iter().all(|&(j, _)| (j as usize) < n),
            "row {i}: columns must ascend and stay below {n}"
        );
        if let Some(&(j, _)) = out.iter().find(|(_, v)| !v.is_finite()) {
            return Err(SolveError::NonFiniteOperator {
                row: i,
                column: j as usize,
            });
        }
        block.columns.extend(out.iter().map(|&(j, _)| j));
        block.values.extend(out.iter().map(|&(_, v)| v));
        let held = u32::try_from(block.values.len()).map_err(|_| {
            too_many(
                n,
                "few enough that one block of 64 rows holds below 2³² numbers",
            )
        })?;
        block.starts.push(held);
    }
    block.columns.shrink_to_fit();
    block.values.shrink_to_fit();
    Ok(block)
}

impl TransferOperator for SparseOperator {
    fn len(&self) -> usize {
        self.n
    }

    fn apply(&self, b: &[f64], out: &mut [f64]) {
        out.par_chunks_mut(ROWS_PER_BLOCK)
            .zip(self.blocks.par_iter())
            .for_each(|(out, block)| {
                for (r, o) in out.iter_mut().enumerate() {
                    let (columns, values) = block.row(r);
                    *o = columns
                        .iter()
                        .zip(values)
                        .map(|(&j, v)| v * b[j as usize])
                        .sum();
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::never;
    use flatland_testkit::assert_close;
    use rand::RngExt;

    /// A random sparse matrix, dense row-major, about `fill` of it non-zero.
    fn random(n: usize, fill: f64, seed: u64) -> Vec<f64> {
        let mut rng = flatland_testkit::rng(seed);
        (0..n * n)
            .map(|_| {
                if rng.random_range(0.0..1.0) < fill {
                    rng.random_range(-1.0..1.0)
                } else {
                    0.0
                }
            })
            .collect()
    }

    fn sparse_of(dense: &[f64], n: usize) -> SparseOperator {
        SparseOperator::assemble(
            n,
            || (),
            |i, _, out| {
                out.extend(
                    (0..n)
                        .filter(|&j| dense[i * n + j] != 0.0)
                        .map(|j| (j as u32, dense[i * n + j])),
                )
            },
            &never,
        )
        .unwrap()
    }

    #[test]
    fn apply_is_the_matrix_product_and_entries_read_back() {
        let mut rng = flatland_testkit::rng(4);
        for (n, fill) in [(1, 1.0), (3, 0.5), (64, 0.1), (65, 0.3), (300, 0.02)] {
            let dense = random(n, fill, n as u64);
            let op = sparse_of(&dense, n);
            assert_eq!(op.len(), n);
            assert_eq!(op.nonzeros(), dense.iter().filter(|&&v| v != 0.0).count());
            assert!(op.memory_bytes() >= 12 * op.nonzeros());
            let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut out = vec![0.0; n];
            op.apply(&b, &mut out);
            for i in 0..n {
                let expected: f64 = (0..n).map(|j| dense[i * n + j] * b[j]).sum();
                assert_close!(out[i], expected, 1e-12, "n = {n}, row {i}");
                for j in 0..n {
                    assert_eq!(op.get(i, j), dense[i * n + j]);
                }
            }
        }
    }

    #[test]
    fn the_transpose_holds_the_columns_and_gathers_them() {
        let mut rng = flatland_testkit::rng(5);
        for (n, fill) in [(1, 1.0), (70, 0.2), (300, 0.03)] {
            let dense = random(n, fill, 10 + n as u64);
            let op = sparse_of(&dense, n);
            let columns = op.transposed();
            assert_eq!(columns.nonzeros(), op.nonzeros());
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(columns.get(j, i), dense[i * n + j], "K[{i}][{j}]");
                }
                let (rows, _) = columns.row(i);
                assert!(rows.windows(2).all(|w| w[0] < w[1]), "column {i} ascends");
            }
            // K x for an x non-zero on a few elements, by its columns, is the product.
            let picked: Vec<(u32, f64)> = (0..n)
                .filter_map(|j| {
                    let w = rng.random_range(-1.0..1.0);
                    (rng.random_range(0.0..1.0) < 0.1).then_some((j as u32, w))
                })
                .collect();
            let mut x = vec![0.0; n];
            for &(j, w) in &picked {
                x[j as usize] = w;
            }
            let mut expected = vec![0.0; n];
            op.apply(&x, &mut expected);
            let mut gathered = vec![0.0; n];
            let read = columns.gather_columns(&picked, &mut gathered);
            let held: usize = picked
                .iter()
                .map(|&(j, _)| columns.row(j as usize).0.len())
                .sum();
            assert_eq!(read, held);
            for i in 0..n {
                assert_close!(gathered[i], expected[i], 1e-12, "n = {n}, row {i}");
            }
        }
    }

    #[test]
    fn assembly_stops_and_refuses_non_finite_entries() {
        let err = SparseOperator::assemble(500, || (), |_, _, out| out.push((0, 1.0)), &|| true)
            .unwrap_err();
        assert!(matches!(err, SolveError::Interrupted), "{err}");
        let err = SparseOperator::assemble(
            100,
            || (),
            |i, _, out| {
                out.push((1, 0.5));
                if i == 70 {
                    out.push((3, f64::INFINITY));
                }
            },
            &never,
        )
        .unwrap_err();
        assert!(err.to_string().contains("row 70, column 3"), "{err}");
    }
}
