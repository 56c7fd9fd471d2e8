//! [`LightFit`]: the light-driven learner as a user runs it — rounds on one mesh until the lit
//! scene meets its tolerance, and the result as a kernel representation.

use std::sync::Arc;

use super::cells::{FaceCell, FaceCells};
use super::{Blocks, Faces, LightLoop, LightParams, LightStop, Round};
use crate::FitError;
use crate::visibility::FaceKey;
use flatland_geom::{Kernel, PairClass};
use flatland_solve::{
    Mesh, Representation, SolveError, SolveParams, Stop, TransferOperator, check_fingerprint,
};

/// A light-driven fit of one scene on one mesh (see the module docs of `light` and
/// docs/ALGORITHM.md §4a): [`LightFit::round`] or [`LightFit::run`], then read the solved
/// radiosity, the estimated error and the cells, or solve with it as a [`Representation`].
///
/// ```
/// use std::sync::Arc;
/// use flatland_geom::{Kernel, generate};
/// use flatland_solve::{Mesh, never};
/// use kernel_fit::{LightFit, LightParams};
///
/// let kernel = Arc::new(Kernel::new(generate::floor_plan(80, 1).unwrap()));
/// let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).unwrap();
/// let mut fit = LightFit::new(kernel, mesh, LightParams::default(), &never).unwrap();
/// let stopped = fit.run(&never, |_| {}).unwrap();
/// let last = fit.history().last().unwrap();
/// assert!(last.estimated_error <= 0.01 || stopped != kernel_fit::LightStop::Tolerance);
/// assert!(fit.radiosity().iter().all(|&b| b >= 0.0));
/// ```
#[derive(Clone)]
pub struct LightFit {
    kernel: Arc<Kernel>,
    mesh: Mesh,
    params: LightParams,
    solve: SolveParams,
    inner: LightLoop<FaceCells>,
    stopped: Option<LightStop>,
}

impl LightFit {
    /// The fit of `kernel` on `mesh` (a mesh of the same scene): every block unresolved, no
    /// ray cast. Builds the closed-form unoccluded transfers of every pair of elements that
    /// face each other (no visibility yet).
    pub fn new(
        kernel: Arc<Kernel>,
        mesh: Mesh,
        params: LightParams,
        stop: &Stop,
    ) -> Result<LightFit, FitError> {
        let faces = FaceCells::new(kernel.clone());
        let inner = LightLoop::new(&kernel, &mesh, faces, &params, stop)?;
        Ok(LightFit {
            kernel,
            mesh,
            params,
            solve: SolveParams::default(),
            inner,
            stopped: None,
        })
    }

    /// One round: solve, estimate, and (unless the estimate meets the tolerance or a budget
    /// ran out) resolve the blocks the most light flows through. `Some` once it has stopped;
    /// later calls return the same reason and do nothing.
    pub fn round(&mut self, stop: &Stop) -> Result<Option<LightStop>, FitError> {
        if self.stopped.is_some() {
            return Ok(self.stopped);
        }
        let (kernel, mesh) = (&self.kernel, &self.mesh);
        self.stopped = self
            .inner
            .round(kernel, mesh, &self.params, &self.solve, stop)?;
        Ok(self.stopped)
    }

    /// Rounds until it stops; `on_round` sees the fit after each (the viewer's snapshots).
    pub fn run(
        &mut self,
        stop: &Stop,
        mut on_round: impl FnMut(&LightFit),
    ) -> Result<LightStop, FitError> {
        loop {
            let stopped = self.round(stop)?;
            on_round(self);
            if let Some(reason) = stopped {
                return Ok(reason);
            }
        }
    }

    /// The settings it runs with.
    pub fn params(&self) -> &LightParams {
        &self.params
    }

    /// Changes the stop rules (tolerance, budgets) of a fit that may be running; a fit that
    /// had stopped goes on if the new ones ask for more.
    pub fn set_params(&mut self, params: LightParams) -> Result<(), FitError> {
        params.check()?;
        self.params = params;
        if self.stopped != Some(LightStop::Exact) {
            self.stopped = None;
        }
        Ok(())
    }

    /// The mesh it learns on.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The kernel it learns.
    pub fn kernel(&self) -> &Arc<Kernel> {
        &self.kernel
    }

    /// B per element from the last round's solve (the emission before the first round).
    pub fn radiosity(&self) -> &[f64] {
        self.inner.radiosity()
    }

    /// Every round so far, as it ended.
    pub fn history(&self) -> &[Round] {
        self.inner.history()
    }

    /// The estimated relative L2 error of the solved `B − E`, after the last round.
    pub fn estimated_error(&self) -> Option<f64> {
        self.history().last().map(|r| r.estimated_error)
    }

    /// Why it stopped, once it has.
    pub fn stopped(&self) -> Option<LightStop> {
        self.stopped
    }

    /// Rays cast so far (one per face learned).
    pub fn rays(&self) -> u64 {
        self.inner.rays()
    }

    /// The cells so far, one per face learned, in the order learned.
    pub fn cells(&self) -> &[FaceCell] {
        self.inner.faces().cells()
    }

    /// Blocks `(receiver element, sending edge)` of the mesh, and how many are resolved.
    pub fn blocks(&self) -> (usize, usize) {
        let blocks: &Blocks = self.inner.blocks();
        (blocks.len(), blocks.len() - blocks.unresolved())
    }

    /// The learned operator on its own mesh: resolved blocks exact for the learned faces,
    /// the others the row's prior times their unoccluded transfer.
    fn learned_operator(&self) -> LearnedOperator {
        LearnedOperator {
            blocks: self.inner.blocks().clone(),
            mesh: self.mesh.clone(),
            priors: self.inner.priors().to_vec(),
        }
    }
}

