//! The least-squares refit of the output weights that ends a fit of ζ or k, and the choice of
//! its ridge weight.

use std::ops::ControlFlow;
use std::time::Instant;

use super::Fit;
use crate::{FitError, Refit};

/// Every this-many-th training sample is held back to choose the refit's ridge weight.
const VALIDATION_STRIDE: usize = 2;
/// Ridge candidates: `refit.ridge × 10^k` for k in 0..RIDGE_DECADES.
const RIDGE_DECADES: i32 = 7;

impl Fit {
    /// Refits every output weight by ridge least squares over the training samples, keeping
    /// centres and widths (an improvement beyond the paper; see `sgcs::Network::refit_outputs`),
    /// telling `progress` how far it is; the callback can stop it ([`FitError::Interrupted`];
    /// the weights are then unchanged). Called by [`Fit::finish`] for a head with a refit.
    ///
    /// The ridge weight is chosen on the training samples alone: every
    /// `VALIDATION_STRIDE`-th sample of the uniform set S₀ is held back, each candidate
    /// `refit.ridge × 10^k` is fitted on the rest and scored on it, and the learned
    /// (delta-rule) weights compete too. The winner is refitted on all samples; if the learned
    /// weights win, nothing changes. So the refit never trusts a solve that merely interpolates
    /// its samples. The normal equations are assembled once (in bounded memory, in parallel)
    /// and every candidate is one sparse Cholesky factorisation; scoring needs no sample again
    /// (see `sgcs::RefitSystem`).
    pub(super) fn refit(
        &mut self,
        refit: Refit,
        mut progress: impl FnMut(sgcs::RefitProgress) -> ControlFlow<()>,
    ) -> Result<(), FitError> {
        let started = Instant::now();
        let result = self.refit_inner(refit, &mut progress);
        self.state.refit_s += started.elapsed().as_secs_f64();
        self.state.wall_s += started.elapsed().as_secs_f64();
        result.map_err(|e| match e {
            FitError::Network(sgcs::SgcsError::Interrupted) => FitError::Interrupted,
            other => other,
        })
    }

    fn refit_inner(
        &mut self,
        refit: Refit,
        progress: &mut dyn FnMut(sgcs::RefitProgress) -> ControlFlow<()>,
    ) -> Result<(), FitError> {
        // Validate on uniform samples only: every VALIDATION_STRIDE-th sample of S₀. The θ sets
        // over-represent critical zones, so scoring on them rewards a fit that is good there and
        // poor elsewhere.
        let samples = &self.state.samples;
        let s0_end = self
            .state
            .set_starts
            .get(1)
            .copied()
            .unwrap_or(samples.len());
        let held_back: Vec<bool> = (0..samples.len())
            .map(|i| i < s0_end && i % VALIDATION_STRIDE == VALIDATION_STRIDE - 1)
            .collect();
        let inputs: Vec<f64> = samples.iter().flat_map(|s| s.xi).collect();
        let targets: Vec<f64> = samples.iter().map(|s| s.target).collect();
        let network = &self.state.model.network;
        let system = network.refit_system_split(&inputs, &targets, &held_back, progress)?;
        drop((inputs, targets, held_back));
        let Some(learned) = system.validation_error(network.outputs()) else {
            // Nothing held back (a tiny S₀): no honest way to choose; keep the learned weights.
            return Ok(());
        };
        let mut best = (learned, None);
        let solves = RIDGE_DECADES as usize + 1;
        let mut stage = |done: usize| -> Result<(), FitError> {
            let report = sgcs::RefitProgress {
                stage: sgcs::RefitStage::Solving,
                done,
                total: solves,
            };
            match progress(report) {
                ControlFlow::Continue(()) => Ok(()),
                ControlFlow::Break(()) => Err(FitError::Interrupted),
            }
        };
        for k in 0..RIDGE_DECADES {
            stage(k as usize)?;
            let ridge = refit.ridge * 10f64.powi(k);
            let (weights, _) = system.solve(ridge, sgcs::RefitPart::Fitting)?;
            let error = system.validation_error(&weights).unwrap_or(f64::INFINITY);
            if error < best.0 {
                best = (error, Some(ridge));
            }
        }
        stage(solves - 1)?;
        if let Some(ridge) = best.1 {
            self.state.model.network.refit_with(&system, ridge)?;
        }
        let _ = progress(sgcs::RefitProgress {
            stage: sgcs::RefitStage::Solving,
            done: solves,
            total: solves,
        });
        Ok(())
    }
}
