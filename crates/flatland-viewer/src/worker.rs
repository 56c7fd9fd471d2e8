//! The learner's thread. It owns the [`Fit`]; the UI talks to it with [`Command`]s and reads
//! what it publishes from a [`Mailbox`] with `try_lock`, so a frame never waits for training.
//! Each publication also wakes whoever waits for one ([`WorkerHandle::wait`]: tests, which wait
//! on what the learner says instead of sleeping), and every status says how many commands the
//! learner has handled, so the UI knows when it has caught up.
//!
//! Publishing is throttled: a [`Snapshot`] at most every [`PUBLISH_EVERY`], the learned ζ̃ on
//! the display grid at most every [`APPROX_EVERY`] (it costs `APPROX_RES²` network evaluations),
//! the lit scene as [`crate::lit`] says. Long work (the lit scene's exact reference and solves)
//! stops as soon as a command is waiting and is taken up again after it.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use flatland_geom::{Kernel, Scene};
use flatland_solve::{Errors, Reference, Representation};
use kernel_fit::{Fit, FitParams, FitSummary, LearnedKernel, LiveParams, Snapshot, StopReason};
use rayon::prelude::*;

use crate::lit::{LitPoint, LitSetup, LitSolve, solve_interval};

/// Resolution of the reference grid (the kernel heatmap).
pub const REFERENCE_RES: usize = 256;
/// Resolution of the approximation and error panels.
pub const APPROX_RES: usize = 128;
/// Shortest time between two published snapshots.
pub const PUBLISH_EVERY: Duration = Duration::from_millis(50);
/// Shortest time between two published approximations while training.
pub const APPROX_EVERY: Duration = Duration::from_millis(600);
/// Longest uninterrupted training slice: commands are read at least this often.
const SLICE: Duration = Duration::from_millis(15);

/// What the UI asks of the learner.
#[derive(Debug)]
pub enum Command {
    /// Train continuously.
    Play,
    /// Stop training (the fit is kept).
    Pause,
    /// Train exactly this many steps (then pause).
    Step(u64),
    /// Start a fresh fit on `scene` (subdivided `subdivide` times).
    Reset {
        /// The scene as the user sees it (not subdivided).
        scene: Scene,
        /// Pieces per surface edge.
        subdivide: usize,
        /// The fit's parameters.
        params: FitParams,
    },
    /// New live parameters for the running fit (what else changes needs a new fit: `Reset`).
    Params(LiveParams),
    /// The scene changed (an end point was dragged): keep learning from the current state.
    Edit {
        /// The changed scene (not subdivided).
        scene: Scene,
        /// Pieces per surface edge.
        subdivide: usize,
    },
    /// Steps per second; `None` trains as fast as possible.
    Speed(Option<f64>),
    /// Solve the lit scene with the learned kernel while it learns (or stop doing so).
    Lit(bool),
    /// Nothing but a status: the UI's way to learn that everything before it was handled.
    Sync,
}

/// A scene and everything derived from it that the UI shows. Replaced, never mutated.
#[derive(Debug)]
pub struct World {
    /// Increases with every new scene.
    pub id: u64,
    /// The scene as the user sees and edits it (not subdivided).
    pub scene: Scene,
    /// The exact kernel (of the subdivided scene: the same function of `(s, t)`).
    pub kernel: Arc<Kernel>,
    /// The exact ζ on the reference grid and at held-out points.
    pub reference: Arc<Reference>,
    /// The exact ζ on the `APPROX_RES` display grid, for the error panel.
    pub exact_small: Vec<f64>,
    /// Whether relative errors are defined on the grid and at the held-out points: against a ζ
    /// that is 0 everywhere (nothing emits) they are 0/0 and shown as "undefined".
    pub defined: [bool; 2],
}

/// The learned ζ̃ on the display grid.
#[derive(Debug)]
pub struct Approx {
    /// The [`World`] it belongs to.
    pub world: u64,
    /// Training steps when it was computed.
    pub steps: u64,
    /// ζ̃ on the `APPROX_RES` grid, row-major, row ↔ s.
    pub values: Vec<f64>,
    /// The model, for the learned value under the pointer.
    pub model: LearnedKernel,
}

