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

use std::collections::HashSet;

use glam::{DVec2, Vec4};
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
#[inline(always)]
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

/// An occluding segment (a parent edge).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Segment {
    pub a: DVec2,
    pub b: DVec2,
}

/// A node of the binary tree the build makes before [`Bvh`] collapses it to four-wide nodes.
#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec2,
    hi: DVec2,
    /// Leaf: first index into `items`; inner: the left child (the right one follows it).
    first: u32,
    /// Leaf: number of items (> 0); inner: 0.
    count: u32,
    /// The one segment all pieces below belong to, or [`MIXED`].
    sole: u32,
}

/// [`Node::sole`] of a subtree with pieces of several segments.
const MIXED: u32 = u32::MAX;

const LEAF_SIZE: usize = 4;

/// Up to four children of a [`Bvh`] node: their boxes (center `c`, half extent `h`, in the
/// BVH's unit frame, single precision) one SIMD lane each, so one node load brings all four and
/// one vector test checks them together.
#[derive(Clone, Copy, Debug)]
struct Wide {
    cx: Vec4,
    cy: Vec4,
    hx: Vec4,
    hy: Vec4,
    /// Inner child: its index in `nodes` (`count` 0); leaf: its first item (`count` > 0).
    child: [u32; 4],
    count: [u32; 4],
    /// The one segment every piece below child `k` belongs to, or [`MIXED`]: a ray skips such a
    /// child when it skips that segment (a wall cut into pieces, seen from a point on it).
    sole: [u32; 4],
    /// Bit `k` set iff slot `k` is used.
    used: u32,
}

/// The rounding margin of the single-precision box tests, in units of the BVH's frame (where
/// the scene spans `[0, 1]`), per unit of the query's own magnitude: single precision rounds
/// a value of size `m` by at most `6e-8·m`, and a test sums about ten such errors.
const BOX_MARGIN: f32 = 4e-6;

impl Wide {
    /// Bit `k`: whether every piece below child `k` belongs to segment `a` or `b`.
    #[inline]
    fn skipped(&self, a: usize, b: usize) -> u32 {
        (0..4).fold(0, |mask, k| {
            let sole = self.sole[k] as usize;
            mask | (u32::from(sole == a || sole == b) << k)
        })
    }
}

/// A bounding volume hierarchy over segments: a binary tree (median split on the longer axis
/// of the centroids) collapsed to four children per node, so a ray tests about `log n` boxes
/// instead of `n` segments, in half the dependent steps of the binary tree.
#[derive(Clone, Debug)]
pub(crate) struct Bvh {
    /// `nodes[0]` is the root; empty for no segments.
    nodes: Vec<Wide>,
    /// The unit frame of the boxes: `p ↦ (p − origin) · inv_scale` maps the segments'
    /// bounding box into `[0, 1]²`, so single precision fits any scene scale.
    origin: DVec2,
    inv_scale: f64,
    items: Vec<u32>,
    /// `segments[items[k]]`, in leaf order: a leaf's segments sit side by side in memory.
    ordered: Vec<Segment>,
}

