//! The learned kernel ζ̃: a network and what turns `(s, t)` into its input and its output into
//! ζ̃ (the input frame, the output scale, the emission factors, and for the visibility learner
//! the exact unoccluded kernel and the faces).

use std::sync::Arc;

use flatland_geom::{Kernel, KernelParams, PairClass, Scene};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sgcs::Network;

use crate::fit::Sample;
use crate::visibility::{FaceGate, FaceId, FaceKey, Faces, Labeller};
use flatland_solve::{
    InputFrame, Mesh, Representation, SolveError, SolveParams, Stop, TransferOperator,
    check_fingerprint, quadrature_operator,
};

use crate::{FitError, Gating, Target};

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
    /// E' per edge when the network learns k ([`Target::FactoredEmission`]); empty otherwise.
    pub(crate) emission_factor: Vec<f64>,
    /// The network learns target / `output_scale` (the RMS of S₀'s targets), so its weights
    /// and errors are O(1) whatever the emission or the units: ζ of 1e200 or 1e-200 neither
    /// overflows the network nor underflows its squared errors. 1 for [`Target::Visibility`].
    pub(crate) output_scale: f64,
    pub(crate) target: Target,
    pub(crate) gating: Gating,
    pub(crate) kernel_params: KernelParams,
    /// [`Target::Visibility`]: the exact geometry and the cells' faces (derived, not saved).
    pub(crate) geometry: Option<Geometry>,
}

/// What a visibility model needs besides its network: the scene's exact unoccluded kernel and
/// visibility structure, and the face of every cell.
#[derive(Clone, Debug)]
pub(crate) struct Geometry {
    pub(crate) kernel: Arc<Kernel>,
    pub(crate) labeller: Labeller,
    pub(crate) faces: Faces,
}

/// The saved form of a [`LearnedKernel`]: everything but the derived geometry.
#[derive(Serialize, Deserialize)]
struct LearnedKernelData {
    scene: Scene,
    frame: InputFrame,
    network: Network,
    #[serde(default)]
    emission_factor: Vec<f64>,
    #[serde(default = "unit_scale")]
    output_scale: f64,
    #[serde(default)]
    target: Target,
    #[serde(default)]
    gating: Gating,
    #[serde(default)]
    kernel_params: KernelParams,
}

pub(crate) fn unit_scale() -> f64 {
    1.0
}

impl From<LearnedKernel> for LearnedKernelData {
    fn from(m: LearnedKernel) -> Self {
        LearnedKernelData {
            scene: m.scene,
            frame: m.frame,
            network: m.network,
            emission_factor: m.emission_factor,
            output_scale: m.output_scale,
            target: m.target,
            gating: m.gating,
            kernel_params: m.kernel_params,
        }
    }
}

impl TryFrom<LearnedKernelData> for LearnedKernel {
    type Error = FitError;
    fn try_from(d: LearnedKernelData) -> Result<Self, FitError> {
        let kernel = (d.target == Target::Visibility)
            .then(|| Kernel::with_params(d.scene.clone(), d.kernel_params).map(Arc::new))
            .transpose()?;
        Ok(LearnedKernel::assemble(
            d.scene,
            d.frame,
            d.network,
            d.emission_factor,
            d.output_scale,
            d.target,
            d.gating,
            kernel,
        ))
    }
}

impl LearnedKernel {
    /// Puts the parts together; `kernel` is required for [`Target::Visibility`].
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn assemble(
        scene: Scene,
        frame: InputFrame,
        network: Network,
        emission_factor: Vec<f64>,
        output_scale: f64,
        target: Target,
        gating: Gating,
        kernel: Option<Arc<Kernel>>,
    ) -> LearnedKernel {
        let kernel_params = kernel
            .as_ref()
            .map_or_else(KernelParams::default, |k| k.params());
        let mut model = LearnedKernel {
            scene,
            frame,
            network,
            emission_factor,
            output_scale,
            target,
            gating,
            kernel_params,
            geometry: None,
        };
        if let (Target::Visibility, Some(kernel)) = (target, kernel) {
            let labeller = Labeller::new(&kernel, frame);
            model.geometry = Some(Geometry {
                kernel,
                labeller,
                faces: Faces::default(),
            });
            let all: Vec<usize> = (0..model.network.len()).collect();
            model.relabel(&all);
        }
        model
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
        self.target
    }
    /// The network input for `(s, t)`.
    pub fn input(&self, s: f64, t: f64) -> [f64; 4] {
        self.frame.gamma(&self.scene, s, t)
    }

    /// Refreshes the faces of the cells the last network step moved or inserted (a cell's
    /// face depends on its position alone).
    pub(crate) fn relabel_moved(&mut self) {
        let LearnedKernel {
            network, geometry, ..
        } = self;
        let Some(geometry) = geometry else {
            return;
        };
        for &c in network.moved_cells() {
            let face = geometry
                .labeller
                .face(&geometry.kernel, network.position(c));
            geometry.faces.place(c, face);
        }
    }

    /// Numbers the face of every sample's ray (visibility models; all `None` otherwise), in
    /// parallel, so a training step gates on it without recomputing it.
    pub(crate) fn intern_faces(&mut self, samples: &[Sample]) -> Vec<Option<FaceId>> {
        let Some(geometry) = &mut self.geometry else {
            return vec![None; samples.len()];
        };
        let kernel = &geometry.kernel;
        let keys: Vec<Option<FaceKey>> = samples
            .par_iter()
            .with_min_len(256)
            .map(|s| FaceKey::at(kernel, &kernel.unoccluded(s.st[0], s.st[1])))
            .collect();
        keys.into_iter()
            .map(|key| key.map(|key| geometry.faces.intern(key)))
            .collect()
    }

