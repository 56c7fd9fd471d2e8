//! Exact visibility: orientation predicates, the segment test with its grazing rule, a BVH over
//! the parent edges, and the per-pair shaft classification.
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
//! - `V(x, y) = V(y, x)`: every predicate below is symmetric in `x` and `y`.
//! - All decisions use Shewchuk's exact `orient2d` (the `robust` crate): no epsilons. The only
//!   floating-point tests are conservative culling (bounding boxes with a generous margin) that
//!   can only keep extra work, never change an answer.

use glam::DVec2;
use robust::{Coord, orient2d};

/// Exact orientation: `> 0` if `c` is left of `a → b`, `< 0` right, `0` on the line.
#[inline]
pub(crate) fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    orient2d(
        Coord { x: a.x, y: a.y },
        Coord { x: b.x, y: b.y },
        Coord { x: c.x, y: c.y },
    )
}

#[inline]
fn strictly_same_side(o1: f64, o2: f64) -> bool {
    (o1 > 0.0 && o2 > 0.0) || (o1 < 0.0 && o2 < 0.0)
}

/// Whether the open segment `(x, y)` meets the closed segment `[p, q]` (the grazing rule above).
#[inline]
pub(crate) fn open_segment_hits(x: DVec2, y: DVec2, p: DVec2, q: DVec2) -> bool {
    let o1 = orient(x, y, p);
    let o2 = orient(x, y, q);
    if strictly_same_side(o1, o2) {
        return false;
    }
    if o1 == 0.0 && o2 == 0.0 {
        return collinear_overlap(x, y, p, q);
    }
    // Line x–y meets [p, q] in one point c. It lies strictly inside (x, y) iff x and y are
    // strictly on opposite sides of line p–q; if x (or y) is on that line, c is x (or y).
    let o3 = orient(p, q, x);
    let o4 = orient(p, q, y);
    (o3 > 0.0 && o4 < 0.0) || (o3 < 0.0 && o4 > 0.0)
}

/// Exactly collinear `x, y, p, q`: does the open `(x, y)` overlap the closed `[p, q]`?
fn collinear_overlap(x: DVec2, y: DVec2, p: DVec2, q: DVec2) -> bool {
    if x == y {
        return false;
    }
    // On one line the order along the line is the order of either coordinate that varies.
    let key = |v: DVec2| if x.x != y.x { v.x } else { v.y };
    let (s0, s1) = (key(x).min(key(y)), key(x).max(key(y)));
    let (o0, o1) = (key(p).min(key(q)), key(p).max(key(q)));
    o0 < s1 && o1 > s0
}

/// An occluding segment (a parent edge) with its index.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Segment {
    pub a: DVec2,
    pub b: DVec2,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec2,
    hi: DVec2,
    /// Leaf: first index into `items`; inner: left child.
    first: u32,
    /// Leaf: number of items (> 0); inner: 0.
    count: u32,
    /// Inner: right child.
    right: u32,
}

const LEAF_SIZE: usize = 4;

/// A bounding volume hierarchy over segments (median split on the longer axis of the
/// centroids), so a ray tests about `log n` boxes instead of `n` segments.
#[derive(Clone, Debug)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

impl Bvh {
    pub(crate) fn new(segments: &[Segment]) -> Bvh {
        let mut items: Vec<u32> = (0..segments.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * segments.len() / LEAF_SIZE + 2);
        if !segments.is_empty() {
            build(segments, &mut items, 0, &mut nodes);
        }
        Bvh { nodes, items }
    }

