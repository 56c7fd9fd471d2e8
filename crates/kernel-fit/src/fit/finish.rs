//! The one way a fit ends: the refit its head asks for (or none) and the final errors, in
//! one [`FitSummary`]. `flatland fit`, `bench`, `solve`, the viewer and the experiments all
//! end their fits here.

use std::ops::ControlFlow;
use std::time::Instant;

use super::{Fit, FitSummary, StopReason};
use crate::FitError;

impl Fit {
    /// Ends the fit: the refit its head asks for ([`Head::refit`](crate::Head::refit); a
    /// learner without one keeps its weights), then the final errors. Idempotent apart from
    /// the refit.
    pub fn finish(&mut self) -> Result<FitSummary, FitError> {
        self.finish_with(|_| ControlFlow::Continue(()))
    }

    /// [`finish`](Fit::finish), telling `progress` how the refit goes; the callback can stop
    /// the refit ([`FitError::Interrupted`], the learned weights stay as they were).
    pub fn finish_with(
        &mut self,
        progress: impl FnMut(sgcs::RefitProgress) -> ControlFlow<()>,
    ) -> Result<FitSummary, FitError> {
        let mut errors_before_refit = None;
        let mut errors_s = 0.0;
        if let Some(refit) = self.valid.fixed.head.refit() {
            let started = Instant::now();
            errors_before_refit = Some(self.reference.errors(&self.state.model));
            errors_s += started.elapsed().as_secs_f64();
            self.refit(refit, progress)?;
        }
        let started = Instant::now();
        let errors = self.reference.errors(&self.state.model);
        errors_s += started.elapsed().as_secs_f64();
        let s = &self.state;
        Ok(FitSummary {
            cells: s.model.network.len(),
            samples: s.samples.len(),
            sets: s.set_starts.len(),
            rays: s.rays,
            steps: self.steps(),
            errors,
            errors_before_refit,
            wall_s: s.wall_s,
            train_s: (s.wall_s - s.resample_s - s.refit_s).max(0.0),
            resample_s: s.resample_s,
            refit_s: s.refit_s,
            reference_s: self.reference.build_s(),
            errors_s,
            stop: s.stop.unwrap_or(StopReason::Interrupted),
        })
    }
}
