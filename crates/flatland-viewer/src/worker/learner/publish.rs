//! Publishing, throttled: a [`Status`] at most every [`PUBLISH_EVERY`], the learned ζ̃ on the
//! display grid at most every [`APPROX_EVERY`] while training (it costs `APPROX_RES²` network
//! evaluations), the exact ζ at the kernel plot's resolution once per scene and plot size.
//! Samples and the learning curve only grow, so a status shares the vector of the last one
//! while it has not grown.

use std::sync::Arc;
use std::time::{Duration, Instant};

use kernel_fit::{Fit, HistoryPoint, Snapshot};

use super::{LearnerThread, Running};
use crate::prefix::Prefix;
use crate::worker::approx_grid;
use crate::worker::faces::{cell_groups, face_edges};
use crate::worker::published::{
    APPROX_RES, Approx, CellMark, Growth, KernelGrid, LearnedGrid, Progress, SamplePoint, Status,
};

/// Shortest time between two published snapshots.
pub const PUBLISH_EVERY: Duration = Duration::from_millis(50);
/// Shortest time between two published approximations while training.
pub const APPROX_EVERY: Duration = Duration::from_millis(600);

/// What was last published, and when.
pub(super) struct PublishState {
    last_publish: Instant,
    last_approx: Instant,
    published_steps: Option<u64>,
    approx_steps: Option<u64>,
    /// Steps per second: when it was measured, at which step, the rate.
    rate: (Instant, u64, f64),
    /// The samples last published and the world they belong to.
    samples: Option<(u64, Prefix<SamplePoint>)>,
    history: Prefix<HistoryPoint>,
    /// The world and resolution of the kernel grid last published.
    kernel_grid: Option<(u64, usize)>,
}

impl PublishState {
    pub(super) fn new(now: Instant) -> PublishState {
        PublishState {
            last_publish: now,
            last_approx: now,
            published_steps: None,
            approx_steps: None,
            rate: (now, 0, 0.0),
            samples: None,
            history: Prefix::default(),
            kernel_grid: None,
        }
    }

    /// Time since the last status.
    pub(super) fn since_last(&self) -> Duration {
        self.last_publish.elapsed()
    }

    /// A status was just published (by the light-driven learner).
    pub(super) fn mark_published(&mut self) {
        self.last_publish = Instant::now();
    }

    /// A new world: everything is published again.
    pub(super) fn forget(&mut self) {
        self.published_steps = None;
        self.approx_steps = None;
        self.samples = None;
    }

    /// ζ̃ changed without a step (the refit): publish it again.
    pub(super) fn approx_stale(&mut self) {
        self.approx_steps = None;
    }

    /// The snapshot's samples, sharing the last vector when none were added.
    fn samples(&mut self, world: u64, all: Vec<SamplePoint>) -> Prefix<SamplePoint> {
        match &self.samples {
            Some((w, last)) if *w == world && last.len() == all.len() => last.clone(),
            _ => {
                let fresh = Prefix::new(Arc::new(all));
                self.samples = Some((world, fresh.clone()));
                fresh
            }
        }
    }

    /// The snapshot's curve, sharing the last vector when it has not grown.
    fn history(&mut self, all: Vec<HistoryPoint>) -> Prefix<HistoryPoint> {
        if self.history.len() != all.len() || all.is_empty() {
            self.history = Prefix::new(Arc::new(all));
        }
        self.history.clone()
    }
}

/// Where to draw cell `c` before it has won a sample (the first cells, a cell just
/// inserted): at the `(s, t)` of the sample nearest to it in the network's input space, where
/// it would win first. Looks at up to [`PLACING_SAMPLES`] of them, spread over all.
fn nearest_sample(fit: &Fit, c: usize, samples: &[SamplePoint]) -> Option<[f32; 2]> {
    let model = fit.model();
    let at = fit.network().position(c);
    let every = samples.len().div_ceil(PLACING_SAMPLES).max(1);
    samples
        .iter()
        .step_by(every)
        .map(|&(st, _)| {
            let x = model.input(f64::from(st[0]), f64::from(st[1]));
            let d: f64 = x.iter().zip(at).map(|(a, b)| (a - b) * (a - b)).sum();
            (d, st)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, st)| st)
}

/// Most statuses waiting in the mailbox: a UI that draws no frames (a minimized window) finds
/// every second one of the older ones, not an ever longer queue.
const MAX_QUEUED: usize = 64;

/// Adds `status` to the waiting ones, thinned to every second one when the queue is full.
pub(super) fn queue(waiting: &mut Vec<Status>, status: Status) {
    if waiting.len() >= MAX_QUEUED {
        let mut k = 0;
        waiting.retain(|_| {
            k += 1;
            k % 2 == 0
        });
    }
    waiting.push(status);
}

/// Most samples looked at to place a cell that has won none.
const PLACING_SAMPLES: usize = 4096;

