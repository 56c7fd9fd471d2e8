//! Changing a running fit: its scene (the network keeps learning from where it is) and its
//! live parameters.

use std::sync::Arc;

use flatland_geom::Kernel;
use flatland_solve::Reference;

use super::{CellStats, Fit, Source, StopReason, rays_of};
use crate::{FitError, LiveParams};

impl Fit {
    /// Continues learning on a changed scene (the representation stays adaptive: a changed
    /// scene is learned on, not from scratch).
    ///
    /// The network keeps its cells, weights and counters and the input frame stays put (so the
    /// cells keep their meaning); the old samples describe the old scene and are dropped, and a
    /// new S₀ of `max(|S₀|, |A|/ψ)` samples is drawn from the new kernel's source.
    pub fn set_kernel(&mut self, kernel: Arc<Kernel>, reference: Arc<Reference>) {
        let (fixed, live) = (self.valid.fixed, self.valid.live);
        let cells = self.state.model.network.len();
        let n = fixed
            .initial_samples
            .max((cells as f64 / live.psi).ceil() as usize);
        let frame = self.state.model.frame;
        let rng = &mut self.state.resample_rng;
        let source = Source::start(&fixed.head, &kernel, rng);
        let draws = source.draw(&kernel, n, rng);
        self.state.samples = source.label(&kernel, frame, self.state.model.output_scale, &draws);
        self.state.stop = source.nothing_to_learn().then_some(StopReason::Exact);
        self.state.source = source;
        self.state.rays += rays_of(&kernel, &self.state.samples);
        self.state.set_starts = if self.state.samples.is_empty() {
            Vec::new()
        } else {
            vec![0]
        };
        self.state.cell_stats = vec![CellStats::default(); cells];
        // The cells keep their places and values; their faces are those of the new scene.
        self.state.model.rebind(&kernel);
        self.kernel = kernel;
        self.reference = reference;
        self.state.steps_at_last_growth = self.steps();
        self.sample_faces.clear();
        self.index_sample_faces();
    }

    /// Changes what may change while the fit runs (the viewer's controls): when it stops, the
    /// network's rates, how new sets are drawn. What the network learns, its rules, S₀ and the
    /// seed are fixed for a fit ([`FixedParams`](crate::FixedParams)): changing them needs a
    /// new [`Fit`]. A fit that stopped may go on under the new rules, except one with nothing
    /// to learn ([`StopReason::Exact`]).
    pub fn set_params(&mut self, live: LiveParams) -> Result<(), FitError> {
        let params = self.state.params.with_live(live);
        let valid = params.check()?;
        self.state.model.network.set_params(valid.network())?;
        self.state.params = params;
        self.valid = valid;
        if self.state.stop != Some(StopReason::Exact) {
            self.state.stop = None;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use flatland_geom::{DVec2, EdgeId};
    use rand::RngExt;

    use super::super::test_support::*;
    use super::*;
    use crate::Preset;

    /// Every cell filed under the face its centre is in, and every sample's face the one a
    /// fresh filing of the samples gives.
    fn assert_filed(fit: &Fit, when: &str) {
        fit.model()
            .check_invariants()
            .unwrap_or_else(|e| panic!("{when}: {e}"));
        let fresh = fit.state.model.clone().intern_faces(&fit.state.samples);
        assert_eq!(fresh, fit.sample_faces, "{when}: the samples' faces");
    }

    /// Scene edits at random (an end point of a random edge dragged, as in the viewer), each
    /// followed by training that moves and inserts cells: the visibility network's cells and
    /// samples stay filed under the faces of the scene of the moment.
    #[test]
    fn face_filing_survives_random_scene_edits() {
        let mut kernel = maze();
        let mut fit = fit_with(&kernel, preset(Preset::Visibility, 60));
        run(&mut fit);
        assert_filed(&fit, "before any edit");
        let mut rng = flatland_testkit::rng(31);
        let (mut edits, mut refused) = (0, 0);
        while edits < 6 {
            let scene = kernel.scene();
            let e = rng.random_range(0..scene.edges().len());
            let mut edge = scene.edges()[e];
            let shift = DVec2::new(rng.random_range(-0.4..0.4), rng.random_range(-0.4..0.4));
            if rng.random_bool(0.5) {
                edge.a += shift;
            } else {
                edge.b += shift;
            }
            let Ok(edited) = scene.with_edge(EdgeId::new(e), edge) else {
                refused += 1; // an edit the scene refuses (a zero-length edge, say)
                continue;
            };
            edits += 1;
            kernel = Arc::new(Kernel::new(edited));
            let reference = Arc::new(Reference::new(&kernel, 32, 256, 1));
            let cells = fit.network().len();
            fit.set_kernel(Arc::clone(&kernel), reference);
            assert_filed(&fit, &format!("after edit {edits} (edge {e})"));
            fit.set_params(preset(Preset::Visibility, cells + 15).live())
                .unwrap();
            for _ in 0..3000 {
                if fit.step().is_some() {
                    break;
                }
            }
            assert_filed(&fit, &format!("after training on edit {edits}"));
        }
        assert!(refused < 20, "{refused} edits refused");
        assert!(fit.network().len() > 60, "cells were inserted on the way");
    }

    #[test]
    fn a_moved_blocker_is_learned_from_the_current_state() {
        let kernel = fig3();
        for p in Preset::ALL {
            let mut fit = fit_with(&kernel, preset(p, 80));
            run(&mut fit);
            let scene = kernel.scene();
            let blocker = scene
                .edges()
                .iter()
                .position(|e| e.role == flatland_geom::Role::Blocker)
                .unwrap();
            let mut moved = scene.edges()[blocker];
            moved.a.x += 0.8;
            moved.b.x += 0.8;
            let moved = scene.with_edge(EdgeId::new(blocker), moved).unwrap();
            let new_kernel = Arc::new(Kernel::new(moved));
            let reference = Arc::new(Reference::new(&new_kernel, 64, 2048, 1));
            let cells_before = fit.network().len();
            fit.set_kernel(Arc::clone(&new_kernel), Arc::clone(&reference));
            let stale = reference.errors(fit.model());
            fit.set_params(preset(p, 100).live()).unwrap();
            let after = run(&mut fit);
            assert!(after.cells >= cells_before && after.cells <= 100, "{p:?}");
            assert!(
                after.errors.heldout < stale.heldout,
                "{p:?}: {stale:?} -> {:?}",
                after.errors
            );
        }
    }
}
