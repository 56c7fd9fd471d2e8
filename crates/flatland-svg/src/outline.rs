//! A path of usvg's tree as polylines in plan coordinates: curves flattened within a tolerance,
//! zero-length pieces merged.

use glam::DVec2;
use kurbo::{Affine, PathEl, Point};
use usvg::tiny_skia_path::{self, PathSegment};

/// Pieces shorter than this times the element's size are merged with their neighbours: below
/// it a piece is rounding, not a wall (the same relative 1e-9 the overlap check uses).
const MERGE: f64 = 1e-9;
/// The flattening tolerance is at least this times the element's size, so a curve never gives
/// more than about a thousand segments, whatever its coordinates.
const FINEST: f64 = 1e-6;

/// One subpath: its points in order and whether it is closed (`Z`).
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    /// The points, at least two, no two consecutive ones the same.
    pub points: Vec<DVec2>,
    /// Whether the last point joins the first (the closing piece is not repeated in `points`).
    pub closed: bool,
}

impl Polyline {
    /// The pieces `(p, q)` in order, the closing one last when closed.
    pub fn pieces(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        let n = self.points.len();
        // A closed outline of two points is a piece there and back.
        let count = if self.closed { n } else { n - 1 };
        (0..count).map(move |i| (self.points[i], self.points[(i + 1) % n]))
    }
}

/// A path's polylines and how many zero-length pieces were merged away.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outline {
    /// The subpaths with at least two distinct points.
    pub polylines: Vec<Polyline>,
    /// Zero-length pieces merged (a closing piece back onto the start is not counted).
    pub merged: usize,
}

/// `path` mapped by `to_plan` and flattened within `tolerance` (plan units). `Err` holds a
/// point that is not finite after the transform.
pub fn outline(
    path: &tiny_skia_path::Path,
    to_plan: Affine,
    tolerance: f64,
) -> Result<Outline, DVec2> {
    let map = |p: tiny_skia_path::Point| to_plan * Point::new(widen(p.x), widen(p.y));
    let elements: Vec<PathEl> = path
        .segments()
        .map(|segment| match segment {
            PathSegment::MoveTo(p) => PathEl::MoveTo(map(p)),
            PathSegment::LineTo(p) => PathEl::LineTo(map(p)),
            PathSegment::QuadTo(c, p) => PathEl::QuadTo(map(c), map(p)),
            PathSegment::CubicTo(c1, c2, p) => PathEl::CurveTo(map(c1), map(c2), map(p)),
            PathSegment::Close => PathEl::ClosePath,
        })
        .collect();
    let mut lo = DVec2::INFINITY;
    let mut hi = DVec2::NEG_INFINITY;
    for el in &elements {
        for p in el_points(el) {
            let p = DVec2::new(p.x, p.y);
            if !p.is_finite() {
                return Err(p);
            }
            (lo, hi) = (lo.min(p), hi.max(p));
        }
    }
    let size = (hi - lo).length();
    if !size.is_finite() {
        return Err(hi - lo);
    }
    let mut raw: Vec<Polyline> = Vec::new();
    kurbo::flatten(elements, tolerance.max(FINEST * size), |el| match el {
        PathEl::MoveTo(p) => raw.push(Polyline {
            points: vec![DVec2::new(p.x, p.y)],
            closed: false,
        }),
        PathEl::LineTo(p) => {
            if let Some(last) = raw.last_mut() {
                last.points.push(DVec2::new(p.x, p.y));
            }
        }
        PathEl::ClosePath => {
            if let Some(last) = raw.last_mut() {
                last.closed = true;
            }
        }
        _ => {}
    });
    let mut result = Outline::default();
    for polyline in raw {
        if let Some(merged) = merge(polyline, MERGE * size, &mut result.merged) {
            result.polylines.push(merged);
        }
    }
    Ok(result)
}

/// The f64 nearest the shortest decimal that reads as `x`: usvg keeps numbers as f32, so the
/// drawing's `7.8` arrives as 7.80000019; this gives back 7.8. Exact for numbers written with up
/// to seven significant digits, and never further from `x` than f32 rounding.
pub fn widen(x: f32) -> f64 {
    // Display prints the shortest decimal that reads back as the same f32.
    x.to_string().parse().unwrap_or(f64::from(x))
}

fn el_points(el: &PathEl) -> Vec<Point> {
    match *el {
        PathEl::MoveTo(p) | PathEl::LineTo(p) => vec![p],
        PathEl::QuadTo(a, b) => vec![a, b],
        PathEl::CurveTo(a, b, c) => vec![a, b, c],
        PathEl::ClosePath => Vec::new(),
    }
}

