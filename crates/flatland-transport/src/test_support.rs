//! What the crate's tests share: a small generated plan with its exact operator, the exact
//! later bounces of a source by GMRES, the weighted relative error.

use flatland_geom::{Kernel, PointLight};
use flatland_solve::{
    DirectLight, LightBuffers, Mesh, SolveParams, SparseOperator, TransferOperator, never,
    solve_linear, sweep_operator,
};

use crate::free::free_points;
use crate::{LaterBounces, Move, QueryBuffers, lit_source};

/// A generated plan of about `edges` edges, lamps removed, on 3 elements per section.
pub(crate) fn plan(edges: usize, seed: u64) -> (Kernel, Mesh, SparseOperator) {
    let scene = flatland_geom::generate::floor_plan_lit(edges, seed)
        .unwrap()
        .with_lights(Vec::new())
        .unwrap();
    let kernel = Kernel::new(scene);
    let mesh = Mesh::new(&kernel, 3 * Mesh::min_elements(kernel.scene())).unwrap();
    let k = sweep_operator(&kernel, &mesh, &never).unwrap();
    (kernel, mesh, k)
}

/// The exact `M₂ B₀ = (I − K)⁻¹ K² B₀` by GMRES.
pub(crate) fn exact_later(k: &SparseOperator, b0: &[f64]) -> Vec<f64> {
    let (mut once, mut twice) = (vec![0.0; b0.len()], vec![0.0; b0.len()]);
    k.apply(b0, &mut once);
    k.apply(&once, &mut twice);
    solve_linear(k, &twice, twice.clone(), &SolveParams::default(), &never)
        .unwrap()
        .radiosity
}

/// Relative L2 of `a` against `b`, element lengths as weights.
pub(crate) fn relative(mesh: &Mesh, a: &[f64], b: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (i, e) in mesh.elements().iter().enumerate() {
        num += e.length * (a[i] - b[i]).powi(2);
        den += e.length * b[i] * b[i];
    }
    (num / den).sqrt()
}

/// `form`'s error of `M₂ B₀` against the exact one at `count` free points drawn from `seed`
/// (lights the set-up never saw), each answer checked nowhere negative.
pub(crate) fn errors_on_unseen_lights(
    form: &dyn LaterBounces,
    kernel: &Kernel,
    mesh: &Mesh,
    k: &SparseOperator,
    count: usize,
    seed: u64,
) -> Vec<f64> {
    let direct = DirectLight::new(kernel, mesh).unwrap();
    let mut rng = flatland_testkit::rng(seed);
    let points = free_points(kernel, mesh, count, 0.05, &mut rng);
    assert_eq!(points.len(), count);
    points
        .into_iter()
        .map(|at| {
            let lights = [PointLight { at, power: 5.0 }];
            let lit = lit_source(&direct, mesh, &lights, &mut LightBuffers::default());
            let mut b0 = vec![0.0; mesh.len()];
            for &(j, b) in &lit {
                b0[j as usize] = b;
            }
            let mut later = vec![0.0; mesh.len()];
            let m = Move {
                lights: &lights,
                lit: &lit,
            };
            form.add_later_bounces(m, &mut later, &mut QueryBuffers::default())
                .unwrap();
            assert!(later.iter().all(|&v| v >= 0.0), "a negative later bounce");
            relative(mesh, &later, &exact_later(k, &b0))
        })
        .collect()
}