/// The network of `fit` as the overlay draws it: its cells and the edges within faces.
fn growth(fit: &Fit, snap: &Snapshot, run_time: Duration) -> Growth {
    let st = fit.cell_st();
    let groups = cell_groups(fit.model(), &st);
    Growth {
        steps: snap.steps,
        cells: snap
            .cells
            .iter()
            .enumerate()
            .map(|(c, cell)| CellMark {
                st: cell
                    .st
                    .map(|[s, t]| [s as f32, t as f32])
                    .or_else(|| nearest_sample(fit, c, &snap.samples)),
                width: cell.width as f32,
                critical: cell.critical,
                seen: Default::default(),
            })
            .collect(),
        face_edges: face_edges(&fit.network().edges(), &groups),
        run_time,
        progress: Progress::Steps {
            rays: snap.rays,
            sets: snap.sets,
        },
    }
}

impl LearnerThread {
    /// Publishes a status (throttled unless `force`) and, less often, the approximation.
    pub(super) fn publish(&mut self, force: bool) {
        let fit = match &self.learning {
            Some(Running::Network(fit)) => fit,
            // Its statuses are `publish_light`'s.
            Some(Running::Light(_)) => return,
            None => {
                self.dirty = false; // nothing to show yet
                return;
            }
        };
        let steps = fit.steps();
        let now = Instant::now();
        let p = &mut self.published;
        let (since, at, rate) = p.rate;
        if now.duration_since(since) >= Duration::from_secs(1) {
            let r = steps.saturating_sub(at) as f64 / now.duration_since(since).as_secs_f64();
            p.rate = (now, steps, r);
        }
        let busy = self.running || self.steps_left > 0;
        let changed = p.published_steps != Some(steps);
        let due = now.duration_since(p.last_publish) >= PUBLISH_EVERY;
        let world = self.world.as_ref().map_or(0, |w| w.id);
        if force || (due && (changed || self.dirty)) {
            let mut snap = fit.snapshot();
            let growth = Arc::new(growth(fit, &snap, self.run_time));
            let status = Status {
                growth,
                samples: p.samples(world, std::mem::take(&mut snap.samples)),
                history: p.history(std::mem::take(&mut snap.history)),
                world,
                running: self.running,
                stopped: fit.stopped(),
                steps_per_s: if busy { p.rate.2.max(rate) } else { 0.0 },
                summary: self.summary.clone(),
                handled: self.handled,
                params: *fit.params(),
                occupied_faces: fit.model().occupied_faces(),
            };
            p.published_steps = Some(steps);
            p.last_publish = now;
            self.dirty = false;
            self.post(|m| queue(&mut m.statuses, status));
        }
        self.publish_approx(busy);
    }

    /// The exact ζ at the kernel plot's resolution, once per world and resolution: about 0.1 s
    /// at 512² on a scene of 1000 edges, 0.4 s at 1024².
    pub(super) fn publish_kernel_grid(&mut self) {
        let Some(world) = &self.world else {
            return;
        };
        let wanted = (world.id, self.plot_res);
        if self.plot_res == 0 || self.published.kernel_grid == Some(wanted) {
            return;
        }
        let grid = Arc::new(KernelGrid {
            world: world.id,
            res: self.plot_res,
            values: world.kernel.grid(self.plot_res, true),
        });
        self.published.kernel_grid = Some(wanted);
        self.post(|m| m.kernel_grid = Some(grid));
    }

    /// The learned ζ̃ on the display grid, when it changed and is due.
    fn publish_approx(&mut self, busy: bool) {
        let (Some(Running::Network(fit)), Some(world)) = (&self.learning, &self.world) else {
            return;
        };
        let steps = fit.steps();
        let p = &mut self.published;
        let due = p.last_approx.elapsed() >= APPROX_EVERY || !busy;
        if p.approx_steps == Some(steps) || !due {
            return;
        }
        let model = fit.model().clone();
        let values = approx_grid(&model, APPROX_RES);
        let approx = Arc::new(Approx {
            grid: Arc::new(LearnedGrid {
                world: world.id,
                steps,
                values,
            }),
            model: Some(model),
        });
        p.approx_steps = Some(steps);
        p.last_approx = Instant::now();
        self.post(|m| m.approx = Some(approx));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{moment, world};

    #[test]
    fn a_full_queue_keeps_every_second_status_and_the_newest() {
        let w = world(1);
        let mut waiting = Vec::new();
        for i in 0..200 {
            queue(&mut waiting, moment(&w, i, 3).status);
        }
        assert!(waiting.len() <= MAX_QUEUED, "{}", waiting.len());
        assert!(waiting.len() > MAX_QUEUED / 2);
        assert_eq!(waiting.last().unwrap().growth.steps, 199 * 100);
        assert!(
            waiting
                .windows(2)
                .all(|p| p[0].growth.steps < p[1].growth.steps),
            "oldest first"
        );
    }
}
