//! The crate's one error type.

/// Everything that can go wrong while configuring or running a light-driven fit.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LightError {
    /// A parameter is outside its valid range.
    #[error("parameter `{name}` is {value}, but must be {valid}")]
    InvalidParameter {
        /// The parameter's name as the CLI spells it.
        name: &'static str,
        /// The rejected value, as text.
        value: String,
        /// The valid range in words.
        valid: &'static str,
    },
    /// The solver (or its visibility sweep) refused something or stopped (its message,
    /// unchanged).
    #[error(transparent)]
    Solve(#[from] flatland_solve::SolveError),
    /// The caller's stop flag ended the work.
    #[error("interrupted")]
    Interrupted,
}
