//! Solve the Flatland radiosity equation with any kernel representation.
//!
//! `B(y) = E(y) + ρ(y) ∫ G(x, y) V(x, y) B(x) dl_x` on the surface edges; in the kernel's
//! parameters, `B(t) = E(t) + ∫ k(s, t) B(s) L ds`. B is the radiosity *leaving* a point,
//! emission included; `B − E` is the reflected part, the only part a kernel decides.
//!
//! **Discretisation.** A [`Mesh`] splits every surface edge into elements (never straddling
//! two edges, default count from the scene: [`Mesh::default_elements`]); B is constant per
//! element and the equation is collocated at element midpoints `y_i`:
//! `B_i = E_i + Σ_j K_ij B_j`, `K_ij = ρ_i ∫_{element j} G(x, y_i) V(x, y_i) dl_x`.
//! Midpoint collocation is second-order accurate away from corners.
//!
//! **Operators.** Each representation supplies its `K` through one trait,
//! [`KernelRepresentation`]:
//! - the exact kernel ([`flatland_geom::Kernel`]): the closed-form point-to-segment transfer
//!   `(sin φ₂ − sin φ₁) / 2` where the shaft test proves a pair of edges clear, and the exact
//!   visible part of each element elsewhere — no rays, no quadrature, so the solve converges as
//!   elements are refined ([`exact_operator`]);
//! - the default learned model ([`LearnedKernel`](crate::LearnedKernel), which keeps `G`
//!   exact and learns `V`): the closed-form transfer of each piece of an element between the
//!   faces of the visibility structure, times the model's `Ṽ` on that face — its own kernel,
//!   integrated exactly, with no ray; the paper's network (which learns ζ itself): Gauss–Legendre
//!   quadrature of `k̃ = ζ̃ / E'` (the default of the trait, [`quadrature_operator`]);
//! - hierarchical radiosity and the uniform grid: their own links or blocks, gathered and
//!   pushed–pulled ([`RectangleOperator`]).
//!
//! **Energy.** In a closed room of one-sided surfaces without blockers every sender's light
//! lands on a surface (`∫ G V dl_y = 1`), so the power the surfaces absorb, `∫ (1 − ρ) H dl`
//! with H the irradiance `(B − E) / ρ`, equals the power emitted, `∫ E dl` (tested to 0.2 % at
//! 512 elements). Blockers absorb too. A two-sided surface sends its one B from both sides,
//! so its emitted power counts twice.
//!
//! **Linear solve.** Restarted GMRES on `(I − K) B = E` to a relative residual
//! [`SolveParams::tolerance`] (default 1e-10); it needs only `I − K` invertible, not `‖K‖ < 1`.
//!
//! **Errors.** [`ExactReference`] solves the exact kernel on a fine mesh once and gives the
//! exact B at any mesh's collocation points (by the equation itself: `E + ρ ∫ G V B` with the
//! fine B, the Nyström interpolation). [`solve_errors`] then measures a solution's relative L2
//! error (element lengths as weights), of B and of the reflected part `B − E`.
//! [`solve_against`] does both for one representation: what a view or a benchmark row needs.
//!
//! ```
//! use flatland_geom::{DVec2, Edge, Kernel, Scene};
//! use kernel_fit::solve::{Mesh, SolveParams, never, solve};
//!
//! // A closed square room, uniform ρ = 0.5 and E = 1 everywhere: B = E / (1 − ρ) = 2.
//! let p = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)];
//! let edges = (0..4).map(|i| Edge::surface(p[i], p[(i + 1) % 4], 0.5).with_emission(1.0)).collect();
//! let kernel = Kernel::new(Scene::new(edges)?);
//! let mesh = Mesh::new(&kernel, 64)?;
//! let solution = solve(&kernel, &mesh, &SolveParams::default(), &never)?;
//! assert!(solution.radiosity.iter().all(|b| (b - 2.0).abs() < 1e-9));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod exact;
mod gmres;
mod learned;
mod mesh;
mod operator;
mod quadrature;
mod represent;
mod transfer;

#[cfg(test)]
mod independent;
#[cfg(test)]
pub(crate) mod test_support;

use std::time::Instant;

