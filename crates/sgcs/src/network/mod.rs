//! The network type: its state, its construction and the small accessors.

mod active;
mod cells;
mod counters;
mod gate;
mod grow;
mod invariants;
mod persist;
mod query;
mod step;

use serde::{Deserialize, Serialize};

use self::cells::{Cells, SavedCells};
use self::step::Scratch;
use crate::index::Index;
use crate::{Params, SgcsError};

pub use self::gate::{Gate, Open};
pub use self::persist::FORMAT_VERSION;
pub use self::step::StepOutcome;

/// A cell's index. Stable: cells are never removed, a new cell gets id `len() - 1`.
pub type CellId = usize;

/// Dimension `k` of the simplices the cell graph is made of (triangles).
pub const SIMPLEX_DIM: usize = 2;

/// Widths are floored here so `M_c` stays defined when cells coincide (`0/0`).
const MIN_WIDTH: f64 = 1e-100;

/// Largest magnitude accepted in inputs and targets: squares stay finite.
const MAX_ABS_VALUE: f64 = 1e100;

/// A supervised growing cell structures network `Rⁿ → Rᵐ`. See the crate docs.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "persist::NetworkData", into = "persist::NetworkData")]
pub struct Network {
    params: Params,
    n: usize,
    m: usize,
    /// Every cell's position, output weight, neighbours, width and counters.
    cells: Cells,
    /// Triangles, each sorted ascending.
    tris: Vec<[CellId; 3]>,
    steps: u64,
    /// Cells whose position or width changed in the last step.
    changed: Vec<CellId>,
    /// Cells whose position changed in the last step (a subset of `changed`).
    moved: Vec<CellId>,
    index: Index,
    scratch: Scratch,
}

fn check_values(what: &'static str, v: &[f64], expected: usize) -> Result<(), SgcsError> {
    if v.len() != expected {
        return Err(SgcsError::Dimension {
            what,
            expected,
            got: v.len(),
        });
    }
    match v.iter().find(|x| x.is_nan() || x.abs() > MAX_ABS_VALUE) {
        Some(&value) => Err(SgcsError::NonFinite { what, value }),
        None => Ok(()),
    }
}

