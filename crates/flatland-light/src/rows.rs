//! The learned operator on the learner's mesh, row by row: the exact row where an element is
//! probed, elsewhere the blend of the rows its two bracketing probes' views give it, with the
//! part of each entry the two views disagree on (its *doubt*).
//!
//! Between probes `l` and `r`, at fraction `f` of the way, element `i` gets
//! `K_ij = (1 − f) K^l_ij + f K^r_ij`, where `K^p_i` is `i`'s row through what `p` saw (the
//! closed form from `y_i` over `p`'s stretches). Where the views agree this is the exact row
//! up to parallax; where they disagree, the view changes somewhere between `l` and `r`. If
//! that change lies anywhere in the gap with equal chance, the blend's expected error is
//! `2 f (1 − f) |K^l_ij − K^r_ij|`: the doubt. A blended row is bounded to `ρ_i` (a one-sided
//! receiver sees one half-plane, whose whole transfer is `ρ_i`): parallax may make two
//! borrowed stretches overlap as seen from `y_i`, and the operator must never gain energy.

use rayon::prelude::*;

use flatland_solve::TransferOperator;

/// Rows per rayon task.
const ROWS_PER_TASK: usize = 32;

/// One entry of a learned row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Entry {
    column: u32,
    value: f64,
    doubt: f64,
}

/// Every row of the learned operator, in compressed rows (a row's entries contiguous, columns
/// ascending): what a solve reads, row after row, many times per round.
#[derive(Clone, Debug)]
pub(crate) struct Rows {
    /// Row `i` is `entries[starts[i]..starts[i + 1]]`.
    starts: Vec<usize>,
    entries: Vec<Entry>,
}

impl Rows {
    /// `n` empty rows.
    pub(crate) fn new(n: usize) -> Rows {
        Rows {
            starts: vec![0; n + 1],
            entries: Vec::new(),
        }
    }

    /// Replaces the rows `updates` names (each row once, any order) in one pass over the
    /// entries.
    pub(crate) fn replace(&mut self, mut updates: Vec<(usize, Vec<Entry>)>) {
        if updates.is_empty() {
            return;
        }
        updates.sort_unstable_by_key(|u| u.0);
        let n = self.len();
        let grown: usize = updates.iter().map(|u| u.1.len()).sum();
        let mut starts = Vec::with_capacity(n + 1);
        let mut entries = Vec::with_capacity(self.entries.len() + grown);
        let mut next = updates.into_iter().peekable();
        for i in 0..n {
            starts.push(entries.len());
            match next.peek() {
                Some((j, _)) if *j == i => {
                    let (_, row) = next.next().expect("peeked");
                    entries.extend(row);
                }
                _ => entries.extend_from_slice(self.row(i)),
            }
        }
        starts.push(entries.len());
        *self = Rows { starts, entries };
    }

    fn row(&self, i: usize) -> &[Entry] {
        &self.entries[self.starts[i]..self.starts[i + 1]]
    }

    /// An exact row (`(j, K_ij)`, columns ascending): no doubt.
    pub(crate) fn exact(row: &[(u32, f64)]) -> Vec<Entry> {
        row.iter()
            .map(|&(column, value)| Entry {
                column,
                value,
                doubt: 0.0,
            })
            .collect()
    }

    /// The blend at fraction `f` of the rows `left` and `right` (columns ascending), bounded
    /// to a sum of `rho` (see the module docs).
    pub(crate) fn blend(rho: f64, f: f64, left: &[(u32, f64)], right: &[(u32, f64)]) -> Vec<Entry> {
        let (wl, wr, wd) = (1.0 - f, f, 2.0 * f * (1.0 - f));
        let mut out = Vec::with_capacity(left.len().max(right.len()));
        let (mut a, mut b) = (left.iter().peekable(), right.iter().peekable());
        loop {
            let (column, l, r) = match (a.peek(), b.peek()) {
                (Some(&&(j, x)), Some(&&(k, y))) if j == k => {
                    a.next();
                    b.next();
                    (j, x, y)
                }
                (Some(&&(j, x)), Some(&&(k, _))) if j < k => {
                    a.next();
                    (j, x, 0.0)
                }
                (Some(&&(j, x)), None) => {
                    a.next();
                    (j, x, 0.0)
                }
                (_, Some(&&(k, y))) => {
                    b.next();
                    (k, 0.0, y)
                }
                (None, None) => break,
            };
            out.push(Entry {
                column,
                value: wl * l + wr * r,
                doubt: wd * (l - r).abs(),
            });
        }
        let sum: f64 = out.iter().map(|e| e.value).sum();
        if sum > rho {
            let scale = rho / sum;
            for e in &mut out {
                e.value *= scale;
                e.doubt *= scale;
            }
        }
        out
    }

