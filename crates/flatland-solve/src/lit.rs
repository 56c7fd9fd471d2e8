//! The lit scene: one type that owns a scene's mesh, its exact solve, the finer solve that
//! estimates that solve's error, and the reference every other solution is scored against —
//! each solved once and reused. `flatland solve`, the bench, the experiments and the viewer
//! all light a scene through it. By default the mesh is chosen for a tolerance on B as a
//! function ([`solve_to_tolerance`]): the exact solve answers B at any surface point by its
//! final gather, its estimate covers B between the collocation points, and the reference is
//! the finer solve of that estimate (or, for the bench, one four times finer still). Every
//! lighting is scored against the reference as a function ([`FunctionReference`], gathered
//! once): the exact solve by its gather, any other by the line through its midpoints.

use std::sync::Arc;

use flatland_geom::Kernel;

use crate::{
    Comparison, DEFAULT_ERROR_BOUND, ExactMethod, ExactReference, FinalGather, FunctionEstimate,
    FunctionReference, FunctionSolve, Mesh, RefinementRound, Representation, Solution, SolveError,
    SolveErrors, SolveParams, Stop, ToleranceParams, ToleranceSolve, solve, solve_to_tolerance,
};

/// How many elements the lit scene's mesh has.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Elements {
    /// A mesh refined where the error of B as a function is until its estimate is at most
    /// this ([`solve_to_tolerance`]; the default, at 1 %).
    ToTolerance(f64),
    /// Exactly this many, spread evenly, with the estimate of B as a function.
    Exactly(usize),
}

/// B as a function on the lit scene's mesh: the final gather of its exact solve, and the
/// rounds that chose the mesh.
#[derive(Clone, Debug)]
pub struct LitFunction {
    /// The final gather of solutions on the mesh.
    pub gather: FinalGather,
    /// The exact solve's mean of B over each element (its function integrated).
    pub element_means: Vec<f64>,
    /// The rounds of refinement (one for a mesh of a given count).
    pub rounds: Vec<RefinementRound>,
}

/// What solutions are scored against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReferenceMesh {
    /// The solve on twice the elements the estimate is made from (no solve more).
    Finer,
    /// An exact solve on this many elements (the finer one when it is that count).
    Elements(usize),
    /// An exact solve on four times the chosen elements, at least 2048
    /// ([`ExactReference::default_elements_for`]): what the bench scores against.
    FourTimes,
}

/// Settings of a lit scene, checked by [`LitParams::check`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LitParams {
    /// The mesh's element count.
    pub elements: Elements,
    /// The reference.
    pub reference: ReferenceMesh,
    /// Every exact solve's settings.
    pub solve: SolveParams,
}

impl Default for LitParams {
    /// What `flatland solve` does by default: a mesh for a 1 % error of `B − E` as a
    /// function, scored against the finer solve of its estimate.
    fn default() -> Self {
        LitParams {
            elements: Elements::ToTolerance(DEFAULT_ERROR_BOUND),
            reference: ReferenceMesh::Finer,
            solve: SolveParams::default(),
        }
    }
}

impl LitParams {
    /// Checks the settings against `kernel`'s scene before any solve: an error bound in
    /// (0, 1), element counts a mesh and the scene's exact operator can have.
    pub fn check(&self, kernel: &Kernel) -> Result<(), SolveError> {
        self.solve.validate()?;
        match self.elements {
            Elements::ToTolerance(bound) if !(bound > 0.0 && bound < 1.0) => {
                return Err(SolveError::InvalidParameter {
                    name: "error bound",
                    value: bound.to_string(),
                    valid: "in (0, 1)",
                });
            }
            Elements::ToTolerance(_) => {}
            Elements::Exactly(n) => check_elements(kernel, n)?,
        }
        if let ReferenceMesh::Elements(n) = self.reference {
            check_elements(kernel, n)?;
        }
        Ok(())
    }
}

/// Refuses an element count no mesh, or no exact operator of this scene, can have.
pub fn check_elements(kernel: &Kernel, elements: usize) -> Result<(), SolveError> {
    ExactMethod::of(kernel).check(elements)?;
    Mesh::new(kernel, elements).map(|_| ())
}

