//! The network: cells, topology, one learning step, growth, queries.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::index::{Index, dist_sq};
use crate::{InsertRule, Insertion, OutputMode, OutputRule, Params, Resource, SgcsError};

/// A cell's index. Stable: cells are never removed, a new cell gets id `len() - 1`.
pub type CellId = usize;

/// Dimension `k` of the simplices the cell graph is made of (triangles).
pub const SIMPLEX_DIM: usize = 2;

/// Version of the JSON format written by [`Network::to_json`].
pub const FORMAT_VERSION: u32 = 1;

const FORMAT_NAME: &str = "sgcs-network";

/// Widths are floored here so `M_c` stays defined when cells coincide (`0/0`).
pub(crate) const MIN_WIDTH: f64 = 1e-100;

/// Largest magnitude accepted in inputs and targets: squares stay finite.
const MAX_ABS_VALUE: f64 = 1e100;

/// Up to this many cells the active cells are found by scanning them all: a small network's
/// supports are wide, so a tree query visits most leaves anyway. Measured by `sgcs_step`
/// (four inputs, the paper's network), µs a step by the tree and by the scan: 6.9 and 5.7 at
/// 400 cells, 9.7 and 8.6 at 1000, 9.9 and 9.9 at 2000, 12.6 and 14.3 at 4000.
const SCAN_MAX_CELLS: usize = 1024;

/// Which cells may respond to, and learn from, one input.
///
/// A caller that knows where its target jumps (a discontinuity it can compute without a sample)
/// gives each query a gate that admits only the cells on the input's side of every such jump;
/// then no cell straddles one, and [`OutputMode::Normalized`] reproduces a piecewise constant
/// target exactly up to the jumps. A gated query uses only admitted cells: output, best
/// matching unit, weight updates and movement. When no admitted cell is active, the output
/// falls back to the ungated one (the network's best guess), the sample's error is booked on
/// the nearest cell (so growth goes there) and nothing moves or learns.
///
/// A gate may also **name** its cells ([`Gate::region`]): all the cells of the input's region,
/// ascending. Then exactly those respond, however far away — no spatial search and no
/// activation cutoff; with [`OutputMode::Normalized`] their weights are computed relative to
/// the nearest one (in `|ξ − w_c|² / δ_c²`), so the output never underflows to 0: a region
/// with one cell anywhere in it has that cell's value. Where the region has no cell, the
/// output is the normalised blend of [`Gate::fallback`] (if it names any cells) or the ungated
/// output.
pub trait Gate {
    /// Whether `cell` may respond to the input.
    fn admits(&self, cell: CellId) -> bool;
    /// True only for a gate that admits every cell (the paper's network, [`Open`]).
    fn is_open(&self) -> bool {
        false
    }
    /// Every admitted cell, ascending, when the caller keeps them by region.
    fn region(&self) -> Option<&[CellId]> {
        None
    }
    /// With [`Gate::region`]: the cells to blend when the region has none (ascending).
    fn fallback(&self) -> Option<&[CellId]> {
        None
    }
}

/// The gate that admits every cell: the ungated network.
#[derive(Clone, Copy, Debug, Default)]
pub struct Open;

impl Gate for Open {
    #[inline]
    fn admits(&self, _: CellId) -> bool {
        true
    }
    #[inline]
    fn is_open(&self) -> bool {
        true
    }
}

impl<F: Fn(CellId) -> bool> Gate for F {
    #[inline]
    fn admits(&self, cell: CellId) -> bool {
        self(cell)
    }
}

/// What one learning step did: the hook for callers keeping their own per-cell statistics.
#[derive(Clone, Copy, Debug)]
pub struct StepOutcome {
    /// The best matching unit of the sample (before the step moved it).
    pub bmu: CellId,
    /// `|ζ − κ(ξ)|²`, the error before the update.
    pub error_sq: f64,
    /// The cell inserted at the end of this step, if any (always `len() - 1`).
    pub inserted: Option<CellId>,
    /// Whether some admitted cell was active (always true ungated): the cells moved and learned.
    pub covered: bool,
}

/// A supervised growing cell structures network `Rⁿ → Rᵐ`. See the crate docs.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "NetworkData", into = "NetworkData")]
pub struct Network {
    params: Params,
    n: usize,
    m: usize,
    /// Positions `w_c`, `len · n`.
    pos: Vec<f64>,
    /// Output weights `v_c`, `len · m`.
    out: Vec<f64>,
    /// Sorted neighbour lists.
    nbrs: Vec<Vec<CellId>>,
    /// `|w_c − w_b|` for each `b` of `nbrs[c]`, in the same order (derived; kept up to date
    /// as cells move, so a width is a sum, not a square root per neighbour).
    edge_len: Vec<Vec<f64>>,
    /// Triangles, each sorted ascending.
    tris: Vec<[CellId; 3]>,
    /// Indices into `tris` per cell (derived).
    cell_tris: Vec<Vec<usize>>,
    /// `δ_c` (derived from `pos` and `nbrs`).
    width: Vec<f64>,
    /// `τ_err / τ_cnt`: the decayed mean squared error of the samples the cell won.
    err_mean: Vec<f64>,
    /// `τ_cnt` as of step `stamp[c]`.
    cnt: Vec<f64>,
    stamp: Vec<u64>,
    /// [`Insertion::WorstSample`]: per cell the largest weighted squared error of a sample it
    /// won, as of step `worst_stamp[c]` (decayed like the counters), and that sample.
    worst_err: Vec<f64>,
    worst_stamp: Vec<u64>,
    worst_in: Vec<f64>,
    worst_out: Vec<f64>,
    steps: u64,
    /// Cells whose position or width changed in the last step.
    changed: Vec<CellId>,
    /// Cells whose position changed in the last step (a subset of `changed`).
    moved: Vec<CellId>,
    index: Index,
    scratch: Scratch,
}

#[derive(Clone, Debug, Default)]
struct Scratch {
    stack: Vec<u32>,
    ids: Vec<u32>,
    found: Vec<(u32, f64)>,
    admitted: Vec<(u32, f64)>,
    kappa: Vec<f64>,
    touched: Vec<CellId>,
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

/// `(1 − α)^dt` without subnormals: values below `e^-700` are 0.
fn decay(ln_keep: f64, dt: u64) -> f64 {
    if dt == 0 {
        return 1.0;
    }
    let e = dt as f64 * ln_keep;
    if e < -700.0 { 0.0 } else { e.exp() }
}

/// `x`, or 0 when it is below `1e-300` (keeps counters clear of subnormal slow paths).
#[inline]
fn flush(x: f64) -> f64 {
    if x < 1e-300 { 0.0 } else { x }
}

/// `exp(−d²/δ²)`, 0 where it would be subnormal.
#[inline]
fn activation(d2: f64, width: f64) -> f64 {
    let a = d2 / (width * width);
    if a > 700.0 { 0.0 } else { (-a).exp() }
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
        let tris = vec![[0, 1, 2]];
        Network::assemble(
            params,
            input_dim,
            output_dim,
            pos,
            vec![0.0; 3 * output_dim],
            tris,
            vec![0.0; 3],
            vec![0.0; 3],
            vec![0; 3],
            None,
            0,
        )
    }