use flatland_geom::Kernel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::FitError;
pub use exact::exact_operator;
pub(crate) use exact::{PairTable, exact_block_means};
pub use mesh::{DEFAULT_ELEMENTS, Element, MAX_ELEMENTS, MIN_PER_EDGE, Mesh, MeshEdge};
pub use operator::{DenseOperator, KernelRectangle, RectangleOperator, TransferOperator};
pub use quadrature::gauss_legendre;
pub use represent::{KernelRepresentation, inverse_source_weights, quadrature_operator};
pub use transfer::{Receiver, Sender, point_to_segment, point_to_segment_visible};

/// The stop flag of every long loop here: polled between rows and iterations; when it returns
/// `true` the work ends with [`FitError::Interrupted`].
pub type Stop = dyn Fn() -> bool + Sync;

/// A [`Stop`] that never stops.
#[must_use]
pub fn never() -> bool {
    false
}

/// Settings of a solve, checked by [`SolveParams::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SolveParams {
    /// Relative residual `‖E − (I − K) B‖ / ‖E‖` the linear solve must reach. Valid: (0, 0.1].
    pub tolerance: f64,
    /// Most products with K before giving up. Valid: ≥ 1.
    pub max_iterations: usize,
    /// Gauss–Legendre points per element for the default (quadrature) operator. Valid: [1, 16].
    pub quadrature_points: usize,
}

impl Default for SolveParams {
    fn default() -> Self {
        SolveParams {
            tolerance: 1e-10,
            max_iterations: 2000,
            quadrature_points: 2,
        }
    }
}

impl SolveParams {
    /// Checks every field; the error names it and its valid range.
    pub fn validate(&self) -> Result<(), FitError> {
        let bad =
            |name, value: String, valid| Err(FitError::InvalidParameter { name, value, valid });
        if !(self.tolerance > 0.0 && self.tolerance <= 0.1) {
            return bad("tolerance", self.tolerance.to_string(), "in (0, 0.1]");
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "0".into(), "at least 1");
        }
        if !(1..=16).contains(&self.quadrature_points) {
            return bad(
                "quadrature_points",
                self.quadrature_points.to_string(),
                "in [1, 16]",
            );
        }
        Ok(())
    }
}

/// A solved radiosity.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// B per element (emission included), in the mesh's order.
    pub radiosity: Vec<f64>,
    /// Products with K the linear solve made.
    pub iterations: usize,
    /// Its final relative residual.
    pub residual: f64,
    /// Seconds spent building the operator.
    pub assembly_s: f64,
    /// Seconds spent in the linear solve.
    pub solve_s: f64,
}

impl Solution {
    /// Seconds for the whole solve (operator and linear solve).
    #[must_use]
    pub fn wall_s(&self) -> f64 {
        self.assembly_s + self.solve_s
    }
}

/// Solves `B = E + K B` on `mesh` with `rep`'s operator.
pub fn solve<R: KernelRepresentation + ?Sized>(
    rep: &R,
    mesh: &Mesh,
    params: &SolveParams,
    stop: &Stop,
) -> Result<Solution, FitError> {
    params.validate()?;
    let started = Instant::now();
    let op = rep.operator(mesh, params, stop)?;
    let assembly_s = started.elapsed().as_secs_f64();
    let mut solution = solve_operator(op.as_ref(), mesh, params, stop)?;
    solution.assembly_s = assembly_s;
    Ok(solution)
}

/// Solves `B = E + K B` with an operator already built on `mesh` (`assembly_s` is 0).
pub fn solve_operator(
    op: &dyn TransferOperator,
    mesh: &Mesh,
    params: &SolveParams,
    stop: &Stop,
) -> Result<Solution, FitError> {
    params.validate()?;
    if op.len() != mesh.len() {
        return Err(FitError::InvalidParameter {
            name: "operator",
            value: format!("{} elements", op.len()),
            valid: "an operator built on the mesh being solved",
        });
    }
    let started = Instant::now();
    let e = mesh.emission();
    let mut b = e.clone();
    let done = gmres::solve(
        op,
        &e,
        &mut b,
        params.tolerance,
        params.max_iterations,
        stop,
    )?;
    Ok(Solution {
        radiosity: b,
        iterations: done.iterations,
        residual: done.residual,
        assembly_s: 0.0,
        solve_s: started.elapsed().as_secs_f64(),
    })
}

