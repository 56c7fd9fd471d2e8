//! The operator of a visibility model ([`Target::Visibility`](crate::Target::Visibility)):
//! the exact unoccluded transfer times the model's own `Ṽ`, integrated exactly.
//!
//! Such a model is `k̃ = ρ G Ṽ` with `G` exact and `Ṽ` constant on each face of the visibility
//! structure of a pair of surface edges. Seen from a collocation point `y`, the faces cut the
//! sending edge at its [`PairEvents::sender_breaks`](flatland_geom::PairEvents::sender_breaks):
//! between two breaks `Ṽ` is one face's value, so `K_ij` is the closed-form transfer of each
//! piece of element `j` times that value, summed. `Ṽ` is asked once per face and receiver, not
//! per element; pairs the geometry decides need no `Ṽ` at all. No ray, no quadrature: the
//! solve sees exactly the kernel the model represents, each row bounded to `ρ_i`
//! ([`make_physical`]): where `Ṽ` passes light a face hides (a face no cell has visited), the
//! unoccluded transfers of surfaces behind each other would add up past the half-plane.

use flatland_geom::{Kernel, PairClass, SurfaceRank};
use flatland_solve::{
    DenseOperator, Mesh, Receiver, Sender, SolveError, Stop, check_scene, make_physical,
    point_to_segment, receiver, sender,
};

/// `K_ij = ρ_i ∫_{element j} G(x, y_i) Ṽ(x, y_i) dl_x` of a visibility model on `mesh`, with
/// `learned_visibility(s, t)` the model's `Ṽ` (`None` where the geometry decides).
pub(crate) fn visibility_operator(
    learned_visibility: &(dyn Fn(f64, f64) -> Option<f64> + Sync),
    kernel: &Kernel,
    mesh: &Mesh,
    stop: &Stop,
) -> Result<DenseOperator, SolveError> {
    check_scene(kernel, mesh)?;
    let (edges, elements) = (mesh.edges(), mesh.elements());
    // The rank of each mesh edge's parent surface edge.
    let rank: Vec<SurfaceRank> = edges
        .iter()
        .map(|e| kernel.unoccluded((e.s[0] + e.s[1]) / 2.0, 0.0).sender)
        .collect();
    DenseOperator::assemble(
        mesh.len(),
        |i, row| {
            row.fill(0.0);
            let rho = mesh.edge_of(i).reflectance;
            if rho == 0.0 {
                return;
            }
            let here = &elements[i];
            let r = receiver(mesh, here.mesh_edge, mesh.local(i)[2]);
            let b = rank[here.mesh_edge];
            for (k, edge) in edges.iter().enumerate() {
                let a = rank[k];
                match kernel.pair_class(a, b) {
                    PairClass::Zero | PairClass::Hidden => {}
                    PairClass::Visible => {
                        for j in edge.elements.clone() {
                            row[j] = point_to_segment(&r, &sender(mesh, j));
                        }
                    }
                    PairClass::Varies => {
                        let Some(events) = kernel.visibility_events(a, b) else {
                            continue;
                        };
                        // Face boundaries along the sending edge, and Ṽ on each face.
                        let mut bounds = vec![0.0];
                        bounds.extend(events.sender_breaks(here.midpoint));
                        bounds.push(1.0);
                        let width = edge.s[1] - edge.s[0];
                        let v: Vec<f64> = bounds
                            .windows(2)
                            .map(|w| {
                                let s = edge.s[0] + width * (w[0] + w[1]) / 2.0;
                                learned_visibility(s, here.s_mid).unwrap_or(0.0)
                            })
                            .collect();
                        for j in edge.elements.clone() {
                            row[j] = piecewise(mesh, j, edge.s[0], width, &bounds, &v, &r);
                        }
                    }
                }
            }
            row.iter_mut().for_each(|x| *x *= rho);
            make_physical(row, rho);
        },
        stop,
    )
}

