//! The app: persisted settings, the state the UI keeps between frames, and the layout.
//! Drawing of the plots and the scene lives in [`crate::views`]; the learner in [`crate::worker`].

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui::{
    Align2, CentralPanel, Color32, ColorImage, DragValue, FontId, Panel, Pos2, Rect, RichText,
    ScrollArea, TextureHandle, TextureOptions, UiBuilder, Vec2,
};
use flatland_geom::{DVec2, Scene};
use kernel_fit::{Approximation, FitParams};
use serde::{Deserialize, Serialize};
use sgcs::{InsertRule, OutputRule};

use crate::BUNDLED_SCENES;
use crate::colormap::{Scale, grid_image, samples_image};
use crate::views::{self, Hover, PlotFrame, SceneDrag};
use crate::worker::{
    APPROX_RES, Approx, Command, REFERENCE_RES, Status, WorkerHandle, World, error_text,
    format_errors,
};

/// Key of the settings in eframe's storage.
const SETTINGS_KEY: &str = "flatland-viewer-settings";

/// Which scene to open: a bundled one by name or a file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum SceneChoice {
    /// One of [`BUNDLED_SCENES`].
    Bundled(String),
    /// A scene file (`.ron` or `.json`).
    File(PathBuf),
}

/// Everything the viewer remembers between runs (eframe persistence).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// The fit's parameters (SPEC §3–4, target cells, seed, …).
    pub params: FitParams,
    /// The scene opened at start.
    pub scene: SceneChoice,
    /// Pieces per surface edge (1: the scene as written).
    pub subdivide: usize,
    /// Training speed limit, steps per second.
    pub speed: f64,
    /// Ignore the speed limit.
    pub unlimited: bool,
    /// Steps done by one press of "Step".
    pub step_size: u64,
    /// Log colour scale for the heatmaps.
    pub log_scale: bool,
    /// Show the cells over the kernel.
    pub show_cells: bool,
    /// Show the network's edges between cells.
    pub show_edges: bool,
    /// Show the training samples, coloured by set.
    pub show_samples: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            params: FitParams::default(),
            scene: SceneChoice::Bundled("fig3".into()),
            subdivide: 1,
            // Slow enough to watch: the default learner is exact on fig3 after about 20 000
            // steps (a few seconds), the paper's network reaches 400 cells in 20 s.
            speed: 6_000.0,
            unlimited: false,
            step_size: 1,
            log_scale: true,
            show_cells: true,
            show_edges: true,
            show_samples: false,
        }
    }
}

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
    /// Parameters last sent to the learner.
    sent_params: FitParams,
    worker: WorkerHandle,
    /// The scene as the user sees and edits it (not subdivided).
    scene: Scene,
    scene_label: String,
    world: Option<Arc<World>>,
    status: Option<Status>,
    approx: Option<Arc<Approx>>,
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
        let settings: Settings = if options.fresh_settings {
            Settings::default()
        } else {
            cc.storage
                .and_then(|s| eframe::get_value(s, SETTINGS_KEY))
                .unwrap_or_default()
        };
        ViewerApp::with_options(cc.egui_ctx.clone(), settings, options)
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
                settings.scene = SceneChoice::Bundled("fig3".into());
                bundled("fig3").expect("fig3 is bundled")
            }
        };
        if settings.params.validate().is_err() {
            message = Some((
                "remembered parameters were invalid; defaults restored".into(),
                true,
            ));
            settings.params = FitParams::default();
        }
        let repaint_ctx = ctx.clone();
        let worker = WorkerHandle::spawn(move || repaint_ctx.request_repaint());
        let mut app = ViewerApp {
            sent_params: settings.params,
            worker,
            scene,
            scene_label: label,
            world: None,
            status: None,
            approx: None,
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
    pub fn final_errors(&self) -> Option<kernel_fit::Errors> {
        self.status
            .as_ref()
            .and_then(|s| s.summary.as_ref())
            .map(|s| s.errors)
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
        self.sent_params = self.settings.params;
        self.worker.send(Command::Reset {
            scene: self.scene.clone(),
            subdivide: self.settings.subdivide.max(1),
            params: self.settings.params,
        });
        self.busy = Some("computing the reference kernel…");
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
    /// (SPEC §6): the learner recomputes the reference and calls `Fit::set_kernel`.
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
        if let Some(e) = mail.error {
            self.message = Some((e, true));
        }
        // The learner's own state; before its first reference, say that it is starting.
        self.busy = mail
            .busy
            .or_else(|| self.world.is_none().then_some("starting…"));
    }

    /// Sends changed parameters (when valid) to the learner.
    fn sync_params(&mut self) {
        if self.settings.params != self.sent_params {
            match self.settings.params.validate() {
                Ok(()) => {
                    self.sent_params = self.settings.params;
                    self.worker.send(Command::Params(self.settings.params));
                    if self
                        .message
                        .as_ref()
                        .is_some_and(|(m, _)| m.starts_with("parameter"))
                    {
                        self.message = None;
                    }
                }
                Err(e) => self.message = Some((e.to_string(), true)),
            }
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
        self.sync_params();
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
            if ui.button("Step").on_hover_text("train `step size` steps, then pause").clicked() {
                self.step();
            }
            let times = ui.label("×");
            ui.add(DragValue::new(&mut self.settings.step_size).range(1..=1_000_000))
                .labelled_by(times.id)
                .on_hover_text("step size: steps per press of Step");
            if ui.button("Reset").on_hover_text("a fresh fit (seed, |S₀|, subdivision apply)").clicked() {
                self.reset();
            }
            ui.separator();
            let mut stats = String::new();
            if let Some(st) = &self.status {
                let snap = &st.snapshot;
                let err = snap.history.last().map_or("–".into(), |h| error_text(h.rel_l2_heldout, defined[1]));
                let per_cell = snap.samples.len() as f64 / snap.cells.len().max(1) as f64;
                stats = format!(
                    "steps {}   rays {}   cells {}/{}   samples {} ({:.1}/cell)   sets {}   held-out rel. L2 {}   {:.0} steps/s",
                    snap.steps,
                    snap.rays,
                    snap.cells.len(),
                    self.sent_params.target_cells,
                    snap.samples.len(),
                    per_cell,
                    snap.sets,
                    err,
                    st.steps_per_s
                );
            }
            ui.label(RichText::new(stats).monospace());
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
                    .map(|s| format!(": final rel. L2 {}", format_errors(&s.errors, defined)))
                    .unwrap_or_default();
                let hint = if r == kernel_fit::StopReason::TargetCells {
                    "; raise the target cells and press Play to go on"
                } else {
                    ""
                };
                (format!("stopped ({r:?}){errs}{hint}"), false)
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

    fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Scene");
        ui.horizontal_wrapped(|ui| {
            for (name, _) in BUNDLED_SCENES {
                let selected = self.settings.scene == SceneChoice::Bundled(name.to_string());
                if ui.selectable_label(selected, *name).clicked() {
                    self.open_bundled(name);
                }
            }
        });
        ui.label(RichText::new(&self.scene_label).strong());
        ui.horizontal(|ui| {
            let edit = egui::TextEdit::singleline(&mut self.path_input)
                .hint_text("scene file (.ron/.json)")
                .desired_width(170.0);
            let r = ui.add(edit);
            let enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            if ui.button("Open").clicked() || enter {
                let path = PathBuf::from(self.path_input.trim());
                self.open_file(&path);
            }
        });
        ui.label(
            RichText::new("or drop a file on the window; drag end points in the scene view")
                .small()
                .weak(),
        );
        egui::Grid::new("scene-grid").num_columns(3).show(ui, |ui| {
            let l = ui.label("subdivision");
            ui.add(DragValue::new(&mut self.settings.subdivide).range(1..=1000))
                .labelled_by(l.id);
            ui.label(RichText::new("[1, 1000], on Reset").small().weak());
            ui.end_row();
        });

        ui.separator();
        ui.heading("Run");
        ui.horizontal(|ui| {
            ui.spacing_mut().slider_width = 80.0;
            let r = ui.add_enabled(
                !self.settings.unlimited,
                egui::Slider::new(&mut self.settings.speed, 100.0..=1_000_000.0)
                    .logarithmic(true)
                    .text("steps/s")
                    .max_decimals(0),
            );
            let u = ui.checkbox(&mut self.settings.unlimited, "max");
            if r.changed() || u.changed() {
                self.worker.send(Command::Speed(self.speed()));
            }
        });

        let p = &mut self.settings.params;
        let n = &mut p.network;
        ui.separator();
        ui.heading("Network (SPEC §3)");
        egui::Grid::new("net-grid")
            .num_columns(3)
            .striped(true)
            .show(ui, |ui| {
                row(
                    ui,
                    "ε_b",
                    "learning rate of the winner",
                    &mut n.eps_b,
                    1e-6..=1.0,
                    "(0, 1]",
                    1e-4,
                );
                row(
                    ui,
                    "ε_n",
                    "learning rate of its neighbours",
                    &mut n.eps_n,
                    0.0..=1.0,
                    "[0, 1]",
                    1e-5,
                );
                row(
                    ui,
                    "η",
                    "output learning rate",
                    &mut n.eta,
                    1e-6..=1.999,
                    "(0, 2)",
                    1e-3,
                );
                row(
                    ui,
                    "α",
                    "resource forgetting factor",
                    &mut n.alpha,
                    0.0..=0.999,
                    "[0, 1)",
                    1e-3,
                );
                row(
                    ui,
                    "λ",
                    "steps between insertions",
                    &mut n.lambda,
                    1..=100_000,
                    "≥ 1",
                    1.0,
                );
                row(
                    ui,
                    "cutoff",
                    "activations below are 0",
                    &mut n.activation_cutoff,
                    0.0..=0.5,
                    "[0, 1)",
                    1e-9,
                );
            });
        ui.horizontal(|ui| {
            ui.label("output rule");
            ui.selectable_value(&mut n.output_rule, OutputRule::Normalized, "NLMS");
            ui.selectable_value(&mut n.output_rule, OutputRule::Plain, "paper");
        });
        ui.horizontal(|ui| {
            ui.label("new cell's v");
            ui.selectable_value(&mut n.insert_rule, InsertRule::PreserveOutput, "preserve");
            ui.selectable_value(&mut n.insert_rule, InsertRule::VolumeWeighted, "volume");
        });

        ui.separator();
        ui.heading("Sampling (SPEC §4)");
        egui::Grid::new("sampling-grid")
            .num_columns(3)
            .striped(true)
            .show(ui, |ui| {
                row(
                    ui,
                    "ω",
                    "critical: τ > ω · mean τ",
                    &mut p.omega,
                    0.0..=100.0,
                    "≥ 0",
                    1e-2,
                );
                row(
                    ui,
                    "φ",
                    "inside a network: Σ M > φ",
                    &mut p.phi,
                    1e-6..=100.0,
                    "> 0",
                    1e-2,
                );
                row(
                    ui,
                    "ψ",
                    "new set when |A|/|S| > ψ",
                    &mut p.psi,
                    1e-4..=1.0,
                    "(0, 1]",
                    1e-3,
                );
                row(
                    ui,
                    "|S₀|",
                    "initial uniform samples (on Reset)",
                    &mut p.initial_samples,
                    3..=1_000_000,
                    "≥ 3",
                    10.0,
                );
                row(
                    ui,
                    "min |S_j|",
                    "smallest resampled set",
                    &mut p.min_set_size,
                    1..=1_000_000,
                    "≥ 1",
                    1.0,
                );
                row(
                    ui,
                    "scan ×",
                    "θ scans ≤ this × set size",
                    &mut p.scan_factor,
                    1..=100_000,
                    "≥ 1",
                    1.0,
                );
            });

        ui.separator();
        ui.heading("Fit");
        egui::Grid::new("fit-grid")
            .num_columns(3)
            .striped(true)
            .show(ui, |ui| {
                row(
                    ui,
                    "target cells",
                    "growth stops here",
                    &mut p.target_cells,
                    3..=20_000,
                    "≥ 3",
                    5.0,
                );
                row(
                    ui,
                    "seed",
                    "every random choice (on Reset)",
                    &mut p.seed,
                    0..=u64::MAX,
                    "any",
                    1.0,
                );
                row(
                    ui,
                    "ridge",
                    "smallest refit ridge tried (×10⁰…10⁶, best on S₀ kept)",
                    &mut p.ridge,
                    1e-12..=1.0,
                    "> 0",
                    1e-7,
                );
                row(
                    ui,
                    "eval every",
                    "steps between error points",
                    &mut p.eval_every,
                    0..=1_000_000,
                    "≥ 0",
                    100.0,
                );
            });
        ui.checkbox(&mut p.refit, "least-squares refit at the end");

        ui.separator();
        ui.heading("View");
        ui.checkbox(&mut self.settings.log_scale, "log colour scale (4 decades)");
        ui.checkbox(
            &mut self.settings.show_cells,
            "cells (size ~ δ_c, cyan = critical)",
        );
        ui.checkbox(&mut self.settings.show_edges, "network edges");
        ui.checkbox(&mut self.settings.show_samples, "samples, coloured by set");
        if ui.button("Default parameters").clicked() {
            let target = self.settings.params.target_cells;
            self.settings.params = FitParams {
                target_cells: target,
                ..FitParams::default()
            };
        }
    }

    fn main_area(&mut self, ui: &mut egui::Ui) {
        let full = ui.available_rect_before_wrap();
        let Some(world) = self.world.clone() else {
            ui.centered_and_justified(|ui| {
                ui.label(self.busy.unwrap_or("waiting for the learner…"))
            });
            return;
        };
        let ctx = ui.ctx().clone();
        let gap = 8.0;
        let curves_h = (full.height() * 0.34).clamp(150.0, 300.0);
        let top_h = full.height() - curves_h - gap;
        let big = top_h.min(full.width() * 0.46);
        let small = (big - views::TITLE_H) / 2.0 + views::TITLE_H / 2.0;
        let kernel_rect = Rect::from_min_size(full.min, Vec2::splat(big));
        let approx_rect = Rect::from_min_size(
            kernel_rect.right_top() + Vec2::new(gap, 0.0),
            Vec2::splat(small),
        );
        let error_rect = Rect::from_min_size(
            approx_rect.left_bottom() + Vec2::new(0.0, big - 2.0 * small),
            Vec2::splat(small),
        );
        let scene_left = approx_rect.right() + gap;
        let scene_rect = Rect::from_min_max(
            Pos2::new(scene_left, full.top()),
            Pos2::new(full.right(), full.top() + top_h * 0.62),
        );
        let info_rect = Rect::from_min_max(
            Pos2::new(scene_left, scene_rect.bottom() + gap),
            Pos2::new(full.right(), full.top() + top_h),
        );
        let curves_rect =
            Rect::from_min_max(Pos2::new(full.left(), full.top() + top_h + gap), full.max);

        // Colour scale from the reference, shared by all three heatmaps.
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
        let kernel_tex = cached_texture(&ctx, &mut self.kernel_tex, "kernel", key, || {
            grid_image(world.reference.grid(), REFERENCE_RES, scale)
        });
        let approx = self.approx.clone().filter(|a| a.world == world.id);
        let (approx_tex, error_tex) = match &approx {
            Some(a) => {
                let key = (world.id, u64::from(log), a.steps + 1);
                let at = cached_texture(&ctx, &mut self.approx_tex, "approx", key, || {
                    grid_image(&a.values, APPROX_RES, scale)
                });
                let et = cached_texture(&ctx, &mut self.error_tex, "error", key, || {
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
        let status = self.status.clone().filter(|s| s.world == world.id);
        let samples_tex = match (&status, self.settings.show_samples) {
            (Some(st), true) => {
                let snap = &st.snapshot;
                let key = (world.id, snap.samples.len() as u64, snap.sets as u64);
                Some(cached_texture(
                    &ctx,
                    &mut self.samples_tex,
                    "samples",
                    key,
                    || samples_image(&snap.samples, 2 * REFERENCE_RES),
                ))
            }
            _ => None,
        };

        // Kernel plot with the live overlay.
        let kernel_frame = PlotFrame::new(kernel_rect, true);
        let ppp = ui.ctx().pixels_per_point();
        let side = ((kernel_frame.plot.width() * ppp).round() as usize).clamp(16, 2048);
        let (cells, edges) = (self.settings.show_cells, self.settings.show_edges);
        let cells_tex = status.as_ref().map(|st| {
            let snap = &st.snapshot;
            let key = (
                Arc::as_ptr(snap) as u64,
                side as u64,
                u64::from(cells) | u64::from(edges) << 1 | u64::from(ppp.to_bits()) << 2,
            );
            cached_texture(&ctx, &mut self.overlay_tex, "overlay", key, || {
                views::overlay_image(side, ppp, snap, cells, edges)
            })
        });
        let hovered = views::kernel_plot(
            ui,
            &kernel_frame,
            "ζ(s, t) exact, with the cells",
            Some(kernel_tex),
            &world.scene,
            &views::Overlay {
                cells: cells_tex,
                samples: samples_tex,
            },
            &self.hover,
        );
        let approx_frame = PlotFrame::new(approx_rect, false);
        let h2 = views::kernel_plot(
            ui,
            &approx_frame,
            "learned ζ (SGCS)",
            approx_tex,
            &world.scene,
            &views::Overlay::none(),
            &self.hover,
        );
        let error_frame = PlotFrame::new(error_rect, false);
        let h3 = views::kernel_plot(
            ui,
            &error_frame,
            "|learned − exact|",
            error_tex,
            &world.scene,
            &views::Overlay::none(),
            &self.hover,
        );
        self.hover.st = hovered.or(h2).or(h3);

        // Scene view: draws the hovered ray, reports hovered s and dragged end points.
        let scene_out = views::scene_view(
            ui,
            scene_rect,
            &self.scene,
            &world,
            &self.hover,
            &mut self.drag,
        );
        self.hover.scene_s = scene_out.hovered_s;
        if let Some((from, to)) = scene_out.moved {
            self.move_point(from, to);
        }

        // Read-out under the scene.
        ui.scope_builder(UiBuilder::new().max_rect(info_rect), |ui| {
            self.readout(ui, &world, approx.as_deref());
        });

        // Curves.
        ui.scope_builder(UiBuilder::new().max_rect(curves_rect), |ui| {
            views::curves(ui, status.as_ref().map(|s| s.snapshot.as_ref()));
        });
    }

    fn readout(&self, ui: &mut egui::Ui, world: &World, approx: Option<&Approx>) {
        ui.horizontal(|ui| {
            for (name, color) in views::LEGEND {
                ui.label(RichText::new(name).color(color).strong());
            }
            ui.label(RichText::new("ticks: front side").weak());
        });
        if let Some([s, t]) = self.hover.st {
            let k = world.kernel.eval(s, t);
            let learned = approx.map(|a| a.model.zeta(s, t));
            let text = format!(
                "s {s:.4} (edge {}) → t {t:.4} (edge {})\nG {:.4}  V {}  k {:.5}\nζ {:.5}  ζ̃ {}",
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
                learned.map_or("–".into(), |v| format!("{v:.5}")),
            );
            ui.label(RichText::new(text).monospace());
        } else if let Some(s) = self.hover.scene_s {
            ui.label(
                RichText::new(format!(
                    "scene point at s = t = {s:.4}\n(row and column marked in the plots)"
                ))
                .monospace(),
            );
        } else {
            ui.label(RichText::new("hover the kernel plot: the ray from x(s) to y(t)\nhover the scene: the point's s and t").weak());
        }
        let _ = ui.painter().text(
            ui.max_rect().left_bottom(),
            Align2::LEFT_BOTTOM,
            format!(
                "{} edges, L = {:.3}",
                world.scene.edges().len(),
                world.scene.total_length()
            ),
            FontId::proportional(11.0),
            ui.visuals().weak_text_color(),
        );
    }
}

/// A labelled, range-limited number in a 3-column grid: name (hover: meaning) | value | range.
fn row<T: egui::emath::Numeric>(
    ui: &mut egui::Ui,
    name: &str,
    meaning: &str,
    value: &mut T,
    range: std::ops::RangeInclusive<T>,
    valid: &str,
    speed: f64,
) {
    let label = ui.label(name).on_hover_text(meaning);
    ui.add(
        DragValue::new(value)
            .range(range)
            .speed(speed)
            .max_decimals(9),
    )
    .labelled_by(label.id)
    .on_hover_text(meaning);
    ui.label(RichText::new(valid).small().weak());
    ui.end_row();
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
    let (_, text) = BUNDLED_SCENES
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| format!("no bundled scene named {name:?}"))?;
    let scene = Scene::from_ron_str(text).map_err(|e| format!("bundled scene {name}: {e}"))?;
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