/// A scene lit exactly on a mesh, and what every other lighting of it is scored against.
#[derive(Clone, Debug)]
pub struct LitScene {
    kernel: Arc<Kernel>,
    mesh: Mesh,
    /// The exact solve on `mesh` and its estimated error, when they were made
    /// ([`LitScene::new`]; [`LitScene::scoring`] makes neither).
    exact: Option<(ExactReference, FunctionEstimate)>,
    /// B as a function, when the exact solve was made.
    function: Option<LitFunction>,
    reference: ExactReference,
    /// The reference's B at `mesh`'s collocation points, the lights' direct light as each
    /// element's mean ([`ExactReference::collocated_on`]).
    reference_on_mesh: Vec<f64>,
    /// The reference as a function at the scoring points of `mesh`: what every lighting is
    /// scored against.
    scoring: FunctionReference,
    /// The exact solve on `mesh` read by its final gather and scored, when both were made.
    exact_errors: Option<SolveErrors>,
    solved: Vec<usize>,
}

impl LitScene {
    /// Lights `kernel`'s scene exactly as `params` say: the mesh, its exact solve, the finer
    /// solve that estimates its error, and the reference (that finer solve, or one more solve
    /// when another count is asked). Each mesh is solved once.
    pub fn new(
        kernel: Arc<Kernel>,
        params: &LitParams,
        stop: &Stop,
    ) -> Result<LitScene, SolveError> {
        params.check(&kernel)?;
        match params.elements {
            Elements::ToTolerance(tolerance) => {
                let asked = ToleranceParams {
                    tolerance,
                    ..ToleranceParams::default()
                };
                let done = solve_to_tolerance(&kernel, &asked, &params.solve, stop)?;
                LitScene::of_function(kernel, params, done, stop)
            }
            Elements::Exactly(n) => {
                let started = std::time::Instant::now();
                let mesh = Mesh::new(&kernel, n)?;
                let solve = FunctionSolve::new(&kernel, mesh, &params.solve, stop)?;
                let rounds = vec![RefinementRound {
                    elements: n,
                    estimate: solve.estimate.estimate,
                    seconds: started.elapsed().as_secs_f64(),
                }];
                LitScene::of_function(kernel, params, ToleranceSolve { solve, rounds }, stop)
            }
        }
    }

    /// The lit scene of a function solve: its mesh, solve, estimate and gather; the reference
    /// its finer solve, or the one `params` ask for.
    fn of_function(
        kernel: Arc<Kernel>,
        params: &LitParams,
        done: ToleranceSolve,
        stop: &Stop,
    ) -> Result<LitScene, SolveError> {
        let ToleranceSolve { solve, rounds } = done;
        let element_means = solve.element_means();
        let FunctionSolve {
            coarse,
            finer,
            gather,
            estimate,
            ..
        } = solve;
        let mesh = coarse.mesh().clone();
        let mut solved: Vec<usize> = rounds
            .iter()
            .flat_map(|r| [r.elements, 3 * r.elements])
            .collect();
        let reference = match params.reference {
            ReferenceMesh::Finer => finer,
            ReferenceMesh::Elements(n) if n == mesh.len() => coarse.clone(),
            ReferenceMesh::Elements(n) if n == finer.mesh().len() => finer,
            ReferenceMesh::Elements(n) => {
                solved.push(n);
                ExactReference::new(&kernel, n, &params.solve, stop)?
            }
            ReferenceMesh::FourTimes => {
                // The function solve's own mesh, every element cut in four.
                let fine = mesh.split(&kernel, &vec![4; mesh.len()])?;
                solved.push(fine.len());
                ExactReference::on_mesh(&kernel, fine, &params.solve, stop)?
            }
        };
        let reference_on_mesh = reference.collocated_on(&mesh, stop)?;
        let scoring = FunctionReference::new(&reference, &mesh, stop)?;
        let exact_errors =
            Some(scoring.gathered_errors(&gather, &coarse.solution().radiosity, stop)?);
        Ok(LitScene {
            kernel,
            mesh,
            scoring,
            exact_errors,
            exact: Some((coarse, estimate)),
            function: Some(LitFunction {
                gather,
                element_means,
                rounds,
            }),
            reference,
            reference_on_mesh,
            solved,
        })
    }

