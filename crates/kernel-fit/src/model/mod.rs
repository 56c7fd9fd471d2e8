//! The learned model: [`LearnedKernel`] (in `learned`; its learner's head in `head`, its
//! transfer operator in `operator`), and model files — scene fingerprint, parameters and
//! network in one versioned JSON, written atomically.

pub(crate) mod checks;
pub(crate) mod head;
pub(crate) mod learned;
mod operator;
mod sample;

use std::path::Path;

use flatland_geom::{Scene, write_atomic};
use serde::{Deserialize, Serialize};

use crate::{FitError, FitParams, FitSummary, LearnedKernel};

pub(crate) use sample::Sample;

/// The `format` field every model file carries.
pub const MODEL_FORMAT: &str = "flatland-model";
/// The model file version this build reads and writes.
pub const MODEL_VERSION: u32 = 1;

/// What a model file holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModelFile {
    /// Always [`MODEL_FORMAT`].
    pub format: String,
    /// Always [`MODEL_VERSION`] when written by this build.
    pub version: u32,
    /// `Scene::fingerprint` of the scene it was learned on, as 16 hex digits.
    pub scene_fingerprint: String,
    /// The parameters of the fit.
    pub params: FitParams,
    /// The figures of the fit.
    pub summary: Option<FitSummary>,
    /// The learned kernel (scene, input frame, network).
    pub model: LearnedKernel,
}

impl ModelFile {
    /// Wraps a learned kernel for saving.
    pub fn new(model: LearnedKernel, params: FitParams, summary: Option<FitSummary>) -> ModelFile {
        ModelFile {
            format: MODEL_FORMAT.to_owned(),
            version: MODEL_VERSION,
            scene_fingerprint: fingerprint_hex(model.scene()),
            params,
            summary,
            model,
        }
    }

    /// Writes the file atomically (temporary file in the same folder, then rename), so a crash
    /// never leaves a half-written model where a good one was.
    pub fn save(&self, path: &Path) -> Result<(), FitError> {
        let text = serde_json::to_string(self).map_err(|e| FitError::Model {
            path: path.to_owned(),
            reason: format!("cannot serialise: {e}"),
        })?;
        Ok(write_atomic(path, text.as_bytes())?)
    }

    /// Reads and checks a model file: format, version, and that the embedded scene matches its
    /// fingerprint.
    pub fn load(path: &Path) -> Result<ModelFile, FitError> {
        let text = std::fs::read_to_string(path).map_err(|source| FitError::Io {
            path: path.to_owned(),
            source,
        })?;
        let bad = |reason: String| FitError::Model {
            path: path.to_owned(),
            reason,
        };
        let file: ModelFile = flatland_geom::versioned::read(
            text.as_bytes(),
            &flatland_geom::versioned::Kind {
                format: MODEL_FORMAT,
                version: MODEL_VERSION,
                noun: "model",
                remedy: "refit the model with this build",
            },
        )
        .map_err(bad)?;
        let actual = fingerprint_hex(file.model.scene());
        if actual != file.scene_fingerprint {
            return Err(bad(format!(
                "embedded scene has fingerprint {actual}, but the file says {}: the file was edited",
                file.scene_fingerprint
            )));
        }
        file.validate().map_err(bad)?;
        Ok(file)
    }

    /// Checks every field against the others: parameters in range, the network's shape, the
    /// input frame, the output scale and emission factors, predictions that cannot overflow,
    /// finite figures. The error names the field and the valid range.
    fn validate(&self) -> Result<(), String> {
        checks::params(&self.params)?;
        checks::learned_kernel(&self.model, self.params.target)?;
        if let Some(summary) = &self.summary {
            checks::summary(summary, self.model.network().len())?;
        }
        Ok(())
    }

    /// Refuses a model learned on another scene.
    pub fn check_scene(&self, scene: &Scene, scene_path: &Path) -> Result<(), FitError> {
        let actual = fingerprint_hex(scene);
        if actual == self.scene_fingerprint {
            Ok(())
        } else {
            Err(FitError::Model {
                path: scene_path.to_owned(),
                reason: format!(
                    "scene fingerprint {actual} does not match the model's {}: \
                     the model was learned on another scene (or another subdivision)",
                    self.scene_fingerprint
                ),
            })
        }
    }
}

/// The scene fingerprint as 16 lower-case hex digits.
pub fn fingerprint_hex(scene: &Scene) -> String {
    format!("{:016x}", scene.fingerprint())
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use crate::Preset;
    use crate::fit::test_support::*;
    use flatland_solve::Representation;

    /// A visibility model saved and loaded predicts exactly the same (its faces are rebuilt).
    #[test]
    fn visibility_models_round_trip_through_model_files() {
        let kernel = maze();
        let mut fit = fit_with(&kernel, preset(Preset::Visibility, 60));
        let summary = run(&mut fit);
        let dir = std::env::temp_dir().join(format!("flatland-vismodel-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("model.json");
        let file = crate::ModelFile::new(fit.model().clone(), *fit.params(), Some(summary));
        file.save(&path).unwrap();
        let loaded = crate::ModelFile::load(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        loaded.model.check_invariants().unwrap();
        let mut r = crate::seeds::stream(5, 0);
        for _ in 0..3000 {
            let (s, t) = (r.random::<f64>(), r.random::<f64>());
            assert_eq!(
                loaded.model.zeta(s, t).to_bits(),
                fit.model().zeta(s, t).to_bits()
            );
        }
    }
}