impl Bvh {
    pub(crate) fn new(segments: &[Segment]) -> Bvh {
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for s in segments {
            lo = lo.min(s.a).min(s.b);
            hi = hi.max(s.a).max(s.b);
        }
        let extent = (hi - lo).max_element();
        let (origin, inv_scale) = if extent > 0.0 && extent.is_finite() {
            (lo, 1.0 / extent)
        } else if segments.is_empty() {
            (DVec2::ZERO, 1.0)
        } else {
            (lo, 1.0)
        };
        let pieces = pieces(segments, |p| (p - origin) * inv_scale);
        let mut order: Vec<u32> = (0..pieces.len() as u32).collect();
        order.sort_by_key(|&k| !pieces[k as usize].cut);
        let mut nodes = Vec::new();
        if !pieces.is_empty() {
            let mut binary = Vec::with_capacity(2 * pieces.len() / LEAF_SIZE + 2);
            binary.push(Node {
                lo: DVec2::ZERO,
                hi: DVec2::ZERO,
                first: 0,
                count: 0,
                sole: MIXED,
            });
            // Pieces of long segments get their own subtree under the root: mixed with the short
            // ones they would put a bit of wall into the leaves along every wall, which every ray
            // from a wall visits; apart, a wall's pieces form subtrees a ray from it skips whole.
            let long = order.partition_point(|&k| pieces[k as usize].cut);
            if long == 0 || long == order.len() {
                build(&pieces, &mut order, 0, 0, &mut binary);
            } else {
                binary.extend([binary[0]; 2]);
                let (l, r) = order.split_at_mut(long);
                build(&pieces, l, 0, 1, &mut binary);
                build(&pieces, r, long, 2, &mut binary);
                binary[0] = Node {
                    lo: binary[1].lo.min(binary[2].lo),
                    hi: binary[1].hi.max(binary[2].hi),
                    first: 1,
                    count: 0,
                    sole: MIXED,
                };
            }
            collapse(&binary, 0, &mut nodes);
        }
        let items: Vec<u32> = order.iter().map(|&k| pieces[k as usize].segment).collect();
        let ordered = items.iter().map(|&i| segments[i as usize]).collect();
        Bvh {
            nodes,
            origin,
            inv_scale,
            items,
            ordered,
        }
    }

