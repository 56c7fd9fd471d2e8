//! A scene's edges: by role, or each element in the colour of its radiosity with a colour bar
//! (the lit scenes); front-side ticks and surface indices only where they have
//! room, so a scene of a thousand edges is drawn as lines, not as a smear of labels.

use std::collections::HashSet;
use std::hash::{BuildHasher, Hasher};

use egui::{Align2, Color32, FontId, Painter, Rect, Stroke, pos2, vec2};
use flatland_geom::{Role, Scene};
use flatland_pictures::colormap::Scale;
use flatland_solve::Mesh;

use super::lit_pieces::{MIN_PIECE, end_values, pieces};
use super::raster::Canvas;
use super::raster::{EdgesTexture, Pen};
use super::widgets::{View, gradient, short};
use super::{BLOCKER, EMITTER, LIT_BLOCKER, SURFACE, TITLE_H};
use crate::colormap::colour;

/// Width of the colour bar beside a lit scene, labels included.
pub(super) const COLOUR_BAR_W: f32 = 58.0;
/// Height of the scene view's line under the title (the hovered ray's k).
pub(super) const INFO_H: f32 = 12.0;
/// Width of a lit element, in points.
const LIT_WIDTH: f32 = 5.0;
/// An edge shorter than this on screen gets no front-side tick.
const MIN_TICKED: f32 = 8.0;
/// An edge shorter than this on screen gets no index.
const MIN_LABELLED: f32 = 18.0;
/// Cells of the grid labels are placed on: one label per cell at most.
const LABEL_CELL: [f32; 2] = [18.0, 12.0];

/// The scene view's colours, for its legend.
pub(super) const LEGEND: [(&str, Color32); 3] = [
    ("emitter", EMITTER),
    ("surface", SURFACE),
    ("blocker", BLOCKER),
];
/// The lit scene's legend (surfaces are coloured by B).
pub(super) const LIT_LEGEND: [(&str, Color32); 2] =
    [("• emitter", EMITTER), ("blocker", LIT_BLOCKER)];

/// A scene's edges coloured by a radiosity: `b` per element of `mesh`, on a linear scale from
/// 0 to `top` or a logarithmic one of [`flatland_pictures::colormap::LOG_DECADES`] below it
/// (emitters, brighter, are drawn at the top colour and marked).
#[derive(Clone, Copy, Debug)]
pub struct LitPaint<'a> {
    /// The elements.
    pub mesh: &'a Mesh,
    /// B per element.
    pub b: &'a [f64],
    /// The value drawn in the top colour (the exposure moves it).
    pub top: f64,
    /// A logarithmic tone scale instead of a linear one.
    pub log: bool,
}

impl LitPaint<'_> {
    fn scale(&self) -> Scale {
        Scale {
            top: self.top,
            log: self.log,
        }
    }

    pub(super) fn color(&self, b: f64) -> Color32 {
        colour(self.scale().unit(b))
    }
}

/// Where a scene is drawn inside its panel `rect`: below the title, clear of the border, and
/// left of the colour bar when it is lit.
pub(super) fn scene_area(rect: Rect, lit: bool) -> Rect {
    let right = if lit { COLOUR_BAR_W } else { 18.0 };
    Rect::from_min_max(
        rect.min + vec2(18.0, TITLE_H + INFO_H + 6.0),
        rect.max - vec2(right, 16.0),
    )
}

/// Every edge of `scene`: by role, or (with `lit`) each element in the colour of its B,
/// emitters marked with a sun on their front side; front-side ticks and surface indices where
/// there is room for them. The lines go to `pen`, the indices to `painter`.
pub(super) fn draw_edges(
    pen: &mut impl Pen,
    painter: &Painter,
    view: &View,
    scene: &Scene,
    lit: Option<&LitPaint<'_>>,
    weak: Color32,
) {
    draw_lines(pen, view, scene, lit, true);
    draw_labels(painter, view, scene, lit.is_some(), weak);
}