    /// Visits every item in a leaf whose box `pass` accepts (inner boxes must pass too).
    /// Stops and returns true as soon as `visit` does.
    #[inline]
    fn any(
        &self,
        mut pass: impl FnMut(DVec2, DVec2) -> bool,
        mut visit: impl FnMut(u32) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        // Depth is about log2(n / LEAF_SIZE) for a median split; 64 levels is ample.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = self.nodes[stack[top] as usize];
            if !pass(node.lo, node.hi) {
                continue;
            }
            if node.count > 0 {
                let items = &self.items[node.first as usize..(node.first + node.count) as usize];
                if items.iter().any(|&i| visit(i)) {
                    return true;
                }
            } else {
                stack[top] = node.right;
                stack[top + 1] = node.first;
                top += 2;
            }
        }
        false
    }

    /// Whether the open segment `(x, y)` meets any segment except `skip_a` and `skip_b`.
    pub(crate) fn any_hit(
        &self,
        segments: &[Segment],
        x: DVec2,
        y: DVec2,
        skip_a: usize,
        skip_b: usize,
    ) -> bool {
        let lo = x.min(y);
        let hi = x.max(y);
        let d = y - x;
        let scale = d.x.abs() + d.y.abs();
        self.any(
            |nlo, nhi| {
                if nlo.x > hi.x || nlo.y > hi.y || nhi.x < lo.x || nhi.y < lo.y {
                    return false;
                }
                // Conservative side test: skip a box clearly on one side of the line x–y.
                let mut pos = false;
                let mut neg = false;
                for c in [nlo, nhi, DVec2::new(nlo.x, nhi.y), DVec2::new(nhi.x, nlo.y)] {
                    let e = c - x;
                    let cross = d.x * e.y - d.y * e.x;
                    let tol = 1e-12 * scale * (e.x.abs() + e.y.abs());
                    pos |= cross >= -tol;
                    neg |= cross <= tol;
                }
                pos && neg
            },
            |i| {
                let i = i as usize;
                i != skip_a && i != skip_b && open_segment_hits(x, y, segments[i].a, segments[i].b)
            },
        )
    }

    /// Indices of the segments whose boxes overlap the closed box `[lo, hi]`, sorted.
    pub(crate) fn overlapping(&self, segments: &[Segment], lo: DVec2, hi: DVec2) -> Vec<u32> {
        let apart =
            |alo: DVec2, ahi: DVec2| alo.x > hi.x || alo.y > hi.y || ahi.x < lo.x || ahi.y < lo.y;
        let mut out = Vec::new();
        self.any(
            |nlo, nhi| !apart(nlo, nhi),
            |i| {
                let s = segments[i as usize];
                if !apart(s.a.min(s.b), s.a.max(s.b)) {
                    out.push(i);
                }
                false
            },
        );
        out.sort_unstable();
        out
    }
}

/// Builds the subtree over `items` (whose first element sits at `offset` in the full list) and
/// returns its node index.
fn build(segments: &[Segment], items: &mut [u32], offset: usize, nodes: &mut Vec<Node>) -> u32 {
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for &i in items.iter() {
        let s = segments[i as usize];
        lo = lo.min(s.a).min(s.b);
        hi = hi.max(s.a).max(s.b);
    }
    let index = nodes.len() as u32;
    nodes.push(Node {
        lo,
        hi,
        first: offset as u32,
        count: items.len() as u32,
        right: 0,
    });
    if items.len() <= LEAF_SIZE {
        return index;
    }
    let ext = hi - lo;
    let axis = usize::from(ext.y > ext.x);
    let key = |i: &u32| {
        let s = segments[*i as usize];
        (s.a + s.b)[axis]
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |p, q| key(p).total_cmp(&key(q)));
    let (left, right) = items.split_at_mut(mid);
    let l = build(segments, left, offset, nodes);
    let r = build(segments, right, offset + mid, nodes);
    nodes[index as usize] = Node {
        lo,
        hi,
        first: l,
        count: 0,
        right: r,
    };
    index
}

/// What a pair of parent surface edges `P`, `Q` needs for the visibility of its facing samples
/// (both cosines positive, checked exactly). Computed once per pair of *parent* edges, so
/// subdividing a scene does not multiply this work.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Shaft {
    /// No point pair faces each other (or all four end points are collinear): `k = 0`, no ray.
    NoFacing,
    /// No occluder meets the shaft: `V = 1`, no ray.
    Clear,
    /// This occluder cuts every segment from `P` to `Q`: `V = 0`, no ray.
    Blocked(u32),
    /// Only these occluders can cut a facing segment; see [`Candidates`].
    Candidates(Candidates),
}

