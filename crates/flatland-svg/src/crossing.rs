//! Whether the outline of a fill crosses or touches itself: exact orientation predicates on the
//! pieces that share a cell of a uniform grid (about linear for the outlines of drawings).

use glam::DVec2;
use robust::{Coord, orient2d};

use crate::outline::Polyline;

/// A piece of a closed outline: its loop, its index in the loop and its end points.
#[derive(Clone, Copy)]
struct Piece {
    ring: usize,
    index: usize,
    p: DVec2,
    q: DVec2,
}

/// A point where the closed outlines `rings` cross, touch or double back on themselves, if they
/// do anywhere; `None` for simple loops that do not meet.
pub fn first_contact(rings: &[Polyline]) -> Option<DVec2> {
    let pieces: Vec<Piece> = rings
        .iter()
        .enumerate()
        .flat_map(|(ring, polyline)| {
            let n = polyline.points.len();
            (0..n).map(move |index| Piece {
                ring,
                index,
                p: polyline.points[index],
                q: polyline.points[(index + 1) % n],
            })
        })
        .collect();
    let sizes: Vec<usize> = rings.iter().map(|r| r.points.len()).collect();
    let grid = Grid::new(&pieces);
    for (c, cell) in grid.cells.iter().enumerate() {
        for (k, &a) in cell.iter().enumerate() {
            for &b in &cell[k + 1..] {
                let (x, y) = (pieces[a], pieces[b]);
                if grid.owns(&x, &y, c)
                    && let Some(at) = contact(&x, &y, &sizes)
                {
                    return Some(at);
                }
            }
        }
    }
    None
}

/// Where pieces `x` and `y` meet in a way a simple outline does not allow.
fn contact(x: &Piece, y: &Piece, sizes: &[usize]) -> Option<DVec2> {
    let n = sizes[x.ring];
    let adjacent =
        x.ring == y.ring && ((x.index + 1) % n == y.index || (y.index + 1) % n == x.index);
    if adjacent {
        // They share a vertex; they may only meet there, unless the outline doubles back.
        let (shared, a, b) = if x.q == y.p {
            (x.q, x.p, y.q)
        } else {
            (x.p, x.q, y.p)
        };
        let back = orient(a, shared, b) == 0.0 && (a - shared).dot(b - shared) > 0.0;
        return back.then_some(shared);
    }
    let (o1, o2) = (orient(x.p, x.q, y.p), orient(x.p, x.q, y.q));
    let (o3, o4) = (orient(y.p, y.q, x.p), orient(y.p, y.q, x.q));
    if o1 * o2 < 0.0 && o3 * o4 < 0.0 {
        return Some(crossing_point(x, y));
    }
    let on = |o: f64, s: (DVec2, DVec2), r: DVec2| o == 0.0 && within(s.0, s.1, r);
    [
        (on(o1, (x.p, x.q), y.p), y.p),
        (on(o2, (x.p, x.q), y.q), y.q),
        (on(o3, (y.p, y.q), x.p), x.p),
        (on(o4, (y.p, y.q), x.q), x.q),
    ]
    .into_iter()
    .find_map(|(touches, at)| touches.then_some(at))
}

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    let coord = |p: DVec2| Coord { x: p.x, y: p.y };
    orient2d(coord(a), coord(b), coord(c))
}

/// Whether `r`, on the line of `p–q`, lies on the closed segment.
fn within(p: DVec2, q: DVec2, r: DVec2) -> bool {
    r.cmpge(p.min(q)).all() && r.cmple(p.max(q)).all()
}

fn crossing_point(x: &Piece, y: &Piece) -> DVec2 {
    let (d, e) = (x.q - x.p, y.q - y.p);
    let t = (y.p - x.p).perp_dot(e) / d.perp_dot(e);
    x.p + d * t
}

/// A uniform grid over the pieces' bounding box; each piece is listed in every cell its box
/// covers.
struct Grid {
    lo: DVec2,
    cell: DVec2,
    dims: (usize, usize),
    cells: Vec<Vec<usize>>,
}

