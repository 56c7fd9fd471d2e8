//! The crate's one error type.

/// Everything that can go wrong while planning or running an experiment.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LabError {
    /// A parameter of an experiment is outside its valid range.
    #[error("parameter `{name}` is {value}, but must be {valid}")]
    InvalidParameter {
        /// The parameter's name as the CLI spells it.
        name: &'static str,
        /// The rejected value, as text.
        value: String,
        /// The valid range in words.
        valid: &'static str,
    },
    /// The learner refused something or stopped (its message, unchanged).
    #[error(transparent)]
    Fit(#[from] kernel_fit::FitError),
    /// A baseline refused its parameters (its message, unchanged).
    #[error(transparent)]
    Baseline(#[from] flatland_baselines::BaselineError),
    /// The solver refused something or stopped (its message, unchanged).
    #[error(transparent)]
    Solve(#[from] flatland_solve::SolveError),
}
