//! What every row is scored against: the solve's mesh, the exact B on it from an independent
//! finer solve, and the ζ reference for the learned kernels.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use flatland_geom::Kernel;
use flatland_solve::{
    Discretization, ExactReference, Mesh, Reference, Representation, SolveErrors, SolveParams,
    Stop, solve_against, solve_errors,
};

use crate::Defined;
use crate::bench::Solver;

/// The mesh rows are solved on and the references they are measured against.
pub struct Scorer {
    mesh: Mesh,
    exact: Vec<f64>,
    fine: ExactReference,
    /// `None` where no ζ is measured (the scaling runs: a ζ grid of a huge scene costs more
    /// than the methods it would judge).
    zeta: Option<Arc<Reference>>,
    defined: Defined,
}

impl Scorer {
    /// Solves `kernel` exactly on `reference_elements` (the independent reference) and
    /// evaluates it at the collocation points of a mesh of `elements`.
    pub fn new(
        kernel: &Kernel,
        elements: usize,
        reference_elements: usize,
        zeta: Arc<Reference>,
        stop: &Stop,
    ) -> Result<Scorer> {
        let mesh = Mesh::new(kernel, elements)?;
        let fine = ExactReference::new(kernel, reference_elements, &SolveParams::default(), stop)?;
        let exact = fine.radiosity_on(&mesh, stop)?;
        let defined = Defined::of(&zeta);
        Ok(Scorer {
            mesh,
            exact,
            fine,
            zeta: Some(zeta),
            defined,
        })
    }

    /// Scores on the chosen mesh of `found` against its solve on twice the elements (what
    /// `flatland solve` measures against), with no ζ reference: rows have no ζ error, and the
    /// learners that need one (first-shot, paper) fail with a note.
    pub fn of_discretization(found: Discretization) -> Scorer {
        Scorer {
            mesh: found.coarse.mesh().clone(),
            exact: found.finer_on_coarse,
            fine: found.finer,
            zeta: None,
            defined: Defined {
                grid: false,
                heldout: false,
            },
        }
    }

    /// The mesh every representation is solved on.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The exact B at the mesh's collocation points.
    pub fn exact(&self) -> &[f64] {
        &self.exact
    }

    /// Elements of the independent reference solve.
    pub fn reference_elements(&self) -> usize {
        self.fine.mesh().len()
    }

    /// The ζ reference learned kernels are measured on, if there is one.
    pub fn zeta(&self) -> Option<&Arc<Reference>> {
        self.zeta.as_ref()
    }

    /// Which ζ errors mean something.
    pub fn defined(&self) -> Defined {
        self.defined
    }

    /// The held-out relative L2 error of `rep`'s ζ̃, where it is defined.
    pub fn zeta_error(&self, rep: &dyn Representation) -> Option<f64> {
        let zeta = self.zeta.as_ref().filter(|_| self.defined.heldout)?;
        Some(zeta.errors(rep).heldout)
    }

    /// The errors of B solved with `rep` on the mesh, and the seconds the solve took.
    pub fn solve(&self, rep: &dyn Representation, stop: &Stop) -> Result<(SolveErrors, f64)> {
        let started = Instant::now();
        let c = solve_against(rep, &self.mesh, &self.exact, &SolveParams::default(), stop)?;
        Ok((c.errors, started.elapsed().as_secs_f64()))
    }

    /// The errors of `b`, a radiosity on `mesh` (any mesh of the scene), against the reference.
    pub fn errors_on(&self, mesh: &Mesh, b: &[f64], stop: &Stop) -> Result<SolveErrors> {
        if mesh.len() == self.mesh.len() {
            return Ok(solve_errors(mesh, b, &self.exact));
        }
        let exact = self.fine.radiosity_on(mesh, stop)?;
        Ok(solve_errors(mesh, b, &exact))
    }

    /// The solver the first-shot and paper rows of [`crate::bench`] score with.
    pub(crate) fn solver(&self) -> Solver {
        Solver::of(self.mesh.clone(), self.exact.clone())
    }
}

/// A small scene scored cheaply, for the tests of the timed bench.
#[cfg(test)]
pub(crate) fn tiny() -> (Arc<Kernel>, Scorer) {
    let scene = flatland_geom::bundled::scene("fig3").unwrap();
    let kernel = Arc::new(Kernel::new(scene));
    let zeta = Arc::new(Reference::new(&kernel, 32, 256, 3));
    let scorer = Scorer::new(&kernel, 64, 256, zeta, &flatland_solve::never).unwrap();
    (kernel, scorer)
}
