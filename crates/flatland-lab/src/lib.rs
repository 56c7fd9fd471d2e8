//! Flatland's experiments and reports. The crate's one job is to *compare*: it runs the
//! learner (`kernel_fit`) and the baselines (`flatland_baselines`) side by side, measures them
//! all with `flatland_solve`, and writes what it finds; nothing below it knows it exists.
//!
//! - The experiments: every method timed to its lit scene on the same kernel, reference and
//!   error measures, each swept over its own knob within a time budget ([`timed`], the one
//!   bench engine: `flatland bench` and the R4 table at equal basis functions are plans of it),
//!   cost against scene size ([`scaling`]), the learner's ideas on and off ([`ablation`]), random
//!   validation rooms ([`rooms`]), the adversarial stability suite ([`stress`]), and RESULTS.md
//!   with its plots, all of them run and rendered ([`results`]).
//! - The outputs: the bench's CSV, plots and tables, the Fig. 3 panels of a fit, grids as CSV or
//!   heatmaps ([`report`]). The pictures themselves (the colour map, charts, heatmaps, the lit
//!   scene) are drawn by `flatland_pictures`, below this crate; here they get their data and are
//!   written where they go.
//! - What every command shares with the experiments: the one reference rule and when an error is
//!   defined ([`reference()`], [`Defined`]), Ctrl-C that keeps what is done ([`interrupt`]), the
//!   rule for output paths ([`output`]), and the process's peak memory ([`memory`]).
//!
//! Errors: the plans' checks are a [`LabError`]; the long-running experiments and the
//! writers end at the command line and return `anyhow` errors with their context as text.
//!
//! Conventions as in the crates below: `s` is the sender parameter, `t` the receiver, both in
//! `[0, 1)`; grids are row-major with row `i ↔ s`; pictures show `t` to the right and `s`
//! upwards.
//!
//! ```
//! use std::sync::Arc;
//! use flatland_geom::{Kernel, bundled};
//! use flatland_lab::timed::{Method, Scorer, TimedPlan, run_timed};
//! use flatland_solve::{Reference, never};
//!
//! // The R4 table is a plan of the one bench engine: the methods it lists, by the names files
//! // and the command line use, at equal basis functions.
//! let plan = TimedPlan::r4(vec![40], 1);
//! let names: Vec<&str> = plan.methods.iter().map(|m| m.name()).collect();
//! assert_eq!(names, ["visibility", "paper", "paper-norefit", "hr", "uniform"]);
//!
//! // Every row is built, solved on one mesh and scored against an independent exact solve.
//! let kernel = Arc::new(Kernel::new(bundled::scene("fig3")?));
//! let zeta = Arc::new(Reference::new(&kernel, 16, 128, 3));
//! let scorer = Scorer::new(&kernel, 64, 256, zeta, &never)?;
//! let plan = TimedPlan { methods: vec![Method::Hr, Method::Uniform], ..plan };
//! let rows = run_timed(&kernel, &scorer, &plan, &never, |_| Ok(()))?;
//! assert_eq!(rows.len(), 2);
//! assert!(rows.iter().all(|r| r.reflected_error().is_some() && r.zeta.is_some()));
//! # Ok::<(), anyhow::Error>(())
//! ```

#![deny(missing_docs)]

pub mod ablation;
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