/// Relative L2 errors of a solved B against the exact one, on the same elements, weighted by
/// element length: `sqrt(Σ l (b̃ − b)² / Σ l b²)`, and the same for the reflected part `B − E`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolveErrors {
    /// Of B.
    pub rel_l2_b: f64,
    /// Of `B − E`: the part the kernel decides.
    pub rel_l2_reflected: f64,
}

/// [`SolveErrors`] of `b` against `exact` on `mesh`. Scale-safe; where the exact value is 0
/// everywhere the absolute RMS is returned instead, so the number is always finite.
#[must_use]
pub fn solve_errors(mesh: &Mesh, b: &[f64], exact: &[f64]) -> SolveErrors {
    assert_eq!(b.len(), mesh.len(), "solve_errors: b is not on the mesh");
    assert_eq!(
        exact.len(),
        mesh.len(),
        "solve_errors: exact is not on the mesh"
    );
    let e = mesh.emission();
    let weights: Vec<f64> = mesh.elements().iter().map(|el| el.length).collect();
    let reflected = |v: &[f64]| -> Vec<f64> { v.iter().zip(&e).map(|(x, ei)| x - ei).collect() };
    SolveErrors {
        rel_l2_b: weighted_relative_l2(b, exact, &weights),
        rel_l2_reflected: weighted_relative_l2(&reflected(b), &reflected(exact), &weights),
    }
}

fn weighted_relative_l2(approx: &[f64], exact: &[f64], weights: &[f64]) -> f64 {
    let scale = crate::eval::largest_finite(approx, exact);
    if scale == 0.0 {
        return 0.0;
    }
    let total: f64 = weights.iter().sum();
    let (mut num, mut den) = (0.0, 0.0);
    for ((a, x), w) in approx.iter().zip(exact).zip(weights) {
        let w = w / total;
        num += w * ((a - x) / scale).powi(2);
        den += w * (x / scale).powi(2);
    }
    if den == 0.0 {
        num.sqrt() * scale
    } else {
        (num / den).sqrt()
    }
}

/// The exact kernel solved on a fine mesh: the reference every solved B is compared with.
#[derive(Clone, Debug)]
pub struct ExactReference {
    mesh: Mesh,
    table: PairTable,
    solution: Solution,
}

impl ExactReference {
    /// Solves `kernel` exactly on `elements` elements.
    pub fn new(
        kernel: &Kernel,
        elements: usize,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<ExactReference, FitError> {
        params.validate()?;
        let mesh = Mesh::new(kernel, elements)?;
        let started = Instant::now();
        let table = PairTable::new(kernel, &mesh)?;
        let op = exact::exact_operator_with(&table, &mesh, stop)?;
        let assembly_s = started.elapsed().as_secs_f64();
        let mut solution = solve_operator(&op, &mesh, params, stop)?;
        solution.assembly_s = assembly_s;
        Ok(ExactReference {
            mesh,
            table,
            solution,
        })
    }

    /// The default fine resolution for comparing solutions on `elements` elements: four times
    /// finer, at least 2048, at most [`MAX_ELEMENTS`].
    #[must_use]
    pub fn default_elements(elements: usize) -> usize {
        (4 * elements).clamp(2048, MAX_ELEMENTS)
    }

    /// The fine mesh.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The fine solution.
    #[must_use]
    pub fn solution(&self) -> &Solution {
        &self.solution
    }

    /// The exact B at the collocation points of `mesh` (a mesh of the same scene): the
    /// equation itself evaluated there, `E + ρ Σ_j B_j ∫_{fine element j} G V`, with the
    /// exact transfer. Rows in parallel; `stop` polled per point.
    pub fn radiosity_on(&self, mesh: &Mesh, stop: &Stop) -> Result<Vec<f64>, FitError> {
        if mesh.fingerprint() != self.mesh.fingerprint() {
            return Err(FitError::SceneMismatch {
                representation: format!("{:016x}", self.mesh.fingerprint()),
                mesh: format!("{:016x}", mesh.fingerprint()),
            });
        }
        let b = &self.solution.radiosity;
        (0..mesh.len())
            .into_par_iter()
            .with_min_len(8)
            .map_init(
                || vec![0.0; self.mesh.len()],
                |row, i| {
                    if stop() {
                        return Err(FitError::Interrupted);
                    }
                    let edge = mesh.edge_of(i);
                    let k = mesh.elements()[i].mesh_edge;
                    if edge.reflectance == 0.0 {
                        return Ok(edge.emission);
                    }
                    exact::transfer_row(
                        &self.mesh,
                        &self.table,
                        k,
                        mesh.local(i)[2],
                        row,
                        &exact::visible,
                    );
                    let gathered: f64 = row.iter().zip(b).map(|(t, bj)| t * bj).sum();
                    Ok(edge.emission + edge.reflectance * gathered)
                },
            )
            .collect()
    }
}

/// One representation solved and compared: what a lit-scene view or a benchmark row needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// The solution with the representation.
    pub solution: Solution,
    /// Its errors against the exact B on the same elements.
    pub errors: SolveErrors,
}

