//! Shaft classification of a pair of parent edges: never facing, clear, blocked, or candidates.

use glam::DVec2;

use super::bvh::{Bvh, Segment};
use super::events::{PairEvents, event_points, pair_events};
use super::predicates::{open_segment_hits, orient, strictly_same_side};
use super::side::Side;

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

/// Classifies the shaft between `p` and `q` (see [`Shaft`]). Valid for segments `x–y` with `x`
/// on `p`, `y` on `q`, `q.faces(x)` and `p.faces(y)`.
/// Only the segments near the shaft are looked at ([`Bvh::overlapping_hull`]).
pub(crate) fn classify(segments: &[Segment], bvh: &Bvh, p: Side, q: Side) -> Shaft {
    classify_among(segments, p, q, |pts| bvh.overlapping_hull(pts))
}

/// [`classify`], looking at the segments `near` gives for the four end points: a superset,
/// in index order, of those no separating line rules out (see [`separated`]).
fn classify_among(
    segments: &[Segment],
    p: Side,
    q: Side,
    near: impl FnOnce(&[DVec2; 4]) -> Vec<u32>,
) -> Shaft {
    let pts = [p.a, p.b, q.a, q.b];
    if p.hides(q.a, q.b) || q.hides(p.a, p.b) {
        return Shaft::NoFacing;
    }
    if orient(p.a, p.b, q.a) == 0.0 && orient(p.a, p.b, q.b) == 0.0 {
        return Shaft::NoFacing; // all on one line: every cosine is 0
    }
    let mut candidates = Vec::new();
    // In index order, so the first occluder that cuts the whole shaft is the lowest index.
    for o in near(&pts) {
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

/// Whether the closed segment `s` cannot meet any facing open segment from `P` to `Q`, decided
/// exactly by a separating line: a line through two of the four end points `pts` with all four
/// on one closed side and `s` on the other, where `s` may touch the line only at one of those
/// two end points (an end point of `P` or `Q` lies on the line of its own edge, so a facing
/// open segment never contains it); or the line of `s` with all four points strictly on one side.
pub(super) fn separated(pts: &[DVec2; 4], s: Segment) -> bool {
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
            let side = |i: usize| Side { index: i, a: segments[i].a, b: segments[i].b };
            for (i, j) in [(0, 1), (2, 3), (4, 5), (0, 7)] {
                let (p, q) = (side(i), side(j));
                let shaft = classify(&segments, &bvh, p, q);
                // The same as from every segment in the shaft's bounding box.
                let boxed = classify_among(&segments, p, q, |pts| {
                    let lo = pts.iter().fold(DVec2::INFINITY, |m, v| m.min(*v));
                    let hi = pts.iter().fold(DVec2::NEG_INFINITY, |m, v| m.max(*v));
                    bvh.overlapping(lo, hi)
                });
                prop_assert_eq!(&shaft, &boxed);
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