    /// Builds the derived state (neighbours, widths, index) from the primary state.
    #[allow(clippy::too_many_arguments)]
    fn assemble(
        params: Params,
        n: usize,
        m: usize,
        pos: Vec<f64>,
        out: Vec<f64>,
        tris: Vec<[CellId; 3]>,
        err_mean: Vec<f64>,
        cnt: Vec<f64>,
        stamp: Vec<u64>,
        worst: Option<WorstSamples>,
        steps: u64,
    ) -> Result<Network, SgcsError> {
        let len = err_mean.len();
        let worst = worst.unwrap_or_else(|| WorstSamples {
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
        let mut net = Network {
            params,
            n,
            m,
            pos,
            out,
            nbrs,
            edge_len: vec![Vec::new(); len],
            tris,
            cell_tris,
            width: vec![MIN_WIDTH; len],
            err_mean,
            cnt,
            stamp,
            worst_err: worst.error,
            worst_stamp: worst.stamp,
            worst_in: worst.inputs,
            worst_out: worst.targets,
            steps,
            changed: Vec::new(),
            moved: Vec::new(),
            index: Index::default(),
            scratch: Scratch::default(),
        };
        for c in 0..len {
            net.edge_len[c] = net.measure_edges(c);
            net.width[c] = net.compute_width(c);
        }
        net.index = Index::build(n, net.params.reach_sq().sqrt(), &net.pos, &net.width);
        Ok(net)
    }

    fn rebuild_index(&mut self) {
        let reach = self.params.reach_sq().sqrt();
        self.index = Index::build(self.n, reach, &self.pos, &self.width);
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
        self.width.len()
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

    /// One learning step on the sample `(xi, zeta)`, including an insertion every `λ` steps.
    ///
    /// # Panics
    /// If a length is wrong or a value is non-finite or beyond `1e100`; see [`Network::try_step`].
    pub fn step(&mut self, xi: &[f64], zeta: &[f64]) -> StepOutcome {
        self.try_step(xi, zeta)
            .unwrap_or_else(|e| panic!("sgcs step: {e}"))
    }

    /// [`Network::step`] that returns an error instead of panicking on a bad sample (and then
    /// leaves the network unchanged).
    pub fn try_step(&mut self, xi: &[f64], zeta: &[f64]) -> Result<StepOutcome, SgcsError> {
        self.try_step_gated(xi, zeta, 1.0, &Open)
    }

    /// One learning step on a sample with importance `weight` (its squared error counts
    /// `weight` times in the resource), using only the cells `gate` admits (see [`Gate`]).
    /// `try_step_gated(xi, zeta, 1.0, &Open)` is [`Network::try_step`].
    pub fn try_step_gated<G: Gate>(
        &mut self,
        xi: &[f64],
        zeta: &[f64],
        weight: f64,
        gate: &G,
    ) -> Result<StepOutcome, SgcsError> {
        check_values("xi", xi, self.n)?;
        check_values("zeta", zeta, self.m)?;
        if !(weight.is_finite() && (0.0..=MAX_ABS_VALUE).contains(&weight)) {
            return Err(SgcsError::NonFinite {
                what: "sample weight",
                value: weight,
            });
        }
        let m = self.m;
        self.steps += 1;
        let now = self.steps;
        self.index.tick();
        if self.index.wants_rebuild(self.len()) {
            self.rebuild_index();
        }
        let mut sc = std::mem::take(&mut self.scratch);

        // Best matching unit and the activations above the cutoff, in id order (or the
        // gate's region, weighted relative to its nearest cell).
        let (s, covered) = if let Some(region) = gate.region() {
            match self.nearest_in(xi, region) {
                Some(c) => {
                    self.region_weights(xi, region, &mut sc.found);
                    (c, true)
                }
                None => match gate.fallback().filter(|f| !f.is_empty()) {
                    Some(list) => {
                        self.region_weights(xi, list, &mut sc.found);
                        (self.index.nearest(xi, &self.pos, &mut sc.stack), false)
                    }
                    None => {
                        let (stack, ids, found) = (&mut sc.stack, &mut sc.ids, &mut sc.found);
                        (self.active_and_nearest(xi, stack, ids, found), false)
                    }
                },
            }
        } else if gate.is_open() {
            let (stack, ids, found) = (&mut sc.stack, &mut sc.ids, &mut sc.found);
            (self.active_and_nearest(xi, stack, ids, found), true)
        } else {
            self.collect_active(xi, &mut sc.stack, &mut sc.ids, &mut sc.found);
            sc.admitted.clear();
            sc.admitted
                .extend(sc.found.iter().filter(|e| gate.admits(e.0 as usize)));
            match self.nearest_of(xi, &sc.admitted) {
                Some(c) => {
                    std::mem::swap(&mut sc.found, &mut sc.admitted);
                    (c, true)
                }
                None => (self.index.nearest(xi, &self.pos, &mut sc.stack), false),
            }
        };

        // Output and error (against the ungated fallback where no admitted cell is active).
        sc.kappa.clear();
        sc.kappa.resize(m, 0.0);
        let (sum_m, sum_m2) = self.combine(&sc.found, &mut sc.kappa);
        let mut error_sq = 0.0;
        for j in 0..m {
            sc.kappa[j] = zeta[j] - sc.kappa[j]; // now the error ζ − κ
            error_sq += sc.kappa[j] * sc.kappa[j];
        }

        if covered {
            self.learn_outputs(s, zeta, &sc.found, &sc.kappa, sum_m, sum_m2);
        }

        // Resource counters of the BMU (everyone else decays lazily).
        let weighted = weight * error_sq;
        self.touch(s, weighted, now);
        if self.params.insertion == Insertion::WorstSample {
            self.remember_worst(s, weighted, xi, zeta, now);
        }

        // Move the BMU and its (admitted) neighbours; widths change for them and their
        // neighbours.
        sc.touched.clear();
        self.moved.clear();
        if covered {
            self.move_winners(s, xi, gate, &mut sc.touched);
        }
        self.changed.clear();
        self.changed.extend_from_slice(&sc.touched);
        self.scratch = sc;

        let inserted = if now.is_multiple_of(u64::from(self.params.lambda)) {
            self.insert(now)
        } else {
            None
        };
        Ok(StepOutcome {
            bmu: s,
            error_sq,
            inserted,
            covered,
        })
    }

    /// The output weights' update after a covered step: the winner towards the target
    /// ([`OutputRule::Local`]), or every active cell by the delta rule (normalised by default).
    /// `error` is ζ − κ.
    fn learn_outputs(
        &mut self,
        s: CellId,
        zeta: &[f64],
        found: &[(u32, f64)],
        error: &[f64],
        sum_m: f64,
        sum_m2: f64,
    ) {
        let m = self.m;
        if self.params.output_rule == OutputRule::Local {
            let v = &mut self.out[s * m..(s + 1) * m];
            for j in 0..m {
                v[j] += self.params.eta * (zeta[j] - v[j]);
            }
            return;
        }
        let gain = match (self.params.output_mode, self.params.output_rule) {
            // φ_c = M_c / Σ M sums to 1, so Σ φ² ≤ 1 and NLMS is the plain rule.
            (OutputMode::Normalized, _) if sum_m > 0.0 => self.params.eta / sum_m,
            (OutputMode::Normalized, _) => 0.0,
            (OutputMode::Sum, OutputRule::Normalized) => self.params.eta / sum_m2.max(1.0),
            (OutputMode::Sum, OutputRule::Plain) => self.params.eta,
            (OutputMode::Sum, OutputRule::Local) => unreachable!("handled above"),
        };
        for &(c, a) in found {
            let v = &mut self.out[c as usize * m..(c as usize + 1) * m];
            for j in 0..m {
                v[j] += gain * error[j] * a;
            }
        }
    }

    /// Moves the winner `s` and its admitted neighbours towards `xi`, and refreshes the widths
    /// of every cell whose width depends on them (listed in `touched`, sorted).
    fn move_winners<G: Gate>(
        &mut self,
        s: CellId,
        xi: &[f64],
        gate: &G,
        touched: &mut Vec<CellId>,
    ) {
        self.move_cell(s, xi, self.params.eps_b);
        self.moved.push(s);
        touched.push(s);
        // Every neighbour's width depends on s; a neighbour that moves also changes its own
        // neighbours' widths.
        touched.extend_from_slice(&self.nbrs[s]);
        for i in 0..self.nbrs[s].len() {
            let b = self.nbrs[s][i];
            if !gate.admits(b) {
                continue;
            }
            self.move_cell(b, xi, self.params.eps_n);
            if self.params.eps_n > 0.0 {
                self.moved.push(b);
            }
            touched.extend_from_slice(&self.nbrs[b]);
        }
        self.moved.sort_unstable();
        touched.sort_unstable();
        touched.dedup();
        for &c in touched.iter() {
            self.refresh_width(c);
        }
    }

    /// The cell of `list` nearest to `xi` (lowest id on ties), if any.
    fn nearest_in(&self, xi: &[f64], list: &[CellId]) -> Option<CellId> {
        let n = self.n;
        let mut best: Option<(f64, CellId)> = None;
        for &c in list {
            let d2 = dist_sq(&self.pos[c * n..(c + 1) * n], xi);
            if best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, c));
            }
        }
        best.map(|b| b.1)
    }

    /// The weights of the cells of `list` at `xi` into `out`: their activations, or for
    /// [`OutputMode::Normalized`] their activations divided by the largest one (the same
    /// normalised output, without underflow however far the cells are).
    fn region_weights(&self, xi: &[f64], list: &[CellId], out: &mut Vec<(u32, f64)>) {
        let n = self.n;
        out.clear();
        out.extend(list.iter().map(|&c| {
            let d2 = dist_sq(&self.pos[c * n..(c + 1) * n], xi);
            let w = self.width[c];
            (c as u32, d2 / (w * w))
        }));
        let shift = match self.params.output_mode {
            OutputMode::Normalized => out.iter().map(|e| e.1).fold(f64::INFINITY, f64::min),
            OutputMode::Sum => 0.0,
        };
        for e in out.iter_mut() {
            let a = e.1 - shift;
            e.1 = if a > 700.0 { 0.0 } else { (-a).exp() };
        }
    }

