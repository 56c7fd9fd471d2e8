//! The learner's thread. It owns the [`Fit`]; the UI talks to it with [`Command`]s and reads
//! what it publishes from a [`Mailbox`] with `try_lock`, so a frame never waits for training.
//! Each publication also wakes whoever waits for one ([`WorkerHandle::wait`]: tests, which wait
//! on what the learner says instead of sleeping), and every status says how many commands the
//! learner has handled, so the UI knows when it has caught up.
//!
//! Publishing is throttled: a [`Snapshot`] at most every [`PUBLISH_EVERY`], the learned ζ̃ on
//! the display grid at most every [`APPROX_EVERY`] (it costs `APPROX_RES²` network evaluations).

use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, TryRecvError};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use flatland_geom::{Kernel, Scene};
use kernel_fit::{
    Approximation, Errors, Fit, FitParams, FitSummary, LearnedKernel, Reference, Snapshot,
    StopReason,
};
use rayon::prelude::*;

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
    /// New parameters for the running fit.
    Params(FitParams),
    /// The scene changed (an end point was dragged): keep learning from the current state.
    Edit {
        /// The changed scene (not subdivided).
        scene: Scene,
        /// Pieces per surface edge.
        subdivide: usize,
    },
    /// Steps per second; `None` trains as fast as possible.
    Speed(Option<f64>),
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

    fn run(mut self) {
        loop {
            // Read every waiting command; sleep on the channel only when there is nothing to
            // train, and then not past the moment a pending status is due.
            let training = self.running || self.steps_left > 0;
            let first = if !training {
                let wait = if self.dirty {
                    PUBLISH_EVERY.saturating_sub(self.last_publish.elapsed())
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
            Command::Params(params) => {
                if let Some(fit) = &mut self.fit {
                    match fit.set_params(params) {
                        Ok(()) => self.summary = None,
                        Err(e) => self.report(e.to_string()),
                    }
                }
            }
            Command::Edit { scene, subdivide } => self.edit(scene, subdivide),
            Command::Sync => {}
        }
        self.dirty = true;
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
        self.post(|m| {
            m.world = Some(world);
            m.approx = None;
        });
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
            if self.running {
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
        if let Some(reason) = stopped {
            self.running = false;
            self.steps_left = 0;
            if self.summary.is_none() && reason != StopReason::Interrupted {
                // Publish the stop first: the refit can take seconds at 1000 cells.
                self.publish(true);
                self.set_busy(Some("least-squares refit of the output weights…"));
                let finished = self.fit.as_mut().map(Fit::finish);
                self.set_busy(None);
                match finished {
                    Some(Ok(summary)) => self.summary = Some(summary),
                    Some(Err(e)) => self.report(e.to_string()),
                    None => {}
                }
                self.approx_steps = None; // the refit changed ζ̃
            }
            self.publish(true);
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
}

/// ζ̃ on the midpoint grid of resolution `res`, row-major, row ↔ s (in parallel).
#[must_use]
pub fn approx_grid(model: &LearnedKernel, res: usize) -> Vec<f64> {
    (0..res * res)
        .into_par_iter()
        .with_min_len(512)
        .map(|k| {
            let (s, t) = kernel_fit::grid_point(res, k);
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
