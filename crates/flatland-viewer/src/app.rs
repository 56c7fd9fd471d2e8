//! The app: the state the UI keeps between frames, the top bar and the layout. Settings live in
//! [`crate::settings`], the controls panel in [`controls`], drawing in [`crate::views`], the
//! learner in [`crate::worker`].

mod controls;

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui::{
    CentralPanel, Color32, ColorImage, DragValue, Panel, Pos2, Rect, RichText, ScrollArea,
    TextureHandle, TextureOptions, UiBuilder, Vec2,
};
use flatland_geom::{DVec2, Kernel, PairClass, Scene, bundled};
use flatland_solve::Representation;
use kernel_fit::{FitParams, LearnedKernel, Preset, StopReason};

use crate::colormap::{grid_image, samples_image};
use crate::settings::{SETTINGS_KEY, SceneChoice, Settings};
use crate::views::{self, Hover, LitPaint, PlotFrame, SceneDrag};
use crate::worker::{
    APPROX_RES, Approx, Command, Lit, LitState, REFERENCE_RES, Status, WorkerHandle, World,
    error_text, format_errors,
};
use flatland_lab::colormap::Scale;

/// How [`crate::run_with`] starts the viewer. The default starts learning at once.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Open this scene file instead of the remembered scene.
    pub scene: Option<PathBuf>,
    /// Start paused instead of learning at once.
    pub paused: bool,
    /// Override the target cell count.
    pub target_cells: Option<usize>,
    /// Ignore (but still save) the remembered settings.
    pub fresh_settings: bool,
    /// Print the frame rate and learner speed to stderr every two seconds.
    pub fps_log: bool,
}

/// A texture and the key of the data it was made from: re-uploaded only when the key changes.
struct Cached {
    key: (u64, u64, u64),
    texture: TextureHandle,
}

fn cached_texture(
    ctx: &egui::Context,
    slot: &mut Option<Cached>,
    name: &str,
    key: (u64, u64, u64),
    make: impl FnOnce() -> ColorImage,
) -> egui::TextureId {
    match slot {
        Some(c) if c.key == key => {}
        Some(c) => {
            c.texture.set(make(), TextureOptions::NEAREST);
            c.key = key;
        }
        None => {
            let texture = ctx.load_texture(name, make(), TextureOptions::NEAREST);
            *slot = Some(Cached { key, texture });
        }
    }
    slot.as_ref().map(|c| c.texture.id()).unwrap_or_default()
}

/// Frames per second over the last second.
#[derive(Default)]
struct FpsMeter {
    frames: VecDeque<Instant>,
    last_log: Option<Instant>,
    /// Main-thread CPU seconds of the frames since the last log (eframe's `cpu_usage`).
    cpu: (f64, u32),
}

impl FpsMeter {
    fn tick(&mut self) -> f64 {
        let now = Instant::now();
        self.frames.push_back(now);
        while self
            .frames
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.frames.pop_front();
        }
        match (self.frames.front(), self.frames.len()) {
            (Some(first), n) if n > 1 => {
                (n - 1) as f64 / now.duration_since(*first).as_secs_f64().max(1e-6)
            }
            _ => 0.0,
        }
    }
}

/// The viewer's state. Built by [`ViewerApp::new`] inside eframe, or by
/// [`ViewerApp::headless`] in tests; [`ViewerApp::show`] draws one frame into a [`egui::Ui`].
pub struct ViewerApp {
    settings: Settings,
    /// Parameters of the fit the last Reset started.
    fit_params: FitParams,
    /// Parameters the learner last got: the fit's, with the live part last sent.
    sent_params: FitParams,
    worker: WorkerHandle,
    /// The scene as the user sees and edits it (not subdivided).
    scene: Scene,
    scene_label: String,
    world: Option<Arc<World>>,
    status: Option<Status>,
    approx: Option<Arc<Approx>>,
    lit: Option<LitState>,
    busy: Option<&'static str>,
    message: Option<(String, bool)>,
    path_input: String,
    hover: Hover,
    drag: Option<SceneDrag>,
    kernel_tex: Option<Cached>,
    approx_tex: Option<Cached>,
    error_tex: Option<Cached>,
    samples_tex: Option<Cached>,
    overlay_tex: Option<Cached>,
    scale: Option<(u64, bool, Scale)>,
    fps: FpsMeter,
    fps_now: f64,
    fps_log: bool,
}