    /// The cell of `list` nearest to `xi` (lowest id on ties), if any.
    fn nearest_of(&self, xi: &[f64], list: &[(u32, f64)]) -> Option<CellId> {
        let n = self.n;
        let mut best: Option<(f64, CellId)> = None;
        for &(c, _) in list {
            let c = c as usize;
            let d2 = dist_sq(&self.pos[c * n..(c + 1) * n], xi);
            if best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, c));
            }
        }
        best.map(|b| b.1)
    }

    /// The output of the active cells `list` into `out` (zeroed by the caller) by the output
    /// mode; returns `(Σ M_c, Σ M_c²)`.
    #[inline]
    fn combine(&self, list: &[(u32, f64)], out: &mut [f64]) -> (f64, f64) {
        let m = self.m;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for &(c, a) in list {
            let v = &self.out[c as usize * m..(c as usize + 1) * m];
            for j in 0..m {
                out[j] += v[j] * a;
            }
            sum += a;
            sum2 += a * a;
        }
        if self.params.output_mode == OutputMode::Normalized && sum > 0.0 {
            for o in out.iter_mut() {
                *o /= sum;
            }
        }
        (sum, sum2)
    }

    /// Keeps the sample with the largest weighted squared error `c` has won (decayed).
    fn remember_worst(&mut self, c: CellId, e2: f64, xi: &[f64], zeta: &[f64], now: u64) {
        let (n, m) = (self.n, self.m);
        let held = self.worst_err[c] * decay(self.ln_keep(), now - self.worst_stamp[c]);
        if e2 > 0.0 && e2 >= held {
            self.worst_err[c] = flush(e2);
            self.worst_stamp[c] = now;
            self.worst_in[c * n..(c + 1) * n].copy_from_slice(xi);
            self.worst_out[c * m..(c + 1) * m].copy_from_slice(zeta);
        }
    }

    fn move_cell(&mut self, c: CellId, xi: &[f64], rate: f64) {
        if rate == 0.0 {
            return;
        }
        let n = self.n;
        let w = &mut self.pos[c * n..(c + 1) * n];
        for d in 0..n {
            w[d] += rate * (xi[d] - w[d]);
        }
        self.index.moved(c, &self.pos[c * n..(c + 1) * n]);
        // Each length is measured once and stored at both ends (|a − b| = |b − a| exactly).
        for k in 0..self.nbrs[c].len() {
            let b = self.nbrs[c][k];
            let length =
                dist_sq(&self.pos[c * n..(c + 1) * n], &self.pos[b * n..(b + 1) * n]).sqrt();
            self.edge_len[c][k] = length;
            let j = self.nbrs[b]
                .binary_search(&c)
                .unwrap_or_else(|_| unreachable!("neighbour lists are symmetric"));
            self.edge_len[b][j] = length;
        }
    }

    /// The lengths of `c`'s edges, measured afresh (in `nbrs[c]`'s order).
    fn measure_edges(&self, c: CellId) -> Vec<f64> {
        let n = self.n;
        let w = &self.pos[c * n..(c + 1) * n];
        self.nbrs[c]
            .iter()
            .map(|&b| dist_sq(w, &self.pos[b * n..(b + 1) * n]).sqrt())
            .collect()
    }

    /// `δ_c`: the mean length of `c`'s edges.
    fn compute_width(&self, c: CellId) -> f64 {
        let sum: f64 = self.edge_len[c].iter().sum();
        (sum / self.edge_len[c].len() as f64).max(MIN_WIDTH)
    }

    fn refresh_width(&mut self, c: CellId) {
        let w = self.compute_width(c);
        self.width[c] = w;
        let n = self.n;
        self.index.reach_to(c, &self.pos[c * n..(c + 1) * n], w);
    }

    fn ln_keep(&self) -> f64 {
        (-self.params.alpha).ln_1p()
    }

    /// `τ_cnt` of `c` decayed to step `now`.
    fn count_at(&self, c: CellId, now: u64) -> f64 {
        flush(self.cnt[c] * decay(self.ln_keep(), now.saturating_sub(self.stamp[c])))
    }

    /// Adds one sample with squared error `e2` to `c`'s counters at step `now`.
    fn touch(&mut self, c: CellId, e2: f64, now: u64) {
        let cnt = self.count_at(c, now) + 1.0;
        self.err_mean[c] = flush(self.err_mean[c] + (flush(e2) - self.err_mean[c]) / cnt);
        self.cnt[c] = cnt;
        self.stamp[c] = now;
    }

    /// Puts the active cells `(c, M_c(xi))` into `found`, sorted by id: by a scan in a small
    /// network, else through the spatial index. Both give the same list.
    fn collect_active(
        &self,
        xi: &[f64],
        stack: &mut Vec<u32>,
        ids: &mut Vec<u32>,
        found: &mut Vec<(u32, f64)>,
    ) {
        if self.len() <= SCAN_MAX_CELLS {
            self.scan_active(xi, found);
        } else {
            self.tree_active(xi, stack, ids, found);
        }
    }

    /// [`collect_active`](Self::collect_active), and returns the nearest cell (the lowest id
    /// on ties): in a small network one scan finds both.
    fn active_and_nearest(
        &self,
        xi: &[f64],
        stack: &mut Vec<u32>,
        ids: &mut Vec<u32>,
        found: &mut Vec<(u32, f64)>,
    ) -> CellId {
        if self.len() <= SCAN_MAX_CELLS {
            self.scan_active(xi, found)
        } else {
            self.tree_active(xi, stack, ids, found);
            self.index.nearest(xi, &self.pos, stack)
        }
    }

    /// [`collect_active`](Self::collect_active) through the spatial index.
    fn tree_active(
        &self,
        xi: &[f64],
        stack: &mut Vec<u32>,
        ids: &mut Vec<u32>,
        found: &mut Vec<(u32, f64)>,
    ) {
        ids.clear();
        found.clear();
        let reach_sq = self.params.reach_sq();
        self.index
            .within(xi, &self.pos, &self.width, reach_sq, stack, ids);
        // Id order makes every sum independent of the index's shape (and equal to the scan).
        // Long lists are ordered through a bit set (in `stack`'s storage, free after the
        // traversal), which is several times cheaper than sorting them.
        if ids.len() > 32 {
            stack.clear();
            stack.resize(self.len().div_ceil(32), 0);
            let (mut lo, mut hi) = (usize::MAX, 0);
            for &c in ids.iter() {
                let w = c as usize / 32;
                stack[w] |= 1 << (c % 32);
                lo = lo.min(w);
                hi = hi.max(w);
            }
            ids.clear();
            for w in lo..=hi {
                let mut bits = stack[w];
                while bits != 0 {
                    ids.push(w as u32 * 32 + bits.trailing_zeros());
                    bits &= bits - 1;
                }
            }
        } else {
            ids.sort_unstable();
        }
        let n = self.n;
        found.extend(ids.iter().map(|&c| {
            let ci = c as usize;
            let d2 = dist_sq(&self.pos[ci * n..(ci + 1) * n], xi);
            (c, activation(d2, self.width[ci]))
        }));
    }

    /// [`collect_active`](Self::collect_active) by visiting every cell, in id order; returns
    /// the nearest cell (the lowest id on ties), as the index's nearest-cell search does.
    fn scan_active(&self, xi: &[f64], found: &mut Vec<(u32, f64)>) -> CellId {
        found.clear();
        let reach_sq = self.params.reach_sq();
        let n = self.n;
        let mut nearest = (f64::INFINITY, usize::MAX);
        for c in 0..self.len() {
            let d2 = dist_sq(&self.pos[c * n..(c + 1) * n], xi);
            if d2 < nearest.0 {
                nearest = (d2, c);
            }
            if crate::index::is_active(d2, self.width[c], reach_sq) {
                found.push((c as u32, activation(d2, self.width[c])));
            }
        }
        nearest.1
    }

    fn active(&self, xi: &[f64]) -> Vec<(u32, f64)> {
        assert_eq!(xi.len(), self.n, "sgcs: xi has the wrong length");
        let (mut stack, mut ids, mut found) = (Vec::new(), Vec::new(), Vec::new());
        self.collect_active(xi, &mut stack, &mut ids, &mut found);
        found
    }

    /// The active cells `(c, M_c(ξ))` (those at or above the activation cutoff), ascending by id.
    pub fn activations(&self, xi: &[f64]) -> Vec<(CellId, f64)> {
        self.active(xi)
            .into_iter()
            .map(|(c, a)| (c as CellId, a))
            .collect()
    }

    /// The network output `κ(ξ) = Σ_c v_c M_c(ξ)` (divided by `Σ_c M_c(ξ)` with
    /// [`OutputMode::Normalized`]) into `out` (length `m`).
    ///
    /// # Panics
    /// If `xi.len() != n` or `out.len() != m`.
    pub fn predict(&self, xi: &[f64], out: &mut [f64]) {
        self.predict_gated(xi, &Open, out);
    }

    /// `κ(ξ)` of a network with one output (the first output otherwise).
    ///
    /// # Panics
    /// If `xi.len() != n` (as every query taking `xi`).
    pub fn predict1(&self, xi: &[f64]) -> f64 {
        self.predict1_gated(xi, &Open)
    }

    /// `κ(ξ)` from the cells `gate` admits into `out`, falling back to the ungated output when
    /// none of them is active (see [`Gate`]). Returns the admitted cells' activation sum
    /// (0 when it fell back).
    ///
    /// # Panics
    /// If `xi.len() != n` or `out.len() != m`.
    pub fn predict_gated<G: Gate>(&self, xi: &[f64], gate: &G, out: &mut [f64]) -> f64 {
        assert_eq!(out.len(), self.m, "sgcs: output slice has the wrong length");
        assert_eq!(xi.len(), self.n, "sgcs: xi has the wrong length");
        out.fill(0.0);
        if let Some(region) = gate.region() {
            let mut weights = Vec::with_capacity(region.len());
            if !region.is_empty() {
                self.region_weights(xi, region, &mut weights);
                return self.combine(&weights, out).0;
            }
            match gate.fallback().filter(|f| !f.is_empty()) {
                Some(list) => self.region_weights(xi, list, &mut weights),
                None => weights = self.active(xi),
            }
            self.combine(&weights, out);
            return 0.0;
        }
        let mut active = self.active(xi);
        if !gate.is_open() {
            let all = active.len();
            active.retain(|e| gate.admits(e.0 as usize));
            if active.is_empty() && all > 0 {
                self.combine(&self.active(xi), out);
                return 0.0;
            }
        }
        self.combine(&active, out).0
    }

    /// [`Network::predict_gated`] of the first output.
    pub fn predict1_gated<G: Gate>(&self, xi: &[f64], gate: &G) -> f64 {
        let mut out = [0.0];
        if self.m == 1 {
            self.predict_gated(xi, gate, &mut out);
            return out[0];
        }
        let mut all = vec![0.0; self.m];
        self.predict_gated(xi, gate, &mut all);
        all[0]
    }

    /// The network activation `D_A(ξ) = Σ_c M_c(ξ)`.
    pub fn activation_sum(&self, xi: &[f64]) -> f64 {
        self.active(xi).iter().map(|e| e.1).sum()
    }

    /// `(D_A(ξ), D_ACC(ξ))`: the activation of all cells and of the cells flagged in `critical`
    /// (length `len()`, e.g. from [`Network::critical_cells`]), in one pass.
    ///
    /// # Panics
    /// If `critical.len() != len()` or `xi.len() != n`.
    pub fn activation_sums(&self, xi: &[f64], critical: &[bool]) -> (f64, f64) {
        self.activation_sums_gated(xi, critical, &Open)
    }

    /// [`Network::activation_sums`] over the cells `gate` admits only (no fallback: an input
    /// no admitted cell reaches has `D_A = 0`, it lies outside the network).
    ///
    /// # Panics
    /// If `critical.len() != len()` or `xi.len() != n`.
    pub fn activation_sums_gated<G: Gate>(
        &self,
        xi: &[f64],
        critical: &[bool],
        gate: &G,
    ) -> (f64, f64) {
        assert_eq!(
            critical.len(),
            self.len(),
            "sgcs: critical has the wrong length"
        );
        let mut all = 0.0;
        let mut crit = 0.0;
        let list = match gate.region() {
            Some(region) => {
                // True activations (no cutoff): a region's far cells count little.
                let n = self.n;
                region
                    .iter()
                    .map(|&c| {
                        let d2 = dist_sq(&self.pos[c * n..(c + 1) * n], xi);
                        (c as u32, activation(d2, self.width[c]))
                    })
                    .collect()
            }
            None => self.active(xi),
        };
        for (c, a) in list {
            if !gate.admits(c as usize) {
                continue;
            }
            all += a;
            if critical[c as usize] {
                crit += a;
            }
        }
        (all, crit)
    }

    /// The critical cells `τ_c > ω · mean(τ)` (none while every `τ` is 0).
    pub fn critical_cells(&self, omega: f64) -> Vec<bool> {
        let tau: Vec<f64> = (0..self.len()).map(|c| self.resource(c)).collect();
        let mean = tau.iter().sum::<f64>() / tau.len() as f64;
        tau.iter().map(|&t| t > omega * mean).collect()
    }

    /// The best matching unit `argmin_c |w_c − ξ|` (the lowest id on ties).
    pub fn bmu(&self, xi: &[f64]) -> CellId {
        assert_eq!(xi.len(), self.n, "sgcs: xi has the wrong length");
        self.index.nearest(xi, &self.pos, &mut Vec::new())
    }

    /// `w_c`, the cell's position.
    pub fn position(&self, c: CellId) -> &[f64] {
        &self.pos[c * self.n..(c + 1) * self.n]
    }

    /// `v_c`, the cell's output weight.
    pub fn output(&self, c: CellId) -> &[f64] {
        &self.out[c * self.m..(c + 1) * self.m]
    }

    /// Every output weight, cell-major: `v_c` is `outputs()[c · m..(c + 1) · m]`.
    pub fn outputs(&self) -> &[f64] {
        &self.out
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
        self.out[c * self.m..(c + 1) * self.m].copy_from_slice(v);
        Ok(())
    }

    /// `δ_c`, the mean length of the cell's edges (floored at `1e-100`).
    pub fn width(&self, c: CellId) -> f64 {
        self.width[c]
    }

    /// The resource: `τ_c = τ_err,c / τ_cnt,c · |F_c|` with `|F_c| = δ_c^k`, or `τ_err,c` for
    /// [`Resource::ErrorSum`] (0 for a cell never hit).
    pub fn resource(&self, c: CellId) -> f64 {
        match self.params.resource {
            Resource::MeanTimesVolume => self.err_mean[c] * self.volume(c),
            Resource::ErrorSum => self.err_mean[c] * self.count_at(c, self.steps),
        }
    }

    /// `τ_err,c / τ_cnt,c`: the decayed mean squared error of the samples `c` won.
    pub fn mean_error(&self, c: CellId) -> f64 {
        self.err_mean[c]
    }

    /// `|F_c| = δ_c^k`.
    fn volume(&self, c: CellId) -> f64 {
        self.width[c].powi(SIMPLEX_DIM as i32)
    }

    /// Every edge `(a, b)` once, `a < b`, sorted.
    pub fn edges(&self) -> Vec<(CellId, CellId)> {
        let mut e = Vec::new();
        for (a, nb) in self.nbrs.iter().enumerate() {
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
        &self.nbrs[c]
    }

    /// Inserts a cell on the longest edge of the cell with the largest resource.
    fn insert(&mut self, now: u64) -> Option<CellId> {
        if self.len() >= self.params.max_cells {
            return None;
        }
        let (n, m) = (self.n, self.m);
        // With insertion at the worst sample, only cells holding one compete (a cell whose
        // worst sample was just used waits for new errors); the largest resource wins. While no
        // cell holds one, every recent sample was predicted exactly: growth waits.
        let worst_only = self.params.insertion == Insertion::WorstSample;
        if worst_only && self.worst_err.iter().all(|&e| e == 0.0) {
            return None;
        }
        let mut q = 0;
        let mut best = f64::NEG_INFINITY;
        for c in 0..self.len() {
            if worst_only && self.worst_err[c] == 0.0 {
                continue;
            }
            let t = self.resource(c);
            if t > best {
                best = t;
                q = c;
            }
        }
        let wq = self.position(q).to_vec();
        let mut f = q;
        let mut longest = f64::NEG_INFINITY;
        for &b in &self.nbrs[q] {
            let l = dist_sq(&wq, self.position(b));
            if l > longest {
                longest = l;
                f = b;
            }
        }
        let r = self.len();
        let worst = (self.params.insertion == Insertion::WorstSample && self.worst_err[q] > 0.0)
            .then(|| {
                (
                    self.worst_in[q * n..(q + 1) * n].to_vec(),
                    self.worst_out[q * m..(q + 1) * m].to_vec(),
                )
            });
        self.worst_err[q] = 0.0;
        let wr: Vec<f64> = match &worst {
            Some((input, _)) => input.clone(),
            None => wq
                .iter()
                .zip(self.position(f))
                .map(|(a, b)| 0.5 * (a + b))
                .collect(),
        };
        // Triangles on the split edge and their third corners, in corner order.
        let mut opp: Vec<(CellId, usize)> = self.cell_tris[q]
            .iter()
            .filter(|&&t| self.tris[t].contains(&f))
            .map(|&t| {
                let c = self.tris[t].iter().copied().find(|&c| c != q && c != f);
                (c.unwrap_or(q), t)
            })
            .collect();
        opp.sort_unstable();
        let mut affected = vec![q, f];
        affected.extend(opp.iter().map(|e| e.0));
        let old_vol: Vec<f64> = affected.iter().map(|&c| self.volume(c)).collect();
        let old_tau: Vec<f64> = affected.iter().map(|&c| self.resource(c)).collect();
        let mut kappa_before = vec![0.0; m];
        if matches!(
            self.params.insert_rule,
            InsertRule::PreserveOutput | InsertRule::SampleTarget
        ) {
            self.predict(&wr, &mut kappa_before);
        }

        // Topology: q–f becomes q–r–f; each triangle q-f-c becomes q-r-c and r-f-c.
        self.nbrs[q].retain(|&b| b != f);
        self.nbrs[f].retain(|&b| b != q);
        let mut nr = vec![q, f];
        for &(c, t) in &opp {
            let t2 = self.tris.len();
            self.tris[t] = sorted3([q, r, c]);
            self.tris.push(sorted3([r, f, c]));
            self.cell_tris[f].retain(|&x| x != t);
            self.cell_tris[f].push(t2);
            self.cell_tris[c].push(t2);
            nr.push(c);
        }
        let mut rt: Vec<usize> = opp.iter().map(|e| e.1).collect();
        rt.extend(self.tris.len() - opp.len()..self.tris.len());
        self.cell_tris.push(rt);
        for &c in &nr {
            self.nbrs[c].push(r); // r is the largest id: lists stay sorted
        }
        nr.sort_unstable();
        self.nbrs.push(nr);
        self.edge_len.push(Vec::new());

        // The new cell's primary state, then widths.
        self.pos.extend_from_slice(&wr);
        // Edge lengths of every cell whose neighbour list changed (q, f, the opposite cells,
        // all neighbours of r) and of r.
        for i in 0..self.nbrs[r].len() {
            let c = self.nbrs[r][i];
            self.edge_len[c] = self.measure_edges(c);
        }
        self.edge_len[r] = self.measure_edges(r);
        self.out.extend(std::iter::repeat_n(0.0, m));
        self.err_mean.push(0.0);
        self.cnt.push(0.0);
        self.stamp.push(now);
        self.worst_err.push(0.0);
        self.worst_stamp.push(now);
        self.worst_in.extend(std::iter::repeat_n(0.0, n));
        self.worst_out.extend(std::iter::repeat_n(0.0, m));
        self.width.push(MIN_WIDTH);
        self.width[r] = self.compute_width(r);
        self.index
            .insert(r, q, &self.pos[r * n..(r + 1) * n], self.width[r]);
        for &c in &affected {
            self.refresh_width(c);
        }
        self.changed.extend_from_slice(&affected);
        self.changed.push(r);
        self.changed.sort_unstable();
        self.changed.dedup();
        self.moved.push(r); // r is the largest id: the list stays sorted

        // Counters: a neighbour's τ = mean·|F| follows its new volume by itself, which is
        // exactly Δτ_c = (|F|new − |F|old)/|F|old · τ_c; r receives what they lose.
        let mut tau_r = 0.0;
        let mut cnt_r = 0.0;
        let mut lost_sum = 0.0;
        let mut weighted = vec![0.0; m];
        for (i, &c) in affected.iter().enumerate() {
            let new_vol = self.volume(c);
            tau_r -= (new_vol - old_vol[i]) / old_vol[i] * old_tau[i];
            cnt_r += (1.0 - new_vol / old_vol[i]).max(0.0) * self.count_at(c, now);
            let lost = (old_vol[i] - new_vol).max(0.0);
            lost_sum += lost;
            for j in 0..m {
                weighted[j] += lost * self.out[c * m + j];
            }
        }
        if worst.is_some() {
            // r sits where q's worst error was; that error is being dealt with, so q's mean
            // error starts over (its decayed count keeps the new mean cautious) and r starts
            // clean.
            self.err_mean[q] = 0.0;
        } else {
            self.err_mean[r] = flush(tau_r.max(0.0) / self.volume(r));
            self.cnt[r] = flush(cnt_r);
        }

        let v_r: Vec<f64> = match (self.params.insert_rule, worst) {
            (InsertRule::SampleTarget, Some((_, target))) => target,
            (InsertRule::PreserveOutput | InsertRule::SampleTarget, _)
                if self.params.output_mode == OutputMode::Normalized =>
            {
                // A normalised output at w_r is a weighted mean; giving r that mean keeps it.
                kappa_before
            }
            (InsertRule::PreserveOutput | InsertRule::SampleTarget, _) => {
                let mut after = vec![0.0; m];
                self.predict(&wr, &mut after);
                kappa_before
                    .iter()
                    .zip(&after)
                    .map(|(b, a)| b - a)
                    .collect()
            }
            (InsertRule::VolumeWeighted, _) if lost_sum > 0.0 => {
                weighted.iter().map(|w| w / lost_sum).collect()
            }
            (InsertRule::VolumeWeighted, _) => (0..m)
                .map(|j| 0.5 * (self.out[q * m + j] + self.out[f * m + j]))
                .collect(),
        };
        self.out[r * m..(r + 1) * m].copy_from_slice(&v_r);
        Some(r)
    }

    /// Checks the simplicial topology (every edge in one or two triangles, every triangle's edges
    /// present, no duplicates, symmetric sorted neighbour lists, Euler characteristic of a disk),
    /// finiteness of every value, cached widths and the spatial index.
    pub fn check_invariants(&self) -> Result<(), String> {
        let len = self.len();
        let (n, m) = (self.n, self.m);
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
        for (a, nb) in self.nbrs.iter().enumerate() {
            if nb.is_empty() {
                return Err(format!("cell {a} has no neighbour"));
            }
            if nb.windows(2).any(|w| w[0] >= w[1]) {
                return Err(format!("neighbours of {a} not strictly ascending: {nb:?}"));
            }
            for &b in nb {
                if b == a || b >= len {
                    return Err(format!("cell {a} has invalid neighbour {b}"));
                }
                if self.nbrs[b].binary_search(&a).is_err() {
                    return Err(format!("edge {a}-{b} is not symmetric"));
                }
            }
        }
        let mut edge_tris: BTreeMap<(CellId, CellId), u32> = BTreeMap::new();
        let mut seen = self.tris.clone();
        seen.sort_unstable();
        if seen.windows(2).any(|w| w[0] == w[1]) {
            return Err("duplicate triangle".into());
        }
        for (t, tri) in self.tris.iter().enumerate() {
            if !(tri[0] < tri[1] && tri[1] < tri[2] && tri[2] < len) {
                return Err(format!("triangle {t} is malformed: {tri:?}"));
            }
            for (a, b) in [(0, 1), (0, 2), (1, 2)] {
                let (a, b) = (tri[a], tri[b]);
                if self.nbrs[a].binary_search(&b).is_err() {
                    return Err(format!("triangle {t} {tri:?} lacks edge {a}-{b}"));
                }
                *edge_tris.entry((a, b)).or_default() += 1;
            }
            for &c in tri {
                if !self.cell_tris[c].contains(&t) {
                    return Err(format!("cell {c} does not list its triangle {t}"));
                }
            }
        }
        for (c, ts) in self.cell_tris.iter().enumerate() {
            if ts
                .iter()
                .any(|&t| t >= self.tris.len() || !self.tris[t].contains(&c))
            {
                return Err(format!("cell {c} lists a triangle it is not in"));
            }
        }
        let edges = self.edges();
        for e in &edges {
            match edge_tris.get(e) {
                Some(1 | 2) => {}
                other => {
                    return Err(format!(
                        "edge {e:?} is in {} triangles",
                        other.unwrap_or(&0)
                    ));
                }
            }
        }
        let euler = len as i64 - edges.len() as i64 + self.tris.len() as i64;
        if euler != 1 {
            return Err(format!("Euler characteristic {euler}, a disk has 1"));
        }
        if self.worst_err.len() != len
            || self.worst_stamp.len() != len
            || self.worst_in.len() != len * n
            || self.worst_out.len() != len * m
        {
            return Err("worst-sample arrays disagree in length".into());
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&self.pos)
            || !finite(&self.out)
            || !finite(&self.err_mean)
            || !finite(&self.cnt)
            || !finite(&self.worst_err)
            || !finite(&self.worst_in)
            || !finite(&self.worst_out)
        {
            return Err("a position, output weight, counter or worst sample is not finite".into());
        }
        if self
            .err_mean
            .iter()
            .chain(&self.cnt)
            .chain(&self.worst_err)
            .any(|&x| x < 0.0)
        {
            return Err("a counter is negative".into());
        }
        if self.edge_len.len() != len {
            return Err("edge lengths disagree in length".into());
        }
        for c in 0..len {
            if self.edge_len[c] != self.measure_edges(c) {
                return Err(format!("cached edge lengths of {c} are stale"));
            }
            let w = self.compute_width(c);
            if w != self.width[c] {
                return Err(format!(
                    "cached width of {c} is {}, actual {w}",
                    self.width[c]
                ));
            }
        }
        self.index.check(&self.pos, &self.width)
    }

    /// The network as versioned JSON (format version [`FORMAT_VERSION`]).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| panic!("sgcs: serialising failed: {e}"))
    }

    /// Reads [`Network::to_json`]'s output; refuses other format versions with a message and
    /// validates the whole network (parameters, values, topology).
    pub fn from_json(text: &str) -> Result<Network, SgcsError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| SgcsError::Format(e.to_string()))?;
        if value.get("format").and_then(|f| f.as_str()) != Some(FORMAT_NAME) {
            return Err(SgcsError::Format(format!(
                "not an {FORMAT_NAME} document (missing \"format\": \"{FORMAT_NAME}\")"
            )));
        }
        match value.get("version").and_then(|v| v.as_u64()) {
            Some(v) if v == u64::from(FORMAT_VERSION) => {}
            Some(found) => {
                return Err(SgcsError::UnsupportedVersion {
                    found,
                    supported: FORMAT_VERSION,
                });
            }
            None => return Err(SgcsError::Format("missing \"version\"".into())),
        }
        serde_json::from_value(value).map_err(|e| SgcsError::Corrupt(e.to_string()))
    }

    /// `collect_active` with caller-owned buffers (used by the refit).
    pub(crate) fn active_into(
        &self,
        xi: &[f64],
        stack: &mut Vec<u32>,
        ids: &mut Vec<u32>,
        found: &mut Vec<(u32, f64)>,
    ) {
        self.collect_active(xi, stack, ids, found);
    }

    pub(crate) fn out_flat_mut(&mut self) -> &mut Vec<f64> {
        &mut self.out
    }
}

