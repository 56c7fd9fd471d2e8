//! What the buttons, tests and the binary can do: run the learner, start fits, open and edit
//! scenes, move through the timeline.

use std::path::Path;
use std::time::Duration;

use flatland_geom::{DVec2, Scene};

use super::ViewerApp;
use crate::learner::Learner;
use crate::scenes;
use crate::scenes::SceneChoice;
use crate::views::{self, Hover};
use crate::worker::Command;

impl ViewerApp {
    /// Starts continuous training.
    pub fn play(&mut self) {
        self.worker.send(Command::Play);
    }
    /// Pauses training.
    pub fn pause(&mut self) {
        self.worker.send(Command::Pause);
    }
    /// Asks the learner for a status made after every command sent so far ([`Self::caught_up`]).
    pub fn sync(&mut self) {
        self.worker.send(Command::Sync);
    }
    /// Trains `settings.step_size` steps.
    pub fn step(&mut self) {
        self.worker
            .send(Command::Step(self.settings.step_size.max(1)));
    }
    /// Tells the learner the pace of growth in the settings.
    pub(super) fn send_pace(&mut self) {
        self.worker.send(Command::Pace(self.pace()));
    }

    /// Starts the chosen learner afresh on the current scene with the current parameters,
    /// seed, subdivision.
    pub fn reset(&mut self) {
        self.status = None;
        self.approx = None;
        self.lit = None;
        self.timeline.clear();
        self.go_live();
        self.fit_learner = self.settings.learner;
        self.fit_params = self.settings.params;
        self.sent_params = self.settings.params;
        self.worker.send(Command::Reset {
            scene: self.scene.clone(),
            subdivide: self.settings.subdivide.max(1),
            learner: self.settings.learner,
            params: self.settings.params,
        });
        self.fit_since = self.worker.sent();
        self.busy = Some("computing the reference kernel…");
    }

    /// Switches to `learner` (a network with its preset's parameters, target cells and seed
    /// kept) and starts it afresh.
    pub fn choose_learner(&mut self, learner: Learner) {
        self.settings.choose_learner(learner);
        self.reset();
    }

    /// Switches to a scene the viewer offers by name (a fresh fit).
    pub fn open_bundled(&mut self, name: &str) {
        let choice = SceneChoice::Bundled(name.into());
        match scenes::load(&choice) {
            Ok(opened) => {
                self.settings.scene = choice;
                self.set_scene(opened);
            }
            Err(e) => self.message = Some((e, true)),
        }
    }

    /// Opens a scene file, `.ron`/`.json` or an SVG drawing (a fresh fit); a drawing's import
    /// warnings go to the message line. A file that does not load leaves the current scene as
    /// it is and says why in the message line.
    pub fn open_file(&mut self, path: &Path) {
        match scenes::open_file(path) {
            Ok(opened) => {
                self.settings.scene = SceneChoice::File(path.to_path_buf());
                self.path_input = path.display().to_string();
                self.set_scene(opened);
            }
            Err(e) => {
                self.message = Some((format!("{e} (kept {})", self.scene_label), true));
            }
        }
    }

    fn set_scene(&mut self, opened: scenes::Opened) {
        self.message = scenes::warnings_note(&opened).map(|note| (note, false));
        self.scene = opened.scene;
        self.scene_label = opened.label;
        self.scene_warnings = opened.warnings;
        self.hover = Hover::default();
        self.reset();
    }

    /// Replaces the scene by an edited one and keeps learning from the current network
    /// (the representation stays adaptive): the learner recomputes the reference and calls
    /// `Fit::set_kernel`. The plots return to the live learner.
    pub fn edit_scene(&mut self, scene: Scene) {
        self.scene = scene;
        if !self.scene_label.ends_with("(edited)") {
            self.scene_label.push_str(" (edited)");
        }
        self.go_live();
        self.worker.send(Command::Edit {
            scene: self.scene.clone(),
            subdivide: self.settings.subdivide.max(1),
        });
        self.busy = Some("computing the reference kernel…");
    }

    /// Moves every end point at `from` to `to` (so closed rooms stay closed), through
    /// `Scene::with_edge`; an invalid result (e.g. a zero-length edge) keeps the scene.
    pub fn move_point(&mut self, from: DVec2, to: DVec2) {
        match views::moved_scene(&self.scene, from, to) {
            Ok(scene) => self.edit_scene(scene),
            Err(e) => self.message = Some((format!("cannot move that point: {e}"), true)),
        }
    }

    // ----- the timeline -----

    /// Shows the kept moment at `position` (0: the first), and stops a replay.
    pub fn scrub_to(&mut self, position: usize) {
        let last = self.timeline.len().saturating_sub(1);
        let position = position.min(last);
        if let Some(m) = self.timeline.get(position) {
            self.cursor.at = Some(m.at());
            self.cursor.picked = self.timeline.number(position);
        }
        self.cursor.replaying = None;
    }

    /// Follows the running learner again.
    pub fn go_live(&mut self) {
        self.cursor.at = None;
        self.cursor.picked = None;
        self.cursor.replaying = None;
    }

    /// Replays the run from the moment shown (from the start when live) at `speed` times the
    /// speed it was recorded at; reaching the newest moment goes live.
    pub fn replay(&mut self, speed: f32) {
        self.cursor.speed = speed;
        if self.cursor.at.is_none() {
            self.cursor.at = Some(Duration::ZERO);
        }
        self.cursor.replaying = Some(speed);
    }

    /// Stops a replay where it is.
    pub fn stop_replay(&mut self) {
        self.cursor.replaying = None;
    }

    /// Moves a running replay on by this frame's time.
    pub(super) fn advance_replay(&mut self, ctx: &egui::Context) {
        let (Some(speed), Some(at)) = (self.cursor.replaying, self.cursor.at) else {
            return;
        };
        let dt = ctx.input(|i| i.stable_dt).min(0.1);
        let next = at + Duration::from_secs_f64(f64::from(dt * speed));
        match self.timeline.latest() {
            Some(latest) if next < latest.at() => {
                self.cursor.at = Some(next);
                self.cursor.picked = None;
            }
            _ => self.go_live(),
        }
    }
}
