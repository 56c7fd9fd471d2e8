//! Which way the edges of a filled shape face: away from (or into) the region its fill paints,
//! decided exactly for outlines that neither cross nor touch.

use glam::DVec2;
use robust::{Coord, orient2d};
use usvg::FillRule;

use crate::crossing::first_contact;
use crate::outline::Polyline;

/// Why a fill gives no edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FillProblem {
    /// Its outline crosses or touches itself near this point (plan coordinates).
    Crosses(DVec2),
    /// No subpath encloses any area.
    NoArea,
}

/// The edges of a fill and what was left out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FillEdges {
    /// Edges `(a, b)`, front to the left, loop by loop.
    pub edges: Vec<(DVec2, DVec2)>,
    /// Subpaths left out: fewer than three points or no area.
    pub flat: usize,
    /// Subpaths left out because the fill lies on both of their sides (a loop inside a loop of
    /// the same direction under the nonzero rule): no boundary.
    pub inside: usize,
}

/// The edges of the region `polylines` paint under `rule` (every subpath closed, as a fill is):
/// facing out of it, or into it when `inward`.
pub fn fill_edges(
    polylines: &[Polyline],
    rule: FillRule,
    inward: bool,
) -> Result<FillEdges, FillProblem> {
    let mut out = FillEdges::default();
    let mut rings: Vec<Polyline> = Vec::new();
    for p in polylines {
        if collinear(&p.points) {
            out.flat += 1;
        } else {
            rings.push(Polyline {
                points: p.points.clone(),
                closed: true,
            });
        }
    }
    if rings.is_empty() {
        return Err(FillProblem::NoArea);
    }
    if let Some(at) = first_contact(&rings) {
        return Err(FillProblem::Crosses(at));
    }
    let boxes: Vec<(DVec2, DVec2)> = rings.iter().map(|r| bounds(&r.points)).collect();
    let filled = |w: i64| match rule {
        FillRule::NonZero => w != 0,
        FillRule::EvenOdd => w % 2 != 0,
    };
    for (i, ring) in rings.iter().enumerate() {
        // The rings neither cross nor touch: one vertex says which others enclose this one.
        let at = ring.points[0];
        let others: i64 = (0..rings.len())
            .filter(|&j| j != i && inside_box(at, boxes[j]))
            .map(|j| winding(&rings[j].points, at))
            .sum();
        let ccw = counter_clockwise(&ring.points);
        let left = others + i64::from(ccw);
        let right = others - i64::from(!ccw);
        // Front to the left: keep the direction when the fill (or, inward, the outside) is to
        // the right.
        let keep = match (filled(left), filled(right)) {
            (false, true) => !inward,
            (true, false) => inward,
            _ => {
                out.inside += 1;
                continue;
            }
        };
        let n = ring.points.len();
        for k in 0..n {
            let (p, q) = (ring.points[k], ring.points[(k + 1) % n]);
            out.edges.push(if keep { (p, q) } else { (q, p) });
        }
        if !keep {
            // Reversed loops run backwards, so consecutive edges still join.
            let start = out.edges.len() - n;
            out.edges[start..].reverse();
        }
    }
    Ok(out)
}

/// Whether `points` (any number) lie on one line: such a loop encloses nothing. Exact.
pub fn collinear(points: &[DVec2]) -> bool {
    let coord = |v: DVec2| Coord { x: v.x, y: v.y };
    let Some(&a) = points.first() else {
        return true;
    };
    let Some(&b) = points.iter().find(|&&p| p != a) else {
        return true;
    };
    points
        .iter()
        .all(|&p| orient2d(coord(a), coord(b), coord(p)) == 0.0)
}

/// Whether a simple polygon runs counter-clockwise (y up), exactly: at its lowest-leftmost
/// vertex, which is convex, its neighbours turn left.
pub fn counter_clockwise(points: &[DVec2]) -> bool {
    let coord = |v: DVec2| Coord { x: v.x, y: v.y };
    let n = points.len();
    let k = (0..n)
        .min_by(|&i, &j| {
            let (p, q) = (points[i], points[j]);
            p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y))
        })
        .unwrap_or(0);
    let (prev, next) = (points[(k + n - 1) % n], points[(k + 1) % n]);
    orient2d(coord(prev), coord(points[k]), coord(next)) > 0.0
}

fn bounds(points: &[DVec2]) -> (DVec2, DVec2) {
    points
        .iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
}

fn inside_box(p: DVec2, (lo, hi): (DVec2, DVec2)) -> bool {
    p.cmpge(lo).all() && p.cmple(hi).all()
}