/// Solves with `rep` on `mesh` and measures the errors against `exact` (the exact B at the
/// mesh's collocation points, from [`ExactReference::radiosity_on`]).
pub fn solve_against<R: KernelRepresentation + ?Sized>(
    rep: &R,
    mesh: &Mesh,
    exact: &[f64],
    params: &SolveParams,
    stop: &Stop,
) -> Result<Comparison, FitError> {
    if exact.len() != mesh.len() {
        return Err(FitError::InvalidParameter {
            name: "exact",
            value: format!("{} values", exact.len()),
            valid: "one exact B per element of the mesh",
        });
    }
    let solution = solve(rep, mesh, params, stop)?;
    let errors = solve_errors(mesh, &solution.radiosity, exact);
    Ok(Comparison { solution, errors })
}

#[cfg(test)]
mod tests {
    use super::test_support::{bundled, l_room, room};
    use super::*;
    use crate::baselines::{BlockValue, HrParams, UniformGrid, UniformParams, run_hr_at_budget};
    use flatland_geom::{DVec2, Edge, KernelParams, Scene};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn exact(scene: Scene, elements: usize) -> (Kernel, Mesh, Solution) {
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, elements).unwrap();
        let solution = solve(&kernel, &mesh, &SolveParams::default(), &never).unwrap();
        (kernel, mesh, solution)
    }

    /// Random convex polygons: sorted angles on an ellipse, counter-clockwise.
    fn convex_rooms(count: usize, rho: f64, e: f64) -> Vec<Scene> {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        (0..count)
            .map(|_| {
                let mut angles: Vec<f64> = (0..rng.random_range(3..9))
                    .map(|_| rng.random_range(0.0..std::f64::consts::TAU))
                    .collect();
                angles.sort_by(f64::total_cmp);
                angles.dedup_by(|a, b| (*a - *b).abs() < 0.05);
                let pts: Vec<DVec2> = angles.iter().map(|a| v(2.0 * a.cos(), a.sin())).collect();
                room(&pts, rho, e)
            })
            .collect()
    }

    #[test]
    fn uniform_emission_and_reflectance_in_a_closed_convex_room_gives_e_over_one_minus_rho() {
        // B = E + ρ ∫ G B dl and ∫ G dl = 1 from every point of a closed room: B = E / (1 − ρ).
        for (k, scene) in convex_rooms(4, 0.0, 0.0).into_iter().enumerate() {
            for (rho, e) in [(0.3, 1.0), (0.9, 2.5), (0.999, 1e-3)] {
                let edges: Vec<Edge> = scene
                    .edges()
                    .iter()
                    .map(|edge| Edge {
                        reflectance: rho,
                        emission: e,
                        ..*edge
                    })
                    .collect();
                let (_, _, solution) = exact(Scene::new(edges).unwrap(), 97);
                let expected = e / (1.0 - rho);
                for b in &solution.radiosity {
                    assert!(
                        (b - expected).abs() <= 1e-8 * expected,
                        "room {k}, ρ = {rho}: B = {b} vs {expected}"
                    );
                }
            }
        }
    }

    #[test]
    fn zero_reflectance_gives_b_equal_to_e() {
        for name in ["fig3", "maze", "corners"] {
            let scene = bundled(name);
            let edges: Vec<Edge> = scene
                .edges()
                .iter()
                .map(|e| Edge {
                    reflectance: 0.0,
                    ..*e
                })
                .collect();
            let (_, mesh, solution) = exact(Scene::new(edges).unwrap(), 128);
            assert_eq!(solution.radiosity, mesh.emission(), "{name}");
        }
    }

    /// Emitted and absorbed power of an exact solve in a closed room without blockers (where
    /// every ray from a surface ends on a surface): `∫ E dl` and `∫ (1 − ρ) H dl`, with H the
    /// irradiance `(K B)_i / ρ_i`.
    fn power_balance(scene: Scene, elements: usize) -> (f64, f64) {
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, elements).unwrap();
        let op = exact_operator(&kernel, &mesh, &never).unwrap();
        let solution = solve_operator(&op, &mesh, &SolveParams::default(), &never).unwrap();
        let mut gathered = vec![0.0; mesh.len()];
        op.apply(&solution.radiosity, &mut gathered);
        let (mut emitted, mut absorbed) = (0.0, 0.0);
        for (i, el) in mesh.elements().iter().enumerate() {
            let edge = mesh.edge_of(i);
            emitted += edge.emission * el.length;
            absorbed += (1.0 - edge.reflectance) * gathered[i] / edge.reflectance * el.length;
        }
        (emitted, absorbed)
    }

    #[test]
    fn emitted_power_equals_absorbed_power_in_closed_rooms() {
        // In a closed room every sender's light lands somewhere (∫ G V dl_y = 1), so what the
        // surfaces absorb, ∫ (1 − ρ) H, is what they emit, ∫ E. Collocation conserves it up to
        // the discretisation: the stated tolerance is 0.2 % at 512 elements.
        let mut rooms = vec![bundled("box"), l_room(0.6)];
        rooms.extend(convex_rooms(3, 0.0, 0.0).into_iter().map(|scene| {
            let mut edges = scene.edges().to_vec();
            for (i, e) in edges.iter_mut().enumerate() {
                e.reflectance = 0.2 + 0.1 * i as f64 % 0.7;
            }
            edges[0].emission = 3.0;
            Scene::new(edges).unwrap()
        }));
        for scene in rooms {
            let (emitted, absorbed) = power_balance(scene.clone(), 512);
            assert!(
                (emitted - absorbed).abs() <= 2e-3 * emitted,
                "emitted {emitted} vs absorbed {absorbed} in {scene:?}"
            );
        }
    }

    #[test]
    fn exact_solve_converges_with_refinement() {
        // Against a 4096-element solve, at the midpoints of a common 64-element probe mesh
        // (printed as the convergence table): every doubling must gain, the whole range 50×.
        for name in ["fig3", "maze", "corners"] {
            let kernel = Kernel::new(bundled(name));
            let params = SolveParams::default();
            let fine = ExactReference::new(&kernel, 4096, &params, &never).unwrap();
            let probes = Mesh::new(&kernel, 64).unwrap();
            let truth = fine.radiosity_on(&probes, &never).unwrap();
            let mut errors = Vec::new();
            for n in [64, 128, 256, 512, 1024, 2048] {
                let reference = ExactReference::new(&kernel, n, &params, &never).unwrap();
                let b = reference.radiosity_on(&probes, &never).unwrap();
                let e = solve_errors(&probes, &b, &truth);
                println!(
                    "{name}: {n:>5} elements: rel. L2 of B {:.2e}, of B − E {:.2e}",
                    e.rel_l2_b, e.rel_l2_reflected
                );
                errors.push(e.rel_l2_reflected);
            }
            for w in errors.windows(2) {
                assert!(w[1] < w[0], "{name}: no convergence: {errors:?}");
            }
            assert!(errors[5] < errors[0] / 50.0, "{name}: too slow: {errors:?}");
            assert!(
                errors[3] < 1e-3,
                "{name}: 512 elements are not within 0.1 %: {errors:?}"
            );
        }
    }

    #[test]
    fn subdividing_the_scene_leaves_the_solution_unchanged() {
        let (_, coarse_mesh, coarse) = exact(bundled("maze"), 300);
        let (_, fine_mesh, fine) = exact(bundled("maze").subdivide(50).unwrap(), 300);
        assert_eq!(coarse_mesh.len(), fine_mesh.len());
        for (a, b) in coarse.radiosity.iter().zip(&fine.radiosity) {
            assert!((a - b).abs() <= 1e-9 * a.max(1.0), "{a} vs {b}");
        }
    }

    #[test]
    fn every_representation_solves_through_the_one_trait() {
        let kernel = Kernel::new(bundled("fig3"));
        let mesh = Mesh::new(&kernel, 256).unwrap();
        let params = SolveParams::default();
        let truth = ExactReference::new(&kernel, 2048, &params, &never)
            .unwrap()
            .radiosity_on(&mesh, &never)
            .unwrap();
        let exact_b = solve_against(&kernel, &mesh, &truth, &params, &never).unwrap();
        assert!(
            exact_b.errors.rel_l2_reflected < 5e-3,
            "{:?}",
            exact_b.errors
        );
        let hr = run_hr_at_budget(&kernel, 400, 1, &HrParams::default())
            .unwrap()
            .approx;
        let uniform = UniformGrid::build(&kernel, 20, &UniformParams::default(), 1).unwrap();
        let exact_means = |block_value| {
            UniformGrid::build(
                &kernel,
                20,
                &UniformParams {
                    block_value,
                    ..UniformParams::default()
                },
                1,
            )
            .unwrap()
        };
        let reps: Vec<(&str, &dyn KernelRepresentation)> = vec![("hr", &hr), ("uniform", &uniform)];
        for (name, rep) in reps {
            let c = solve_against(rep, &mesh, &truth, &params, &never).unwrap();
            assert!(c.solution.radiosity.iter().all(|b| b.is_finite()), "{name}");
            assert!(
                c.errors.rel_l2_reflected.is_finite()
                    && c.errors.rel_l2_reflected > exact_b.errors.rel_l2_reflected,
                "{name}: {:?}",
                c.errors
            );
            println!("fig3, {name} at 400: {:?}", c.errors);
        }
        for block_value in [BlockValue::ExactZetaMean, BlockValue::ExactKernelMean] {
            let grid = exact_means(block_value);
            let c = solve_against(&grid, &mesh, &truth, &params, &never).unwrap();
            println!("fig3, uniform {block_value:?} 20×20: {:?}", c.errors);
            assert!(c.errors.rel_l2_reflected.is_finite());
        }
    }

    #[test]
    fn piecewise_constant_operators_equal_brute_force_integration_of_their_own_zeta() {
        // HR's gather/push–pull and the uniform grid's blocks against ∫ ζ̃(s, t_i) / E' L ds by
        // dense midpoint sampling of their own ζ̃ (which jumps where a link or block ends inside
        // an element, so the sampling error is below jump / samples per element).
        let kernel = Kernel::new(bundled("fig3"));
        let mesh = Mesh::new(&kernel, 60).unwrap();
        let params = SolveParams::default();
        let hr = run_hr_at_budget(&kernel, 200, 1, &HrParams::default())
            .unwrap()
            .approx;
        let grid = UniformGrid::build(&kernel, 12, &UniformParams::default(), 1).unwrap();
        let k_grid = UniformGrid::build(
            &kernel,
            12,
            &UniformParams {
                block_value: BlockValue::ExactKernelMean,
                ..UniformParams::default()
            },
            1,
        )
        .unwrap();
        let inverse = inverse_source_weights(&mesh).unwrap();
        let reps: [&dyn KernelRepresentation; 3] = [&hr, &grid, &k_grid];
        let samples = 4000;
        for rep in reps {
            let fast = solve(rep, &mesh, &params, &never).unwrap();
            let els = mesh.elements();
            let brute = DenseOperator::assemble(
                mesh.len(),
                |i, row| {
                    for (j, e) in els.iter().enumerate() {
                        let sum: f64 = (0..samples)
                            .map(|q| {
                                let s =
                                    e.s[0] + (e.s[1] - e.s[0]) * (q as f64 + 0.5) / samples as f64;
                                rep.zeta(s, els[i].s_mid)
                            })
                            .sum();
                        row[j] = sum / samples as f64 * e.length * inverse[e.mesh_edge];
                    }
                },
                &never,
            )
            .unwrap();
            let slow = solve_operator(&brute, &mesh, &params, &never).unwrap();
            let e = solve_errors(&mesh, &fast.radiosity, &slow.radiosity);
            assert!(e.rel_l2_reflected < 1e-3, "{e:?}");
        }
    }

    #[test]
    fn the_default_quadrature_of_the_exact_zeta_approaches_the_exact_operator() {
        // The generic path (ζ̃ / E' by Gauss–Legendre) fed the exact ζ: what it loses is only
        // quadrature at shadow edges and next to corners, and it shrinks with more points.
        let kernel = Kernel::new(bundled("fig3"));
        let mesh = Mesh::new(&kernel, 256).unwrap();
        let params = SolveParams::default();
        let exact_b = solve(&kernel, &mesh, &params, &never).unwrap().radiosity;
        let mut errors = Vec::new();
        for points in [1, 2, 4, 8] {
            let op = quadrature_operator(&kernel, &mesh, points, &never).unwrap();
            let b = solve_operator(&op, &mesh, &params, &never)
                .unwrap()
                .radiosity;
            let e = solve_errors(&mesh, &b, &exact_b);
            println!("fig3, quadrature of exact ζ, {points} points: {e:?}");
            errors.push(e.rel_l2_reflected);
        }
        assert!(errors[3] < errors[0] && errors[3] < 0.01, "{errors:?}");
    }

    #[test]
    fn representations_of_zeta_refuse_zero_source_weights_and_other_scenes() {
        let scene = bundled("fig3");
        let kernel = Kernel::with_params(
            scene.clone(),
            KernelParams {
                emission_floor: 0.0,
            },
        )
        .unwrap();
        let mesh = Mesh::new(&kernel, 64).unwrap();
        let grid = UniformGrid::build(&kernel, 4, &UniformParams::default(), 1).unwrap();
        let err = solve(&grid, &mesh, &SolveParams::default(), &never)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("surface edge 0 has source weight E' = 0"),
            "{err}"
        );
        // The exact kernel needs no E'.
        assert!(solve(&kernel, &mesh, &SolveParams::default(), &never).is_ok());
        // A mesh of another scene.
        let other = Mesh::new(&Kernel::new(bundled("box")), 64).unwrap();
        let err = solve(&kernel, &other, &SolveParams::default(), &never)
            .unwrap_err()
            .to_string();
        assert!(err.contains("fingerprint"), "{err}");
        // Stop.
        let err = solve(&kernel, &mesh, &SolveParams::default(), &|| true).unwrap_err();
        assert!(matches!(err, FitError::Interrupted), "{err}");
        let bad = SolveParams {
            tolerance: 0.0,
            ..SolveParams::default()
        };
        assert!(
            solve(&kernel, &mesh, &bad, &never)
                .unwrap_err()
                .to_string()
                .contains("tolerance")
        );
    }

    #[test]
    fn a_closed_white_room_with_a_light_is_refused_not_nan() {
        let p = [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        let scene = room(&p, 1.0, 1.0);
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, 40).unwrap();
        let params = SolveParams {
            max_iterations: 200,
            ..SolveParams::default()
        };
        let err = solve(&kernel, &mesh, &params, &never).unwrap_err();
        assert!(matches!(err, FitError::NotConverged { .. }), "{err}");
    }

    #[test]
    fn solve_errors_weigh_by_length_and_stay_finite() {
        let kernel = Kernel::new(bundled("fig3"));
        let mesh = Mesh::new(&kernel, 14).unwrap();
        let e = mesh.emission();
        let exact: Vec<f64> = e.iter().map(|x| x + 0.5).collect();
        let same = solve_errors(&mesh, &exact, &exact);
        assert_eq!((same.rel_l2_b, same.rel_l2_reflected), (0.0, 0.0));
        let off: Vec<f64> = exact.iter().map(|x| x * 1.1).collect();
        let err = solve_errors(&mesh, &off, &exact);
        assert!(err.rel_l2_b > 0.09 && err.rel_l2_b < 0.11, "{err:?}");
        // Nothing reflected anywhere: absolute RMS instead of a division by zero.
        let err = solve_errors(&mesh, &e, &e);
        assert_eq!(err.rel_l2_reflected, 0.0);
    }
}
