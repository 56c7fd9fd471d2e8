//! What the cases share: generators, transformed scenes, the small fit every comparison runs,
//! and the checks of kernels, networks and errors.

#![allow(clippy::wildcard_imports)]

use std::ops::ControlFlow;
use std::sync::Arc;

use anyhow::Result;
use flatland_geom::{DVec2, Edge, Kernel, Scene};
use flatland_solve::{Errors, Reference};
use kernel_fit::{Fit, FitParams, FitSummary};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sgcs::Network;

use super::*;

pub fn v(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

/// The suite's seeded generator: reproducible points, from the stream every crate uses.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A closed room through `points`, counter-clockwise (so it faces inwards), all with `rho`.
pub fn room(points: &[DVec2], rho: f64) -> Vec<Edge> {
    Edge::polygon(points, rho)
}

/// Every edge mapped through `f` (scale, translate, …).
pub fn transformed(scene: &Scene, f: impl Fn(DVec2) -> DVec2) -> Result<Scene> {
    let edges = scene
        .edges()
        .iter()
        .map(|e| Edge {
            a: f(e.a),
            b: f(e.b),
            ..*e
        })
        .collect();
    Ok(Scene::new(edges)?)
}

/// The small fit on the original fig3 that the scaling, translation and emission cases compare
/// with (its time is counted in the first case that asks for it).
pub struct Baseline<'a> {
    pub scene: &'a Scene,
    pub summary: Option<FitSummary>,
}

impl Baseline<'_> {
    pub fn get(&mut self) -> Result<&FitSummary> {
        if self.summary.is_none() {
            self.summary = Some(small_fit(self.scene, FitParams::default())?.0);
        }
        Ok(self.summary.as_ref().expect("just computed"))
    }
}

/// The small fit every comparison runs: 60 cells, seed 7, a 64² grid and 1024 held-out points.
pub fn small_fit(scene: &Scene, params: FitParams) -> Result<(FitSummary, Fit)> {
    let kernel = Arc::new(Kernel::new(scene.clone()));
    let reference = Arc::new(Reference::new(&kernel, REF_RES, REF_HELDOUT, SEED));
    let params = FitParams {
        target_cells: FIT_CELLS,
        seed: SEED,
        heldout: REF_HELDOUT,
        eval_every: 0,
        ..params
    };
    let mut fit = Fit::new(kernel, reference, params)?;
    let summary = fit.run(10_000, |_| ControlFlow::Continue(()))?;
    Ok((summary, fit))
}

/// Records a fit's figures (errors, every network number, every prediction on the reference
/// grid) and checks that nothing is non-finite and predictions stay bounded.
pub fn inspect_fit(row: &mut Row, summary: &FitSummary, fit: &Fit) {
    row.finite(summary.errors.grid);
    row.finite(summary.errors.heldout);
    row.error = Some(summary.errors.heldout);
    inspect_network(row, fit.network());
    let exact = fit.reference().grid();
    let predicted = fit.reference().approximate_grid(fit.model());
    let top = exact.iter().fold(0.0_f64, |m, z| m.max(z.abs()));
    let worst = predicted.iter().fold(0.0_f64, |m, z| m.max(z.abs()));
    row.see_all(predicted.iter().copied());
    row.require(worst <= BOUND_FACTOR * top.max(f64::MIN_POSITIVE), || {
        format!("prediction {worst:.3e} exceeds {BOUND_FACTOR} × max ζ {top:.3e}")
    });
}

/// Runs the small fit on `scene` and inspects it, keeping the row's error (the case's own
/// measure, set before: the energy balance of a geometry case).
pub fn inspect_fit_keeping_error(row: &mut Row, scene: &Scene) -> Result<()> {
    let error = row.error;
    let (summary, fit) = small_fit(scene, FitParams::default())?;
    inspect_fit(row, &summary, &fit);
    row.error = error;
    Ok(())
}

/// Every number a network holds must be finite, and its counters meaningful: non-negative and
/// never subnormal.
pub fn inspect_network(row: &mut Row, net: &Network) {
    let mut bad_counters = 0;
    for c in 0..net.len() {
        for &p in net.position(c) {
            row.finite(p);
        }
        row.see_all(net.output(c).iter().copied());
        row.finite(net.width(c));
        for tau in [net.resource(c), net.mean_error(c)] {
            row.finite(tau);
            if tau < 0.0 || (tau != 0.0 && !tau.is_normal()) {
                bad_counters += 1;
            }
        }
    }
    row.require(bad_counters == 0, || {
        format!("{bad_counters} resource counters negative or subnormal")
    });
}

/// `|a − b| / b ≤ tol` for each of the two errors, or both below [`TINY_ERROR`] (the default
/// learner is often exact: 0 and 0.001 are the same fit, not 100 % apart).
pub fn same_errors(row: &mut Row, what: &str, got: Errors, base: Errors) {
    for (name, g, b) in [
        ("held-out", got.heldout, base.heldout),
        ("grid", got.grid, base.grid),
    ] {
        let rel = (g - b).abs() / b;
        row.require(rel <= SAME_ERROR || g.max(b) < TINY_ERROR, || {
            format!(
                "{what}: {name} error {g:.5} vs {b:.5} at the original scale ({:.1} % apart, \
                 allowed {:.0} %)",
                100.0 * rel,
                100.0 * SAME_ERROR
            )
        });
    }
}

