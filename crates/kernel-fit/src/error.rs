//! The crate's one error type.

/// Everything that can go wrong while configuring, running, saving or loading a fit.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FitError {
    /// A parameter is outside its valid range.
    #[error("parameter `{name}` is {value}, but must be {valid}")]
    InvalidParameter {
        /// The parameter's name as the CLI and files spell it.
        name: &'static str,
        /// The rejected value, as text.
        value: String,
        /// The valid range in words.
        valid: &'static str,
    },
    /// A parameter of a schema ([`sgcs::schema`]) is outside its range.
    #[error("parameter `{name}` is {value}, but must be in {range}")]
    OutOfRange {
        /// The parameter's name as the CLI and files spell it.
        name: &'static str,
        /// The rejected value, as text.
        value: String,
        /// The valid range, in interval notation.
        range: String,
    },
    /// A parameter whose value means nothing with another's (a learner would ignore it).
    #[error(
        "parameter `{name}` is {value}, which means nothing with `{other}` = {other_value}: {valid}"
    )]
    Meaningless {
        /// The parameter refused.
        name: &'static str,
        /// Its value, as text.
        value: String,
        /// The parameter whose value makes it meaningless.
        other: &'static str,
        /// That parameter's value, as text.
        other_value: String,
        /// What would be valid, in words.
        valid: &'static str,
    },
    /// The geometry layer refused something.
    #[error(transparent)]
    Geom(#[from] flatland_geom::GeomError),
    /// The network layer refused something.
    #[error(transparent)]
    Network(#[from] sgcs::SgcsError),
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// A model file is malformed, from another version, or for another scene.
    #[error("{path}: {reason}")]
    Model {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong and what would be valid.
        reason: String,
    },
    /// The solver refused something or stopped (its message, unchanged).
    #[error(transparent)]
    Solve(#[from] flatland_solve::SolveError),
    /// The caller's stop flag ended the work.
    #[error("interrupted")]
    Interrupted,
}
