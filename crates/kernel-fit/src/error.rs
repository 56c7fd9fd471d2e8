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
