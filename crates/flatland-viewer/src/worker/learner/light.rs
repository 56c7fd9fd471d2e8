//! The light-driven learner ([`flatland_light::LightFit`], docs/ALGORITHM.md §4a) on the learner's
//! thread: rounds on the lit view's mesh, each published with its lit `B`, its estimated and
//! measured error, and its new cells revealed over time.
//!
//! Why the cells of a round are revealed over time: a round is a solve and a batch of probes,
//! and on the default floor plan the loop meets its tolerance in 4 rounds and under 0.2 s —
//! over before the window has drawn its first frame. So a round's new cells appear in the
//! order they were learned, at the pace of growth asked for but never slower than the whole
//! round in [`ROUND_SECONDS`] of wall time (rounds double in size, so a fixed pace would make
//! the last rounds last minutes); the next round runs once they are all shown. Most cells
//! come in one round (about 400 of 430 there): at 2 s a round, the whole run was shown in 3 s
//! and screenshots at 6 s and 12 s were the same picture. The lit scene
//! changes with each round's solve. With no pace ("max") rounds run as fast as they come.

use std::sync::Arc;
use std::time::{Duration, Instant};

use flatland_light::{LightFit, LightParams, LightStop};
use flatland_solve::{Representation, solve_errors};
use kernel_fit::FitParams;
use rayon::prelude::*;

use super::{LearnerThread, Running};
use crate::lit::{LitPoint, LitSolve};
use crate::prefix::Prefix;
use crate::worker::published::{
    APPROX_RES, Approx, CellMark, Growth, LearnedGrid, Lit, LitState, Progress, Status,
};

/// Longest a round's new cells take to appear, in seconds of wall time.
pub const ROUND_SECONDS: f64 = 8.0;
/// How long a learner revealing cells sleeps between looks (it publishes every 50 ms).
const REVEAL_WAIT: Duration = Duration::from_millis(10);

/// The light-driven learner and how much of it the user has seen.
pub(in crate::worker) struct LightRun {
    /// The fit, once the lit view's mesh is made (it learns on that mesh).
    fit: Option<LightFit>,
    /// The network parameters the user had, kept for the status (and a switch back).
    pub(super) params: FitParams,
    /// Probes shown so far (the first ones of `fit.cells()`).
    shown: usize,
    /// Cells before the newest round: from here on they are the newest round's.
    newest_from: usize,
    /// When the newest round's reveal started, and how many cells per second it shows.
    reveal: (Instant, f64),
    /// Cells as published, shared by the statuses (cells are only ever added).
    marks: Vec<CellMark>,
    history: Vec<LitPoint>,
    /// The cells shown when a status was last published.
    published: Option<usize>,
    /// The cells shown when ζ̃ was last published.
    approx_at: Option<usize>,
}

impl LightRun {
    pub(super) fn new(params: FitParams) -> LightRun {
        LightRun {
            fit: None,
            params,
            shown: 0,
            newest_from: 0,
            reveal: (Instant::now(), f64::INFINITY),
            marks: Vec::new(),
            history: Vec::new(),
            published: None,
            approx_at: None,
        }
    }

    /// Training goes on after a pause: the reveal picks up where it was, instead of showing at
    /// once every cell that would have appeared meanwhile.
    pub(super) fn resume(&mut self) {
        let (_, rate) = self.reveal;
        if rate.is_finite() && rate > 0.0 {
            let done = (self.shown - self.newest_from) as f64 / rate;
            let now = Instant::now();
            self.reveal.0 = now
                .checked_sub(Duration::from_secs_f64(done))
                .unwrap_or(now);
        }
    }

    /// Why it stopped, once it has (and every cell is shown).
    pub(super) fn stopped(&self) -> Option<LightStop> {
        let fit = self.fit.as_ref()?;
        fit.stopped().filter(|_| self.shown == fit.cells().len())
    }
}