    /// Per row, the light its doubt leaves uncertain: `δ_i = Σ_j doubt_ij |b_j|`.
    pub(crate) fn doubt(&self, b: &[f64]) -> Vec<f64> {
        (0..self.len())
            .into_par_iter()
            .with_min_len(ROWS_PER_TASK)
            .map(|i| {
                self.row(i)
                    .iter()
                    .map(|e| e.doubt * b[e.column as usize].abs())
                    .sum()
            })
            .collect()
    }

    /// Whether any row has any doubt left.
    pub(crate) fn doubtful(&self) -> bool {
        self.entries.iter().any(|e| e.doubt > 0.0)
    }

    /// Bytes held.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.starts.capacity() * 8 + self.entries.capacity() * std::mem::size_of::<Entry>()
    }

    /// Non-zero entries.
    pub(crate) fn nonzeros(&self) -> usize {
        self.entries.len()
    }
}

impl TransferOperator for Rows {
    fn len(&self) -> usize {
        self.starts.len() - 1
    }

    fn apply(&self, b: &[f64], out: &mut [f64]) {
        out.par_iter_mut()
            .enumerate()
            .with_min_len(ROWS_PER_TASK)
            .for_each(|(i, o)| {
                *o = self
                    .row(i)
                    .iter()
                    .map(|e| e.value * b[e.column as usize])
                    .sum();
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn a_blend_of_equal_rows_is_that_row_without_doubt() {
        let row = [(1, 0.1), (4, 0.2), (7, 0.05)];
        let blended = Rows::blend(0.9, 0.3, &row, &row);
        assert_eq!(blended.len(), 3);
        for (e, &(j, v)) in blended.iter().zip(&row) {
            assert_eq!(e.column, j);
            assert_close!(e.value, v, 1e-15);
            assert_eq!(e.doubt, 0.0);
        }
    }

    #[test]
    fn a_blend_merges_columns_and_weighs_disagreement() {
        let left = [(1, 0.2), (3, 0.1)];
        let right = [(2, 0.3), (3, 0.1)];
        let b = Rows::blend(1.0, 0.25, &left, &right);
        let columns: Vec<u32> = b.iter().map(|e| e.column).collect();
        assert_eq!(columns, [1, 2, 3]);
        assert_close!(b[0].value, 0.15, 1e-15);
        assert_close!(b[1].value, 0.075, 1e-15);
        // 2 f (1 − f) = 0.375.
        assert_close!(b[0].doubt, 0.375 * 0.2, 1e-15);
        assert_close!(b[1].doubt, 0.375 * 0.3, 1e-15);
        assert_eq!(b[2].doubt, 0.0);
    }

    #[test]
    fn a_blend_never_gathers_more_than_rho() {
        let left = [(1, 0.5), (2, 0.4)];
        let right = [(1, 0.2), (3, 0.7)];
        let b = Rows::blend(0.8, 0.5, &left, &right);
        let sum: f64 = b.iter().map(|e| e.value).sum();
        assert!(sum <= 0.8 + 1e-15, "{sum}");
        assert!(b.iter().all(|e| e.value >= 0.0 && e.doubt >= 0.0));
    }

    #[test]
    fn apply_and_doubt_read_the_rows() {
        let mut rows = Rows::new(3);
        rows.replace(vec![
            (2, Rows::blend(1.0, 0.5, &[(0, 0.4)], &[(0, 0.0)])),
            (0, Rows::exact(&[(1, 0.5), (2, 0.25)])),
        ]);
        let mut out = vec![0.0; 3];
        rows.apply(&[1.0, 2.0, 4.0], &mut out);
        assert_eq!(out, [2.0, 0.0, 0.2]);
        let d = rows.doubt(&[1.0, -2.0, 4.0]);
        assert_eq!(d, [0.0, 0.0, 0.5 * 0.4]);
        assert!(rows.doubtful());
        assert_eq!(rows.nonzeros(), 3);
        rows.replace(vec![(2, Rows::exact(&[(1, 0.1)]))]);
        rows.apply(&[1.0, 2.0, 4.0], &mut out);
        assert_eq!(out, [2.0, 0.0, 0.2]);
        assert!(!rows.doubtful());
    }
}
