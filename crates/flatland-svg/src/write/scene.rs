//! A scene as SVG that [`import`](crate::import) reads back to the same edges, in the same
//! order (within f32 rounding: usvg keeps coordinates as f32).
//!
//! The encoding, in plan units (`unit = 1`), y flipped as the importer flips it: consecutive
//! edges that join end to start with the same material form a run. A closed run of one-sided
//! surfaces that is a simple polygon with its fill to the right of every edge (a column, a box:
//! its edges face out) is a filled `<polygon>`; every other run is a `<polyline>` (or a
//! `<polygon>` when closed) with `fill="none"` and `data-flatland-faces="left"`, so each piece
//! is one edge facing as it did. Blockers carry `data-flatland-role="blocker"` and faces `both`
//! when two-sided. Every element carries its reflectance, and its emission when not 0. Point
//! lights are circles of class `flatland-light` with their power.

use std::fmt::Write as _;

use flatland_geom::{DVec2, Edge, Role, Scene};

use super::{escape, hex, points_attribute, svg_point};
use crate::crossing::first_contact;
use crate::faces::counter_clockwise;
use crate::outline::Polyline;

/// A piece shorter than this times its element's size would be merged by the importer; a run
/// holding one is written edge by edge instead.
const SHORT: f64 = 1e-8;

/// `scene` as an SVG drawing (see the module docs), titled `title`.
#[must_use]
pub fn scene_svg(scene: &Scene, title: &str) -> String {
    let edges = scene.edges();
    let runs = runs(edges);
    let solid: Vec<bool> = runs.iter().map(|r| is_solid(&edges[r.clone()])).collect();
    let solid = without_twins(edges, &runs, solid);
    let (lo, hi) = scene.bounds();
    let margin = 0.05 * (hi - lo).max_element();
    let (corner, size) = (
        svg_point(DVec2::new(lo.x, hi.y)) - margin,
        hi - lo + 2.0 * margin,
    );
    let stroke = 0.004 * (hi - lo).length();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"{} {} {} {}\">",
        1000.0,
        (1000.0 * size.y / size.x).round(),
        corner.x,
        corner.y,
        size.x,
        size.y
    );
    let _ = writeln!(out, "<title>{}</title>", escape(title));
    let _ = writeln!(
        out,
        "<desc>A flatland scene: filled polygons are solids whose edges face out; the other lines face left of the way they run (data-flatland-faces). y is up in the scene, down here.</desc>"
    );
    let _ = writeln!(
        out,
        "<g stroke-width=\"{stroke}\" stroke-linejoin=\"round\" stroke-linecap=\"round\">"
    );
    for (run, &is_solid) in runs.iter().zip(&solid) {
        let run = &edges[run.clone()];
        if !is_solid && run.iter().any(|e| e.length() <= SHORT * size_of(run)) {
            for edge in run {
                write_run(&mut out, std::slice::from_ref(edge), false);
            }
        } else {
            write_run(&mut out, run, is_solid);
        }
    }
    out.push_str("</g>\n");
    // Point lights: marked circles (their radius only draws them).
    for light in scene.lights() {
        let p = svg_point(light.at);
        let _ = writeln!(
            out,
            "<circle class=\"flatland-light\" cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"#f5b800\" data-flatland-power=\"{}\"/>",
            p.x,
            p.y,
            3.0 * stroke,
            light.power
        );
    }
    out.push_str("</svg>\n");
    out
}

