//! What the viewer remembers between runs and the two learner presets. Which parameters a
//! running fit can take is the learner's rule ([`kernel_fit::LiveParams`]), not the viewer's.
//!
//! Settings are stored by eframe (RON). They carry the preset the user chose and that preset's
//! parameters as the build that saved them defined it, so a later build whose preset differs
//! (the project's default learner changed) replaces the saved learner instead of running an
//! older learner under the name "Default". Settings that do not decode at all load as defaults.

use kernel_fit::{FitParams, Preset};
use serde::{Deserialize, Serialize};

use crate::scenes::SceneChoice;

/// Key of the settings in eframe's storage.
pub const SETTINGS_KEY: &str = "flatland-viewer-settings";

/// Which learner runs: the light-driven loop ([`flatland_light::LightFit`], what `flatland solve`
/// runs by default) or a network ([`kernel_fit::Fit`], with [`Settings::preset`]'s parameters).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum LearnerChoice {
    /// Rounds of solving and learning where the light flows (docs/ALGORITHM.md §4a).
    #[default]
    Light,
    /// A growing cell structures network trained step by step (the θ-driven or the paper's).
    Network,
}

/// A learner as the controls offer it, and as `--learner` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LearnerName {
    /// The light-driven loop (`light`).
    Light,
    /// The default network, [`Preset::Visibility`] (`theta`).
    Theta,
    /// The paper's network, [`Preset::Paper`] (`paper`).
    Paper,
}

impl std::str::FromStr for LearnerName {
    type Err = String;

    fn from_str(text: &str) -> Result<LearnerName, String> {
        match text {
            "light" => Ok(LearnerName::Light),
            "theta" => Ok(LearnerName::Theta),
            "paper" => Ok(LearnerName::Paper),
            _ => Err(format!(
                "expected a learner: light, theta or paper; got {text:?}"
            )),
        }
    }
}

/// Everything the viewer remembers between runs (eframe persistence).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Which learner runs (settings saved before there was a choice: the light-driven one).
    pub learner: LearnerChoice,
    /// The network learner the parameters started from ([`Preset::Visibility`] or [`Preset::Paper`]).
    pub preset: Preset,
    /// The fit's parameters (the preset's, possibly changed in the panel).
    pub params: FitParams,
    /// `preset`'s parameters as the build that saved these settings defined them; `None` in
    /// settings saved before presets existed. See [`Settings::upgraded`].
    #[serde(default)]
    learner_defaults: Option<FitParams>,
    /// The scene opened at start.
    pub scene: SceneChoice,
    /// Pieces per surface edge (1: the scene as written).
    pub subdivide: usize,
    /// Pace of growth, cells per second of training (the learner's `train` module says why).
    pub growth: f64,
    /// Ignore the pace: grow as fast as the machine can.
    pub unlimited: bool,
    /// Steps done by one press of "Step".
    pub step_size: u64,
    /// Log colour scale for the heatmaps.
    pub log_scale: bool,
    /// Show the cells over the kernel.
    pub show_cells: bool,
    /// Show the network's edges between cells of one face.
    pub show_edges: bool,
    /// Show the training samples, coloured by set.
    pub show_samples: bool,
    /// Solve the radiosity with the learned kernel while it learns, and colour the scene by it.
    pub lit: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            learner: LearnerChoice::Light,
            preset: Preset::Visibility,
            params: FitParams::default(),
            learner_defaults: Some(Preset::Visibility.params()),
            scene: SceneChoice::Bundled(crate::scenes::DEFAULT.into()),
            subdivide: 1,
            // Slow enough to watch: the default 400 cells grow over 20 s.
            growth: 20.0,
            unlimited: false,
            step_size: 1,
            log_scale: true,
            show_cells: true,
            show_edges: true,
            show_samples: false,
            lit: true,
        }
    }
}

impl Settings {
    /// The settings saved in `storage` (key `SETTINGS_KEY`), [`upgraded`](Settings::upgraded),
    /// with a note for the message line when something saved was not kept. Nothing saved, or
    /// settings that no longer decode, give the defaults.
    #[must_use]
    pub fn load(storage: Option<&dyn eframe::Storage>) -> (Settings, Option<String>) {
        let Some(storage) = storage else {
            return (Settings::default(), None);
        };
        if storage.get_string(SETTINGS_KEY).is_none() {
            return (Settings::default(), None);
        }
        match eframe::get_value::<Settings>(storage, SETTINGS_KEY) {
            Some(saved) => saved.upgraded(),
            None => (
                Settings::default(),
                Some("saved settings could not be read (older format): defaults restored".into()),
            ),
        }
    }

