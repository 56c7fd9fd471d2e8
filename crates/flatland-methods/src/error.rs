//! `MethodError`: a name that is not a method's, or a build that failed below.

use thiserror::Error;

/// Why a method could not be named or built.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum MethodError {
    /// A name no method has.
    #[error("`{name}` is not a method: expected one of {valid}")]
    Unknown {
        /// The name given.
        name: String,
        /// The valid names.
        valid: String,
    },
    /// A name a method had before it got its one name.
    #[error("`{name}` is no longer a method's name: use {now}")]
    Retired {
        /// The old name given.
        name: String,
        /// What to write instead.
        now: &'static str,
    },
    /// A method where only some are meant (the viewer's learners, `fit`'s networks).
    #[error("`{method}` is not {what}: expected {valid}")]
    NotOneOf {
        /// The method named.
        method: &'static str,
        /// What was asked for.
        what: &'static str,
        /// The valid names.
        valid: &'static str,
    },
    /// The tracer lights a scene without any kernel: it has no representation to build.
    #[error("`{0}` lights a scene without a kernel: it has no representation to build")]
    NotAKernel(&'static str),
    /// A method that lights one scene for a moving light only (the learned transport, the
    /// probe grid): it has no kernel to solve once with. Its name, title and the command that
    /// runs it.
    #[error("`{0}` ({1}) is for a moving light: run `{2}`")]
    RelightOnly(&'static str, &'static str, &'static str),
    /// A build parameter out of its range.
    #[error("{name} must be {valid}, but is {value}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// Its value.
        value: String,
        /// The valid range.
        valid: &'static str,
    },
    /// Ctrl-C (or another stop) ended the build.
    #[error("interrupted")]
    Interrupted,
    /// The light-driven learner failed.
    #[error(transparent)]
    Light(#[from] flatland_light::LightError),
    /// A network's fit failed.
    #[error(transparent)]
    Fit(#[from] kernel_fit::FitError),
    /// A baseline failed.
    #[error(transparent)]
    Baseline(#[from] flatland_baselines::BaselineError),
    /// The solver refused.
    #[error(transparent)]
    Solve(#[from] flatland_solve::SolveError),
}

impl MethodError {
    /// Whether a stop ended the build, here or in the crate below that was running.
    #[must_use]
    pub fn is_interrupted(&self) -> bool {
        matches!(
            self,
            MethodError::Interrupted
                | MethodError::Light(flatland_light::LightError::Interrupted)
                | MethodError::Fit(kernel_fit::FitError::Interrupted)
                | MethodError::Solve(flatland_solve::SolveError::Interrupted)
        )
    }
}