/// One element for the edges of `run`.
fn write_run(out: &mut String, run: &[Edge], solid: bool) {
    let first = run[0];
    let closed = run.len() > 1 && run[run.len() - 1].b == first.a;
    let mut points: Vec<DVec2> = run.iter().map(|e| e.a).collect();
    if !closed {
        points.push(run[run.len() - 1].b);
    }
    let tag = if closed { "polygon" } else { "polyline" };
    let grey = (255.0 * (0.25 + 0.6 * first.reflectance)) as u8;
    let colour = if first.emission > 0.0 {
        [245, 184, 0]
    } else {
        [grey; 3]
    };
    let paint = if solid {
        format!("fill=\"{}\" stroke=\"#303030\"", hex(colour))
    } else if first.role == Role::Blocker {
        "fill=\"none\" stroke=\"#8c8c8c\"".to_string()
    } else {
        format!("fill=\"none\" stroke=\"{}\"", hex(colour))
    };
    let mut attributes = format!("data-flatland-reflectance=\"{}\"", first.reflectance);
    if first.emission > 0.0 {
        let _ = write!(attributes, " data-flatland-emission=\"{}\"", first.emission);
    }
    if first.role == Role::Blocker {
        attributes.push_str(" data-flatland-role=\"blocker\"");
    }
    if !solid {
        let faces = if first.two_sided { "both" } else { "left" };
        let _ = write!(attributes, " data-flatland-faces=\"{faces}\"");
    }
    let _ = writeln!(
        out,
        "<{tag} points=\"{}\" {paint} {attributes}/>",
        points_attribute(points.into_iter())
    );
}

/// Maximal runs of consecutive edges that join end to start and share their material.
fn runs(edges: &[Edge]) -> Vec<std::ops::Range<usize>> {
    let same = |e: &Edge, f: &Edge| {
        e.b == f.a
            && e.reflectance == f.reflectance
            && e.emission == f.emission
            && e.role == f.role
            && e.two_sided == f.two_sided
    };
    let mut runs = Vec::new();
    let mut start = 0;
    for i in 1..=edges.len() {
        // A run stops where it closes, so a room's loop is one run and the next starts anew.
        let closes = edges[i - 1].b == edges[start].a;
        if i == edges.len() || closes || !same(&edges[i - 1], &edges[i]) {
            runs.push(start..i);
            start = i;
        }
    }
    runs
}

fn size_of(run: &[Edge]) -> f64 {
    let (lo, hi) = run
        .iter()
        .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), e| {
            (lo.min(e.a).min(e.b), hi.max(e.a).max(e.b))
        });
    (hi - lo).length()
}

/// Whether `run` is written as a filled polygon: a closed loop of one-sided surfaces, simple
/// and clockwise (its fill to the right of every edge), judged on the f32 coordinates the
/// importer will see, with no piece short enough to be merged.
fn is_solid(run: &[Edge]) -> bool {
    let first = run[0];
    if run.len() < 3 || first.role != Role::Surface || run[run.len() - 1].b != first.a {
        return false;
    }
    let points: Vec<DVec2> = run.iter().map(|e| e.a.as_vec2().as_dvec2()).collect();
    let distinct = (0..points.len()).all(|i| points[i] != points[(i + 1) % points.len()]);
    let size = size_of(run);
    let ring = Polyline {
        points,
        closed: true,
    };
    distinct
        && run.iter().all(|e| e.length() > SHORT * size)
        && first_contact(std::slice::from_ref(&ring)).is_none()
        && !counter_clockwise(&ring.points)
}

/// `solid` with the runs that hold an edge lying back to back with an edge of another solid
/// written as lines: the importer would remove such a pair as faces hidden inside the fills.
fn without_twins(
    edges: &[Edge],
    runs: &[std::ops::Range<usize>],
    mut solid: Vec<bool>,
) -> Vec<bool> {
    use std::collections::HashMap;
    // On the f32 coordinates the importer sees.
    let key = |a: DVec2, b: DVec2| {
        let (a, b) = (a.as_vec2(), b.as_vec2());
        (a.x.to_bits(), a.y.to_bits(), b.x.to_bits(), b.y.to_bits())
    };
    let mut owner: HashMap<_, usize> = HashMap::new();
    for (r, run) in runs.iter().enumerate().filter(|&(r, _)| solid[r]) {
        for e in &edges[run.clone()] {
            owner.insert(key(e.a, e.b), r);
        }
    }
    for (r, run) in runs.iter().enumerate() {
        if !solid[r] {
            continue;
        }
        for e in &edges[run.clone()] {
            if let Some(&other) = owner.get(&key(e.b, e.a))
                && other != r
            {
                solid[r] = false;
                solid[other] = false;
            }
        }
    }
    solid
}