/// Probe `id` of `fit` as the overlay draws it: its column of what it sees, and a disc in the
/// middle of the longest stretch seen.
fn mark(fit: &LightFit, id: usize, t: f64) -> CellMark {
    let seen: Vec<[f32; 2]> = fit
        .seen(id)
        .iter()
        .map(|&[s0, s1]| [s0 as f32, s1 as f32])
        .collect();
    let s = seen
        .iter()
        .max_by(|a, b| (a[1] - a[0]).total_cmp(&(b[1] - b[0])))
        .map_or(0.5, |[s0, s1]| 0.5 * (s0 + s1));
    CellMark {
        st: Some([s, t as f32]),
        width: 0.0,
        critical: false,
        seen: seen.into(),
    }
}

impl LearnerThread {
    /// The light-driven learner, when it is the one running.
    fn light_run(&self) -> Option<&LightRun> {
        match &self.learning {
            Some(Running::Light(run)) => Some(run),
            _ => None,
        }
    }

    /// One slice of the light-driven learner: make the fit once the mesh is there, reveal the
    /// newest round's cells, or run the next round.
    pub(super) fn light_slice(&mut self) {
        let Some(run) = self.light_run() else { return };
        if !self.training() {
            return;
        }
        if run.fit.is_none() && !self.make_light_fit() {
            std::thread::sleep(REVEAL_WAIT);
            return;
        }
        let stepping = self.steps_left > 0;
        let per_s = self.pace.per_s();
        let Some(Running::Light(run)) = &mut self.learning else {
            return;
        };
        let Some(fit) = &mut run.fit else { return };
        let learned = fit.cells().len();
        if run.shown < learned {
            let (since, rate) = run.reveal;
            let due = run.newest_from + (since.elapsed().as_secs_f64() * rate) as usize;
            run.shown = if stepping { learned } else { due.min(learned) };
            let cells = fit.cells();
            let new: Vec<CellMark> = (run.marks.len()..run.shown)
                .map(|id| mark(fit, id, cells[id].t))
                .collect();
            run.marks.extend(new);
            if run.shown < learned {
                std::thread::sleep(REVEAL_WAIT);
            }
            return;
        }
        if fit.stopped().is_some() {
            self.running = false;
            self.steps_left = 0;
            self.publish_light_approx();
            self.publish_light(true);
            return;
        }
        // Every cell learned so far is shown: ζ̃ with them all, then the next round.
        self.publish_light_approx();
        let Some(Running::Light(run)) = &mut self.learning else {
            return;
        };
        let Some(fit) = &mut run.fit else { return };
        let started = Instant::now();
        match fit.round(&|| false) {
            Ok(_) => {}
            Err(e) => {
                self.running = false;
                return self.report(format!("the light-driven round failed: {e}"));
            }
        }
        let now_learned = fit.cells().len();
        run.newest_from = run.shown;
        let rate = match per_s {
            Some(r) if !stepping => r.max((now_learned - run.shown) as f64 / ROUND_SECONDS),
            // A step, or no pace: the round's cells at once.
            _ => f64::INFINITY,
        };
        run.reveal = (Instant::now(), rate);
        if rate.is_infinite() {
            run.shown = now_learned;
            let cells = fit.cells();
            let new: Vec<CellMark> = (run.marks.len()..cells.len())
                .map(|id| mark(fit, id, cells[id].t))
                .collect();
            run.marks.extend(new);
        }
        self.steps_left = self.steps_left.saturating_sub(1);
        self.publish_round(started.elapsed());
    }

    /// Makes the fit on the lit view's mesh once its setup is there; whether it is.
    fn make_light_fit(&mut self) -> bool {
        let Some(setup) = self.lit_setup() else {
            return false;
        };
        let Some(world) = &self.world else {
            return false;
        };
        let made = LightFit::new(
            Arc::clone(&world.kernel),
            setup.mesh().clone(),
            LightParams::default(),
        );
        match made {
            Ok(fit) => {
                if let Some(Running::Light(run)) = &mut self.learning {
                    run.fit = Some(fit);
                }
                true
            }
            Err(e) => {
                self.learning = None;
                self.running = false;
                self.report(format!("the light-driven learner did not start: {e}"));
                false
            }
        }
    }

