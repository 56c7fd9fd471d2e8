//! The lit plan as SVG: each element a stroked segment coloured by its B as it runs along it
//! (a gradient through B at its start, middle and end; its mean in `data-b`), drawn on its
//! front side so both faces of a thin wall show; blockers grey;
//! emitters and point lights marked; a colour bar and a title. [`LitSvg::png`] renders it with
//! resvg, so the PNG is the same picture.
//!
//! The colours come from the caller ([`ColourScale`]): this crate does not own the project's
//! colour map or its scale rule, and draws whatever map it is handed.

use std::fmt::Write as _;

use flatland_geom::{DVec2, EdgeId};

use super::{escape, hex};
use crate::SvgError;

/// The colour map and scale a lit plan is drawn with, supplied by the caller (the project's one
/// colour map and scale rule, so the SVG looks like the viewer).
pub trait ColourScale {
    /// The colour of radiosity `value`.
    fn colour(&self, value: f64) -> [u8; 3];
    /// The colour bar's colour at `x ∈ [0, 1]`, bottom to top.
    fn bar(&self, x: f64) -> [u8; 3];
    /// The bar's labelled marks: where (`x ∈ [0, 1]`, bottom to top) and the label.
    fn ticks(&self) -> Vec<(f64, String)>;
    /// What the bar shows, e.g. `B (log scale)`.
    fn caption(&self) -> String;
}

/// One element of the lit plan: a segment in plan coordinates (front to the left of `a → b`),
/// the scene edge it lies on, its radiosity and its emission.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LitSegment {
    /// The scene edge it lies on (emitters are marked once per edge; written as `data-edge`).
    pub edge: EdgeId,
    /// Start.
    pub a: DVec2,
    /// End.
    pub b: DVec2,
    /// Its radiosity B (its mean, written as `data-b`).
    pub value: f64,
    /// B as it runs along it: at its start, middle and end, drawn as a gradient through the
    /// three colours (one colour when they are the same).
    pub along: [f64; 3],
    /// Its emission E (emitters are marked).
    pub emission: f64,
}

/// What a lit plan shows.
pub struct LitPlan<'a> {
    /// The title, e.g. the scene's name and the solver.
    pub title: &'a str,
    /// The lit elements.
    pub segments: &'a [LitSegment],
    /// Blockers, drawn grey (they have no radiosity).
    pub blockers: &'a [(DVec2, DVec2)],
    /// Point lights, marked.
    pub lights: &'a [DVec2],
    /// The colours.
    pub colours: &'a dyn ColourScale,
}

/// The plan's drawing area in pixels, beside the colour bar.
const PLAN: f64 = 900.0;
/// Margin around the plan, title height and bar panel width, in pixels.
const MARGIN: f64 = 30.0;
const TITLE: f64 = 40.0;
const PANEL: f64 = 150.0;
/// An element's stroke, in pixels.
const STROKE: f64 = 4.0;
/// The shortest segment, in pixels, drawn as a gradient: below it one colour shows the same.
const MIN_GRADIENT_PIXELS: f64 = 3.0;

/// A written lit plan and where plan points land in it.
#[derive(Clone, Debug)]
pub struct LitSvg {
    svg: String,
    scale: f64,
    offset: DVec2,
    size: (u32, u32),
}

impl LitSvg {
    /// The SVG text.
    #[must_use]
    pub fn svg(&self) -> &str {
        &self.svg
    }

    /// The picture's size in pixels.
    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Where plan point `p` is drawn, in pixels (y down).
    #[must_use]
    pub fn to_pixel(&self, p: DVec2) -> DVec2 {
        DVec2::new(
            self.offset.x + self.scale * p.x,
            self.offset.y - self.scale * p.y,
        )
    }

    /// The same picture as PNG: the SVG rendered by resvg.
    pub fn png(&self) -> Result<Vec<u8>, SvgError> {
        crate::render::png(&self.svg)
    }
}

