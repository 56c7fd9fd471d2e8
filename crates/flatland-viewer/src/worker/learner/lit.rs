//! The learner's side of the lit scene: the setup of each scene once, then a solve of the
//! learned kernel whenever [`crate::lit`] says one is due. Both give way to any waiting command
//! and are taken up again after it.

use std::sync::Arc;
use std::time::{Duration, Instant};

use super::Learner;
use crate::lit::{LitPoint, LitSetup, solve_interval};
use crate::worker::published::{Lit, LitState};

/// What the lit scene needs between solves.
pub(super) struct LitWork {
    pub(super) enabled: bool,
    /// The mesh and exact B of the current world, once made.
    setup: Option<Arc<LitSetup>>,
    /// The world whose setup failed (not retried until the scene changes).
    failed: Option<u64>,
    /// Steps of the model last solved (`None`: solve again whatever the steps).
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
            failed: None,
            steps: None,
            last: now,
            cost: Duration::ZERO,
            history: Vec::new(),
        }
    }

    /// A new world: its setup is made again.
    pub(super) fn forget_setup(&mut self) {
        self.setup = None;
        self.steps = None;
    }

    /// The model changed without a step (the refit): solve it again.
    pub(super) fn solve_again(&mut self) {
        self.steps = None;
    }
}

impl Learner {
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

    /// Whether the lit scene has work that is due now (so the loop must not sleep).
    pub(super) fn lit_pending(&self) -> bool {
        let (Some(fit), Some(world)) = (&self.fit, &self.world) else {
            return false;
        };
        if !self.lit.enabled || self.lit.failed == Some(world.id) {
            return false;
        }
        self.lit.setup.as_ref().is_none_or(|s| s.world != world.id)
            || (self.lit.steps != Some(fit.steps())
                && (!self.training()
                    || self.lit.last.elapsed()
                        >= solve_interval(self.lit.cost, self.pace.idle_share())))
    }

    /// The setup of the current world, made if missing; `None` when interrupted or failed
    /// (then said in the mailbox).
    fn lit_setup(&mut self) -> Option<Arc<LitSetup>> {
        let (fit, world) = (self.fit.as_ref()?, self.world.as_ref()?);
        if let Some(s) = &self.lit.setup
            && s.world == world.id
        {
            return Some(Arc::clone(s));
        }
        let stop = self.command_waiting();
        match LitSetup::build(world.id, &world.kernel, fit.params().target, &stop) {
            Ok(s) => {
                let s = Arc::new(s);
                self.lit.setup = Some(Arc::clone(&s));
                Some(s)
            }
            Err(flatland_solve::SolveError::Interrupted) => None,
            Err(e) => {
                self.lit.failed = Some(world.id);
                let why = format!("no lit scene: {e}");
                self.post(|m| m.lit = Some(LitState::Failed(why)));
                None
            }
        }
    }

    /// Makes the lit scene's setup for a new scene, then solves the learned kernel when a
    /// solve is due.
    pub(super) fn update_lit(&mut self) {
        if !self.lit_pending() {
            return;
        }
        let Some(setup) = self.lit_setup() else {
            return;
        };
        let Some(fit) = &self.fit else { return };
        let stop = self.command_waiting();
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
