//! Resource counters: each cell's lazily decayed error and count, worst sample, and `τ_c`.

use super::{CellId, Network, SIMPLEX_DIM};
use crate::Resource;

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
pub(super) fn flush(x: f64) -> f64 {
    if x < 1e-300 { 0.0 } else { x }
}

impl Network {
    /// The resource: `τ_c = τ_err,c / τ_cnt,c · |F_c|` with `|F_c| = δ_c^k`, or `τ_err,c` for
    /// [`Resource::ErrorSum`] (0 for a cell never hit).
    pub fn resource(&self, c: CellId) -> f64 {
        match self.params.resource {
            Resource::MeanTimesVolume => self.cells.err_mean[c] * self.volume(c),
            Resource::ErrorSum => self.cells.err_mean[c] * self.count_at(c, self.steps),
        }
    }

    /// `τ_err,c / τ_cnt,c`: the decayed mean squared error of the samples `c` won.
    pub fn mean_error(&self, c: CellId) -> f64 {
        self.cells.err_mean[c]
    }

    /// `|F_c| = δ_c^k`.
    pub(super) fn volume(&self, c: CellId) -> f64 {
        self.cells.width[c].powi(SIMPLEX_DIM as i32)
    }

    fn ln_keep(&self) -> f64 {
        (-self.params.alpha).ln_1p()
    }

    /// `τ_cnt` of `c` decayed to step `now`.
    pub(super) fn count_at(&self, c: CellId, now: u64) -> f64 {
        let dt = now.saturating_sub(self.cells.stamp[c]);
        flush(self.cells.cnt[c] * decay(self.ln_keep(), dt))
    }

    /// Adds one sample with squared error `e2` to `c`'s counters at step `now`.
    pub(super) fn touch(&mut self, c: CellId, e2: f64, now: u64) {
        let cnt = self.count_at(c, now) + 1.0;
        let mean = self.cells.err_mean[c];
        self.cells.err_mean[c] = flush(mean + (flush(e2) - mean) / cnt);
        self.cells.cnt[c] = cnt;
        self.cells.stamp[c] = now;
    }

    /// Keeps the sample with the largest weighted squared error `c` has won (decayed).
    pub(super) fn remember_worst(
        &mut self,
        c: CellId,
        e2: f64,
        xi: &[f64],
        zeta: &[f64],
        now: u64,
    ) {
        let (n, m) = (self.n, self.m);
        let age = now - self.cells.worst_stamp[c];
        let held = self.cells.worst_err[c] * decay(self.ln_keep(), age);
        if e2 > 0.0 && e2 >= held {
            let cells = &mut self.cells;
            cells.worst_err[c] = flush(e2);
            cells.worst_stamp[c] = now;
            cells.worst_in[c * n..(c + 1) * n].copy_from_slice(xi);
            cells.worst_out[c * m..(c + 1) * m].copy_from_slice(zeta);
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use crate::test_support::{assert_close, gated_params, rng, unit_triangle};
    use crate::{Network, Open, Params};

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
            for v in [net.mean_error(c), net.cells.cnt[c], net.resource(c)] {
                assert!(v == 0.0 || v.is_normal(), "cell {c}: {v}");
            }
        }
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
}