/// Writes `plan` (see the module docs). An empty plan gives a picture with the bar only.
#[must_use]
pub fn lit_svg(plan: &LitPlan<'_>) -> LitSvg {
    let points = plan
        .segments
        .iter()
        .flat_map(|s| [s.a, s.b])
        .chain(plan.blockers.iter().flat_map(|&(a, b)| [a, b]))
        .chain(plan.lights.iter().copied())
        .filter(|p| p.is_finite());
    let (lo, hi) = points.fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    let (lo, hi) = if lo.cmple(hi).all() {
        (lo, hi)
    } else {
        (DVec2::ZERO, DVec2::ONE)
    };
    let span = (hi - lo)
        .max(DVec2::splat((hi - lo).max_element() * 1e-3))
        .max(DVec2::splat(1e-300));
    let scale = PLAN / span.max_element();
    let plan_size = span * scale;
    let height = (TITLE + plan_size.y + 2.0 * MARGIN).max(420.0).ceil();
    let width = (plan_size.x + 2.0 * MARGIN + PANEL).ceil();
    let offset = DVec2::new(MARGIN - scale * lo.x, TITLE + MARGIN + scale * hi.y);
    let picture = LitSvg {
        svg: String::new(),
        scale,
        offset,
        size: (width as u32, height as u32),
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" font-family=\"Ubuntu, sans-serif\">"
    );
    let _ = writeln!(out, "<title>{}</title>", escape(plan.title));
    let _ = writeln!(
        out,
        "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>"
    );
    let _ = writeln!(
        out,
        "<text x=\"{MARGIN}\" y=\"{}\" font-size=\"18\" fill=\"#000000\">{}</text>",
        TITLE - 12.0,
        escape(plan.title)
    );
    write_plan(&mut out, plan, &picture);
    write_bar(
        &mut out,
        plan.colours,
        width - PANEL + 20.0,
        TITLE + MARGIN,
        height - TITLE - 3.0 * MARGIN,
    );
    out.push_str("</svg>\n");
    LitSvg {
        svg: out,
        ..picture
    }
}

/// The segments, blockers and lights, in a group whose transform maps plan units to pixels.
fn write_plan(out: &mut String, plan: &LitPlan<'_>, picture: &LitSvg) {
    let s = picture.scale;
    let _ = writeln!(
        out,
        "<g id=\"plan\" transform=\"matrix({s} 0 0 {} {} {})\" stroke-linecap=\"butt\">",
        -s, picture.offset.x, picture.offset.y
    );
    let width = STROKE / s;
    for (a, b) in plan.blockers {
        let _ = writeln!(
            out,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"#8c8c8c\" stroke-width=\"{}\" class=\"blocker\"/>",
            a.x,
            a.y,
            b.x,
            b.y,
            0.75 * width
        );
    }
    for (k, seg) in plan.segments.iter().enumerate() {
        let d = seg.b - seg.a;
        // A piece of no length or not finite has no front to draw on.
        if d.length().is_nan() || d.length() <= 0.0 || !seg.a.is_finite() || !seg.b.is_finite() {
            continue;
        }
        // On its front side, so the two faces of a thin wall both show.
        let shift = DVec2::new(-d.y, d.x) / d.length() * (width / 2.0);
        let class = if seg.emission > 0.0 {
            " class=\"emitter\""
        } else {
            ""
        };
        if seg.emission > 0.0 {
            // Emitters are brighter than the scale's top: outlined, so they show on white.
            let _ = writeln!(
                out,
                "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" transform=\"translate({} {})\" stroke=\"#000000\" stroke-width=\"{}\"/>",
                seg.a.x,
                seg.a.y,
                seg.b.x,
                seg.b.y,
                shift.x,
                shift.y,
                width + 2.0 / s
            );
        }
        let stroke = write_stroke(out, plan.colours, seg, k, d.length() * s);
        let _ = writeln!(
            out,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" transform=\"translate({} {})\" stroke=\"{stroke}\" stroke-width=\"{width}\" data-b=\"{}\" data-edge=\"{}\"{class}/>",
            seg.a.x,
            seg.a.y,
            seg.b.x,
            seg.b.y,
            shift.x,
            shift.y,
            seg.value,
            seg.edge.index()
        );
    }
    out.push_str("</g>\n");
    write_marks(out, plan, picture);
}

