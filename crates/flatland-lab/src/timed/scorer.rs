//! What every row is scored against: a [`LitScene`] (the solve's mesh and the exact B on it
//! from an independent finer solve) and the ζ reference for the learned kernels.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use flatland_geom::Kernel;
use flatland_solve::{
    Errors, LitScene, Mesh, Reference, Representation, SolveErrors, SolveParams, Stop,
};

use crate::Defined;

/// The lit scene rows are solved on and scored against, and the ζ reference.
pub struct Scorer {
    lit: LitScene,
    /// `None` where no ζ is measured (the scaling runs: a ζ grid of a huge scene costs more
    /// than the methods it would judge).
    zeta: Option<Arc<Reference>>,
    defined: Defined,
}

impl Scorer {
    /// Solves `kernel` exactly on `reference_elements` (the independent reference) and
    /// evaluates it at the collocation points of a mesh of `elements`.
    pub fn new(
        kernel: &Arc<Kernel>,
        elements: usize,
        reference_elements: usize,
        zeta: Arc<Reference>,
        stop: &Stop,
    ) -> Result<Scorer> {
        let params = SolveParams::default();
        let lit = LitScene::scoring(
            Arc::clone(kernel),
            elements,
            reference_elements,
            &params,
            stop,
        )?;
        Ok(Scorer::with_zeta(lit, zeta))
    }

    /// Scores on `lit`, and the learned kernels' ζ on `zeta`.
    pub fn with_zeta(lit: LitScene, zeta: Arc<Reference>) -> Scorer {
        let defined = Defined::of(&zeta);
        Scorer {
            lit,
            zeta: Some(zeta),
            defined,
        }
    }

    /// Scores on `lit`'s mesh against its reference (what `flatland solve` measures against),
    /// with no ζ reference: rows have no ζ error, and the learners that need one (visibility,
    /// paper) fail with a note.
    pub fn of_lit(lit: LitScene) -> Scorer {
        Scorer {
            lit,
            zeta: None,
            defined: Defined {
                grid: false,
                heldout: false,
            },
        }
    }

    /// The lit scene rows are scored on.
    pub fn lit(&self) -> &LitScene {
        &self.lit
    }

    /// The mesh every representation is solved on.
    pub fn mesh(&self) -> &Mesh {
        self.lit.mesh()
    }

    /// The exact B at the mesh's collocation points.
    pub fn exact(&self) -> &[f64] {
        self.lit.reference_on_mesh()
    }

    /// Elements of the independent reference solve.
    pub fn reference_elements(&self) -> usize {
        self.lit.reference().mesh().len()
    }

    /// The ζ reference learned kernels are measured on, if there is one.
    pub fn zeta(&self) -> Option<&Arc<Reference>> {
        self.zeta.as_ref()
    }

    /// Which ζ errors mean something.
    pub fn defined(&self) -> Defined {
        self.defined
    }

    /// The errors of `rep`'s ζ̃ against the ζ reference, where there is one and its held-out
    /// error is defined.
    pub fn zeta_errors(&self, rep: &dyn Representation) -> Option<Errors> {
        let zeta = self.zeta.as_ref().filter(|_| self.defined.heldout)?;
        Some(zeta.errors(rep))
    }

    /// `errors` (a learner's own measure against [`Scorer::zeta`]) where the held-out error is
    /// defined.
    pub fn defined_zeta(&self, errors: Errors) -> Option<Errors> {
        (self.zeta.is_some() && self.defined.heldout).then_some(errors)
    }

    /// The errors of B solved with `rep` on the mesh, and the seconds the solve took.
    pub fn solve(&self, rep: &dyn Representation, stop: &Stop) -> Result<(SolveErrors, f64)> {
        let started = Instant::now();
        let c = self.lit.score(rep, stop)?;
        Ok((c.errors, started.elapsed().as_secs_f64()))
    }

    /// The errors of `b`, an exact solve on `mesh`, read by its own final gather, against the
    /// reference as a function.
    pub fn gathered_errors_on(&self, mesh: &Mesh, b: &[f64], stop: &Stop) -> Result<SolveErrors> {
        Ok(self.lit.gathered_errors_on(mesh, b, stop)?)
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