/// The occluders of a shaft that some facing segments meet and others do not, and where the
/// answer can change (see [`PairEvents`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Candidates {
    /// The occluders (sorted) that can cut a facing segment.
    pub occluders: Box<[u32]>,
    /// Where visibility changes, for rays from `P` to `Q` and from `Q` to `P`; `None` when it
    /// cannot change between interior points.
    pub events: Option<Box<[PairEvents; 2]>>,
    /// Visibility of every segment between interior points of `P` and `Q`, when there are no
    /// events (decided by one ray).
    pub interior: Option<bool>,
}

/// Where the visibility between two parent surface edges `P` and `Q` can change.
///
/// Visibility between `x` on `P` and `y` on `Q` changes only where the segment `x–y` sweeps
/// over an **event point**: an end point of an occluder (the ray starts or stops meeting it),
/// or a point where an occluder crosses `P` or `Q` (an end of the ray crosses the occluder's
/// line on the occluder). A segment between interior points of `P` and `Q` lies inside the
/// convex hull of the two edges, touching its boundary only at its ends, so only event points
/// strictly inside that hull or on `P` or `Q` matter; the end points of `P` and `Q`
/// themselves are events only where the other edge reaches that edge's line (a ray through
/// one of them runs along that line). With no event point, visibility is the same for all rays
/// between interior points of `P` and `Q`.
///
/// **Faces.** When `P` and `Q` both lie on the boundary of their convex hull, a ray through an
/// event point has it between its ends, so in the `(s, t)` rectangle of the pair the rays
/// through one event point form one arc from border to border, two arcs cross at most once (one
/// line passes through two points), and the regions where a ray has every event point on the
/// same side are connected: visibility is constant on each. An edge that crosses the other's
/// line is first cut there into pieces that do not, giving up to four **sub-pairs**, each with
/// its own event points. So two rays with the same [`PairEvents::sub_pair`] and the same side
/// of each of that sub-pair's [`PairEvents::points`] have the same visibility.
#[derive(Clone, Debug, PartialEq)]
pub struct PairEvents {
    /// The lines of `P` and `Q` (end points).
    p: [DVec2; 2],
    q: [DVec2; 2],
    /// Whether `P` strictly crosses the line of `Q`, and `Q` that of `P`.
    split_p: bool,
    split_q: bool,
    /// Event points of sub-pair `2·side(x) + side(y)`.
    sub: [Box<[DVec2]>; 4],
}

impl PairEvents {
    /// The sub-pair (0..4) of the ray from `x` on `P` to `y` on `Q`: which side of the line of
    /// `Q` `x` is on, if `P` crosses it, and which side of the line of `P` `y` is on.
    #[must_use]
    #[inline]
    pub fn sub_pair(&self, x: DVec2, y: DVec2) -> usize {
        let sx = self.split_p && orient(self.q[0], self.q[1], x) > 0.0;
        let sy = self.split_q && orient(self.p[0], self.p[1], y) > 0.0;
        2 * usize::from(sx) + usize::from(sy)
    }

    /// The event points of sub-pair `sub` (empty for a sub-pair that does not exist).
    ///
    /// # Panics
    /// If `sub >= 4`.
    #[must_use]
    pub fn points(&self, sub: usize) -> &[DVec2] {
        &self.sub[sub]
    }

    /// Whether two rays from `P` to `Q` lie in the same face: the same sub-pair and the same
    /// [`PairEvents::side`] of each of its event points. Then their visibility is the same.
    #[must_use]
    pub fn same_face(&self, (x1, y1): (DVec2, DVec2), (x2, y2): (DVec2, DVec2)) -> bool {
        let sub = self.sub_pair(x1, y1);
        sub == self.sub_pair(x2, y2)
            && self.sub[sub]
                .iter()
                .all(|&v| PairEvents::side(x1, y1, v) == PairEvents::side(x2, y2, v))
    }

    /// The side of the ray `x → y` an event point `v` is on: `true` if strictly left (exact).
    #[must_use]
    #[inline]
    pub fn side(x: DVec2, y: DVec2, v: DVec2) -> bool {
        orient(x, y, v) > 0.0
    }

