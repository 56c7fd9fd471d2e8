//! Learn a Flatland scene's radiosity kernel with supervised growing cell structures
//! (C.-A. Bohn, *Efficiently Representing the Radiosity Kernel through Learning*, EGRW 1996).
//!
//! The job: turn an exact but expensive kernel ([`flatland_geom::Kernel`], one visibility query
//! per value) into a compact learned one, spending rays where the network is poor or absent.
//!
//! - **Inputs.** A sample is `(γ(s, t), ζ(s, t))` with `γ = (x₁, y₁, x₂, y₂)`, the sender point
//!   `x = point(s)` and receiver point `y = point(t)`, mapped into the scene's unit box by an
//!   [`InputFrame`] so that nothing depends on units or origin. `ζ = E'(sender) · k(s, t)`.
//! - **Sets.** `S₀` is uniform random. Whenever `|A| / |S| > ψ` a new set is made by scanning
//!   uniform candidates with `θ(ξ) = ρ_ACC(ξ) ∨ ¬ρ_A(ξ)` (SPEC erratum 3): a candidate costs a ray
//!   only if it falls in a critical zone or outside the network. The scan is bounded. Training
//!   draws a set uniformly, then a sample from it.
//! - **Growth.** The [`sgcs::Network`] inserts a cell every λ steps until the target count.
//! - **Errors** are measured only against a [`Reference`] the fit never trains on: the exact ζ on
//!   a midpoint grid and at held-out random points. [`relative_l2`] is SPEC §5's measure.
//! - **Rays** counted are exact kernel evaluations made for training; evaluation is not counted.
//!
//! ```
//! use std::sync::Arc;
//! use flatland_geom::{DVec2, Edge, Kernel, Role, Scene};
//! use kernel_fit::{Fit, FitParams, Reference};
//!
//! // Two facing walls, the lower one emitting.
//! let wall = |a: [f64; 2], b: [f64; 2], emission| Edge {
//!     a: DVec2::from(a), b: DVec2::from(b), reflectance: 0.5, emission,
//!     role: Role::Surface, two_sided: false,
//! };
//! let scene = Scene::new(vec![wall([0., 0.], [1., 0.], 1.0), wall([1., 1.], [0., 1.], 0.0)])?;
//! let kernel = Arc::new(Kernel::new(scene));
//! let reference = Arc::new(Reference::new(&kernel, 32, 256, 7));
//! let params = FitParams { target_cells: 20, ..FitParams::default() };
//! let mut fit = Fit::new(kernel, reference, params)?;
//! let summary = fit.run(1000, |_| std::ops::ControlFlow::Continue(()))?;
//! assert_eq!(summary.cells, 20);
//! assert!(summary.errors.heldout < 0.5, "{summary:?}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

pub mod baselines;
pub mod bench;
mod error;
mod eval;
mod fit;
pub mod limits;
mod model;
mod params;
mod sampling;

pub use error::FitError;
pub use eval::{
    Approximation, Errors, Reference, density_ratio, discontinuity_mask, grid_point, relative_l2,
};
pub use fit::{
    CellSnapshot, Fit, FitSummary, HistoryPoint, INPUT_DIM, LearnedKernel, RefitChoice, Snapshot,
    StopReason,
};
pub use limits::REFERENCE_SEED;
pub use model::{MODEL_FORMAT, MODEL_VERSION, ModelFile, fingerprint_hex};
pub use params::{FitParams, Resampling, Target};
pub use sampling::InputFrame;
