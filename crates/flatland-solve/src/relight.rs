//! The exact re-solve of one scene lit again and again: the exact operator built once, and per
//! move of the point lights only what the move changes.
//!
//! With the lights `ℓ` of a move, `B = B₀ + K B`, `B₀ = E + ρ H̄(ℓ)` (docs/ALGORITHM.md §1a):
//! E the emitting edges' static light, H̄ the lights' exact mean irradiance per element. Per
//! move the relighter computes
//! 1. **the direct light** by one view of the sweep's hierarchy per light ([`DirectLight`]):
//!    `O(log n + seen)`, and `B₀` from it;
//! 2. **the first bounce** `K B₀ = K E + Σ_{j lit} K_{·j} ρ_j H̄_j`: `K E` once at set-up, and
//!    only the columns of the elements the lights lit, from a transposed copy of the operator
//!    (the rows gather, the columns scatter);
//! 3. **the later bounces** by GMRES on `(I − K) B = B₀`, started from
//!    `B₀ + K B₀ + L_prev`, `L_prev = B − B₀ − K B₀` of the last move ([`WarmStart`]): the
//!    light that has bounced twice or more changes least as a light moves, so the start is
//!    closest there.
//!
//! What a move costs is reported ([`MoveCost`]); its vectors live in the relighter, so a move
//! allocates nothing once the first has sized them. Memory is the operator twice (rows and
//! columns, [`Relighter::memory_bytes`]) plus a few vectors and the GMRES basis.

use std::sync::Arc;
use std::time::Instant;

use flatland_geom::{Kernel, LightCheck, PointLight};

use crate::gmres::{Finish, Gmres, Limits};
use crate::sweep::{SweepScene, sweep_operator_with};
use crate::{
    DirectLight, LightBuffers, Mesh, Solution, SolveError, SolveErrors, SolveParams,
    SparseOperator, Stop, TransferOperator, check_scene, solve_errors, solve_operator,
};

/// Where each move's GMRES starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WarmStart {
    /// `B₀ + K B₀ + (B − B₀ − K B₀)` of the last move: this move's exact first two terms and
    /// the last move's later bounces (the first move starts from `B₀ + K B₀`).
    LaterBounces,
    /// The last move's B (the first from `B₀`).
    LastRadiosity,
    /// `B₀` every move, as a one-off solve starts.
    Cold,
}

/// Settings of a relighter, checked by [`RelightParams::check`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelightParams {
    /// The relative residual `‖B₀ − (I − K) B‖ / ‖B₀‖` each move's solve reaches. Valid:
    /// `(0, 0.1]`. The default, 1e-6, leaves B within about 1e-6 of the solve to 1e-10, four
    /// decades below the discretization error a mesh is chosen for (1 %).
    pub tolerance: f64,
    /// Most products with K per move. Valid: ≥ 1.
    pub max_iterations: usize,
    /// Where each move's solve starts.
    pub warm_start: WarmStart,
}

impl Default for RelightParams {
    fn default() -> Self {
        RelightParams {
            tolerance: 1e-6,
            max_iterations: 2000,
            warm_start: WarmStart::LaterBounces,
        }
    }
}

impl RelightParams {
    /// Checks every field; the error names it and its valid range.
    pub fn check(&self) -> Result<(), SolveError> {
        SolveParams {
            tolerance: self.tolerance,
            max_iterations: self.max_iterations,
            ..SolveParams::default()
        }
        .validate()
    }
}

/// What one move cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MoveCost {
    /// Elements the lights lit (directly).
    pub lit_elements: usize,
    /// Numbers of the operator's columns read for the first bounce.
    pub first_bounce_reads: usize,
    /// Products with K the later bounces took (GMRES steps, the first residual included).
    pub products: usize,
    /// The relative residual reached.
    pub residual: f64,
    /// Seconds for the direct light and `B₀`.
    pub direct_s: f64,
    /// Seconds for the first bounce `K B₀`.
    pub first_bounce_s: f64,
    /// Seconds for the later bounces (the linear solve).
    pub solve_s: f64,
}

impl MoveCost {
    /// Seconds for the whole move.
    #[must_use]
    pub fn seconds(&self) -> f64 {
        self.direct_s + self.first_bounce_s + self.solve_s
    }
}

