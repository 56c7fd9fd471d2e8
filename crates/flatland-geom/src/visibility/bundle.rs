//! What geometry decides for a whole bundle of pairs at once: the pairs of edges between two
//! clusters of edges, each cluster known by the convex hull of its end points (exact).
//!
//! Every segment from a point of `P` to a point of `Q` lies in the convex hull of `P ∪ Q` (the
//! hull of two segments is the union of those segments), and that hull lies in the hull of
//! any two clusters holding `P` and `Q`. So a segment that meets no cluster pair's hull meets
//! none of its pairs', and a segment that cuts every segment between the two clusters' hulls
//! cuts every segment between any `P` and `Q` of theirs.

use glam::DVec2;

use super::bvh::Segment;
use super::predicates::{convex_hull, orient, strictly_same_side};

/// A convex polygon: the hull of a cluster's end points, with its bounding box (which rules out
/// most segments before any orientation is taken).
#[derive(Clone, Debug)]
pub(crate) struct Hull {
    /// Counter-clockwise, no three on a line; fewer than 3 when every point lies on one line.
    points: Vec<DVec2>,
    lo: DVec2,
    hi: DVec2,
}

impl Hull {
    /// The convex hull of `points` (exact).
    pub(crate) fn of(points: &[DVec2]) -> Hull {
        let mut points = match convex_hull(points) {
            hull if hull.is_empty() => points.first().copied().into_iter().collect(),
            hull => hull,
        };
        points.dedup();
        let (lo, hi) = points
            .iter()
            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        Hull { points, lo, hi }
    }

    /// The hull of two hulls.
    pub(crate) fn join(&self, other: &Hull) -> Hull {
        Hull::of(&[self.points.as_slice(), other.points.as_slice()].concat())
    }

    /// Its vertices, counter-clockwise.
    pub(crate) fn points(&self) -> &[DVec2] {
        &self.points
    }

    /// Whether the closed segment `s` meets the open interior (exact; a hull of fewer than 3
    /// points has none). A segment along the boundary, or touching it from outside, does not.
    ///
    /// By the separating axis theorem the two are apart exactly when a line along one of the
    /// hull's sides, or along `s`, has the hull on one closed side and `s` on the other; the
    /// bounding boxes' sides come first (the interior lies strictly inside its box).
    pub(crate) fn meets_interior(&self, s: Segment) -> bool {
        let (hull, n) = (&self.points, self.points.len());
        let (lo, hi) = (s.a.min(s.b), s.a.max(s.b));
        if n < 3 || hi.x <= self.lo.x || hi.y <= self.lo.y || lo.x >= self.hi.x || lo.y >= self.hi.y
        {
            return false;
        }
        for i in 0..n {
            let (u, v) = (hull[i], hull[(i + 1) % n]);
            if orient(u, v, s.a) <= 0.0 && orient(u, v, s.b) <= 0.0 {
                return false;
            }
        }
        let (mut left, mut right) = (false, false);
        for &h in hull {
            let o = orient(s.a, s.b, h);
            left |= o > 0.0;
            right |= o < 0.0;
        }
        left && right
    }
}

