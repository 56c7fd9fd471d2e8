//! The learner's loop: read commands, train a slice at the pace asked for, publish, start and
//! pick up the lit scene's solves. What runs is one [`Running`] learner: a network, trained
//! and paced in [`train`] and published in [`publish`], or the light-driven learner (rounds
//! instead of steps) in [`light`]. The lit scene (solved beside the learner, on a thread of its
//! own) is in [`lit`].

mod light;
mod lit;
mod publish;
mod train;

use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, RecvTimeoutError, TryRecvError};
use std::time::{Duration, Instant};

use flatland_geom::{Kernel, Scene};
use flatland_solve::Reference;
use kernel_fit::{Fit, FitParams, FitSummary, LiveParams, ModelFile, StopReason};

use super::published::{APPROX_RES, LitState, REFERENCE_RES, World};
use super::{Command, Mailbox, Shared};
use crate::learner::Learner;
use crate::lit::Integration;
use light::LightRun;
use lit::LitWork;
use publish::PublishState;
use train::Pace;

/// The learner running: the light-driven one round by round, or a network step by step.
pub(super) enum Running {
    /// The light-driven learner ([`flatland_light::LightFit`]) and how much of it was shown.
    Light(Box<LightRun>),
    /// A network: the visibility network or the paper's (its parameters say which).
    Network(Box<Fit>),
}

impl Running {
    /// How the lit view integrates what this learner learned: exactly (the light-driven
    /// learner's rows, a network of V), or by quadrature of ζ̃ (a network of ζ or k).
    fn integration(&self) -> Integration {
        match self {
            Running::Light(_) => Integration::Exact,
            Running::Network(fit) => Integration::of_target(fit.params().target),
        }
    }
}

/// The thread's state: the running learner, the scene's world, what was last published.
pub(super) struct LearnerThread {
    rx: Receiver<Command>,
    shared: Arc<Shared>,
    repaint: Box<dyn Fn() + Send>,
    /// The learner running (`None` before the first reset, or after it failed to start).
    learning: Option<Running>,
    world: Option<Arc<World>>,
    next_world: u64,
    running: bool,
    steps_left: u64,
    pace: Pace,
    last_tick: Instant,
    /// Time spent training since the fit started (the timeline's clock).
    run_time: Duration,
    summary: Option<FitSummary>,
    /// A command changed something a status shows: publish one as soon as it is due.
    dirty: bool,
    handled: u64,
    published: PublishState,
    /// The kernel plot's resolution on screen (0 until the UI says).
    plot_res: usize,
    lit: LitWork,
}