    /// Refreshes the faces of `cells` (after they moved or were inserted).
    pub(crate) fn relabel(&mut self, cells: &[usize]) {
        let Some(geometry) = &mut self.geometry else {
            return;
        };
        for &c in cells {
            let face = geometry
                .labeller
                .face(&geometry.kernel, self.network.position(c));
            geometry.faces.place(c, face);
        }
    }

    /// The gate of a ray in face `key` (visibility models with gating only).
    pub(crate) fn gate<'a>(&'a self, key: &FaceKey) -> Option<FaceGate<'a>> {
        let geometry = self.geometry.as_ref()?;
        (self.gating != Gating::Off).then(|| geometry.faces.gate(key, self.gating))
    }

    /// `Ṽ` at a ray of a pair with varying visibility, in `[0, 1]`.
    fn visibility(&self, xi: &[f64; 4], key: &FaceKey) -> f64 {
        let v = match self.gate(key) {
            Some(gate) => self.network.predict1_gated(xi, &gate),
            None => self.network.predict1(xi),
        };
        v.clamp(0.0, 1.0)
    }

    /// The exact kernel a visibility model keeps; `None` for the paper's network.
    pub(crate) fn geometry_kernel(&self) -> Option<&Kernel> {
        self.geometry.as_ref().map(|g| g.kernel.as_ref())
    }

    /// A visibility model's `Ṽ(s, t)` on a pair where visibility varies; `None` elsewhere.
    pub(crate) fn learned_visibility(&self, s: f64, t: f64) -> Option<f64> {
        let g = self.geometry.as_ref()?;
        let key = FaceKey::at(&g.kernel, &g.kernel.unoccluded(s, t))?;
        Some(self.visibility(&self.input(s, t), &key))
    }

    /// The cells of the face of the visibility structure at `(s, t)` (visibility models, on a
    /// pair where visibility varies): the cells that decide `Ṽ` there.
    pub fn face_cells(&self, s: f64, t: f64) -> Option<Vec<usize>> {
        let g = self.geometry.as_ref()?;
        let key = FaceKey::at(&g.kernel, &g.kernel.unoccluded(s, t))?;
        let gate = g.faces.gate(&key, Gating::Faces);
        Some(sgcs::Gate::region(&gate).unwrap_or(&[]).to_vec())
    }

    /// Checks the network's invariants and, for a visibility model, that every cell is filed
    /// under the face its centre lies in.
    pub fn check_invariants(&self) -> Result<(), String> {
        self.network.check_invariants()?;
        if let Some(g) = &self.geometry {
            g.faces.check(self.network.len(), |c| {
                g.labeller.face(&g.kernel, self.network.position(c))
            })?;
        }
        Ok(())
    }

    /// Number of faces of the visibility structure that hold a cell (visibility models).
    pub fn occupied_faces(&self) -> Option<usize> {
        self.geometry.as_ref().map(|g| g.faces.occupied())
    }
}

/// The learned model. A visibility model (the default learner) integrates its own `Ṽ` exactly
/// against the closed-form transfer, asking `Ṽ` once per face (the `operator` module); the
/// paper's network, which learns ζ itself, uses the quadrature default.
impl Representation for LearnedKernel {
    fn zeta(&self, s: f64, t: f64) -> f64 {
        if let Some(geometry) = &self.geometry {
            let kernel = &geometry.kernel;
            let u = kernel.unoccluded(s, t);
            if u.zeta == 0.0 {
                return 0.0;
            }
            return match kernel.pair_class(u.sender, u.receiver) {
                PairClass::Zero | PairClass::Hidden => 0.0,
                PairClass::Visible => u.zeta,
                PairClass::Varies => match FaceKey::at(kernel, &u) {
                    Some(key) => u.zeta * self.visibility(&self.input(s, t), &key),
                    None => 0.0,
                },
            };
        }
        let kappa = self.network.predict1(&self.input(s, t)) * self.output_scale;
        if self.emission_factor.is_empty() {
            kappa
        } else {
            kappa * self.emission_factor[self.scene.point(s).edge]
        }
    }
    fn basis_functions(&self) -> Option<usize> {
        Some(self.network.len())
    }
    fn memory_bytes(&self) -> usize {
        // Per cell: position (4), output (1), width (1) as f64; per edge two u32 ids.
        let cells = self.network.len() * (INPUT_DIM + 2) * 8;
        let network = cells + self.network.edges().len() * 8;
        // A visibility model also keeps what it needs to find a ray's face: each cell's face
        // (a u32), the class of every pair of surface edges (a byte each) and the event points
        // of the pairs where visibility varies (two f64 each).
        let geometry = self.geometry.as_ref().map_or(0, |g| {
            let n = g.kernel.surface_parents();
            if n > crate::visibility::MAX_LISTED_PARENTS {
                // Not kept: computed per pair when asked (as the exact kernel does).
                return self.network.len() * 4;
            }
            let mut events = 0;
            for a in 0..n {
                for b in 0..n {
                    if let Some(e) = g.kernel.visibility_events(a, b) {
                        events += (0..4).map(|k| e.points(k).len()).sum::<usize>();
                    }
                }
            }
            self.network.len() * 4 + n * n + events * 16
        });
        network + geometry
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
        match self.geometry_kernel() {
            Some(kernel) => Ok(Box::new(super::operator::visibility_operator(
                self, kernel, mesh, stop,
            )?)),
            None => Ok(Box::new(quadrature_operator(
                self,
                mesh,
                params.quadrature_points,
                stop,
            )?)),
        }
    }
}
