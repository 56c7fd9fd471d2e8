//! Where the visibility of a pair of parent edges can change: [`PairEvents`] and its event points.

use std::collections::HashSet;
use std::hash::BuildHasherDefault;

use glam::DVec2;

use super::bvh::Segment;
use super::predicates::{
    convex_hull, on_closed_segment, orient, proper_crossing, strictly_inside, strictly_opposite,
};
use super::side::Side;
use crate::hashing::WordHasher;

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
///
/// **Rays that meet an event point.** A ray through an event point lies on the border of two
/// faces, and the grazing rule gives it a visibility of its own: every event point lies on an
/// occluder, so a ray with one strictly inside is blocked, while a ray that starts on one (an
/// occluder standing on `P`, or crossing it there) ignores the occluders touching its end and
/// may see past them, where the rays on either side do not. [`PairEvents::face`] therefore
/// puts such rays in faces of their own ([`RayFace::on_ray`]); they are a set of measure zero
/// in `(s, t)`, met only by rays aimed exactly at a corner, a junction or a foot.
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

    /// Whether two rays from `P` to `Q` lie in the same face ([`PairEvents::face`]). Then
    /// their visibility is the same.
    #[must_use]
    pub fn same_face(&self, (x1, y1): (DVec2, DVec2), (x2, y2): (DVec2, DVec2)) -> bool {
        self.face(x1, y1) == self.face(x2, y2)
    }

    /// The face of the ray from `x` on `P` to `y` on `Q`: its sub-pair, the
    /// [`PairEvents::side`] of each of that sub-pair's event points, and the event points it
    /// meets (see the type's docs). Exact.
    #[must_use]
    pub fn face(&self, x: DVec2, y: DVec2) -> RayFace {
        let sub = self.sub_pair(x, y);
        let points = &self.sub[sub];
        let mut sides = vec![0u64; points.len().div_ceil(64)];
        let mut on_ray = Vec::new();
        for (k, &v) in points.iter().enumerate() {
            let o = orient(x, y, v);
            if o > 0.0 {
                sides[k / 64] |= 1 << (k % 64);
            } else if o == 0.0
                && let Some(at) = OnRay::of(x, y, v)
            {
                on_ray.push((k as u32, at));
            }
        }
        RayFace {
            sub,
            sides: sides.into(),
            on_ray: on_ray.into(),
        }
    }

    /// The side of the ray `x → y` an event point `v` is on: `true` if strictly left (exact).
    /// A point on the ray's line counts as right; [`PairEvents::face`] tells apart the ones
    /// on the ray itself.
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

    /// For rays from `P` to a fixed point `y` of `Q`: the stretches of `P` between its
    /// [`PairEvents::sender_breaks`], each with the face its rays lie in — the sub-pair and the
    /// [`PairEvents::side`] of each of that sub-pair's event points, as bits (point `k` is bit
    /// `k % 64` of word `k / 64`). The same faces [`PairEvents::same_face`] compares, found in
    /// `O(m log m)` for `m` event points instead of `O(m)` per stretch: crossing a break flips
    /// the side of the points on that line only. Where a stretch or its neighbour is shorter
    /// than `1e-9` of `P` the sides are taken afresh at its middle, so rounding in a break's
    /// position never changes a face.
    #[must_use]
    pub fn sender_faces(&self, y: DVec2) -> Vec<SenderFace> {
        let [a, b] = self.p;
        let d = b - a;
        // Every break with the event point (sub-pair, index) that causes it.
        let mut labelled: Vec<(f64, usize, usize)> = Vec::new();
        for (sub, points) in self.sub.iter().enumerate() {
            for (k, &v) in points.iter().enumerate() {
                let w = v - y;
                let denominator = w.perp_dot(d);
                if denominator != 0.0 {
                    labelled.push((w.perp_dot(y - a) / denominator, sub, k));
                }
            }
        }
        labelled.retain(|&(u, _, _)| u > 0.0 && u < 1.0);
        labelled.sort_by(|x, z| x.0.total_cmp(&z.0));
        let mut bounds = vec![0.0];
        bounds.extend(self.sender_breaks(y));
        bounds.push(1.0);
        const TINY: f64 = 1e-9;
        let mut faces: Vec<SenderFace> = Vec::with_capacity(bounds.len() - 1);
        let mut next = 0;
        for w in bounds.windows(2) {
            let (u0, u1) = (w[0], w[1]);
            let mid = a + d * (0.5 * (u0 + u1));
            let sub = self.sub_pair(mid, y);
            // The breaks at u0 (between the last stretch and this one).
            let start = next;
            while next < labelled.len() && labelled[next].0 <= u0 {
                next += 1;
            }
            let flipped = &labelled[start..next];
            let previous = faces
                .last()
                .filter(|f| f.sub == sub && f.u[1] - f.u[0] >= TINY && u1 - u0 >= TINY);
            let sides = match previous {
                Some(prev) => {
                    let mut sides = prev.sides.clone();
                    for &(_, _, k) in flipped.iter().filter(|&&(_, s, _)| s == sub) {
                        sides[k / 64] ^= 1 << (k % 64);
                    }
                    sides
                }
                None => self.sides(sub, mid, y),
            };
            faces.push(SenderFace {
                u: [u0, u1],
                sub,
                sides,
            });
        }
        faces
    }

    /// The side of each event point of sub-pair `sub` of the ray `x → y`, as bits.
    fn sides(&self, sub: usize, x: DVec2, y: DVec2) -> Box<[u64]> {
        let points = &self.sub[sub];
        let mut sides = vec![0u64; points.len().div_ceil(64)];
        for (k, &v) in points.iter().enumerate() {
            if PairEvents::side(x, y, v) {
                sides[k / 64] |= 1 << (k % 64);
            }
        }
        sides.into()
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

/// Where an event point lies on a ray that meets it (exactly on its line, not beyond its ends).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OnRay {
    /// It is the ray's start `x`: the occluders touching it do not block the ray.
    Sender,
    /// It lies strictly between `x` and `y`: the ray grazes its occluder and is blocked.
    Inside,
    /// It is the ray's end `y`.
    Receiver,
}

