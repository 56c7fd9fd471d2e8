//! Solve the Flatland radiosity equation with any kernel representation, and measure how far a
//! representation of the kernel is from the exact one. The crate's one job: everything a
//! representation is *measured with* — the solver and the error measures — so the learner and
//! the baselines above it are judged by the same code.
//!
//! Conventions: points are `glam::DVec2` in scene units, an edge's front is the left of
//! `a → b`, `s` is the sender parameter and `t` the receiver parameter, both in `[0, 1)`; grids
//! are row-major with row `i ↔ s = (i + ½)/R`.
//!
//! `B(y) = E(y) + ρ(y) ∫ G(x, y) V(x, y) B(x) dl_x` on the surface edges; in the kernel's
//! parameters, `B(t) = E(t) + ∫ k(s, t) B(s) L ds`. B is the radiosity *leaving* a point,
//! emission included; `B − E` is the reflected part, the only part a kernel decides.
//!
//! **Discretisation.** A [`Mesh`] splits every surface edge into elements (never straddling
//! two edges, default count from the scene: [`Mesh::default_elements`]; nested refinements by
//! [`Mesh::split`] and [`Mesh::cut`]); the unknown B is one value per element and the equation
//! is collocated at element midpoints `y_i`: `B_i = E_i + Σ_j K_ij B_j`,
//! `K_ij = ρ_i ∫_{element j} G(x, y_i) V(x, y_i) dl_x`. Midpoint collocation is second-order
//! accurate at the midpoints away from corners; between them B is read through the equation
//! (below).
//! **Operators.** Each representation supplies its `K` through one trait,
//! [`Representation`]:
//! - the exact kernel ([`flatland_geom::Kernel`]): the closed-form point-to-segment transfer
//!   `(sin φ₂ − sin φ₁) / 2` where the shaft test proves a pair of edges clear, and the exact
//!   visible part of each element elsewhere — no rays, no quadrature, so the solve converges as
//!   elements are refined. Small scenes take it from a table of pairs of edges, dense
//!   ([`exact_operator`]); from [`SWEEP_FROM_EDGES`] edges on, a visibility sweep finds what
//!   each collocation point sees without forming pairs and keeps only that, sparse
//!   ([`sweep_operator`], [`SparseOperator`]): 10⁵ edges in seconds ([`ExactMethod`]);
//! - the default learned model (`kernel_fit::LearnedKernel`, which keeps `G` exact and learns
//!   `V`): the closed-form transfer of each piece of an element between the faces of the
//!   visibility structure, times the model's `Ṽ` on that face — its own kernel, integrated
//!   exactly, with no ray; the paper's network (which learns ζ itself): Gauss–Legendre
//!   quadrature of `k̃ = ζ̃ / E'` (the default of the trait, [`quadrature_operator`]);
//! - hierarchical radiosity and the uniform grid (`flatland_baselines`): their own links or
//!   blocks, gathered and pushed–pulled ([`RectangleOperator`]).
//!
//! **Energy.** In a closed room of one-sided surfaces without blockers every sender's light
//! lands on a surface (`∫ G V dl_y = 1`), so the power the surfaces absorb, `∫ (1 − ρ) H dl`
//! with H the irradiance `(B − E) / ρ`, equals the power emitted, `∫ E dl` (tested to 0.2 % at
//! 512 elements). Blockers absorb too. Surfaces are one-sided (flatland-geom refuses a
//! two-sided one: its one B would gather from both half-planes, row sums up to 2ρ); a thin
//! wall is two faces back to back.
//!
//! **Linear solve.** Restarted GMRES on `(I − K) B = E` to a relative residual
//! [`SolveParams::tolerance`] (default 1e-10); it needs only `I − K` invertible, not `‖K‖ < 1`.
//!
//! **Relighting.** One scene lit by point lights that move: a [`Relighter`] builds the exact
//! operator once, by rows and by columns, and per move computes the direct light by one view
//! per light, the first bounce `K B₀` from the columns of the lit elements only, and the later
//! bounces by GMRES warm-started from the last move's ([`Relighter::relight`]); [`cold_solve`]
//! is the one-off solve a move is checked against.
//!
//! **B as a function.** A solved scene answers B at any surface point by the equation itself,
//! the final gather `B(y) = E(y) + ρ(y) (H(y) + Σ_j B_j ∫_{element j} G V)` ([`FinalGather`],
//! H the point lights' exact direct irradiance at y,
//! [`ExactReference::radiosity_at`]): one view of the sweep per point, the solve's own value
//! at each midpoint, and far closer to the exact B between them than the elements' values read
//! as steps (0.3–0.6 % against 4–8 % on generated scenes at the same elements;
//! docs/FUNCTION-ERROR.md). [`FunctionSolve`] solves a mesh and its Gauss refinement (each
//! element cut in three so the new midpoints are its Gauss points) from one view per Gauss
//! point and estimates the relative L2 error of `B − E` as a function from them
//! ([`FunctionEstimate`], 1.3–1.5 times the error measured against solves 16 times finer);
//! [`solve_to_tolerance`] refines the mesh where that estimate puts the error until it meets a
//! tolerance (1 % by default, [`ToleranceParams`]), and [`SamplePoints`] measures two functions
//! against each other.
//!
//! **Scoring a lighting.** [`ExactReference`] solves the exact kernel on a fine mesh once and
//! gives the exact B at any surface point (by the equation itself: `E + ρ ∫ G V B` with the
//! fine B, the Nyström interpolation). A [`LitScene`] scores every lighting as a function
//! against it ([`FunctionReference`]: the reference gathered once at 8 points per element; a
//! solution read by its own gather where it has one, else as the line through its element
//! midpoints, [`midpoint_line`]). [`solve_errors`] and [`solve_against`] compare two B on the
//! same elements at their collocation points only.
//!
//! ```
//! use flatland_geom::{Kernel, bundled};
//! use flatland_solve::{SolveParams, ToleranceParams, never, solve_to_tolerance};
//!
//! // The maze lit to 1 % as a function, and B at 8 evenly spaced points in every element.
//! let kernel = Kernel::new(bundled::scene("maze")?);
//! let params = ToleranceParams::default();
//! let done = solve_to_tolerance(&kernel, &params, &SolveParams::default(), &never)?;
//! assert!(done.solve.estimate.estimate <= params.tolerance);
//! let samples = done.solve.samples(8, &never)?;
//! assert_eq!(samples.len(), 8 * done.solve.coarse.mesh().len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **Errors of ζ.** A [`Reference`] holds the exact ζ on a midpoint grid and at held-out random
//! points; [`Reference::errors`] gives a representation's relative L2 and L1 on both
//! ([`Errors`], docs/ALGORITHM.md §5).
//!
//! ```
//! use flatland_geom::{DVec2, Edge, Kernel, Scene};
//! use flatland_solve::{Mesh, SolveParams, never, solve};
//!
//! // A closed square room, uniform ρ = 0.5 and E = 1 everywhere: B = E / (1 − ρ) = 2.
//! let p = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)];
//! let edges = (0..4).map(|i| Edge::surface(p[i], p[(i + 1) % 4], 0.5).with_emission(1.0)).collect();
//! let kernel = Kernel::new(Scene::new(edges)?);
//! let mesh = Mesh::new(&kernel, 64)?;
//! let solution = solve(&kernel, &mesh, &SolveParams::default(), &never)?;
//! assert!(solution.radiosity.iter().all(|b| (b - 2.0).abs() < 1e-9));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]