    /// Visits every item in a leaf whose box `pass` accepts (given a node, for each of its four
    /// children; the boxes of their ancestors must pass too). Stops and returns true as soon as
    /// `visit` does.
    #[inline]
    fn any(&self, pass: impl Fn(&Wide) -> u32, mut visit: impl FnMut(usize) -> bool) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        // A median split has depth about log2(n / LEAF_SIZE), which the collapse halves, and
        // each level leaves at most 3 entries behind: 64 is ample for any u32 count.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let passed = pass(node) & node.used;
            for k in 0..4 {
                if passed & (1 << k) == 0 {
                    continue;
                }
                let (child, count) = (node.child[k] as usize, node.count[k] as usize);
                if count > 0 {
                    if (child..child + count).any(&mut visit) {
                        return true;
                    }
                } else {
                    stack[top] = child as u32;
                    top += 1;
                }
            }
        }
        false
    }

    /// Whether the open segment `(x, y)` meets any segment except `skip_a` and `skip_b`.
    pub(crate) fn any_hit(&self, x: DVec2, y: DVec2, skip_a: usize, skip_b: usize) -> bool {
        let ray = RayBox::new(self.to_frame(x), self.to_frame(y));
        self.any(
            |node| ray.may_meet(node) & !node.skipped(skip_a, skip_b),
            |k| {
                let i = self.items[k] as usize;
                let s = self.ordered[k];
                i != skip_a && i != skip_b && open_segment_hits(x, y, s.a, s.b)
            },
        )
    }

    /// `p` in the unit frame of the boxes (double precision; the tests round it).
    #[inline]
    fn to_frame(&self, p: DVec2) -> DVec2 {
        (p - self.origin) * self.inv_scale
    }

    /// Indices of the segments whose boxes overlap the closed box `[lo, hi]`, sorted.
    pub(crate) fn overlapping(&self, lo: DVec2, hi: DVec2) -> Vec<u32> {
        let apart =
            |alo: DVec2, ahi: DVec2| alo.x > hi.x || alo.y > hi.y || ahi.x < lo.x || ahi.y < lo.y;
        // The exact test runs on the segments; the boxes only need to be conservative.
        let query = Boxes::new(self.to_frame(lo), self.to_frame(hi));
        let mut out = Vec::new();
        self.any(
            |node| query.overlaps(node),
            |k| {
                let s = self.ordered[k];
                if !apart(s.a.min(s.b), s.a.max(s.b)) {
                    out.push(self.items[k]);
                }
                false
            },
        );
        // A segment cut into pieces is found once per piece.
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// Appends the four-wide node for binary node `b` (and, after it, those of its descendants) and
/// returns its index. Its children are `b`'s grandchildren, or `b`'s children where those are
/// leaves, or `b` itself if it is a leaf (a root with few segments).
fn collapse(binary: &[Node], b: usize, nodes: &mut Vec<Wide>) -> u32 {
    let index = nodes.len();
    let empty = Wide {
        cx: Vec4::ZERO,
        cy: Vec4::ZERO,
        hx: Vec4::ZERO,
        hy: Vec4::ZERO,
        child: [0; 4],
        count: [0; 4],
        sole: [MIXED; 4],
        used: 0,
    };
    nodes.push(empty);
    let node = binary[b];
    let mut slots: Vec<usize> = Vec::with_capacity(4);
    if node.count > 0 {
        slots.push(b);
    } else {
        for c in [node.first as usize, node.first as usize + 1] {
            if binary[c].count > 0 {
                slots.push(c);
            } else {
                slots.extend([binary[c].first as usize, binary[c].first as usize + 1]);
            }
        }
    }
    let mut wide = empty;
    let (mut cx, mut cy, mut hx, mut hy) = ([0.0f32; 4], [0.0f32; 4], [0.0f32; 4], [0.0f32; 4]);
    for (k, &slot) in slots.iter().enumerate() {
        let child = binary[slot];
        let (c, h) = ((child.lo + child.hi) * 0.5, (child.hi - child.lo) * 0.5);
        (cx[k], cy[k], hx[k], hy[k]) = (c.x as f32, c.y as f32, h.x as f32, h.y as f32);
        wide.used |= 1 << k;
        wide.sole[k] = child.sole;
        if child.count > 0 {
            (wide.child[k], wide.count[k]) = (child.first, child.count);
        } else {
            wide.child[k] = collapse(binary, slot, nodes);
        }
    }
    (wide.cx, wide.cy, wide.hx, wide.hy) = (cx.into(), cy.into(), hx.into(), hy.into());
    nodes[index] = wide;
    index as u32
}

/// An axis-aligned query box for [`Bvh::overlapping`], in the unit frame.
struct Boxes {
    cx: Vec4,
    cy: Vec4,
    hx: Vec4,
    hy: Vec4,
    margin: Vec4,
}

impl Boxes {
    fn new(lo: DVec2, hi: DVec2) -> Boxes {
        let (c, h) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
        Boxes {
            cx: Vec4::splat(c.x as f32),
            cy: Vec4::splat(c.y as f32),
            hx: Vec4::splat(h.x as f32),
            hy: Vec4::splat(h.y as f32),
            margin: Vec4::splat(BOX_MARGIN * (1.0 + (c.abs() + h).element_sum() as f32)),
        }
    }

    /// Bit `k`: whether the box may overlap child `k`'s box (conservative).
    #[inline]
    fn overlaps(&self, node: &Wide) -> u32 {
        let apart_x = (node.cx - self.cx).abs() - node.hx - self.hx;
        let apart_y = (node.cy - self.cy).abs() - node.hy - self.hy;
        !(apart_x.cmpgt(self.margin) | apart_y.cmpgt(self.margin)).bitmask() & 0b1111
    }
}

/// A conservative segment–box test for one ray (end points in the unit frame): never rejects a
/// closed box the closed segment `[x, y]` touches; it may accept a few it misses by the margin.
struct RayBox {
    /// The ray's bounding box, as a query box (its margin serves both tests).
    bounds: Boxes,
    /// The normal of the ray's line, scaled so its larger component is ±1, and its absolute
    /// value: the line is `normal · p = offset`.
    nx: Vec4,
    ny: Vec4,
    nx_abs: Vec4,
    ny_abs: Vec4,
    offset: Vec4,
}

impl RayBox {
    #[inline]
    fn new(x: DVec2, y: DVec2) -> RayBox {
        let d = y - x;
        let m = d.abs().max_element();
        let normal = if m > 0.0 { d.perp() / m } else { DVec2::ZERO };
        RayBox {
            bounds: Boxes::new(x.min(y), x.max(y)),
            nx: Vec4::splat(normal.x as f32),
            ny: Vec4::splat(normal.y as f32),
            nx_abs: Vec4::splat(normal.x.abs() as f32),
            ny_abs: Vec4::splat(normal.y.abs() as f32),
            offset: Vec4::splat(normal.dot(x) as f32),
        }
    }

    /// Bit `k`: the separating-axis test of the ray against child `k`'s box. The boxes overlap
    /// on both axes, and the box reaches the ray's line (`|n·c − n·x| ≤ |n|·h`), each within the
    /// margin. A NaN or infinite comparison (a query far outside single precision) accepts.
    #[inline]
    fn may_meet(&self, node: &Wide) -> u32 {
        let b = &self.bounds;
        let apart_x = (node.cx - b.cx).abs() - node.hx - b.hx;
        let apart_y = (node.cy - b.cy).abs() - node.hy - b.hy;
        let off_line = (self.nx * node.cx + self.ny * node.cy - self.offset).abs()
            - (self.nx_abs * node.hx + self.ny_abs * node.hy);
        let rejected = apart_x.cmpgt(b.margin) | apart_y.cmpgt(b.margin) | off_line.cmpgt(b.margin);
        !rejected.bitmask() & 0b1111
    }
}

/// A piece of a segment for the tree, its box in the unit frame.
#[derive(Clone, Copy, Debug)]
struct Piece {
    segment: u32,
    /// Whether the segment is cut into more than one piece.
    cut: bool,
    lo: DVec2,
    hi: DVec2,
}

/// The segments cut into pieces for the tree: a long segment (a room's wall among many small
/// blockers) would make every box that holds it span the room, so every ray would visit its
/// branch. A piece is about the spacing of `n` segments spread over the unit frame
/// (`2 / √n`), more if the total length asks for over three pieces per segment. A hit found in
/// any piece is tested against the whole segment, so pieces only change the culling.
fn pieces(segments: &[Segment], to_frame: impl Fn(DVec2) -> DVec2) -> Vec<Piece> {
    let framed: Vec<(DVec2, DVec2)> = segments
        .iter()
        .map(|s| (to_frame(s.a), to_frame(s.b)))
        .collect();
    let n = segments.len().max(1) as f64;
    let total: f64 = framed.iter().map(|(a, b)| (*b - *a).length()).sum();
    let piece = (2.0 / n.sqrt()).max(total / (3.0 * n));
    let mut out = Vec::with_capacity(segments.len());
    for (i, &(a, b)) in framed.iter().enumerate() {
        // A NaN or infinite length (coordinates near f64::MAX) gives one piece.
        let count = (((b - a).length() / piece).ceil() as usize).clamp(1, MAX_PIECES);
        for j in 0..count {
            let p = a.lerp(b, j as f64 / count as f64);
            let q = if j + 1 == count {
                b
            } else {
                a.lerp(b, (j + 1) as f64 / count as f64)
            };
            out.push(Piece {
                segment: i as u32,
                cut: count > 1,
                lo: p.min(q),
                hi: p.max(q),
            });
        }
    }
    out
}

/// At most this many pieces per segment.
const MAX_PIECES: usize = 256;

/// Fills `nodes[index]` with the subtree over `items` (pieces; whose first element sits at
/// `offset` in the full list); children are appended as adjacent pairs.
fn build(pieces: &[Piece], items: &mut [u32], offset: usize, index: usize, nodes: &mut Vec<Node>) {
    let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    for &i in items.iter() {
        let p = pieces[i as usize];
        lo = lo.min(p.lo);
        hi = hi.max(p.hi);
    }
    if items.len() <= LEAF_SIZE {
        let first = pieces[items[0] as usize].segment;
        let one = items.iter().all(|&i| pieces[i as usize].segment == first);
        nodes[index] = Node {
            lo,
            hi,
            first: offset as u32,
            count: items.len() as u32,
            sole: if one { first } else { MIXED },
        };
        return;
    }
    let ext = hi - lo;
    let axis = usize::from(ext.y > ext.x);
    let key = |i: &u32| {
        let p = pieces[*i as usize];
        (p.lo + p.hi)[axis]
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |p, q| key(p).total_cmp(&key(q)));
    let left = nodes.len();
    nodes[index] = Node {
        lo,
        hi,
        first: left as u32,
        count: 0,
        sole: MIXED,
    };
    let placeholder = nodes[index];
    nodes.extend([placeholder; 2]);
    let (l, r) = items.split_at_mut(mid);
    build(pieces, l, offset, left, nodes);
    build(pieces, r, offset + mid, left + 1, nodes);
    if nodes[left].sole == nodes[left + 1].sole {
        nodes[index].sole = nodes[left].sole;
    }
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
    for o in bvh.overlapping(lo, hi) {
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
    // Points already pushed, by bit pattern (`+ 0.0` folds -0.0 into 0.0, as `==` does): a
    // linear `contains` made the shaft of 10 000 blockers quadratic.
    let mut seen: HashSet<[u64; 2]> = HashSet::new();
    let mut push = |e: DVec2, events: &mut Vec<DVec2>| {
        if !corner_of_only_one(e) && seen.insert([(e.x + 0.0).to_bits(), (e.y + 0.0).to_bits()]) {
            events.push(e);
        }
    };
    let hull = convex_hull(&corners);
    for &i in candidates {
        let s = segments[i as usize];
        for e in [s.a, s.b] {
            // A ray between interior points of P and Q runs inside the hull: it can sweep over
            // a point inside it or on P or Q, never over one on the hull's other sides.
            if strictly_inside(e, &hull)
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

/// The convex hull of four points, counter-clockwise, collinear points dropped (exact).
fn convex_hull(pts: &[DVec2; 4]) -> Vec<DVec2> {
    // Andrew's monotone chain.
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
    hull
}

/// Whether `e` lies strictly inside a counter-clockwise convex `hull` (exact; never inside
/// a hull of fewer than 3 points).
fn strictly_inside(e: DVec2, hull: &[DVec2]) -> bool {
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
                assert_eq!(bvh.any_hit(x, y, skip, skip), linear);
            }
            let (lo, hi) = (v(-0.2, -0.2), v(0.3, 0.1));
            let boxed: Vec<u32> = (0..n as u32)
                .filter(|&i| {
                    let s = segments[i as usize];
                    let (slo, shi) = (s.a.min(s.b), s.a.max(s.b));
                    !(slo.x > hi.x || slo.y > hi.y || shi.x < lo.x || shi.y < lo.y)
                })
                .collect();
            assert_eq!(bvh.overlapping(lo, hi), boxed);
        }
    }

    proptest! {
        /// Grazing everywhere: segments and rays on a coarse grid, so rays pass exactly through
        /// end points, run along segments and along box boundaries, at scales from 1e-150 to
        /// 1e150 (beyond, the exact predicate's products leave the range of `f64`). The BVH's
        /// float culling must never lose a hit the exact scan finds.
        #[test]
        fn bvh_matches_the_linear_scan_on_grazing_rays(seed in any::<u64>(), n in 1usize..300) {
            let mut r = rng(seed);
            let scale = [1e-150, 1.0, 3.0, 1e150][r.random_range(0..4)];
            let snap = |p: DVec2| (p * 4.0).round() / 4.0 * scale;
            let segments: Vec<Segment> = (0..n)
                .map(|_| Segment { a: snap(point(&mut r)), b: snap(point(&mut r)) })
                .collect();
            let bvh = Bvh::new(&segments);
            for _ in 0..300 {
                let (x, y) = (snap(point(&mut r)), snap(point(&mut r)));
                let (skip_a, skip_b) = (r.random_range(0..n + 1), r.random_range(0..n + 1));
                let linear = segments
                    .iter()
                    .enumerate()
                    .any(|(i, s)| i != skip_a && i != skip_b && open_segment_hits(x, y, s.a, s.b));
                prop_assert_eq!(bvh.any_hit(x, y, skip_a, skip_b), linear, "{:?} {:?}", x, y);
            }
        }
    }

    /// Regression: with a `-0.0` coordinate the hull's sort put two points of one vertical line
    /// out of order, dropped an event point inside the hull and merged two faces.
    #[test]
    fn hull_test_ignores_the_sign_of_zero() {
        let pts = [v(0.0, -2.0 / 3.0), v(1.0, -0.0), v(-0.0, 1.0), v(0.0, 0.5)];
        let hull = convex_hull(&pts);
        assert!(strictly_inside(v(0.5, 0.0), &hull));
        assert!(!strictly_inside(v(0.0, 0.7), &hull), "on the hull's side");
        assert!(!strictly_inside(v(2.0, 0.0), &hull));
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
