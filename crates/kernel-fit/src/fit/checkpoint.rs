//! Checkpoints: the whole learning state in a versioned file, saved atomically, resumed to the
//! same result as an uninterrupted run.

use std::sync::Arc;

use flatland_geom::Kernel;
use flatland_solve::Reference;

use super::state::{CHECKPOINT_FORMAT, CHECKPOINT_VERSION, Checkpoint, LoadedState};
use super::{Fit, StopReason, checks};
use crate::FitError;

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
            state: self.state.saved(),
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
        let c: Checkpoint<LoadedState> = flatland_geom::versioned::read(
            &text,
            &flatland_geom::versioned::Kind {
                format: CHECKPOINT_FORMAT,
                version: CHECKPOINT_VERSION,
                noun: "checkpoint",
                remedy: "start the fit again with this build",
            },
        )
        .map_err(bad)?;
        checks::checkpoint(&c).map_err(bad)?;
        let loaded = c.state;
        if crate::fingerprint_hex(&loaded.model.scene) != c.scene_fingerprint {
            return Err(bad(
                "the embedded scene does not match its fingerprint".to_owned()
            ));
        }
        let valid = loaded.params.check().map_err(|e| bad(e.to_string()))?;
        let mut state = loaded.into_state(&valid.fixed.head).map_err(bad)?;
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
        state.model.share_kernel(&kernel);
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
            valid,
            state,
            sample_faces: Vec::new(),
        };
        fit.index_sample_faces();
        Ok(fit)
    }
}

#[cfg(test)]
mod tests {
    use std::ops::ControlFlow;

    use super::super::test_support::*;
    use super::*;
    use crate::Preset;

    #[test]
    fn resume_continues_to_the_same_result() {
        for (p, kernel, cells) in [
            (Preset::Paper, fig3(), 60),
            (Preset::Visibility, maze(), 120),
        ] {
            let mut full = fit_with(&kernel, preset(p, cells));
            let uninterrupted = run(&mut full);

            let mut first = fit_with(&kernel, preset(p, cells));
            let reason = first.train(500, |f| {
                if f.steps() >= 7_000 {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            });
            assert_eq!(reason, StopReason::Interrupted);
            let dir = std::env::temp_dir().join(format!(
                "flatland-resume-{}-{}",
                std::process::id(),
                p.name()
            ));
            std::fs::create_dir_all(&dir).unwrap();
            let path = dir.join("fit.ckpt.json");
            first.save_checkpoint(&path).unwrap();
            let mut resumed = Fit::resume(&path, flatland_geom::KernelParams::default()).unwrap();
            assert_eq!(resumed.steps(), first.steps());
            let summary = run(&mut resumed);
            std::fs::remove_dir_all(&dir).unwrap();
            assert_eq!(
                (summary.rays, summary.steps, summary.cells, summary.samples),
                (
                    uninterrupted.rays,
                    uninterrupted.steps,
                    uninterrupted.cells,
                    uninterrupted.samples
                ),
                "{p:?}"
            );
            // serde_json's float_roundtrip makes the checkpoint exact: the same fit to the last
            // bit (a visibility model rebuilds its cells' faces from their positions).
            assert_eq!(summary.errors, uninterrupted.errors, "{p:?}");
        }
    }

    #[test]
    fn checkpoints_of_another_kind_or_version_are_refused() {
        let dir = std::env::temp_dir().join(format!("flatland-ckpt-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cases = [
            (
                r#"{"format":"flatland-checkpoint","version":99}"#,
                "version",
            ),
            (
                r#"{"format":"something-else","version":1}"#,
                "not a flatland checkpoint",
            ),
            ("{ truncated", "line 1"),
            (
                r#"{"format":"flatland-checkpoint","version":1,"params":{}}"#,
                "malformed",
            ),
        ];
        for (i, (text, expected)) in cases.iter().enumerate() {
            let path = dir.join(format!("{i}.json"));
            std::fs::write(&path, text).unwrap();
            let err = Fit::resume(&path, flatland_geom::KernelParams::default())
                .err()
                .expect("must be refused")
                .to_string();
            assert!(
                err.contains(expected) && err.contains(&format!("{i}.json")),
                "{err}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
