//! The exact operator by columns: column `j` of K holds the light element `j` sends to every
//! collocation point that sees it. Shooting light forward (what lands where from a lit
//! element) reads columns; gathering it (the adjoint) reads the operator's rows.

use flatland_solve::SparseOperator;

/// K in compressed columns (rows ascending in each column), a transposed copy of a
/// [`SparseOperator`]'s rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Columns {
    /// Column `j` is `rows[starts[j]..starts[j + 1]]`.
    starts: Vec<usize>,
    rows: Vec<u32>,
    values: Vec<f64>,
}

impl Columns {
    /// The columns of `operator`: two passes over its rows, linear in its non-zero numbers.
    #[must_use]
    pub fn of(operator: &SparseOperator) -> Columns {
        use flatland_solve::TransferOperator as _;
        let n = operator.len();
        let mut starts = vec![0usize; n + 1];
        for i in 0..n {
            for &j in operator.row(i).0 {
                starts[j as usize + 1] += 1;
            }
        }
        for j in 0..n {
            starts[j + 1] += starts[j];
        }
        let mut next = starts.clone();
        let mut rows = vec![0u32; starts[n]];
        let mut values = vec![0.0; starts[n]];
        // Rows in ascending order, so each column's rows ascend.
        for i in 0..n {
            let (columns, row_values) = operator.row(i);
            for (&j, &v) in columns.iter().zip(row_values) {
                let at = next[j as usize];
                rows[at] = i as u32;
                values[at] = v;
                next[j as usize] += 1;
            }
        }
        Columns {
            starts,
            rows,
            values,
        }
    }

    /// Number of columns N.
    #[must_use]
    pub fn len(&self) -> usize {
        self.starts.len() - 1
    }

    /// Whether N = 0.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Column `j`: the rows that see element `j` (ascending) and `K_ij`.
    #[must_use]
    pub fn column(&self, j: usize) -> (&[u32], &[f64]) {
        let range = self.starts[j]..self.starts[j + 1];
        (&self.rows[range.clone()], &self.values[range])
    }

    /// Bytes held (indices and values).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        8 * self.starts.len() + 4 * self.rows.len() + 8 * self.values.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::Kernel;
    use flatland_solve::{Mesh, never, sweep_operator};

    #[test]
    fn columns_hold_the_entries_of_the_rows() {
        let kernel = Kernel::new(flatland_geom::bundled::scene("maze").unwrap());
        let mesh = Mesh::new(&kernel, 300).unwrap();
        let k = sweep_operator(&kernel, &mesh, &never).unwrap();
        let columns = Columns::of(&k);
        assert_eq!(columns.len(), mesh.len());
        let mut seen = 0;
        for j in 0..columns.len() {
            let (rows, values) = columns.column(j);
            assert!(
                rows.windows(2).all(|w| w[0] < w[1]),
                "column {j} not ascending"
            );
            for (&i, &v) in rows.iter().zip(values) {
                assert_eq!(k.get(i as usize, j), v, "K[{i}][{j}]");
            }
            seen += rows.len();
        }
        assert_eq!(seen, k.nonzeros());
    }
}