fn sorted3(mut t: [CellId; 3]) -> [CellId; 3] {
    t.sort_unstable();
    t
}

/// The saved form: primary state only; everything derived is rebuilt and checked on load.
#[derive(Serialize, Deserialize)]
struct NetworkData {
    format: String,
    version: u32,
    params: Params,
    input_dim: usize,
    output_dim: usize,
    steps: u64,
    positions: Vec<f64>,
    outputs: Vec<f64>,
    triangles: Vec<[CellId; 3]>,
    error_mean: Vec<f64>,
    count: Vec<f64>,
    stamp: Vec<u64>,
    /// Only with [`Insertion::WorstSample`] (absent: all zero).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    worst: Option<WorstSamples>,
}

/// The per-cell worst samples of [`Insertion::WorstSample`], as saved.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct WorstSamples {
    error: Vec<f64>,
    stamp: Vec<u64>,
    inputs: Vec<f64>,
    targets: Vec<f64>,
}

impl From<Network> for NetworkData {
    fn from(net: Network) -> Self {
        NetworkData {
            format: FORMAT_NAME.to_string(),
            version: FORMAT_VERSION,
            params: net.params,
            input_dim: net.n,
            output_dim: net.m,
            steps: net.steps,
            positions: net.pos,
            outputs: net.out,
            triangles: net.tris,
            error_mean: net.err_mean,
            count: net.cnt,
            stamp: net.stamp,
            worst: (net.params.insertion == Insertion::WorstSample).then_some(WorstSamples {
                error: net.worst_err,
                stamp: net.worst_stamp,
                inputs: net.worst_in,
                targets: net.worst_out,
            }),
        }
    }
}