/// `Σ` over the pieces of element `j` between face boundaries `bounds` (parameters along its
/// edge, which starts at `s0` and spans `width`) of the closed-form transfer times that face's
/// `v`.
fn piecewise(
    mesh: &Mesh,
    j: usize,
    s0: f64,
    width: f64,
    bounds: &[f64],
    v: &[f64],
    r: &Receiver,
) -> f64 {
    let element = &mesh.elements()[j];
    let whole = sender(mesh, j);
    let (u0, u1) = ((element.s[0] - s0) / width, (element.s[1] - s0) / width);
    let at = |u: f64| whole.a + (whole.b - whole.a) * ((u - u0) / (u1 - u0));
    // The face holding the element's start, then every boundary inside it.
    let mut face = bounds.partition_point(|&b| b <= u0).saturating_sub(1);
    let mut from = u0;
    let mut total = 0.0;
    while from < u1 {
        let to = bounds.get(face + 1).copied().unwrap_or(1.0).min(u1);
        if v[face] > 0.0 && to > from {
            let piece = Sender {
                a: at(from),
                b: at(to),
                ..whole
            };
            total += v[face] * point_to_segment(r, &piece);
        }
        from = to;
        face += 1;
        if face >= v.len() {
            break;
        }
    }
    total
}

#[cfg(test)]
mod tests {
    use std::ops::ControlFlow;
    use std::sync::Arc;

    use super::*;
    use crate::{Fit, FitParams, LearnedKernel};
    use flatland_baselines::{BlockValue, HrParams, UniformParams, run_hr_at_budget, run_uniform};
    use flatland_solve::{
        ExactReference, Reference, Representation, SolveParams, never, quadrature_operator,
        solve_against,
    };

    fn bundled(name: &str) -> flatland_geom::Scene {
        flatland_geom::bundled::scene(name).expect("bundled scene")
    }

    fn learned(name: &str, cells: usize) -> (Arc<Kernel>, LearnedKernel) {
        let kernel = Arc::new(Kernel::new(bundled(name)));
        let reference = Arc::new(Reference::new(&kernel, 32, 256, 1));
        let params = FitParams {
            target_cells: cells,
            eval_every: 0,
            ..FitParams::default()
        };
        let mut fit = Fit::new(Arc::clone(&kernel), reference, params).unwrap();
        fit.run(u64::MAX, |_| ControlFlow::Continue(())).unwrap();
        (kernel, fit.model().clone())
    }

    /// The operator integrates the model's own kernel: it agrees with fine Gauss–Legendre
    /// quadrature of `k̃ = ζ̃ / E'` away from the corners where `k` is singular.
    #[test]
    fn the_operator_is_the_integral_of_the_models_kernel() {
        let (kernel, model) = learned("maze", 150);
        let mesh = Mesh::new(&kernel, 96).unwrap();
        let learned = |s, t| model.learned_visibility(s, t);
        let exact = visibility_operator(&learned, &kernel, &mesh, &never).unwrap();
        let quadrature = quadrature_operator(&model, &mesh, 16, &never).unwrap();
        let (mut sum, mut diff) = (0.0, 0.0);
        for i in 0..mesh.len() {
            for j in 0..mesh.len() {
                let (e, q) = (exact.get(i, j), quadrature.get(i, j));
                sum += e.abs();
                diff += (e - q).abs();
            }
        }
        // 16 Gauss points cannot follow a jump of Ṽ or the 1/r of a shared corner exactly.
        assert!(diff < 0.01 * sum, "{diff} of {sum}");
    }

