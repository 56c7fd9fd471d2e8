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
    /// Only these occluders (sorted) can cut a facing segment.
    Candidates(Box<[u32]>),
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
        Shaft::Clear
    } else {
        Shaft::Candidates(candidates.into())
    }
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
                            let by_candidates = !c.iter().any(|&k| {
                                let s = segments[k as usize];
                                open_segment_hits(x, y, s.a, s.b)
                            });
                            prop_assert_eq!(by_candidates, truth);
                        }
                    }
                }
            }
        }
    }
}