/// [`draw_edges`] rastered into `texture` over `rect` in two layers: the lit elements (again
/// when B, its scale, the scene or the panel changed: [`draw_lit`]) under the other lines
/// (again only when the scene or the panel changed). A new B rasters only its elements.
pub(super) fn draw_edges_once(
    texture: &mut EdgesTexture,
    painter: &Painter,
    rect: Rect,
    view: &View,
    scene: &Scene,
    lit: Option<&LitPaint<'_>>,
    weak: Color32,
) {
    if let Some(lit) = lit {
        let key = fingerprint(
            lit.b
                .iter()
                .map(|b| b.to_bits())
                .chain([lit.top.to_bits(), u64::from(lit.log)]),
        );
        texture.paint_lit(painter, rect, [scene_fingerprint(scene), key], |canvas| {
            draw_lit(canvas, view, lit);
        });
    }
    texture.paint(
        painter,
        rect,
        [scene_fingerprint(scene), u64::from(lit.is_some())],
        |canvas| {
            draw_lines(canvas, view, scene, lit, false);
        },
    );
    draw_labels(painter, view, scene, lit.is_some(), weak);
}

/// The lit elements as B along them, a function, not flat steps: pieces of at least
/// [`MIN_PIECE`] points ([`pieces`]), each from its start to its middle and on to its end,
/// coloured by B there ([`end_values`]: linear between the middles along an edge).
fn draw_lit(canvas: &mut Canvas, view: &View, lit: &LitPaint<'_>) {
    let pieces = pieces(view, lit.mesh, lit.b, MIN_PIECE);
    for (p, [start, end]) in pieces.iter().zip(end_values(&pieces)) {
        let (m, mid) = (p.a + (p.b - p.a) * 0.5, lit.color(p.value));
        canvas.span_line(p.a, m, [lit.color(start), mid], LIT_WIDTH);
        canvas.span_line(m, p.b, [mid, lit.color(end)], LIT_WIDTH);
    }
}

/// The lines of [`draw_edges`]: lit elements (unless `elements` is false: drawn as a mesh),
/// edges, front-side ticks, emitters' suns.
fn draw_lines(
    pen: &mut impl Pen,
    view: &View,
    scene: &Scene,
    lit: Option<&LitPaint<'_>>,
    elements: bool,
) {
    if let Some(lit) = lit.filter(|_| elements) {
        for (el, &b) in lit.mesh.elements().iter().zip(lit.b) {
            pen.line(
                view.screen(el.a),
                view.screen(el.b),
                Stroke::new(LIT_WIDTH, lit.color(b)),
            );
        }
    }
    for e in scene.edges() {
        let (color, width) = match (e.role, lit.is_some()) {
            (Role::Blocker, false) => (BLOCKER, 3.0),
            (Role::Blocker, true) => (LIT_BLOCKER, 3.0),
            (Role::Surface, true) => (Color32::from_gray(150), 0.0),
            (Role::Surface, false) if e.emission > 0.0 => (EMITTER, 4.0),
            (Role::Surface, false) => (SURFACE, 2.0),
        };
        let (a, b) = (view.screen(e.a), view.screen(e.b));
        if width > 0.0 {
            pen.line(a, b, Stroke::new(width, color));
        }
        let length = a.distance(b);
        let n = screen_normal(e);
        if length >= MIN_TICKED {
            let ticks = ((length / 22.0) as usize).clamp(1, 16);
            let tick = Stroke::new(1.0, color.gamma_multiply(0.8));
            for k in 0..ticks {
                let p = a + (b - a) * ((k as f32 + 0.5) / ticks as f32);
                pen.line(p, p + n * 6.0, tick);
                if e.two_sided {
                    pen.line(p, p - n * 6.0, tick);
                }
            }
        }
        if lit.is_some() && e.role == Role::Surface && e.emission > 0.0 && length >= MIN_TICKED {
            // Small, and only on edges long enough to tick: a big plan's emitters are many, and
            // their marks would cover the rooms they light.
            let sun = a + (b - a) * 0.5 + n * 7.0;
            pen.disc(sun, 3.0, EMITTER);
            pen.ring(sun, 3.0, Stroke::new(0.8, Color32::BLACK));
        }
    }
}