    /// These settings with the learner brought up to date: when the saved preset's parameters
    /// differ from what this build's preset is, they were saved by a build with another
    /// learner under that name, and the learner parameters are replaced by this build's
    /// preset ([`with_preset`]; target cells, seed and budgets are kept). Returns a note when
    /// that happened.
    #[must_use]
    pub fn upgraded(mut self) -> (Settings, Option<String>) {
        let current = self.preset.params();
        if self.learner_defaults == Some(current) {
            return (self, None);
        }
        let note = match self.learner_defaults {
            None => format!(
                "settings from an older viewer: learner reset to the {} preset",
                self.preset.name()
            ),
            Some(_) => format!(
                "the {} learner changed since these settings were saved: its parameters were reset",
                self.preset.name()
            ),
        };
        self.choose_preset(self.preset);
        (self, Some(note))
    }

    /// Switches to `preset`: its learner, with target cells, seed and budgets kept.
    pub fn choose_preset(&mut self, preset: Preset) {
        self.preset = preset;
        self.params = with_preset(preset, &self.params);
        self.learner_defaults = Some(preset.params());
    }

    /// Switches to the learner `name` (a network's with its preset's parameters; target cells,
    /// seed and budgets kept).
    pub fn choose_learner(&mut self, name: LearnerName) {
        match name {
            LearnerName::Light => self.learner = LearnerChoice::Light,
            LearnerName::Theta | LearnerName::Paper => {
                self.learner = LearnerChoice::Network;
                self.choose_preset(if name == LearnerName::Theta {
                    Preset::Visibility
                } else {
                    Preset::Paper
                });
            }
        }
    }

    /// Whether the parameters are the preset's (apart from target cells, seed and budgets).
    #[must_use]
    pub fn is_preset(&self) -> bool {
        with_preset(self.preset, &self.params) == self.params
    }
}