impl ViewerApp {
    /// The app inside eframe: settings from eframe's storage (unless `options.fresh_settings`),
    /// the scene from `options.scene`, else the remembered one, else `fig3`.
    pub fn new(cc: &eframe::CreationContext<'_>, options: &Options) -> ViewerApp {
        let (settings, note) = if options.fresh_settings {
            (Settings::default(), None)
        } else {
            Settings::load(cc.storage)
        };
        let mut app = ViewerApp::with_options(cc.egui_ctx.clone(), settings, options);
        if let Some(note) = note
            && app.message.is_none()
        {
            app.message = Some((note, false));
        }
        app
    }

    /// The app as [`ViewerApp::new`] starts it, from given settings: the options applied, and
    /// learning at once unless `options.paused`.
    pub fn with_options(
        ctx: egui::Context,
        mut settings: Settings,
        options: &Options,
    ) -> ViewerApp {
        if let Some(cells) = options.target_cells {
            settings.params.target_cells = cells;
        }
        if let Some(path) = &options.scene {
            settings.scene = SceneChoice::File(path.clone());
        }
        let mut app = ViewerApp::headless(ctx, settings);
        app.fps_log = options.fps_log;
        if !options.paused {
            app.play();
        }
        app
    }

    /// The app without eframe (for tests): starts the learner and a fresh fit of the chosen
    /// scene, paused.
    pub fn headless(ctx: egui::Context, mut settings: Settings) -> ViewerApp {
        let mut message = None;
        let (scene, label) = match load_choice(&settings.scene) {
            Ok(found) => found,
            Err(e) => {
                message = Some((format!("{e}; opened fig3 instead"), true));
                settings.scene = SceneChoice::Bundled(bundled::DEFAULT.into());
                bundled(bundled::DEFAULT).expect("the default scene is bundled")
            }
        };
        if settings.params.validate().is_err() {
            message = Some((
                "remembered parameters were invalid; the preset's restored".into(),
                true,
            ));
            settings.choose_preset(settings.preset);
        }
        let repaint_ctx = ctx.clone();
        let worker = WorkerHandle::spawn(move || repaint_ctx.request_repaint());
        let mut app = ViewerApp {
            fit_params: settings.params,
            sent_params: settings.params,
            worker,
            scene,
            scene_label: label,
            world: None,
            status: None,
            approx: None,
            lit: None,
            busy: Some("starting…"),
            message,
            path_input: match &settings.scene {
                SceneChoice::File(p) => p.display().to_string(),
                SceneChoice::Bundled(_) => String::new(),
            },
            hover: Hover::default(),
            drag: None,
            kernel_tex: None,
            approx_tex: None,
            error_tex: None,
            samples_tex: None,
            overlay_tex: None,
            scale: None,
            fps: FpsMeter::default(),
            fps_now: 0.0,
            fps_log: false,
            settings,
        };
        app.worker.send(Command::Speed(app.speed()));
        app.worker.send(Command::Lit(app.settings.lit));
        app.reset();
        app
    }

    // ----- what tests and the binary can ask -----