    /// For rays from `P` to a fixed point `y` of `Q`: the parameters `u ∈ (0, 1)` along `P`
    /// (from its start) where the face of the ray `x(u) → y` can change — where `x(u)`, `y`
    /// and an event point are collinear, and where `P` crosses the line of `Q`. Sorted, no
    /// duplicates; between two of them (and the ends) every ray lies in one face.
    #[must_use]
    pub fn sender_breaks(&self, y: DVec2) -> Vec<f64> {
        let [a, b] = self.p;
        let d = b - a;
        let mut breaks: Vec<f64> = Vec::new();
        for &v in self.sub.iter().flat_map(|points| points.iter()) {
            let w = v - y;
            let denominator = w.perp_dot(d);
            if denominator != 0.0 {
                breaks.push(w.perp_dot(y - a) / denominator);
            }
        }
        if self.split_p {
            let (oa, ob) = (
                orient(self.q[0], self.q[1], a),
                orient(self.q[0], self.q[1], b),
            );
            breaks.push(oa / (oa - ob));
        }
        breaks.retain(|u| *u > 0.0 && *u < 1.0);
        breaks.sort_by(f64::total_cmp);
        breaks.dedup();
        breaks
    }

    /// The same events seen from `Q` to `P` (rays reversed).
    #[must_use]
    pub fn reversed(&self) -> PairEvents {
        let [a, b, c, d] = self.sub.clone();
        PairEvents {
            p: self.q,
            q: self.p,
            split_p: self.split_q,
            split_q: self.split_p,
            // Index 2·side(x) + side(y) with the roles of x and y exchanged.
            sub: [a, c, b, d],
        }
    }
}

/// One side of a shaft: a parent edge and whether it is two-sided.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Side {
    pub index: usize,
    pub a: DVec2,
    pub b: DVec2,
    pub two_sided: bool,
}

impl Side {
    /// Whether `p` is strictly in front (strictly off the line for a two-sided edge): the
    /// facing condition the classification assumes for the *other* end of a segment.
    #[inline]
    pub(crate) fn faces(&self, p: DVec2) -> bool {
        let o = orient(self.a, self.b, p);
        if self.two_sided { o != 0.0 } else { o > 0.0 }
    }

    /// Whether the closed segment `[p, q]` is entirely on or behind this one-sided edge's line,
    /// where no facing segment can reach it.
    fn hides(&self, p: DVec2, q: DVec2) -> bool {
        !self.two_sided && orient(self.a, self.b, p) <= 0.0 && orient(self.a, self.b, q) <= 0.0
    }
}

/// Classifies the shaft between `p` and `q` (see [`Shaft`]). Valid for segments `x–y` with `x`
/// on `p`, `y` on `q`, `q.faces(x)` and `p.faces(y)`.
pub(crate) fn classify(segments: &[Segment], bvh: &Bvh, p: Side, q: Side) -> Shaft {
    let pts = [p.a, p.b, q.a, q.b];
    if p.hides(q.a, q.b) || q.hides(p.a, p.b) {
        return Shaft::NoFacing;
    }
    if orient(p.a, p.b, q.a) == 0.0 && orient(p.a, p.b, q.b) == 0.0 {
        return Shaft::NoFacing; // all on one line: every cosine is 0
    }
    let lo = pts.iter().fold(DVec2::INFINITY, |m, v| m.min(*v));
    let hi = pts.iter().fold(DVec2::NEG_INFINITY, |m, v| m.max(*v));
    let mut candidates = Vec::new();
    for o in bvh.overlapping(segments, lo, hi) {
        let i = o as usize;
        if i == p.index || i == q.index {
            continue;
        }
        let s = segments[i];
        if p.hides(s.a, s.b) || q.hides(s.a, s.b) || separated(&pts, s) {
            continue;
        }
        if cuts_whole_shaft(p, q, s) {
            return Shaft::Blocked(o);
        }
        candidates.push(o);
    }
    if candidates.is_empty() {
        return Shaft::Clear;
    }
    let whole = event_points(segments, &candidates, p, q);
    let interior = whole.is_empty().then(|| {
        let (mp, mq) = ((p.a + p.b) * 0.5, (q.a + q.b) * 0.5);
        !candidates.iter().any(|&i| {
            let s = segments[i as usize];
            open_segment_hits(mp, mq, s.a, s.b)
        })
    });
    let events = (!whole.is_empty()).then(|| {
        let forward = pair_events(segments, &candidates, p, q);
        let backward = forward.reversed();
        Box::new([forward, backward])
    });
    Shaft::Candidates(Candidates {
        occluders: candidates.into(),
        events,
        interior,
    })
}