mod adapt;
mod bvh;
mod discretization;
mod error;
mod exact;
mod field;
mod frame;
mod gmres;
mod lights;
mod lit;
mod mesh;
mod operator;
mod physical;
mod quadrature;
mod reference;
mod relight;
mod represent;
mod score;
mod settings;
mod solve;
mod sparse;
mod sweep;
mod table;
mod transfer;

pub mod seeds;

#[cfg(test)]
mod independent;
#[cfg(test)]
mod test_support;

pub use adapt::{
    RefinementRound, ToleranceParams, ToleranceSolve, initial_elements, refine_for,
    solve_to_tolerance,
};
pub use discretization::{
    DEFAULT_ERROR_BOUND, FUNCTION_SAFETY, FunctionEstimate, FunctionSolve, gauss_refinement,
};
pub use error::SolveError;
pub use exact::{
    ExactMethod, SWEEP_FROM_EDGES, check_scene, exact_block_means, exact_operator, receiver, sender,
};
pub use field::{ALONG, FieldSample, FinalGather, SamplePoints, line_along, midpoint_line};
pub use frame::InputFrame;
pub use lights::{DirectLight, LightBuffers, LitSurfaces};
pub use lit::{Elements, LitFunction, LitParams, LitScene, ReferenceMesh, check_elements};
pub use mesh::{
    DEFAULT_ELEMENTS, Element, MAX_ELEMENTS, MAX_MESH_ELEMENTS, MIN_PER_EDGE, Mesh, MeshEdge,
};
pub use operator::{DenseOperator, KernelRectangle, RectangleOperator, TransferOperator};
pub use physical::make_physical;
pub use quadrature::gauss_legendre;
pub use reference::{
    BOOTSTRAP_RESAMPLES, Errors, Reference, bootstrap_l2, density_ratio, discontinuity_mask,
    grid_point, relative_l1, relative_l2,
};
pub use relight::{ColdSolve, MoveCost, RelightParams, Relighter, Relit, WarmStart, cold_solve};
pub use represent::{
    Representation, check_fingerprint, check_lights, inverse_source_weights, quadrature_operator,
};
pub use score::{FunctionReference, SCORE_POINTS_PER_ELEMENT};
pub use settings::{SolveParams, Stop, never};
pub use solve::{
    Comparison, ExactReference, Solution, SolveErrors, solve, solve_against, solve_errors,
    solve_linear, solve_operator,
};
pub use sparse::{MAX_NONZEROS, SparseOperator, predicted_nonzeros};
pub use sweep::{ProbeBuffers, SeenSpan, Sweep, sweep_operator};
pub use table::{RADIOSITY_HEADER, radiosity_csv, radiosity_rows, samples_csv};
pub use transfer::{Receiver, Sender, point_to_segment, point_to_segment_visible};
