//! What the learner's estimated error covers. Its own estimate is of its solve against the
//! exact kernel's solve *on the same elements*: the learned operator's error, not the mesh's.
//! Read as a function along the surfaces its B carries the mesh's error as well, so where the
//! mesh's own estimate is known (the exact solve's [`FunctionEstimate`], which `flatland
//! solve` makes before any learner runs) the two are added: the learner's element values read
//! by the exact final gather are then within their sum of the exact B as a function (the
//! triangle inequality, the gather of the learner's error no larger than that error, since
//! every reflectance is below 1).

use flatland_solve::FunctionEstimate;

/// The light-driven learner's estimated relative L2 error of `B − E`, and what it covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightEstimate {
    /// Its estimate against the exact solve on its own mesh: each row's doubt carried through
    /// the bounces ([`LightFit::estimated_error`](crate::LightFit::estimated_error)).
    pub learner: f64,
    /// Elements of its mesh.
    pub elements: usize,
    /// The exact solve's estimated error of `B − E` as a function on that mesh, when known.
    pub discretization: Option<FunctionEstimate>,
}

impl LightEstimate {
    /// The learner's own estimate on a mesh of `elements`, the mesh's error not included.
    #[must_use]
    pub fn on_mesh(learner: f64, elements: usize) -> LightEstimate {
        LightEstimate {
            learner,
            elements,
            discretization: None,
        }
    }

    /// With the mesh's error as a function added (`mesh` the exact solve's estimate on the
    /// same elements; another mesh's is not this one's and is refused with `None`).
    #[must_use]
    pub fn with_discretization(self, mesh: &FunctionEstimate) -> Option<LightEstimate> {
        (mesh.elements == self.elements).then_some(LightEstimate {
            discretization: Some(*mesh),
            ..self
        })
    }

    /// The estimate: the learner's, plus the mesh's as a function when it is known.
    #[must_use]
    pub fn estimate(&self) -> f64 {
        self.learner + self.discretization.map_or(0.0, |d| d.estimate)
    }

    /// What [`LightEstimate::estimate`] covers, in words (for a report or `--json`).
    #[must_use]
    pub fn covers(&self) -> String {
        let n = self.elements;
        match self.discretization {
            None => format!(
                "the relative L2 error of B − E of the learner's solve against the exact \
                 kernel's solve on the same {n} elements, at the elements only: not the \
                 mesh's own error, nor B between the collocation points"
            ),
            Some(d) => format!(
                "the relative L2 error of B − E as a function along the surfaces, the \
                 learner's values on {n} elements read by the exact final gather: its error \
                 against the exact solve on those elements ({:.1e}, the learner's estimate) \
                 plus that solve's error as a function ({:.1e}, from a solve on {} elements)",
                self.learner, d.estimate, d.finer_elements
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh_estimate(elements: usize) -> FunctionEstimate {
        FunctionEstimate {
            elements,
            finer_elements: 3 * elements,
            difference: 0.002,
            estimate: 0.0035,
        }
    }

    #[test]
    fn the_mesh_part_is_added_only_for_the_same_mesh_and_said() {
        let own = LightEstimate::on_mesh(0.004, 800);
        assert_eq!(own.estimate(), 0.004);
        assert!(
            own.covers().contains("same 800 elements"),
            "{}",
            own.covers()
        );
        assert!(own.with_discretization(&mesh_estimate(900)).is_none());
        let whole = own.with_discretization(&mesh_estimate(800)).unwrap();
        assert!((whole.estimate() - 0.0075).abs() < 1e-15, "{whole:?}");
        let covers = whole.covers();
        assert!(
            covers.contains("as a function") && covers.contains("2400"),
            "{covers}"
        );
    }
}
