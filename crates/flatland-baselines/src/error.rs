//! The crate's one error type.

/// Everything a baseline can refuse.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BaselineError {
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
}
