//! A BVH over segments: pieces, a median-split tree collapsed to four-wide nodes, its queries.

use std::cmp::Ordering;

use glam::{DVec2, Vec4};

use super::boxes::{Along, Beyond, Boxes, RayBox, Wide};
use super::predicates::{open_segment_hits, orient};
use super::ray::{Contact, Ray};

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
pub(super) const MIXED: u32 = u32::MAX;

const LEAF_SIZE: usize = 4;

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

    /// Whether the open segment `(x, y)` meets any segment except `skip_a` and `skip_b` (each
    /// skips nothing where it is `None`).
    pub(crate) fn any_hit(
        &self,
        x: DVec2,
        y: DVec2,
        skip_a: Option<usize>,
        skip_b: Option<usize>,
    ) -> bool {
        let (skip_a, skip_b) = (skip_index(skip_a), skip_index(skip_b));
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

    /// [`Bvh::any_hit`] skipping two segments, but a segment the open segment meets does not
    /// count when `ignore` accepts it (asked only then, so a costly rule costs little).
    pub(crate) fn any_hit_unless(
        &self,
        x: DVec2,
        y: DVec2,
        skip_a: usize,
        skip_b: usize,
        ignore: impl Fn(Segment) -> bool,
    ) -> bool {
        let ray = RayBox::new(self.to_frame(x), self.to_frame(y));
        self.any(
            |node| ray.may_meet(node) & !node.skipped(skip_a, skip_b),
            |k| {
                let i = self.items[k] as usize;
                let s = self.ordered[k];
                i != skip_a && i != skip_b && open_segment_hits(x, y, s.a, s.b) && !ignore(s)
            },
        )
    }

    /// Whether a segment the open segment `(x, y)` meets satisfies `rule` (given its index and
    /// the segment; asked only of those it meets, so a costly rule costs little).
    pub(crate) fn any_hit_where(
        &self,
        x: DVec2,
        y: DVec2,
        rule: impl Fn(usize, Segment) -> bool,
    ) -> bool {
        let ray = RayBox::new(self.to_frame(x), self.to_frame(y));
        self.any(
            |node| ray.may_meet(node),
            |k| {
                let s = self.ordered[k];
                open_segment_hits(x, y, s.a, s.b) && rule(self.items[k] as usize, s)
            },
        )
    }

    /// The first segment except `skip` (if any) the ray meets, and where ([`Ray::contact`]): the
    /// contact first along the ray, of several at one point one that `judge` says faces the
    /// origin, then the lowest segment index, so the answer is the linear scan's whatever the
    /// tree. `judge(i)` is asked only of a segment the ray meets: `None` if that meeting does
    /// not count, else whether the segment faces the origin. Nearer children are visited
    /// first; once a contact is known, boxes wholly beyond it are skipped.
    pub(crate) fn first_hit(
        &self,
        ray: &Ray,
        skip: Option<usize>,
        judge: impl Fn(usize) -> Option<bool>,
    ) -> Option<(usize, Contact)> {
        if self.nodes.is_empty() {
            return None;
        }
        let skip = skip_index(skip);
        let (o, f) = (self.to_frame(ray.o), self.to_frame(ray.f));
        let (boxes, along) = (RayBox::new(o, f), Along::new(o, f));
        let mut best: Option<(usize, Contact)> = None;
        let mut beyond: Option<(Beyond, f32)> = None;
        // As in `any`: each level leaves at most 3 entries behind. Each entry keeps how far
        // along the ray its box starts, to skip it if a nearer contact has turned up since.
        let mut stack = [(0u32, f32::NEG_INFINITY); 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let (index, entry) = stack[top];
            let mut passed = 0b1111;
            if let Some((cut, reach)) = &beyond {
                if entry > *reach {
                    continue;
                }
                passed = !cut.holds(&self.nodes[index as usize]);
            }
            let node = &self.nodes[index as usize];
            passed &= boxes.may_meet(node) & node.used & !node.skipped(skip, skip);
            let entries = along.entries(node).to_array();
            let mut inner = [(0u32, 0.0f32); 4];
            let mut n = 0;
            for (k, &entry) in entries.iter().enumerate() {
                if passed & (1 << k) == 0 {
                    continue;
                }
                let (child, count) = (node.child[k] as usize, node.count[k] as usize);
                if count == 0 {
                    inner[n] = (child as u32, entry);
                    n += 1;
                    continue;
                }
                for item in child..child + count {
                    if let Some(found) = self.improves(ray, item, skip, best.as_ref(), &judge) {
                        beyond = Some(self.beyond(ray, &found.1, &along));
                        best = Some(found);
                    }
                }
            }
            // The farthest goes onto the stack first, so the nearest is visited next.
            inner[..n].sort_unstable_by(|x, y| y.1.total_cmp(&x.1));
            stack[top..top + n].copy_from_slice(&inner[..n]);
            top += n;
        }
        best
    }

    /// Item `item`'s segment and contact if it comes before `best` (or ties it and wins the
    /// tie: facing the origin where `best` does not, or as facing with a lower index).
    #[inline]
    fn improves(
        &self,
        ray: &Ray,
        item: usize,
        skip: usize,
        best: Option<&(usize, Contact)>,
        judge: &impl Fn(usize) -> Option<bool>,
    ) -> Option<(usize, Contact)> {
        let i = self.items[item] as usize;
        if i == skip || best.is_some_and(|&(b, _)| b == i) {
            return None;
        }
        let s = self.ordered[item];
        let contact = ray.contact(s.a, s.b)?;
        let facing = judge(i)?;
        let better = best.is_none_or(|(b, first)| match ray.order(&contact, first) {
            Ordering::Less => true,
            Ordering::Equal => wins_tie(facing, i, judge(*b) == Some(true), *b),
            Ordering::Greater => false,
        });
        better.then_some((i, contact))
    }

    /// What lies beyond a contact, in the unit frame: the half-plane past the line of the
    /// segment it crosses (or past the point, across the ray), and a bound on its distance
    /// along the ray (the point's, or the farther end of the segment it lies on).
    fn beyond(&self, ray: &Ray, contact: &Contact, along: &Along) -> (Beyond, f32) {
        match *contact {
            Contact::At(p) => {
                let p = self.to_frame(p);
                (Beyond::new(p, ray.f - ray.o), along.reach(p))
            }
            Contact::Crossing { a, b, .. } => {
                let away = -orient(a, b, ray.o).signum();
                let (fa, fb) = (self.to_frame(a), self.to_frame(b));
                let reach = along.reach(fa).max(along.reach(fb));
                (Beyond::new(fa, (b - a).perp() * away), reach)
            }
        }
    }

    /// The point twice as far from `o` along `d` as the farthest corner of the segments'
    /// bounding square: the far end of a ray from `o` that no segment reaches. `None` for a
    /// zero or non-finite `d`, or if the point is not finite.
    pub(crate) fn far_point(&self, o: DVec2, d: DVec2) -> Option<DVec2> {
        let scale = d.abs().max_element();
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        let (lo, hi) = (
            self.origin,
            self.origin + DVec2::splat(1.0 / self.inv_scale),
        );
        // The L1 distance bounds the Euclidean one and cannot overflow where it is finite.
        let reach = [lo, hi, DVec2::new(lo.x, hi.y), DVec2::new(hi.x, lo.y)]
            .iter()
            .fold(0.0, |m: f64, c| m.max((*c - o).abs().element_sum()));
        let unit = d / scale;
        let f = o + unit * (2.0 * reach / unit.length());
        (f.is_finite() && f != o).then_some(f)
    }

    /// `p` in the unit frame of the boxes (double precision; the tests round it).
    #[inline]
    fn to_frame(&self, p: DVec2) -> DVec2 {
        (p - self.origin) * self.inv_scale
    }

    /// Indices of the segments whose boxes overlap the closed box `[lo, hi]`, sorted.
    pub(crate) fn overlapping(&self, lo: DVec2, hi: DVec2) -> Vec<u32> {
        self.overlapping_beyond(lo, hi, &[])
    }

    /// The segments whose boxes overlap the closed bounding box of `pts`, except some wholly
    /// outside their convex hull: sorted. A subtree is skipped when its box lies strictly
    /// beyond a line through two of the points with all four on its other closed side (by
    /// more than the rounding margin), so every segment left out lies strictly beyond such a
    /// line. Only the segments near the hull are visited: in a convex room of `n` walls a
    /// shaft between two of them meets `O(log n)` boxes, where its bounding box holds `O(n)`.
    pub(crate) fn overlapping_hull(&self, pts: &[DVec2; 4]) -> Vec<u32> {
        let lo = pts.iter().fold(DVec2::INFINITY, |m, v| m.min(*v));
        let hi = pts.iter().fold(DVec2::NEG_INFINITY, |m, v| m.max(*v));
        let cuts: Vec<Beyond> = hull_lines(pts)
            .map(|(u, outward)| Beyond::new(self.to_frame(u), outward))
            .collect();
        self.overlapping_beyond(lo, hi, &cuts)
    }

    /// The segments whose boxes overlap `[lo, hi]`, but for subtrees wholly beyond a cut.
    fn overlapping_beyond(&self, lo: DVec2, hi: DVec2, cuts: &[Beyond]) -> Vec<u32> {
        let apart =
            |alo: DVec2, ahi: DVec2| alo.x > hi.x || alo.y > hi.y || ahi.x < lo.x || ahi.y < lo.y;
        // The exact test runs on the segments; the boxes only need to be conservative.
        let query = Boxes::new(self.to_frame(lo), self.to_frame(hi));
        let mut out = Vec::new();
        self.any(
            |node| {
                cuts.iter()
                    .fold(query.overlaps(node), |mask, cut| mask & !cut.holds(node))
            },
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

/// `skip` as the index the tree's tests compare with: for none, `usize::MAX`, which no segment
/// has (a plain index keeps the four-wide node test ([`Wide::skipped`]) one comparison a lane).
#[inline]
fn skip_index(skip: Option<usize>) -> usize {
    skip.unwrap_or(usize::MAX)
}

/// Of two segments met at one point, whether `i` (facing the origin or not) comes before `b`:
/// the one facing the origin, then the lower index.
#[inline]
pub(crate) fn wins_tie(facing: bool, i: usize, b_facing: bool, b: usize) -> bool {
    (facing, std::cmp::Reverse(i)) > (b_facing, std::cmp::Reverse(b))
}

/// The lines through two of `pts` (distinct) with all four points on one closed side, each as
/// a point on it and its normal pointing to the other, open side: the edges of the convex hull
/// (and, for collinear points, their line both ways). Decided by exact orientations.
fn hull_lines(pts: &[DVec2; 4]) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
    (0..4)
        .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
        .filter(|&(i, j)| pts[i] != pts[j])
        .flat_map(move |(i, j)| {
            let (u, v) = (pts[i], pts[j]);
            let mut others = (0..4)
                .filter(|&k| k != i && k != j)
                .map(|k| orient(u, v, pts[k]));
            let (o1, o2) = (others.next().unwrap_or(0.0), others.next().unwrap_or(0.0));
            // `orient(u, v, p) = perp(v − u)·(p − u)`: the hull is on the side of `sign`.
            [1.0, -1.0]
                .into_iter()
                .filter(move |&sign| o1 * sign >= 0.0 && o2 * sign >= 0.0)
                .map(move |sign: f64| (u, (v - u).perp() * -sign))
        })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{point, rng};
    use proptest::prelude::*;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
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
                assert_eq!(bvh.any_hit(x, y, Some(skip), Some(skip)), linear);
                // A rule that only the `skip`-th segment passes: found exactly when it is hit.
                let hit_skip = open_segment_hits(x, y, segments[skip].a, segments[skip].b);
                assert_eq!(bvh.any_hit_where(x, y, |i, _| i == skip), hit_skip);
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
                // `n` stands for no skip.
                let some = |k: usize| (k < n).then_some(k);
                prop_assert_eq!(bvh.any_hit(x, y, some(skip_a), some(skip_b)), linear, "{:?} {:?}", x, y);
            }
        }

        /// A shaft's query keeps, of the segments whose boxes overlap the bounding box of its
        /// four points, every one the shaft classification does not rule out by a separating
        /// line ([`separated`](super::super::shaft::separated)), in index order: so the
        /// classification finds what it found among all the box's segments. On a coarse grid,
        /// so segments touch hull lines and corners, and hulls degenerate.
        #[test]
        fn shaft_query_keeps_every_segment_a_separating_line_does_not_rule_out(
            seed in any::<u64>(),
            n in 1usize..200,
        ) {
            let mut r = rng(seed);
            let scale = [1e-150, 1.0, 3.0, 1e150][r.random_range(0..4)];
            let snap = |p: DVec2| (p * 4.0).round() / 4.0 * scale;
            let segments: Vec<Segment> = (0..n)
                .map(|_| Segment { a: snap(point(&mut r)), b: snap(point(&mut r)) })
                .collect();
            let bvh = Bvh::new(&segments);
            let mut culled = 0;
            for _ in 0..50 {
                let pts = [(); 4].map(|()| snap(point(&mut r)));
                let (lo, hi) = (
                    pts.iter().fold(DVec2::INFINITY, |m, v| m.min(*v)),
                    pts.iter().fold(DVec2::NEG_INFINITY, |m, v| m.max(*v)),
                );
                let boxed = bvh.overlapping(lo, hi);
                let found = bvh.overlapping_hull(&pts);
                prop_assert!(found.windows(2).all(|w| w[0] < w[1]), "sorted, once each");
                prop_assert!(found.iter().all(|i| boxed.contains(i)), "within the box");
                for &i in &boxed {
                    let s = segments[i as usize];
                    let ruled_out = super::super::shaft::separated(&pts, s);
                    prop_assert!(ruled_out || found.contains(&i), "lost {} {:?} of {:?}", i, s, pts);
                }
                culled += boxed.len() - found.len();
            }
            // The query does cull (on all but the tiniest scenes).
            prop_assert!(n < 50 || culled > 0, "nothing culled");
        }

        /// The closest hit on the same grazing rays: the tree's answer is the linear scan's
        /// (the contact first along the ray, of ties one facing the origin, then the lowest
        /// index; some meetings do not count), though its boxes cull in single precision and
        /// its half-planes skip what lies beyond.
        #[test]
        fn bvh_first_hit_matches_the_linear_scan_on_grazing_rays(
            seed in any::<u64>(),
            n in 1usize..300,
        ) {
            let mut r = rng(seed);
            let scale = [1e-150, 1.0, 3.0, 1e150][r.random_range(0..4)];
            let snap = |p: DVec2| (p * 4.0).round() / 4.0 * scale;
            let segments: Vec<Segment> = (0..n)
                .map(|_| Segment { a: snap(point(&mut r)), b: snap(point(&mut r)) })
                .collect();
            let bvh = Bvh::new(&segments);
            for _ in 0..300 {
                let ray = Ray { o: snap(point(&mut r)), f: snap(point(&mut r) * 2.0) };
                let skip = r.random_range(0..n + 1);
                let judge = |i: usize| {
                    let s = segments[i];
                    (i % 7 != 3).then(|| orient(s.a, s.b, ray.o) > 0.0)
                };
                let mut linear: Option<(usize, Contact)> = None;
                for (i, s) in segments.iter().enumerate() {
                    if i == skip {
                        continue;
                    }
                    let Some(c) = ray.contact(s.a, s.b) else { continue };
                    let Some(facing) = judge(i) else { continue };
                    let first = linear.is_none_or(|(b, first)| match ray.order(&c, &first) {
                        Ordering::Less => true,
                        Ordering::Equal => wins_tie(facing, i, judge(b) == Some(true), b),
                        Ordering::Greater => false,
                    });
                    if first {
                        linear = Some((i, c));
                    }
                }
                let skip = (skip < n).then_some(skip);
                prop_assert_eq!(bvh.first_hit(&ray, skip, judge), linear, "{:?}", ray);
            }
        }
    }
}