/// A move's result: borrowed from the relighter until the next move.
#[derive(Clone, Copy, Debug)]
pub struct Relit<'a> {
    /// B per element, in the mesh's order.
    pub radiosity: &'a [f64],
    /// The source `B₀ = E + ρ H̄`: the static emission and the lights' direct light.
    pub source: &'a [f64],
    /// The first bounce `K B₀`.
    pub first_bounce: &'a [f64],
    /// What the move cost.
    pub cost: MoveCost,
}

/// The exact re-solve of one scene and mesh under any point lights (see the module docs):
/// built once ([`Relighter::new`]), then [`Relighter::relight`] per move.
#[derive(Debug)]
pub struct Relighter {
    built: Arc<Built>,
    params: RelightParams,
    state: State,
}

/// What a relighter builds once, shared by the relighters made from it
/// ([`Relighter::with_params`]).
#[derive(Debug)]
struct Built {
    mesh: Mesh,
    rows: SparseOperator,
    columns: SparseOperator,
    direct: DirectLight,
    lights: LightCheck,
    /// E per element (the emitting edges) and `K E`.
    emission: Vec<f64>,
    emission_bounce: Vec<f64>,
    /// `ρ_i / (2π l_i)`: a light's power times the angle it lights element `i` under, times
    /// this, is its share of `ρ H̄_i`.
    direct_per_radian: Vec<f64>,
    setup_s: f64,
}

/// The vectors of the current move and what carries over to the next.
#[derive(Debug, Default)]
struct State {
    radiosity: Vec<f64>,
    source: Vec<f64>,
    first_bounce: Vec<f64>,
    /// `ρ H̄_j` of each element lit this move, by element (summed over the lights).
    lit: Vec<(u32, f64)>,
    /// The later bounces of the last move, `B − B₀ − K B₀`; empty before the first.
    later: Vec<f64>,
    views: LightBuffers,
    gmres: Gmres,
}

impl Relighter {
    /// Builds the relighter of `kernel`'s scene on `mesh` (a mesh of that scene; its own
    /// lights, if any, are not used: each move brings its own): the sweep's hierarchy, the
    /// exact operator by rows and by columns, and the first bounce of the emitting edges.
    /// `stop` is polled once per row of the operator (a caller may count the polls as
    /// progress: there are `mesh.len()` of them, then a few).
    pub fn new(
        kernel: &Kernel,
        mesh: &Mesh,
        params: RelightParams,
        stop: &Stop,
    ) -> Result<Relighter, SolveError> {
        params.check()?;
        check_scene(kernel, mesh)?;
        let started = Instant::now();
        let scene = SweepScene::new(kernel.scene(), mesh);
        let rows = sweep_operator_with(&scene, mesh, true, stop)?;
        let columns = rows.transposed();
        let emission: Vec<f64> = (0..mesh.len()).map(|i| mesh.edge_of(i).emission).collect();
        let mut emission_bounce = vec![0.0; mesh.len()];
        rows.apply(&emission, &mut emission_bounce);
        let direct_per_radian = mesh
            .elements()
            .iter()
            .map(|e| mesh.edges()[e.mesh_edge].reflectance / (std::f64::consts::TAU * e.length))
            .collect();
        let built = Built {
            mesh: mesh.clone(),
            rows,
            columns,
            direct: DirectLight::of_sweep(scene),
            lights: LightCheck::new(kernel.scene()),
            emission,
            emission_bounce,
            direct_per_radian,
            setup_s: started.elapsed().as_secs_f64(),
        };
        Ok(Relighter {
            built: Arc::new(built),
            params,
            state: State::default(),
        })
    }

    /// Another relighter on the same operator (shared, not built again nor copied), with its
    /// own settings and its own last move.
    pub fn with_params(&self, params: RelightParams) -> Result<Relighter, SolveError> {
        params.check()?;
        Ok(Relighter {
            built: Arc::clone(&self.built),
            params,
            state: State::default(),
        })
    }