/// The [`PairEvents`] of `p` and `q`: each edge cut where it crosses the other's line, and the
/// event points of every resulting sub-pair.
fn pair_events(segments: &[Segment], candidates: &[u32], p: Side, q: Side) -> PairEvents {
    // The pieces of `own` on side 0 and side 1 of the line of `other` (one piece if it does not
    // cross it, then on side 0).
    let pieces = |own: Side, other: Side| -> (bool, [Option<Side>; 2]) {
        let (oa, ob) = (
            orient(other.a, other.b, own.a),
            orient(other.a, other.b, own.b),
        );
        if !strictly_opposite(oa, ob) {
            return (false, [Some(own), None]);
        }
        let z = own.a + (own.b - own.a) * (oa / (oa - ob));
        let (first, second) = (Side { b: z, ..own }, Side { a: z, ..own });
        // Side 1 is the positive side of the other's line.
        let split = if oa > 0.0 {
            [Some(second), Some(first)]
        } else {
            [Some(first), Some(second)]
        };
        (true, split)
    };
    let (split_p, p_pieces) = pieces(p, q);
    let (split_q, q_pieces) = pieces(q, p);
    let mut sub: [Box<[DVec2]>; 4] = Default::default();
    for (sx, pp) in p_pieces.iter().enumerate() {
        for (sy, qq) in q_pieces.iter().enumerate() {
            if let (Some(pp), Some(qq)) = (pp, qq) {
                sub[2 * sx + sy] = event_points(segments, candidates, *pp, *qq).into();
            }
        }
    }
    PairEvents {
        p: [p.a, p.b],
        q: [q.a, q.b],
        split_p,
        split_q,
        sub,
    }
}

/// The event points of the shaft between `p` and `q` with occluders `candidates` (see
/// [`PairEvents`]): occluder end points strictly inside the hull of the two edges or on one of
/// them (their own end points excepted) and the points where an occluder crosses `p` or `q`
/// inside it.
fn event_points(segments: &[Segment], candidates: &[u32], p: Side, q: Side) -> Vec<DVec2> {
    let corners = [p.a, p.b, q.a, q.b];
    // A ray from x on P through P's own end point runs along P's line, so it can only reach a
    // point y of Q on that line. Unless Q lies on P's line there (its end point there is the
    // pair's corner, a boundary of the (s, t) rectangle), that end point of P sweeps over no ray
    // between interior points and is no event. Likewise for Q's end points.
    let ignorable = |e: DVec2, own: Side, other: Side| {
        (e == own.a || e == own.b)
            && !on_closed_segment(e, other.a, other.b)
            && !strictly_opposite(orient(own.a, own.b, other.a), orient(own.a, own.b, other.b))
    };
    let corner_of_only_one = |e: DVec2| ignorable(e, p, q) || ignorable(e, q, p);
    let mut events: Vec<DVec2> = Vec::new();
    let push = |e: DVec2, events: &mut Vec<DVec2>| {
        if !corner_of_only_one(e) && !events.contains(&e) {
            events.push(e);
        }
    };
    for &i in candidates {
        let s = segments[i as usize];
        for e in [s.a, s.b] {
            // A ray between interior points of P and Q runs inside the hull: it can sweep over
            // a point inside it or on P or Q, never over one on the hull's other sides.
            if strictly_inside_hull(e, &corners)
                || on_closed_segment(e, p.a, p.b)
                || on_closed_segment(e, q.a, q.b)
            {
                push(e, &mut events);
            }
        }
        for edge in [p, q] {
            if let Some(c) = proper_crossing(s.a, s.b, edge.a, edge.b) {
                push(c, &mut events);
            }
        }
    }
    events
}

