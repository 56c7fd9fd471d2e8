//! Flatland's experiments and reports: every method at every budget on the same kernel and
//! error measure ([`bench`](mod@bench)), the learner's ideas on and off ([`ablation`]), random
//! validation rooms ([`rooms`]), and the one colour map of every picture ([`colormap`]). The
//! crate's one job is to *compare*: it runs the learner (`kernel_fit`) and the baselines side by
//! side and measures them all with `flatland_solve`; nothing below it knows it exists.
//!
//! Conventions as in the crates below: `s` is the sender parameter, `t` the receiver, both in
//! `[0, 1)`; grids are row-major with row `i ↔ s`; pictures show `t` to the right and `s`
//! upwards.
//!
//! ```
//! use flatland_lab::bench::Method;
//!
//! // The methods every table lists, by the names files and the command line use.
//! let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
//! assert_eq!(names, ["sgcs", "sgcs-paper", "sgcs-paper-norefit", "hr", "uniform"]);
//! assert_eq!(Method::parse("hr")?, Method::Hr);
//! # Ok::<(), flatland_lab::LabError>(())
//! ```

#![deny(missing_docs)]

pub mod ablation;
pub mod bench;
pub mod colormap;
mod error;
pub mod interrupt;
mod measure;
pub mod output;
pub mod plot;
pub mod report;
pub mod results;
pub mod rooms;
pub mod stress;

pub use error::LabError;
pub use measure::{Defined, error_text, reference};