    /// Lights the scene with `lights` (its emitting edges stay on): B, its source B₀, its
    /// first bounce `K B₀` and what the move cost. Errors: a light that is not finite, of
    /// negative power or on an edge (named by its index), a solve that does not converge, or
    /// `stop`.
    pub fn relight(&mut self, lights: &[PointLight], stop: &Stop) -> Result<Relit<'_>, SolveError> {
        self.built.lights.check(lights)?;
        let started = Instant::now();
        self.direct_light(lights);
        let direct_s = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let reads = self.first_bounce();
        let first_bounce_s = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let done = self.later_bounces(stop)?;
        let cost = MoveCost {
            lit_elements: self.state.lit.len(),
            first_bounce_reads: reads,
            products: done.0,
            residual: done.1,
            direct_s,
            first_bounce_s,
            solve_s: started.elapsed().as_secs_f64(),
        };
        let s = &self.state;
        Ok(Relit {
            radiosity: &s.radiosity,
            source: &s.source,
            first_bounce: &s.first_bounce,
            cost,
        })
    }

    /// `B₀ = E + ρ H̄` into the state, and the lit elements' `ρ H̄`.
    fn direct_light(&mut self, lights: &[PointLight]) {
        let (s, b) = (&mut self.state, &*self.built);
        s.lit.clear();
        for light in lights.iter().filter(|l| l.power > 0.0) {
            for &(j, angle) in b.direct.view(&b.mesh, light.at, &mut s.views) {
                let value = light.power * angle * b.direct_per_radian[j as usize];
                s.lit.push((j, value));
            }
        }
        // Several lights: one entry per element, summed in the lights' order.
        s.lit.sort_by_key(|&(j, _)| j);
        s.lit.dedup_by(|later, kept| {
            let same = later.0 == kept.0;
            if same {
                kept.1 += later.1;
            }
            same
        });
        s.lit.retain(|&(_, v)| v != 0.0);
        s.source.clone_from(&b.emission);
        for &(j, v) in &s.lit {
            s.source[j as usize] += v;
        }
    }

    /// `K B₀ = K E + Σ_{j lit} K_{·j} ρ_j H̄_j` into the state: the numbers read.
    fn first_bounce(&mut self) -> usize {
        let (s, b) = (&mut self.state, &*self.built);
        s.first_bounce.clone_from(&b.emission_bounce);
        b.columns.gather_columns(&s.lit, &mut s.first_bounce)
    }

    /// The solve from the warm start: products with K and the residual reached.
    fn later_bounces(&mut self, stop: &Stop) -> Result<(usize, f64), SolveError> {
        let (s, b) = (&mut self.state, &*self.built);
        let n = b.mesh.len();
        let first = s.later.is_empty();
        match self.params.warm_start {
            WarmStart::Cold => s.radiosity.clone_from(&s.source),
            WarmStart::LastRadiosity if first => s.radiosity.clone_from(&s.source),
            WarmStart::LastRadiosity => {}
            WarmStart::LaterBounces => {
                s.radiosity.resize(n, 0.0);
                let later = s.later.iter().copied().chain(std::iter::repeat(0.0));
                let start = s.source.iter().zip(&s.first_bounce).zip(later);
                for (b, ((b0, b1), l)) in s.radiosity.iter_mut().zip(start) {
                    *b = b0 + b1 + l;
                }
            }
        }
        let limits = Limits {
            tolerance: self.params.tolerance,
            max_iterations: self.params.max_iterations,
            finish: Finish::Estimate,
        };
        let done = s
            .gmres
            .solve(&b.rows, &s.source, &mut s.radiosity, limits, stop)?;
        s.later.resize(n, 0.0);
        let parts = s.source.iter().zip(&s.first_bounce);
        for ((l, b), (b0, b1)) in s.later.iter_mut().zip(&s.radiosity).zip(parts) {
            *l = b - b0 - b1;
        }
        // The first residual is one product more than the Krylov steps.
        Ok((done.iterations + 1, done.residual))
    }

    /// Forgets the last move: the next starts as the first does.
    pub fn forget(&mut self) {
        self.state.later.clear();
    }

    /// The mesh every move is solved on.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.built.mesh
    }

    /// The exact operator by rows: `(K b)_i = Σ_j K_ij b_j`.
    #[must_use]
    pub fn rows(&self) -> &SparseOperator {
        &self.built.rows
    }

    /// The same operator by columns: row `j` of this is column `j` of K
    /// ([`SparseOperator::transposed`]).
    #[must_use]
    pub fn columns(&self) -> &SparseOperator {
        &self.built.columns
    }

    /// The exact direct light of point lights on the mesh (the sweep's hierarchy).
    #[must_use]
    pub fn direct(&self) -> &DirectLight {
        &self.built.direct
    }

    /// The static source E per element: the emitting edges.
    #[must_use]
    pub fn emission(&self) -> &[f64] {
        &self.built.emission
    }

    /// Its settings.
    #[must_use]
    pub fn params(&self) -> RelightParams {
        self.params
    }

    /// Seconds [`Relighter::new`] took.
    #[must_use]
    pub fn setup_s(&self) -> f64 {
        self.built.setup_s
    }

    /// Bytes held: the operator's rows and columns, the vectors and the GMRES work space
    /// (as allocated; the sweep's hierarchy is a few numbers per edge and not counted). A
    /// relighter made by [`Relighter::with_params`] counts the operator it shares.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        let (s, b) = (&self.state, &*self.built);
        let vectors = [
            &b.emission,
            &b.emission_bounce,
            &b.direct_per_radian,
            &s.radiosity,
            &s.source,
            &s.first_bounce,
            &s.later,
        ];
        b.rows.memory_bytes()
            + b.columns.memory_bytes()
            + 8 * vectors.iter().map(|v| v.capacity()).sum::<usize>()
            + 12 * s.lit.capacity()
            + s.gmres.memory_bytes()
    }
}

