//! Supervised growing cell structures (SGCS): Fritzke's growing cell structures (1993) with a
//! radial-basis output layer and the resource term of Bohn (1996, §3.2). The crate learns any
//! `f: Rⁿ → Rᵐ` from samples `(ξ, ζ)` and knows nothing about where they come from.
//!
//! # The model
//! Cells `c` have a position `w_c ∈ Rⁿ`, an output weight `v_c ∈ Rᵐ` and a width `δ_c` (the mean
//! length of the cell's edges). The cells form a graph made of triangles only (`k = 2`), starting
//! from one triangle. The output is `κ(ξ) = Σ_c v_c M_c(ξ)` with
//! `M_c(ξ) = exp(−|ξ − w_c|² / δ_c²)`. One [`Network::step`]:
//!
//! 1. finds the best matching unit `s = argmin_c |w_c − ξ|` (lowest id on ties),
//! 2. updates every active cell's output weight (the delta rule, see [`OutputRule`]),
//! 3. adds `|ζ − κ(ξ)|²` to `s`'s resource counters,
//! 4. moves `s` by `ε_b (ξ − w_s)` and its neighbours by `ε_n (ξ − w_b)`,
//! 5. every `λ` steps inserts a cell (below).
//!
//! # Conventions and choices (docs/ALGORITHM.md §3, and where the paper leaves room)
//! - **Counters.** The paper keeps `τ_err` and `τ_cnt` and multiplies both by `1 − α` every step,
//!   for every cell: `O(|A|)` work per step, and after 20 000 idle steps both are `0.95^20000`,
//!   i.e. 0 or subnormal, and `τ_err / τ_cnt` is `0/0`. Only the ratio matters, and it is a
//!   weighted mean that a common decay factor does not change. So each cell stores that mean
//!   ([`Network::mean_error`]) and `τ_cnt` as of the step it was last hit; `(1 − α)^Δt` is applied
//!   when the cell is hit again (`O(1)` per step, factors below `e^-700` are 0). Step `t`'s
//!   sample has weight 1 and a sample from step `u` weight `(1 − α)^(t−u)`. A cell never hit has
//!   mean 0. The resource is `τ_c = mean_c · |F_c|` with `|F_c| = δ_c^k`, `k = 2`.
//! - **Insertion.** Every `λ` steps (while `len() < max_cells`): `q = argmax τ_c`, `f` = the
//!   neighbour across `q`'s longest edge, `r` at the edge's midpoint; edge `q–f` is removed and every
//!   triangle `q-f-c` becomes `q-r-c` and `r-f-c`, so `r` joins `q`, `f` and the common corners.
//! - **Counter redistribution** (as SOMToolbox's `GrowingCellLayer`): each neighbour `c` of `r`
//!   changes by `Δτ_c = (|F_c|new − |F_c|old) / |F_c|old · τ_c`. Because `τ_c = mean_c · |F_c|`,
//!   keeping `mean_c` and recomputing `|F_c|` from the new widths *is* that rule. `r` receives what
//!   they lose, `τ_r = max(0, −Σ Δτ_c)` (a neighbour can gain volume; the total is clamped at 0),
//!   stored as `mean_r = τ_r / |F_r|` with weight `Σ_c max(0, 1 − |F_c|new/|F_c|old) · τ_cnt,c`.
//! - **New output weight** ([`InsertRule`]): by default `v_r` keeps `κ(w_r)` unchanged by the
//!   insertion (`v_r = κ_before(w_r) − κ_after(w_r)` with `v_r = 0`, as `M_r(w_r) = 1`). The
//!   volume-weighted mean the paper's text suggests ([`InsertRule::VolumeWeighted`], kept as an option) adds
//!   `≈ v̄` on top of an output already built by several overlapping cells (`D_A` is 3 to 12
//!   inside a grown network), a jump the delta rule must then unlearn. Measured on the
//!   bump-and-ridge test, 400 cells: held-out relative L2 0.213 vs 0.231 (λ = 300), 0.256 vs
//!   0.282 (λ = 100); the tests `insertion_splits_the_longest_edge_of_the_worst_cell` and
//!   `preserve_rule_learns_at_least_as_well_as_volume_weighted` check both properties.
//! - **Stability** ([`OutputRule::Normalized`], default): the step is divided by
//!   `max(1, Σ M_c²)`, so it equals the paper's rule in sparse networks and cannot diverge where
//!   cells overlap: the error of the presented sample is multiplied by `1 − η min(1, Σ M_c²)`,
//!   which lies in `(−1, 1)` for `η ∈ (0, 2)`. The plain rule multiplies it by `1 − η Σ M_c²`
//!   and diverges once `η Σ M_c² > 2`; grown networks have `Σ M_c² > 1` (overlapping cells), so
//!   it is safe only for small enough `η` (test `plain_rule_diverges_where_normalized_does_not`).
//! - **Activation cutoff** ([`Params::activation_cutoff`], default `1e-8`): cells with
//!   `M_c(ξ) < cutoff` are skipped, i.e. those farther than `δ_c · sqrt(ln(1/cutoff))`. Every sum
//!   (`κ`, `D_A`, `D_ACC`, the update) uses exactly the cells at or above the cutoff, summed in id
//!   order, so results are the brute-force ones bit for bit and never depend on the spatial index.
//! - **Speed.** A bounding-volume k-d tree over the positions answers the nearest-cell query
//!   exactly (branch and bound) and finds the active cells: each node also bounds its cells'
//!   activation balls `|ξ − w_c| ≤ δ_c sqrt(ln(1/cutoff))` (a "reach box" and the largest width),
//!   so cells of very different widths are pruned correctly. The tree is updated conservatively
//!   (boxes only grow) as cells move, widen or are inserted, and rebuilt after enough growth or
//!   drift. A step touches the active cells (about 140 at 4000 cells for inputs on a 2D surface in
//!   R⁴), not all cells, and its cost grows only with the local overlap, not with `len()`. A
//!   network of up to 1024 cells scans them all instead: its supports are wide, so a tree query
//!   would visit most leaves anyway. Measured (`benches/sgcs_step.rs`, n = 4, m = 1, a shared
//!   2-core machine): with [`Params::default`] a step takes 2.2 µs at 100 cells, 6.0 µs at 400
//!   and 12.8 µs at 4000; configured like kernel-fit's visibility network, 0.44, 0.69 and 1.7 µs.
//!   Widths are cached and refreshed for the cells whose edges moved.
//! - **Numbers.** Inputs and targets must be finite and at most `1e100` in magnitude
//!   ([`Network::try_step`] rejects others); widths are floored at `1e-100`. No value becomes NaN
//!   with the default output rule.
//! - **Determinism.** No randomness inside, no hash-map iteration: the same samples in the same
//!   order give the same network, bit for bit, including across save/load.
//! - Cells are never removed, so a [`CellId`] is stable; callers keep per-cell statistics keyed by
//!   [`StepOutcome::bmu`] and push a slot when [`StepOutcome::inserted`] is `Some`.
//! - **Refit** (beyond the paper): [`Network::refit_outputs`] solves ridge least squares for all
//!   output weights at fixed centres and widths (sparse normal equations assembled in bounded
//!   memory, sparse Cholesky); [`Network::refit_system_split`] + [`RefitSystem::solve`] try
//!   several ridges on one assembly and score them on held-back samples without revisiting
//!   any sample.
//!   A relative ridge near `1e-3` generalises best in our tests; see the `refit` module notes on
//!   [`RefitReport`].
//!
//! # Tests and the soak
//! `cargo test -p sgcs` runs in seconds. The 10⁷-step soak (idle phases, spikes, counters
//! checked for subnormals) is an ignored test: `cargo test --release -p sgcs -- --ignored soak`.
//! The step benchmark is the workspace bench `cargo bench --bench sgcs_step`.
//!
//! # Example
//! ```
//! use sgcs::{Network, Params};
//!
//! let params = Params { lambda: 100, ..Params::default() };
//! let simplex = vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]];
//! let mut net = Network::new(params, 2, 1, &simplex).unwrap();
//! // Learn f(x, y) = x + y on the unit square from a simple deterministic sample stream.
//! for i in 0..20_000u32 {
//!     let x = f64::from(i % 97) / 96.0;
//!     let y = f64::from(i % 89) / 88.0;
//!     let outcome = net.step(&[x, y], &[x + y]);
//!     assert!(outcome.bmu < net.len());
//! }
//! assert_eq!(net.len(), 3 + 200);
//! net.check_invariants().unwrap();
//! assert!((net.predict1(&[0.5, 0.5]) - 1.0).abs() < 0.3);
//! let copy = sgcs::Network::from_json(&net.to_json()).unwrap();
//! assert_eq!(copy.predict1(&[0.3, 0.6]), net.predict1(&[0.3, 0.6]));
//! ```
#![deny(missing_docs)]
#![forbid(unsafe_code)]
// Index loops over small vector dimensions read like the formulas they implement.
#![allow(clippy::needless_range_loop)]

mod error;
mod index;
mod network;
mod params;
mod refit;
pub mod schema;
#[cfg(test)]
mod test_support;

pub use error::SgcsError;
pub use network::{CellId, FORMAT_VERSION, Gate, Network, Open, SIMPLEX_DIM, StepOutcome};
pub use params::{InsertRule, Insertion, OutputMode, OutputRule, Params, Resource};
pub use refit::{RefitPart, RefitProgress, RefitReport, RefitStage, RefitSystem};