impl TryFrom<NetworkData> for Network {
    type Error = SgcsError;

    fn try_from(d: NetworkData) -> Result<Self, SgcsError> {
        if d.format != FORMAT_NAME {
            return Err(SgcsError::Format(format!("format is {:?}", d.format)));
        }
        if d.version != FORMAT_VERSION {
            return Err(SgcsError::UnsupportedVersion {
                found: u64::from(d.version),
                supported: FORMAT_VERSION,
            });
        }
        d.params.validate()?;
        let len = d.error_mean.len();
        if d.input_dim == 0
            || d.output_dim == 0
            || len < 3
            || len.checked_mul(d.input_dim) != Some(d.positions.len())
            || len.checked_mul(d.output_dim) != Some(d.outputs.len())
            || d.count.len() != len
            || d.stamp.len() != len
        {
            return Err(SgcsError::Corrupt("array lengths disagree".into()));
        }
        check_values("positions", &d.positions, d.positions.len())?;
        let net = Network::assemble(
            d.params,
            d.input_dim,
            d.output_dim,
            d.positions,
            d.outputs,
            d.triangles,
            d.error_mean,
            d.count,
            d.stamp,
            d.worst,
            d.steps,
        )?;
        net.check_invariants().map_err(SgcsError::Corrupt)?;
        Ok(net)
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::test_support::{
        assert_close, bump_distance, bump_ridge, relative_l2, ridge_distance, rng,
        unit_square_points,
    };

    fn unit_triangle() -> Vec<Vec<f64>> {
        vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]]
    }

    /// A network grown on uniform samples of `f` over the unit square.
    fn grown(params: Params, steps: usize, seed: u64, f: impl Fn(f64, f64) -> f64) -> Network {
        let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
        let mut r = rng(seed);
        for _ in 0..steps {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            net.step(&[x, y], &[f(x, y)]);
        }
        net
    }

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
    fn topology_holds_after_every_insertion() {
        let params = Params {
            lambda: 10,
            ..Params::default()
        };
        let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
        let mut r = rng(1);
        let mut insertions = 0;
        for _ in 0..5_000 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            let out = net.step(&[x, y], &[(x * 7.0).sin() * y]);
            if let Some(c) = out.inserted {
                insertions += 1;
                assert_eq!(c, net.len() - 1);
                net.check_invariants()
                    .unwrap_or_else(|e| panic!("after insertion {c}: {e}"));
            }
        }
        assert_eq!(insertions, 500);
        assert_eq!(net.len(), 503);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// Any sample stream, scale and λ: the simplicial topology holds after every insertion
        /// and the fast queries equal brute force.
        #[test]
        fn topology_and_queries_hold_for_any_stream(
            seed in 0u64..1_000_000,
            lambda in 1u32..20,
            log_scale in -6i32..7,
            dims in 2usize..5,
        ) {
            let scale = 10f64.powi(log_scale);
            let simplex: Vec<Vec<f64>> = (0..3)
                .map(|i| (0..dims).map(|d| if d == i { scale } else { 0.0 }).collect())
                .collect();
            let p = Params { lambda, ..Params::default() };
            let mut net = Network::new(p, dims, 1, &simplex).unwrap();
            let mut r = rng(seed);
            let (mut fast, mut brute) = (Vec::new(), Vec::new());
            let (mut stack, mut ids) = (Vec::new(), Vec::new());
            for _ in 0..400 {
                let xi: Vec<f64> = (0..dims).map(|_| r.random::<f64>() * scale).collect();
                let z = r.random::<f64>() - 0.5;
                if net.step(&xi, &[z]).inserted.is_some() {
                    net.check_invariants().map_err(proptest::test_runner::TestCaseError::fail)?;
                }
                net.tree_active(&xi, &mut stack, &mut ids, &mut fast);
                let nearest = net.scan_active(&xi, &mut brute);
                proptest::prop_assert_eq!(&fast, &brute);
                proptest::prop_assert_eq!(nearest, net.index.nearest(&xi, &net.pos, &mut stack));
            }
        }
    }

    #[test]
    fn same_seed_same_network() {
        let f = |x: f64, y: f64| (3.0 * x).cos() + y * y;
        let p = Params {
            lambda: 50,
            ..Params::default()
        };
        let a = grown(p, 20_000, 7, f);
        let b = grown(p, 20_000, 7, f);
        assert_eq!(a.to_json(), b.to_json());
        let c = grown(p, 20_000, 8, f);
        assert_ne!(a.to_json(), c.to_json());
    }

    #[test]
    fn save_load_gives_identical_predictions_and_training() {
        let f = |x: f64, y: f64| (3.0 * x).cos() + y * y;
        let p = Params {
            lambda: 50,
            ..Params::default()
        };
        let mut a = grown(p, 10_000, 3, f);
        let mut b = Network::from_json(&a.to_json()).unwrap();
        b.check_invariants().unwrap();
        let mut r = rng(99);
        for _ in 0..200 {
            let xi = [r.random::<f64>() * 1.2 - 0.1, r.random::<f64>() * 1.2 - 0.1];
            assert_eq!(a.predict1(&xi).to_bits(), b.predict1(&xi).to_bits());
            assert_eq!(a.bmu(&xi), b.bmu(&xi));
        }
        // Training on after loading stays bit-identical (the index is rebuilt, results are not).
        for _ in 0..3_000 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            a.step(&[x, y], &[f(x, y)]);
            b.step(&[x, y], &[f(x, y)]);
        }
        assert_eq!(a.to_json(), b.to_json());
    }

    #[test]
    fn load_refuses_other_versions_and_garbage() {
        let net = Network::new(Params::default(), 2, 1, &unit_triangle()).unwrap();
        let text = net.to_json().replace("\"version\":1", "\"version\":2");
        let err = Network::from_json(&text).unwrap_err().to_string();
        assert!(
            err.contains("version 2") && err.contains("version 1"),
            "{err}"
        );
        assert!(Network::from_json("{}").is_err());
        assert!(Network::from_json("not json").is_err());
        let broken = net.to_json().replace("[0,1,2]", "[0,1,7]");
        assert!(Network::from_json(&broken).is_err());
    }

    #[test]
    fn fast_queries_equal_brute_force() {
        let f = |x: f64, y: f64| (5.0 * x).sin() * y + if x > 0.6 { 1.0 } else { 0.0 };
        let p = Params {
            lambda: 20,
            ..Params::default()
        };
        let net = grown(p, 30_000, 11, f);
        let mut r = rng(12);
        let (mut fast, mut brute) = (Vec::new(), Vec::new());
        let (mut stack, mut ids) = (Vec::new(), Vec::new());
        for _ in 0..2_000 {
            let xi = [r.random::<f64>() * 1.4 - 0.2, r.random::<f64>() * 1.4 - 0.2];
            net.tree_active(&xi, &mut stack, &mut ids, &mut fast);
            net.scan_active(&xi, &mut brute);
            assert_eq!(fast, brute);
            let nearest = (0..net.len())
                .min_by(|&a, &b| {
                    dist_sq(net.position(a), &xi).total_cmp(&dist_sq(net.position(b), &xi))
                })
                .unwrap();
            assert_eq!(net.bmu(&xi), nearest);
        }
    }

    #[test]
    fn learns_bump_and_ridge_and_concentrates_cells_on_the_ridge() {
        // The paper's defaults (λ = 300), uniform samples, held-out points never trained on.
        let held_out = unit_square_points(1234, 4_000);
        let mut net = Network::new(Params::default(), 2, 1, &unit_triangle()).unwrap();
        let mut r = rng(5);
        let mut errors = Vec::new();
        for cells in [50, 100, 200, 400] {
            while net.len() < cells {
                let (x, y) = (r.random::<f64>(), r.random::<f64>());
                net.step(&[x, y], &[bump_ridge(x, y)]);
            }
            let e = relative_l2(&held_out, |x, y| net.predict1(&[x, y]), bump_ridge);
            errors.push((cells, e));
        }
        // The error falls at every doubling of the network.
        for w in errors.windows(2) {
            assert!(w[1].1 < w[0].1, "error did not fall: {errors:?}");
        }
        // Bound: a uniform 20 x 20 grid of the same 400 cells, each holding the exact value at its
        // centre (piecewise constant, no learning noise), is the non-adaptive reference. SGCS
        // must beat it with the same cell budget (measured 0.21 vs 0.29).
        let k = 20usize;
        let grid = |x: f64, y: f64| {
            let i = ((x * k as f64) as usize).min(k - 1) as f64;
            let j = ((y * k as f64) as usize).min(k - 1) as f64;
            bump_ridge((i + 0.5) / k as f64, (j + 0.5) / k as f64)
        };
        let uniform = relative_l2(&held_out, grid, bump_ridge);
        let last = errors[3].1;
        assert!(
            last < 0.9 * uniform,
            "SGCS {last} vs uniform grid {uniform}"
        );
        // Cell density within 0.05 of the ridge vs on the flat part (far from ridge and bump),
        // each divided by its area (estimated on the held-out points).
        let near = |x: f64, y: f64| ridge_distance(x, y) < 0.05;
        let flat = |x: f64, y: f64| ridge_distance(x, y) > 0.2 && bump_distance(x, y) > 0.35;
        let count = |pred: &dyn Fn(f64, f64) -> bool| {
            (0..net.len())
                .filter(|&c| pred(net.position(c)[0], net.position(c)[1]))
                .count() as f64
        };
        let area = |pred: &dyn Fn(f64, f64) -> bool| {
            held_out.iter().filter(|p| pred(p[0], p[1])).count() as f64 / held_out.len() as f64
        };
        let near_density = count(&near) / area(&near);
        let flat_density = count(&flat) / area(&flat);
        assert!(
            near_density > 5.0 * flat_density,
            "ridge density {near_density} vs flat density {flat_density}"
        );
    }

    #[test]
    fn lazy_counters_equal_the_papers_eager_decay() {
        let params = Params {
            lambda: u32::MAX,
            alpha: 0.05,
            ..Params::default()
        };
        let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
        let keep = 1.0 - params.alpha;
        let (mut te, mut tc) = (vec![0.0f64; 3], vec![0.0f64; 3]);
        let mut r = rng(21);
        for _ in 0..3_000 {
            // Mostly near cell 0, so the others go long without a hit.
            let (x, y) = (r.random::<f64>().powi(4), r.random::<f64>().powi(4));
            let out = net.step(&[x, y], &[x - y]);
            for c in 0..3 {
                te[c] *= keep;
                tc[c] *= keep;
            }
            te[out.bmu] += out.error_sq;
            tc[out.bmu] += 1.0;
        }
        for c in 0..3 {
            if tc[c] > 0.0 {
                assert_close!(net.mean_error(c), te[c] / tc[c], 1e-9 * te[c] / tc[c]);
                assert_close!(net.count_at(c, net.steps), tc[c], 1e-9 * tc[c] + 1e-290);
            }
        }
    }

    #[test]
    fn counters_survive_long_idle_periods() {
        // ε_n = 0: cells 1 and 2 stay where they are while cell 0 wins everything.
        let params = Params {
            lambda: u32::MAX,
            eps_n: 0.0,
            ..Params::default()
        };
        let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
        net.step(&[1.0, 0.0], &[2.0]);
        assert_eq!(net.mean_error(1), 4.0);
        // 100 000 steps that only cell 0 wins: cell 1's count decays to exactly 0, never to a
        // subnormal, and its mean stays what it was.
        for _ in 0..100_000 {
            net.step(&[0.0, 0.0], &[0.0]);
        }
        assert_eq!(net.mean_error(1), 4.0);
        assert_eq!(net.count_at(1, net.steps), 0.0);
        let out = net.step(&[1.0, 0.0], &[2.0]);
        assert_eq!(out.bmu, 1);
        assert_close!(net.mean_error(1), out.error_sq, 0.0);
        for c in 0..net.len() {
            for v in [net.mean_error(c), net.cnt[c], net.resource(c)] {
                assert!(v == 0.0 || v.is_normal(), "cell {c}: {v}");
            }
        }
    }

    /// A network grown on the bump-and-ridge function, ready for a hand-triggered insertion.
    fn before_insertion(rule: InsertRule) -> Network {
        let p = Params {
            lambda: 100,
            insert_rule: rule,
            ..Params::default()
        };
        let mut net = grown(p, 15_000, 31, bump_ridge);
        net.set_params(Params {
            lambda: u32::MAX,
            ..p
        })
        .unwrap();
        let mut r = rng(32);
        for _ in 0..50 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            net.step(&[x, y], &[bump_ridge(x, y)]);
        }
        net
    }

    #[test]
    fn insertion_splits_the_longest_edge_of_the_worst_cell() {
        let mut net = before_insertion(InsertRule::PreserveOutput);
        let q = (0..net.len())
            .max_by(|&a, &b| net.resource(a).total_cmp(&net.resource(b)).then(b.cmp(&a)))
            .unwrap();
        let f = *net
            .neighbours(q)
            .iter()
            .max_by(|&&a, &&b| {
                dist_sq(net.position(q), net.position(a))
                    .total_cmp(&dist_sq(net.position(q), net.position(b)))
                    .then(b.cmp(&a))
            })
            .unwrap();
        let common: Vec<CellId> = net
            .triangles()
            .iter()
            .filter(|t| t.contains(&q) && t.contains(&f))
            .map(|t| t.iter().copied().find(|&c| c != q && c != f).unwrap())
            .collect();
        let wr: Vec<f64> = net
            .position(q)
            .iter()
            .zip(net.position(f))
            .map(|(a, b)| (a + b) / 2.0)
            .collect();
        let tau_before: f64 = (0..net.len()).map(|c| net.resource(c)).sum();
        let kappa_before = net.predict1(&wr);

        let r = net.insert(net.steps).unwrap();
        net.check_invariants().unwrap();
        assert_eq!(r, net.len() - 1);
        assert_eq!(net.position(r), &wr[..]);
        assert!(!net.neighbours(q).contains(&f));
        let mut expect = vec![q, f];
        expect.extend(&common);
        expect.sort_unstable();
        assert_eq!(net.neighbours(r), &expect[..]);
        assert_eq!(
            net.triangles().iter().filter(|t| t.contains(&r)).count(),
            2 * common.len()
        );
        // SOMToolbox redistribution: r receives what its neighbours lose, the total is kept
        // (unless the neighbours' net change was a gain, which is clamped).
        let tau_after: f64 = (0..net.len()).map(|c| net.resource(c)).sum();
        if net.resource(r) > 0.0 {
            assert_close!(tau_after, tau_before, 1e-12 * tau_before);
        }
        // The default weight rule leaves the output at the new centre unchanged.
        assert_close!(
            net.predict1(&wr),
            kappa_before,
            1e-12 * (1.0 + kappa_before.abs())
        );
    }

    #[test]
    fn volume_weighted_rule_is_a_convex_combination_of_the_neighbours() {
        let mut net = before_insertion(InsertRule::VolumeWeighted);
        let r = net.insert(net.steps).unwrap();
        let vs: Vec<f64> = net
            .neighbours(r)
            .iter()
            .map(|&c| net.output(c)[0])
            .collect();
        let (lo, hi) = vs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let v = net.output(r)[0];
        assert!(
            lo - 1e-12 <= v && v <= hi + 1e-12,
            "{v} outside [{lo}, {hi}]"
        );
    }

    #[test]
    fn preserve_rule_learns_at_least_as_well_as_volume_weighted() {
        // The reason for the default: same data, same growth, the output-preserving insertion
        // ends with the lower held-out error (measured 0.21 vs 0.23 at 400 cells, λ = 300).
        let held_out = unit_square_points(77, 2_000);
        let err = |rule| {
            let p = Params {
                lambda: 150,
                insert_rule: rule,
                ..Params::default()
            };
            let net = grown(p, 60_000, 5, bump_ridge);
            relative_l2(&held_out, |x, y| net.predict1(&[x, y]), bump_ridge)
        };
        let (preserve, volume) = (
            err(InsertRule::PreserveOutput),
            err(InsertRule::VolumeWeighted),
        );
        assert!(
            preserve < volume * 1.02,
            "preserve {preserve} vs volume-weighted {volume}"
        );
    }

    #[test]
    fn plain_rule_diverges_where_normalized_does_not() {
        // A grown network where cells overlap (Σ M_c² > 1), then a large but valid η = 1.5:
        // the paper's rule needs η Σ M² < 2 and blows up; the normalised rule cannot.
        let base = grown(
            Params {
                lambda: 50,
                ..Params::default()
            },
            10_000,
            41,
            bump_ridge,
        );
        let mut r = rng(42);
        let probe: Vec<[f64; 2]> = unit_square_points(43, 500);
        let max_sum_m2 = probe
            .iter()
            .map(|p| base.activations(p).iter().map(|e| e.1 * e.1).sum::<f64>())
            .fold(0.0, f64::max);
        assert!(
            1.5 * max_sum_m2 > 2.0,
            "not an overlapping network: max Σ M² = {max_sum_m2}"
        );
        let samples: Vec<[f64; 2]> = (0..20_000).map(|_| [r.random(), r.random()]).collect();
        let train = |rule| {
            let mut net = base.clone();
            net.set_params(Params {
                eta: 1.5,
                output_rule: rule,
                lambda: u32::MAX,
                ..*net.params()
            })
            .unwrap();
            let mut worst = 0.0f64;
            for p in &samples {
                net.step(p, &[bump_ridge(p[0], p[1])]);
                worst = (0..net.len())
                    .map(|c| net.output(c)[0].abs())
                    .fold(worst, f64::max);
                if worst.is_nan() || worst >= 1e12 {
                    break;
                }
            }
            worst
        };
        let plain = train(OutputRule::Plain);
        let normalized = train(OutputRule::Normalized);
        assert!(
            plain.is_nan() || plain >= 1e12,
            "plain rule stayed bounded: {plain}"
        );
        assert!(normalized < 100.0, "normalised rule grew to {normalized}");
    }

    #[test]
    fn spikes_in_zeta_stay_finite_bounded_and_fade() {
        let p = Params {
            lambda: 100,
            ..Params::default()
        };
        let mut net = Network::new(p, 2, 1, &unit_triangle()).unwrap();
        let mut r = rng(51);
        let held_out = unit_square_points(52, 1_000);
        let mut after_spikes = 0.0;
        for i in 0..40_000 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            // 40 targets of 10⁶ among values of order 1 during the first 20 000 steps.
            let z = if i % 500 == 250 && i < 20_000 {
                1e6
            } else {
                bump_ridge(x, y)
            };
            net.step(&[x, y], &[z]);
            if i % 5_000 == 0 {
                net.check_invariants().unwrap();
            }
            if i == 20_000 {
                after_spikes = relative_l2(&held_out, |x, y| net.predict1(&[x, y]), bump_ridge);
            }
        }
        net.check_invariants().unwrap();
        // A spike moves each weight by at most η·10⁶·M_c / max(1, Σ M²): bounded well below it.
        let max_v = (0..net.len())
            .map(|c| net.output(c)[0].abs())
            .fold(0.0, f64::max);
        assert!(max_v < 1e6, "weights reached {max_v}");
        // Once the spikes stop, the delta rule unlearns them (slowly: η = 0.1 and the slow
        // eigen-directions of overlapping cells; measured a factor ≈ 8 in 20 000 steps).
        let end = relative_l2(&held_out, |x, y| net.predict1(&[x, y]), bump_ridge);
        assert!(
            end.is_finite() && end < 0.5 * after_spikes,
            "{after_spikes} -> {end}"
        );
    }

    #[test]
    fn extreme_input_scales_learn_like_the_unit_scale() {
        let held_out = unit_square_points(61, 1_000);
        let run = |scale: f64| {
            let p = Params {
                lambda: 100,
                ..Params::default()
            };
            let simplex: Vec<Vec<f64>> = unit_triangle()
                .iter()
                .map(|v| v.iter().map(|x| x * scale).collect())
                .collect();
            let mut net = Network::new(p, 2, 1, &simplex).unwrap();
            let mut r = rng(62);
            for _ in 0..20_000 {
                let (x, y) = (r.random::<f64>(), r.random::<f64>());
                net.step(&[x * scale, y * scale], &[bump_ridge(x, y)]);
            }
            net.check_invariants().unwrap();
            relative_l2(
                &held_out,
                |x, y| net.predict1(&[x * scale, y * scale]),
                bump_ridge,
            )
        };
        let unit = run(1.0);
        for scale in [1e-6, 1e6] {
            let e = run(scale);
            assert!(
                e.is_finite() && e < 1.2 * unit,
                "scale {scale}: {e} vs {unit} at unit scale"
            );
        }
    }

    #[test]
    fn bad_samples_are_rejected_and_change_nothing() {
        let mut net = grown(
            Params {
                lambda: 50,
                ..Params::default()
            },
            2_000,
            71,
            bump_ridge,
        );
        let before = net.to_json();
        for (xi, z) in [
            (vec![f64::NAN, 0.0], vec![0.0]),
            (vec![0.0, f64::INFINITY], vec![0.0]),
            (vec![0.0, 0.0], vec![f64::NAN]),
            (vec![0.0, 0.0], vec![1e101]),
            (vec![0.0], vec![0.0]),
            (vec![0.0, 0.0], vec![0.0, 1.0]),
        ] {
            assert!(net.try_step(&xi, &z).is_err(), "{xi:?} {z:?} accepted");
        }
        assert_eq!(net.to_json(), before);
    }

    #[test]
    fn growth_stops_at_max_cells() {
        let p = Params {
            lambda: 10,
            max_cells: 40,
            ..Params::default()
        };
        let net = grown(p, 5_000, 81, bump_ridge);
        assert_eq!(net.len(), 40);
        net.check_invariants().unwrap();
    }

    #[test]
    fn cutoff_changes_results_by_less_than_its_bound() {
        let mut net = grown(
            Params {
                lambda: 50,
                ..Params::default()
            },
            20_000,
            91,
            bump_ridge,
        );
        let points = unit_square_points(92, 500);
        let with: Vec<f64> = points.iter().map(|p| net.predict1(p)).collect();
        let sum_abs_v: f64 = (0..net.len()).map(|c| net.output(c)[0].abs()).sum();
        let cutoff = net.params().activation_cutoff;
        net.set_params(Params {
            activation_cutoff: 0.0,
            ..*net.params()
        })
        .unwrap();
        for (p, w) in points.iter().zip(&with) {
            assert_close!(net.predict1(p), *w, cutoff * sum_abs_v);
            assert_eq!(net.activations(p).len(), net.len());
        }
        // A coarse cutoff: the index is rebuilt and still agrees with brute force.
        net.set_params(Params {
            activation_cutoff: 0.01,
            ..*net.params()
        })
        .unwrap();
        net.check_invariants().unwrap();
        let (mut stack, mut ids, mut fast, mut brute) = (vec![], vec![], vec![], vec![]);
        for p in &points {
            net.tree_active(p, &mut stack, &mut ids, &mut fast);
            net.scan_active(p, &mut brute);
            assert_eq!(fast, brute);
        }
    }

    #[test]
    fn activation_sums_match_their_definitions() {
        let net = grown(
            Params {
                lambda: 50,
                ..Params::default()
            },
            20_000,
            95,
            bump_ridge,
        );
        let critical = net.critical_cells(0.6);
        let tau: Vec<f64> = (0..net.len()).map(|c| net.resource(c)).collect();
        let mean = tau.iter().sum::<f64>() / tau.len() as f64;
        for c in 0..net.len() {
            assert_eq!(critical[c], tau[c] > 0.6 * mean);
        }
        assert!(critical.iter().any(|&c| c) && !critical.iter().all(|&c| c));
        for p in unit_square_points(96, 300) {
            let acts = net.activations(&p);
            let (da, dacc) = net.activation_sums(&p, &critical);
            let all: f64 = acts.iter().map(|e| e.1).sum();
            let crit: f64 = acts.iter().filter(|e| critical[e.0]).map(|e| e.1).sum();
            assert_eq!(da, all);
            assert_eq!(dacc, crit);
            assert_eq!(net.activation_sum(&p), da);
            let kappa: f64 = acts.iter().map(|&(c, a)| net.output(c)[0] * a).sum();
            assert_eq!(net.predict1(&p), kappa);
        }
    }

    #[test]
    fn multiple_outputs_learn_independently() {
        let p = Params {
            lambda: 100,
            ..Params::default()
        };
        let mut net = Network::new(p, 2, 2, &unit_triangle()).unwrap();
        let mut r = rng(97);
        for _ in 0..20_000 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            net.step(&[x, y], &[x + y, 1.0 - x]);
        }
        let mut out = [0.0; 2];
        net.predict(&[0.5, 0.5], &mut out);
        assert_close!(out[0], 1.0, 0.15);
        assert_close!(out[1], 0.5, 0.15);
        assert_eq!(net.predict1(&[0.5, 0.5]), out[0]);
    }

    /// The 10⁷-step soak: `cargo test --release -p sgcs -- --ignored soak` (one to four minutes).
    /// Phases restrict the samples to a corner for 10⁶ steps (the rest of the network idles),
    /// targets of 10⁶ hit every 100 003 steps for the first 8·10⁶ steps; the last 2·10⁶ steps
    /// are clean. Asserted: finite errors, invariants, bounded weights, counters never
    /// subnormal, and the spikes fading once they stop. (They fade slowly: the delta rule
    /// removes the smooth part of a spike's imprint fast and the part in the ill-conditioned
    /// directions of overlapping Gaussians only like a power law; measured 0.2 → ~300 during
    /// spikes, ~28 after 2·10⁶ clean steps. `refit_outputs` removes it at once.)
    #[test]
    #[ignore = "10^7 steps: run in release with --ignored"]
    fn soak_ten_million_steps() {
        let p = Params {
            max_cells: 800,
            ..Params::default()
        };
        let mut net = Network::new(p, 2, 1, &unit_triangle()).unwrap();
        let mut r = rng(101);
        let held_out = unit_square_points(102, 2_000);
        let error =
            |net: &Network| relative_l2(&held_out, |x, y| net.predict1(&[x, y]), bump_ridge);
        let mut max_v = 0.0f64;
        let mut at_last_spike = 0.0;
        for i in 0..10_000_000u64 {
            let spiky = i < 8_000_000;
            let (mut x, mut y) = (r.random::<f64>(), r.random::<f64>());
            if (i / 1_000_000) % 3 == 1 && spiky {
                x *= 0.3;
                y *= 0.3;
            }
            let z = if i % 100_003 == 0 && spiky {
                1e6
            } else {
                bump_ridge(x, y)
            };
            let out = net.step(&[x, y], &[z]);
            assert!(out.error_sq.is_finite());
            if i % 1_000_000 == 999_999 {
                net.check_invariants().unwrap();
                max_v = (0..net.len())
                    .map(|c| net.output(c)[0].abs())
                    .fold(max_v, f64::max);
                for c in 0..net.len() {
                    for v in [net.mean_error(c), net.cnt[c], net.width(c)] {
                        assert!(v == 0.0 || v.is_normal(), "cell {c}: {v}");
                    }
                }
            }
            if i == 7_999_999 {
                at_last_spike = error(&net);
            }
        }
        assert!(max_v < 1e6, "weights reached {max_v}");
        let end = error(&net);
        assert!(
            end < 0.5 * at_last_spike,
            "held-out error {at_last_spike} -> {end}"
        );
        // The refit removes what is left of the spikes.
        let pts = unit_square_points(103, 16_000);
        let inputs: Vec<f64> = pts.iter().flatten().copied().collect();
        let targets: Vec<f64> = pts.iter().map(|p| bump_ridge(p[0], p[1])).collect();
        net.refit_outputs(&inputs, &targets, 1e-3).unwrap();
        let refit = error(&net);
        assert!(refit < 0.3, "after the refit: {refit}");
    }

    #[test]
    fn network_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Network>();
    }

    /// What a caller that knows where its target jumps keeps: the side of `x = 0.5` of every
    /// cell, and the cells of each side (ascending).
    #[derive(Default)]
    struct Halves {
        of: Vec<bool>,
        sides: [Vec<CellId>; 2],
    }

    impl Halves {
        fn update(&mut self, net: &Network) {
            self.of = (0..net.len()).map(|c| net.position(c)[0] > 0.5).collect();
            for side in 0..2 {
                self.sides[side] = (0..net.len())
                    .filter(|&c| usize::from(self.of[c]) == side)
                    .collect();
            }
        }
        fn gate(&self, x: f64) -> HalfGate<'_> {
            let right = x > 0.5;
            HalfGate {
                of: &self.of,
                right,
                cells: &self.sides[usize::from(right)],
            }
        }
    }

    struct HalfGate<'a> {
        of: &'a [bool],
        right: bool,
        cells: &'a [CellId],
    }

    impl Gate for HalfGate<'_> {
        fn admits(&self, c: CellId) -> bool {
            self.of[c] == self.right
        }
        fn region(&self) -> Option<&[CellId]> {
            Some(self.cells)
        }
    }

    fn gated_params() -> Params {
        Params {
            lambda: 20,
            output_rule: OutputRule::Local,
            output_mode: OutputMode::Normalized,
            insertion: Insertion::WorstSample,
            insert_rule: InsertRule::SampleTarget,
            resource: Resource::ErrorSum,
            ..Params::default()
        }
    }

    /// A step target with its jump known to the caller: gated cells never straddle it, so a
    /// normalised network reproduces it exactly on both sides; the same network ungated blurs
    /// the jump.
    #[test]
    fn gated_normalized_cells_reproduce_a_known_jump_exactly() {
        let step = |x: f64| if x > 0.5 { 1.0 } else { 0.25 };
        let train = |gated: bool| {
            let mut net = Network::new(gated_params(), 2, 1, &unit_triangle()).unwrap();
            // The initial cells start from the target at their centres (as inserted ones do).
            for c in 0..3 {
                let x = net.position(c)[0];
                net.set_output(c, &[step(x)]).unwrap();
            }
            let mut halves = Halves::default();
            halves.update(&net);
            let mut r = rng(11);
            for _ in 0..4_000 {
                let (x, y) = (r.random::<f64>(), r.random::<f64>());
                if gated {
                    net.try_step_gated(&[x, y], &[step(x)], 1.0, &halves.gate(x))
                        .unwrap();
                } else {
                    net.step(&[x, y], &[step(x)]);
                }
                halves.update(&net);
                if net.steps().is_multiple_of(500) {
                    net.check_invariants().unwrap();
                }
            }
            (net, halves)
        };
        let (net, halves) = train(true);
        let (open, _) = train(false);
        let (mut gated_worst, mut open_worst) = (0.0f64, 0.0f64);
        for p in unit_square_points(12, 2_000) {
            let gated = net.predict1_gated(&p, &halves.gate(p[0]));
            gated_worst = gated_worst.max((gated - step(p[0])).abs());
            open_worst = open_worst.max((open.predict1(&p) - step(p[0])).abs());
        }
        assert!(gated_worst < 1e-9, "gated: worst error {gated_worst}");
        assert!(
            open_worst > 0.2,
            "ungated blurs the jump: worst error {open_worst}"
        );
    }

    /// A gate naming a region with one far cell gives that cell's value (no underflow), and an
    /// empty region books the error on the nearest cell, moves and teaches nothing.
    #[test]
    fn region_gates_reach_far_cells_and_uncovered_inputs_only_book_error() {
        let mut net = Network::new(gated_params(), 2, 1, &unit_triangle()).unwrap();
        net.out = vec![0.5, 2.0, 3.0];
        let far = [1e3, 1e3];
        let one: &[CellId] = &[1];
        struct Named<'a>(&'a [CellId]);
        impl Gate for Named<'_> {
            fn admits(&self, c: CellId) -> bool {
                self.0.contains(&c)
            }
            fn region(&self) -> Option<&[CellId]> {
                Some(self.0)
            }
        }
        assert_eq!(net.predict1_gated(&far, &Named(one)), 2.0);
        assert_eq!(
            net.predict1(&far),
            0.0,
            "ungated: every activation underflows"
        );
        let before = net.to_json();
        let (pos, out) = (net.pos.clone(), net.out.clone());
        let outcome = net
            .try_step_gated(&[0.1, 0.1], &[9.0], 2.0, &Named(&[]))
            .unwrap();
        assert!(!outcome.covered);
        assert_eq!(outcome.bmu, 0, "the nearest cell takes the error");
        assert_eq!((net.pos.clone(), net.out.clone()), (pos, out));
        assert!(net.resource(0) > 0.0 && net.resource(1) == 0.0);
        assert_ne!(net.to_json(), before);
    }

    /// The error-sum resource is the decayed sum of weighted squared errors.
    #[test]
    fn error_sum_resource_sums_weighted_errors() {
        let params = Params {
            alpha: 0.0,
            lambda: 1_000,
            ..gated_params()
        };
        let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
        let at_cell_0 = [0.0, 0.0];
        let mut expected = 0.0;
        for (target, weight) in [(1.0, 1.0), (2.0, 0.5), (-1.0, 3.0)] {
            let predicted = net.predict1(&at_cell_0);
            let outcome = net
                .try_step_gated(&at_cell_0, &[target], weight, &Open)
                .unwrap();
            assert_eq!(outcome.bmu, 0);
            expected += weight * (target - predicted).powi(2);
        }
        assert_close!(net.resource(0), expected, 1e-12 * expected);
    }

    /// Insertion at the worst sample puts the new cell exactly there, with that sample's target.
    #[test]
    fn worst_sample_insertion_places_the_cell_at_the_worst_error() {
        let params = Params {
            lambda: 5,
            ..gated_params()
        };
        let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
        let spike = [0.15, 0.2];
        for i in 0..5 {
            let (xi, z) = if i == 3 {
                (spike, 10.0)
            } else {
                ([0.9, 0.05 * i as f64], 0.01)
            };
            let outcome = net.step(&xi, &[z]);
            assert_eq!(outcome.inserted.is_some(), i == 4);
        }
        net.check_invariants().unwrap();
        assert_eq!(net.position(3), &spike);
        assert_eq!(net.output(3), &[10.0]);
        assert!(net.changed_cells().contains(&3));
    }

    /// `moved_cells` lists exactly the cells whose position changed (the inserted one included),
    /// a subset of `changed_cells`, gated or not.
    #[test]
    fn moved_cells_are_exactly_the_cells_that_moved() {
        for params in [gated_params(), Params::default()] {
            let params = Params {
                lambda: 7,
                ..params
            };
            let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
            let mut halves = Halves::default();
            halves.update(&net);
            let mut r = rng(21);
            for i in 0..2_000 {
                let (x, y) = (r.random::<f64>(), r.random::<f64>());
                let before = net.pos.clone();
                let z = if x > 0.5 { 1.0 } else { 0.0 };
                if i % 2 == 0 {
                    net.try_step_gated(&[x, y], &[z], 1.0, &halves.gate(x))
                        .unwrap();
                } else {
                    net.step(&[x, y], &[z]);
                }
                let moved: Vec<CellId> = (0..net.len())
                    .filter(|&c| {
                        c * 2 >= before.len() || net.position(c) != &before[c * 2..c * 2 + 2]
                    })
                    .collect();
                let listed = net.moved_cells();
                assert!(listed.windows(2).all(|w| w[0] < w[1]), "{listed:?}");
                assert!(
                    moved.iter().all(|c| listed.contains(c)),
                    "{moved:?} {listed:?}"
                );
                assert!(listed.iter().all(|c| net.changed_cells().contains(c)));
                halves.update(&net);
            }
        }
    }

    /// Worst samples are saved: a reloaded network trains on exactly like the original.
    #[test]
    fn worst_samples_survive_save_and_load() {
        let f = |x: f64, y: f64| if x + y > 1.0 { 1.0 } else { 0.0 };
        let mut a = grown(gated_params(), 3_000, 5, f);
        let mut b = Network::from_json(&a.to_json()).unwrap();
        let mut r = rng(6);
        for _ in 0..2_000 {
            let (x, y) = (r.random::<f64>(), r.random::<f64>());
            a.step(&[x, y], &[f(x, y)]);
            b.step(&[x, y], &[f(x, y)]);
        }
        assert_eq!(a.to_json(), b.to_json());
    }

    /// The refit of a normalised network fits the normalised output.
    #[test]
    fn refit_of_a_normalized_network_lowers_its_training_error() {
        let params = Params {
            output_mode: OutputMode::Normalized,
            lambda: 50,
            ..Params::default()
        };
        let mut net = grown(params, 10_000, 8, bump_ridge);
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
