//! What the viewer remembers between runs: the learner ([`Learner`]), the networks'
//! parameters, the scene and the view. Which parameters a running fit can take is the
//! learner's rule ([`kernel_fit::LiveParams`]), not the viewer's.
//!
//! Settings are stored by eframe (RON). They carry the network parameters and those of the
//! preset they started from as the build that saved them defined it, so a later build whose
//! preset differs (the network under that name changed) replaces the saved parameters instead
//! of running an older learner under the current name. Settings saved before the one learner
//! choice (a "light or network" choice and a preset) load as the learner they ran. Settings
//! that do not decode at all load as defaults.

use kernel_fit::{FitParams, Preset};
use serde::{Deserialize, Serialize};

use crate::learner::Learner;
use crate::scenes::SceneChoice;

/// Key of the settings in eframe's storage.
pub const SETTINGS_KEY: &str = "flatland-viewer-settings";

/// Everything the viewer remembers between runs (eframe persistence).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Which learner runs (settings saved before there was a choice: the light-driven one).
    pub learner: Learner,
    /// The network's parameters: the running network's preset's, possibly changed in the
    /// panel. Under the light-driven learner, which has none, the last network's (choosing a
    /// network starts from its preset again, keeping the run's length and seed).
    pub params: FitParams,
    /// The parameters of the preset `params` started from, as the build that saved these
    /// settings defined it; `None` in settings saved before presets existed. See
    /// [`Settings::upgraded`].
    #[serde(default)]
    learner_defaults: Option<FitParams>,
    /// The preset of settings saved before the one learner choice, when their learner was a
    /// network: which network it was. Read, never written ([`Settings::upgraded`] takes it).
    // Saved as a bare preset (`preset: Paper`), which RON does not read as an `Option`.
    #[serde(default, skip_serializing, deserialize_with = "saved_preset")]
    preset: Option<Preset>,
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
    /// The relit scene's first light wanders along a walk through the free space by itself.
    pub wander: bool,
    /// The moving light's later bounces come from the learned transport (built in the
    /// background, the exact re-solve answering meanwhile), else from the exact re-solve.
    pub transport: bool,
    /// Draw the learned transport's blocks over the kernel plot.
    pub show_blocks: bool,
    /// The kernel plot shows the transport's learned `M₂(s, t)` in place of the exact ζ.
    pub show_m2: bool,
    /// The lit scenes' exposure, in stops: the colour scale's top is divided by 2^exposure.
    pub exposure: f32,
    /// A logarithmic tone scale for the lit scenes (else linear).
    pub tone_log: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            learner: Learner::Light,
            params: FitParams::default(),
            learner_defaults: Some(Preset::Visibility.params()),
            preset: None,
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
            wander: true,
            // The viewer shows the transport at work: it is what makes a light on a big plan
            // move at frame rate (the exact re-solve is the CLI's default and one click away).
            transport: true,
            show_blocks: true,
            show_m2: false,
            exposure: 0.0,
            tone_log: true,
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

    /// These settings brought up to date. A network saved with a preset (before the one
    /// learner choice) is that preset's network. When the parameters' preset as saved differs
    /// from what this build's preset is, they were saved by a build with another learner under
    /// that name, and the learner parameters are replaced by this build's preset
    /// ([`with_preset`]; target cells, seed and budgets are kept). Returns a note when that
    /// happened.
    #[must_use]
    pub fn upgraded(mut self) -> (Settings, Option<String>) {
        if let Some(preset) = self.preset.take()
            && self.learner != Learner::Light
        {
            self.learner = Learner::of_preset(preset);
        }
        let current = match self.learner.preset() {
            Some(preset) => self.learner_defaults == Some(preset.params()),
            // The last network's parameters, whichever network that was.
            None => Preset::ALL
                .iter()
                .any(|p| self.learner_defaults == Some(p.params())),
        };
        if current {
            return (self, None);
        }
        let preset = self.network();
        let note = match self.learner_defaults {
            None => format!(
                "settings from an older viewer: the {}'s parameters restored",
                Learner::of_preset(preset).title()
            ),
            Some(_) => format!(
                "the {} changed since these settings were saved: its parameters were reset",
                Learner::of_preset(preset).title()
            ),
        };
        self.restore_preset();
        (self, Some(note))
    }

    /// The network whose preset the parameters are measured against: the running one, or
    /// under the light-driven learner the visibility network (the parameters' learner part
    /// is replaced whenever a network is chosen).
    fn network(&self) -> Preset {
        self.learner.preset().unwrap_or(Preset::Visibility)
    }

    /// Switches to `learner`: a network with its preset's parameters (target cells, seed and
    /// budgets kept); the light-driven learner keeps the parameters as they are.
    pub fn choose_learner(&mut self, learner: Learner) {
        self.learner = learner;
        if learner.preset().is_some() {
            self.restore_preset();
        }
    }

    /// The network's preset parameters again, with target cells, seed and budgets kept.
    pub fn restore_preset(&mut self) {
        let preset = self.network();
        self.params = with_preset(preset, &self.params);
        self.learner_defaults = Some(preset.params());
    }

    /// Whether the parameters are the network's preset (apart from target cells, seed and
    /// budgets).
    #[must_use]
    pub fn is_preset(&self) -> bool {
        with_preset(self.network(), &self.params) == self.params
    }
}