/// A full, cold, independent exact solve of `kernel`'s scene lit by `lights` (its emitting
/// edges on): the scene relit, its mesh of `elements` made and lit from scratch, and
/// `(I − K) B = B₀` solved from `B = B₀` with `params` (by default to 1e-10) using `rows`, the
/// exact operator of the scene on that mesh (K does not depend on the lights). What a
/// relighter's move is checked against.
pub fn cold_solve(
    kernel: &Kernel,
    rows: &SparseOperator,
    elements: usize,
    lights: &[PointLight],
    params: &SolveParams,
    stop: &Stop,
) -> Result<ColdSolve, SolveError> {
    let relit = Kernel::new(kernel.scene().clone().with_lights(lights.to_vec())?);
    let mesh = Mesh::new(&relit, elements)?;
    let solution = solve_operator(rows, &mesh, params, stop)?;
    Ok(ColdSolve { mesh, solution })
}

/// A cold exact solve under one set of lights ([`cold_solve`]).
#[derive(Clone, Debug)]
pub struct ColdSolve {
    /// The mesh, lit by the lights (its [`Mesh::emission`] is their `B₀`).
    pub mesh: Mesh,
    /// The solve.
    pub solution: Solution,
}

impl ColdSolve {
    /// The errors of `b` (on the same elements) against this solve: of B, and of the part
    /// beyond the source, `B − B₀` (the indirect light: B minus the lights' direct light and
    /// the emission).
    #[must_use]
    pub fn errors(&self, b: &[f64]) -> SolveErrors {
        solve_errors(&self.mesh, b, &self.solution.radiosity)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::never;
    use flatland_geom::{DVec2, Edge, Scene};
    use flatland_testkit::assert_close;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    /// A generated plan with a lamp per room, its mesh, and a few positions of one lamp.
    fn plan() -> (Kernel, Mesh, Vec<Vec<PointLight>>) {
        let scene = flatland_geom::generate::floor_plan_lit(200, 5).unwrap();
        let lamps: Vec<PointLight> = scene.lights().to_vec();
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, 800).unwrap();
        let moves = lamps
            .iter()
            .map(|l| vec![PointLight::new(l.at, 8.0)])
            .chain([lamps.clone(), Vec::new()])
            .collect();
        (kernel, mesh, moves)
    }

    #[test]
    fn every_move_is_the_cold_exact_solve_and_its_parts_add_up() {
        let (kernel, mesh, moves) = plan();
        let params = RelightParams {
            tolerance: 1e-10,
            ..RelightParams::default()
        };
        let mut relighter = Relighter::new(&kernel, &mesh, params, &never).unwrap();
        assert!(relighter.memory_bytes() >= 2 * relighter.rows().memory_bytes());
        for lights in &moves {
            let cold = cold_solve(
                &kernel,
                relighter.rows(),
                mesh.len(),
                lights,
                &SolveParams::default(),
                &never,
            )
            .unwrap();
            let relit = relighter.relight(lights, &never).unwrap();
            // B₀ is the independently lit mesh's source; K B₀ the product by rows.
            let expected_source = cold.mesh.emission();
            for (a, b) in relit.source.iter().zip(&expected_source) {
                assert_close!(*a, *b, 1e-12);
            }
            let mut bounce = vec![0.0; mesh.len()];
            relighter_rows(&kernel, &mesh).apply(relit.source, &mut bounce);
            for (a, b) in relit.first_bounce.iter().zip(&bounce) {
                assert_close!(*a, *b, 1e-12);
            }
            let errors = cold.errors(relit.radiosity);
            assert!(errors.rel_l2_b < 1e-8, "{errors:?}");
            assert!(
                errors.rel_l2_reflected < 1e-8 || lights.is_empty(),
                "{errors:?}"
            );
            assert!(relit.cost.residual <= 1e-10, "{:?}", relit.cost);
        }
    }

