//! How every lighting of a scene is scored: as a function along the surfaces, not at its
//! collocation points. The reference's final gather is taken once at
//! [`SCORE_POINTS_PER_ELEMENT`] points inside every element of the mesh solutions live on
//! ([`FunctionReference`]); a solution is read there by its own function where it has one (the
//! exact solve's gather) and otherwise as the line through its element midpoints, with the
//! point lights' direct light taken at each point: that light is exact and no kernel's work,
//! so only what the representation decides, the reflected light, is read from its values.
//! At the midpoints alone a solve looks right however B runs between them.

use crate::field::midpoint_line;
use crate::{ExactReference, FinalGather, Mesh, SamplePoints, SolveError, SolveErrors, Stop};

/// Points per element where solutions are scored (as in every figure of
/// docs/FUNCTION-ERROR.md).
pub const SCORE_POINTS_PER_ELEMENT: usize = 8;

/// A reference as a function at the scoring points of one mesh: what every solution on that
/// mesh is scored against, gathered once and reused.
#[derive(Clone, Debug)]
pub struct FunctionReference {
    mesh: Mesh,
    points: SamplePoints,
    /// The reference's B at each point (its final gather).
    exact: Vec<f64>,
    /// The lights' reflected direct light `ρ H` at each point.
    direct: Vec<f64>,
    /// `ρ H̄` per element of the mesh, what a solution's value holds of the direct light.
    direct_means: Vec<f64>,
}

impl FunctionReference {
    /// `reference`'s B at [`SCORE_POINTS_PER_ELEMENT`] points inside every element of `mesh`
    /// (a mesh of the same scene, lit by the same lights): one view of the reference per
    /// point, in parallel.
    pub fn new(
        reference: &ExactReference,
        mesh: &Mesh,
        stop: &Stop,
    ) -> Result<FunctionReference, SolveError> {
        let points = SamplePoints::evenly(mesh, SCORE_POINTS_PER_ELEMENT);
        let exact = reference.radiosity_at(&points.s, stop)?;
        let direct = reference.direct_at(&points.s);
        let direct_means = if mesh.direct_irradiance().is_empty() {
            vec![0.0; mesh.len()]
        } else {
            (0..mesh.len())
                .map(|i| mesh.edge_of(i).reflectance * mesh.direct_irradiance()[i])
                .collect()
        };
        Ok(FunctionReference {
            mesh: mesh.clone(),
            points,
            exact,
            direct,
            direct_means,
        })
    }

    /// The mesh whose solutions it scores.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Where it scores.
    #[must_use]
    pub fn points(&self) -> &SamplePoints {
        &self.points
    }

    /// The reference's B at [`FunctionReference::points`].
    #[must_use]
    pub fn exact(&self) -> &[f64] {
        &self.exact
    }

    /// `b`, one value per element of the mesh, read as a function at the points: the line
    /// through its midpoints of what it holds beyond the direct light (`b − ρ H̄`, at least
    /// the edge's emission), plus the direct light `ρ H` at the point.
    #[must_use]
    pub fn read(&self, b: &[f64]) -> Vec<f64> {
        let beyond: Vec<f64> = b
            .iter()
            .zip(&self.direct_means)
            .map(|(b, d)| b - d)
            .collect();
        self.points
            .s
            .iter()
            .zip(&self.points.emission)
            .zip(&self.direct)
            .map(|((&s, &e), d)| midpoint_line(&self.mesh, &beyond, s).max(e) + d)
            .collect()
    }

    /// The errors of `b` (one value per element of the mesh) read as a function
    /// ([`FunctionReference::read`]).
    #[must_use]
    pub fn errors(&self, b: &[f64]) -> SolveErrors {
        self.errors_of(&self.read(b))
    }

    /// The errors of `b` read by its own final gather (`gather` a gather of this mesh):
    /// what the exact solve, which has one, is scored by.
    pub fn gathered_errors(
        &self,
        gather: &FinalGather,
        b: &[f64],
        stop: &Stop,
    ) -> Result<SolveErrors, SolveError> {
        let values = gather.at(b, &self.points.s, stop)?;
        Ok(self.errors_of(&values))
    }

    /// The relative L2 errors of B and of `B − E` of `values` (one per point) against the
    /// reference.
    #[must_use]
    pub fn errors_of(&self, values: &[f64]) -> SolveErrors {
        SolveErrors {
            rel_l2_b: self.points.relative_l2(values, &self.exact, false),
            rel_l2_reflected: self.points.relative_l2(values, &self.exact, true),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{bundled, floor_plan};
    use crate::{FunctionSolve, SolveParams, never, solve};
    use flatland_geom::{Kernel, generate};

    /// The exact solve read by its gather scores what its estimate says; read as a line
    /// through its midpoints, several times worse; its own reference scores it zero.
    #[test]
    fn the_exact_solve_is_scored_as_a_function() {
        for scene in [bundled("floorplan"), floor_plan(300)] {
            let kernel = Kernel::new(scene);
            let mesh = Mesh::new(&kernel, 600).unwrap();
            let function =
                FunctionSolve::new(&kernel, mesh.clone(), &SolveParams::default(), &never).unwrap();
            let reference = ExactReference::on_mesh(
                &kernel,
                mesh.split(&kernel, &vec![8; mesh.len()]).unwrap(),
                &SolveParams::default(),
                &never,
            )
            .unwrap();
            let scoring = FunctionReference::new(&reference, &mesh, &never).unwrap();
            let b = &function.coarse.solution().radiosity;
            let gathered = scoring
                .gathered_errors(&function.gather, b, &never)
                .unwrap();
            let line = scoring.errors(b);
            let estimate = function.estimate.estimate;
            assert!(
                gathered.rel_l2_reflected < estimate && gathered.rel_l2_reflected > estimate / 4.0,
                "gathered {gathered:?} against estimate {estimate}"
            );
            assert!(
                line.rel_l2_reflected > 2.0 * gathered.rel_l2_reflected,
                "{line:?}"
            );
            assert!(line.rel_l2_b <= line.rel_l2_reflected, "{line:?}");
            let itself = FunctionReference::new(&function.coarse, &mesh, &never).unwrap();
            let zero = itself.gathered_errors(&function.gather, b, &never).unwrap();
            assert!(zero.rel_l2_reflected < 1e-9, "{zero:?}");
        }
    }

    /// With point lights a solution's values hold each element's mean direct light; read as a
    /// function it carries the direct light at each point, so a solve on the reference's own
    /// mesh, read on that mesh, misses only what the line cannot follow of the reflected light.
    #[test]
    fn the_direct_light_is_read_at_the_point() {
        let scene = generate::floor_plan_lit(120, 5).unwrap();
        let kernel = Kernel::new(scene);
        let mesh = Mesh::new(&kernel, 512).unwrap();
        let fine = mesh.split(&kernel, &vec![8; mesh.len()]).unwrap();
        let reference =
            ExactReference::on_mesh(&kernel, fine, &SolveParams::default(), &never).unwrap();
        let scoring = FunctionReference::new(&reference, &mesh, &never).unwrap();
        let b = solve(&kernel, &mesh, &SolveParams::default(), &never)
            .unwrap()
            .radiosity;
        let read = scoring.errors(&b).rel_l2_reflected;
        // The same values read as steps, with the direct light as each element's mean.
        let steps = scoring
            .errors_of(&scoring.points().steps(&mesh, &b))
            .rel_l2_reflected;
        assert!(read < steps / 2.0, "read {read} against steps {steps}");
    }
}