impl Grid {
    fn new(pieces: &[Piece]) -> Grid {
        let lo = pieces
            .iter()
            .fold(DVec2::INFINITY, |m, s| m.min(s.p).min(s.q));
        let hi = pieces
            .iter()
            .fold(DVec2::NEG_INFINITY, |m, s| m.max(s.p).max(s.q));
        let mean = pieces
            .iter()
            .map(|s| (s.q - s.p).abs().max_element())
            .sum::<f64>()
            / pieces.len().max(1) as f64;
        // Cells about the size of a piece, at most 2√n + 1 along each axis.
        let limit = 2.0 * (pieces.len() as f64).sqrt() + 1.0;
        let along = |extent: f64| (extent / mean.max(f64::MIN_POSITIVE)).clamp(1.0, limit) as usize;
        let span = hi - lo;
        let dims = (along(span.x), along(span.y));
        let cell = DVec2::new(span.x / dims.0 as f64, span.y / dims.1 as f64)
            .max(DVec2::splat(f64::MIN_POSITIVE));
        let mut grid = Grid {
            lo,
            cell,
            dims,
            cells: vec![Vec::new(); dims.0 * dims.1],
        };
        for (i, s) in pieces.iter().enumerate() {
            let (a, b) = (grid.index(s.p.min(s.q)), grid.index(s.p.max(s.q)));
            for cy in a.1..=b.1 {
                for cx in a.0..=b.0 {
                    grid.cells[cy * dims.0 + cx].push(i);
                }
            }
        }
        grid
    }

    fn index(&self, p: DVec2) -> (usize, usize) {
        let c = (p - self.lo) / self.cell;
        let clamp = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
        (clamp(c.x, self.dims.0), clamp(c.y, self.dims.1))
    }

    /// Whether `cell` is the one cell that tests the pair: the cell of the lower corner of the
    /// overlap of their boxes (pairs whose boxes do not overlap cannot meet).
    fn owns(&self, x: &Piece, y: &Piece, cell: usize) -> bool {
        let lo = x.p.min(x.q).max(y.p.min(y.q));
        let hi = x.p.max(x.q).min(y.p.max(y.q));
        if lo.cmpgt(hi).any() {
            return false;
        }
        let (cx, cy) = self.index(lo);
        cy * self.dims.0 + cx == cell
    }
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

    #[test]
    fn simple_and_nested_loops_do_not_meet() {
        let outer = ring(&[[0., 0.], [10., 0.], [10., 10.], [0., 10.]]);
        let hole = ring(&[[2., 2.], [2., 8.], [8., 8.], [8., 2.]]);
        assert_eq!(first_contact(&[outer.clone(), hole]), None);
        let triangle = ring(&[[0., 0.], [1., 0.], [0., 1.]]);
        assert_eq!(first_contact(&[triangle]), None);
        // A circle of many pieces.
        let n = 2000;
        let circle: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                [a.cos(), a.sin()]
            })
            .collect();
        assert_eq!(first_contact(&[ring(&circle)]), None);
    }

    #[test]
    fn crossings_touches_and_fold_backs_are_found() {
        let bowtie = ring(&[[0., 0.], [2., 2.], [2., 0.], [0., 2.]]);
        assert_eq!(first_contact(&[bowtie]), Some(DVec2::new(1.0, 1.0)));
        // A vertex touching another piece of the same loop.
        let pinch = ring(&[[0., 0.], [4., 0.], [4., 4.], [2., 0.], [0., 4.]]);
        assert_eq!(first_contact(&[pinch]), Some(DVec2::new(2.0, 0.0)));
        // Two loops sharing an edge.
        let a = ring(&[[0., 0.], [1., 0.], [1., 1.], [0., 1.]]);
        let b = ring(&[[1., 0.], [2., 0.], [2., 1.], [1., 1.]]);
        assert!(first_contact(&[a, b]).is_some());
        // A spike: the outline goes out and comes back along itself.
        let spike = ring(&[[0., 0.], [4., 0.], [6., 0.], [5., 0.], [4., 3.]]);
        assert!(first_contact(&[spike]).is_some());
    }
}