/// The learner's state as last published.
#[derive(Clone, Debug)]
pub struct Status {
    /// The fit's state.
    pub snapshot: Arc<Snapshot>,
    /// The [`World`] it belongs to.
    pub world: u64,
    /// Whether it is training continuously.
    pub running: bool,
    /// Why it stopped, if it did.
    pub stopped: Option<StopReason>,
    /// Training steps per second over the last second.
    pub steps_per_s: f64,
    /// Final errors of the last finished fit (after the refit, if enabled).
    pub summary: Option<FitSummary>,
    /// Commands handled before this status was made.
    pub handled: u64,
    /// The running fit's parameters.
    pub params: FitParams,
    /// Faces of the visibility structure that hold a cell (visibility learners only).
    pub occupied_faces: Option<usize>,
}

/// The lit scene as last published.
#[derive(Clone, Debug)]
pub enum LitState {
    /// Nothing to show yet; what is being done.
    Pending(&'static str),
    /// The lit view is switched off.
    Off,
    /// The setup or a solve failed; why.
    Failed(String),
    /// A solve with the learned kernel.
    Ready(Arc<Lit>),
}

/// The scene lit by the learned kernel.
#[derive(Debug)]
pub struct Lit {
    /// The mesh and the exact B (its `world` is the id of the reference it belongs to).
    pub setup: Arc<LitSetup>,
    /// Training steps of the model solved.
    pub steps: u64,
    /// Its cells.
    pub cells: usize,
    /// B and its errors.
    pub solve: LitSolve,
    /// The error of every solve of this fit so far.
    pub history: Vec<LitPoint>,
}

/// What the learner publishes. Each field holds the newest value; the UI takes them.
#[derive(Debug, Default)]
pub struct Mailbox {
    /// A new scene's data.
    pub world: Option<Arc<World>>,
    /// The newest status.
    pub status: Option<Status>,
    /// The newest approximation.
    pub approx: Option<Arc<Approx>>,
    /// The newest lit scene.
    pub lit: Option<LitState>,
    /// An error to show (a bad parameter, a failed reset).
    pub error: Option<String>,
    /// Work that keeps the learner busy for a noticeable time (e.g. "computing the reference").
    pub busy: Option<&'static str>,
    /// Something was posted since the UI last took the mail.
    fresh: bool,
}

/// The mailbox and the signal that something was posted to it.
#[derive(Default)]
struct Shared {
    mailbox: Mutex<Mailbox>,
    posted: Condvar,
    /// Commands sent so far: more than the learner has handled means one is waiting.
    sent: AtomicU64,
}

/// The UI's end: a command channel and the mailbox. Dropping it stops the thread.
pub struct WorkerHandle {
    commands: Option<Sender<Command>>,
    sent: u64,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

impl WorkerHandle {
    /// Starts the thread. `repaint` is called after each publication (the UI's repaint request).
    pub fn spawn(repaint: impl Fn() + Send + 'static) -> WorkerHandle {
        let (tx, rx) = mpsc::channel();
        let shared = Arc::new(Shared::default());
        let learner_end = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("flatland-learner".into())
            .spawn(move || Learner::new(rx, learner_end, Box::new(repaint)).run())
            .expect("spawning the learner thread");
        WorkerHandle {
            commands: Some(tx),
            sent: 0,
            shared,
            thread: Some(thread),
        }
    }

    /// Sends a command (ignored if the thread has ended).
    pub fn send(&mut self, command: Command) {
        if let Some(tx) = &self.commands
            && tx.send(command).is_ok()
        {
            self.sent += 1;
            self.shared.sent.store(self.sent, Ordering::Release);
        }
    }

    /// Commands sent so far (compare with [`Status::handled`]).
    pub fn sent(&self) -> u64 {
        self.sent
    }

    /// Takes what was published since the last call, without waiting: `None` when the learner
    /// holds the lock right now (try again next frame).
    pub fn take(&self) -> Option<Mailbox> {
        let mut guard = self.shared.mailbox.try_lock().ok()?;
        let mail = std::mem::take(&mut *guard);
        guard.busy = mail.busy; // a state, not an event: it stays until the learner clears it
        Some(mail)
    }

