//! The cells an input reaches (active and nearest), by a scan or through the spatial index.

use super::{CellId, Network};
use crate::OutputMode;
use crate::index::{dist_sq, is_active};

/// Up to this many cells the active cells are found by scanning them all: a small network's
/// supports are wide, so a tree query visits most leaves anyway. Measured by `sgcs_step`
/// (four inputs, the paper's network), µs a step by the tree and by the scan: 6.9 and 5.7 at
/// 400 cells, 9.7 and 8.6 at 1000, 9.9 and 9.9 at 2000, 12.6 and 14.3 at 4000.
const SCAN_MAX_CELLS: usize = 1024;

/// `exp(−d²/δ²)`, 0 where it would be subnormal.
#[inline]
pub(super) fn activation(d2: f64, width: f64) -> f64 {
    let a = d2 / (width * width);
    if a > 700.0 { 0.0 } else { (-a).exp() }
}

impl Network {
    /// The cell of `list` nearest to `xi` (lowest id on ties), if any.
    pub(super) fn nearest_in(&self, xi: &[f64], list: &[CellId]) -> Option<CellId> {
        let n = self.n;
        let mut best: Option<(f64, CellId)> = None;
        for &c in list {
            let d2 = dist_sq(&self.cells.pos[c * n..(c + 1) * n], xi);
            if best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, c));
            }
        }
        best.map(|b| b.1)
    }

    /// The weights of the cells of `list` at `xi` into `out`: their activations, or for
    /// [`OutputMode::Normalized`] their activations divided by the largest one (the same
    /// normalised output, without underflow however far the cells are).
    pub(super) fn region_weights(&self, xi: &[f64], list: &[CellId], out: &mut Vec<(u32, f64)>) {
        let n = self.n;
        out.clear();
        out.extend(list.iter().map(|&c| {
            let d2 = dist_sq(&self.cells.pos[c * n..(c + 1) * n], xi);
            let w = self.cells.width[c];
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
    pub(super) fn nearest_of(&self, xi: &[f64], list: &[(u32, f64)]) -> Option<CellId> {
        let n = self.n;
        let mut best: Option<(f64, CellId)> = None;
        for &(c, _) in list {
            let c = c as usize;
            let d2 = dist_sq(&self.cells.pos[c * n..(c + 1) * n], xi);
            if best.is_none_or(|(b, _)| d2 < b) {
                best = Some((d2, c));
            }
        }
        best.map(|b| b.1)
    }

    /// Puts the active cells `(c, M_c(xi))` into `found`, sorted by id: by a scan in a small
    /// network, else through the spatial index. Both give the same list.
    pub(super) fn collect_active(
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
    pub(super) fn active_and_nearest(
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
            self.index.nearest(xi, &self.cells.pos, stack)
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
            .within(xi, &self.cells.pos, &self.cells.width, reach_sq, stack, ids);
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
            let d2 = dist_sq(&self.cells.pos[ci * n..(ci + 1) * n], xi);
            (c, activation(d2, self.cells.width[ci]))
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
            let d2 = dist_sq(&self.cells.pos[c * n..(c + 1) * n], xi);
            if d2 < nearest.0 {
                nearest = (d2, c);
            }
            if is_active(d2, self.cells.width[c], reach_sq) {
                found.push((c as u32, activation(d2, self.cells.width[c])));
            }
        }
        nearest.1
    }

    /// The active cells of `xi` in fresh buffers.
    pub(super) fn active(&self, xi: &[f64]) -> Vec<(u32, f64)> {
        assert_eq!(xi.len(), self.n, "sgcs: xi has the wrong length");
        let (mut stack, mut ids, mut found) = (Vec::new(), Vec::new(), Vec::new());
        self.collect_active(xi, &mut stack, &mut ids, &mut found);
        found
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
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::Params;
    use crate::test_support::{assert_close, bump_ridge, grown, rng, unit_square_points};

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
                let by_index = net.index.nearest(&xi, &net.cells.pos, &mut stack);
                proptest::prop_assert_eq!(nearest, by_index);
            }
        }
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
}
