//! Flatland's experiments and reports. The crate's one job is to *compare*: it runs the
//! learner (`kernel_fit`) and the baselines (`flatland_baselines`) side by side, measures them
//! all with `flatland_solve`, and writes what it finds; nothing below it knows it exists.
//!
//! - The experiments: every method at every budget on the same kernel and error measure
//!   ([`bench`](mod@bench)), the learner's ideas on and off ([`ablation`]), random validation
//!   rooms ([`rooms`]), the adversarial stability suite ([`stress`]), and RESULTS.md with its
//!   plots, all of them run and rendered ([`results`]).
//! - The outputs: the bench's CSV, plots and tables, the Fig. 3 panels of a fit, grids as CSV or
//!   heatmaps ([`report`]). The pictures themselves (the colour map, charts, heatmaps, the lit
//!   scene) are drawn by `flatland_pictures`, below this crate; here they get their data and are
//!   written where they go.
//! - What every command shares with the experiments: the one reference rule and when an error is
//!   defined ([`reference()`], [`Defined`]), Ctrl-C that keeps what is done ([`interrupt`]), the
//!   rule for output paths ([`output`]), and the process's peak memory ([`memory`]).
//!
//! Errors: the bench plan's checks are a [`LabError`]; the long-running experiments and the
//! writers end at the command line and return `anyhow` errors with their context as text.
//!
//! Conventions as in the crates below: `s` is the sender parameter, `t` the receiver, both in
//! `[0, 1)`; grids are row-major with row `i ↔ s`; pictures show `t` to the right and `s`
//! upwards.
//!
//! ```
//! use flatland_lab::bench::{METHODS, Method};
//!
//! // The methods the R4 table lists, by the names files and the command line use.
//! let names: Vec<&str> = METHODS.iter().map(|m| m.name()).collect();
//! assert_eq!(names, ["visibility", "paper", "paper-norefit", "hr", "uniform"]);
//! assert_eq!(Method::parse("hr")?, Method::Hr);
//! # Ok::<(), flatland_methods::MethodError>(())
//! ```

#![deny(missing_docs)]

pub mod ablation;
pub mod bench;
mod error;
pub mod interrupt;
mod measure;
pub mod memory;
pub mod output;
pub mod report;
pub mod results;
pub mod rooms;
pub mod scaling;
pub mod stress;
pub mod timed;

pub use error::LabError;
pub use measure::{Defined, error_text, reference};
