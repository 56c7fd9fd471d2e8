//! The θ-resampling driver's training loop: one step (resample when due, draw a set and a
//! sample, adapt the network), the stopping rules, and training to a stop.

use std::ops::ControlFlow;
use std::time::Instant;

use rand::RngExt;

use super::{CellStats, Fit, FitSummary, Sample, StopReason};
use crate::FitError;
use crate::visibility::FaceId;

/// Growth periods (λ steps) without an insertion, each with a θ scan, after which a fit that
/// grows at its worst samples has converged (see [`StopReason::Converged`]).
const STALL_PERIODS: u64 = 20;

impl Fit {
    /// One training step: resample if `|A| / |S| > ψ`, draw a set uniformly and a sample from
    /// it, adapt the network, record who won. Returns the stop reason once a rule fires.
    pub fn step(&mut self) -> Option<StopReason> {
        if self.state.stop.is_some() {
            return self.state.stop;
        }
        if let Some(reason) = self.resample_if_due() {
            self.state.stop = Some(reason);
            return self.state.stop;
        }
        let set = self
            .state
            .train_rng
            .random_range(0..self.state.set_starts.len());
        let start = self.state.set_starts[set];
        let end = self
            .state
            .set_starts
            .get(set + 1)
            .copied()
            .unwrap_or(self.state.samples.len());
        let index = self.state.train_rng.random_range(start..end);
        let sample = self.state.samples[index];
        let outcome = self.train_on(&sample, self.sample_faces[index]);
        if let Some(new) = outcome.inserted {
            debug_assert_eq!(new, self.state.cell_stats.len());
            self.state.cell_stats.push(CellStats::default());
            self.state.steps_at_last_growth = self.steps();
        }
        let stats = &mut self.state.cell_stats[outcome.bmu];
        stats.sum_s += sample.st[0];
        stats.sum_t += sample.st[1];
        stats.wins += 1;

        let steps = self.steps();
        let eval_every = self.valid.measurement.eval_every;
        if eval_every > 0 && steps.is_multiple_of(eval_every) {
            self.record_history();
        }
        self.state.stop = self.stop_reason();
        self.state.stop
    }

    /// Draws a new set when `|A| / |S| > ψ`, or when growth at the worst sample has stalled;
    /// [`StopReason::Converged`] when a stalled fit finds nothing left to learn.
    fn resample_if_due(&mut self) -> Option<StopReason> {
        let steps = self.steps();
        let cells = self.state.model.network.len();
        let live = &self.valid.live;
        // Growth at the worst sample waits while every sample is predicted exactly; then only a
        // θ scan can show where the model is still wrong, whatever |A| / |S|.
        let lambda = u64::from(live.rates.lambda);
        let stalled = self.valid.fixed.rules.insertion == sgcs::Insertion::WorstSample
            && cells < live.target_cells
            && steps >= self.state.steps_at_last_growth + 2 * lambda
            && steps.is_multiple_of(lambda);
        if stalled && steps >= self.state.steps_at_last_growth + STALL_PERIODS * lambda {
            // Every scan since the last growth found only samples predicted exactly.
            return Some(StopReason::Converged);
        }
        if (stalled || cells as f64 > live.psi * self.state.samples.len() as f64)
            && steps >= self.state.resample_not_before
            && self.state.rays < live.ray_budget
        {
            let before = self.state.samples.len();
            self.resample();
            if stalled && self.state.samples.len() == before {
                return Some(StopReason::Converged);
            }
        }
        None
    }

    /// One network step on `sample` (whose ray is in `face`): gated by that face where the
    /// head gates (whose cell faces then follow the cells that moved), plain otherwise.
    fn train_on(&mut self, sample: &Sample, face: Option<FaceId>) -> sgcs::StepOutcome {
        let model = &mut self.state.model;
        let gate = model.head.training_gate(face);
        let (xi, target, weight) = (&sample.xi, [sample.target], sample.weight);
        let outcome = match &gate {
            Some(gate) => model.network.try_step_gated(xi, &target, weight, gate),
            None => model
                .network
                .try_step_gated(xi, &target, weight, &sgcs::Open),
        }
        .expect("training samples are finite and bounded");
        model.relabel_moved();
        outcome
    }

    fn stop_reason(&self) -> Option<StopReason> {
        let live = &self.valid.live;
        let steps = self.steps();
        let lambda = u64::from(live.rates.lambda);
        if self.state.model.network.len() >= live.target_cells
            && steps - self.state.steps_at_last_growth >= lambda
        {
            return Some(StopReason::TargetCells);
        }
        if live.target_error > 0.0
            && self
                .state
                .history
                .last()
                .is_some_and(|h| h.steps == steps && h.rel_l2_heldout <= live.target_error)
        {
            return Some(StopReason::TargetError);
        }
        if self.state.rays >= live.ray_budget {
            return Some(StopReason::RayBudget);
        }
        if steps >= live.max_steps {
            return Some(StopReason::StepBudget);
        }
        None
    }

    /// Trains until a stopping rule fires, calling `progress` every `every` steps (and once at
    /// the end); the callback stops the fit by returning `ControlFlow::Break`
    /// ([`StopReason::Interrupted`]). The state is then exactly what a checkpoint saves.
    pub fn train(
        &mut self,
        every: u64,
        mut progress: impl FnMut(&Fit) -> ControlFlow<()>,
    ) -> StopReason {
        let started = Instant::now();
        let every = every.max(1);
        let reason = loop {
            if let Some(reason) = self.step() {
                break reason;
            }
            if self.steps().is_multiple_of(every) && progress(self).is_break() {
                self.state.stop = Some(StopReason::Interrupted);
                break StopReason::Interrupted;
            }
        };
        self.state.wall_s += started.elapsed().as_secs_f64();
        let _ = progress(self);
        reason
    }

    /// [`train`](Fit::train), then [`finish`](Fit::finish): the whole fit.
    pub fn run(
        &mut self,
        every: u64,
        progress: impl FnMut(&Fit) -> ControlFlow<()>,
    ) -> Result<FitSummary, FitError> {
        self.train(every, progress);
        self.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use super::*;
    use crate::FitParams;

    #[test]
    fn rays_samples_and_stopping_rules() {
        let kernel = fig3();
        let mut fit = fit_with(&kernel, paper(100));
        let summary = run(&mut fit);
        assert_eq!(summary.stop, StopReason::TargetCells);
        assert_eq!(summary.cells, 100);
        // A sample costs a ray only where geometry cannot decide visibility (on fig3: the
        // pairs the blocker shadows); R5: ψ = 0.05 keeps ≈ 20 samples per cell.
        assert!(
            summary.rays > 0 && summary.rays < summary.samples as u64,
            "{summary:?}"
        );
        let per_cell = summary.samples as f64 / summary.cells as f64;
        assert!(
            (15.0..=25.0).contains(&per_cell),
            "{per_cell} samples per cell"
        );

        let budget = run(&mut fit_with(
            &kernel,
            FitParams {
                ray_budget: 400,
                ..paper(100)
            },
        ));
        assert_eq!(budget.stop, StopReason::RayBudget);
        assert!(budget.rays <= 400, "{}", budget.rays);
        let steps = run(&mut fit_with(
            &kernel,
            FitParams {
                max_steps: 1234,
                ..paper(100)
            },
        ));
        assert_eq!((steps.stop, steps.steps), (StopReason::StepBudget, 1234));
        let target = run(&mut fit_with(
            &kernel,
            FitParams {
                target_error: 0.9,
                eval_every: 500,
                ..paper(100)
            },
        ));
        assert_eq!(target.stop, StopReason::TargetError);
    }
}
