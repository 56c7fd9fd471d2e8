//! What tests and the binary can ask the app: the learner's newest state, the moment shown,
//! the message line.

use std::time::Duration;

use flatland_geom::Scene;
use kernel_fit::{FitParams, StopReason};

use super::ViewerApp;
use crate::settings::Settings;
use crate::timeline::Moment;
use crate::worker::{Lit, LitState};

impl ViewerApp {
    /// The settings (persisted on exit).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }
    /// The settings, to change from code; changed parameters are sent on the next frame.
    pub fn settings_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
    /// Name of the scene being learned ("floorplan", a file name, "… (edited)").
    pub fn scene_label(&self) -> &str {
        &self.scene_label
    }
    /// The scene being learned (not subdivided).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Training steps (rounds of the light-driven learner) in the newest snapshot (0 before
    /// the first one).
    pub fn steps(&self) -> u64 {
        self.status.as_ref().map_or(0, |s| s.growth.steps)
    }
    /// Cells in the newest snapshot.
    pub fn cells(&self) -> usize {
        self.status.as_ref().map_or(0, |s| s.growth.cells.len())
    }
    /// Rays cast, as of the newest snapshot (none by the light-driven learner).
    pub fn rays(&self) -> u64 {
        self.status.as_ref().map_or(0, |s| s.growth.progress.rays())
    }
    /// The learner the last Reset started.
    pub fn fit_learner(&self) -> crate::Learner {
        self.fit_learner
    }
    /// Whether the learner reports that it is training continuously.
    pub fn running(&self) -> bool {
        self.status.as_ref().is_some_and(|s| s.running)
    }
    /// The scene the newest published reference was computed for, if any yet.
    pub fn reference_scene(&self) -> Option<&Scene> {
        self.world.as_deref().map(|w| &w.scene)
    }
    /// Identifier of the newest reference (increases with each scene change).
    pub fn world_id(&self) -> u64 {
        self.world.as_ref().map_or(0, |w| w.id)
    }
    /// The message line (text, whether it is an error).
    pub fn message(&self) -> Option<(&str, bool)> {
        self.message.as_ref().map(|(m, e)| (m.as_str(), *e))
    }
    /// Frames per second over the last second.
    pub fn fps(&self) -> f64 {
        self.fps.now
    }
    /// Final errors of the finished fit (after the refit), once the learner has them.
    pub fn final_errors(&self) -> Option<flatland_solve::Errors> {
        self.status
            .as_ref()
            .and_then(|s| s.summary.as_ref())
            .map(|s| s.errors)
    }
    /// Why the fit stopped, if it did (newest status).
    pub fn stopped(&self) -> Option<StopReason> {
        self.status.as_ref().and_then(|s| s.stopped)
    }
    /// The parameters of the fit the learner is running (newest status).
    pub fn fit_params(&self) -> Option<FitParams> {
        self.status.as_ref().map(|s| s.params)
    }
    /// Faces of the visibility structure that hold a cell (visibility learners, newest status).
    pub fn occupied_faces(&self) -> Option<usize> {
        self.status.as_ref().and_then(|s| s.occupied_faces)
    }
    /// The newest lit scene: B solved with the learned kernel, its errors, the exact B.
    pub fn lit(&self) -> Option<&Lit> {
        match &self.lit {
            Some(LitState::Ready(lit)) => Some(lit),
            _ => None,
        }
    }
    /// Whether the newest status was made after the learner handled every command sent so far
    /// (what a test waits for before it asserts on the learner's state).
    pub fn caught_up(&self) -> bool {
        self.status
            .as_ref()
            .is_some_and(|s| s.handled == self.worker.sent())
    }
    /// The relit scene's lights, where the user sees them.
    pub fn lights(&self) -> &[flatland_geom::PointLight] {
        &self.lamps.lights
    }

    /// The newest B the relighting thread published for the current scene.
    pub fn relit(&self) -> Option<&crate::relit::RelitFrame> {
        self.lamps.frame.as_deref()
    }

    /// Where the lights' marks were drawn in the last frame (in points), by light.
    pub fn light_marks(&self) -> &[egui::Pos2] {
        &self.lamps.marks
    }

    /// Blocks until the relighting thread publishes something this app has not taken yet, or
    /// `timeout` passes (for tests). The UI never calls it.
    pub fn wait_for_relit(&self, timeout: Duration) -> bool {
        self.lamps.handle.wait(timeout)
    }

    /// Blocks until the learner publishes something this app has not taken yet, or `timeout`
    /// passes (for tests: wait on the learner instead of sleeping). The UI never calls it.
    pub fn wait_for_learner(&self, timeout: Duration) -> bool {
        self.worker.wait(timeout)
    }

    // ----- the timeline -----

    /// Whether the plots follow the running learner (not a moment scrubbed to).
    pub fn is_live(&self) -> bool {
        self.cursor.at.is_none()
    }
    /// Whether a replay is running.
    pub fn replaying(&self) -> bool {
        self.cursor.replaying.is_some()
    }
    /// Every moment kept, for scrubbing.
    pub fn timeline(&self) -> &crate::Timeline {
        &self.timeline
    }
    /// Moments of this fit the timeline keeps.
    pub fn moments(&self) -> usize {
        self.timeline.len()
    }
    /// The moment the plots show: the newest when live, else the one scrubbed to.
    pub fn shown(&self) -> Option<&Moment> {
        self.shown_position().and_then(|p| self.timeline.get(p))
    }
    /// The position of the shown moment in the timeline (0: the first).
    pub fn shown_position(&self) -> Option<usize> {
        match self.cursor.at {
            None => self.timeline.len().checked_sub(1),
            Some(at) => self
                .cursor
                .picked
                .and_then(|n| self.timeline.position_of(n))
                .or_else(|| self.timeline.position_at(at)),
        }
    }
}
