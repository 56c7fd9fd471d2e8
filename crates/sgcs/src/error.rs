//! The crate's one error type.

/// Everything that can go wrong building, training, refitting or loading a network.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SgcsError {
    /// A parameter is outside its valid range.
    #[error("parameter `{name}` must be in {range}, but is {value}")]
    InvalidParam {
        /// The parameter's field name in [`crate::Params`].
        name: &'static str,
        /// The valid range, in interval notation.
        range: String,
        /// The rejected value.
        value: String,
    },
    /// A vector has the wrong length.
    #[error("{what} has length {got}, expected {expected}")]
    Dimension {
        /// Which vector.
        what: &'static str,
        /// The length the network needs.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A value is NaN, infinite, or beyond the supported magnitude (`1e100`).
    #[error("{what} must be finite and at most 1e100 in magnitude, but contains {value}")]
    NonFinite {
        /// Which vector.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The initial simplex is unusable.
    #[error("invalid initial simplex: {0}")]
    InvalidSimplex(String),
    /// Saved data is not valid JSON or not a network.
    #[error("cannot read network: {0}")]
    Format(String),
    /// Saved data has another format version.
    #[error("network file has format version {found}, this build reads only version {supported}")]
    UnsupportedVersion {
        /// The version in the file.
        found: u64,
        /// The version this build writes and reads.
        supported: u32,
    },
    /// Saved data is well-formed but describes an inconsistent network.
    #[error("saved network is inconsistent: {0}")]
    Corrupt(String),
    /// Bad input to [`crate::Network::refit_outputs`], or a system it cannot solve.
    #[error("refit: {0}")]
    Refit(String),
    /// [`crate::Network::insert_at`] on a network that already holds `max_cells` cells.
    #[error(
        "the network already holds its maximum of {max_cells} cells (parameter `max_cells`); raise it to insert more"
    )]
    Full {
        /// The network's `max_cells`.
        max_cells: usize,
    },
    /// The caller's progress callback stopped the work.
    #[error("interrupted")]
    Interrupted,
}
