//! Exact predicates (`orient2d`): the segment test with its grazing rule, crossings, convex hulls.

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
pub(super) fn strictly_same_side(o1: f64, o2: f64) -> bool {
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
pub(super) fn collinear_overlap(x: DVec2, y: DVec2, p: DVec2, q: DVec2) -> bool {
    if x == y {
        return false;
    }
    // On one line the order along the line is the order of either coordinate that varies.
    let key = |v: DVec2| if x.x != y.x { v.x } else { v.y };
    let (s0, s1) = (key(x).min(key(y)), key(x).max(key(y)));
    let (o0, o1) = (key(p).min(key(q)), key(p).max(key(q)));
    o0 < s1 && o1 > s0
}

/// Whether `u` and `v` are both nonzero and of opposite signs.
pub(super) fn strictly_opposite(u: f64, v: f64) -> bool {
    (u > 0.0 && v < 0.0) || (u < 0.0 && v > 0.0)
}

/// Whether `e` lies on the closed segment `[a, b]` (exactly).
pub(crate) fn on_closed_segment(e: DVec2, a: DVec2, b: DVec2) -> bool {
    orient(a, b, e) == 0.0
        && e.x >= a.x.min(b.x)
        && e.x <= a.x.max(b.x)
        && e.y >= a.y.min(b.y)
        && e.y <= a.y.max(b.y)
}

/// The convex hull of `pts`, counter-clockwise, collinear points and repeats dropped (exact);
/// fewer than 3 points when they all lie on one line.
pub(super) fn convex_hull(pts: &[DVec2]) -> Vec<DVec2> {
    // Andrew's monotone chain.
    let mut sorted = pts.to_vec();
    // `+ 0.0` makes -0.0 equal to 0.0 for `total_cmp`: equal coordinates must sort by y.
    sorted.sort_by(|a, b| {
        (a.x + 0.0)
            .total_cmp(&(b.x + 0.0))
            .then((a.y + 0.0).total_cmp(&(b.y + 0.0)))
    });
    let mut hull: Vec<DVec2> = Vec::with_capacity(sorted.len() + 1);
    let n = sorted.len();
    for pass in 0..2 {
        let start = hull.len();
        for k in 0..n {
            let p = if pass == 0 {
                sorted[k]
            } else {
                sorted[n - 1 - k]
            };
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
pub(super) fn strictly_inside(e: DVec2, hull: &[DVec2]) -> bool {
    hull.len() >= 3 && (0..hull.len()).all(|i| orient(hull[i], hull[(i + 1) % hull.len()], e) > 0.0)
}

/// The point where segment `[a, b]` crosses segment `[c, d]` strictly inside both (not at an
/// end point, not collinear), rounded; `None` otherwise.
pub(super) fn proper_crossing(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> Option<DVec2> {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