/// `polyline` without pieces of length `<= tiny`; `None` when fewer than two points remain.
fn merge(polyline: Polyline, tiny: f64, merged: &mut usize) -> Option<Polyline> {
    let mut points: Vec<DVec2> = Vec::with_capacity(polyline.points.len());
    for p in polyline.points {
        match points.last() {
            Some(&last) if (p - last).length() <= tiny => *merged += 1,
            _ => points.push(p),
        }
    }
    // An outline that returns to its start is closed, with or without `Z`; the closing piece
    // is implied.
    let mut closed = polyline.closed;
    if points.len() > 2 && (points[points.len() - 1] - points[0]).length() <= tiny {
        points.pop();
        closed = true;
    }
    (points.len() >= 2).then_some(Polyline { points, closed })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(d: &str) -> tiny_skia_path::Path {
        let svg = format!("<svg xmlns='http://www.w3.org/2000/svg'><path id='p' d='{d}'/></svg>");
        let tree = usvg::Tree::from_str(&svg, &usvg::Options::default()).unwrap();
        match tree.node_by_id("p").unwrap() {
            usvg::Node::Path(p) => p.data().clone(),
            _ => unreachable!(),
        }
    }

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn lines_keep_their_points_and_the_transform_applies() {
        let flip = Affine::new([2.0, 0.0, 0.0, -2.0, 1.0, 0.0]);
        let out = outline(&path("M0 0 L3 0 L3 4 Z"), flip, 0.1).unwrap();
        assert_eq!(
            out.polylines,
            [Polyline {
                points: vec![v(1.0, 0.0), v(7.0, 0.0), v(7.0, -8.0)],
                closed: true
            }]
        );
        assert_eq!(out.polylines[0].pieces().count(), 3);
        assert_eq!(out.merged, 0);
    }

    #[test]
    fn a_circle_stays_within_the_tolerance() {
        let r = 10.0;
        let circle = path("M10 0 A10 10 0 1 1 -10 0 A10 10 0 1 1 10 0 Z");
        for tolerance in [0.5, 0.01] {
            let out = outline(&circle, Affine::IDENTITY, tolerance).unwrap();
            let points = &out.polylines[0].points;
            // usvg turns an arc into cubics, within 1e-3 r of the circle (7.5e-4 r seen).
            let cubic = 1e-3 * r;
            for (p, q) in out.polylines[0].pieces() {
                assert!((p.length() - r).abs() < cubic, "{p}");
                // A chord's sagitta is its largest distance from the arc.
                let sagitta = r - ((p + q) * 0.5).length();
                assert!(sagitta <= tolerance + cubic, "{sagitta} > {tolerance}");
            }
            // Not far finer than asked: the sagitta of a chord 2r·sin(π/n) is r(1 − cos(π/n)).
            let needed = std::f64::consts::PI / (1.0 - tolerance / r).acos();
            assert!(
                (points.len() as f64) < 2.0 * needed + 8.0,
                "{} points",
                points.len()
            );
        }
    }

    #[test]
    fn zero_length_pieces_are_merged_and_counted() {
        let out = outline(
            &path("M0 0 L0 0 L5 0 L5 0 L5 5 L0 0 Z"),
            Affine::IDENTITY,
            0.1,
        )
        .unwrap();
        assert_eq!(
            out.polylines[0].points,
            [v(0.0, 0.0), v(5.0, 0.0), v(5.0, 5.0)]
        );
        assert_eq!(out.merged, 2);
        // Nothing but one point: no polyline.
        let dot = outline(&path("M1 1 L1 1"), Affine::IDENTITY, 0.1).unwrap();
        assert!(dot.polylines.is_empty());
    }

    #[test]
    fn numbers_come_back_as_written() {
        assert_eq!(widen(7.8), 7.8);
        assert_eq!(widen(-0.2), -0.2);
        assert_eq!(widen(12345.67), 12345.67);
        assert_eq!(widen(1.0e-30), 1.0e-30);
        assert_eq!(widen(f32::MAX), 3.4028235e38);
        assert!(widen(f32::NAN).is_nan());
        assert_eq!(widen(f32::INFINITY), f64::INFINITY);
    }

    #[test]
    fn a_non_finite_transform_is_reported() {
        let nan = Affine::new([f64::NAN, 0.0, 0.0, 1.0, 0.0, 0.0]);
        assert!(outline(&path("M0 0 L1 1"), nan, 0.1).is_err());
    }
}