    /// Blocks until the learner has posted something the UI has not taken yet, or `timeout`
    /// passes; returns whether there is something. For tests and tools that wait on the
    /// learner: the UI itself never waits.
    pub fn wait(&self, timeout: Duration) -> bool {
        let Ok(guard) = self.shared.mailbox.lock() else {
            return false;
        };
        self.shared
            .posted
            .wait_timeout_while(guard, timeout, |m| !m.fresh)
            .map(|(m, _)| m.fresh)
            .unwrap_or(false)
    }
}

impl Drop for WorkerHandle {
    fn drop(&mut self) {
        self.commands = None; // disconnects: the learner's next read ends its loop
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

struct Learner {
    rx: Receiver<Command>,
    shared: Arc<Shared>,
    repaint: Box<dyn Fn() + Send>,
    fit: Option<Fit>,
    world: Option<Arc<World>>,
    next_world: u64,
    running: bool,
    steps_left: u64,
    speed: Option<f64>,
    allowance: f64,
    last_tick: Instant,
    last_publish: Instant,
    last_approx: Instant,
    published_steps: Option<u64>,
    approx_steps: Option<u64>,
    rate: (Instant, u64, f64),
    summary: Option<FitSummary>,
    /// A command changed something a status shows: publish one as soon as it is due.
    dirty: bool,
    handled: u64,
    lit: LitWork,
}

/// The learner's side of the lit scene.
struct LitWork {
    enabled: bool,
    /// The mesh and exact B of the current world, once made.
    setup: Option<Arc<LitSetup>>,
    /// The world whose setup failed (not retried until the scene changes).
    failed: Option<u64>,
    /// Steps of the model last solved (`None`: solve again whatever the steps).
    steps: Option<u64>,
    /// When the last solve ended, and what it cost.
    last: Instant,
    cost: Duration,
    history: Vec<LitPoint>,
}

impl LitWork {
    fn new(now: Instant) -> LitWork {
        LitWork {
            enabled: true,
            setup: None,
            failed: None,
            steps: None,
            last: now,
            cost: Duration::ZERO,
            history: Vec::new(),
        }
    }
}

impl Learner {
    fn new(rx: Receiver<Command>, shared: Arc<Shared>, repaint: Box<dyn Fn() + Send>) -> Self {
        let now = Instant::now();
        Learner {
            rx,
            shared,
            repaint,
            fit: None,
            world: None,
            next_world: 1,
            running: false,
            steps_left: 0,
            speed: None,
            allowance: 0.0,
            last_tick: now,
            last_publish: now,
            last_approx: now,
            published_steps: None,
            approx_steps: None,
            rate: (now, 0, 0.0),
            summary: None,
            dirty: false,
            handled: 0,
            lit: LitWork::new(now),
        }
    }

    /// Changes the mailbox, marks it fresh, wakes waiters and asks the UI to repaint.
    fn post(&self, change: impl FnOnce(&mut Mailbox)) {
        if let Ok(mut m) = self.shared.mailbox.lock() {
            change(&mut m);
            m.fresh = true;
        }
        self.shared.posted.notify_all();
        (self.repaint)();
    }

    /// A stop flag for long work: true once a command is waiting.
    fn command_waiting(&self) -> impl Fn() -> bool + Sync + use<> {
        let shared = Arc::clone(&self.shared);
        let handled = self.handled;
        move || shared.sent.load(Ordering::Acquire) > handled
    }

    fn run(mut self) {
        loop {
            // Read every waiting command; sleep on the channel only when there is nothing to
            // train, and then not past the moment a pending status is due.
            let training = self.running || self.steps_left > 0;
            let first = if !training {
                let wait = if self.dirty {
                    PUBLISH_EVERY.saturating_sub(self.last_publish.elapsed())
                } else if self.lit_pending() {
                    Duration::ZERO
                } else {
                    Duration::from_millis(200)
                };
                match self.rx.recv_timeout(wait) {
                    Ok(c) => Some(c),
                    Err(RecvTimeoutError::Timeout) => None,
                    Err(RecvTimeoutError::Disconnected) => return,
                }
            } else {
                match self.rx.try_recv() {
                    Ok(c) => Some(c),
                    Err(TryRecvError::Empty) => None,
                    Err(TryRecvError::Disconnected) => return,
                }
            };
            if let Some(c) = first {
                self.handle(c);
                loop {
                    match self.rx.try_recv() {
                        Ok(c) => self.handle(c),
                        Err(TryRecvError::Empty) => break,
                        Err(TryRecvError::Disconnected) => return,
                    }
                }
            }
            self.train_slice();
            self.publish(false);
            self.update_lit();
        }
    }

    fn handle(&mut self, command: Command) {
        self.handled += 1;
        match command {
            Command::Play => {
                self.running = true;
                self.last_tick = Instant::now();
                self.allowance = 0.0;
            }
            Command::Pause => {
                self.running = false;
                self.steps_left = 0;
            }
            Command::Step(n) => {
                self.running = false;
                self.steps_left = self.steps_left.saturating_add(n);
            }
            Command::Speed(speed) => self.speed = speed,
            Command::Reset {
                scene,
                subdivide,
                params,
            } => self.reset(scene, subdivide, params),
            Command::Params(params) => self.set_params(params),
            Command::Edit { scene, subdivide } => self.edit(scene, subdivide),
            Command::Lit(on) => {
                self.lit.enabled = on;
                self.lit.steps = None;
                let state = if on {
                    LitState::Pending("solving the radiosity…")
                } else {
                    LitState::Off
                };
                self.post(|m| m.lit = Some(state));
            }
            Command::Sync => {}
        }
        self.dirty = true;
    }

    fn set_params(&mut self, live: LiveParams) {
        let Some(fit) = &mut self.fit else {
            return;
        };
        match fit.set_params(live) {
            // A fit that goes on under the new rules has no final errors yet; one with nothing
            // to learn stays stopped (`StopReason::Exact`) and keeps them.
            Ok(()) if fit.stopped().is_none() => self.summary = None,
            Ok(()) => {}
            Err(e) => self.report(e.to_string()),
        }
    }

    fn report(&self, message: String) {
        self.post(|m| m.error = Some(message));
    }

    fn set_busy(&self, busy: Option<&'static str>) {
        self.post(|m| m.busy = busy);
    }

    /// The scene's kernel, reference and display grid: the expensive part of a scene change.
    fn build_world(
        &mut self,
        scene: Scene,
        subdivide: usize,
        params: &FitParams,
    ) -> Result<Arc<World>, String> {
        self.set_busy(Some("computing the reference kernel…"));
        let built = if subdivide > 1 {
            scene.subdivide(subdivide)
        } else {
            Ok(scene.clone())
        };
        let result = built.map_err(|e| e.to_string()).map(|learned| {
            let kernel = Arc::new(Kernel::new(learned));
            let reference = Arc::new(Reference::new(
                &kernel,
                REFERENCE_RES,
                params.heldout,
                kernel_fit::REFERENCE_SEED,
            ));
            let exact_small = kernel.grid(APPROX_RES, true);
            let defined = [
                reference.grid().iter().any(|v| *v != 0.0),
                reference.heldout().1.iter().any(|v| *v != 0.0),
            ];
            let id = self.next_world;
            self.next_world += 1;
            Arc::new(World {
                id,
                scene,
                kernel,
                reference,
                exact_small,
                defined,
            })
        });
        self.set_busy(None);
        result
    }

    fn reset(&mut self, scene: Scene, subdivide: usize, params: FitParams) {
        if let Err(e) = params.validate() {
            self.report(e.to_string());
            return;
        }
        let world = match self.build_world(scene, subdivide, &params) {
            Ok(w) => w,
            Err(e) => return self.report(e),
        };
        match Fit::new(
            Arc::clone(&world.kernel),
            Arc::clone(&world.reference),
            params,
        ) {
            Ok(fit) => {
                self.fit = Some(fit);
                self.lit.history.clear();
                self.install(world);
            }
            Err(e) => self.report(e.to_string()),
        }
        self.running = false;
        self.steps_left = 0;
    }

    fn edit(&mut self, scene: Scene, subdivide: usize) {
        let Some(params) = self.fit.as_ref().map(|f| *f.params()) else {
            return;
        };
        let world = match self.build_world(scene, subdivide, &params) {
            Ok(w) => w,
            Err(e) => return self.report(e),
        };
        if let Some(fit) = &mut self.fit {
            fit.set_kernel(Arc::clone(&world.kernel), Arc::clone(&world.reference));
        }
        self.install(world);
    }

    fn install(&mut self, world: Arc<World>) {
        self.world = Some(Arc::clone(&world));
        self.summary = None;
        self.published_steps = None;
        self.approx_steps = None;
        self.lit.setup = None;
        self.lit.steps = None;
        let lit = if self.lit.enabled {
            LitState::Pending("solving the exact radiosity…")
        } else {
            LitState::Off
        };
        self.post(|m| {
            m.world = Some(world);
            m.approx = None;
            m.lit = Some(lit);
        });
        // A fit can stop before its first step (nothing to learn: `StopReason::Exact`).
        self.finish_if_stopped();
        self.publish(true);
    }

    /// Trains for at most one [`SLICE`], honouring the speed limit and pending single steps.
    fn train_slice(&mut self) {
        let Some(fit) = &mut self.fit else {
            return;
        };
        let now = Instant::now();
        let mut budget = if self.steps_left > 0 {
            self.steps_left
        } else if self.running {
            match self.speed {
                None => u64::MAX,
                Some(rate) => {
                    let dt = now.duration_since(self.last_tick).as_secs_f64();
                    self.allowance = (self.allowance + rate * dt).min(rate * 0.1);
                    self.allowance.floor() as u64
                }
            }
        } else {
            0
        };
        self.last_tick = now;
        if budget == 0 {
            if self.running && !self.lit_pending() {
                std::thread::sleep(Duration::from_millis(2));
            }
            return;
        }
        let start_steps = fit.steps();
        let mut stopped = None;
        while budget > 0 {
            let chunk = budget.min(256);
            for _ in 0..chunk {
                if let Some(reason) = fit.step() {
                    stopped = Some(reason);
                    break;
                }
            }
            budget -= chunk;
            if stopped.is_some() || now.elapsed() >= SLICE {
                break;
            }
        }
        let done = fit.steps() - start_steps;
        if self.steps_left > 0 {
            self.steps_left = self.steps_left.saturating_sub(done.max(1));
        } else if self.speed.is_some() {
            self.allowance -= done as f64;
        }
        if stopped.is_some() {
            self.running = false;
            self.steps_left = 0;
            // Publish the stop first: the refit can take seconds at 1000 cells.
            self.publish(true);
            self.finish_if_stopped();
            self.publish(true);
        }
    }

    /// The final errors (after the paper's refit) of a fit that has stopped, once per stop.
    fn finish_if_stopped(&mut self) {
        let Some(fit) = &mut self.fit else {
            return;
        };
        let Some(reason) = fit.stopped() else {
            return;
        };
        if self.summary.is_some() || reason == StopReason::Interrupted {
            return;
        }
        let refit = fit.head().refit().is_some();
        self.set_busy(Some(if refit {
            "least-squares refit of the output weights…"
        } else {
            "final errors…"
        }));
        let finished = self.fit.as_mut().map(Fit::finish);
        self.set_busy(None);
        match finished {
            Some(Ok(summary)) => self.summary = Some(summary),
            Some(Err(e)) => self.report(e.to_string()),
            None => {}
        }
        if refit {
            // The refit changed ζ̃.
            self.approx_steps = None;
            self.lit.steps = None;
        }
    }

    /// Publishes a snapshot (throttled unless `force`) and, less often, the approximation.
    fn publish(&mut self, force: bool) {
        let Some(fit) = &self.fit else {
            self.dirty = false; // nothing to show yet
            return;
        };
        let steps = fit.steps();
        let now = Instant::now();
        let (since, at, rate) = self.rate;
        if now.duration_since(since) >= Duration::from_secs(1) {
            let r = steps.saturating_sub(at) as f64 / now.duration_since(since).as_secs_f64();
            self.rate = (now, steps, r);
        }
        let busy = self.running || self.steps_left > 0;
        let changed = self.published_steps != Some(steps);
        let due = now.duration_since(self.last_publish) >= PUBLISH_EVERY;
        if force || (due && (changed || self.dirty)) {
            let status = Status {
                snapshot: Arc::new(fit.snapshot()),
                world: self.world.as_ref().map_or(0, |w| w.id),
                running: self.running,
                stopped: fit.stopped(),
                steps_per_s: if busy { self.rate.2.max(rate) } else { 0.0 },
                summary: self.summary.clone(),
                handled: self.handled,
                params: *fit.params(),
                occupied_faces: fit.model().occupied_faces(),
            };
            self.post(|m| m.status = Some(status));
            self.published_steps = Some(steps);
            self.last_publish = now;
            self.dirty = false;
        }
        let approx_due = now.duration_since(self.last_approx) >= APPROX_EVERY || !busy;
        if self.approx_steps != Some(steps)
            && approx_due
            && let Some(world) = &self.world
        {
            let model = fit.model().clone();
            let values = approx_grid(&model, APPROX_RES);
            let approx = Arc::new(Approx {
                world: world.id,
                steps,
                values,
                model,
            });
            self.post(|m| m.approx = Some(approx));
            self.approx_steps = Some(steps);
            self.last_approx = Instant::now();
        }
    }

    /// Whether the lit scene has work that is due now (so the loop must not sleep).
    fn lit_pending(&self) -> bool {
        let (Some(fit), Some(world)) = (&self.fit, &self.world) else {
            return false;
        };
        if !self.lit.enabled || self.lit.failed == Some(world.id) {
            return false;
        }
        let training = self.running || self.steps_left > 0;
        self.lit.setup.as_ref().is_none_or(|s| s.world != world.id)
            || (self.lit.steps != Some(fit.steps())
                && (!training || self.lit.last.elapsed() >= solve_interval(self.lit.cost)))
    }

    /// Makes the lit scene's setup for a new scene, then solves the learned kernel when a
    /// solve is due. Both give way to any waiting command and are taken up again after it.
    fn update_lit(&mut self) {
        if !self.lit_pending() {
            return;
        }
        let (Some(fit), Some(world)) = (&self.fit, &self.world) else {
            return;
        };
        let stop = self.command_waiting();
        let world_id = world.id;
        let setup = match &self.lit.setup {
            Some(s) if s.world == world_id => Arc::clone(s),
            _ => match LitSetup::build(world_id, &world.kernel, fit.params().target, &stop) {
                Ok(s) => {
                    let s = Arc::new(s);
                    self.lit.setup = Some(Arc::clone(&s));
                    s
                }
                Err(flatland_solve::SolveError::Interrupted) => return,
                Err(e) => {
                    self.lit.failed = Some(world_id);
                    let why = format!("no lit scene: {e}");
                    self.post(|m| m.lit = Some(LitState::Failed(why)));
                    return;
                }
            },
        };
        let Some(fit) = &self.fit else { return };
        let (steps, rays, cells) = (fit.steps(), fit.rays(), fit.network().len());
        let started = Instant::now();
        let solved = setup.solve(fit.model(), &stop);
        self.lit.last = Instant::now();
        self.lit.cost = started.elapsed();
        let state = match solved {
            Err(flatland_solve::SolveError::Interrupted) => return,
            Err(e) => LitState::Failed(format!("the learned kernel did not solve: {e}")),
            Ok(solve) => {
                if self.lit.history.last().is_none_or(|p| p.steps != steps) {
                    self.lit.history.push(LitPoint {
                        steps,
                        rays,
                        rel_l2_reflected: solve.errors.rel_l2_reflected,
                    });
                }
                LitState::Ready(Arc::new(Lit {
                    setup,
                    steps,
                    cells,
                    solve,
                    history: self.lit.history.clone(),
                }))
            }
        };
        self.lit.steps = Some(steps);
        self.post(|m| m.lit = Some(state));
    }
}

/// ζ̃ on the midpoint grid of resolution `res`, row-major, row ↔ s (in parallel).
#[must_use]
pub fn approx_grid(model: &LearnedKernel, res: usize) -> Vec<f64> {
    (0..res * res)
        .into_par_iter()
        .with_min_len(512)
        .map(|k| {
            let (s, t) = flatland_solve::grid_point(res, k);
            model.zeta(s, t)
        })
        .collect()
}

/// Both final errors, formatted; "undefined" where [`World::defined`] says so.
#[must_use]
pub fn format_errors(e: &Errors, defined: [bool; 2]) -> String {
    format!(
        "grid {}, held out {}",
        error_text(e.grid, defined[0]),
        error_text(e.heldout, defined[1])
    )
}

/// A relative error with three decimals, or "undefined".
#[must_use]
pub fn error_text(value: f64, defined: bool) -> String {
    if defined {
        format!("{value:.3}")
    } else {
        "undefined".to_owned()
    }
}
