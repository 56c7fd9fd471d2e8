//! What turns the network's output into ζ̃, per learner: ζ itself, k times the exact emission,
//! or `V` times the exact unoccluded ζ, with the faces of the visibility structure that gate
//! the cells.

use std::sync::Arc;

use flatland_geom::{EdgeId, Kernel, KernelParams, PairClass};
use flatland_solve::InputFrame;
use rayon::prelude::*;
use sgcs::{CellId, Network};

use super::Sample;
use crate::visibility::{FaceGate, FaceId, FaceKey, Faces, Labeller};
use crate::{Gating, Head, Target};

/// Up to this many surface edges a model's bytes count the class of every pair (n² of them).
const MAX_COUNTED_PARENTS: usize = 512;

/// A learned kernel's head (see [`Head`], from which it is built).
#[derive(Clone, Debug)]
pub(crate) enum ModelHead {
    /// `ζ̃ = κ · output scale` (the paper's network).
    Zeta,
    /// `ζ̃ = κ · output scale · E'(sender edge)`.
    FactoredEmission {
        /// `E'` per edge of the scene.
        emission: Vec<f64>,
    },
    /// `ζ̃ = ζ_unoccluded · Ṽ` where visibility varies, the exact kernel elsewhere.
    Visibility(Box<VisibilityHead>),
}

/// The visibility learner's head: its gating and what it derives from the scene — the exact
/// unoccluded kernel and visibility structure, and the face of every cell (rebuilt from the
/// cells' positions, never saved).
#[derive(Clone, Debug)]
pub(crate) struct VisibilityHead {
    pub(crate) gating: Gating,
    pub(crate) kernel: Arc<Kernel>,
    pub(crate) labeller: Labeller,
    pub(crate) faces: Faces,
}

impl ModelHead {
    /// The head of `head`'s learner on `kernel`'s scene (a visibility head's cells are not
    /// filed yet: see [`ModelHead::relabel`]).
    pub(crate) fn new(head: &Head, kernel: &Arc<Kernel>, frame: InputFrame) -> ModelHead {
        match head {
            Head::Zeta { .. } => ModelHead::Zeta,
            Head::FactoredEmission { .. } => ModelHead::FactoredEmission {
                emission: emission(kernel),
            },
            Head::Visibility(v) => ModelHead::visibility(v.gating, kernel, frame),
        }
    }

    /// A visibility head with no cell filed yet.
    pub(crate) fn visibility(gating: Gating, kernel: &Arc<Kernel>, frame: InputFrame) -> Self {
        ModelHead::Visibility(Box::new(VisibilityHead {
            gating,
            kernel: Arc::clone(kernel),
            labeller: Labeller::new(kernel, frame),
            faces: Faces::default(),
        }))
    }

    /// The same learner's head on another scene (the kernel of a changed scene).
    pub(crate) fn on(&self, kernel: &Arc<Kernel>, frame: InputFrame) -> ModelHead {
        match self {
            ModelHead::Zeta => ModelHead::Zeta,
            ModelHead::FactoredEmission { .. } => ModelHead::FactoredEmission {
                emission: emission(kernel),
            },
            ModelHead::Visibility(v) => ModelHead::visibility(v.gating, kernel, frame),
        }
    }

    /// What the network learns.
    pub(crate) fn target(&self) -> Target {
        match self {
            ModelHead::Zeta => Target::Zeta,
            ModelHead::FactoredEmission { .. } => Target::FactoredEmission,
            ModelHead::Visibility(_) => Target::Visibility,
        }
    }

    /// The kernel parameters a visibility head's exact kernel was built with (the defaults for
    /// the others, which keep no kernel).
    pub(crate) fn kernel_params(&self) -> KernelParams {
        match self {
            ModelHead::Visibility(v) => v.kernel.params(),
            ModelHead::Zeta | ModelHead::FactoredEmission { .. } => KernelParams::default(),
        }
    }

    /// The visibility head, for what only it has (faces, gates, the exact kernel).
    pub(crate) fn visibility_head(&self) -> Option<&VisibilityHead> {
        match self {
            ModelHead::Visibility(v) => Some(v),
            ModelHead::Zeta | ModelHead::FactoredEmission { .. } => None,
        }
    }

    /// Files `cells` under the faces their centres are in (after they moved or were inserted);
    /// nothing for a head without faces.
    pub(crate) fn relabel(&mut self, network: &Network, cells: &[CellId]) {
        if let ModelHead::Visibility(v) = self {
            for &c in cells {
                let face = v.labeller.face(&v.kernel, network.position(c));
                v.faces.place(c, face);
            }
        }
    }

    /// Numbers the face of every sample's ray (all `None` for a head without faces), in
    /// parallel, so a training step gates on it without recomputing it.
    pub(crate) fn intern_faces(&mut self, samples: &[Sample]) -> Vec<Option<FaceId>> {
        let ModelHead::Visibility(v) = self else {
            return vec![None; samples.len()];
        };
        let kernel = &v.kernel;
        let keys: Vec<Option<FaceKey>> = samples
            .par_iter()
            .with_min_len(256)
            .map(|s| FaceKey::at(kernel, &kernel.unoccluded(s.st[0], s.st[1])))
            .collect();
        keys.into_iter()
            .map(|key| key.map(|key| v.faces.intern(key)))
            .collect()
    }

