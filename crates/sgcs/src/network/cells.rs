//! Per-cell storage: one array per quantity, side by side, grown only together by one `push`.

use std::ops::{Deref, DerefMut};

use serde::{Deserialize, Serialize};

use super::{CellId, MIN_WIDTH};
use crate::SgcsError;
use crate::index::dist_sq;

/// One per-cell array of [`Cells`]: read and written in place like a slice, but only
/// [`Cells::push`] can grow it, so the arrays always describe the same cells.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct PerCell<T>(Vec<T>);

impl<T> Deref for PerCell<T> {
    type Target = [T];
    #[inline]
    fn deref(&self) -> &[T] {
        &self.0
    }
}

impl<T> DerefMut for PerCell<T> {
    #[inline]
    fn deref_mut(&mut self) -> &mut [T] {
        &mut self.0
    }
}

/// Every cell's state in id order, one array per quantity (a struct of arrays: a step reads
/// a few quantities of many cells). Positions, output weights and worst samples are flat,
/// `n` or `m` values a cell; every other array has one entry a cell.
#[derive(Clone, Debug)]
pub(super) struct Cells {
    /// Positions `w_c`, `len · n`.
    pub(super) pos: PerCell<f64>,
    /// Output weights `v_c`, `len · m`.
    pub(super) out: PerCell<f64>,
    /// Sorted neighbour lists.
    pub(super) nbrs: PerCell<Vec<CellId>>,
    /// `|w_c − w_b|` for each `b` of `nbrs[c]`, in the same order (derived; kept up to date
    /// as cells move, so a width is a sum, not a square root per neighbour).
    pub(super) edge_len: PerCell<Vec<f64>>,
    /// Indices into the network's triangles per cell (derived).
    pub(super) cell_tris: PerCell<Vec<usize>>,
    /// `δ_c` (derived from `pos` and `nbrs`).
    pub(super) width: PerCell<f64>,
    /// `τ_err / τ_cnt`: the decayed mean squared error of the samples the cell won.
    pub(super) err_mean: PerCell<f64>,
    /// `τ_cnt` as of step `stamp[c]`.
    pub(super) cnt: PerCell<f64>,
    pub(super) stamp: PerCell<u64>,
    /// [`Insertion::WorstSample`](crate::Insertion::WorstSample): per cell the largest
    /// weighted squared error of a sample it won, as of step `worst_stamp[c]` (decayed like the
    /// counters), and that sample.
    pub(super) worst_err: PerCell<f64>,
    pub(super) worst_stamp: PerCell<u64>,
    pub(super) worst_in: PerCell<f64>,
    pub(super) worst_out: PerCell<f64>,
}

/// The per-cell worst samples of [`Insertion::WorstSample`](crate::Insertion::WorstSample), as
/// saved.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub(super) struct WorstSamples {
    pub(super) error: Vec<f64>,
    pub(super) stamp: Vec<u64>,
    pub(super) inputs: Vec<f64>,
    pub(super) targets: Vec<f64>,
}

/// The per-cell state a saved network keeps; everything else in [`Cells`] is derived from it
/// and the triangles.
pub(super) struct SavedCells {
    pub(super) pos: Vec<f64>,
    pub(super) out: Vec<f64>,
    pub(super) err_mean: Vec<f64>,
    pub(super) cnt: Vec<f64>,
    pub(super) stamp: Vec<u64>,
    /// Absent: all zero.
    pub(super) worst: Option<WorstSamples>,
}

impl Cells {
    /// The cells of `saved` (input dimension `n`, output dimension `m`) with their derived
    /// state: neighbour lists and triangle lists from `tris`, edge lengths and widths.
    pub(super) fn from_saved(
        saved: SavedCells,
        n: usize,
        m: usize,
        tris: &[[CellId; 3]],
    ) -> Result<Cells, SgcsError> {
        let len = saved.err_mean.len();
        let worst = saved.worst.unwrap_or_else(|| WorstSamples {
            error: vec![0.0; len],
            stamp: vec![0; len],
            inputs: vec![0.0; len * n],
            targets: vec![0.0; len * m],
        });
        if worst.error.len() != len
            || worst.stamp.len() != len
            || worst.inputs.len() != len * n
            || worst.targets.len() != len * m
        {
            return Err(SgcsError::Corrupt(
                "worst-sample arrays disagree in length".into(),
            ));
        }
        let (nbrs, cell_tris) = adjacency(len, tris)?;
        let mut cells = Cells {
            pos: PerCell(saved.pos),
            out: PerCell(saved.out),
            nbrs: PerCell(nbrs),
            edge_len: PerCell(vec![Vec::new(); len]),
            cell_tris: PerCell(cell_tris),
            width: PerCell(vec![MIN_WIDTH; len]),
            err_mean: PerCell(saved.err_mean),
            cnt: PerCell(saved.cnt),
            stamp: PerCell(saved.stamp),
            worst_err: PerCell(worst.error),
            worst_stamp: PerCell(worst.stamp),
            worst_in: PerCell(worst.inputs),
            worst_out: PerCell(worst.targets),
        };
        for c in 0..len {
            cells.edge_len[c] = cells.measure_edges(c, n);
            cells.width[c] = cells.compute_width(c);
        }
        Ok(cells)
    }

    /// The state a saved network keeps (the worst samples always included).
    pub(super) fn into_saved(self) -> SavedCells {
        SavedCells {
            pos: self.pos.0,
            out: self.out.0,
            err_mean: self.err_mean.0,
            cnt: self.cnt.0,
            stamp: self.stamp.0,
            worst: Some(WorstSamples {
                error: self.worst_err.0,
                stamp: self.worst_stamp.0,
                inputs: self.worst_in.0,
                targets: self.worst_out.0,
            }),
        }
    }

