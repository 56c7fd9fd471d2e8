//! The solve itself: the solution, `B = E + K B` by GMRES with any
//! representation's operator, a solution's errors, and the exact reference every solved B is
//! compared with.

use std::time::Instant;

use flatland_geom::{DVec2, Kernel};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::exact::{self, PairTable};
use crate::field::Receiver;
use crate::sweep::{self, SweepBuffers, SweepScene};
use crate::{
    DirectLight, ExactMethod, LitSurfaces, MAX_ELEMENTS, MAX_MESH_ELEMENTS, Mesh, Representation,
    SolveError, SolveParams, Stop, TransferOperator, check_scene, gmres,
};

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
pub fn solve<R: Representation + ?Sized>(
    rep: &R,
    mesh: &Mesh,
    params: &SolveParams,
    stop: &Stop,
) -> Result<Solution, SolveError> {
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
) -> Result<Solution, SolveError> {
    params.validate()?;
    if op.len() != mesh.len() {
        return Err(SolveError::InvalidParameter {
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

/// Solves `x − K x = rhs` by restarted GMRES from `initial` — a warm start, such as the last
/// solution of a slightly changed `K` — to `params.tolerance` (relative residual). The same
/// solve as [`solve_operator`], for any right-hand side (`assembly_s` is 0).
pub fn solve_linear(
    op: &dyn TransferOperator,
    rhs: &[f64],
    initial: Vec<f64>,
    params: &SolveParams,
    stop: &Stop,
) -> Result<Solution, SolveError> {
    params.validate()?;
    if op.len() != rhs.len() || initial.len() != rhs.len() {
        return Err(SolveError::InvalidParameter {
            name: "operator",
            value: format!(
                "{} elements, {} right-hand sides, {} initial values",
                op.len(),
                rhs.len(),
                initial.len()
            ),
            valid: "an operator, a right-hand side and a start of the same length",
        });
    }
    let started = Instant::now();
    let mut x = initial;
    let done = gmres::solve(
        op,
        rhs,
        &mut x,
        params.tolerance,
        params.max_iterations,
        stop,
    )?;
    Ok(Solution {
        radiosity: x,
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
    let scale = crate::reference::largest_finite(approx, exact);
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
/// Large scenes are solved by the visibility sweep ([`ExactMethod`]), so no pair of edges is
/// ever classified there: ground truth at 10⁵ edges.
#[derive(Clone, Debug)]
pub struct ExactReference {
    mesh: Mesh,
    visibility: Visibility,
    solution: Solution,
    /// What the scene's point lights see, for their irradiance at other points; `None`
    /// without lights.
    lit: Option<LitSurfaces>,
    /// Numbers its operator held: `n²` dense, the non-zeros by the sweep.
    nonzeros: usize,
}

/// What an [`ExactReference`] keeps to evaluate the exact transfer at other points.
#[derive(Clone, Debug)]
enum Visibility {
    /// The pair table of the dense operator (small scenes).
    Pairs(PairTable),
    /// The sweep's hierarchy of every edge (large scenes).
    Sweep(SweepScene),
}

impl ExactReference {
    /// Solves `kernel` exactly on `elements` elements.
    pub fn new(
        kernel: &Kernel,
        elements: usize,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<ExactReference, SolveError> {
        ExactReference::with_method(kernel, elements, ExactMethod::of(kernel), params, stop)
    }

    /// [`ExactReference::new`] assembled by `method`, whatever the scene's size.
    pub(crate) fn with_method(
        kernel: &Kernel,
        elements: usize,
        method: ExactMethod,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<ExactReference, SolveError> {
        method.check(elements)?;
        let mesh = Mesh::new(kernel, elements)?;
        ExactReference::on_mesh_with(kernel, mesh, method, params, stop)
    }

    /// Solves `kernel` exactly on `mesh` (a mesh of its scene: uniform, split or adapted), by
    /// [`ExactMethod::of`] the scene, or by the sweep where the mesh is past the dense limit.
    pub fn on_mesh(
        kernel: &Kernel,
        mesh: Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<ExactReference, SolveError> {
        let method = match ExactMethod::of(kernel) {
            ExactMethod::Dense if ExactMethod::Dense.check(mesh.len()).is_err() => {
                ExactMethod::Sweep
            }
            method => method,
        };
        check_scene(kernel, &mesh)?;
        ExactReference::on_mesh_with(kernel, mesh, method, params, stop)
    }

    pub(crate) fn on_mesh_with(
        kernel: &Kernel,
        mesh: Mesh,
        method: ExactMethod,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<ExactReference, SolveError> {
        params.validate()?;
        let started = Instant::now();
        let (visibility, op, nonzeros): (Visibility, Box<dyn TransferOperator>, usize) =
            match method {
                ExactMethod::Dense => {
                    let table = PairTable::new(kernel, &mesh)?;
                    let op = exact::exact_operator_with(&table, &mesh, stop)?;
                    (
                        Visibility::Pairs(table),
                        Box::new(op),
                        mesh.len() * mesh.len(),
                    )
                }
                ExactMethod::Sweep => {
                    check_scene(kernel, &mesh)?;
                    let scene = SweepScene::new(kernel.scene(), &mesh);
                    let op = sweep::sweep_operator_with(&scene, &mesh, true, stop)?;
                    let nonzeros = op.nonzeros();
                    (Visibility::Sweep(scene), Box::new(op), nonzeros)
                }
            };
        let assembly_s = started.elapsed().as_secs_f64();
        let mut solution = solve_operator(op.as_ref(), &mesh, params, stop)?;
        solution.assembly_s = assembly_s;
        let lights = kernel.scene().lights();
        let lit = if lights.is_empty() {
            None
        } else {
            Some(DirectLight::new(kernel, &mesh)?.lit(&mesh, lights))
        };
        Ok(ExactReference {
            mesh,
            visibility,
            solution,
            lit,
            nonzeros,
        })
    }

    /// A solve by the sweep on `mesh` already made: its hierarchy and solution (and what the
    /// scene's lights see, if it has any).
    pub(crate) fn from_sweep(
        mesh: Mesh,
        scene: SweepScene,
        solution: Solution,
        lit: Option<LitSurfaces>,
        nonzeros: usize,
    ) -> ExactReference {
        ExactReference {
            mesh,
            visibility: Visibility::Sweep(scene),
            solution,
            lit,
            nonzeros,
        }
    }

    /// Numbers its operator held: `n²` for a dense one, the non-zeros of the sweep's.
    #[must_use]
    pub fn nonzeros(&self) -> usize {
        self.nonzeros
    }

    /// The default fine resolution for comparing solutions on `elements` elements: four times
    /// finer, at least 2048, at most [`MAX_ELEMENTS`] (the dense limit; see
    /// [`ExactReference::default_elements_for`] for a scene the sweep solves).
    #[must_use]
    pub fn default_elements(elements: usize) -> usize {
        (4 * elements).clamp(2048, MAX_ELEMENTS)
    }

    /// [`ExactReference::default_elements`] for `kernel`'s scene: not capped at the dense limit
    /// where the sweep assembles the operator ([`ExactMethod`]), only at [`MAX_MESH_ELEMENTS`].
    #[must_use]
    pub fn default_elements_for(kernel: &Kernel, elements: usize) -> usize {
        match ExactMethod::of(kernel) {
            ExactMethod::Dense => ExactReference::default_elements(elements),
            ExactMethod::Sweep => (4 * elements).clamp(2048, MAX_MESH_ELEMENTS),
        }
    }

    /// How the exact operator was assembled: dense from pairs of edges, or by the sweep.
    #[must_use]
    pub fn method(&self) -> ExactMethod {
        match self.visibility {
            Visibility::Pairs(_) => ExactMethod::Dense,
            Visibility::Sweep(_) => ExactMethod::Sweep,
        }
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

    /// The exact B at the collocation points of `mesh` (a mesh of the same scene, lit by the
    /// same lights): the equation itself evaluated there,
    /// `E + ρ (H + Σ_j B_j ∫_{fine element j} G V)`, with the exact transfer and `H` the point
    /// lights' irradiance at the point itself ([`LitSurfaces::irradiance_at`]; a solved B
    /// holds the element's mean of it instead, so an element a shadow edge crosses differs
    /// from this by what piecewise constant B cannot hold). Rows in parallel; `stop` polled
    /// per point.
    pub fn radiosity_on(&self, mesh: &Mesh, stop: &Stop) -> Result<Vec<f64>, SolveError> {
        if mesh.fingerprint() != self.mesh.fingerprint() {
            return Err(SolveError::SceneMismatch {
                representation: format!("{:016x}", self.mesh.fingerprint()),
                mesh: format!("{:016x}", mesh.fingerprint()),
            });
        }
        if mesh.lights() != self.mesh.lights() {
            return Err(SolveError::InvalidParameter {
                name: "mesh",
                value: format!("lit by {} point lights", mesh.lights().len()),
                valid: "a mesh of the scene the reference was solved for, lit by the same \
                        point lights",
            });
        }
        let receivers: Vec<Receiver> = (0..mesh.len())
            .map(|i| Receiver {
                edge: mesh.elements()[i].mesh_edge,
                local: mesh.local(i)[2],
                point: mesh.elements()[i].midpoint,
            })
            .collect();
        self.gather_at(&receivers, stop)
    }

    /// [`ExactReference::radiosity_on`] with the lights' direct light taken as each element's
    /// mean instead of its value at the midpoint: what a solve on `mesh` holds at its
    /// collocation points (its source is `E + ρ H̄`), so a solution on `mesh` is compared with
    /// it like for like, with no error charged for the shadow edges inside its elements that
    /// element values cannot hold. The same as `radiosity_on` without lights.
    pub fn collocated_on(&self, mesh: &Mesh, stop: &Stop) -> Result<Vec<f64>, SolveError> {
        let mut b = self.radiosity_on(mesh, stop)?;
        if let Some(lit) = &self.lit {
            let means = mesh.direct_irradiance();
            for (i, v) in b.iter_mut().enumerate() {
                let e = mesh.elements()[i];
                let rho = mesh.edges()[e.mesh_edge].reflectance;
                let at_midpoint = lit.irradiance_at(mesh, e.mesh_edge, e.midpoint);
                *v += rho * (means[i] - at_midpoint);
            }
        }
        Ok(b)
    }

    /// B as a function: the exact B at the surface parameters `points` (each in `[0, 1)`),
    /// the equation itself evaluated there from this solve (the final gather, as
    /// [`ExactReference::radiosity_on`] at collocation points; a point at an end of its edge
    /// is taken just inside, see [`FinalGather`](crate::FinalGather)). Points in parallel;
    /// `stop` polled per point.
    pub fn radiosity_at(&self, points: &[f64], stop: &Stop) -> Result<Vec<f64>, SolveError> {
        let receivers: Vec<Receiver> = points
            .iter()
            .map(|&s| crate::field::locate(&self.mesh, s))
            .collect();
        self.gather_at(&receivers, stop)
    }

    /// The lights' reflected direct light `ρ H` at the surface parameters `points` (the
    /// irradiance at the point itself, sharp at shadow edges): 0 everywhere without lights.
    pub(crate) fn direct_at(&self, points: &[f64]) -> Vec<f64> {
        let Some(lit) = &self.lit else {
            return vec![0.0; points.len()];
        };
        points
            .iter()
            .map(|&s| {
                let r = crate::field::locate(&self.mesh, s);
                self.mesh.edges()[r.edge].reflectance
                    * lit.irradiance_at(&self.mesh, r.edge, r.point)
            })
            .collect()
    }

    /// `E + ρ (H + Σ_j B_j ∫_{fine element j} G V)` at each receiver.
    fn gather_at(&self, receivers: &[Receiver], stop: &Stop) -> Result<Vec<f64>, SolveError> {
        let b = &self.solution.radiosity;
        match &self.visibility {
            Visibility::Pairs(table) => self.interpolate(
                receivers,
                || vec![0.0; self.mesh.len()],
                |row, k, y| {
                    exact::transfer_row(&self.mesh, table, k, y, row, &exact::visible);
                    row.iter().zip(b).map(|(t, bj)| t * bj).sum()
                },
                stop,
            ),
            Visibility::Sweep(scene) => self.interpolate(
                receivers,
                SweepBuffers::default,
                |buffers, k, y| {
                    let row = sweep::transfers(scene, &self.mesh, k, y, true, buffers);
                    row.iter().map(|&(j, t)| t * b[j as usize]).sum()
                },
                stop,
            ),
        }
    }

    /// `E + ρ · (H + gather(scratch, k, y))` at every receiver (frame point `y` on mesh edge
    /// `k`, H the lights' irradiance there), where `gather` is `Σ_j B_j ∫_{fine element j} G V` at `y`; receivers in
    /// parallel, each thread with its own scratch from `init`.
    fn interpolate<S: Send>(
        &self,
        receivers: &[Receiver],
        init: impl Fn() -> S + Sync + Send,
        gather: impl Fn(&mut S, usize, DVec2) -> f64 + Sync + Send,
        stop: &Stop,
    ) -> Result<Vec<f64>, SolveError> {
        receivers
            .par_iter()
            .with_min_len(8)
            .map_init(init, |scratch, r| {
                if stop() {
                    return Err(SolveError::Interrupted);
                }
                let edge = &self.mesh.edges()[r.edge];
                if edge.reflectance == 0.0 {
                    return Ok(edge.emission);
                }
                let gathered = gather(scratch, r.edge, r.local);
                let direct = self
                    .lit
                    .as_ref()
                    .map_or(0.0, |lit| lit.irradiance_at(&self.mesh, r.edge, r.point));
                Ok(edge.emission + edge.reflectance * (direct + gathered))
            })
            .collect()
    }
}

/// One representation solved and compared: what a lit-scene view or a benchmark row needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// The solution with the representation.
    pub solution: Solution,
    /// Its errors against the exact B: as a function along the surfaces when a
    /// [`LitScene`](crate::LitScene) scored it, on the same elements from [`solve_against`].
    pub errors: SolveErrors,
}

/// Solves with `rep` on `mesh` and measures the errors against `exact` (the exact B at the
/// mesh's collocation points, from [`ExactReference::radiosity_on`]).
pub fn solve_against<R: Representation + ?Sized>(
    rep: &R,
    mesh: &Mesh,
    exact: &[f64],
    params: &SolveParams,
    stop: &Stop,
) -> Result<Comparison, SolveError> {
    if exact.len() != mesh.len() {
        return Err(SolveError::InvalidParameter {
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
    use super::*;
    use crate::test_support::{bundled, l_room, room, thin_wall_plan};
    use crate::{exact_operator, never, quadrature_operator};
    use flatland_geom::{DVec2, Edge, Scene};
    use flatland_testkit::assert_close;
    use rand::RngExt;

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
        let mut rng = flatland_testkit::rng(21);
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

    /// A floor plan whose walls are thin (two one-sided faces back to back, the way a two-sided
    /// wall must now be drawn): the exact solve, by the pair table and by the sweep, never
    /// gives negative radiosity, and B ≥ E everywhere (the light only adds). One radiosity for
    /// both sides of a two-sided wall gave row sums up to 2ρ and negative B here.
    #[test]
    fn a_floor_plan_of_thin_walls_solves_to_b_at_least_e() {
        for (cols, rows, seed) in [(2, 2, 1), (4, 3, 2), (6, 5, 3)] {
            let scene = thin_wall_plan(cols, rows, seed);
            let kernel = Kernel::new(scene);
            let elements = 4 * Mesh::min_elements(kernel.scene());
            let mesh = Mesh::new(&kernel, elements).unwrap();
            for method in [ExactMethod::Dense, ExactMethod::Sweep] {
                if method == ExactMethod::Dense && elements > 1500 {
                    continue;
                }
                let reference = ExactReference::with_method(
                    &kernel,
                    elements,
                    method,
                    &SolveParams::default(),
                    &never,
                )
                .unwrap();
                let b = &reference.solution().radiosity;
                let e = mesh.emission();
                let lit = b.iter().zip(&e).filter(|(b, e)| *b > *e).count();
                for (i, (b, e)) in b.iter().zip(&e).enumerate() {
                    assert!(
                        b.is_finite() && *b >= *e && *e >= 0.0,
                        "{cols} × {rows} rooms, {method:?}, element {i}: B = {b}, E = {e}"
                    );
                }
                // Light reaches most of the plan (through the doors), not just the lamps' rooms.
                assert!(
                    lit > b.len() / 2,
                    "{cols} × {rows}: only {lit} of {} lit",
                    b.len()
                );
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
        crate::test_support::power_balance(&op, &mesh)
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
            assert_close!(*a, *b, 1e-9 * a.max(1.0));
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
    fn a_closed_white_room_with_a_light_is_refused_not_nan() {
        let scene = room(&flatland_testkit::rooms::unit_square(), 1.0, 1.0);
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, 40).unwrap();
        let params = SolveParams {
            max_iterations: 200,
            ..SolveParams::default()
        };
        let err = solve(&kernel, &mesh, &params, &never).unwrap_err();
        assert!(matches!(err, SolveError::NotConverged { .. }), "{err}");
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

    #[test]
    fn small_scenes_keep_the_dense_path_bit_for_bit() {
        // Every bundled scene is below the crossover: the exact kernel's operator is the pair
        // table's, number for number, so every figure made with them stays what it was.
        for name in ["fig3", "box", "maze", "corners"] {
            let kernel = Kernel::new(bundled(name));
            assert_eq!(ExactMethod::of(&kernel), ExactMethod::Dense, "{name}");
            let mesh = Mesh::new(&kernel, 200).unwrap();
            let dense = exact_operator(&kernel, &mesh, &never).unwrap();
            let op = kernel
                .operator(&mesh, &SolveParams::default(), &never)
                .unwrap();
            let mut rng = flatland_testkit::rng(3);
            let b: Vec<f64> = (0..mesh.len())
                .map(|_| rng.random_range(0.0..1.0))
                .collect();
            let (mut expected, mut got) = (vec![0.0; mesh.len()], vec![0.0; mesh.len()]);
            dense.apply(&b, &mut expected);
            op.apply(&b, &mut got);
            assert_eq!(expected, got, "{name}");
            let reference =
                ExactReference::new(&kernel, 400, &SolveParams::default(), &never).unwrap();
            assert_eq!(reference.method(), ExactMethod::Dense);
        }
    }

    #[test]
    fn the_sweep_and_the_dense_path_give_the_same_reference() {
        // Above the crossover the sweep is used, and never a pair table; both methods give
        // the same solution and the same interpolated B, to rounding.
        let params = SolveParams::default();
        for scene in [
            crate::test_support::floor_plan(200),
            crate::test_support::hall(200),
        ] {
            let kernel = Kernel::new(scene);
            assert_eq!(ExactMethod::of(&kernel), ExactMethod::Sweep);
            let n = 2 * Mesh::min_elements(kernel.scene());
            let sweep = ExactReference::new(&kernel, n, &params, &never).unwrap();
            assert_eq!(sweep.method(), ExactMethod::Sweep);
            let dense =
                ExactReference::with_method(&kernel, n, ExactMethod::Dense, &params, &never)
                    .unwrap();
            let close = |a: &[f64], b: &[f64], what: &str| {
                for (i, (x, y)) in a.iter().zip(b).enumerate() {
                    assert!(
                        (x - y).abs() <= 1e-9 * x.abs().max(1e-3),
                        "{what} {i}: {x} vs {y}"
                    );
                }
            };
            close(
                &sweep.solution().radiosity,
                &dense.solution().radiosity,
                "B",
            );
            let coarse = Mesh::new(&kernel, Mesh::min_elements(kernel.scene()) + 7).unwrap();
            close(
                &sweep.radiosity_on(&coarse, &never).unwrap(),
                &dense.radiosity_on(&coarse, &never).unwrap(),
                "interpolated B",
            );
        }
    }

    #[test]
    fn reference_sizes_follow_the_method() {
        let small = Kernel::new(bundled("maze"));
        let large = Kernel::new(crate::test_support::floor_plan(200));
        assert_eq!(
            ExactReference::default_elements_for(&small, 4000),
            MAX_ELEMENTS
        );
        assert_eq!(ExactReference::default_elements_for(&small, 100), 2048);
        assert_eq!(ExactReference::default_elements_for(&large, 4000), 16000);
        let err = ExactReference::new(&small, MAX_ELEMENTS + 1, &SolveParams::default(), &never)
            .unwrap_err();
        assert!(err.to_string().contains("at most 8192"), "{err}");
    }
}