    /// A mesh of `elements` to score other lightings on, against an exact solve on
    /// `reference_elements` — no exact solve on the mesh itself, no estimate.
    pub fn scoring(
        kernel: Arc<Kernel>,
        elements: usize,
        reference_elements: usize,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<LitScene, SolveError> {
        params.validate()?;
        check_elements(&kernel, reference_elements)?;
        let mesh = Mesh::new(&kernel, elements)?;
        let reference = ExactReference::new(&kernel, reference_elements, params, stop)?;
        let reference_on_mesh = reference.collocated_on(&mesh, stop)?;
        let scoring = FunctionReference::new(&reference, &mesh, stop)?;
        Ok(LitScene {
            kernel,
            mesh,
            scoring,
            exact_errors: None,
            exact: None,
            function: None,
            reference,
            reference_on_mesh,
            solved: vec![reference_elements],
        })
    }

    /// The kernel of the scene lit.
    #[must_use]
    pub fn kernel(&self) -> &Arc<Kernel> {
        &self.kernel
    }

    /// The mesh every lighting is solved on.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The exact solve on the mesh, when it was made.
    #[must_use]
    pub fn exact(&self) -> Option<&ExactReference> {
        self.exact.as_ref().map(|(e, _)| e)
    }

    /// The exact solve's estimated error of B − E as a function, when it was made.
    #[must_use]
    pub fn estimate(&self) -> Option<&FunctionEstimate> {
        self.exact.as_ref().map(|(_, e)| e)
    }

    /// B as a function on the mesh (the exact solve's final gather), when the exact solve was
    /// made.
    #[must_use]
    pub fn function(&self) -> Option<&LitFunction> {
        self.function.as_ref()
    }

    /// The exact solve scores are measured against.
    #[must_use]
    pub fn reference(&self) -> &ExactReference {
        &self.reference
    }

    /// The reference's B at the mesh's collocation points (for colour scales and curves; scores
    /// are measured as functions, [`LitScene::function_reference`]).
    #[must_use]
    pub fn reference_on_mesh(&self) -> &[f64] {
        &self.reference_on_mesh
    }

    /// The element count of every exact solve this lit scene made, in order: no count twice.
    #[must_use]
    pub fn solved(&self) -> &[usize] {
        &self.solved
    }

    /// The reference as a function at the mesh's scoring points, what every score is
    /// measured against.
    #[must_use]
    pub fn function_reference(&self) -> &FunctionReference {
        &self.scoring
    }

    /// Solves the scene with `rep` on the mesh and scores the solution as a function against
    /// the reference ([`LitScene::scored`]).
    pub fn score(&self, rep: &dyn Representation, stop: &Stop) -> Result<Comparison, SolveError> {
        let solution = solve(rep, &self.mesh, &SolveParams::default(), stop)?;
        Ok(self.scored(solution))
    }

    /// The exact solve on the mesh scored against the reference as a function, read by its
    /// own final gather (what `flatland solve` measures), without solving again.
    #[must_use]
    pub fn exact_scored(&self) -> Option<Comparison> {
        let solution = self.exact()?.solution().clone();
        let errors = self.exact_errors?;
        Some(Comparison { solution, errors })
    }

    /// `solution`, a radiosity on the mesh, scored against the reference as a function:
    /// read as the line through its midpoints, with the lights' direct light at each point
    /// ([`FunctionReference::read`]), at the scoring points.
    #[must_use]
    pub fn scored(&self, solution: Solution) -> Comparison {
        let errors = self.scoring.errors(&solution.radiosity);
        Comparison { solution, errors }
    }

    /// The errors of `b`, a radiosity on `mesh` (any mesh of the scene), against the
    /// reference as a function: on the lit scene's own mesh at its scoring points, on
    /// another at that mesh's (one view of the reference per point, made for this call).
    pub fn errors_on(
        &self,
        mesh: &Mesh,
        b: &[f64],
        stop: &Stop,
    ) -> Result<SolveErrors, SolveError> {
        if self.is_own(mesh) {
            return Ok(self.scoring.errors(b));
        }
        Ok(FunctionReference::new(&self.reference, mesh, stop)?.errors(b))
    }

    /// The errors of `b`, an exact solve on `mesh` (any mesh of the scene), read by its own
    /// final gather, against the reference as a function: how an exact solve on another
    /// mesh is scored like the lit scene's own.
    pub fn gathered_errors_on(
        &self,
        mesh: &Mesh,
        b: &[f64],
        stop: &Stop,
    ) -> Result<SolveErrors, SolveError> {
        let gather = FinalGather::new(&self.kernel, mesh)?;
        let scoring = if self.is_own(mesh) {
            std::borrow::Cow::Borrowed(&self.scoring)
        } else {
            std::borrow::Cow::Owned(FunctionReference::new(&self.reference, mesh, stop)?)
        };
        scoring.gathered_errors(&gather, b, stop)
    }

    /// Whether `mesh` is the lit scene's own (the same scene and elements).
    fn is_own(&self, mesh: &Mesh) -> bool {
        mesh.fingerprint() == self.mesh.fingerprint() && mesh.elements() == self.mesh.elements()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::never;
    use crate::test_support::{bundled, floor_plan};

    #[test]
    fn each_mesh_is_solved_once_and_the_exact_solve_is_reused() {
        for (scene, params) in [
            (bundled("fig3"), LitParams::default()),
            (
                floor_plan(300),
                LitParams {
                    elements: Elements::Exactly(600),
                    ..LitParams::default()
                },
            ),
            (
                bundled("maze"),
                LitParams {
                    elements: Elements::Exactly(256),
                    reference: ReferenceMesh::Elements(1024),
                    ..LitParams::default()
                },
            ),
        ] {
            let kernel = Arc::new(Kernel::new(scene));
            let lit = LitScene::new(kernel, &params, &never).unwrap();
            let mut counts = lit.solved().to_vec();
            counts.sort_unstable();
            counts.dedup();
            assert_eq!(counts.len(), lit.solved().len(), "{:?}", lit.solved());
            let n = lit.mesh().len();
            assert!(lit.solved().contains(&n) && lit.solved().contains(&(3 * n)));
            assert_eq!(lit.estimate().unwrap().elements, n);
            let function = lit.function().unwrap();
            assert_eq!(function.element_means.len(), n);
            assert_eq!(function.rounds.last().unwrap().elements, n);
            // The exact lighting is the solve already made, scored as a re-solve would be.
            let reused = lit.exact_scored().unwrap();
            let again = lit.score(lit.kernel().as_ref(), &never).unwrap();
            // (one operator from the Gauss pass of the sweep, the other assembled alone: the
            // same entries up to rounding, as the sweep's tests show)
            for (a, b) in reused
                .solution
                .radiosity
                .iter()
                .zip(&again.solution.radiosity)
            {
                assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-12), "{a} vs {b}");
            }
            // Scored as a function: the exact solve by its gather, as a re-solve read by a
            // gather of its own would be; read as a line through its midpoints (what a
            // representation without a gather is read as), it is worse.
            let gathered = lit
                .gathered_errors_on(lit.mesh(), &again.solution.radiosity, &never)
                .unwrap();
            let (a, b) = (reused.errors.rel_l2_reflected, gathered.rel_l2_reflected);
            assert!((a - b).abs() <= 1e-6 * b.max(1e-12), "{a} vs {b}");
            assert!(
                again.errors.rel_l2_reflected > a,
                "{again:?} against {reused:?}"
            );
        }
    }

