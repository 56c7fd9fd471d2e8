//! The lit scene: the radiosity `B` solved with the kernel as learned so far, beside the
//! exact `B`, made beside the learner (`worker`) and drawn by `views`.
//!
//! Per scene, once: a [`LitScene`] — a [`Mesh`] and an [`ExactReference`] (the exact kernel
//! solved on a mesh four times finer), whose `B` at the mesh's collocation points is what every
//! learned solve is measured against ([`LitSetup`]). While a network learns, the learned kernel
//! is solved on that mesh again at most every [`LIT_EVERY`], and for no more than
//! [`LIT_SHARE`] of the time (of its core) — or, when the learner spends its time waiting for
//! the pace of growth, for at most [`LIT_SHARE_IDLE`] of it ([`solve_interval`]); the
//! light-driven learner solves the mesh itself, once a round. How the learned operator is
//! integrated ([`Integration`]) sets the mesh: a visibility model integrates its own kernel
//! exactly in 5–40 ms at 512 elements on `fig3`, but in 0.3–1 s on a floor plan of 220 edges
//! with a few hundred cells; the paper's network needs quadrature of ζ̃ (two network
//! evaluations per element pair), so it is solved on [`NETWORK_ELEMENTS`] elements.

use std::time::Duration;

use flatland_geom::Kernel;
use std::sync::Arc;

use flatland_solve::{
    ExactReference, LitScene, MAX_ELEMENTS, Mesh, SolveError, SolveErrors, SolveParams, Stop,
};
use kernel_fit::{LearnedKernel, Target};

/// Shortest time between two solves while the network learns.
pub const LIT_EVERY: Duration = Duration::from_millis(500);
/// Largest share of the learner's time the solves may take: a solve that took `c` waits at
/// least `c / LIT_SHARE` for the next.
pub const LIT_SHARE: f64 = 0.1;
/// Largest share when the learner waits for the pace of growth: solves may take the time it
/// would spend waiting, up to this share (growth catches up after a solve).
pub const LIT_SHARE_IDLE: f64 = 0.5;
/// Elements for a network that learns ζ or k (the paper's), whose operator is quadrature:
/// measured at 400 cells ≈ 150 ms for 128 elements, ≈ 600 ms for 256.
pub const NETWORK_ELEMENTS: usize = 128;

/// How a learner's operator on the lit view's mesh is integrated, which sets how many elements
/// a solve can afford.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integration {
    /// Exactly, row by row: the light-driven learner's rows (exact views and blends of them),
    /// a network of V times the exact unoccluded kernel.
    Exact,
    /// By quadrature of ζ̃: a network of ζ or k (two network evaluations per element pair).
    Quadrature,
}

impl Integration {
    /// How a network learning `target` is integrated.
    #[must_use]
    pub fn of_target(target: Target) -> Integration {
        match target {
            Target::Visibility => Integration::Exact,
            Target::Zeta | Target::FactoredEmission => Integration::Quadrature,
        }
    }
}

/// Elements the lit view solves `kernel`'s scene on for a learner integrated as
/// `integration`: the solver's default when exact, [`NETWORK_ELEMENTS`] by quadrature; never
/// fewer than the scene's sections.
#[must_use]
pub fn lit_elements(kernel: &Kernel, integration: Integration) -> usize {
    let scene = kernel.scene();
    match integration {
        Integration::Exact => Mesh::default_elements(scene),
        Integration::Quadrature => NETWORK_ELEMENTS
            .max(Mesh::min_elements(scene))
            .min(MAX_ELEMENTS),
    }
}

/// How long to wait after a solve that took `cost` before the next one, when the learner spends
/// the share `idle` of its time waiting for the pace of growth (0 when it trains flat out).
#[must_use]
pub fn solve_interval(cost: Duration, idle: f64) -> Duration {
    let share = LIT_SHARE.max(idle.min(LIT_SHARE_IDLE));
    LIT_EVERY.max(cost.div_f64(share))
}

/// What the lit view needs of one scene, made once per scene (after a reset or an edit).
#[derive(Debug)]
pub struct LitSetup {
    /// The id of the reference (the worker's `World`) it belongs to.
    pub world: u64,
    /// The elements the learned kernel is solved on and the exact kernel solved on a finer
    /// mesh (its B at the mesh's collocation points is what every solve is scored against).
    pub lit: LitScene,
    /// The top of the colour scale: the brightest non-emitting element of the exact `B`
    /// (emitters are drawn above the scale).
    pub top: f64,
    /// Seconds it took to make.
    pub build_s: f64,
}

impl LitSetup {
    /// The mesh for a learner integrated as `integration` on `kernel`'s scene and the exact
    /// `B` on it. `stop` is polled in the long loops ([`SolveError::Interrupted`]).
    pub fn build(
        world: u64,
        kernel: Arc<Kernel>,
        integration: Integration,
        stop: &Stop,
    ) -> Result<LitSetup, SolveError> {
        let started = std::time::Instant::now();
        let elements = lit_elements(&kernel, integration);
        let fine = ExactReference::default_elements(elements);
        let params = SolveParams::default();
        let lit = LitScene::scoring(kernel, elements, fine, &params, stop)?;
        let top = colour_top(lit.mesh(), lit.reference_on_mesh());
        Ok(LitSetup {
            world,
            lit,
            top,
            build_s: started.elapsed().as_secs_f64(),
        })
    }

