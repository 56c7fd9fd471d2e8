//! The kernel's query results: a sample, a ray's hit, a pair's class, `k` unoccluded.

use glam::DVec2;

use crate::scene::SurfacePoint;
use crate::{EdgeId, SurfaceRank};

/// Everything [`Kernel::eval`](crate::Kernel::eval) knows about one `(s, t)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelSample {
    /// Sender `x = point(s)`.
    pub x: SurfacePoint,
    /// Receiver `y = point(t)`.
    pub y: SurfacePoint,
    /// `G(x, y) = cos_x cos_y / (2 r)` (0 on the same parent edge or when `x = y`).
    pub geometry: f64,
    /// `V(x, y)`.
    pub visible: bool,
    /// `k(s, t)`, exactly what [`Kernel::k`](crate::Kernel::k) returns.
    pub k: f64,
    /// `ζ(s, t) = E'(e_x) · k(s, t)`.
    pub zeta: f64,
}

/// Where a ray first meets an edge ([`Kernel::first_hit`](crate::Kernel::first_hit)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// The edge met (of a subdivided edge, the piece).
    pub edge: EdgeId,
    /// The distance from the ray's origin to `point`.
    pub distance: f64,
    /// The point met: on the edge up to rounding, and exactly an end point where the ray
    /// touches one (or the first point of an edge it runs along).
    pub point: DVec2,
    /// Its fraction along the edge from `a` to `b`, in `[0, 1]`: `point ≈ edge.point_at(u)`.
    pub u: f64,
}

/// How visibility behaves over all facing rays between interior points of two parent surface
/// edges, known from geometry alone (see [`Kernel::pair_class`](crate::Kernel::pair_class)):
/// the kernel's one classification of a pair, from the shaft it keeps per pair. What a
/// `Varies` pair needs besides is asked of the kernel: the occluders its rays are tested
/// against ([`Kernel::pair_occluders`](crate::Kernel::pair_occluders)) and where its
/// visibility changes ([`Kernel::visibility_events`](crate::Kernel::visibility_events)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairClass {
    /// The same parent edge, or edges that never face each other: `k = 0`.
    Zero,
    /// No occluder cuts a facing ray between interior points of the edges: `V = 1`, no ray.
    /// (A ray from an end point may still be checked: one running along a wall that touches
    /// the pair's corner is blocked by the grazing rule.)
    Visible,
    /// Every such ray is blocked: `V = 0`, no ray.
    Hidden,
    /// Some rays are blocked and some are not; the boundaries are the curves of the pair's
    /// [`Kernel::visibility_events`](crate::Kernel::visibility_events).
    Varies,
}

/// The kernel at one `(s, t)` without its visibility: what geometry gives without a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unoccluded {
    /// Rank of the sender's parent surface edge (its place among the parent surface edges in
    /// parameter order; pieces of one subdivided edge share it).
    pub sender: SurfaceRank,
    /// Rank of the receiver's parent surface edge.
    pub receiver: SurfaceRank,
    /// The sender point `x = point(s)`.
    pub x: DVec2,
    /// The receiver point `y = point(t)`.
    pub y: DVec2,
    /// `ρ(e_y) · G(x, y)`: `k(s, t)` when `x` and `y` see each other (0 on one parent edge).
    pub k: f64,
    /// `E'(e_x) · ρ(e_y) · G(x, y)`: `ζ(s, t)` when `x` and `y` see each other.
    pub zeta: f64,
}