/// The winding number of the closed polygon `points` around `p` (not on it), exactly.
fn winding(points: &[DVec2], p: DVec2) -> i64 {
    let coord = |v: DVec2| Coord { x: v.x, y: v.y };
    let n = points.len();
    let mut w = 0;
    for k in 0..n {
        let (a, b) = (points[k], points[(k + 1) % n]);
        let side = orient2d(coord(a), coord(b), coord(p));
        if a.y <= p.y {
            if b.y > p.y && side > 0.0 {
                w += 1;
            }
        } else if b.y <= p.y && side < 0.0 {
            w -= 1;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(points: &[[f64; 2]]) -> Polyline {
        Polyline {
            points: points.iter().map(|&p| DVec2::from(p)).collect(),
            closed: true,
        }
    }

    fn square(lo: f64, hi: f64, ccw: bool) -> Polyline {
        let mut r = ring(&[[lo, lo], [hi, lo], [hi, hi], [lo, hi]]);
        if !ccw {
            r.points.reverse();
        }
        r
    }

    /// Whether every edge's front (left) looks away from the square `[lo, hi]²`'s inside.
    fn faces_away(edges: &[(DVec2, DVec2)], centre: DVec2) -> bool {
        edges.iter().all(|&(a, b)| {
            let mid = (a + b) * 0.5;
            let normal = (b - a).perp();
            normal.dot(mid - centre) > 0.0
        })
    }

    #[test]
    fn a_column_faces_out_either_way_it_is_drawn_and_in_when_asked() {
        for ccw in [true, false] {
            let got = fill_edges(&[square(0.0, 1.0, ccw)], FillRule::NonZero, false).unwrap();
            assert_eq!(got.edges.len(), 4);
            assert!(faces_away(&got.edges, DVec2::splat(0.5)));
            // Consecutive edges join.
            for k in 0..4 {
                assert_eq!(got.edges[k].1, got.edges[(k + 1) % 4].0);
            }
            let inward = fill_edges(&[square(0.0, 1.0, ccw)], FillRule::NonZero, true).unwrap();
            assert!(!faces_away(&inward.edges, DVec2::splat(0.5)));
        }
    }

    #[test]
    fn a_thick_wall_ring_faces_out_outside_and_into_the_room_inside() {
        // Outer 0..10, room 1..9: the hole's edges face the hole's centre, i.e. into the room.
        for rule in [FillRule::EvenOdd, FillRule::NonZero] {
            let got = fill_edges(
                &[square(0.0, 10.0, true), square(1.0, 9.0, false)],
                rule,
                false,
            )
            .unwrap();
            let (outer, hole) = got.edges.split_at(4);
            assert!(faces_away(outer, DVec2::splat(5.0)));
            assert!(!faces_away(hole, DVec2::splat(5.0)));
            assert_eq!(got.inside, 0);
        }
        // Same direction under nonzero: the inner loop lies inside the fill, no boundary.
        let same = fill_edges(
            &[square(0.0, 10.0, true), square(1.0, 9.0, true)],
            FillRule::NonZero,
            false,
        )
        .unwrap();
        assert_eq!((same.edges.len(), same.inside), (4, 1));
        // ...and a hole under even-odd.
        let evenodd = fill_edges(
            &[square(0.0, 10.0, true), square(1.0, 9.0, true)],
            FillRule::EvenOdd,
            false,
        )
        .unwrap();
        assert_eq!(evenodd.edges.len(), 8);
    }

    #[test]
    fn flat_and_crossing_fills_are_reported() {
        let line = ring(&[[0., 0.], [1., 0.], [2., 0.]]);
        assert_eq!(
            fill_edges(&[line], FillRule::NonZero, false),
            Err(FillProblem::NoArea)
        );
        let bowtie = ring(&[[0., 0.], [2., 2.], [2., 0.], [0., 2.]]);
        assert_eq!(
            fill_edges(&[bowtie], FillRule::NonZero, false),
            Err(FillProblem::Crosses(DVec2::new(1.0, 1.0)))
        );
    }

    #[test]
    fn orientation_is_exact() {
        assert!(counter_clockwise(&square(0.0, 2.0, true).points));
        assert!(!counter_clockwise(&square(0.0, 2.0, false).points));
        // A sliver far from the origin, whose area rounds badly, still has its direction.
        let sliver = ring(&[[1e8, 1e8], [1e8 + 1.0, 1e8 + 1e-7], [1e8 + 2.0, 1e8]]);
        assert!(!counter_clockwise(&sliver.points));
    }
}