/// The learned operator, owned (a solve may outlive the borrow of a running fit).
struct LearnedOperator {
    blocks: Blocks,
    mesh: Mesh,
    priors: Vec<f64>,
}

impl TransferOperator for LearnedOperator {
    fn len(&self) -> usize {
        self.mesh.len()
    }
    fn apply(&self, b: &[f64], out: &mut [f64]) {
        self.blocks.operator(&self.mesh, &self.priors).apply(b, out);
    }
}

/// As a kernel: the geometry where it decides a pair, the learned face where a cell lies in
/// it, and the receiver's prior times the unoccluded kernel where the model knows nothing —
/// never a guess that could pass or block light outright.
impl Representation for LightFit {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        let kernel = &self.kernel;
        let u = kernel.unoccluded(s, t);
        if u.zeta == 0.0 {
            return 0.0;
        }
        match kernel.pair_class(u.sender, u.receiver) {
            PairClass::Zero | PairClass::Hidden => 0.0,
            PairClass::Visible => u.zeta,
            PairClass::Varies => {
                let known = FaceKey::at(kernel, &u).and_then(|key| self.inner.faces().known(&key));
                let v = known.unwrap_or_else(|| self.inner.priors()[self.mesh.element_at(t)]);
                v * u.zeta
            }
        }
    }

    fn basis_functions(&self) -> Option<usize> {
        Some(self.cells().len())
    }

    fn memory_bytes(&self) -> usize {
        self.inner.faces().memory_bytes() + self.inner.blocks().memory_bytes()
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        Some(self.kernel.scene().fingerprint())
    }

    /// Its own operator on the mesh it learned on; on any other mesh, the quadrature of its
    /// pointwise ζ̃.
    fn operator(
        &self,
        mesh: &Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        check_fingerprint(self.scene_fingerprint(), mesh)?;
        if mesh.elements() == self.mesh.elements() {
            return Ok(Box::new(self.learned_operator()));
        }
        Ok(Box::new(flatland_solve::quadrature_operator(
            self,
            mesh,
            params.quadrature_points,
            stop,
        )?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::generate;
    use flatland_solve::{ExactReference, never, solve, solve_errors};

    fn fit(edges: usize, seed: u64, params: LightParams) -> LightFit {
        let kernel = Arc::new(Kernel::new(generate::floor_plan(edges, seed).unwrap()));
        let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).unwrap();
        let mut fit = LightFit::new(kernel, mesh, params, &never).unwrap();
        fit.run(&never, |_| {}).unwrap();
        fit
    }

    /// A solve with the fit as a representation on its own mesh gives the B its last round
    /// solved, and meets the tolerance against the exact solve on that mesh.
    #[test]
    fn solving_with_the_fit_gives_its_own_radiosity_within_the_tolerance() {
        let fit = fit(120, 3, LightParams::default());
        let solved = solve(&fit, fit.mesh(), &SolveParams::default(), &never).unwrap();
        for (a, b) in solved.radiosity.iter().zip(fit.radiosity()) {
            assert!((a - b).abs() <= 1e-6 * (1.0 + b.abs()), "{a} vs {b}");
        }
        let exact = solve(
            fit.kernel().as_ref(),
            fit.mesh(),
            &SolveParams::default(),
            &never,
        )
        .unwrap()
        .radiosity;
        let measured = solve_errors(fit.mesh(), fit.radiosity(), &exact).rel_l2_reflected;
        let estimated = fit.estimated_error().unwrap();
        assert!(
            measured <= 3.0 * estimated.max(0.01),
            "{measured} vs {estimated}"
        );
        assert_eq!(fit.cells().len() as u64, fit.rays());
    }

    /// On another mesh it solves through its pointwise ζ̃, which on the learned mesh's blocks
    /// is the kernel's own where the model knows, so finer reference meshes agree with it.
    #[test]
    fn on_another_mesh_the_pointwise_kernel_lights_the_scene_alike() {
        let fit = fit(80, 5, LightParams::default());
        let other = Mesh::new(fit.kernel(), fit.mesh().len() * 2).unwrap();
        let solved = solve(&fit, &other, &SolveParams::default(), &never).unwrap();
        let params = SolveParams::default();
        let reference = ExactReference::new(fit.kernel(), other.len(), &params, &never).unwrap();
        let exact = reference.radiosity_on(&other, &never).unwrap();
        let error = solve_errors(&other, &solved.radiosity, &exact).rel_l2_reflected;
        assert!(error < 0.1, "{error}");
        assert!(solved.radiosity.iter().all(|&b| b >= 0.0));
    }

    /// Raising the tolerance's demand after a stop continues the fit; the same settings give
    /// the same fit (no randomness: the rays are the pieces' midpoints).
    #[test]
    fn a_stopped_fit_goes_on_when_asked_for_more_and_is_deterministic() {
        let loose = LightParams {
            tolerance: 0.2,
            ..LightParams::default()
        };
        let mut a = fit(100, 7, loose);
        let cells = a.cells().len();
        a.set_params(LightParams::default()).unwrap();
        a.run(&never, |_| {}).unwrap();
        assert!(
            a.cells().len() > cells,
            "{} cells after {cells}",
            a.cells().len()
        );
        let b = fit(100, 7, LightParams::default());
        assert_eq!(a.radiosity().len(), b.radiosity().len());
        assert!(a.estimated_error().unwrap() <= 0.01 || a.stopped() != Some(LightStop::Tolerance));
        let c = fit(100, 7, LightParams::default());
        assert_eq!(b.radiosity(), c.radiosity());
        assert_eq!(b.cells(), c.cells());
    }
}
