//! The app: the state the UI keeps between frames, and one frame's order of work (take what the
//! learner published, record it in the timeline, draw, send changed parameters).
//!
//! Its parts: what tests and the binary can ask ([`queries`]), what they can do ([`actions`]),
//! the top bar ([`top_bar`]), the controls panel ([`controls`]), the timeline bar
//! ([`timeline_bar`]), the plots and scenes of the central area ([`panels`], laid out by
//! [`layout`], textured by [`heatmaps`]), the moving lights of the relit scene ([`lamps`]), the readout under the pointer ([`readout`]), export
//! ([`export`]) and the frame counter ([`fps`]). Drawing is in [`crate::views`], the learner
//! in [`crate::worker`], settings in [`crate::settings`].

mod actions;
mod controls;
mod export;
mod fps;
mod heatmaps;
mod lamps;
mod layout;
mod panels;
mod queries;
mod readout;
mod timeline_bar;
mod top_bar;

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use egui::{CentralPanel, Color32, Frame, Panel, ScrollArea};
use flatland_geom::Scene;
use kernel_fit::FitParams;

use crate::background::Priority;
use crate::learner::Learner;
use crate::relit::{MovingLight, RelitHandle};
use crate::scenes;
use crate::scenes::SceneChoice;
use crate::settings::{SETTINGS_KEY, Settings};
use crate::timeline::{Moment, Timeline};
use crate::views::{EdgesTexture, Hover, SceneDrag};
use crate::worker::{Approx, Command, KernelGrid, LitState, Status, WorkerHandle, World};

pub use top_bar::stop_text;

/// What the panels show this frame: a world, and its moment (once one was published).
struct Shown {
    world: Arc<World>,
    moment: Option<Moment>,
    /// Whether it is the running learner's newest state.
    live: bool,
    /// Cells with this id or more were inserted in the last
    /// [`NEW_FOR`](crate::views::NEW_FOR) before the moment.
    new_from: usize,
    /// The exact ζ at the plot's resolution, once the learner has made it for this world.
    kernel_grid: Option<Arc<KernelGrid>>,
}

/// How [`crate::run_with`] starts the viewer. The default starts learning at once.
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Open this scene file (or scene the viewer offers by name: [`scenes::named`]) instead of
    /// the remembered scene.
    pub scene: Option<PathBuf>,
    /// Start paused instead of learning at once.
    pub paused: bool,
    /// Run this learner instead of the remembered one.
    pub learner: Option<Learner>,
    /// Override the target cell count.
    pub target_cells: Option<usize>,
    /// Override the pace of growth, cells per second (infinite: as fast as the machine goes).
    pub growth: Option<f64>,
    /// Ignore (but still save) the remembered settings.
    pub fresh_settings: bool,
    /// Print the frame rate, frame times and learner speed to stderr every two seconds.
    pub fps_log: bool,
    /// Where exported pictures and models go (default: the current folder).
    pub export_dir: Option<PathBuf>,
}

/// Which moment the plots show, and the replay.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Cursor {
    /// The training time shown; `None`: live, the newest moment.
    at: Option<Duration>,
    /// The moment scrubbed to, by its number in the timeline (moments recorded within one
    /// training instant, before Play or while paused, share a time).
    picked: Option<u64>,
    /// Replaying at this many times the speed it was recorded at.
    replaying: Option<f32>,
    /// The speed Replay uses.
    speed: f32,
}

/// The viewer's state. Built by [`ViewerApp::new`] inside eframe, or by
/// [`ViewerApp::headless`] in tests; [`ViewerApp::show`] draws one frame into a [`egui::Ui`].
pub struct ViewerApp {
    settings: Settings,
    /// The learner the last Reset started.
    fit_learner: Learner,
    /// Parameters of the fit the last Reset started.
    fit_params: FitParams,
    /// Parameters the learner last got: the fit's, with the live part last sent.
    sent_params: FitParams,
    worker: WorkerHandle,
    /// Commands sent up to and including the last Reset: older statuses are the old fit's.
    fit_since: u64,
    /// The scene as the user sees and edits it (not subdivided).
    scene: Scene,
    scene_label: String,
    /// What importing the scene's drawing said, one line each (shown under its name).
    scene_warnings: Vec<String>,
    world: Option<Arc<World>>,
    /// The newest of each publication.
    status: Option<Status>,
    approx: Option<Arc<Approx>>,
    lit: Option<LitState>,
    kernel_grid: Option<Arc<KernelGrid>>,
    /// The kernel plot's resolution last asked of the learner.
    plot_res: usize,
    timeline: Timeline,
    cursor: Cursor,
    busy: Option<&'static str>,
    message: Option<(String, bool)>,
    path_input: String,
    hover: Hover,
    drag: Option<SceneDrag>,
    textures: heatmaps::Textures,
    /// The lines of the scene view.
    scene_edges: EdgesTexture,
    /// The scene relit under its moving lights, on a thread of its own.
    lamps: lamps::Lamps,
    fps: fps::FpsMeter,
    export: export::Exports,
}