    /// Whatever the network's weights (negative, huge), a solve with the learned kernel of
    /// either preset stays physical: every entry of its operator ≥ 0, every row summing to at
    /// most `ρ_i`, and B finite with B ≥ E ≥ 0 (up to the solve's tolerance). The paper's
    /// network learns ζ itself, so its wild ζ̃ goes negative and past the kernel; the default
    /// learner's `Ṽ` (clamped to [0, 1]) passes light through every face it calls visible.
    #[test]
    fn wild_weights_still_solve_to_physical_light() {
        use rand::{RngExt, SeedableRng};
        let params = SolveParams::default();
        for (preset, base) in [
            ("default", FitParams::default()),
            ("paper", FitParams::paper()),
        ] {
            for name in ["maze", "corners"] {
                let kernel = Arc::new(Kernel::new(bundled(name)));
                let reference = Arc::new(Reference::new(&kernel, 32, 256, 1));
                let fit_params = FitParams {
                    target_cells: 60,
                    eval_every: 0,
                    ..base
                };
                let mut fit = Fit::new(Arc::clone(&kernel), reference, fit_params).unwrap();
                fit.run(u64::MAX, |_| ControlFlow::Continue(())).unwrap();
                let mut model = fit.model().clone();
                let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
                for c in 0..model.network.len() {
                    let wild = [-1e12, -3.0, 0.5, 40.0, 1e12][rng.random_range(0..5)];
                    model.network.set_output(c, &[wild]).unwrap();
                }
                let mesh = Mesh::new(&kernel, 96).unwrap();
                let op = model.operator(&mesh, &params, &never).unwrap();
                let n = mesh.len();
                let mut column = vec![0.0; n];
                let mut sums = vec![0.0; n];
                for j in 0..n {
                    let mut unit = vec![0.0; n];
                    unit[j] = 1.0;
                    op.apply(&unit, &mut column);
                    for (i, &k) in column.iter().enumerate() {
                        assert!(
                            k >= 0.0 && k.is_finite(),
                            "{preset} {name}: K[{i}][{j}] = {k}"
                        );
                        sums[i] += k;
                    }
                }
                for (i, sum) in sums.iter().enumerate() {
                    let rho = mesh.edge_of(i).reflectance;
                    assert!(
                        *sum <= rho * (1.0 + 1e-12),
                        "{preset} {name}: row {i} {sum} > ρ {rho}"
                    );
                }
                let b = flatland_solve::solve(&model, &mesh, &params, &never)
                    .unwrap()
                    .radiosity;
                let e = mesh.emission();
                let top = b.iter().fold(0.0_f64, |m, &x| m.max(x));
                for (i, (b, e)) in b.iter().zip(&e).enumerate() {
                    assert!(
                        b.is_finite() && *e >= 0.0 && *b >= e - 1e-9 * top,
                        "{preset} {name}, element {i}: B = {b}, E = {e}"
                    );
                }
            }
        }
    }

    /// Issue 11's bar: with the visibility network at 400 cells the reflected light is at most
    /// half as wrong as with exact 20×20 block means of k, and no worse than with HR.
    #[test]
    fn the_learned_kernel_lights_the_scene_better_than_the_baselines() {
        let params = SolveParams::default();
        for name in ["fig3", "maze", "corners"] {
            let (kernel, model) = learned(name, 400);
            let mesh = Mesh::new(&kernel, 128).unwrap();
            let reference = ExactReference::new(&kernel, 1024, &params, &never).unwrap();
            let exact = reference.radiosity_on(&mesh, &never).unwrap();
            let error = |rep: &dyn Representation| {
                solve_against(rep, &mesh, &exact, &params, &never)
                    .unwrap()
                    .errors
                    .rel_l2_reflected
            };
            let blocks = UniformParams {
                block_value: BlockValue::ExactKernelMean,
                ..UniformParams::default()
            };
            let uniform = run_uniform(&kernel, 400, 1, &blocks).unwrap().approx;
            let hr = run_hr_at_budget(&kernel, 400, 1, &HrParams::default())
                .unwrap()
                .approx;
            let (learned, uniform, hr) = (error(&model), error(&uniform), error(&hr));
            assert!(
                learned <= 0.5 * uniform && learned <= hr,
                "{name}: learned {learned}, exact block means {uniform}, HR {hr}"
            );
        }
    }
}