/// The stroke of segment `k`, `pixels` long: its one colour when B along it stays in one or
/// it is too short for a gradient to show (which keeps a plan of 10⁴ edges, mostly elements
/// of a pixel or two, the size of its flat drawing), else a gradient through its three
/// colours along it, written to `out` (in the segment's own user space, so it follows the
/// segment whatever its direction; a bounding-box gradient would vanish on a horizontal or
/// vertical line, whose box has no height or width).
fn write_stroke(
    out: &mut String,
    colours: &dyn ColourScale,
    seg: &LitSegment,
    k: usize,
    pixels: f64,
) -> String {
    let [start, middle, end] = seg.along.map(|v| hex(colours.colour(v)));
    if (start == middle && middle == end) || pixels < MIN_GRADIENT_PIXELS {
        return middle;
    }
    let _ = writeln!(
        out,
        "<linearGradient id=\"b{k}\" gradientUnits=\"userSpaceOnUse\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"><stop offset=\"0\" stop-color=\"{start}\"/><stop offset=\".5\" stop-color=\"{middle}\"/><stop offset=\"1\" stop-color=\"{end}\"/></linearGradient>",
        // Single precision is plenty for where a gradient runs, and a third shorter.
        seg.a.x as f32,
        seg.a.y as f32,
        seg.b.x as f32,
        seg.b.y as f32
    );
    format!("url(#b{k})")
}

/// The emitters' and point lights' marks, in pixels so they keep their size.
fn write_marks(out: &mut String, plan: &LitPlan<'_>, picture: &LitSvg) {
    let s = picture.scale;
    // One per emitting edge, at its middle, in front of it.
    for (start, end, emission) in emitting_edges(plan.segments) {
        let d = end - start;
        if d.length().is_nan() || d.length() <= 0.0 {
            continue;
        }
        let front = DVec2::new(-d.y, d.x) / d.length();
        let at = picture.to_pixel((start + end) * 0.5 + front * (14.0 / s));
        let _ = writeln!(
            out,
            "<circle class=\"emitter-mark\" cx=\"{}\" cy=\"{}\" r=\"5\" fill=\"#ffc800\" stroke=\"#000000\" stroke-width=\"1\"><title>E = {}</title></circle>",
            at.x, at.y, emission
        );
    }
    for &light in plan.lights {
        let p = picture.to_pixel(light);
        let _ = writeln!(
            out,
            "<g class=\"light\" transform=\"translate({} {})\"><circle r=\"7\" fill=\"#ffc800\" stroke=\"#000000\" stroke-width=\"1\"/><path d=\"M-11 0H11M0 -11V11\" stroke=\"#000000\" stroke-width=\"1\"/></g>",
            p.x, p.y
        );
    }
}

/// Each emitting edge's extent (the first of its segments' starts to the last's end) and
/// emission, in the order the segments list them.
fn emitting_edges(segments: &[LitSegment]) -> Vec<(DVec2, DVec2, f64)> {
    let mut out: Vec<(EdgeId, DVec2, DVec2, f64)> = Vec::new();
    for seg in segments.iter().filter(|s| s.emission > 0.0) {
        match out.iter_mut().find(|(edge, ..)| *edge == seg.edge) {
            Some(found) => found.2 = seg.b,
            None => out.push((seg.edge, seg.a, seg.b, seg.emission)),
        }
    }
    out.into_iter().map(|(_, a, b, e)| (a, b, e)).collect()
}

/// The colour bar at `x`, from `top` down `length` pixels, with its marks and caption.
fn write_bar(out: &mut String, colours: &dyn ColourScale, x: f64, top: f64, length: f64) {
    const STOPS: usize = 33;
    out.push_str("<defs><linearGradient id=\"bar\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">");
    for k in 0..STOPS {
        let t = k as f64 / (STOPS - 1) as f64;
        let _ = write!(
            out,
            "<stop offset=\"{t}\" stop-color=\"{}\"/>",
            hex(colours.bar(t))
        );
    }
    out.push_str("</linearGradient></defs>\n");
    let _ = writeln!(
        out,
        "<g id=\"colour-bar\"><text x=\"{x}\" y=\"{}\" font-size=\"14\" fill=\"#000000\">{}</text>",
        top - 8.0,
        escape(&colours.caption())
    );
    let _ = writeln!(
        out,
        "<rect x=\"{x}\" y=\"{top}\" width=\"24\" height=\"{length}\" fill=\"url(#bar)\" stroke=\"#000000\" stroke-width=\"1\"/>"
    );
    for (at, label) in colours.ticks() {
        let y = top + (1.0 - at.clamp(0.0, 1.0)) * length;
        let _ = writeln!(
            out,
            "<path d=\"M{} {y}h6\" stroke=\"#000000\"/><text x=\"{}\" y=\"{}\" font-size=\"13\" fill=\"#000000\">{}</text>",
            x + 24.0,
            x + 34.0,
            y + 4.5,
            escape(&label)
        );
    }
    out.push_str("</g>\n");
}