    fn relighter_rows(kernel: &Kernel, mesh: &Mesh) -> SparseOperator {
        crate::sweep_operator(kernel, mesh, &never).unwrap()
    }

    #[test]
    fn the_warm_starts_agree_and_the_later_bounces_take_fewest_products() {
        let (kernel, mesh, moves) = plan();
        let mut products = Vec::new();
        let mut answers: Vec<Vec<Vec<f64>>> = Vec::new();
        for warm_start in [
            WarmStart::Cold,
            WarmStart::LastRadiosity,
            WarmStart::LaterBounces,
        ] {
            let params = RelightParams {
                warm_start,
                ..RelightParams::default()
            };
            let mut relighter = Relighter::new(&kernel, &mesh, params, &never).unwrap();
            let mut total = 0;
            let mut bs = Vec::new();
            for lights in &moves[..moves.len() - 2] {
                let relit = relighter.relight(lights, &never).unwrap();
                total += relit.cost.products;
                bs.push(relit.radiosity.to_vec());
            }
            products.push(total);
            answers.push(bs);
        }
        for (cold, warm) in answers[0].iter().zip(&answers[2]) {
            let errors = solve_errors(&mesh, warm, cold);
            assert!(errors.rel_l2_b < 1e-5, "{errors:?}");
        }
        assert!(
            products[2] < products[0],
            "products per warm start {products:?}"
        );
    }

    #[test]
    fn emitting_edges_stay_on_light_adds_linearly_and_bad_lights_are_refused_by_index() {
        // A closed unit square, ρ = 0.5, its floor emitting.
        let square = |floor: f64| {
            let mut edges = Edge::polygon(&flatland_testkit::rooms::unit_square(), 0.5);
            edges[0] = edges[0].with_emission(floor);
            Scene::new(edges).unwrap()
        };
        let kernel = Kernel::new(square(1.0));
        let mesh = Mesh::new(&kernel, 64).unwrap();
        let params = RelightParams {
            tolerance: 1e-10,
            ..RelightParams::default()
        };
        let mut relighter = Relighter::new(&kernel, &mesh, params, &never).unwrap();
        // No light: the floor's light alone, as the one-off solve gives it.
        let dark = relighter.relight(&[], &never).unwrap().radiosity.to_vec();
        let cold = crate::solve(&kernel, &mesh, &SolveParams::default(), &never).unwrap();
        assert!(solve_errors(&mesh, &dark, &cold.radiosity).rel_l2_b < 1e-9);
        // B(E + lamp) − B(E) is the lamp's B in the same room without emission.
        let lamp = [PointLight::new(v(0.3, 0.6), 2.0)];
        let both = relighter.relight(&lamp, &never).unwrap().radiosity.to_vec();
        let unlit = Kernel::new(square(0.0).with_lights(lamp.to_vec()).unwrap());
        let alone = crate::solve(
            &unlit,
            &Mesh::new(&unlit, 64).unwrap(),
            &SolveParams::default(),
            &never,
        )
        .unwrap();
        for i in 0..64 {
            assert_close!(both[i] - dark[i], alone.radiosity[i], 1e-8);
        }
        for (bad, says) in [
            (
                PointLight::new(v(0.0, 0.5), 1.0),
                "light 0: at (0, 0.5) lies on edge 3",
            ),
            (
                PointLight::new(v(0.5, 0.5), -1.0),
                "light 0: power must be finite",
            ),
        ] {
            let err = relighter.relight(&[bad], &never).unwrap_err().to_string();
            assert!(err.starts_with(says), "{err}");
        }
        let bad = RelightParams {
            tolerance: 0.0,
            ..RelightParams::default()
        };
        let err = Relighter::new(&kernel, &mesh, bad, &never)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("tolerance") && err.contains("(0, 0.1]"),
            "{err}"
        );
    }
}
