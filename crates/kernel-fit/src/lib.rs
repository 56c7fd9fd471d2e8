//! Learn a Flatland scene's radiosity kernel with supervised growing cell structures.
//!
//! (Work in progress: the fit driver lands with its issue.)

#![deny(missing_docs)]

pub mod baselines;
mod error;
mod eval;

pub use error::FitError;
pub use eval::{grid_point, relative_l2, Approximation, Errors, Reference};
