//! The learned kernel ζ̃: a network and what turns `(s, t)` into its input (the input frame)
//! and its output into ζ̃ (the output scale and the learner's head), saved as the fields
//! model and checkpoint files have always held.

use std::sync::Arc;

use flatland_geom::{Kernel, KernelParams, Scene};
use serde::{Deserialize, Serialize};
use sgcs::Network;

use super::head::ModelHead;
use super::sample::{Sample, unit_scale};
use crate::visibility::{FaceGate, FaceId, FaceKey};
use flatland_solve::{
    InputFrame, Mesh, Representation, SolveError, SolveParams, Stop, TransferOperator,
    check_fingerprint, check_lights, quadrature_operator,
};

use crate::{Gating, Target};

/// Input dimension of the kernel's network: `γ(s, t) = (x₁, y₁, x₂, y₂)`.
pub const INPUT_DIM: usize = 4;

/// The learned ζ̃: a network plus what it needs to turn `(s, t)` into its input and its output
/// into ζ̃.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "LearnedKernelData", into = "LearnedKernelData")]
pub struct LearnedKernel {
    pub(crate) scene: Scene,
    pub(crate) frame: InputFrame,
    pub(crate) network: Network,
    /// The network learns target / `output_scale` (the RMS of S₀'s targets), so its weights
    /// and errors are O(1) whatever the emission or the units: ζ of 1e200 or 1e-200 neither
    /// overflows the network nor underflows its squared errors. 1 for the visibility learner.
    pub(crate) output_scale: f64,
    /// What turns the network's output into ζ̃.
    pub(crate) head: ModelHead,
}

/// The saved form of a [`LearnedKernel`]: everything but what the head derives from the scene.
#[derive(Serialize, Deserialize)]
struct LearnedKernelData {
    scene: Scene,
    frame: InputFrame,
    network: Network,
    /// E' per edge for a model of k, empty otherwise.
    #[serde(default)]
    emission_factor: Vec<f64>,
    #[serde(default = "unit_scale")]
    output_scale: f64,
    #[serde(default)]
    target: Target,
    /// A visibility model's gating, `off` otherwise.
    #[serde(default)]
    gating: Gating,
    /// The parameters of a visibility model's exact kernel.
    #[serde(default)]
    kernel_params: KernelParams,
}

impl From<LearnedKernel> for LearnedKernelData {
    fn from(m: LearnedKernel) -> Self {
        let kernel_params = m.head.kernel_params();
        let target = m.head.target();
        let (emission_factor, gating) = match m.head {
            ModelHead::Zeta => (Vec::new(), Gating::Off),
            ModelHead::FactoredEmission { emission } => (emission, Gating::Off),
            ModelHead::Visibility(v) => (Vec::new(), v.gating),
        };
        LearnedKernelData {
            scene: m.scene,
            frame: m.frame,
            network: m.network,
            emission_factor,
            output_scale: m.output_scale,
            target,
            gating,
            kernel_params,
        }
    }
}

/// Why saved fields do not make a model, naming the field and what would be valid.
#[derive(Debug)]
pub(crate) struct InvalidModel(String);

impl std::fmt::Display for InvalidModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl TryFrom<LearnedKernelData> for LearnedKernel {
    type Error = InvalidModel;
    fn try_from(d: LearnedKernelData) -> Result<Self, InvalidModel> {
        let bad = |field: &str, what: String| Err(InvalidModel(format!("`model.{field}` {what}")));
        if d.target != Target::Visibility && d.gating != Gating::Off {
            return bad(
                "gating",
                format!(
                    "is {}, but a model of ζ or k (target `zeta`, `factored_emission`) has no \
                     faces to gate by (valid: off)",
                    d.gating.name()
                ),
            );
        }
        let head = match d.target {
            Target::Zeta | Target::Visibility if !d.emission_factor.is_empty() => {
                return bad(
                    "emission_factor",
                    format!(
                        "has {} values, but a model of ζ or of V (target `zeta`, `visibility`) \
                         has none",
                        d.emission_factor.len()
                    ),
                );
            }
            Target::Zeta => ModelHead::Zeta,
            Target::FactoredEmission => {
                let edges = d.scene.edges().len();
                if d.emission_factor.len() != edges {
                    return bad(
                        "emission_factor",
                        format!(
                            "has {} values, but must have one per edge of the scene ({edges})",
                            d.emission_factor.len()
                        ),
                    );
                }
                if let Some(v) = d
                    .emission_factor
                    .iter()
                    .find(|v| !(v.is_finite() && **v >= 0.0))
                {
                    return bad(
                        "emission_factor",
                        format!("contains {v}, but every value must be finite and ≥ 0"),
                    );
                }
                ModelHead::FactoredEmission {
                    emission: d.emission_factor,
                }
            }
            Target::Visibility => {
                let kernel = Kernel::with_params(d.scene.clone(), d.kernel_params)
                    .map_err(|e| InvalidModel(e.to_string()))?;
                ModelHead::visibility(d.gating, &Arc::new(kernel), d.frame)
            }
        };
        Ok(LearnedKernel::new(
            d.scene,
            d.frame,
            d.network,
            d.output_scale,
            head,
        ))
    }
}

