//! Flatland geometry: 2D scenes, their arc-length parameterization, exact visibility and the
//! radiosity kernel `k(s, t)` of Bohn (1996), with the errata of the printed paper listed in docs/ALGORITHM.md §2.
//!
//! # Conventions
//! - A [`Scene`] is a list of [`Edge`]s (segments, `f64`). The **front** of an edge is the left
//!   of `a → b`; its normal is `perp(b − a)/|b − a|` with `perp(x, y) = (−y, x)`, so a room
//!   listed counter-clockwise faces inwards. Surfaces are one-sided (a thin wall is two edges
//!   back to back, or a box); only a blocker may be marked two-sided.
//! - **Surfaces** are parameterized: laid end to end in file order, total length `L`;
//!   `s ∈ [0, 1)` walks arc length `s·L` ([`Scene::point`]). **Blockers** only occlude.
//! - `s` is the **sender** `x = point(s)`, `t` the **receiver** `y = point(t)`. Reflection
//!   happens at the receiver: `k(s, t) = ρ(e_y) · cos_x cos_y / (2r) · V(x, y)` — note `1/(2r)`,
//!   not the paper's `1/(2πr)` — and `ζ(s, t) = E'(e_x) · k(s, t)` is the learning target.
//!
//! # Visibility
//! `V(x, y) = 1` iff the open segment `x–y` meets no closed edge other than `e_x`, `e_y` (and
//! other pieces of their parent edges). A ray that **grazes** an occluder (touches an end point,
//! or runs along it) is **blocked**; the end points `x`, `y` themselves never block. Every
//! decision uses exact orientation predicates, and `V(x, y) = V(y, x)`. Per pair of parent
//! edges a cached shaft classification skips rays that cannot matter; the rest go through a BVH.
//!
//! # Example
//! ```
//! use flatland_geom::{DVec2, Edge, Kernel, Scene};
//! // A unit square room, counter-clockwise so it faces inwards; the floor emits.
//! let p = [DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)];
//! let edges = (0..4)
//!     .map(|i| Edge::surface(p[i], p[(i + 1) % 4], 0.5).with_emission(if i == 0 { 1.0 } else { 0.0 }))
//!     .collect();
//! let scene = Scene::new(edges)?;
//! assert_eq!(scene.total_length(), 4.0);
//! let kernel = Kernel::new(scene);
//! // From the middle of the floor (s = 0.125) to the middle of the ceiling (t = 0.625):
//! // r = 1, both cosines 1, so k = ρ · 1 / 2.
//! assert!((kernel.k(0.125, 0.625) - 0.25).abs() < 1e-12);
//! assert_eq!(kernel.k(0.1, 0.2), 0.0); // same edge
//! # Ok::<(), flatland_geom::GeomError>(())
//! ```

#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod bundled;
mod error;
pub mod generate;
mod hashing;
mod ids;
mod io;
mod kernel;
mod overlap;
mod scene;
pub mod versioned;
mod visibility;
mod walk;

#[cfg(test)]
mod test_support;
// The tests' `assert_close!` (the workspace's), at the crate root where they name it.
#[cfg(test)]
use flatland_testkit::assert_close;

pub use error::GeomError;
pub use glam::DVec2;
pub use ids::{EdgeId, SurfaceRank};
pub use io::{AtomicFile, write_atomic};
pub use kernel::{
    Hit, Kernel, KernelParams, KernelSample, PairClass, PairEventsRef, Unoccluded, VaryingPairs,
};
pub use scene::{Edge, LightCheck, PointLight, Role, Scene, SurfacePoint};
pub use visibility::{OnRay, PairEvents, RayFace, SenderFace};
pub use walk::{MAX_POSITIONS, MAX_TURN, PROBES, START_SAMPLES, Walk, WalkParams, in_a_room, walk};