/// A preset saved by an older viewer, as it was written: bare, not as an `Option`.
fn saved_preset<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Preset>, D::Error> {
    Preset::deserialize(d).map(Some)
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
        settings.choose_learner(Learner::parse("paper").unwrap());
        assert_eq!(settings.learner, Learner::Paper);
        assert_eq!(settings.params.target_cells, 6400, "target cells kept");
        assert!(settings.is_preset());
        assert_eq!(
            settings.params,
            with_preset(Preset::Paper, &settings.params)
        );
        settings.choose_learner(Learner::parse("visibility").unwrap());
        assert_eq!(settings.learner, Learner::Visibility);
        assert_eq!(
            settings.params,
            with_preset(Preset::Visibility, &settings.params)
        );
        settings.params.network.eta = 0.3;
        settings.choose_learner(Learner::parse("light").unwrap());
        assert_eq!(settings.learner, Learner::Light);
        assert_eq!(
            settings.params.network.eta, 0.3,
            "the light-driven learner leaves the network's parameters as they are"
        );
        settings.choose_learner(Learner::Visibility);
        assert!(settings.is_preset(), "a network starts from its preset");
        assert_eq!(settings.params.target_cells, 6400);
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
        settings.choose_learner(Learner::Paper);
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
    fn settings_saved_before_presets_load_with_the_light_learner_and_the_visibility_network() {
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
        assert_eq!(loaded.learner, Learner::Light);
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
        // As if an older build's visibility network had another φ.
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
    fn choosing_a_network_takes_its_preset_and_keeps_the_run() {
        let mut settings = Settings::default();
        settings.params.target_cells = 50;
        settings.params.seed = 4;
        settings.params.eval_every = 500;
        settings.params.network.eta = 0.3;
        settings.choose_learner(Learner::Paper);
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
        settings.choose_learner(Learner::Visibility);
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

    /// The learner as the viewer saved it before the one learner choice: light or a network,
    /// and the network's preset (once called "Default").
    #[derive(Serialize)]
    enum OldChoice {
        Light,
        Network,
    }

    #[derive(Serialize)]
    #[serde(rename_all = "snake_case")]
    enum OldPreset {
        Default,
        Paper,
    }

    #[derive(Serialize)]
    struct ChoiceSettings {
        learner: OldChoice,
        preset: OldPreset,
        params: FitParams,
        learner_defaults: Option<FitParams>,
        step_size: u64,
    }

    #[test]
    fn a_learner_saved_as_a_choice_and_a_preset_loads_under_its_new_name() {
        let saved = |learner, preset, network: Preset| {
            let mut storage = Memory::default();
            let params = FitParams {
                target_cells: 321,
                ..network.params()
            };
            let old = ChoiceSettings {
                learner,
                preset,
                params,
                learner_defaults: Some(network.params()),
                step_size: 7,
            };
            eframe::set_value(&mut storage, SETTINGS_KEY, &old);
            Settings::load(Some(&storage))
        };
        let (paper, note) = saved(OldChoice::Network, OldPreset::Paper, Preset::Paper);
        assert_eq!((paper.learner, note), (Learner::Paper, None));
        assert!(paper.is_preset());
        assert_eq!((paper.params.target_cells, paper.step_size), (321, 7));
        let (visibility, note) = saved(OldChoice::Network, OldPreset::Default, Preset::Visibility);
        assert_eq!((visibility.learner, note), (Learner::Visibility, None));
        let (light, note) = saved(OldChoice::Light, OldPreset::Paper, Preset::Paper);
        assert_eq!((light.learner, note), (Learner::Light, None));
        assert_eq!(
            light.params,
            FitParams {
                target_cells: 321,
                ..FitParams::paper()
            },
            "the paper's parameters kept for when a network is chosen"
        );
        // Saved again and read back: the new form, the same settings.
        let mut storage = Memory::default();
        eframe::set_value(&mut storage, SETTINGS_KEY, &paper);
        assert_eq!(Settings::load(Some(&storage)), (paper, None));
    }
}