/// Uniform random `(s, t)` pairs.
pub fn random_pairs(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| [r.random::<f64>(), r.random::<f64>()])
        .collect()
}

/// Checks `k` and `ζ` on `pairs`: finite, ≥ 0, `V` symmetric, reciprocity
/// `k(s,t)/ρ(t) = k(t,s)/ρ(s)` (relative 1e-9) where both reflectances are positive.
pub fn check_kernel(row: &mut Row, kernel: &Kernel, pairs: &[[f64; 2]]) {
    let scene = kernel.scene();
    let (mut negative, mut asymmetric, mut unreciprocal) = (0, 0, 0);
    for &[s, t] in pairs {
        let a = kernel.eval(s, t);
        let b = kernel.eval(t, s);
        row.see(a.k);
        row.see(a.zeta);
        if a.k < 0.0 || a.zeta < 0.0 {
            negative += 1;
        }
        let vab = kernel.visible(a.x.position, a.x.edge, a.y.position, a.y.edge);
        let vba = kernel.visible(a.y.position, a.y.edge, a.x.position, a.x.edge);
        if vab != vba {
            asymmetric += 1;
        }
        let (rx, ry) = (
            scene.edge(a.x.edge).reflectance,
            scene.edge(a.y.edge).reflectance,
        );
        if rx > 0.0 && ry > 0.0 {
            let (p, q) = (a.k / ry, b.k / rx);
            if (p - q).abs() > 1e-9 * p.abs().max(q.abs()) {
                unreciprocal += 1;
            }
        }
    }
    row.require(negative == 0, || format!("{negative} negative k or ζ"));
    row.require(asymmetric == 0, || {
        format!("V(x, y) ≠ V(y, x) at {asymmetric} pairs")
    });
    row.require(unreciprocal == 0, || {
        format!("reciprocity k(s,t)/ρ(t) = k(t,s)/ρ(s) broken at {unreciprocal} pairs")
    });
}

/// `∫ k(s, t)/ρ(e_t) dl(t)` over every receiver, by a midpoint rule in the angle seen from the
/// sender (`dl = r dθ / cos_y`, so the integrand is `cos_x / 2 · V`: smooth even when the
/// receiver is 10⁻⁹ away). In a closed room with no blocker it is 1 (energy conservation).
pub fn row_integral(kernel: &Kernel, s: f64, per_edge: usize) -> f64 {
    let scene = kernel.scene();
    let x = scene.point(s);
    let mut sum = 0.0;
    for &e in scene.surface_edges() {
        let edge = scene.edge(e);
        let (ua, ub) = (edge.a - x.position, edge.b - x.position);
        let span = ua.perp_dot(ub).atan2(ua.dot(ub));
        if span == 0.0 || !span.is_finite() || ua.length() == 0.0 {
            continue;
        }
        let dir0 = ua / ua.length();
        let d = edge.b - edge.a;
        let step = span / per_edge as f64;
        for j in 0..per_edge {
            let phi = (j as f64 + 0.5) * step;
            let u = DVec2::from_angle(phi).rotate(dir0);
            let denom = u.perp_dot(d);
            if denom == 0.0 {
                continue;
            }
            let mu = (ua.perp_dot(u) / denom).clamp(0.0, 1.0);
            let Some(t) = scene.param_of(e, edge.a + d * mu) else {
                continue;
            };
            let k = kernel.k(s, t);
            if k == 0.0 {
                continue;
            }
            let y = scene.point(t);
            let r = y.position - x.position;
            let cos_y = (y.normal.dot(r) / r.length()).abs();
            sum += k / scene.edge(y.edge).reflectance * r.length() / cos_y * step.abs();
        }
    }
    sum
}

/// Energy conservation at the middle and near both ends of every surface edge (up to `max`
/// edges, spread over the scene): records the largest `|∫ − 1|` as the case's error.
pub fn check_energy(row: &mut Row, kernel: &Kernel, per_edge: usize, max: usize) {
    let scene = kernel.scene();
    let surfaces = scene.surface_edges();
    let stride = surfaces.len().div_ceil(max).max(1);
    let mut worst = 0.0_f64;
    let mut worst_at = 0.0;
    for &e in surfaces.iter().step_by(stride) {
        let (s0, s1) = scene.edge_param_range(e).expect("a surface edge");
        for f in [0.5, 1e-3, 1.0 - 1e-3] {
            let s = s0 + f * (s1 - s0);
            let integral = row_integral(kernel, s, per_edge);
            row.finite(integral);
            if (integral - 1.0).abs() > worst {
                worst = (integral - 1.0).abs();
                worst_at = s;
            }
        }
    }
    row.error = Some(worst);
    row.require(worst <= ENERGY_TOL, || {
        format!("energy ∫ k/ρ dl = 1 off by {worst:.2e} at s = {worst_at} (allowed {ENERGY_TOL})")
    });
}