impl LearnedKernel {
    /// Puts the parts together and files every cell under its face (a visibility head).
    pub(crate) fn new(
        scene: Scene,
        frame: InputFrame,
        network: Network,
        output_scale: f64,
        head: ModelHead,
    ) -> LearnedKernel {
        let mut model = LearnedKernel {
            scene,
            frame,
            network,
            output_scale,
            head,
        };
        model.relabel_all();
        model
    }

    /// The same network and frame on a changed scene: the head's emission or visibility
    /// structure are those of `kernel`, the cells keep their places and values.
    pub(crate) fn rebind(&mut self, kernel: &Arc<Kernel>) {
        self.scene = kernel.scene().clone();
        self.head = self.head.on(kernel, self.frame);
        self.relabel_all();
    }

    /// Makes a visibility head use `kernel` (the same scene's) instead of its own.
    pub(crate) fn share_kernel(&mut self, kernel: &Arc<Kernel>) {
        if let ModelHead::Visibility(v) = &mut self.head {
            v.kernel = Arc::clone(kernel);
        }
    }

    /// The scene it was learned on.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// The input normalisation.
    pub fn frame(&self) -> InputFrame {
        self.frame
    }
    /// The network.
    pub fn network(&self) -> &Network {
        &self.network
    }
    /// What the network learns.
    pub fn target(&self) -> Target {
        self.head.target()
    }
    /// The network input for `(s, t)`.
    pub fn input(&self, s: f64, t: f64) -> [f64; 4] {
        self.frame.gamma(&self.scene, s, t)
    }

    /// Files every cell under its face (a visibility head).
    fn relabel_all(&mut self) {
        let all: Vec<usize> = (0..self.network.len()).collect();
        self.head.relabel(&self.network, &all);
    }

    /// Refreshes the faces of the cells the last network step moved or inserted (a cell's
    /// face depends on its position alone).
    pub(crate) fn relabel_moved(&mut self) {
        self.head.relabel(&self.network, self.network.moved_cells());
    }

    /// Numbers the face of every sample's ray (see [`ModelHead::intern_faces`]).
    pub(crate) fn intern_faces(&mut self, samples: &[Sample]) -> Vec<Option<FaceId>> {
        self.head.intern_faces(samples)
    }

    /// The gate of a query at `(s, t)` (see [`ModelHead::gate_at`]).
    pub(crate) fn gate_at(&self, s: f64, t: f64) -> Option<FaceGate<'_>> {
        self.head.gate_at(s, t)
    }

    /// A visibility model's `Ṽ(s, t)` on a pair where visibility varies; `None` elsewhere.
    pub(crate) fn learned_visibility(&self, s: f64, t: f64) -> Option<f64> {
        let v = self.head.visibility_head()?;
        let key = FaceKey::at(&v.kernel, &v.kernel.unoccluded(s, t))?;
        Some(v.visibility(&self.network, &self.input(s, t), &key))
    }

    /// The cells of the face of the visibility structure at `(s, t)` (visibility models, on a
    /// pair where visibility varies): the cells that decide `Ṽ` there.
    pub fn face_cells(&self, s: f64, t: f64) -> Option<Vec<usize>> {
        let v = self.head.visibility_head()?;
        let key = FaceKey::at(&v.kernel, &v.kernel.unoccluded(s, t))?;
        let gate = v.faces.gate(&key, Gating::Faces);
        Some(sgcs::Gate::region(&gate).unwrap_or(&[]).to_vec())
    }

    /// Checks the network's invariants and, for a visibility model, that every cell is filed
    /// under the face its centre lies in.
    pub fn check_invariants(&self) -> Result<(), String> {
        self.network.check_invariants()?;
        if let Some(v) = self.head.visibility_head() {
            v.faces.check(self.network.len(), |c| {
                v.labeller.face(&v.kernel, self.network.position(c))
            })?;
        }
        Ok(())
    }

    /// Number of faces of the visibility structure that hold a cell (visibility models).
    pub fn occupied_faces(&self) -> Option<usize> {
        self.head.visibility_head().map(|v| v.faces.occupied())
    }
}

