//! Exact visibility: the rule, decided by exact predicates, a BVH and per-pair shafts and events.
//!
//! # The rule
//! `V(x, y) = 1` iff the **open** segment `x–y` meets no **closed** occluding segment, where the
//! occluders are all edges (surfaces and blockers) except `e_x`, `e_y` and the other pieces of
//! their parent edges (see [`crate::Scene::subdivide`]). Consequences, all tested:
//! - *Grazing*: a ray that touches an occluder's end point, or runs along an occluder, is
//!   **blocked**. This makes closed blockers watertight (a ray through a shared corner of two
//!   blocker edges cannot slip between them) and makes `V` invariant under subdivision (a ray
//!   through the junction of two pieces is blocked exactly as a ray through the interior of the
//!   unsplit edge).
//! - The end points `x` and `y` themselves never block: an occluder touching `x` (e.g. the
//!   neighbouring wall at a room corner) does not hide anything from `x`.
//! - `V(x, y) = V(y, x)`: every predicate is symmetric in `x` and `y`.
//! - All decisions use Shewchuk's exact `orient2d` (the `robust` crate): no epsilons. The only
//!   floating-point tests are conservative culling (bounding boxes with a generous margin) that
//!   can only keep extra work, never change an answer.
//!
//! # Closest hit
//! A ray from `o` is the open segment from `o` to a point beyond the scene, so it meets an
//! edge by the same rule: touching an end point or running along an edge hits it (at the
//! first point of the overlap), `o` itself never does. Which edge it meets first is decided
//! exactly too: by orientations where one segment does not cross the other's line, and for
//! two segments that cross each other by an exact degree-4 comparison (expansion arithmetic).
//! Of several edges met at one point (a corner, a junction) the first listed wins.

mod boxes;
mod bundle;
mod bvh;
mod events;
mod expansion;
mod predicates;
mod ray;
mod shaft;
mod side;

pub(crate) use bundle::{Hull, cuts_bundle};
pub(crate) use bvh::{Bvh, Segment, wins_tie};
pub use events::{OnRay, PairEvents, RayFace, SenderFace};
pub(crate) use predicates::{on_closed_segment, open_segment_hits, orient};
pub(crate) use ray::{Contact, Ray};
#[cfg(test)]
pub(crate) use shaft::Candidates;
pub(crate) use shaft::{Shaft, classify};
pub(crate) use side::Side;