impl OnRay {
    /// Where `v`, exactly on the line of `x → y`, lies on the closed segment `[x, y]`; `None`
    /// beyond its ends (then the ray does not meet it: it counts as right of the ray, as its
    /// neighbours on one side do, and the visibility is theirs).
    fn of(x: DVec2, y: DVec2, v: DVec2) -> Option<OnRay> {
        if v == x {
            return Some(OnRay::Sender);
        }
        if v == y {
            return Some(OnRay::Receiver);
        }
        // On one line the order along it is the order of either coordinate that varies.
        let key = |p: DVec2| if x.x != y.x { p.x } else { p.y };
        let (lo, hi) = (key(x).min(key(y)), key(x).max(key(y)));
        (lo < key(v) && key(v) < hi).then_some(OnRay::Inside)
    }
}

/// The face of one ray ([`PairEvents::face`]): two rays of one pair with the same face have
/// the same visibility.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct RayFace {
    /// The sub-pair ([`PairEvents::sub_pair`]).
    pub sub: usize,
    /// The side of each of the sub-pair's event points ([`PairEvents::side`]), as bits (point
    /// `k` is bit `k % 64` of word `k / 64`).
    pub sides: Box<[u64]>,
    /// The event points (index, where) on the closed ray, by index: empty for every ray but
    /// those through an event point.
    pub on_ray: Box<[(u32, OnRay)]>,
}

/// One stretch of `P` seen from a point of `Q` ([`PairEvents::sender_faces`]): every ray from
/// its interior to that point lies in one face, which meets no event point (its
/// [`RayFace::on_ray`] is empty).
#[derive(Clone, Debug, PartialEq)]
pub struct SenderFace {
    /// The stretch: parameters along `P`, from its start.
    pub u: [f64; 2],
    /// The sub-pair of its rays ([`PairEvents::sub_pair`]).
    pub sub: usize,
    /// The side of each of the sub-pair's event points ([`PairEvents::side`]), as bits.
    pub sides: Box<[u64]>,
}

/// The [`PairEvents`] of `p` and `q`: each edge cut where it crosses the other's line, and the
/// event points of every resulting sub-pair.
pub(super) fn pair_events(
    segments: &[Segment],
    candidates: &[u32],
    p: Side,
    q: Side,
) -> PairEvents {
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
pub(super) fn event_points(
    segments: &[Segment],
    candidates: &[u32],
    p: Side,
    q: Side,
) -> Vec<DVec2> {
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
    let mut seen: HashSet<[u64; 2], BuildHasherDefault<WordHasher>> = HashSet::default();
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

#[cfg(test)]
mod tests {
    use proptest::prelude::*;
    use rand::RngExt;

    use crate::Kernel;
    use crate::test_support::{random_scene, rng};

    proptest! {
        #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

        /// The faces found by flipping sides at breaks are those found afresh at each
        /// stretch's middle, and the stretches are those between the sender's breaks.
        #[test]
        fn sender_faces_flip_exactly_at_the_breaks(seed in any::<u64>(), snap in any::<bool>()) {
            let kernel = Kernel::new(random_scene(seed, snap));
            let n = kernel.surface_parents();
            let mut r = rng(seed ^ 0x5e9d);
            for _ in 0..40 {
                let (a, b) = (r.random_range(0..n), r.random_range(0..n));
                let (a, b) = (crate::SurfaceRank::new(a), crate::SurfaceRank::new(b));
                let Some(events) = kernel.visibility_events(a, b) else { continue };
                let (qa, qb) = kernel.surface_parent(b);
                let y = qa + (qb - qa) * r.random_range(0.0..1.0);
                let faces = events.sender_faces(y);
                let mut bounds = vec![0.0];
                bounds.extend(events.sender_breaks(y));
                bounds.push(1.0);
                prop_assert_eq!(faces.len(), bounds.len() - 1);
                let (pa, pb) = kernel.surface_parent(a);
                for (f, w) in faces.iter().zip(bounds.windows(2)) {
                    prop_assert_eq!(f.u, [w[0], w[1]]);
                    let mid = pa + (pb - pa) * (0.5 * (f.u[0] + f.u[1]));
                    let sub = events.sub_pair(mid, y);
                    prop_assert_eq!(f.sub, sub);
                    prop_assert_eq!(&f.sides, &events.sides(sub, mid, y), "stretch {:?} of {:?}", f.u, bounds);
                }
            }
        }
    }
}