    /// The number of cells.
    #[inline]
    pub(super) fn len(&self) -> usize {
        self.width.len()
    }

    /// Appends a cell at `position` with neighbours `nbrs` and triangles `tris`, a zero output
    /// weight of `m` values, empty counters and no worst sample as of step `now`, and no edge
    /// lengths yet (width `1e-100`): the caller measures them once the neighbours know the
    /// cell. Returns the new cell's id.
    pub(super) fn push(
        &mut self,
        position: &[f64],
        m: usize,
        nbrs: Vec<CellId>,
        tris: Vec<usize>,
        now: u64,
    ) -> CellId {
        let id = self.len();
        self.pos.0.extend_from_slice(position);
        self.out.0.extend(std::iter::repeat_n(0.0, m));
        self.nbrs.0.push(nbrs);
        self.edge_len.0.push(Vec::new());
        self.cell_tris.0.push(tris);
        self.width.0.push(MIN_WIDTH);
        self.err_mean.0.push(0.0);
        self.cnt.0.push(0.0);
        self.stamp.0.push(now);
        self.worst_err.0.push(0.0);
        self.worst_stamp.0.push(now);
        self.worst_in
            .0
            .extend(std::iter::repeat_n(0.0, position.len()));
        self.worst_out.0.extend(std::iter::repeat_n(0.0, m));
        id
    }

    /// Whether every array has the length `len()` cells of input dimension `n` and output
    /// dimension `m` need.
    pub(super) fn check_lengths(&self, n: usize, m: usize) -> Result<(), String> {
        let len = self.len();
        if self.pos.len() != len * n
            || self.out.len() != len * m
            || self.nbrs.len() != len
            || self.cell_tris.len() != len
            || self.err_mean.len() != len
            || self.cnt.len() != len
            || self.stamp.len() != len
        {
            return Err("per-cell arrays disagree in length".into());
        }
        if self.worst_err.len() != len
            || self.worst_stamp.len() != len
            || self.worst_in.len() != len * n
            || self.worst_out.len() != len * m
        {
            return Err("worst-sample arrays disagree in length".into());
        }
        if self.edge_len.len() != len {
            return Err("edge lengths disagree in length".into());
        }
        Ok(())
    }

    /// The lengths of `c`'s edges (input dimension `n`), measured afresh (in `nbrs[c]`'s
    /// order).
    pub(super) fn measure_edges(&self, c: CellId, n: usize) -> Vec<f64> {
        let w = &self.pos[c * n..(c + 1) * n];
        self.nbrs[c]
            .iter()
            .map(|&b| dist_sq(w, &self.pos[b * n..(b + 1) * n]).sqrt())
            .collect()
    }

    /// `δ_c`: the mean length of `c`'s edges.
    #[inline]
    pub(super) fn compute_width(&self, c: CellId) -> f64 {
        let sum: f64 = self.edge_len[c].iter().sum();
        (sum / self.edge_len[c].len() as f64).max(MIN_WIDTH)
    }
}

/// Per cell: its neighbours (ascending), and the triangles it is a corner of.
type Adjacency = (Vec<Vec<CellId>>, Vec<Vec<usize>>);

/// The [`Adjacency`] of the triangles `tris` over `len` cells.
fn adjacency(len: usize, tris: &[[CellId; 3]]) -> Result<Adjacency, SgcsError> {
    let mut nbrs = vec![Vec::new(); len];
    let mut cell_tris = vec![Vec::new(); len];
    for (t, tri) in tris.iter().enumerate() {
        for &c in tri {
            if c >= len {
                return Err(SgcsError::Corrupt(format!(
                    "triangle {t} names cell {c} of {len}"
                )));
            }
            cell_tris[c].push(t);
        }
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            nbrs[tri[a]].push(tri[b]);
            nbrs[tri[b]].push(tri[a]);
        }
    }
    for l in &mut nbrs {
        l.sort_unstable();
        l.dedup();
    }
    Ok((nbrs, cell_tris))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_triangle() -> Cells {
        let saved = SavedCells {
            pos: vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0],
            out: vec![0.0; 3],
            err_mean: vec![0.0; 3],
            cnt: vec![0.0; 3],
            stamp: vec![0; 3],
            worst: None,
        };
        Cells::from_saved(saved, 2, 1, &[[0, 1, 2]]).unwrap()
    }

    #[test]
    fn derived_state_follows_the_triangles() {
        let cells = one_triangle();
        assert_eq!(cells.len(), 3);
        assert_eq!(&cells.nbrs[0], &[1, 2]);
        assert_eq!(&cells.cell_tris[2], &[0]);
        assert_eq!(cells.edge_len[1], vec![1.0, 2f64.sqrt()]);
        assert_eq!(cells.width[0], 1.0);
        cells.check_lengths(2, 1).unwrap();
    }

    #[test]
    fn push_grows_every_array_together() {
        let mut cells = one_triangle();
        let r = cells.push(&[0.5, 0.5], 1, vec![1, 2], vec![0], 7);
        assert_eq!((r, cells.len()), (3, 4));
        cells.check_lengths(2, 1).unwrap();
        assert_eq!(&cells.pos[6..], &[0.5, 0.5]);
        assert_eq!((cells.stamp[r], cells.worst_stamp[r]), (7, 7));
        assert_eq!((cells.out[r], cells.width[r]), (0.0, MIN_WIDTH));
        assert!(cells.edge_len[r].is_empty());
    }

    #[test]
    fn triangles_naming_missing_cells_are_corrupt() {
        let saved = one_triangle().into_saved();
        let err = Cells::from_saved(saved, 2, 1, &[[0, 1, 3]]).err().unwrap();
        assert!(err.to_string().contains("names cell 3"), "{err}");
    }
}