/// The learned model. A visibility model (the visibility network) integrates its own `Ṽ` exactly
/// against the closed-form transfer, asking `Ṽ` once per face (the `operator` module); a
/// model of ζ or k uses the quadrature default.
impl Representation for LearnedKernel {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        match &self.head {
            ModelHead::Visibility(v) => v.zeta(&self.network, s, t, || self.input(s, t)),
            ModelHead::Zeta => self.network.predict1(&self.input(s, t)) * self.output_scale,
            ModelHead::FactoredEmission { emission } => {
                let kappa = self.network.predict1(&self.input(s, t)) * self.output_scale;
                kappa * emission[self.scene.point(s).edge.index()]
            }
        }
    }
    fn basis_functions(&self) -> Option<usize> {
        Some(self.network.len())
    }
    fn memory_bytes(&self) -> usize {
        // Per cell: position (4), output (1), width (1) as f64; per edge two u32 ids.
        let cells = self.network.len() * (INPUT_DIM + 2) * 8;
        let network = cells + self.network.edges().len() * 8;
        let faces = self
            .head
            .visibility_head()
            .map_or(0, |v| v.memory_bytes(self.network.len()));
        network + faces
    }

    fn scene_fingerprint(&self) -> Option<u64> {
        Some(self.scene().fingerprint())
    }

    fn operator(
        &self,
        mesh: &Mesh,
        params: &SolveParams,
        stop: &Stop,
    ) -> Result<Box<dyn TransferOperator>, SolveError> {
        check_fingerprint(self.scene_fingerprint(), mesh)?;
        if self.head.visibility_head().is_none() {
            check_lights(self.scene.lights(), mesh)?;
        }
        match self.head.visibility_head() {
            Some(v) => Ok(Box::new(super::operator::visibility_operator(
                &|s, t| self.learned_visibility(s, t),
                &v.kernel,
                mesh,
                stop,
            )?)),
            // ζ̃ / E' is k only under the lamps it was learned with (E' depends on them).
            None => Ok(Box::new(quadrature_operator(
                self,
                mesh,
                params.quadrature_points,
                stop,
            )?)),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::ops::ControlFlow;
    use std::sync::Arc;

    use flatland_geom::{DVec2, Edge, Kernel, PointLight, Scene};
    use flatland_solve::{Mesh, Reference, Representation, SolveError, SolveParams, never};

    use crate::{Fit, FitParams, Target};

    /// A room lit by one lamp at `at` only.
    fn lamp_lit(at: DVec2) -> Kernel {
        let room = Edge::polygon(&flatland_testkit::rooms::rectangle(2.0, 1.0), 0.5);
        let scene = Scene::new(room).unwrap();
        Kernel::new(scene.with_lights(vec![PointLight::new(at, 3.0)]).unwrap())
    }

    #[test]
    fn a_model_of_zeta_solves_under_its_own_lamps_and_refuses_them_moved() {
        // E' weighs the walls by the lamp's light, so a lamp-lit scene has a ζ to learn.
        let kernel = Arc::new(lamp_lit(DVec2::new(0.5, 0.5)));
        let reference = Arc::new(Reference::new(&kernel, 16, 64, crate::REFERENCE_SEED));
        let params = FitParams {
            target_cells: 12,
            initial_samples: 60,
            heldout: 64,
            refit: false,
            ..FitParams::default().learning(Target::Zeta)
        };
        let mut fit = Fit::new(Arc::clone(&kernel), reference, params).unwrap();
        fit.run(500, |_| ControlFlow::Continue(())).unwrap();
        let model = fit.model();
        let solve = SolveParams::default();
        let mesh = Mesh::new(&kernel, 40).unwrap();
        assert!(model.operator(&mesh, &solve, &never).is_ok());
        // The same walls, the lamp moved: E' differs, so ζ̃ / E' is not k.
        let moved = lamp_lit(DVec2::new(1.5, 0.5));
        let mesh = Mesh::new(&moved, 40).unwrap();
        let err = model.operator(&mesh, &solve, &never).err().unwrap();
        assert!(
            matches!(
                err,
                SolveError::LightsMismatch {
                    representation: 1,
                    mesh: 1
                }
            ),
            "{err}"
        );
        assert!(
            err.to_string().contains("learn it again on this scene"),
            "{err}"
        );
    }
}