    /// The elements the learned kernel is solved on.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        self.lit.mesh()
    }

    /// The exact `B` at the mesh's collocation points.
    #[must_use]
    pub fn exact(&self) -> &[f64] {
        self.lit.reference_on_mesh()
    }

    /// The exact kernel solved on a finer mesh (for the `B(s)` curve).
    #[must_use]
    pub fn reference(&self) -> &ExactReference {
        self.lit.reference()
    }

    /// Solves `model` on the mesh and measures it against the exact `B`.
    pub fn solve(&self, model: &LearnedKernel, stop: &Stop) -> Result<LitSolve, SolveError> {
        let started = std::time::Instant::now();
        let c = self.lit.score(model, stop)?;
        Ok(LitSolve {
            b: c.solution.radiosity,
            errors: c.errors,
            solve_s: started.elapsed().as_secs_f64(),
        })
    }
}

/// One solve with the learned kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct LitSolve {
    /// `B` per element of [`LitSetup::mesh`].
    pub b: Vec<f64>,
    /// Its errors against [`LitSetup::exact`].
    pub errors: SolveErrors,
    /// Seconds the solve took (operator and linear solve).
    pub solve_s: f64,
}

/// A point of the lit error's curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LitPoint {
    /// Training steps of the model solved.
    pub steps: u64,
    /// Rays cast by then.
    pub rays: u64,
    /// Cells of the model solved.
    pub cells: usize,
    /// Relative L2 error of the reflected part `B − E`.
    pub rel_l2_reflected: f64,
    /// The light-driven learner's own estimate of that error (`None` for a network).
    pub estimated: Option<f64>,
}

/// The brightest element of `b` that does not emit (emitters are 10–100× brighter than what
/// they light and would leave the rest dark); the brightest of all when everything emits or
/// nothing is lit; never 0.
#[must_use]
pub fn colour_top(mesh: &Mesh, b: &[f64]) -> f64 {
    flatland_pictures::colormap::radiosity_top(mesh, b)
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use flatland_solve::{Reference, never};
    use kernel_fit::{Fit, FitParams, StopReason};

    use super::*;

    fn kernel(name: &str) -> Kernel {
        Kernel::new(flatland_geom::bundled::scene(name).unwrap())
    }

    #[test]
    fn solves_are_spaced_by_time_and_by_their_cost() {
        assert_eq!(solve_interval(Duration::ZERO, 0.0), LIT_EVERY);
        assert_eq!(solve_interval(Duration::from_millis(20), 0.0), LIT_EVERY);
        assert_eq!(
            solve_interval(Duration::from_millis(150), 0.0),
            Duration::from_millis(1500)
        );
        // A learner that waits for the pace lends its waiting time, up to half.
        assert_eq!(
            solve_interval(Duration::from_millis(400), 0.25),
            Duration::from_millis(1600)
        );
        assert_eq!(
            solve_interval(Duration::from_millis(400), 0.9),
            Duration::from_millis(800)
        );
    }

    #[test]
    fn the_paper_network_is_solved_on_fewer_elements() {
        let k = kernel("fig3");
        let exact = Integration::of_target(Target::Visibility);
        let quadrature = Integration::of_target(Target::Zeta);
        assert_eq!(exact, Integration::Exact);
        assert_eq!(
            Integration::of_target(Target::FactoredEmission),
            Integration::Quadrature
        );
        assert_eq!(lit_elements(&k, exact), Mesh::default_elements(k.scene()));
        assert_eq!(lit_elements(&k, quadrature), NETWORK_ELEMENTS);
        assert!(lit_elements(&k, quadrature) < lit_elements(&k, exact));
    }

    #[test]
    fn the_colour_scale_tops_at_the_brightest_lit_surface() {
        let k = kernel("fig3");
        let mesh = Mesh::new(&k, 64).unwrap();
        let emission = mesh.emission();
        assert!(emission.iter().any(|e| *e > 0.0));
        let b: Vec<f64> = (0..mesh.len())
            .map(|i| emission[i] * 100.0 + i as f64)
            .collect();
        let brightest_lit = (0..mesh.len())
            .filter(|&i| emission[i] == 0.0)
            .map(|i| i as f64)
            .fold(0.0, f64::max);
        assert_eq!(colour_top(&mesh, &b), brightest_lit);
        let dark = vec![0.0; mesh.len()];
        assert!(colour_top(&mesh, &dark) > 0.0);
        let mut nan = b.clone();
        nan[0] = f64::NAN;
        assert!(colour_top(&mesh, &nan).is_finite());
    }

    #[test]
    fn an_exact_default_model_solves_to_the_exact_b() {
        // The visibility network on fig3 converges to the exact kernel; its solve then matches the
        // exact B up to the mesh's discretisation (512 elements against 2048: ≈ 1e-4).
        let k = Arc::new(kernel("fig3"));
        let setup = LitSetup::build(1, Arc::clone(&k), Integration::Exact, &never).unwrap();
        assert_eq!(setup.mesh().len(), setup.exact().len());
        assert!(setup.top > 0.0 && setup.top.is_finite());
        let reference = Arc::new(Reference::new(&k, 32, 64, 1));
        let mut fit = Fit::new(Arc::clone(&k), reference, FitParams::default()).unwrap();
        let first = setup.solve(fit.model(), &never).unwrap();
        assert_eq!(first.b.len(), setup.mesh().len());
        assert!(first.errors.rel_l2_reflected > 0.05, "{:?}", first.errors);
        let stop = loop {
            if let Some(reason) = fit.step() {
                break reason;
            }
        };
        assert_eq!(stop, StopReason::Converged);
        let last = setup.solve(fit.model(), &never).unwrap();
        assert!(last.errors.rel_l2_reflected < 1e-3, "{:?}", last.errors);
        // Interrupted on request.
        let err = setup.solve(fit.model(), &|| true).unwrap_err();
        assert!(matches!(err, SolveError::Interrupted), "{err}");
    }
}
