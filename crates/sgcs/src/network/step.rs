//! One learning step: the winner, the output error, the weight update, the movement.

use super::{CellId, Gate, MAX_ABS_VALUE, Network, Open, check_values};
use crate::index::dist_sq;
use crate::{Insertion, OutputMode, OutputRule, SgcsError};

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

/// The step's buffers, kept between steps so a step allocates nothing.
#[derive(Clone, Debug, Default)]
pub(super) struct Scratch {
    stack: Vec<u32>,
    ids: Vec<u32>,
    found: Vec<(u32, f64)>,
    admitted: Vec<(u32, f64)>,
    kappa: Vec<f64>,
    touched: Vec<CellId>,
}

impl Network {
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
        self.check_sample(xi, zeta, weight)?;
        self.steps += 1;
        let now = self.steps;
        self.index.tick();
        if self.index.wants_rebuild(self.len()) {
            self.rebuild_index();
        }
        let mut sc = std::mem::take(&mut self.scratch);

        let (s, covered) = self.winner_and_active(xi, gate, &mut sc);
        let (error_sq, sum_m, sum_m2) = self.output_error(zeta, &sc.found, &mut sc.kappa);
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

    /// Refuses a sample of the wrong lengths, with a value beyond `1e100` or NaN, or with a
    /// weight outside `[0, 1e100]`.
    pub(super) fn check_sample(
        &self,
        xi: &[f64],
        zeta: &[f64],
        weight: f64,
    ) -> Result<(), SgcsError> {
        check_values("xi", xi, self.n)?;
        check_values("zeta", zeta, self.m)?;
        if !(weight.is_finite() && (0.0..=MAX_ABS_VALUE).contains(&weight)) {
            return Err(SgcsError::NonFinite {
                what: "sample weight",
                value: weight,
            });
        }
        Ok(())
    }

    /// The best matching unit and the activations above the cutoff into `sc.found`, in id
    /// order (or the gate's region, weighted relative to its nearest cell); and whether an
    /// admitted cell is active (else `found` holds the fallback's cells, which do not learn).
    fn winner_and_active<G: Gate>(&self, xi: &[f64], gate: &G, sc: &mut Scratch) -> (CellId, bool) {
        if let Some(region) = gate.region() {
            match self.nearest_in(xi, region) {
                Some(c) => {
                    self.region_weights(xi, region, &mut sc.found);
                    (c, true)
                }
                None => match gate.fallback().filter(|f| !f.is_empty()) {
                    Some(list) => {
                        self.region_weights(xi, list, &mut sc.found);
                        (
                            self.index.nearest(xi, &self.cells.pos, &mut sc.stack),
                            false,
                        )
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
                None => (
                    self.index.nearest(xi, &self.cells.pos, &mut sc.stack),
                    false,
                ),
            }
        }
    }

    /// The error `ζ − κ` of the cells `found` into `error` (resized to `m`), and
    /// `(|ζ − κ|², Σ M_c, Σ M_c²)`.
    fn output_error(
        &self,
        zeta: &[f64],
        found: &[(u32, f64)],
        error: &mut Vec<f64>,
    ) -> (f64, f64, f64) {
        let m = self.m;
        error.clear();
        error.resize(m, 0.0);
        let (sum_m, sum_m2) = self.combine(found, error);
        let mut error_sq = 0.0;
        for j in 0..m {
            error[j] = zeta[j] - error[j]; // now the error ζ − κ
            error_sq += error[j] * error[j];
        }
        (error_sq, sum_m, sum_m2)
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
            let v = &mut self.cells.out[s * m..(s + 1) * m];
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
            let v = &mut self.cells.out[c as usize * m..(c as usize + 1) * m];
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
        touched.extend_from_slice(&self.cells.nbrs[s]);
        for i in 0..self.cells.nbrs[s].len() {
            let b = self.cells.nbrs[s][i];
            if !gate.admits(b) {
                continue;
            }
            self.move_cell(b, xi, self.params.eps_n);
            if self.params.eps_n > 0.0 {
                self.moved.push(b);
            }
            touched.extend_from_slice(&self.cells.nbrs[b]);
        }
        self.moved.sort_unstable();
        touched.sort_unstable();
        touched.dedup();
        for &c in touched.iter() {
            self.refresh_width(c);
        }
    }

    /// Moves `c` by `rate (xi − w_c)` and re-measures its edges (at both ends).
    fn move_cell(&mut self, c: CellId, xi: &[f64], rate: f64) {
        if rate == 0.0 {
            return;
        }
        let n = self.n;
        let cells = &mut self.cells;
        let w = &mut cells.pos[c * n..(c + 1) * n];
        for d in 0..n {
            w[d] += rate * (xi[d] - w[d]);
        }
        self.index.moved(c, &cells.pos[c * n..(c + 1) * n]);
        // Each length is measured once and stored at both ends (|a − b| = |b − a| exactly).
        for k in 0..cells.nbrs[c].len() {
            let b = cells.nbrs[c][k];
            let length = dist_sq(
                &cells.pos[c * n..(c + 1) * n],
                &cells.pos[b * n..(b + 1) * n],
            )
            .sqrt();
            cells.edge_len[c][k] = length;
            let j = cells.nbrs[b]
                .binary_search(&c)
                .unwrap_or_else(|_| unreachable!("neighbour lists are symmetric"));
            cells.edge_len[b][j] = length;
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::Params;
    use crate::test_support::{
        Halves, assert_close, bump_distance, bump_ridge, gated_params, grown, relative_l2,
        ridge_distance, rng, unit_square_points, unit_triangle,
    };

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
                let before = net.cells.pos.to_vec();
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
                    for v in [net.mean_error(c), net.cells.cnt[c], net.width(c)] {
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
}