/// `preset`'s learner with the run's length and bookkeeping taken from `run`: target cells,
/// seed, step and ray budgets, target error, held-out points and evaluation interval.
#[must_use]
pub fn with_preset(preset: Preset, run: &FitParams) -> FitParams {
    FitParams {
        target_cells: run.target_cells,
        seed: run.seed,
        max_steps: run.max_steps,
        ray_budget: run.ray_budget,
        target_error: run.target_error,
        heldout: run.heldout,
        eval_every: run.eval_every,
        ..preset.params()
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use eframe::Storage as _;
    use kernel_fit::{Gating, Target};
    use sgcs::Insertion;

    use super::*;

    #[test]
    fn a_learner_by_name_is_the_one_the_controls_would_pick() {
        let mut settings = Settings::default();
        settings.params.target_cells = 6400;
        settings.choose_learner("paper".parse().unwrap());
        assert_eq!(settings.learner, LearnerChoice::Network);
        assert_eq!(settings.preset, Preset::Paper);
        assert_eq!(settings.params.target_cells, 6400, "target cells kept");
        assert!(settings.is_preset());
        settings.choose_learner("theta".parse().unwrap());
        assert_eq!(
            (settings.learner, settings.preset),
            (LearnerChoice::Network, Preset::Visibility)
        );
        assert_eq!(
            settings.params,
            with_preset(Preset::Visibility, &settings.params)
        );
        settings.choose_learner("light".parse().unwrap());
        assert_eq!(settings.learner, LearnerChoice::Light);
        assert_eq!(
            settings.preset,
            Preset::Visibility,
            "the network's choice is kept for later"
        );
        let err = "network".parse::<LearnerName>().unwrap_err();
        assert!(
            err.contains("light, theta or paper") && err.contains("\"network\""),
            "{err}"
        );
    }

    /// eframe's storage in memory: the same RON encoding as on disk.
    #[derive(Default)]
    struct Memory(HashMap<String, String>);

    impl eframe::Storage for Memory {
        fn get_string(&self, key: &str) -> Option<String> {
            self.0.get(key).cloned()
        }
        fn set_string(&mut self, key: &str, value: String) {
            self.0.insert(key.to_owned(), value);
        }
        fn remove_string(&mut self, key: &str) {
            self.0.remove(key);
        }
        fn flush(&mut self) {}
    }

    #[test]
    fn settings_round_trip_through_eframe_storage_unchanged() {
        let mut settings = Settings::default();
        settings.choose_preset(Preset::Paper);
        settings.params.target_cells = 77;
        settings.params.network.eta = 0.25;
        settings.lit = false;
        let mut storage = Memory::default();
        eframe::set_value(&mut storage, SETTINGS_KEY, &settings);
        let (loaded, note) = Settings::load(Some(&storage));
        assert_eq!(loaded, settings);
        assert_eq!(note, None);
        assert!(!loaded.is_preset(), "η was changed");
        assert_eq!(Settings::load(None), (Settings::default(), None));
        assert_eq!(
            Settings::load(Some(&Memory::default())),
            (Settings::default(), None)
        );
    }

    /// The settings as the viewer saved them before presets existed: the paper's learner was
    /// the only default.
    #[derive(Serialize)]
    struct OldSettings {
        params: FitParams,
        scene: SceneChoice,
        subdivide: usize,
        speed: f64,
        unlimited: bool,
        step_size: u64,
        log_scale: bool,
        show_cells: bool,
        show_edges: bool,
        show_samples: bool,
    }

    #[test]
    fn settings_saved_before_presets_load_with_the_current_default_learner() {
        let old = OldSettings {
            params: FitParams {
                target_cells: 123,
                seed: 9,
                ..FitParams::paper()
            },
            scene: SceneChoice::Bundled("maze".into()),
            subdivide: 3,
            speed: 500.0,
            unlimited: true,
            step_size: 10,
            log_scale: false,
            show_cells: false,
            show_edges: true,
            show_samples: true,
        };
        let mut storage = Memory::default();
        eframe::set_value(&mut storage, SETTINGS_KEY, &old);
        let (loaded, note) = Settings::load(Some(&storage));
        assert!(note.unwrap().contains("older viewer"));
        assert_eq!(loaded.preset, Preset::Visibility);
        assert_eq!(loaded.params.target, Target::Visibility);
        assert_eq!(loaded.params.gating, Gating::Faces);
        assert_eq!(loaded.params.network.insertion, Insertion::WorstSample);
        assert_eq!(loaded.params.phi, FitParams::default().phi);
        assert!(loaded.is_preset());
        // What is not the learner is kept.
        assert_eq!((loaded.params.target_cells, loaded.params.seed), (123, 9));
        assert_eq!(loaded.scene, SceneChoice::Bundled("maze".into()));
        assert_eq!((loaded.subdivide, loaded.step_size), (3, 10));
        assert!(loaded.unlimited && loaded.show_samples && !loaded.show_cells);
        // Saved again, it loads as it is.
        eframe::set_value(&mut storage, SETTINGS_KEY, &loaded);
        assert_eq!(Settings::load(Some(&storage)), (loaded, None));
    }

    #[test]
    fn a_preset_that_changed_since_saving_is_replaced_and_undecodable_settings_give_defaults() {
        // As if an older build's default learner had another φ.
        let mut settings = Settings {
            learner_defaults: Some(FitParams {
                phi: 0.5,
                ..FitParams::default()
            }),
            ..Settings::default()
        };
        settings.params.phi = 0.5;
        settings.params.target_cells = 42;
        let (upgraded, note) = settings.upgraded();
        assert!(note.unwrap().contains("changed since"));
        assert_eq!(upgraded.params.phi, FitParams::default().phi);
        assert_eq!(upgraded.params.target_cells, 42);

        let mut storage = Memory::default();
        storage.set_string(SETTINGS_KEY, "(params: (target: \"no such target\"".into());
        let (loaded, note) = Settings::load(Some(&storage));
        assert_eq!(loaded, Settings::default());
        assert!(note.unwrap().contains("could not be read"));
    }

    #[test]
    fn choosing_a_preset_takes_its_learner_and_keeps_the_run() {
        let mut settings = Settings::default();
        settings.params.target_cells = 50;
        settings.params.seed = 4;
        settings.params.eval_every = 500;
        settings.params.network.eta = 0.3;
        settings.choose_preset(Preset::Paper);
        assert_eq!(settings.params.target, Target::Zeta);
        assert_eq!(settings.params.network, sgcs::Params::default());
        assert_eq!(
            (
                settings.params.target_cells,
                settings.params.seed,
                settings.params.eval_every
            ),
            (50, 4, 500)
        );
        assert!(settings.is_preset());
        settings.choose_preset(Preset::Visibility);
        assert_eq!(
            settings.params,
            FitParams {
                target_cells: 50,
                seed: 4,
                eval_every: 500,
                ..FitParams::default()
            }
        );
    }
}
