//! Queries: the output, the activation sums, the critical cells, the best matching unit.

use super::active::activation;
use super::{CellId, Gate, Network, Open};
use crate::OutputMode;
use crate::index::dist_sq;

impl Network {
    /// The output of the active cells `list` into `out` (zeroed by the caller) by the output
    /// mode; returns `(Σ M_c, Σ M_c²)`.
    #[inline]
    pub(super) fn combine(&self, list: &[(u32, f64)], out: &mut [f64]) -> (f64, f64) {
        let m = self.m;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for &(c, a) in list {
            let v = &self.cells.out[c as usize * m..(c as usize + 1) * m];
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
                        let d2 = dist_sq(&self.cells.pos[c * n..(c + 1) * n], xi);
                        (c as u32, activation(d2, self.cells.width[c]))
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
        self.index.nearest(xi, &self.cells.pos, &mut Vec::new())
    }
}

#[cfg(test)]
mod tests {
    use crate::Params;
    use crate::test_support::{bump_ridge, grown, unit_square_points};

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
            let kappa: f64 = acts.iter().map(|&(c, a)| net.output(c)[0] * a).sum();
            assert_eq!(net.predict1(&p), kappa);
        }
    }
}
