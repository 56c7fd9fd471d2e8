//! Writing SVG: a scene as a drawing that imports back to the same edges ([`scene_svg`]), and
//! the lit plan ([`lit`]).

pub mod lit;
mod scene;

pub use scene::scene_svg;

use std::fmt::Write as _;

use flatland_geom::DVec2;

/// A plan point as SVG coordinates: y down, so the plan reads as drawn.
fn svg_point(p: DVec2) -> DVec2 {
    DVec2::new(p.x, -p.y)
}

/// `points` as an SVG `points` list, in SVG coordinates.
fn points_attribute(points: impl Iterator<Item = DVec2>) -> String {
    let mut out = String::new();
    for p in points {
        let q = svg_point(p);
        if !out.is_empty() {
            out.push(' ');
        }
        // `{}` prints the shortest text that reads back as the same f64.
        let _ = write!(out, "{},{}", q.x, q.y);
    }
    out
}

/// `#rrggbb`.
fn hex([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// `text` with XML's five special characters escaped.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}
