//! Training a network in slices at a pace of cells per second.
//!
//! Why a pace of growth and not of steps: how many steps make a cell depends on the learner
//! (λ, stalls, resampling) and how fast a step runs on the machine; on a fast machine the
//! visibility network is exact on a small scene in a fraction of a second, over before the
//! window shows it. So the learner trains freely between insertions, and an insertion waits for its
//! credit: cells appear at the pace asked for on any machine fast enough, and as fast as the
//! machine goes on a slower one. Training without growth (the last growth period, a stall
//! before convergence) is not slowed.

use std::time::{Duration, Instant};

use super::{LearnerThread, Running};

/// Longest uninterrupted training slice: commands are read at least this often.
const SLICE: Duration = Duration::from_millis(15);
/// Most credit saved up, in seconds of growth: after a stall (a lit solve), growth catches up
/// this much.
const MAX_CREDIT_S: f64 = 1.0;
/// Time constant of the average of how much the learner waits for the pace.
const IDLE_MEMORY: Duration = Duration::from_secs(2);
/// How long a learner that waits for credit sleeps before it looks again.
const WAIT: Duration = Duration::from_millis(2);

/// How fast the network may grow.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Pace {
    /// Cells per second of training; `None`: as fast as the machine goes.
    per_s: Option<f64>,
    /// Cells that may be inserted now.
    credit: f64,
    /// Recent time spent training and waiting for credit (decaying sums), seconds.
    trained: f64,
    waited: f64,
}

impl Pace {
    /// Another pace (`None` or a non-positive rate: unlimited).
    pub(super) fn set(&mut self, per_s: Option<f64>) {
        self.per_s = per_s.filter(|r| *r > 0.0 && r.is_finite());
        self.credit = self.credit.min(self.max_credit());
    }

    /// Cells per second; `None`: as fast as the machine goes.
    pub(super) fn per_s(&self) -> Option<f64> {
        self.per_s
    }

    /// Training starts (again): one cell may come at once.
    pub(super) fn restart(&mut self) {
        self.credit = 1.0;
    }

    fn max_credit(&self) -> f64 {
        self.per_s
            .map_or(f64::INFINITY, |r| (r * MAX_CREDIT_S).max(1.0))
    }

    /// Credit for `dt` of training.
    pub(super) fn tick(&mut self, dt: Duration) {
        if let Some(r) = self.per_s {
            self.credit = (self.credit + r * dt.as_secs_f64()).min(self.max_credit());
        }
    }

    /// Whether the next step may run: it might insert a cell.
    pub(super) fn may_grow(&self) -> bool {
        self.per_s.is_none() || self.credit >= 1.0
    }

    /// `cells` were inserted.
    pub(super) fn grew(&mut self, cells: usize) {
        if self.per_s.is_some() {
            self.credit -= cells as f64;
        }
    }

    /// A slice trained for `trained` and waited for credit for `waited`.
    pub(super) fn record(&mut self, trained: Duration, waited: Duration) {
        let (t, w) = (trained.as_secs_f64(), waited.as_secs_f64());
        let keep = (-(t + w) / IDLE_MEMORY.as_secs_f64()).exp();
        self.trained = self.trained * keep + t;
        self.waited = self.waited * keep + w;
    }

    /// The share of its recent time the learner spent waiting for credit (0 without a pace):
    /// time the lit scene may use.
    pub(super) fn idle_share(&self) -> f64 {
        let all = self.trained + self.waited;
        if self.per_s.is_none() || all <= 0.0 {
            0.0
        } else {
            self.waited / all
        }
    }
}

impl LearnerThread {
    /// Trains for at most one [`SLICE`]: pending single steps, or continuously at the pace.
    pub(super) fn train_slice(&mut self) {
        let now = Instant::now();
        let dt = now.duration_since(self.last_tick);
        self.last_tick = now;
        if !self.training() {
            return;
        }
        self.run_time += dt;
        let Some(Running::Network(fit)) = &mut self.learning else {
            return;
        };
        let stepping = self.steps_left > 0;
        if !stepping {
            self.pace.tick(dt);
        }
        let start_steps = fit.steps();
        let mut stopped = None;
        let mut cells = fit.network().len();
        loop {
            if !stepping && !self.pace.may_grow() {
                break;
            }
            if stepping && fit.steps() - start_steps >= self.steps_left {
                break;
            }
            if let Some(reason) = fit.step() {
                stopped = Some(reason);
                break;
            }
            let now_cells = fit.network().len();
            if now_cells > cells {
                self.pace.grew(now_cells - cells);
                cells = now_cells;
            }
            if (fit.steps() - start_steps).is_multiple_of(64) && now.elapsed() >= SLICE {
                break;
            }
        }
        let done = fit.steps() - start_steps;
        if stepping {
            self.steps_left = self.steps_left.saturating_sub(done.max(1));
        } else if done == 0 {
            // Waiting for the pace: the lit scene may have the time, else the other core.
            if !self.lit_pending() {
                std::thread::sleep(WAIT);
            }
            self.pace.record(Duration::ZERO, now.elapsed());
        } else {
            // No rest at full speed: in a window the learner runs at the lowest priority
            // (`crate::background`), so it only takes what the window leaves.
            self.pace.record(now.elapsed(), Duration::ZERO);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn growth_waits_for_credit_at_the_pace_asked_for() {
        let mut pace = Pace::default();
        assert!(pace.may_grow(), "unlimited by default");
        pace.set(Some(10.0));
        pace.restart();
        assert!(pace.may_grow(), "one cell at once");
        pace.grew(1);
        assert!(!pace.may_grow());
        pace.tick(Duration::from_millis(50));
        assert!(!pace.may_grow(), "half a cell of credit");
        pace.tick(Duration::from_millis(60));
        assert!(pace.may_grow());
        // Credit saved up is bounded: after a long stall at most a second's growth.
        pace.tick(Duration::from_secs(60));
        pace.grew(9);
        assert!(pace.may_grow(), "1 cell left");
        pace.grew(1);
        assert!(!pace.may_grow(), "10 cells of credit at most");
        pace.set(None);
        assert!(pace.may_grow());
        pace.set(Some(0.0));
        assert!(pace.may_grow(), "a zero rate means unlimited, not stopped");
    }

    #[test]
    fn the_idle_share_is_the_recent_time_spent_waiting() {
        let mut pace = Pace::default();
        pace.record(Duration::from_millis(10), Duration::from_millis(90));
        assert_eq!(pace.idle_share(), 0.0, "no pace, no waiting");
        pace.set(Some(20.0));
        assert_close!(pace.idle_share(), 0.9, 1e-9);
        // Training flat out for a few seconds: the waiting is forgotten.
        for _ in 0..100 {
            pace.record(Duration::from_millis(100), Duration::ZERO);
        }
        assert!(pace.idle_share() < 0.01, "{}", pace.idle_share());
    }
}
