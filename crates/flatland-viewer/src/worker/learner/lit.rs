//! The learner's side of the lit scene: the setup of each scene once, then a solve of the
//! learned kernel whenever [`crate::lit`] says one is due — both beside the learner, on a
//! thread of their own with one core, picked up when done.
//!
//! On the learner's thread they would stop growth while they run: the setup is an exact solve
//! on a mesh four times finer (10–40 s on a floor plan of 1100 edges), and a solve of the
//! learned kernel takes 0.3–1 s on a floor plan of 220 edges but a minute on one of 1100.
//! One core, so that the learner and the window keep the other.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use flatland_solve::{SolveError, Stop};

use super::{LearnerThread, Running};
use crate::lit::{LitPoint, LitSetup, LitSolve, solve_interval};
use crate::worker::published::{Lit, LitState};

/// How often an idle learner looks whether the lit scene's work is done.
pub(super) const LIT_POLL: Duration = Duration::from_millis(50);

/// Work running on a thread of its own; dropping it stops that work.
struct Background<T> {
    cancel: Arc<AtomicBool>,
    result: Arc<Mutex<Option<T>>>,
}

impl<T: Send + 'static> Background<T> {
    /// Starts `work` on a pool of one thread (its parallel loops stay on that thread).
    fn start(work: impl FnOnce(&Stop) -> T + Send + 'static) -> Background<T> {
        let cancel = Arc::new(AtomicBool::new(false));
        let result = Arc::new(Mutex::new(None));
        let (stop, slot) = (Arc::clone(&cancel), Arc::clone(&result));
        std::thread::spawn(move || {
            let stopped = move || stop.load(Ordering::Relaxed);
            let run = || work(&stopped);
            let made = match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                Ok(pool) => pool.install(run),
                Err(_) => run(),
            };
            if let Ok(mut slot) = slot.lock() {
                *slot = Some(made);
            }
        });
        Background { cancel, result }
    }

    fn done(&self) -> bool {
        self.result.lock().is_ok_and(|r| r.is_some())
    }

    fn take(&self) -> Option<T> {
        self.result.lock().ok()?.take()
    }
}

impl<T> Drop for Background<T> {
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

/// A solve of the learned kernel under way: of which model, and since when.
struct Solving {
    setup: Arc<LitSetup>,
    steps: u64,
    rays: u64,
    cells: usize,
    started: Instant,
    work: Background<Result<LitSolve, SolveError>>,
}

/// What the lit scene needs between solves.
pub(super) struct LitWork {
    pub(super) enabled: bool,
    /// The mesh and exact B of the current world, once made.
    setup: Option<Arc<LitSetup>>,
    /// The setup being made, and its world.
    building: Option<(u64, Background<Result<LitSetup, SolveError>>)>,
    /// The solve under way.
    solving: Option<Solving>,
    /// The world whose setup failed (not retried until the scene changes).
    failed: Option<u64>,
    /// Steps of the model last solved or being solved (`None`: solve again whatever the steps).
    steps: Option<u64>,
    /// When the last solve ended, and what it cost.
    last: Instant,
    cost: Duration,
    pub(super) history: Vec<LitPoint>,
}

impl LitWork {
    pub(super) fn new(now: Instant) -> LitWork {
        LitWork {
            enabled: true,
            setup: None,
            building: None,
            solving: None,
            failed: None,
            steps: None,
            last: now,
            cost: Duration::ZERO,
            history: Vec::new(),
        }
    }

    /// A new world: its setup is made again (work for the old one stops).
    pub(super) fn forget_setup(&mut self) {
        self.setup = None;
        self.building = None;
        self.solving = None;
        self.steps = None;
    }

    /// Whether work runs beside the learner and is not done yet.
    pub(super) fn busy(&self) -> bool {
        self.building.as_ref().is_some_and(|(_, b)| !b.done())
            || self.solving.as_ref().is_some_and(|s| !s.work.done())
    }

    /// Whether work beside the learner is done and waits to be picked up.
    fn finished(&self) -> bool {
        self.building.as_ref().is_some_and(|(_, b)| b.done())
            || self.solving.as_ref().is_some_and(|s| s.work.done())
    }

    /// The current setup, if made.
    pub(super) fn setup(&self) -> Option<Arc<LitSetup>> {
        self.setup.clone()
    }

    /// The model changed without a step (the refit): solve it again.
    pub(super) fn solve_again(&mut self) {
        self.steps = None;
    }
}

impl LearnerThread {
    pub(super) fn switch_lit(&mut self, on: bool) {
        self.lit.enabled = on;
        self.lit.steps = None;
        let state = if on {
            LitState::Pending("solving the radiosity…")
        } else {
            LitState::Off
        };
        self.post(|m| m.lit = Some(state));
    }