fn strictly_opposite(u: f64, v: f64) -> bool {
    (u > 0.0 && v < 0.0) || (u < 0.0 && v > 0.0)
}

/// Whether `e` lies on the closed segment `[a, b]` (exactly).
fn on_closed_segment(e: DVec2, a: DVec2, b: DVec2) -> bool {
    orient(a, b, e) == 0.0
        && e.x >= a.x.min(b.x)
        && e.x <= a.x.max(b.x)
        && e.y >= a.y.min(b.y)
        && e.y <= a.y.max(b.y)
}

/// Whether `e` lies strictly inside the convex hull of the four points (exact).
fn strictly_inside_hull(e: DVec2, pts: &[DVec2; 4]) -> bool {
    // Andrew's monotone chain, dropping collinear points: the hull counter-clockwise.
    let mut sorted = *pts;
    // `+ 0.0` makes -0.0 equal to 0.0 for `total_cmp`: equal coordinates must sort by y.
    sorted.sort_by(|a, b| {
        (a.x + 0.0)
            .total_cmp(&(b.x + 0.0))
            .then((a.y + 0.0).total_cmp(&(b.y + 0.0)))
    });
    let mut hull: Vec<DVec2> = Vec::with_capacity(8);
    for pass in 0..2 {
        let start = hull.len();
        let points: Vec<DVec2> = if pass == 0 {
            sorted.to_vec()
        } else {
            sorted.iter().rev().copied().collect()
        };
        for p in points {
            while hull.len() >= start + 2
                && orient(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop(); // the last point starts the other chain
    }
    hull.len() >= 3 && (0..hull.len()).all(|i| orient(hull[i], hull[(i + 1) % hull.len()], e) > 0.0)
}

/// The point where segment `[a, b]` crosses segment `[c, d]` strictly inside both (not at an
/// end point, not collinear), rounded; `None` otherwise.
fn proper_crossing(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Option<DVec2> {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    if !(strictly_opposite(o1, o2) && strictly_opposite(o3, o4)) {
        return None;
    }
    // o3 and o4 are twice the signed areas of (c, d, a) and (c, d, b): the crossing divides
    // [a, b] in their ratio.
    let u = o3 / (o3 - o4);
    Some(a + (b - a) * u)
}

/// Whether the closed segment `s` cannot meet any facing open segment from `P` to `Q`, decided
/// exactly by a separating line: a line through two of the four end points `pts` with all four
/// on one closed side and `s` on the other, where `s` may touch the line only at one of those
/// two end points (an end point of `P` or `Q` lies on the line of its own edge, so a facing
/// open segment never contains it); or the line of `s` with all four points strictly on one side.
fn separated(pts: &[DVec2; 4], s: Segment) -> bool {
    for i in 0..4 {
        for j in i + 1..4 {
            let (u, v) = (pts[i], pts[j]);
            if u == v {
                continue;
            }
            let mut others = (0..4)
                .filter(|&k| k != i && k != j)
                .map(|k| orient(u, v, pts[k]));
            let (o1, o2) = (others.next().unwrap_or(0.0), others.next().unwrap_or(0.0));
            let outside = |o: f64, end: DVec2, sign: f64| {
                o * sign < 0.0 || (o == 0.0 && (end == u || end == v))
            };
            let (sa, sb) = (orient(u, v, s.a), orient(u, v, s.b));
            let touches_both = sa == 0.0 && sb == 0.0;
            for sign in [1.0, -1.0] {
                let hull_inside = o1 * sign >= 0.0 && o2 * sign >= 0.0;
                if hull_inside && !touches_both && outside(sa, s.a, sign) && outside(sb, s.b, sign)
                {
                    return true;
                }
            }
        }
    }
    let sides = pts.map(|v| orient(s.a, s.b, v));
    sides.iter().all(|&o| o > 0.0) || sides.iter().all(|&o| o < 0.0)
}

/// Whether the closed segment `s` meets every open segment from a point of `p` to a point of
/// `q`. True when `p` and `q` lie strictly on opposite sides of the line of `s` and the four
/// corner segments (end point to end point) all meet `s`: the crossing point with the line of
/// `s` is a weighted mean that is monotone in each end point's parameter, so its extremes are
/// at the corners and every crossing lies between them, on `s`.
fn cuts_whole_shaft(p: Side, q: Side, s: Segment) -> bool {
    let side = |v: DVec2| orient(s.a, s.b, v);
    let (p1, p2, q1, q2) = (side(p.a), side(p.b), side(q.a), side(q.b));
    let opposite = (p1 > 0.0 && p2 > 0.0 && q1 < 0.0 && q2 < 0.0)
        || (p1 < 0.0 && p2 < 0.0 && q1 > 0.0 && q2 > 0.0);
    opposite
        && [p.a, p.b].iter().all(|&u| {
            [q.a, q.b]
                .iter()
                .all(|&v| !strictly_same_side(orient(u, v, s.a), orient(u, v, s.b)))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{point, rng};
    use proptest::prelude::*;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn hits(x: DVec2, y: DVec2, p: DVec2, q: DVec2) -> bool {
        let h = open_segment_hits(x, y, p, q);
        // Symmetric in the ray's ends and in the occluder's ends.
        assert_eq!(h, open_segment_hits(y, x, p, q));
        assert_eq!(h, open_segment_hits(x, y, q, p));
        h
    }

    #[test]
    fn segment_test_follows_the_grazing_rule() {
        let (x, y) = (v(0.0, 0.0), v(4.0, 0.0));
        assert!(hits(x, y, v(2.0, -1.0), v(2.0, 1.0)), "proper crossing");
        assert!(!hits(x, y, v(2.0, 1.0), v(2.0, 3.0)), "miss");
        assert!(
            hits(x, y, v(2.0, 0.0), v(2.0, 1.0)),
            "touching an occluder's end point blocks"
        );
        assert!(
            hits(x, y, v(1.0, 0.0), v(3.0, 0.0)),
            "collinear overlap blocks"
        );
        assert!(
            hits(x, y, v(-1.0, 0.0), v(5.0, 0.0)),
            "collinear, covering blocks"
        );
        assert!(
            !hits(x, y, v(4.0, 0.0), v(6.0, 0.0)),
            "collinear, touching only y"
        );
        assert!(!hits(x, y, v(5.0, 0.0), v(6.0, 0.0)), "collinear, beyond y");
        assert!(
            !hits(x, y, v(0.0, -1.0), v(0.0, 1.0)),
            "an occluder through x does not block"
        );
        assert!(
            !hits(x, y, v(4.0, 0.0), v(4.0, 1.0)),
            "an occluder ending at y does not block"
        );
        assert!(
            !hits(x, x, v(0.0, -1.0), v(0.0, 1.0)),
            "an empty ray meets nothing"
        );
        // Exactly through an end point with coordinates that are not exact decimals: the
        // predicate sees the exact collinearity, whatever the rounding of a float cross product.
        // (0.1, 0.2) is exactly half of (0.2, 0.4): exactly on the ray.
        let (x2, y2, p) = (v(0.0, 0.0), v(0.2, 0.4), v(0.1, 0.2));
        assert_eq!(orient(x2, y2, p), 0.0);
        assert!(hits(x2, y2, p, v(0.3, 0.1)), "through an end point");
        assert!(!hits(x2, y2, v(0.3, 0.1), v(0.5, 0.1)));
    }

    #[test]
    fn bvh_finds_exactly_what_a_linear_scan_finds() {
        let mut r = rng(11);
        for n in [1, 3, 17, 200] {
            let segments: Vec<Segment> = (0..n)
                .map(|_| {
                    let a = point(&mut r);
                    Segment {
                        a,
                        b: a + (point(&mut r) * 0.3),
                    }
                })
                .collect();
            let bvh = Bvh::new(&segments);
            for _ in 0..2000 {
                let (x, y) = (point(&mut r), point(&mut r));
                let skip = r.random_range(0..n);
                let linear = segments
                    .iter()
                    .enumerate()
                    .any(|(i, s)| i != skip && open_segment_hits(x, y, s.a, s.b));
                assert_eq!(bvh.any_hit(&segments, x, y, skip, skip), linear);
            }
            let (lo, hi) = (v(-0.2, -0.2), v(0.3, 0.1));
            let boxed: Vec<u32> = (0..n as u32)
                .filter(|&i| {
                    let s = segments[i as usize];
                    let (slo, shi) = (s.a.min(s.b), s.a.max(s.b));
                    !(slo.x > hi.x || slo.y > hi.y || shi.x < lo.x || shi.y < lo.y)
                })
                .collect();
            assert_eq!(bvh.overlapping(&segments, lo, hi), boxed);
        }
    }

    /// Regression: with a `-0.0` coordinate the hull's sort put two points of one vertical line
    /// out of order, dropped an event point inside the hull and merged two faces.
    #[test]
    fn hull_test_ignores_the_sign_of_zero() {
        let pts = [v(0.0, -2.0 / 3.0), v(1.0, -0.0), v(-0.0, 1.0), v(0.0, 0.5)];
        assert!(strictly_inside_hull(v(0.5, 0.0), &pts));
        assert!(
            !strictly_inside_hull(v(0.0, 0.7), &pts),
            "on the hull's side"
        );
        assert!(!strictly_inside_hull(v(2.0, 0.0), &pts));
    }

    proptest! {
        /// The classification agrees with brute force for facing segments between random pairs:
        /// `Blocked` rays are all blocked, `Clear` rays all visible, candidates suffice.
        #[test]
        fn shaft_classification_is_sound(seed in any::<u64>()) {
            let mut r = rng(seed);
            let snap = |p: DVec2| (p * 4.0).round() / 4.0;
            let mut segments: Vec<Segment> = Vec::new();
            while segments.len() < 8 {
                let (a, b) = (snap(point(&mut r)), snap(point(&mut r)));
                if a != b {
                    segments.push(Segment { a, b });
                }
            }
            let bvh = Bvh::new(&segments);
            let side = |i: usize, two_sided: bool| Side { index: i, a: segments[i].a, b: segments[i].b, two_sided };
            for (i, j) in [(0, 1), (2, 3), (4, 5), (0, 7)] {
                let (p, q) = (side(i, r.random_bool(0.3)), side(j, r.random_bool(0.3)));
                let shaft = classify(&segments, &bvh, p, q);
                for _ in 0..200 {
                    // Exact dyadic points on the snapped segments.
                    let at = |s: Segment, k: u32| s.a + (s.b - s.a) * (f64::from(k) / 8.0);
                    let x = at(segments[i], r.random_range(0..=8));
                    let y = at(segments[j], r.random_range(0..=8));
                    if !(q.faces(x) && p.faces(y)) {
                        continue;
                    }
                    let truth = !segments.iter().enumerate()
                        .any(|(k, s)| k != i && k != j && open_segment_hits(x, y, s.a, s.b));
                    match &shaft {
                        Shaft::NoFacing => prop_assert!(false, "facing pair classified NoFacing"),
                        Shaft::Clear => prop_assert!(truth, "Clear but blocked: {x:?} {y:?}"),
                        Shaft::Blocked(_) => prop_assert!(!truth, "Blocked but visible: {x:?} {y:?}"),
                        Shaft::Candidates(c) => {
                            let by_candidates = !c.occluders.iter().any(|&k| {
                                let s = segments[k as usize];
                                open_segment_hits(x, y, s.a, s.b)
                            });
                            prop_assert_eq!(by_candidates, truth);
                            let interior = ![segments[i].a, segments[i].b].contains(&x)
                                && ![segments[j].a, segments[j].b].contains(&y);
                            if let (Some(v), true) = (c.interior, interior) {
                                prop_assert_eq!(v, truth, "constant interior visibility {:?} {:?}", x, y);
                            }
                        }
                    }
                }
            }
        }
    }
}