impl ViewerApp {
    /// The app inside eframe: settings from eframe's storage (unless `options.fresh_settings`),
    /// the scene from `options.scene`, else the remembered one, else the floor plan.
    pub fn new(cc: &eframe::CreationContext<'_>, options: &Options) -> ViewerApp {
        let (settings, note) = if options.fresh_settings {
            (Settings::default(), None)
        } else {
            Settings::load(cc.storage)
        };
        // In a window the learner runs in the background: the window's frames come first.
        let ctx = cc.egui_ctx.clone();
        let mut app = ViewerApp::launch(ctx, settings, options, Priority::Background);
        if let Some(note) = note
            && app.message.is_none()
        {
            app.message = Some((note, false));
        }
        app
    }

    /// The app as [`ViewerApp::new`] starts it, from given settings: the options applied, and
    /// learning at once unless `options.paused` (at normal priority: no window waits for it).
    pub fn with_options(ctx: egui::Context, settings: Settings, options: &Options) -> ViewerApp {
        ViewerApp::launch(ctx, settings, options, Priority::Normal)
    }

    /// [`ViewerApp::with_options`] with the learner's threads at `priority`.
    fn launch(
        ctx: egui::Context,
        mut settings: Settings,
        options: &Options,
        priority: Priority,
    ) -> ViewerApp {
        if let Some(learner) = options.learner {
            settings.choose_learner(learner);
        }
        if let Some(cells) = options.target_cells {
            settings.params.target_cells = cells;
        }
        if let Some(path) = &options.scene {
            settings.scene = scenes::choice_for(path);
        }
        if let Some(growth) = options.growth {
            settings.unlimited = !growth.is_finite();
            if growth.is_finite() {
                settings.growth = growth.max(f64::MIN_POSITIVE);
            }
        }
        let mut app = ViewerApp::start(ctx, settings, priority);
        app.fps.log = options.fps_log;
        if let Some(dir) = &options.export_dir {
            app.export.dir.clone_from(dir);
        }
        if !options.paused {
            app.play();
        }
        app
    }

    /// The app without eframe (for tests): starts the learner and a fresh fit of the chosen
    /// scene, paused.
    pub fn headless(ctx: egui::Context, settings: Settings) -> ViewerApp {
        ViewerApp::start(ctx, settings, Priority::Normal)
    }

    /// [`ViewerApp::headless`] with the learner's threads at `priority`.
    fn start(ctx: egui::Context, mut settings: Settings, priority: Priority) -> ViewerApp {
        let (opened, mut message) = match scenes::load(&settings.scene) {
            Ok(opened) => {
                let note = scenes::warnings_note(&opened).map(|note| (note, false));
                (opened, note)
            }
            Err(e) => {
                let note = Some((format!("{e}; opened {} instead", scenes::DEFAULT), true));
                settings.scene = SceneChoice::Bundled(scenes::DEFAULT.into());
                let default = scenes::load(&settings.scene).expect("the default scene loads");
                (default, note)
            }
        };
        if settings.params.validate().is_err() {
            message = Some((
                "remembered parameters were invalid; the preset's restored".into(),
                true,
            ));
            settings.restore_preset();
        }
        let repaint_ctx = ctx.clone();
        let worker = WorkerHandle::spawn(priority, move || repaint_ctx.request_repaint());
        // At normal priority: each move is short, and the window waits for the light to follow.
        let relit_ctx = ctx.clone();
        let relit = RelitHandle::spawn(Priority::Normal, MovingLight::make, move || {
            relit_ctx.request_repaint();
        });
        relit.use_transport(settings.transport);
        let mut app = ViewerApp {
            fit_learner: settings.learner,
            fit_params: settings.params,
            sent_params: settings.params,
            worker,
            fit_since: 0,
            scene: opened.scene,
            scene_label: opened.label,
            scene_warnings: opened.warnings,
            world: None,
            status: None,
            approx: None,
            lit: None,
            kernel_grid: None,
            plot_res: 0,
            timeline: Timeline::default(),
            cursor: Cursor {
                speed: 1.0,
                ..Cursor::default()
            },
            busy: Some("starting…"),
            message,
            path_input: match &settings.scene {
                SceneChoice::File(p) => p.display().to_string(),
                SceneChoice::Bundled(_) => String::new(),
            },
            hover: Hover::default(),
            drag: None,
            textures: heatmaps::Textures::default(),
            scene_edges: EdgesTexture::default(),
            lamps: lamps::Lamps::new(relit),
            fps: fps::FpsMeter::default(),
            export: export::Exports::new(),
            settings,
        };
        app.worker.send(Command::Pace(app.pace()));
        app.worker.send(Command::Lit(app.settings.lit));
        app.reset();
        app
    }