    /// The settings (persisted on exit).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }
    /// The settings, to change from code; changed parameters are sent on the next frame.
    pub fn settings_mut(&mut self) -> &mut Settings {
        &mut self.settings
    }
    /// Name of the scene being learned ("fig3", a file name, "… (edited)").
    pub fn scene_label(&self) -> &str {
        &self.scene_label
    }
    /// The scene being learned (not subdivided).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
    /// Training steps in the newest snapshot (0 before the first one).
    pub fn steps(&self) -> u64 {
        self.status.as_ref().map_or(0, |s| s.snapshot.steps)
    }
    /// Cells in the newest snapshot.
    pub fn cells(&self) -> usize {
        self.status.as_ref().map_or(0, |s| s.snapshot.cells.len())
    }
    /// Rays cast, as of the newest snapshot.
    pub fn rays(&self) -> u64 {
        self.status.as_ref().map_or(0, |s| s.snapshot.rays)
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
        self.fps_now
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
    /// Why there is no lit scene, when it failed.
    pub fn lit_failure(&self) -> Option<&str> {
        match &self.lit {
            Some(LitState::Failed(why)) => Some(why),
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
    /// Blocks until the learner publishes something this app has not taken yet, or `timeout`
    /// passes (for tests: wait on the learner instead of sleeping). The UI never calls it.
    pub fn wait_for_learner(&self, timeout: Duration) -> bool {
        self.worker.wait(timeout)
    }

    // ----- actions -----

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
    /// Starts a fresh fit of the current scene with the current parameters, seed, subdivision.
    pub fn reset(&mut self) {
        self.status = None;
        self.approx = None;
        self.lit = None;
        self.fit_params = self.settings.params;
        self.sent_params = self.settings.params;
        self.worker.send(Command::Reset {
            scene: self.scene.clone(),
            subdivide: self.settings.subdivide.max(1),
            params: self.settings.params,
        });
        self.busy = Some("computing the reference kernel…");
    }

    /// Switches to `preset`'s learner (target cells and seed kept) and starts a fresh fit.
    pub fn choose_preset(&mut self, preset: Preset) {
        self.settings.choose_preset(preset);
        self.reset();
    }

    /// Switches to a bundled scene (a fresh fit).
    pub fn open_bundled(&mut self, name: &str) {
        match bundled(name) {
            Ok((scene, label)) => {
                self.settings.scene = SceneChoice::Bundled(name.into());
                self.set_scene(scene, label);
            }
            Err(e) => self.message = Some((e, true)),
        }
    }

    /// Opens a scene file (a fresh fit). A file that does not load leaves the current scene as it
    /// is and says why in the message line.
    pub fn open_file(&mut self, path: &Path) {
        match Scene::load(path) {
            Ok(scene) => {
                self.settings.scene = SceneChoice::File(path.to_path_buf());
                self.path_input = path.display().to_string();
                let label = file_label(path);
                self.set_scene(scene, label);
            }
            Err(e) => {
                self.message = Some((
                    format!(
                        "could not open {}: {e} (kept {})",
                        path.display(),
                        self.scene_label
                    ),
                    true,
                ));
            }
        }
    }

    fn set_scene(&mut self, scene: Scene, label: String) {
        self.scene = scene;
        self.scene_label = label;
        self.message = None;
        self.hover = Hover::default();
        self.reset();
    }

    /// Replaces the scene by an edited one and keeps learning from the current network
    /// (the representation stays adaptive): the learner recomputes the reference and calls
    /// `Fit::set_kernel`.
    pub fn edit_scene(&mut self, scene: Scene) {
        self.scene = scene;
        if !self.scene_label.ends_with("(edited)") {
            self.scene_label.push_str(" (edited)");
        }
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

    fn speed(&self) -> Option<f64> {
        (!self.settings.unlimited).then_some(self.settings.speed.max(1.0))
    }

    /// Takes what the learner published.
    fn poll(&mut self) {
        let Some(mail) = self.worker.take() else {
            return;
        };
        if let Some(world) = mail.world {
            self.world = Some(world);
            self.approx = None;
        }
        if let Some(status) = mail.status {
            self.status = Some(status);
        }
        if let Some(approx) = mail.approx {
            self.approx = Some(approx);
        }
        if let Some(lit) = mail.lit {
            self.lit = Some(lit);
        }
        if let Some(e) = mail.error {
            self.message = Some((e, true));
        }
        // The learner's own state; before its first reference, say that it is starting.
        self.busy = mail
            .busy
            .or_else(|| self.world.is_none().then_some("starting…"));
    }

    /// Sends changed parameters (when valid) to the learner: a change of the live part
    /// ([`kernel_fit::LiveParams`]) to the running fit, any other as a new fit, once the
    /// control is let go (a drag does not start a fit per frame).
    fn sync_params(&mut self, ctx: &egui::Context) {
        let wanted = self.settings.params;
        if wanted == self.sent_params {
            return;
        }
        if let Err(e) = wanted.validate() {
            self.message = Some((e.to_string(), true));
            return;
        }
        if self
            .message
            .as_ref()
            .is_some_and(|(m, _)| m.starts_with("parameter"))
        {
            self.message = None;
        }
        if self.fit_params.with_live(wanted.live()) == wanted {
            self.sent_params = wanted;
            self.worker.send(Command::Params(wanted.live()));
        } else if ctx.egui_is_using_pointer() {
            ctx.request_repaint();
        } else {
            self.reset();
        }
    }

    /// One frame.
    pub fn show(&mut self, ui: &mut egui::Ui) {
        self.poll();
        self.fps_now = self.fps.tick();
        self.log_fps();
        let dropped: Vec<PathBuf> = ui.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .filter(|p| !p.as_os_str().is_empty())
                .collect()
        });
        if let Some(path) = dropped.first() {
            self.open_file(path);
        }
        Panel::top("bar").show(ui, |ui| self.top_bar(ui));
        Panel::left("controls")
            .resizable(false)
            .exact_size(262.0)
            .show(ui, |ui| {
                ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        CentralPanel::default().show(ui, |ui| self.main_area(ui));
        self.sync_params(ui.ctx());
        if self.running() || self.busy.is_some() {
            ui.ctx().request_repaint_after(Duration::from_millis(16));
        }
    }

    fn log_fps(&mut self) {
        if !self.fps_log {
            return;
        }
        let now = Instant::now();
        let last = *self.fps.last_log.get_or_insert(now);
        if now.duration_since(last) >= Duration::from_secs(2) {
            self.fps.last_log = Some(now);
            let rate = self.status.as_ref().map_or(0.0, |s| s.steps_per_s);
            let (cpu, n) = std::mem::take(&mut self.fps.cpu);
            eprintln!(
                "fps {:.1}  ui-thread {:.1} ms/frame  steps/s {:.0}  steps {}  cells {}  samples {}",
                self.fps_now,
                1e3 * cpu / f64::from(n.max(1)),
                rate,
                self.steps(),
                self.cells(),
                self.status.as_ref().map_or(0, |s| s.snapshot.samples.len())
            );
        }
    }

    /// The top bar's numbers: the learner, its progress, the held-out error of ζ and (with the
    /// lit scene) of the solved `B − E`, its speed.
    fn stats_text(&self, st: &Status, heldout_defined: bool) -> String {
        let snap = &st.snapshot;
        let mut parts = vec![
            learner_name(&st.params),
            format!("steps {}", snap.steps),
            format!("rays {}", snap.rays),
            format!(
                "cells {}/{}",
                snap.cells.len(),
                self.sent_params.target_cells
            ),
        ];
        if let Some(faces) = st.occupied_faces {
            parts.push(format!("in {faces} faces"));
        }
        parts.push(format!(
            "samples {} in {} sets",
            snap.samples.len(),
            snap.sets
        ));
        let err = snap.history.last().map_or("–".into(), |h| {
            error_text(h.rel_l2_heldout, heldout_defined)
        });
        parts.push(format!("ζ held out {err}"));
        if let Some(l) = self.lit() {
            let err = error_text(l.solve.errors.rel_l2_reflected, true);
            parts.push(format!("solved B−E {err}"));
        }
        if st.steps_per_s > 0.0 {
            parts.push(format!("{:.0} steps/s", st.steps_per_s));
        }
        parts.join("  ")
    }

    fn top_bar(&mut self, ui: &mut egui::Ui) {
        let defined = self.world.as_ref().map_or([true; 2], |w| w.defined);
        ui.horizontal(|ui| {
            if self.running() {
                if ui.button("Pause").clicked() {
                    self.pause();
                }
            } else if ui.button("Play").clicked() {
                self.play();
            }
            if ui
                .button("Step")
                .on_hover_text("train `step size` steps, then pause")
                .clicked()
            {
                self.step();
            }
            let times = ui.label("×");
            ui.add(DragValue::new(&mut self.settings.step_size).range(1..=1_000_000))
                .labelled_by(times.id)
                .on_hover_text("step size: steps per press of Step");
            if ui
                .button("Reset")
                .on_hover_text("a fresh fit (seed, |S₀|, subdivision apply)")
                .clicked()
            {
                self.reset();
            }
            ui.separator();
            let stats = self
                .status
                .as_ref()
                .map(|st| self.stats_text(st, defined[1]))
                .unwrap_or_default();
            ui.label(RichText::new(stats).monospace().size(11.0));
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                ui.label(RichText::new(format!("{:.0} fps", self.fps_now)).weak());
            });
        });
        let line = if let Some(b) = self.busy {
            Some((b.to_string(), false))
        } else if let Some((m, e)) = &self.message {
            Some((m.clone(), *e))
        } else if let Some(st) = &self.status {
            st.stopped.map(|r| {
                let errs = st
                    .summary
                    .as_ref()
                    .map(|s| {
                        format!(
                            "; final rel. L2 of ζ: {}",
                            format_errors(&s.errors, defined)
                        )
                    })
                    .unwrap_or_default();
                let hint = if r == StopReason::TargetCells {
                    "; raise the target cells and press Play to go on"
                } else {
                    ""
                };
                (format!("stopped: {}{errs}{hint}", stop_text(r)), false)
            })
        } else {
            None
        };
        // The line is always there (empty if nothing to say) so the layout never jumps under
        // the pointer, e.g. while an end point is being dragged.
        let (text, is_error) = line.unwrap_or_default();
        ui.horizontal(|ui| {
            ui.set_min_height(ui.spacing().interact_size.y);
            let color = if is_error {
                Color32::from_rgb(255, 110, 90)
            } else {
                ui.visuals().weak_text_color()
            };
            ui.label(RichText::new(text).color(color));
            if is_error && ui.small_button("dismiss").clicked() {
                self.message = None;
            }
        });
    }

    fn main_area(&mut self, ui: &mut egui::Ui) {
        let full = ui.available_rect_before_wrap();
        let Some(world) = self.world.clone() else {
            ui.centered_and_justified(|ui| {
                ui.label(self.busy.unwrap_or("waiting for the learner…"))
            });
            return;
        };
        let layout = Layout::of(full, self.settings.lit);
        let status = self.status.clone().filter(|s| s.world == world.id);
        let approx = self.approx.clone().filter(|a| a.world == world.id);
        self.kernel_panels(ui, &layout, &world, status.as_ref(), approx.as_deref());

        // The lit scene, when there is one for the scene as it is (not while it is edited).
        let lit_state = self.lit.clone();
        let lit = match &lit_state {
            Some(LitState::Ready(l)) if l.setup.world == world.id && self.scene == world.scene => {
                Some(l.as_ref())
            }
            _ => None,
        };
        self.scene_panels(ui, &layout, &world, lit, lit_state.as_ref());
        ui.scope_builder(UiBuilder::new().max_rect(layout.curves), |ui| {
            views::curves(ui, status.as_ref().map(|s| s.snapshot.as_ref()), lit);
        });
    }

    /// The textures of the three heatmaps and the overlay, re-made only when their data
    /// changed; one colour scale, fitted to the reference, for all three heatmaps.
    fn heatmap_textures(
        &mut self,
        ctx: &egui::Context,
        world: &World,
        status: Option<&Status>,
        approx: Option<&Approx>,
        overlay_side: usize,
    ) -> Heatmaps {
        let log = self.settings.log_scale;
        let scale = match self.scale {
            Some((id, l, s)) if id == world.id && l == log => s,
            _ => {
                let s = Scale::fit(world.reference.grid(), log);
                self.scale = Some((world.id, log, s));
                s
            }
        };
        let key = (world.id, u64::from(log), 0);
        let kernel = cached_texture(ctx, &mut self.kernel_tex, "kernel", key, || {
            grid_image(world.reference.grid(), REFERENCE_RES, scale)
        });
        let (approx_tex, error_tex) = match approx {
            Some(a) => {
                let key = (world.id, u64::from(log), a.steps + 1);
                let at = cached_texture(ctx, &mut self.approx_tex, "approx", key, || {
                    grid_image(&a.values, APPROX_RES, scale)
                });
                let et = cached_texture(ctx, &mut self.error_tex, "error", key, || {
                    let err: Vec<f64> = a
                        .values
                        .iter()
                        .zip(&world.exact_small)
                        .map(|(x, y)| (x - y).abs())
                        .collect();
                    grid_image(&err, APPROX_RES, scale)
                });
                (Some(at), Some(et))
            }
            None => (None, None),
        };
        let samples = status.filter(|_| self.settings.show_samples).map(|st| {
            let snap = &st.snapshot;
            let key = (world.id, snap.samples.len() as u64, snap.sets as u64);
            cached_texture(ctx, &mut self.samples_tex, "samples", key, || {
                samples_image(&snap.samples, 2 * REFERENCE_RES)
            })
        });
        let ppp = ctx.pixels_per_point();
        let (cells, edges) = (self.settings.show_cells, self.settings.show_edges);
        let overlay = status.map(|st| {
            let snap = &st.snapshot;
            let key = (
                Arc::as_ptr(snap) as u64,
                overlay_side as u64,
                u64::from(cells) | u64::from(edges) << 1 | u64::from(ppp.to_bits()) << 2,
            );
            cached_texture(ctx, &mut self.overlay_tex, "overlay", key, || {
                views::overlay_image(overlay_side, ppp, snap, cells, edges)
            })
        });
        Heatmaps {
            scale,
            kernel,
            approx: approx_tex,
            error: error_tex,
            samples,
            overlay,
        }
    }

    /// The exact ζ with the cells over it, the learned ζ and the error; the readout of the
    /// hovered `(s, t)`.
    fn kernel_panels(
        &mut self,
        ui: &mut egui::Ui,
        layout: &Layout,
        world: &World,
        status: Option<&Status>,
        approx: Option<&Approx>,
    ) {
        let ctx = ui.ctx().clone();
        let mut kernel_frame = PlotFrame::new(layout.kernel, true);
        let side =
            ((kernel_frame.plot.width() * ctx.pixels_per_point()).round() as usize).clamp(16, 2048);
        let textures = self.heatmap_textures(&ctx, world, status, approx, side);
        kernel_frame.scale = Some(textures.scale);
        let overlay = views::Overlay {
            cells: textures.overlay,
            samples: textures.samples,
        };
        let learned_title = match status.map(|s| s.params.target) {
            Some(kernel_fit::Target::Visibility) => "learned ζ (unoccluded ζ × V)",
            _ => "learned ζ (SGCS)",
        };
        let panels = [
            (
                kernel_frame,
                "ζ(s, t) exact, with the cells",
                Some(textures.kernel),
                overlay,
            ),
            (
                PlotFrame::new(layout.approx, false),
                learned_title,
                textures.approx,
                views::Overlay::none(),
            ),
            (
                PlotFrame::new(layout.error, false),
                "|learned − exact|",
                textures.error,
                views::Overlay::none(),
            ),
        ];
        let mut hovered = None;
        for (frame, title, texture, overlay) in &panels {
            let st = views::kernel_plot(
                ui,
                frame,
                title,
                *texture,
                &world.scene,
                overlay,
                &self.hover,
            );
            hovered = hovered.or(st);
        }
        self.hover.st = hovered;
        if let Some([s, t]) = self.hover.st
            && let Some(pointer) = ui.input(|i| i.pointer.hover_pos())
        {
            let text = readout_text(&world.kernel, approx.map(|a| &a.model), s, t);
            views::readout_box(&ctx, pointer, &text);
        }
    }

    /// The scene (lit by the learned B when `lit` is given; hovered ray, hovered s, dragged end
    /// points) and, with the lit view on, the scene lit by the exact kernel.
    fn scene_panels(
        &mut self,
        ui: &mut egui::Ui,
        layout: &Layout,
        world: &World,
        lit: Option<&Lit>,
        lit_state: Option<&LitState>,
    ) {
        let learned_paint = lit.map(|l| LitPaint {
            mesh: &l.setup.mesh,
            b: &l.solve.b,
            top: l.setup.top,
        });
        let scene_title = match lit {
            Some(l) => format!(
                "lit by the learned kernel: B − E rel. L2 {} ({} el., {:.0} ms)",
                error_text(l.solve.errors.rel_l2_reflected, true),
                l.setup.mesh.len(),
                1e3 * l.solve.solve_s
            ),
            None => "scene".to_owned(),
        };
        let scene_out = views::scene_view(
            ui,
            &views::SceneFrame {
                rect: layout.scene,
                title: &scene_title,
                world,
                lit: learned_paint.as_ref(),
            },
            &self.scene,
            &self.hover,
            &mut self.drag,
        );
        self.hover.scene_s = scene_out.hovered_s;
        if let Some((from, to)) = scene_out.moved {
            self.move_point(from, to);
        }
        let Some(rect) = layout.exact else {
            return;
        };
        let title = "lit by the exact kernel";
        match (lit, lit_state) {
            (Some(l), _) => {
                let paint = LitPaint {
                    mesh: &l.setup.mesh,
                    b: &l.setup.exact,
                    top: l.setup.top,
                };
                views::lit_view(ui, rect, title, &world.scene, &paint);
            }
            (None, Some(LitState::Failed(why))) => views::placeholder(ui, rect, title, why),
            (None, Some(LitState::Off)) => {
                views::placeholder(ui, rect, title, "the lit scene is off (View)");
            }
            (None, Some(LitState::Pending(what))) => views::placeholder(ui, rect, title, what),
            _ => views::placeholder(ui, rect, title, "solving the exact radiosity…"),
        }
    }
}

/// The textures of one frame's heatmaps and overlays, and the heatmaps' colour scale.
struct Heatmaps {
    scale: Scale,
    kernel: egui::TextureId,
    approx: Option<egui::TextureId>,
    error: Option<egui::TextureId>,
    samples: Option<egui::TextureId>,
    overlay: Option<egui::TextureId>,
}

/// Where the panels go: the kernel plot (a big square), ζ̃ and the error beside it, the scene
/// (and the exact lit scene) on the right, the curves below.
struct Layout {
    kernel: Rect,
    approx: Rect,
    error: Rect,
    scene: Rect,
    exact: Option<Rect>,
    curves: Rect,
}

impl Layout {
    fn of(full: Rect, lit: bool) -> Layout {
        let gap = 8.0;
        let curves_h = (full.height() * 0.32).clamp(150.0, 300.0);
        let top_h = full.height() - curves_h - gap;
        let big = top_h.min(full.width() * 0.42);
        let small = (big - views::TITLE_H) / 2.0 + views::TITLE_H / 2.0;
        let kernel = Rect::from_min_size(full.min, Vec2::splat(big));
        let approx =
            Rect::from_min_size(kernel.right_top() + Vec2::new(gap, 0.0), Vec2::splat(small));
        let error = Rect::from_min_size(
            approx.left_bottom() + Vec2::new(0.0, big - 2.0 * small),
            Vec2::splat(small),
        );
        let right = Rect::from_min_max(
            Pos2::new(approx.right() + gap, full.top()),
            Pos2::new(full.right(), full.top() + top_h),
        );
        let (scene, exact) = if !lit {
            (right, None)
        } else if right.width() >= 1.6 * right.height() {
            // Wide: side by side.
            let mid = right.center().x;
            (
                Rect::from_min_max(right.min, Pos2::new(mid - gap / 2.0, right.bottom())),
                Some(Rect::from_min_max(
                    Pos2::new(mid + gap / 2.0, right.top()),
                    right.max,
                )),
            )
        } else {
            let split = right.top() + right.height() * 0.56;
            (
                Rect::from_min_max(right.min, Pos2::new(right.right(), split - gap / 2.0)),
                Some(Rect::from_min_max(
                    Pos2::new(right.left(), split + gap / 2.0),
                    right.max,
                )),
            )
        };
        let curves = Rect::from_min_max(Pos2::new(full.left(), full.top() + top_h + gap), full.max);
        Layout {
            kernel,
            approx,
            error,
            scene,
            exact,
            curves,
        }
    }
}

/// What the pointer at `(s, t)` shows: the two points, G, V, k, ζ; the learned ζ̃; for a
/// visibility model, Ṽ and how it is decided there (geometry, or the cells of the face).
fn readout_text(kernel: &Kernel, model: Option<&LearnedKernel>, s: f64, t: f64) -> String {
    let k = kernel.eval(s, t);
    let mut text = format!(
        "s {s:.4} (edge {}), t {t:.4} (edge {})\nG {:.4}  V {}  k {:.5}\nζ {:.5}  learned {}",
        k.x.edge,
        k.y.edge,
        k.geometry,
        if k.visible {
            "1 (visible)"
        } else {
            "0 (blocked)"
        },
        k.k,
        k.zeta,
        model.map_or("–".into(), |m| format!("{:.5}", m.zeta(s, t))),
    );
    let Some(model) = model.filter(|m| m.target() == kernel_fit::Target::Visibility) else {
        return text;
    };
    let u = kernel.unoccluded(s, t);
    let line = if u.k <= 0.0 {
        "learned V –: the points do not face each other".to_owned()
    } else {
        match kernel.pair_class(u.sender, u.receiver) {
            PairClass::Zero => "learned V –: no transfer between these edges".to_owned(),
            PairClass::Visible => "learned V 1: geometry says visible (no cell, no ray)".to_owned(),
            PairClass::Hidden => "learned V 0: geometry says blocked (no cell, no ray)".to_owned(),
            PairClass::Varies => {
                let v = model.zeta(s, t) / u.zeta;
                match model.face_cells(s, t).map_or(0, |c| c.len()) {
                    0 => {
                        format!("learned V {v:.3}: no cell in this face (its pair's cells answer)")
                    }
                    1 => format!("learned V {v:.3}: from the 1 cell of this face"),
                    n => format!("learned V {v:.3}: from the {n} cells of this face"),
                }
            }
        }
    };
    text.push('\n');
    text.push_str(&line);
    text
}

/// A stop reason in words.
#[must_use]
pub fn stop_text(reason: StopReason) -> &'static str {
    match reason {
        StopReason::TargetCells => "target cell count reached",
        StopReason::TargetError => "target error reached",
        StopReason::RayBudget => "ray budget spent",
        StopReason::StepBudget => "step budget spent",
        StopReason::Interrupted => "interrupted",
        StopReason::Exact => {
            "exact: geometry decides every visibility in this scene, there is nothing to learn"
        }
        StopReason::Converged => {
            "converged: every sample is predicted exactly and a θ scan found nothing left to learn"
        }
    }
}

/// The learner a fit runs, in a few words.
fn learner_name(p: &FitParams) -> String {
    let preset = Preset::ALL
        .into_iter()
        .find(|&preset| crate::settings::with_preset(preset, p) == *p);
    let target = match p.target {
        kernel_fit::Target::Visibility => "V",
        kernel_fit::Target::Zeta => "ζ",
        kernel_fit::Target::FactoredEmission => "k",
    };
    match preset {
        Some(preset) => format!("{} ({target})", preset.name()),
        None => format!("custom ({target})"),
    }
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        if let Some(cpu) = frame.info().cpu_usage {
            self.fps.cpu.0 += f64::from(cpu);
            self.fps.cpu.1 += 1;
        }
        self.show(ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, SETTINGS_KEY, &self.settings);
    }
}

/// A bundled scene by name, with its label.
fn bundled(name: &str) -> Result<(Scene, String), String> {
    let scene = bundled::scene(name).map_err(|e| e.to_string())?;
    Ok((scene, name.to_string()))
}

fn file_label(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

fn load_choice(choice: &SceneChoice) -> Result<(Scene, String), String> {
    match choice {
        SceneChoice::Bundled(name) => bundled(name),
        SceneChoice::File(path) => Scene::load(path)
            .map(|s| (s, file_label(path)))
            .map_err(|e| format!("could not open {}: {e}", path.display())),
    }
}
