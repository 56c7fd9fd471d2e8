//! Learn a Flatland scene's radiosity kernel with supervised growing cell structures
//! (C.-A. Bohn, *Efficiently Representing the Radiosity Kernel through Learning*, EGRW 1996).
//!
//! The job, the learner only: turn an exact but expensive kernel ([`flatland_geom::Kernel`], one
//! visibility query per value) into a compact learned one, spending rays where the network is
//! poor or absent; its parameters, training, model and files. It is measured by `flatland_solve`
//! (below it) and compared with the baselines by `flatland_lab` (above it). Two learners share
//! one driver ([`Fit`]), chosen by [`Preset`]; [`FitParams::check`] refuses combinations that
//! mean nothing and gives the learner's variant ([`Head`]) and the parameters by lifetime
//! ([`FixedParams`] at the start, [`LiveParams`] while it runs, [`Measurement`]); every fit
//! ends with [`Fit::finish`]:
//!
//! - **The paper's network** ([`FitParams::paper`]). A sample is `(γ(s, t), ζ(s, t))` with
//!   `γ = (x₁, y₁, x₂, y₂)`, the sender point `x = point(s)` and receiver point `y = point(t)`,
//!   mapped into the scene's unit box by an [`InputFrame`](flatland_solve::InputFrame) so that
//!   nothing depends on units or origin; `ζ = E'(sender) · k(s, t)`. `S₀` is uniform random.
//!   Whenever `|A| / |S| > ψ` a new set is made by scanning candidates with
//!   `θ(ξ) = ρ_ACC(ξ) ∨ ¬ρ_A(ξ)` (the printed `∧` is an erratum): a candidate costs a ray only if
//!   it falls in a critical zone or outside the network. Training draws a set uniformly, then a
//!   sample from it; the [`sgcs::Network`] inserts a cell every λ steps.
//! - **The visibility network** ([`FitParams::default`], [`Head::Visibility`]). `ζ = E' ρ G · V`, and
//!   everything but `V` is known in closed form, as is `V` itself on every pair of surface
//!   edges the geometry proves unoccluded or fully blocked. So the network learns only `V`,
//!   only where it varies, and `ζ̃ = ζ_unoccluded · Ṽ`. On such a pair `V` is constant on the
//!   faces cut out by the curves of the pair's visibility event points
//!   ([`flatland_geom::PairEvents`]); each cell belongs to one face and only the cells of a
//!   query's face respond ([`Gating::Faces`]), with a normalised output, so a face with a cell
//!   is exact and the error lives only in faces no cell has found yet. Samples are drawn where
//!   the unoccluded ζ is large, errors weighted accordingly, and new cells go to the worst
//!   sample. Same sets, θ and growth schedule as the paper.
//! - **Errors** are measured only against a [`Reference`](flatland_solve::Reference) the fit
//!   never trains on: the exact ζ on a midpoint grid and at held-out random points
//!   ([`relative_l2`](flatland_solve::relative_l2)).
//! - **Rays** counted are exact kernel evaluations made for training; evaluation is not counted.
//! - **Solving.** A kernel is learned to be used: [`LearnedKernel`] (and a running [`Fit`])
//!   implements [`flatland_solve::Representation`], the one trait the solver and the error
//!   measures take; a visibility model brings its own operator, the closed-form transfer times
//!   its `Ṽ` on each face, integrated exactly.
//!
//! ```
//! use std::sync::Arc;
//! use flatland_geom::{DVec2, Edge, Kernel, Scene};
//! use flatland_solve::{Reference, Representation};
//! use kernel_fit::{Fit, FitParams, StopReason};
//!
//! // A lit floor, a ceiling, and a blocker between them casting a shadow.
//! let v = DVec2::new;
//! let scene = Scene::new(vec![
//!     Edge::surface(v(0.0, 0.0), v(2.0, 0.0), 0.5).with_emission(1.0),
//!     Edge::surface(v(2.0, 1.0), v(0.0, 1.0), 0.5),
//!     Edge::blocker(v(0.8, 0.5), v(1.2, 0.5)),
//! ])?;
//! let kernel = Arc::new(Kernel::new(scene));
//! let reference = Arc::new(Reference::new(&kernel, 64, 1024, 7));
//! let params = FitParams { target_cells: 50, ..FitParams::default() };
//! let mut fit = Fit::new(Arc::clone(&kernel), reference, params)?;
//! let summary = fit.run(1000, |_| std::ops::ControlFlow::Continue(()))?;
//! // The shadow's few faces are soon all found: the learned kernel is then exact.
//! assert_eq!(summary.stop, StopReason::Converged);
//! assert!(summary.errors.heldout < 1e-9, "{summary:?}");
//! let (s, t) = (0.3, 0.7);
//! assert!((fit.model().zeta(s, t) - kernel.zeta(s, t)).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

mod error;
mod fit;
pub mod limits;
mod model;
mod params;
pub mod seeds;
mod summary;
mod visibility;

pub use error::FitError;
pub use fit::{CellSnapshot, Fit, HistoryPoint, INPUT_DIM, LearnedKernel, Snapshot};
pub use limits::REFERENCE_SEED;
pub use model::{MODEL_FORMAT, MODEL_VERSION, ModelFile, fingerprint_hex};
pub use params::{
    FitParams, FixedParams, Gating, Head, LiveParams, Measurement, NetworkRates, NetworkRules,
    Preset, Refit, Resampling, Target, ValidParams, VisibilityParams, parameter_table,
};
pub use sgcs::schema::{self, Schema, Spec};
pub use summary::{FitSummary, StopReason};