impl Network {
    /// A network of one triangle with corners `simplex` (`k + 1 = 3` points of length
    /// `input_dim`, distinct), zero output weights and empty counters.
    pub fn new(
        params: Params,
        input_dim: usize,
        output_dim: usize,
        simplex: &[Vec<f64>],
    ) -> Result<Network, SgcsError> {
        params.validate()?;
        if input_dim == 0 || output_dim == 0 {
            return Err(SgcsError::InvalidSimplex(format!(
                "input_dim ({input_dim}) and output_dim ({output_dim}) must be at least 1"
            )));
        }
        if simplex.len() != SIMPLEX_DIM + 1 {
            return Err(SgcsError::InvalidSimplex(format!(
                "needs {} points, got {}",
                SIMPLEX_DIM + 1,
                simplex.len()
            )));
        }
        let mut pos = Vec::with_capacity(3 * input_dim);
        for p in simplex {
            check_values("simplex point", p, input_dim)?;
            pos.extend_from_slice(p);
        }
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            if simplex[a] == simplex[b] {
                return Err(SgcsError::InvalidSimplex(format!(
                    "points {a} and {b} coincide"
                )));
            }
        }
        let cells = SavedCells {
            pos,
            out: vec![0.0; 3 * output_dim],
            err_mean: vec![0.0; 3],
            cnt: vec![0.0; 3],
            stamp: vec![0; 3],
            worst: None,
        };
        Network::assemble(params, input_dim, output_dim, cells, vec![[0, 1, 2]], 0)
    }

    /// Builds the derived state (neighbours, widths, index) from the primary state.
    fn assemble(
        params: Params,
        n: usize,
        m: usize,
        cells: SavedCells,
        tris: Vec<[CellId; 3]>,
        steps: u64,
    ) -> Result<Network, SgcsError> {
        let cells = Cells::from_saved(cells, n, m, &tris)?;
        let index = Index::build(n, params.reach_sq().sqrt(), &cells.pos, &cells.width);
        Ok(Network {
            params,
            n,
            m,
            cells,
            tris,
            steps,
            changed: Vec::new(),
            moved: Vec::new(),
            index,
            scratch: Scratch::default(),
        })
    }

    pub(super) fn rebuild_index(&mut self) {
        let reach = self.params.reach_sq().sqrt();
        self.index = Index::build(self.n, reach, &self.cells.pos, &self.cells.width);
    }

    /// Recomputes `δ_c` from the cached edge lengths and widens the index's reach box for it.
    fn refresh_width(&mut self, c: CellId) {
        let w = self.cells.compute_width(c);
        self.cells.width[c] = w;
        let n = self.n;
        self.index
            .reach_to(c, &self.cells.pos[c * n..(c + 1) * n], w);
    }

    /// The learning parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Replaces the parameters (e.g. live from a viewer) after validating them.
    pub fn set_params(&mut self, p: Params) -> Result<(), SgcsError> {
        p.validate()?;
        let cutoff_changed = p.activation_cutoff != self.params.activation_cutoff;
        self.params = p;
        if cutoff_changed {
            self.rebuild_index(); // the reach boxes depend on the cutoff
        }
        Ok(())
    }

    /// `n`, the input dimension.
    pub fn input_dim(&self) -> usize {
        self.n
    }

    /// `m`, the output dimension.
    pub fn output_dim(&self) -> usize {
        self.m
    }

    /// The number of cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Always false: a network has at least one simplex. (For clippy's `len_without_is_empty`.)
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Learning steps taken so far.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// The cells whose position or width changed in the last step (ascending, with repeats
    /// removed; an inserted cell included): what a caller keeping per-cell data derived from
    /// positions and widths must refresh.
    pub fn changed_cells(&self) -> &[CellId] {
        &self.changed
    }

    /// The cells whose position changed in the last step (ascending; an inserted cell
    /// included): a subset of [`Network::changed_cells`], and all that a caller keeping per-cell
    /// data derived from positions alone must refresh.
    pub fn moved_cells(&self) -> &[CellId] {
        &self.moved
    }

    /// `w_c`, the cell's position.
    pub fn position(&self, c: CellId) -> &[f64] {
        &self.cells.pos[c * self.n..(c + 1) * self.n]
    }

    /// `v_c`, the cell's output weight.
    pub fn output(&self, c: CellId) -> &[f64] {
        &self.cells.out[c * self.m..(c + 1) * self.m]
    }

    /// Every output weight, cell-major: `v_c` is `outputs()[c · m..(c + 1) · m]`.
    pub fn outputs(&self) -> &[f64] {
        &self.cells.out
    }

    /// Every output weight, cell-major, to overwrite (the refit installs its solution).
    pub(crate) fn outputs_mut(&mut self) -> &mut [f64] {
        &mut self.cells.out
    }

    /// Sets `v_c` (e.g. the initial cells' weights to their samples' targets).
    pub fn set_output(&mut self, c: CellId, v: &[f64]) -> Result<(), SgcsError> {
        if c >= self.len() {
            return Err(SgcsError::Dimension {
                what: "cell id",
                expected: self.len(),
                got: c,
            });
        }
        check_values("output weight", v, self.m)?;
        self.cells.out[c * self.m..(c + 1) * self.m].copy_from_slice(v);
        Ok(())
    }

    /// `δ_c`, the mean length of the cell's edges (floored at `1e-100`).
    pub fn width(&self, c: CellId) -> f64 {
        self.cells.width[c]
    }

    /// Every edge `(a, b)` once, `a < b`, sorted.
    pub fn edges(&self) -> Vec<(CellId, CellId)> {
        let mut e = Vec::new();
        for (a, nb) in self.cells.nbrs.iter().enumerate() {
            e.extend(nb.iter().filter(|&&b| b > a).map(|&b| (a, b)));
        }
        e
    }

    /// Every triangle, corners ascending.
    pub fn triangles(&self) -> Vec<[CellId; 3]> {
        self.tris.clone()
    }

    /// The cell's topological neighbours, ascending.
    pub fn neighbours(&self, c: CellId) -> &[CellId] {
        &self.cells.nbrs[c]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{assert_close, unit_triangle};

    #[test]
    fn new_network_is_one_triangle() {
        let net = Network::new(Params::default(), 2, 1, &unit_triangle()).unwrap();
        assert_eq!(net.len(), 3);
        assert_eq!(net.triangles(), vec![[0, 1, 2]]);
        assert_eq!(net.edges(), vec![(0, 1), (0, 2), (1, 2)]);
        assert_close!(net.width(0), 1.0, 1e-15);
        assert_close!(net.width(1), (1.0 + 2f64.sqrt()) / 2.0, 1e-15);
        net.check_invariants().unwrap();
    }

    #[test]
    fn bad_construction_is_an_error() {
        let p = Params::default();
        assert!(Network::new(p, 2, 1, &unit_triangle()[..2]).is_err());
        let same = vec![vec![0.0, 0.0], vec![0.0, 0.0], vec![0.0, 1.0]];
        assert!(Network::new(p, 2, 1, &same).is_err());
        let nan = vec![vec![0.0, f64::NAN], vec![1.0, 0.0], vec![0.0, 1.0]];
        assert!(Network::new(p, 2, 1, &nan).is_err());
        assert!(Network::new(p, 3, 1, &unit_triangle()).is_err());
        let bad = Params { eta: 0.0, ..p };
        assert!(
            Network::new(bad, 2, 1, &unit_triangle())
                .unwrap_err()
                .to_string()
                .contains("eta")
        );
    }

    #[test]
    fn network_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Network>();
    }
}