/// The surface edges' indices of [`draw_edges`], where they have room (not on a lit
/// emitter, which has its sun there).
fn draw_labels(painter: &Painter, view: &View, scene: &Scene, lit: bool, weak: Color32) {
    let mut labels = LabelGrid::default();
    for (i, e) in scene.edges().iter().enumerate() {
        if e.role != Role::Surface || (lit && e.emission > 0.0) {
            continue;
        }
        let (a, b) = (view.screen(e.a), view.screen(e.b));
        let mid = a + (b - a) * 0.5 + screen_normal(e) * 13.0;
        if a.distance(b) >= MIN_LABELLED && labels.take(mid) {
            painter.text(
                mid,
                Align2::CENTER_CENTER,
                i.to_string(),
                FontId::proportional(10.0),
                weak,
            );
        }
    }
}

/// An edge's front-side normal on screen (y down).
fn screen_normal(e: &flatland_geom::Edge) -> egui::Vec2 {
    let n = e.normal();
    vec2(n.x as f32, -n.y as f32)
}

/// A hash of `words` (foldhash, fixed seed): a texture's key.
fn fingerprint(words: impl IntoIterator<Item = u64>) -> u64 {
    let mut hasher = foldhash::fast::FixedState::with_seed(0).build_hasher();
    for word in words {
        hasher.write_u64(word);
    }
    hasher.finish()
}

/// [`fingerprint`] of what a scene's lines depend on: each edge's ends, role, emission and
/// sides.
fn scene_fingerprint(scene: &Scene) -> u64 {
    fingerprint(scene.edges().iter().flat_map(|e| {
        [
            e.a.x.to_bits(),
            e.a.y.to_bits(),
            e.b.x.to_bits(),
            e.b.y.to_bits(),
            e.emission.to_bits(),
            u64::from(e.role == Role::Blocker) | u64::from(e.two_sided) << 1,
        ]
    }))
}

/// The cells of a coarse screen grid that hold a label already.
#[derive(Default)]
struct LabelGrid(HashSet<(i32, i32)>);

impl LabelGrid {
    /// Whether a label at `p` is free of the others (and then takes its cell).
    fn take(&mut self, p: egui::Pos2) -> bool {
        let cell = (
            (p.x / LABEL_CELL[0]).floor() as i32,
            (p.y / LABEL_CELL[1]).floor() as i32,
        );
        let near = (-1..=1).any(|dx| self.0.contains(&(cell.0 + dx, cell.1)));
        !near && self.0.insert(cell)
    }
}

/// A vertical colour bar at the right of `rect` for `lit`'s scale: its bottom value at the
/// bottom (0, or `top` × 10^−decades on a log scale), `top` at the top.
pub(super) fn colour_bar(painter: &Painter, rect: Rect, lit: &LitPaint<'_>, text: Color32) {
    let scale = lit.scale();
    let bar = Rect::from_min_max(
        pos2(
            rect.right() - COLOUR_BAR_W + 10.0,
            rect.top() + TITLE_H + 22.0,
        ),
        pos2(rect.right() - COLOUR_BAR_W + 22.0, rect.bottom() - 34.0),
    );
    if bar.height() < 20.0 {
        return;
    }
    gradient(painter, bar, 48, text);
    let font = FontId::proportional(10.0);
    painter.text(
        bar.center_top() - vec2(0.0, 3.0),
        Align2::CENTER_BOTTOM,
        "B",
        FontId::proportional(12.0),
        text,
    );
    painter.text(
        bar.right_top() + vec2(3.0, 0.0),
        Align2::LEFT_TOP,
        short(scale.top),
        font.clone(),
        text,
    );
    painter.text(
        bar.right_bottom() + vec2(3.0, 0.0),
        Align2::LEFT_BOTTOM,
        if scale.log {
            short(scale.value_at(0.0))
        } else {
            "0".to_owned()
        },
        font.clone(),
        text,
    );
    painter.text(
        bar.center_bottom() + vec2(0.0, 4.0),
        Align2::CENTER_TOP,
        "emitters\nabove",
        font,
        text,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_keep_their_distance() {
        let mut grid = LabelGrid::default();
        assert!(grid.take(pos2(100.0, 100.0)));
        assert!(!grid.take(pos2(104.0, 101.0)), "the same cell");
        assert!(
            !grid.take(pos2(118.0, 100.0)),
            "the next cell along the line"
        );
        assert!(grid.take(pos2(140.0, 100.0)));
        assert!(grid.take(pos2(100.0, 115.0)), "the next row");
    }
}