    #[test]
    fn a_reference_of_another_count_is_one_solve_more() {
        let kernel = Arc::new(Kernel::new(bundled("maze")));
        let params = LitParams {
            elements: Elements::Exactly(256),
            reference: ReferenceMesh::Elements(1024),
            ..LitParams::default()
        };
        let lit = LitScene::new(kernel, &params, &never).unwrap();
        assert_eq!(lit.solved(), [256, 768, 1024]);
        assert_eq!(lit.reference().mesh().len(), 1024);
        let finer = LitParams {
            reference: ReferenceMesh::Finer,
            ..params
        };
        let lit = LitScene::new(Arc::clone(lit.kernel()), &finer, &never).unwrap();
        assert_eq!(lit.solved(), [256, 768]);
        assert_eq!(lit.reference().mesh().len(), 768);
        // The bench's reference: the function solve's own mesh cut in four.
        let four = LitParams {
            reference: ReferenceMesh::FourTimes,
            ..params
        };
        let lit = LitScene::new(Arc::clone(lit.kernel()), &four, &never).unwrap();
        assert_eq!(lit.solved(), [256, 768, 1024]);
        let fine = lit.reference().mesh();
        assert_eq!(fine.elements()[4 * 7].s[0], lit.mesh().elements()[7].s[0]);
    }

    #[test]
    fn bad_counts_are_refused_before_any_solve() {
        let kernel = Arc::new(Kernel::new(bundled("fig3")));
        for params in [
            LitParams {
                elements: Elements::ToTolerance(0.0),
                ..LitParams::default()
            },
            LitParams {
                elements: Elements::Exactly(1),
                ..LitParams::default()
            },
            LitParams {
                reference: ReferenceMesh::Elements(1),
                ..LitParams::default()
            },
        ] {
            let err = LitScene::new(Arc::clone(&kernel), &params, &never).unwrap_err();
            assert!(matches!(err, SolveError::InvalidParameter { .. }), "{err}");
        }
    }
}