impl LearnerThread {
    pub(super) fn new(
        rx: Receiver<Command>,
        shared: Arc<Shared>,
        repaint: Box<dyn Fn() + Send>,
    ) -> Self {
        let now = Instant::now();
        LearnerThread {
            rx,
            shared,
            repaint,
            learning: None,
            world: None,
            next_world: 1,
            running: false,
            steps_left: 0,
            pace: Pace::default(),
            last_tick: now,
            run_time: Duration::ZERO,
            summary: None,
            dirty: false,
            handled: 0,
            published: PublishState::new(now),
            plot_res: 0,
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

    /// The network, when one is running.
    fn fit(&self) -> Option<&Fit> {
        match &self.learning {
            Some(Running::Network(fit)) => Some(fit),
            _ => None,
        }
    }

    /// Whether it trains now (continuously, or steps asked for).
    fn training(&self) -> bool {
        self.running || self.steps_left > 0
    }

    pub(super) fn run(mut self) {
        loop {
            // Read every waiting command; sleep on the channel only when there is nothing to
            // train, and then not past the moment a pending status is due.
            let first = if !self.training() {
                match self.rx.recv_timeout(self.idle_wait()) {
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
            self.light_slice();
            self.publish(false);
            self.publish_light(false);
            self.publish_kernel_grid();
            self.update_lit();
        }
    }

    /// How long an idle learner may sleep on the channel.
    fn idle_wait(&self) -> Duration {
        if self.dirty {
            publish::PUBLISH_EVERY.saturating_sub(self.published.since_last())
        } else if self.lit_pending() {
            Duration::ZERO
        } else if self.lit.busy() {
            lit::LIT_POLL
        } else {
            Duration::from_millis(200)
        }
    }

    fn handle(&mut self, command: Command) {
        self.handled += 1;
        match command {
            Command::Play => {
                self.running = true;
                if let Some(Running::Light(run)) = &mut self.learning {
                    run.resume();
                }
                self.last_tick = Instant::now();
                self.pace.restart();
            }
            Command::Pause => {
                self.running = false;
                self.steps_left = 0;
            }
            Command::Step(n) => {
                self.running = false;
                self.steps_left = self.steps_left.saturating_add(n);
                self.last_tick = Instant::now();
            }
            Command::Pace(per_s) => self.pace.set(per_s),
            Command::Reset {
                scene,
                subdivide,
                learner,
                params,
            } => self.reset(scene, subdivide, learner, params),
            Command::Params(params) => self.set_params(params),
            Command::Edit { scene, subdivide } => self.edit(scene, subdivide),
            Command::Lit(on) => self.switch_lit(on),
            Command::PlotResolution(res) => self.plot_res = res,
            Command::ExportModel { dir, stem } => self.export_model(&dir, &stem),
            Command::Sync => {}
        }
        self.dirty = true;
    }

    fn set_params(&mut self, live: LiveParams) {
        let Some(Running::Network(fit)) = &mut self.learning else {
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

    /// Saves the running fit (its model as it is now, with the final errors if it finished) as
    /// the model file `flatland eval` reads.
    fn export_model(&self, dir: &Path, stem: &str) {
        let fit = match &self.learning {
            Some(Running::Network(fit)) => fit,
            Some(Running::Light(_)) => {
                return self.report(format!(
                    "the {} keeps no network: its model is the mesh's rows (choose the {} or \
                     the {} to save a model file)",
                    Learner::Light.title(),
                    Learner::Visibility.title(),
                    Learner::Paper.title()
                ));
            }
            None => return self.report("no fit to save yet".into()),
        };
        let path = dir.join(format!("{stem}-step{}.model.json", fit.steps()));
        let file = ModelFile::new(fit.model().clone(), *fit.params(), self.summary.clone());
        match file.save(&path) {
            Ok(()) => {
                let note = format!("saved the model to {}", path.display());
                self.post(|m| m.note = Some(note));
            }
            Err(e) => self.report(format!("could not save the model: {e}")),
        }
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

    /// Starts `learner` afresh on `scene`; a bad parameter or scene is reported and what runs
    /// goes on.
    fn reset(&mut self, scene: Scene, subdivide: usize, learner: Learner, params: FitParams) {
        if let Err(e) = params.validate() {
            self.report(e.to_string());
            return;
        }
        let world = match self.build_world(scene, subdivide, &params) {
            Ok(w) => w,
            Err(e) => return self.report(e),
        };
        self.running = false;
        self.steps_left = 0;
        let running = match learner {
            // Its fit is made on the lit view's mesh, once that is there (`light_slice`).
            Learner::Light => Running::Light(Box::new(LightRun::new(params))),
            Learner::Visibility | Learner::Paper => match Fit::new(
                Arc::clone(&world.kernel),
                Arc::clone(&world.reference),
                params,
            ) {
                Ok(fit) => Running::Network(Box::new(fit)),
                Err(e) => return self.report(e.to_string()),
            },
        };
        self.learning = Some(running);
        self.run_time = Duration::ZERO;
        self.lit.history.clear();
        self.install(world);
    }

    fn edit(&mut self, scene: Scene, subdivide: usize) {
        let params = match &self.learning {
            Some(Running::Light(run)) => {
                // Its rows belong to the old mesh: a fresh run on the changed scene.
                let (params, running) = (run.params, self.running);
                self.reset(scene, subdivide, Learner::Light, params);
                self.running = running;
                return;
            }
            Some(Running::Network(fit)) => *fit.params(),
            None => return,
        };
        let world = match self.build_world(scene, subdivide, &params) {
            Ok(w) => w,
            Err(e) => return self.report(e),
        };
        if let Some(Running::Network(fit)) = &mut self.learning {
            fit.set_kernel(Arc::clone(&world.kernel), Arc::clone(&world.reference));
        }
        self.install(world);
    }

    fn install(&mut self, world: Arc<World>) {
        self.world = Some(Arc::clone(&world));
        self.summary = None;
        self.published.forget();
        self.lit.forget_setup();
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
        self.publish_light(true);
    }

    /// The final errors (after the paper's refit) of a fit that has stopped, once per stop.
    fn finish_if_stopped(&mut self) {
        let Some(fit) = self.fit() else {
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
        let finished = match &mut self.learning {
            Some(Running::Network(fit)) => Some(fit.finish()),
            _ => None,
        };
        self.set_busy(None);
        match finished {
            Some(Ok(summary)) => self.summary = Some(summary),
            Some(Err(e)) => self.report(e.to_string()),
            None => {}
        }
        if refit {
            // The refit changed ζ̃.
            self.published.approx_stale();
            self.lit.solve_again();
        }
    }
}
