//! Checkpoints: the whole learning state in a versioned file, saved atomically, resumed to the
//! same result as an uninterrupted run.

use super::*;

/// The `format` field of checkpoint files.
pub const CHECKPOINT_FORMAT: &str = "flatland-checkpoint";
/// The checkpoint version this build reads and writes.
pub const CHECKPOINT_VERSION: u32 = 1;

/// A checkpoint file: a header that identifies it, then the state (borrowed when written).
#[derive(Serialize, Deserialize)]
pub(crate) struct Checkpoint<S> {
    pub(crate) format: String,
    pub(crate) version: u32,
    pub(crate) scene_fingerprint: String,
    pub(crate) reference_res: usize,
    pub(crate) reference_heldout: usize,
    pub(crate) state: S,
}

impl Fit {
    /// Saves the whole learning state atomically (temporary file, then rename), so an
    /// interrupted run leaves the previous checkpoint intact. [`Fit::resume`] continues from it
    /// to the same result as an uninterrupted run with the same seed.
    pub fn save_checkpoint(&self, path: &std::path::Path) -> Result<(), FitError> {
        let checkpoint = Checkpoint {
            format: CHECKPOINT_FORMAT.to_owned(),
            version: CHECKPOINT_VERSION,
            scene_fingerprint: crate::fingerprint_hex(&self.state.model.scene),
            reference_res: self.reference.res(),
            reference_heldout: self.reference.heldout().0.len(),
            state: &self.state,
        };
        let text = serde_json::to_vec(&checkpoint).map_err(|e| FitError::Model {
            path: path.to_owned(),
            reason: format!("cannot serialise the checkpoint: {e}"),
        })?;
        Ok(flatland_geom::write_atomic(path, &text)?)
    }

    /// Continues a fit from a checkpoint. The kernel is rebuilt from the embedded scene with
    /// `kernel_params`; the reference from it with the checkpoint's resolution and
    /// [`REFERENCE_SEED`](crate::REFERENCE_SEED).
    /// A file of another kind or version is refused with a message, never misread.
    pub fn resume(
        path: &std::path::Path,
        kernel_params: flatland_geom::KernelParams,
    ) -> Result<Fit, FitError> {
        let bad = |reason: String| FitError::Model {
            path: path.to_owned(),
            reason,
        };
        let text = std::fs::read(path).map_err(|source| FitError::Io {
            path: path.to_owned(),
            source,
        })?;
        let c: Checkpoint<FitState> = crate::versioned::read(
            &text,
            &crate::versioned::Kind {
                format: CHECKPOINT_FORMAT,
                version: CHECKPOINT_VERSION,
                noun: "checkpoint",
                remedy: "start the fit again with this build",
            },
        )
        .map_err(bad)?;
        checks::checkpoint(&c).map_err(bad)?;
        let mut state = c.state;
        if crate::fingerprint_hex(&state.model.scene) != c.scene_fingerprint {
            return Err(bad(
                "the embedded scene does not match its fingerprint".to_owned()
            ));
        }
        state.params.validate()?;
        let kernel = Arc::new(Kernel::with_params(
            state.model.scene.clone(),
            kernel_params,
        )?);
        let reference = Arc::new(Reference::new(
            &kernel,
            c.reference_res,
            c.reference_heldout,
            crate::REFERENCE_SEED,
        ));
        if let Some(geometry) = &mut state.model.geometry {
            geometry.kernel = Arc::clone(&kernel);
        }
        let sets_ok = if state.samples.is_empty() {
            state.set_starts.is_empty()
        } else {
            state.set_starts.first() == Some(&0)
        };
        if state.cell_stats.len() != state.model.network.len()
            || !sets_ok
            || state.set_starts.windows(2).any(|w| w[0] >= w[1])
            || state
                .set_starts
                .last()
                .is_some_and(|&l| l >= state.samples.len())
        {
            return Err(bad(
                "inconsistent checkpoint (cells, sets or samples)".to_owned()
            ));
        }
        // An interrupted fit resumes; a finished one stays finished.
        state.stop = state.stop.filter(|&r| r != StopReason::Interrupted);
        let mut fit = Fit {
            kernel,
            reference,
            state,
            sample_faces: Vec::new(),
        };
        fit.index_sample_faces();
        Ok(fit)
    }
}