    /// The learned ζ̃ on the display grid, with every cell learned so far (once per cell
    /// count).
    fn publish_light_approx(&mut self) {
        let (Some(Running::Light(run)), Some(world)) = (&mut self.learning, &self.world) else {
            return;
        };
        let Some(fit) = &run.fit else { return };
        let steps = fit.history().len() as u64;
        if run.approx_at == Some(run.shown) {
            return;
        }
        run.approx_at = Some(run.shown);
        let values = (0..APPROX_RES * APPROX_RES)
            .into_par_iter()
            .with_min_len(512)
            .map(|k| {
                let (s, t) = flatland_solve::grid_point(APPROX_RES, k);
                fit.zeta(s, t)
            })
            .collect();
        let approx = Arc::new(Approx {
            grid: Arc::new(LearnedGrid {
                world: world.id,
                steps,
                values,
            }),
            model: None,
        });
        self.post(|m| m.approx = Some(approx));
    }

    /// Publishes the lit scene of the round just solved, with its point on the error curves.
    fn publish_round(&mut self, cost: Duration) {
        let Some(setup) = self
            .lit
            .setup()
            .filter(|s| self.world.as_ref().is_some_and(|w| w.id == s.world))
        else {
            return;
        };
        let Some(Running::Light(run)) = &mut self.learning else {
            return;
        };
        let Some(fit) = &run.fit else { return };
        let b = fit.radiosity().to_vec();
        let errors = solve_errors(setup.mesh(), &b, setup.exact());
        let rounds = fit.history().len();
        run.history.push(LitPoint {
            steps: rounds as u64,
            rays: 0,
            cells: run.shown,
            rel_l2_reflected: errors.rel_l2_reflected,
            estimated: fit.estimated_error(),
        });
        let lit = Lit {
            setup,
            steps: rounds as u64,
            cells: run.shown,
            solve: LitSolve {
                b,
                errors,
                solve_s: cost.as_secs_f64(),
            },
            history: run.history.clone(),
        };
        if self.lit.enabled {
            self.post(|m| m.lit = Some(LitState::Ready(Arc::new(lit))));
        }
        self.publish_light(true);
    }

    /// A status of the light-driven learner (throttled unless `force`).
    pub(super) fn publish_light(&mut self, force: bool) {
        let Some(run) = self.light_run() else { return };
        let due = self.published.since_last() >= super::publish::PUBLISH_EVERY;
        let changed = run.published != Some(run.shown);
        if !(force || (due && (changed || self.dirty))) {
            return;
        }
        let (rounds, estimated_error) = run
            .fit
            .as_ref()
            .map_or((0, None), |f| (f.history().len(), f.estimated_error()));
        let growth = Growth {
            steps: rounds as u64,
            cells: run.marks.clone(),
            face_edges: Vec::new(),
            run_time: self.run_time,
            progress: Progress::Rounds {
                newest_from: run.newest_from,
                estimated_error,
                stopped: run.stopped(),
            },
        };
        let status = Status {
            growth: Arc::new(growth),
            samples: Prefix::default(),
            history: Prefix::default(),
            world: self.world.as_ref().map_or(0, |w| w.id),
            running: self.running,
            stopped: None,
            steps_per_s: 0.0,
            summary: None,
            handled: self.handled,
            params: run.params,
            occupied_faces: None,
        };
        let shown = run.shown;
        if let Some(Running::Light(run)) = &mut self.learning {
            run.published = Some(shown);
        }
        self.published.mark_published();
        self.dirty = false;
        self.post(|m| super::publish::queue(&mut m.statuses, status));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn after_a_pause_the_reveal_goes_on_where_it_was() {
        let mut run = LightRun::new(FitParams::default());
        run.newest_from = 100;
        run.shown = 150;
        // 100 cells per second, started long ago (a pause of a minute since).
        run.reveal = (Instant::now() - Duration::from_secs(60), 100.0);
        run.resume();
        let since = run.reveal.0.elapsed().as_secs_f64();
        assert!((0.5..1.5).contains(&since), "{since} s: 50 cells at 100/s");
        // Cells due now: where it paused, not a minute's worth.
        let due = run.newest_from + (since * run.reveal.1) as usize;
        assert!(due < 160, "{due}");
        // A round shown at once has nothing to resume.
        run.reveal = (Instant::now() - Duration::from_secs(60), f64::INFINITY);
        run.resume();
        assert!(run.reveal.0.elapsed() >= Duration::from_secs(59));
    }
}