/// Whether the closed segment `s` meets every segment from a point of hull `a` to a point of
/// hull `b`: `a` and `b` lie strictly on opposite sides of the line of `s`, and the segment
/// between every vertex of `a` and every vertex of `b` meets `s`. Where a segment from `u` to
/// `v` crosses the line of `s` moves along it by a central projection as `u` (or `v`) moves
/// along a segment, which maps a segment to a segment: the crossings of all of them lie
/// between those of the vertices. For single segments this is [`super::shaft`]'s test of an
/// occluder cutting a whole shaft.
pub(crate) fn cuts_bundle(a: &Hull, b: &Hull, s: Segment) -> bool {
    // `s` crosses the segment between two points of the hulls, so it meets their joint box.
    let (lo, hi) = (a.lo.min(b.lo), a.hi.max(b.hi));
    if a.points.is_empty()
        || b.points.is_empty()
        || s.a.max(s.b).cmplt(lo).any()
        || s.a.min(s.b).cmpgt(hi).any()
    {
        return false;
    }
    let side = |v: DVec2| orient(s.a, s.b, v);
    let all = |pts: &[DVec2], positive: bool| {
        pts.iter().all(|&v| {
            if positive {
                side(v) > 0.0
            } else {
                side(v) < 0.0
            }
        })
    };
    let (a, b) = (a.points(), b.points());
    let opposite = (all(a, true) && all(b, false)) || (all(a, false) && all(b, true));
    opposite
        && a.iter().all(|&u| {
            b.iter()
                .all(|&v| !strictly_same_side(orient(u, v, s.a), orient(u, v, s.b)))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{point, rng};
    use crate::visibility::predicates::open_segment_hits;
    use rand::RngExt;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    fn seg(a: DVec2, b: DVec2) -> Segment {
        Segment { a, b }
    }

    #[test]
    fn interior_is_met_through_it_and_not_along_or_outside() {
        let square = Hull::of(&[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]);
        let meets_interior = |hull: &Hull, s| hull.meets_interior(s);
        assert!(
            meets_interior(&square, seg(v(0.5, 0.5), v(3.0, 3.0))),
            "from inside"
        );
        assert!(
            meets_interior(&square, seg(v(-1.0, 0.5), v(2.0, 0.5))),
            "across"
        );
        assert!(
            meets_interior(&square, seg(v(0.0, 0.0), v(1.0, 1.0))),
            "a diagonal"
        );
        assert!(
            !meets_interior(&square, seg(v(0.0, 0.0), v(1.0, 0.0))),
            "a side"
        );
        assert!(
            !meets_interior(&square, seg(v(-1.0, 0.0), v(2.0, 0.0))),
            "along a side"
        );
        assert!(
            !meets_interior(&square, seg(v(1.0, 1.0), v(2.0, 3.0))),
            "a corner"
        );
        assert!(
            !meets_interior(&square, seg(v(2.0, 0.0), v(0.0, 2.5))),
            "outside"
        );
        assert!(
            !meets_interior(&square, seg(v(-1.0, 1.0), v(1.0, 3.0))),
            "past a corner"
        );
        let flat = Hull::of(&[v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0)]);
        assert!(
            !meets_interior(&flat, seg(v(0.5, -1.0), v(0.5, 1.0))),
            "no interior"
        );
    }

    /// Against an independent oracle: the lines of the hull's sides cut `s` into pieces on
    /// each of which every side's orientation is constant, so `s` meets the interior exactly
    /// when the middle of some piece lies strictly inside (snapped points keep every piece
    /// long against rounding).
    #[test]
    fn interior_test_agrees_with_the_pieces_of_the_segment() {
        let mut r = rng(7);
        let snap = |p: DVec2| (p * 2.0).round() / 2.0;
        let (mut met, mut missed) = (0, 0);
        for _ in 0..4000 {
            let pts: Vec<DVec2> = (0..r.random_range(3..7))
                .map(|_| snap(point(&mut r)))
                .collect();
            let shape = Hull::of(&pts);
            let hull = shape.points();
            let s = seg(snap(point(&mut r)) * 1.5, snap(point(&mut r)) * 1.5);
            if s.a == s.b {
                continue;
            }
            let n = hull.len();
            let inside =
                |e: DVec2| n >= 3 && (0..n).all(|i| orient(hull[i], hull[(i + 1) % n], e) > 0.0);
            let mut cuts = vec![0.0, 1.0];
            for i in 0..n {
                let (u, w) = (hull[i], hull[(i + 1) % n]);
                let (oa, ob) = (orient(u, w, s.a), orient(u, w, s.b));
                if oa * ob < 0.0 {
                    cuts.push(oa / (oa - ob));
                }
            }
            cuts.sort_by(f64::total_cmp);
            let oracle = cuts
                .windows(2)
                .any(|w| w[1] > w[0] && inside(s.a + (s.b - s.a) * (0.5 * (w[0] + w[1]))));
            assert_eq!(shape.meets_interior(s), oracle, "{hull:?} {s:?}");
            if oracle { met += 1 } else { missed += 1 }
        }
        assert!(
            met > 500 && missed > 500,
            "both cases are tried ({met}, {missed})"
        );
    }

    /// A segment that cuts a bundle cuts every segment between the two clusters' points.
    #[test]
    fn a_cut_bundle_has_every_segment_cut() {
        let mut r = rng(11);
        let mut cut = 0;
        for _ in 0..4000 {
            let cluster = |r: &mut rand_chacha::ChaCha8Rng, y: f64| -> Vec<DVec2> {
                (0..r.random_range(1..5))
                    .map(|_| point(r) * 0.5 + v(0.0, y))
                    .collect()
            };
            let (a, b) = (cluster(&mut r, 1.0), cluster(&mut r, -1.0));
            let s = seg(point(&mut r) * 2.0, point(&mut r) * 2.0);
            if !cuts_bundle(&Hull::of(&a), &Hull::of(&b), s) {
                continue;
            }
            cut += 1;
            for _ in 0..50 {
                let mix = |pts: &[DVec2], r: &mut rand_chacha::ChaCha8Rng| {
                    let w: Vec<f64> = pts.iter().map(|_| r.random::<f64>()).collect();
                    let sum: f64 = w.iter().sum();
                    pts.iter()
                        .zip(&w)
                        .map(|(&p, &w)| p * (w / sum))
                        .sum::<DVec2>()
                };
                let (x, y) = (mix(&a, &mut r), mix(&b, &mut r));
                assert!(open_segment_hits(x, y, s.a, s.b), "{a:?} {b:?} {s:?}");
            }
        }
        assert!(cut > 100, "the test cuts bundles ({cut})");
    }
}