    /// Whether the lit scene has work that is due now (so the loop must not sleep): work done
    /// beside the learner to pick up, a setup to start, or a solve.
    pub(super) fn lit_pending(&self) -> bool {
        let fit = match &self.learning {
            Some(Running::Network(fit)) => fit,
            Some(Running::Light(_)) => return self.light_setup_pending(),
            None => return false,
        };
        let Some(world) = &self.world else {
            return false;
        };
        if !self.lit.enabled || self.lit.failed == Some(world.id) {
            return false;
        }
        if self.lit.finished() {
            return true;
        }
        if self.lit.busy() {
            return false;
        }
        self.lit.setup.as_ref().is_none_or(|s| s.world != world.id)
            || (self.lit.steps != Some(fit.steps())
                && (!self.training()
                    || self.lit.last.elapsed()
                        >= solve_interval(self.lit.cost, self.pace.idle_share())))
    }

    /// Whether the light-driven learner's setup (its mesh and the exact `B`, needed whether or
    /// not the lit view is on) is to be started or picked up.
    fn light_setup_pending(&self) -> bool {
        let Some(world) = &self.world else {
            return false;
        };
        self.lit.failed != Some(world.id)
            && (self.lit.finished()
                || (!self.lit.busy()
                    && self.lit.setup.as_ref().is_none_or(|s| s.world != world.id)))
    }

    /// The setup of the current world once made; `None` while it is being made (started if
    /// it is not) or when it failed (then said in the mailbox).
    pub(super) fn lit_setup(&mut self) -> Option<Arc<LitSetup>> {
        let world = self.world.as_ref()?;
        let integration = self.learning.as_ref()?.integration();
        if let Some(s) = &self.lit.setup
            && s.world == world.id
        {
            return Some(Arc::clone(s));
        }
        let made = match &self.lit.building {
            Some((w, b)) if *w == world.id => b.take()?,
            _ => {
                let (id, kernel) = (world.id, Arc::clone(&world.kernel));
                let work =
                    Background::start(move |stop| LitSetup::build(id, kernel, integration, stop));
                self.lit.building = Some((id, work));
                return None;
            }
        };
        self.lit.building = None;
        match made {
            Ok(s) => {
                let s = Arc::new(s);
                self.lit.setup = Some(Arc::clone(&s));
                self.post(|m| m.lit = Some(LitState::Pending("solving the learned kernel…")));
                Some(s)
            }
            Err(e) => {
                self.lit.failed = Some(world.id);
                let why = format!("no lit scene: {e}");
                self.post(|m| m.lit = Some(LitState::Failed(why)));
                None
            }
        }
    }

    /// Picks up a finished setup or solve, and starts what is due next: the setup for a new
    /// scene, or a solve of the model as it is now.
    pub(super) fn update_lit(&mut self) {
        if !self.lit_pending() {
            return;
        }
        self.take_solve();
        let Some(setup) = self.lit_setup() else {
            return;
        };
        let Some(Running::Network(fit)) = &self.learning else {
            return;
        };
        if self.lit.solving.is_some() || self.lit.steps == Some(fit.steps()) {
            return;
        }
        let model = fit.model().clone();
        let on = Arc::clone(&setup);
        self.lit.steps = Some(fit.steps());
        self.lit.solving = Some(Solving {
            setup,
            steps: fit.steps(),
            rays: fit.rays(),
            cells: fit.network().len(),
            started: Instant::now(),
            work: Background::start(move |stop| on.solve(&model, stop)),
        });
    }

    /// Publishes a finished solve as the lit scene, with its point on the error curve.
    fn take_solve(&mut self) {
        let Some(solved) = self.lit.solving.as_ref().and_then(|s| s.work.take()) else {
            return;
        };
        let Some(Solving {
            setup,
            steps,
            rays,
            cells,
            started,
            ..
        }) = self.lit.solving.take()
        else {
            return;
        };
        self.lit.last = Instant::now();
        self.lit.cost = started.elapsed();
        let state = match solved {
            Err(SolveError::Interrupted) => return,
            Err(e) => LitState::Failed(format!("the learned kernel did not solve: {e}")),
            Ok(solve) => {
                if self.lit.history.last().is_none_or(|p| p.steps != steps) {
                    self.lit.history.push(LitPoint {
                        steps,
                        rays,
                        cells,
                        rel_l2_reflected: solve.errors.rel_l2_reflected,
                        estimated: None,
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
        self.post(|m| m.lit = Some(state));
    }
}
