//! How a fit ended: the figures it reports ([`FitSummary`], which model files keep) and why it
//! stopped ([`StopReason`]). Below both the fit that writes them and the model file that keeps
//! them.

use flatland_solve::Errors;
use serde::{Deserialize, Serialize};

/// The figures a finished fit reports.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitSummary {
    /// Cells in the network.
    pub cells: usize,
    /// Training samples (= rays cast for training).
    pub samples: usize,
    /// Sample sets.
    pub sets: usize,
    /// Rays cast for training.
    pub rays: u64,
    /// Training steps.
    pub steps: u64,
    /// Errors of the final model.
    pub errors: Errors,
    /// Errors before the least-squares refit, when it ran.
    pub errors_before_refit: Option<Errors>,
    /// Wall time of the training and the refit (reference construction excluded), seconds.
    pub wall_s: f64,
    /// Of `wall_s`: the network's training steps and the driver around them, seconds.
    #[serde(default)]
    pub train_s: f64,
    /// Of `wall_s`: θ-resampling (drawing and scanning candidates, casting the rays), seconds.
    #[serde(default)]
    pub resample_s: f64,
    /// Of `wall_s`: the least-squares refit (0 without one), seconds.
    #[serde(default)]
    pub refit_s: f64,
    /// Building the reference the errors are measured against (not in `wall_s`), seconds.
    #[serde(default)]
    pub reference_s: f64,
    /// Measuring the final errors against the reference (not in `wall_s`), seconds.
    #[serde(default)]
    pub errors_s: f64,
    /// Why it stopped.
    pub stop: StopReason,
}

/// Why a fit stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The target cell count was reached and trained for one growth period.
    TargetCells,
    /// The held-out error reached the target.
    TargetError,
    /// The ray budget is spent.
    RayBudget,
    /// The step budget is spent.
    StepBudget,
    /// The caller's progress callback asked to stop.
    Interrupted,
    /// The visibility learner on a scene where the geometry decides every visibility: the
    /// model is exact without learning anything.
    Exact,
    /// Growth at the worst sample ([`sgcs::Insertion::WorstSample`]) found no error left: every
    /// sample is predicted exactly and a θ scan found no place worth a ray. More cells would
    /// change nothing.
    Converged,
}