    /// The gate of a training step on a sample in `face`: the cells of that face (or pair), for
    /// a visibility head that gates; `None` (every cell) otherwise.
    pub(crate) fn training_gate(&self, face: Option<FaceId>) -> Option<FaceGate<'_>> {
        match (self, face) {
            (ModelHead::Visibility(v), Some(face)) if v.gating != Gating::Off => {
                Some(v.faces.gate_of(face, v.gating))
            }
            _ => None,
        }
    }

    /// The gate of a query at `(s, t)`: that of its face for a visibility head that gates and
    /// a pair where visibility varies; `None` (every cell) otherwise.
    pub(crate) fn gate_at(&self, s: f64, t: f64) -> Option<FaceGate<'_>> {
        let v = self.visibility_head()?;
        let key = FaceKey::at(&v.kernel, &v.kernel.unoccluded(s, t))?;
        v.gate(&key)
    }
}

/// `E'` per edge of `kernel`'s scene.
fn emission(kernel: &Kernel) -> Vec<f64> {
    (0..kernel.scene().edges().len())
        .map(|e| kernel.source_weight(EdgeId::new(e)))
        .collect()
}

impl VisibilityHead {
    /// The gate of a ray in face `key` (`None` without gating).
    pub(crate) fn gate(&self, key: &FaceKey) -> Option<FaceGate<'_>> {
        (self.gating != Gating::Off).then(|| self.faces.gate(key, self.gating))
    }

    /// `Ṽ` at a ray (network input `xi`) in face `key`, in `[0, 1]`.
    pub(crate) fn visibility(&self, network: &Network, xi: &[f64; 4], key: &FaceKey) -> f64 {
        let v = match self.gate(key) {
            Some(gate) => network.predict1_gated(xi, &gate),
            None => network.predict1(xi),
        };
        v.clamp(0.0, 1.0)
    }

    /// `ζ̃(s, t)`: exact where geometry decides visibility, `ζ_unoccluded · Ṽ` where it varies
    /// (`input` gives the network input at `(s, t)`, computed only there).
    pub(crate) fn zeta(
        &self,
        network: &Network,
        s: f64,
        t: f64,
        input: impl FnOnce() -> [f64; 4],
    ) -> f64 {
        let kernel = &self.kernel;
        let u = kernel.unoccluded(s, t);
        if u.zeta == 0.0 {
            return 0.0;
        }
        match kernel.pair_class(u.sender, u.receiver) {
            PairClass::Zero | PairClass::Hidden => 0.0,
            PairClass::Visible => u.zeta,
            PairClass::Varies => match FaceKey::at(kernel, &u) {
                Some(key) => u.zeta * self.visibility(network, &input(), &key),
                None => 0.0,
            },
        }
    }

    /// Bytes it keeps to find a ray's face: each cell's face (a u32), the class of every pair
    /// of surface edges (a byte each) and the event points of the pairs where visibility
    /// varies (two f64 each).
    pub(crate) fn memory_bytes(&self, cells: usize) -> usize {
        let n = self.kernel.surface_parents();
        if n > MAX_COUNTED_PARENTS {
            // Not kept: computed per pair when asked (as the exact kernel does).
            return cells * 4;
        }
        let mut events = 0;
        for a in self.kernel.surface_ranks() {
            for b in self.kernel.surface_ranks() {
                if let Some(e) = self.kernel.visibility_events(a, b) {
                    events += (0..4).map(|k| e.points(k).len()).sum::<usize>();
                }
            }
        }
        cells * 4 + n * n + events * 16
    }
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use crate::fit::test_support::*;
    use crate::model::Sample;
    use crate::{FitParams, Preset};

    /// A visibility model's cells, moved far by training steps at random rays (gated by the
    /// ray's face or not) and inserted at random places, stay filed under the face their centre
    /// is in: the invariants hold after every change.
    #[test]
    fn cells_stay_filed_under_their_faces_through_random_moves_and_insertions() {
        let kernel = maze();
        let base = preset(Preset::Visibility, 120);
        let params = FitParams {
            network: sgcs::Params {
                eps_b: 0.5,
                eps_n: 0.2,
                lambda: 7,
                ..base.network
            },
            ..base
        };
        let mut model = fit_with(&kernel, params).model().clone();
        let mut rng = crate::seeds::stream(12, 0);
        let mut inserted = 0;
        for change in 0..600 {
            let st = [rng.random::<f64>(), rng.random::<f64>()];
            let xi = model.input(st[0], st[1]);
            if rng.random::<f64>() < 0.1 && model.network.len() < 120 {
                let c = model
                    .network
                    .insert_at(&xi, &[rng.random::<f64>()])
                    .unwrap();
                model.head.relabel(&model.network, &[c]);
                inserted += 1;
            } else {
                let sample = Sample {
                    st,
                    xi,
                    target: f64::from(rng.random::<bool>()),
                    weight: 1.0,
                };
                let face = model.intern_faces(&[sample])[0];
                let face = if rng.random::<bool>() { face } else { None };
                let target = [sample.target];
                let gate = model.head.training_gate(face);
                match &gate {
                    Some(gate) => model.network.try_step_gated(&xi, &target, 1.0, gate),
                    None => model.network.try_step_gated(&xi, &target, 1.0, &sgcs::Open),
                }
                .unwrap();
                model.relabel_moved();
            }
            model
                .check_invariants()
                .unwrap_or_else(|e| panic!("after change {change}: {e}"));
        }
        assert!(inserted > 20, "{inserted} insertions");
        assert!(model.occupied_faces().unwrap() > 3);
    }
}
