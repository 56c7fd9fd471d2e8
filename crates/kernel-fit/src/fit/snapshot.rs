//! What a fit reports while it runs: the learning curve, the cells' re-projected (s, t), and
//! cheap snapshots for progress displays and the viewer.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::Fit;
use flatland_solve::Representation;

/// A point of the learning curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HistoryPoint {
    /// Training steps so far.
    pub steps: u64,
    /// Rays cast so far.
    pub rays: u64,
    /// Cells.
    pub cells: usize,
    /// Training samples.
    pub samples: usize,
    /// Held-out relative L2 error (on the first ≤ 1024 held-out points).
    pub rel_l2_heldout: f64,
}

/// One cell as a viewer or a figure needs it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellSnapshot {
    /// Mean (s, t) of the samples the cell won; `None` until it has won one.
    pub st: Option<[f64; 2]>,
    /// δ_c, in the unit-box input frame.
    pub width: f64,
    /// Whether the cell is critical (`τ_c > ω · mean τ`).
    pub critical: bool,
    /// τ_c.
    pub resource: f64,
    /// The output weight v_c.
    pub output: f64,
}

/// A cheap copy of the fit's state for progress displays.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Snapshot {
    /// Training steps so far.
    pub steps: u64,
    /// Rays cast for training so far.
    pub rays: u64,
    /// The cells, indexed by cell id.
    pub cells: Vec<CellSnapshot>,
    /// The network's edges, as cell ids.
    pub edges: Vec<[u32; 2]>,
    /// Every training sample's (s, t) and the index of the set that produced it.
    pub samples: Vec<([f32; 2], u32)>,
    /// Number of sample sets (S₀ is set 0).
    pub sets: usize,
    /// The learning curve so far.
    pub history: Vec<HistoryPoint>,
}

/// Held-out points used for the learning curve (the final errors use all of them).
const HISTORY_HELDOUT: usize = 1024;

impl Fit {
    /// The learning curve so far.
    pub fn history(&self) -> &[HistoryPoint] {
        &self.state.history
    }

    /// Measures the held-out error of the model now and adds it to the learning curve.
    pub(super) fn record_history(&mut self) {
        let (points, values) = self.reference.heldout();
        let n = points.len().min(HISTORY_HELDOUT);
        let predicted: Vec<f64> = points[..n]
            .par_iter()
            .map(|&[s, t]| self.state.model.zeta(s, t))
            .collect();
        self.state.history.push(HistoryPoint {
            steps: self.steps(),
            rays: self.state.rays,
            cells: self.state.model.network.len(),
            samples: self.state.samples.len(),
            rel_l2_heldout: flatland_solve::relative_l2(&predicted, &values[..n]),
        });
    }

    /// The re-projected (s, t) of every cell (paper Fig. 3c); `None` for a cell that never won.
    pub fn cell_st(&self) -> Vec<Option<[f64; 2]>> {
        self.state
            .cell_stats
            .iter()
            .map(|c| (c.wins > 0).then(|| [c.sum_s / c.wins as f64, c.sum_t / c.wins as f64]))
            .collect()
    }

    /// A cheap copy of the state for a progress display or the viewer.
    pub fn snapshot(&self) -> Snapshot {
        let net = &self.state.model.network;
        let critical = net.critical_cells(self.valid.live.omega);
        let st = self.cell_st();
        let cells = (0..net.len())
            .map(|c| CellSnapshot {
                st: st[c],
                width: net.width(c),
                critical: critical[c],
                resource: net.resource(c),
                output: net.output(c)[0],
            })
            .collect();
        let mut samples = Vec::with_capacity(self.state.samples.len());
        for (set, &start) in self.state.set_starts.iter().enumerate() {
            let end = self
                .state
                .set_starts
                .get(set + 1)
                .copied()
                .unwrap_or(self.state.samples.len());
            samples.extend(
                self.state.samples[start..end]
                    .iter()
                    .map(|s| ([s.st[0] as f32, s.st[1] as f32], set as u32)),
            );
        }
        Snapshot {
            steps: self.steps(),
            rays: self.state.rays,
            cells,
            edges: net
                .edges()
                .into_iter()
                .map(|(a, b)| [a as u32, b as u32])
                .collect(),
            samples,
            sets: self.state.set_starts.len(),
            history: self.state.history.clone(),
        }
    }
}