    /// The pace the settings ask for (cells per second; `None`: as fast as it goes).
    fn pace(&self) -> Option<f64> {
        (!self.settings.unlimited).then_some(self.settings.growth)
    }

    /// Takes what the learner published; a new status is recorded as a moment of the run.
    fn poll(&mut self) {
        let Some(mail) = self.worker.take() else {
            return;
        };
        if let Some(world) = mail.world {
            self.world = Some(world);
            self.approx = None;
        }
        let fresh_grid = mail.approx.as_ref().map(|a| Arc::clone(&a.grid));
        if let Some(approx) = mail.approx {
            self.approx = Some(approx);
        }
        let fresh_lit = match &mail.lit {
            Some(LitState::Ready(l)) => Some(Arc::clone(l)),
            _ => None,
        };
        if let Some(lit) = mail.lit {
            self.lit = Some(lit);
        }
        if let Some(grid) = mail.kernel_grid {
            self.kernel_grid = Some(grid);
        }
        let fresh_status = !mail.statuses.is_empty();
        for status in mail.statuses {
            self.status = Some(status);
            self.record();
        }
        if !fresh_status {
            self.complete_latest(fresh_grid, fresh_lit);
        }
        if let Some(e) = mail.error {
            self.message = Some((e, true));
        }
        if let Some(note) = mail.note {
            self.message = Some((note, false));
        }
        // The learner's own state; before its first reference, say that it is starting.
        self.busy = mail
            .busy
            .or_else(|| self.world.is_none().then_some("starting…"));
    }

    /// Records the newest status as a moment of the current fit, with the newest learned grid
    /// and lit scene of its world that are not newer than it (else the last moment's).
    fn record(&mut self) {
        let (Some(status), Some(world)) = (&self.status, &self.world) else {
            return;
        };
        if status.world != world.id || status.handled < self.fit_since {
            return;
        }
        let steps = status.growth.steps;
        let before = self.timeline.latest().filter(|m| m.world.id == world.id);
        let learned = self
            .approx
            .as_ref()
            .map(|a| Arc::clone(&a.grid))
            .filter(|g| g.world == world.id && g.steps <= steps)
            .or_else(|| before.and_then(|m| m.learned.clone()));
        let lit = match &self.lit {
            Some(LitState::Ready(l)) if l.setup.world == world.id && l.steps <= steps => {
                Some(Arc::clone(l))
            }
            _ => before.and_then(|m| m.lit.clone()),
        };
        self.timeline.record(Moment {
            world: Arc::clone(world),
            status: status.clone(),
            learned,
            lit,
        });
    }

    /// A learned grid or lit scene that came after the newest status belongs to its moment.
    fn complete_latest(
        &mut self,
        grid: Option<Arc<crate::worker::LearnedGrid>>,
        lit: Option<Arc<crate::worker::Lit>>,
    ) {
        let Some(m) = self.timeline.latest_mut() else {
            return;
        };
        if let Some(g) = grid.filter(|g| g.world == m.world.id && g.steps <= m.steps()) {
            m.learned = Some(g);
        }
        if let Some(l) = lit.filter(|l| l.setup.world == m.world.id && l.steps <= m.steps()) {
            m.lit = Some(l);
        }
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
        self.tick_lamps(ui.ctx());
        self.fps.tick();
        self.log_fps();
        self.export.take_finished(&mut self.message);
        self.advance_replay(ui.ctx());
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
        // The panels are not filled: the window is cleared to their colour (`clear_color`), and
        // filling the whole window again costs a software rasterizer as much as a plot.
        let bare = Frame::side_top_panel(ui.style()).fill(Color32::TRANSPARENT);
        Panel::top("bar")
            .frame(bare)
            .show(ui, |ui| self.top_bar(ui));
        Panel::bottom("timeline")
            .frame(bare)
            .show(ui, |ui| self.timeline_bar(ui));
        Panel::left("controls")
            .frame(bare)
            .resizable(false)
            .exact_size(262.0)
            .show(ui, |ui| {
                ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        CentralPanel::default()
            .frame(Frame::central_panel(ui.style()).fill(Color32::TRANSPARENT))
            .show(ui, |ui| self.main_area(ui));
        self.sync_params(ui.ctx());
        if self.running() || self.busy.is_some() || self.cursor.replaying.is_some() {
            ui.ctx().request_repaint_after(Duration::from_millis(16));
        }
    }
}

impl eframe::App for ViewerApp {
    /// The panels' colour: they are drawn without a fill of their own.
    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        visuals.panel_fill.to_normalized_gamma_f32()
    }

    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        if let Some(cpu) = frame.info().cpu_usage {
            self.fps.add_cpu(cpu);
        }
        self.show(ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, SETTINGS_KEY, &self.settings);
    }
}
