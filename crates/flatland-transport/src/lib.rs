//! The learned transport of a fixed scene's later bounces, so that a point light can move
//! through a level and be relit in a fraction of a millisecond, light bouncing off walls, rooms
//! off screen contributing, no light through walls (docs/ALGORITHM.md §9).
//!
//! **The split.** With the scene and mesh fixed, a light at `p` changes only the source:
//! `B = (I − K)⁻¹ B₀(p) = B₀ + K B₀ + M₂ B₀`, `M₂ = K² (I − K)⁻¹` the second and later bounces.
//! B₀ is exact and cheap (one view of the sweep from `p`: [`lit_source`]), and so is the first
//! bounce `K B₀` (only the columns of K of the elements the light lit). What is left to learn
//! is `M₂`, a smooth operator — two bounces blur every shadow — and block-structured: rooms far
//! apart decouple.
//!
//! **The form.** [`Transport`] (the default, and the winner of the measurements in
//! docs/ALGORITHM.md §9): elements are clustered by a spatial tree (a cluster is a room or a
//! few walls of one); per cluster `c` the block of columns `M₂[:, c]` is computed exactly by
//! local shooting solves that touch only the rooms its light reaches, rows whose share is
//! below the tolerance are dropped, and what is left is truncated by its singular values:
//! `M₂[:, c] ≈ U_c V_cᵀ`. Set-up grows with the number of rooms, not their square; a query
//! touches the few clusters the light lit. It estimates its own error on lights it draws itself
//! ([`ErrorEstimate`]), reports its bytes, and saves and loads as a versioned file refused for
//! another scene or mesh. Two other forms are measured against it through the same
//! [`LaterBounces`] trait: [`LightProbes`] (what game light-probe grids do) and
//! [`CellNetwork`] (the paper's growing cells on `M₂(s, t)`).
//!
//! Conventions: as `flatland_solve`'s (elements in the mesh's order, `B` the radiosity leaving
//! a point, lengths in scene units). B₀ here is what the moving lights add (`ρ H̄`, no static
//! emission): the transport is linear, so static light is solved once by the caller.
//!
//! ```
//! use flatland_geom::{Kernel, PointLight, generate};
//! use flatland_solve::{DirectLight, LightBuffers, Mesh, SolveParams, never, solve_linear, sweep_operator};
//! use flatland_transport::{Columns, QueryBuffers, Transport, TransportParams, lit_source};
//!
//! // A generated floor plan, its lamps removed: one light will move through it.
//! let plan = generate::floor_plan_lit(150, 3)?;
//! let lamp = plan.lights()[0];
//! let kernel = Kernel::new(plan.with_lights(Vec::new())?);
//! let mesh = Mesh::new(&kernel, 3 * Mesh::min_elements(kernel.scene()))?;
//! let k = sweep_operator(&kernel, &mesh, &never)?;
//! // Built once.
//! let transport = Transport::build(&kernel, &mesh, &k, &TransportParams::default(), &never)?;
//! // One move: B₀ by one view, K B₀ from the lit columns, M₂ B₀ from the model.
//! let direct = DirectLight::new(&kernel, &mesh)?;
//! let b0 = lit_source(&direct, &mesh, &[lamp], &mut LightBuffers::default());
//! let columns = Columns::of(&k);
//! let mut b = vec![0.0; mesh.len()];
//! for &(j, v) in &b0 {
//!     b[j as usize] += v;
//!     let (rows, values) = columns.column(j as usize);
//!     rows.iter().zip(values).for_each(|(&i, k_ij)| b[i as usize] += k_ij * v);
//! }
//! transport.add_later_bounces_of(&b0, &mut b, &mut QueryBuffers::default())?;
//! // Against the exact solve of B = B₀ + K B: within the model's own estimate, with room.
//! let mut dense = vec![0.0; mesh.len()];
//! b0.iter().for_each(|&(j, v)| dense[j as usize] = v);
//! let exact = solve_linear(&k, &dense, dense.clone(), &SolveParams::default(), &never)?.radiosity;
//! let norm = |f: &dyn Fn(usize) -> f64| {
//!     mesh.elements().iter().enumerate().map(|(i, e)| e.length * f(i).powi(2)).sum::<f64>().sqrt()
//! };
//! let error = norm(&|i| b[i] - exact[i]) / norm(&|i| exact[i]);
//! assert!(error < 3.0 * transport.estimated_error().b_max.max(1e-3), "{error}");
//! assert!(b.iter().all(|&v| v >= 0.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(missing_docs)]
#![forbid(unsafe_code)]

mod clusters;
mod columns;
mod error;
mod estimate;
mod file;
mod footprint;
mod free;
mod local;
mod lowrank;
mod network;
mod params;
mod probes;
mod query;
mod relit;
mod source;
#[cfg(test)]
mod test_support;
mod transport;

pub use columns::Columns;
pub use error::TransportError;
pub use file::{TRANSPORT_FORMAT, TRANSPORT_VERSION};
pub use flatland_solve::Stop;
pub use footprint::{BlockFootprint, Watch};
pub use network::{CellNetwork, NetworkParams};
pub use params::TransportParams;
pub use probes::{LightProbes, Placement, ProbeParams};
pub use query::{ErrorEstimate, LaterBounces, Move, QueryBuffers};
pub use relit::TransportRelighter;
pub use source::lit_source;
pub use transport::Transport;
