//! Drawing: the (s, t) plots with their overlay, the scene view, the learning curves.
//! Functions of what they show plus a little interaction state; nothing here trains or waits.

use std::f32::consts::FRAC_PI_2;
#[cfg(test)]
use std::sync::Arc;

use egui::{
    Align2, Color32, ColorImage, FontId, Painter, Pos2, Rect, Sense, Shape, Stroke, TextureId,
    Vec2, epaint::TextShape, pos2, vec2,
};
use egui_plot::{Legend, Line, LineStyle, Plot, PlotPoints, Polygon};
use flatland_geom::{DVec2, GeomError, Role, Scene};
use flatland_solve::Mesh;
use kernel_fit::Snapshot;

use flatland_lab::colormap::Scale;

use crate::colormap::colour;
use crate::lit::LitPoint;
use crate::worker::{Lit, World};

/// Height of a panel's title line.
pub const TITLE_H: f32 = 18.0;
/// Height of the scene view's line under the title (the hovered ray's k).
const INFO_H: f32 = 12.0;

const CELL: Color32 = Color32::from_rgb(245, 245, 245);
const CRITICAL: Color32 = Color32::from_rgb(40, 230, 255);
const NET_EDGE: Color32 = Color32::from_rgba_premultiplied(120, 120, 120, 120);
const BOUNDARY: Color32 = Color32::from_rgba_premultiplied(90, 90, 90, 90);
const SCENE_MARK: Color32 = Color32::from_rgb(120, 255, 140);
const EMITTER: Color32 = Color32::from_rgb(255, 210, 60);
const SURFACE: Color32 = Color32::from_rgb(190, 190, 195);
const BLOCKER: Color32 = Color32::from_rgb(235, 80, 70);
/// Blockers in a lit scene: out of the colour map's range, so never read as a radiosity.
const LIT_BLOCKER: Color32 = Color32::from_rgb(110, 150, 210);
/// Width of the colour bar beside the big kernel plot, labels included.
const HEAT_BAR_W: f32 = 56.0;
/// Width of the colour bar beside a lit scene, labels included.
const COLOUR_BAR_W: f32 = 58.0;

/// The scene view's colours, for its legend.
const LEGEND: [(&str, Color32); 3] = [
    ("emitter", EMITTER),
    ("surface", SURFACE),
    ("blocker", BLOCKER),
];
/// The lit scene's legend (surfaces are coloured by B).
const LIT_LEGEND: [(&str, Color32); 2] = [("• emitter", EMITTER), ("blocker", LIT_BLOCKER)];

/// What the pointer is over, shared between the panels (one frame late for the other panels).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hover {
    /// `(s, t)` under the pointer in one of the plots.
    pub st: Option<[f64; 2]>,
    /// The parameter of the scene point under the pointer.
    pub scene_s: Option<f64>,
}

/// An end point being dragged in the scene view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneDrag {
    /// Where it was.
    pub from: DVec2,
    /// Where it is now.
    pub to: DVec2,
}

/// Where the unit square of `(s, t)` sits on screen: `t` to the right, `s` upwards.
#[derive(Clone, Copy, Debug)]
pub struct PlotFrame {
    /// The whole panel (title, axes, plot).
    pub outer: Rect,
    /// The square the unit square maps to.
    pub plot: Rect,
    /// Whether axis titles, edge labels and a colour bar are drawn.
    pub big: bool,
    /// The colour scale, for the colour bar of a big frame.
    pub scale: Option<Scale>,
}

impl PlotFrame {
    /// Fits the square plot into `outer`, leaving room for a title and (if `big`) axis labels.
    #[must_use]
    pub fn new(outer: Rect, big: bool) -> PlotFrame {
        let (left, bottom, right) = if big {
            (34.0, 30.0, HEAT_BAR_W)
        } else {
            (4.0, 4.0, 2.0)
        };
        let avail = Rect::from_min_max(
            outer.min + vec2(left, TITLE_H),
            outer.max - vec2(right, bottom),
        );
        let side = avail.width().min(avail.height()).max(8.0);
        PlotFrame {
            outer,
            plot: Rect::from_min_size(avail.min, Vec2::splat(side)),
            big,
            scale: None,
        }
    }

    /// Screen position of `(s, t)`.
    #[must_use]
    pub fn screen(&self, s: f64, t: f64) -> Pos2 {
        pos2(
            self.plot.left() + t as f32 * self.plot.width(),
            self.plot.bottom() - s as f32 * self.plot.height(),
        )
    }

    /// `[s, t]` at a screen position inside the plot.
    #[must_use]
    pub fn at(&self, p: Pos2) -> Option<[f64; 2]> {
        self.plot.contains(p).then(|| {
            let t = f64::from((p.x - self.plot.left()) / self.plot.width());
            let s = f64::from((self.plot.bottom() - p.y) / self.plot.height());
            [s.clamp(0.0, 0.999_999), t.clamp(0.0, 0.999_999)]
        })
    }
}

/// What is drawn over a heatmap.
pub struct Overlay {
    /// The cells and network edges, prebuilt by [`overlay_image`].
    pub cells: Option<TextureId>,
    /// The samples texture, if shown.
    pub samples: Option<TextureId>,
}

impl Overlay {
    /// Nothing over the heatmap.
    #[must_use]
    pub fn none() -> Overlay {
        Overlay {
            cells: None,
            samples: None,
        }
    }
}

/// The network's edges and its cells (discs sized by δ_c, cyan when critical, black rim) drawn
/// into a transparent `side × side` image (one pixel per screen pixel of the plot, `s` upwards).
///
/// Built on the CPU only when a new snapshot arrives; a frame then draws one textured square
/// instead of ~25 000 triangles, which is what keeps software GL fast with 1000 cells.
/// `px_per_point` scales the disc sizes with the display's pixel density.
#[must_use]
pub fn overlay_image(
    side: usize,
    px_per_point: f32,
    snap: &Snapshot,
    cells: bool,
    edges: bool,
) -> ColorImage {
    let mut img = ColorImage::filled([side, side], Color32::TRANSPARENT);
    let n = side as f32;
    let pos: Vec<Option<[f32; 2]>> = snap
        .cells
        .iter()
        .map(|c| c.st.map(|[s, t]| [t as f32 * n, (1.0 - s as f32) * n]))
        .collect();
    if edges {
        for &[a, b] in &snap.edges {
            if let (Some(Some(pa)), Some(Some(pb))) = (pos.get(a as usize), pos.get(b as usize)) {
                draw_line(&mut img, *pa, *pb, NET_EDGE);
            }
        }
    }
    if cells {
        for (c, p) in snap.cells.iter().zip(&pos) {
            let Some(p) = p else { continue };
            // δ_c lives in the 4-D input frame, not in (s, t): the size is a relative cue.
            let r = (c.width as f32 * n / px_per_point * 0.06).clamp(1.5, 6.0) * px_per_point;
            let fill = if c.critical { CRITICAL } else { CELL };
            draw_disc(&mut img, *p, r, fill, px_per_point);
        }
    }
    img
}

/// `src` over `dst`, both premultiplied.
fn blend(dst: Color32, src: Color32) -> Color32 {
    let k = u16::from(255 - src.a());
    let mix = |s: u8, d: u8| s.saturating_add(((u16::from(d) * k + 127) / 255) as u8);
    Color32::from_rgba_premultiplied(
        mix(src.r(), dst.r()),
        mix(src.g(), dst.g()),
        mix(src.b(), dst.b()),
        mix(src.a(), dst.a()),
    )
}

fn draw_line(img: &mut ColorImage, a: [f32; 2], b: [f32; 2], color: Color32) {
    let [w, h] = img.size;
    let steps = (b[0] - a[0]).abs().max((b[1] - a[1]).abs()).ceil().max(1.0) as usize;
    for k in 0..=steps {
        let u = k as f32 / steps as f32;
        let x = (a[0] + (b[0] - a[0]) * u) as usize;
        let y = (a[1] + (b[1] - a[1]) * u) as usize;
        if x < w && y < h {
            let px = &mut img.pixels[y * w + x];
            *px = blend(*px, color);
        }
    }
}

fn draw_disc(img: &mut ColorImage, c: [f32; 2], r: f32, fill: Color32, rim: f32) {
    let [w, h] = img.size;
    let outer = r + rim;
    let (x0, x1) = (
        (c[0] - outer).floor().max(0.0) as usize,
        ((c[0] + outer).ceil() as usize).min(w),
    );
    let (y0, y1) = (
        (c[1] - outer).floor().max(0.0) as usize,
        ((c[1] + outer).ceil() as usize).min(h),
    );
    for y in y0..y1 {
        for x in x0..x1 {
            let d = ((x as f32 + 0.5 - c[0]).powi(2) + (y as f32 + 0.5 - c[1]).powi(2)).sqrt();
            if d <= r {
                img.pixels[y * w + x] = fill;
            } else if d <= outer {
                img.pixels[y * w + x] = Color32::BLACK;
            }
        }
    }
}

fn uv() -> Rect {
    Rect::from_min_max(Pos2::ZERO, pos2(1.0, 1.0))
}

/// One (s, t) panel: heatmap, edge boundaries, overlay, hover marks. Returns `(s, t)` under
/// the pointer.
pub fn kernel_plot(
    ui: &mut egui::Ui,
    frame: &PlotFrame,
    title: &str,
    heatmap: Option<TextureId>,
    scene: &Scene,
    overlay: &Overlay,
    hover: &Hover,
) -> Option<[f64; 2]> {
    let response = ui.allocate_rect(frame.plot, Sense::hover());
    let painter = ui.painter_at(frame.outer.expand(2.0));
    let plot = frame.plot;
    let text = ui.visuals().text_color();
    let weak = ui.visuals().weak_text_color();
    painter.text(
        pos2(plot.left(), frame.outer.top()),
        Align2::LEFT_TOP,
        title,
        FontId::proportional(13.0),
        text,
    );
    painter.rect_filled(plot, 0.0, Color32::BLACK);
    match heatmap {
        Some(tex) => {
            painter.image(tex, plot, uv(), Color32::WHITE);
        }
        None => {
            painter.text(
                plot.center(),
                Align2::CENTER_CENTER,
                "…",
                FontId::proportional(14.0),
                weak,
            );
        }
    }

    // Edge boundaries on both axes, labelled with the edge index when there is room.
    let label_font = FontId::proportional(10.0);
    for &e in scene.surface_edges() {
        let Some((s0, s1)) = scene.edge_param_range(e) else {
            continue;
        };
        if s0 > 0.0 {
            let p = frame.screen(s0, s0);
            painter.vline(p.x, plot.y_range(), Stroke::new(1.0, BOUNDARY));
            painter.hline(plot.x_range(), p.y, Stroke::new(1.0, BOUNDARY));
            painter.vline(
                p.x,
                plot.bottom()..=plot.bottom() + 5.0,
                Stroke::new(1.0, weak),
            );
            painter.hline(plot.left() - 5.0..=plot.left(), p.y, Stroke::new(1.0, weak));
        }
        let mid = frame.screen((s0 + s1) / 2.0, (s0 + s1) / 2.0);
        if frame.big && (s1 - s0) as f32 * plot.width() >= 12.0 {
            painter.text(
                pos2(mid.x, plot.bottom() + 2.0),
                Align2::CENTER_TOP,
                e.to_string(),
                label_font.clone(),
                weak,
            );
            painter.text(
                pos2(plot.left() - 3.0, mid.y),
                Align2::RIGHT_CENTER,
                e.to_string(),
                label_font.clone(),
                weak,
            );
        }
    }
    if frame.big {
        painter.text(
            pos2(plot.center().x, plot.bottom() + 14.0),
            Align2::CENTER_TOP,
            "t (receiver edge)",
            FontId::proportional(12.0),
            weak,
        );
        let galley =
            painter.layout_no_wrap("s (sender edge)".into(), FontId::proportional(12.0), weak);
        let pos = pos2(frame.outer.left(), plot.center().y + galley.size().x / 2.0);
        painter.add(TextShape::new(pos, galley, weak).with_angle(-FRAC_PI_2));
    }

    if let (true, Some(scale)) = (frame.big, frame.scale) {
        scale_bar(&painter, frame, scale, weak);
    }
    if let Some(tex) = overlay.samples {
        painter.image(tex, plot, uv(), Color32::WHITE);
    }
    if let Some(tex) = overlay.cells {
        painter.image(tex, plot, uv(), Color32::WHITE);
    }

    if let Some([s, t]) = hover.st {
        let p = frame.screen(s, t);
        let stroke = Stroke::new(1.0, Color32::from_white_alpha(200));
        painter.hline(plot.x_range(), p.y, stroke);
        painter.vline(p.x, plot.y_range(), stroke);
    }
    if let Some(s) = hover.scene_s {
        let p = frame.screen(s, s);
        let stroke = Stroke::new(1.5, SCENE_MARK);
        painter.hline(plot.x_range(), p.y, stroke);
        painter.vline(p.x, plot.y_range(), stroke);
    }
    response.hover_pos().and_then(|p| frame.at(p))
}

/// The read-out under the pointer: a small box beside it, on the side away from the nearer
/// screen edge (drawn as an area, not a tooltip: it shows at once and follows the pointer).
pub fn readout_box(ctx: &egui::Context, pointer: Pos2, text: &str) {
    let screen = ctx.content_rect();
    let right = pointer.x > screen.center().x;
    let below = pointer.y < screen.center().y;
    let pivot = match (right, below) {
        (false, true) => Align2::LEFT_TOP,
        (false, false) => Align2::LEFT_BOTTOM,
        (true, true) => Align2::RIGHT_TOP,
        (true, false) => Align2::RIGHT_BOTTOM,
    };
    let offset = vec2(
        if right { -16.0 } else { 16.0 },
        if below { 16.0 } else { -16.0 },
    );
    egui::Area::new(egui::Id::unique("flatland-readout"))
        .order(egui::Order::Tooltip)
        .pivot(pivot)
        .fixed_pos(pointer + offset)
        .interactable(false)
        .show(ctx, |ui| {
            egui::Frame::popup(ui.style()).show(ui, |ui| {
                ui.label(egui::RichText::new(text).monospace().size(11.5));
            });
        });
}

/// What the scene view reports back.
#[derive(Clone, Copy, Debug, Default)]
pub struct SceneOut {
    /// The parameter of the surface point under the pointer.
    pub hovered_s: Option<f64>,
    /// A finished drag: from, to.
    pub moved: Option<(DVec2, DVec2)>,
}

/// The scene `scene` with every end point equal to `from` moved to `to`, edge by edge through
/// [`Scene::with_edge`] (so each step is validated).
pub fn moved_scene(scene: &Scene, from: DVec2, to: DVec2) -> Result<Scene, GeomError> {
    let mut out = scene.clone();
    for (i, e) in scene.edges().iter().enumerate() {
        let mut moved = *e;
        if e.a == from {
            moved.a = to;
        }
        if e.b == from {
            moved.b = to;
        }
        if moved != *e {
            out = out.with_edge(i, moved)?;
        }
    }
    Ok(out)
}

struct View {
    centre: Pos2,
    mid: DVec2,
    scale: f64,
}

impl View {
    fn of(scene: &Scene, rect: Rect) -> View {
        let (lo, hi) = scene.bounds();
        let size = (hi - lo).max(DVec2::splat(1e-9));
        let scale = (f64::from(rect.width()) / size.x).min(f64::from(rect.height()) / size.y);
        View {
            centre: rect.center(),
            mid: (lo + hi) / 2.0,
            scale,
        }
    }
    fn screen(&self, p: DVec2) -> Pos2 {
        let d = (p - self.mid) * self.scale;
        self.centre + vec2(d.x as f32, -d.y as f32)
    }
    fn at(&self, q: Pos2) -> DVec2 {
        let d = q - self.centre;
        self.mid + DVec2::new(f64::from(d.x), -f64::from(d.y)) / self.scale
    }
}

/// A scene's edges coloured by a radiosity: `b` per element of `mesh`, on a linear scale from
/// 0 to `top` (emitters, brighter, are drawn at the top colour and marked).
#[derive(Clone, Copy, Debug)]
pub struct LitPaint<'a> {
    /// The elements.
    pub mesh: &'a Mesh,
    /// B per element.
    pub b: &'a [f64],
    /// The value drawn in the top colour.
    pub top: f64,
}

impl LitPaint<'_> {
    fn color(&self, b: f64) -> Color32 {
        colour(b / self.top)
    }
}

/// The colour map drawn upwards in `bar` (0 at the bottom, 1 at the top) in `steps` slices,
/// outlined in `text`.
fn gradient(painter: &Painter, bar: Rect, steps: usize, text: Color32) {
    for k in 0..steps {
        let (u0, u1) = (k as f32 / steps as f32, (k + 1) as f32 / steps as f32);
        let slice = Rect::from_min_max(
            pos2(bar.left(), bar.bottom() - u1 * bar.height()),
            pos2(bar.right(), bar.bottom() - u0 * bar.height() + 0.5),
        );
        painter.rect_filled(slice, 0.0, colour(f64::from((u0 + u1) / 2.0)));
    }
    painter.rect_stroke(bar, 0.0, Stroke::new(1.0, text), egui::StrokeKind::Outside);
}

/// The heatmaps' colour bar, right of `frame`'s plot: the scale's values at its ticks (each
/// decade of a log scale; 0, half and the top of a linear one). The learned and error panels
/// share the scale.
fn scale_bar(painter: &Painter, frame: &PlotFrame, scale: Scale, text: Color32) {
    let plot = frame.plot;
    let bar = Rect::from_min_max(
        pos2(plot.right() + 8.0, plot.top() + 14.0),
        pos2(plot.right() + 20.0, plot.bottom()),
    );
    gradient(painter, bar, 64, text);
    painter.text(
        bar.center_top() - vec2(0.0, 2.0),
        Align2::CENTER_BOTTOM,
        "ζ",
        FontId::proportional(12.0),
        text,
    );
    let ticks: Vec<f64> = if scale.log {
        let decades = flatland_lab::colormap::LOG_DECADES;
        (0..=decades as usize).map(|d| d as f64 / decades).collect()
    } else {
        vec![0.0, 0.5, 1.0]
    };
    for x in ticks {
        let y = bar.bottom() - x as f32 * bar.height();
        painter.hline(bar.right()..=bar.right() + 3.0, y, Stroke::new(1.0, text));
        let label = if scale.log && x == 0.0 {
            format!("≤{}", short(scale.value_at(x)))
        } else {
            short(scale.value_at(x))
        };
        painter.text(
            pos2(bar.right() + 4.0, y),
            Align2::LEFT_CENTER,
            label,
            FontId::proportional(10.0),
            text,
        );
    }
}

/// Where a scene is drawn inside its panel `rect`: below the title, clear of the border, and
/// left of the colour bar when it is lit.
fn scene_area(rect: Rect, lit: bool) -> Rect {
    let right = if lit { COLOUR_BAR_W } else { 18.0 };
    Rect::from_min_max(
        rect.min + vec2(18.0, TITLE_H + INFO_H + 6.0),
        rect.max - vec2(right, 16.0),
    )
}

/// Where and what the scene view draws besides the scene itself.
pub struct SceneFrame<'a> {
    /// The panel.
    pub rect: Rect,
    /// Its title.
    pub title: &'a str,
    /// The kernel of the scene the references were made for (the hovered ray).
    pub world: &'a World,
    /// The radiosity to colour the edges by, if any.
    pub lit: Option<&'a LitPaint<'a>>,
}

/// The scene: edges by role (emitters yellow, surfaces grey, blockers red) or, with `lit`, each
/// element in the colour of its B (emitters marked, blockers blue) with a colour bar;
/// front-side ticks, surface edge indices, draggable end points; the hovered ray `x(s) → y(t)`.
pub fn scene_view(
    ui: &mut egui::Ui,
    frame: &SceneFrame<'_>,
    scene: &Scene,
    hover: &Hover,
    drag: &mut Option<SceneDrag>,
) -> SceneOut {
    let rect = frame.rect;
    let response = ui.allocate_rect(rect, Sense::click_and_drag());
    let painter = ui.painter_at(rect);
    let weak = ui.visuals().weak_text_color();
    // A dragged end point changes the scene: the solved B belongs to the old one.
    let lit = frame.lit.filter(|_| drag.is_none());
    panel_frame(&painter, rect, frame.title, ui.visuals().text_color());
    let view = View::of(scene, scene_area(rect, lit.is_some()));
    let ends = EndPoints::of(scene);
    let mut out = SceneOut {
        moved: follow_drag(ui, &response, &view, &ends, drag),
        hovered_s: None,
    };
    let preview;
    let shown = match drag {
        Some(d) => {
            preview = moved_scene(scene, d.from, d.to).ok();
            preview.as_ref().unwrap_or(scene)
        }
        None => scene,
    };

    draw_edges(&painter, &view, shown, lit, weak);
    if let Some(lit) = lit {
        colour_bar(&painter, rect, lit.top, weak);
    }
    let x = legend(
        &painter,
        rect,
        if lit.is_some() { &LIT_LEGEND } else { &LEGEND },
    );
    painter.text(
        pos2(x, rect.bottom() - 3.0),
        Align2::LEFT_BOTTOM,
        format!(
            "· {} edges, L = {:.3}{}",
            scene.edges().len(),
            scene.total_length(),
            // Lit, the colour bar's labels take the bottom right.
            if lit.is_some() {
                ""
            } else {
                " · drag an end point to edit"
            }
        ),
        FontId::proportional(10.0),
        weak,
    );
    let pointer = response.hover_pos();
    let hovered_end = pointer.and_then(|q| ends.nearest(&view, q));
    ends.draw(&painter, &view, hovered_end, *drag);
    if hovered_end.is_some() || drag.is_some() {
        ui.ctx().set_cursor_icon(egui::CursorIcon::Grab);
    }
    if let Some([s, t]) = hover.st {
        draw_ray(&painter, &view, rect, frame.world, s, t);
    }
    if drag.is_none()
        && hovered_end.is_none()
        && let Some(q) = pointer
    {
        out.hovered_s = mark_hovered_surface(&painter, &view, scene, q);
    }
    out
}

/// The end points of a scene's edges, which the user can drag.
struct EndPoints(Vec<DVec2>);

impl EndPoints {
    fn of(scene: &Scene) -> EndPoints {
        let mut v: Vec<DVec2> = scene.edges().iter().flat_map(|e| [e.a, e.b]).collect();
        v.dedup();
        EndPoints(v)
    }

    /// The end point within 9 points of `q` on screen, the nearest if several.
    fn nearest(&self, view: &View, q: Pos2) -> Option<DVec2> {
        self.0
            .iter()
            .map(|&p| (p, view.screen(p).distance(q)))
            .filter(|(_, d)| *d <= 9.0)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(p, _)| p)
    }

    /// Dots; the hovered or dragged one big and white, the dragged one where it is dragged to.
    fn draw(
        &self,
        painter: &Painter,
        view: &View,
        hovered: Option<DVec2>,
        drag: Option<SceneDrag>,
    ) {
        for p in &self.0 {
            let hot = hovered == Some(*p) || drag.is_some_and(|d| d.from == *p);
            let at = match drag {
                Some(d) if d.from == *p => view.screen(d.to),
                _ => view.screen(*p),
            };
            let (r, c) = if hot {
                (5.0, Color32::WHITE)
            } else {
                (2.5, Color32::from_gray(150))
            };
            painter.circle_filled(at, r, c);
        }
    }
}

/// Starts, moves and ends the drag of an end point (snapped to 0.01 scene units); returns a
/// finished move (from, to).
fn follow_drag(
    ui: &egui::Ui,
    response: &egui::Response,
    view: &View,
    ends: &EndPoints,
    drag: &mut Option<SceneDrag>,
) -> Option<(DVec2, DVec2)> {
    if response.drag_started()
        // Where the button went down, not where the pointer is once the drag is recognised.
        && let Some(p) = ui
            .input(|i| i.pointer.press_origin())
            .and_then(|q| ends.nearest(view, q))
    {
        *drag = Some(SceneDrag { from: p, to: p });
    }
    if let (Some(d), Some(q)) = (drag.as_mut(), response.interact_pointer_pos()) {
        let p = view.at(q);
        d.to = (p * 100.0).round() / 100.0;
    }
    if response.drag_stopped()
        && let Some(d) = drag.take()
        && d.to != d.from
    {
        return Some((d.from, d.to));
    }
    None
}

/// The ray `x(s) → y(t)` hovered in a kernel plot: solid green when visible, dashed red when
/// blocked, dashed grey when the points do not face each other; its k at the top right.
fn draw_ray(painter: &Painter, view: &View, rect: Rect, world: &World, s: f64, t: f64) {
    let k = world.kernel.eval(s, t);
    let (x, y) = (view.screen(k.x.position), view.screen(k.y.position));
    let (color, label) = if k.geometry <= 0.0 {
        (Color32::from_gray(140), "G = 0")
    } else if k.visible {
        (Color32::from_rgb(90, 255, 110), "visible")
    } else {
        (Color32::from_rgb(255, 80, 80), "blocked")
    };
    if k.visible && k.geometry > 0.0 {
        painter.line_segment([x, y], Stroke::new(2.0, color));
    } else {
        painter.extend(Shape::dashed_line(
            &[x, y],
            Stroke::new(2.0, color),
            6.0,
            4.0,
        ));
    }
    painter.circle_filled(x, 5.0, Color32::from_rgb(255, 150, 40));
    painter.circle_filled(y, 5.0, CRITICAL);
    for (at, name) in [(x, "x(s)"), (y, "y(t)")] {
        painter.text(
            at + vec2(6.0, -6.0),
            Align2::LEFT_BOTTOM,
            name,
            FontId::proportional(12.0),
            Color32::WHITE,
        );
    }
    painter.text(
        rect.left_top() + vec2(6.0, TITLE_H + 1.0),
        Align2::LEFT_TOP,
        format!("k = {:.4}, {label}", k.k),
        FontId::proportional(12.0),
        color,
    );
}

/// The surface point within 10 points of the pointer `q`, marked with its parameter; returns
/// that parameter.
fn mark_hovered_surface(painter: &Painter, view: &View, scene: &Scene, q: Pos2) -> Option<f64> {
    let mut best: Option<(f64, f32, Pos2)> = None;
    for &i in scene.surface_edges() {
        let e = &scene.edges()[i];
        let (a, b) = (view.screen(e.a), view.screen(e.b));
        let ab = b - a;
        let u = ((q - a).dot(ab) / ab.length_sq().max(1e-6)).clamp(0.0, 1.0);
        let c = a + ab * u;
        let d = c.distance(q);
        if d <= 10.0
            && best.is_none_or(|(_, bd, _)| d < bd)
            && let Some(s) = scene.param_of(i, view.at(c))
        {
            best = Some((s, d, c));
        }
    }
    let (s, _, c) = best?;
    painter.circle_stroke(c, 5.0, Stroke::new(2.0, SCENE_MARK));
    painter.text(
        c + vec2(8.0, 8.0),
        Align2::LEFT_TOP,
        format!("s = t = {s:.3}"),
        FontId::proportional(12.0),
        SCENE_MARK,
    );
    Some(s)
}

/// The panel background and its title.
fn panel_frame(painter: &Painter, rect: Rect, title: &str, text: Color32) {
    painter.rect_filled(rect, 4.0, Color32::from_gray(16));
    painter.text(
        rect.left_top() + vec2(6.0, 3.0),
        Align2::LEFT_TOP,
        title,
        FontId::proportional(13.0),
        text,
    );
}

/// Every edge of `scene`: by role, or (with `lit`) each element in the colour of its B,
/// emitters marked with a sun on their front side; front-side ticks and surface indices.
fn draw_edges(
    painter: &Painter,
    view: &View,
    scene: &Scene,
    lit: Option<&LitPaint<'_>>,
    weak: Color32,
) {
    if let Some(lit) = lit {
        for (el, &b) in lit.mesh.elements().iter().zip(lit.b) {
            painter.line_segment(
                [view.screen(el.a), view.screen(el.b)],
                Stroke::new(5.0, lit.color(b)),
            );
        }
    }
    for (i, e) in scene.edges().iter().enumerate() {
        let (color, width) = match (e.role, lit.is_some()) {
            (Role::Blocker, false) => (BLOCKER, 3.0),
            (Role::Blocker, true) => (LIT_BLOCKER, 3.0),
            (Role::Surface, true) => (Color32::from_gray(150), 0.0),
            (Role::Surface, false) if e.emission > 0.0 => (EMITTER, 4.0),
            (Role::Surface, false) => (SURFACE, 2.0),
        };
        let (a, b) = (view.screen(e.a), view.screen(e.b));
        if width > 0.0 {
            painter.line_segment([a, b], Stroke::new(width, color));
        }
        let n = e.normal();
        let n = vec2(n.x as f32, -n.y as f32);
        let ticks = ((a.distance(b) / 22.0) as usize).clamp(1, 16);
        let tick = Stroke::new(1.0, color.gamma_multiply(0.8));
        for k in 0..ticks {
            let p = a + (b - a) * ((k as f32 + 0.5) / ticks as f32);
            painter.line_segment([p, p + n * 6.0], tick);
            if e.two_sided {
                painter.line_segment([p, p - n * 6.0], tick);
            }
        }
        if e.role == Role::Surface {
            let mid = a + (b - a) * 0.5 + n * 13.0;
            if lit.is_some() && e.emission > 0.0 {
                painter.circle_filled(mid, 6.0, EMITTER);
                painter.circle_stroke(mid, 6.0, Stroke::new(1.0, Color32::BLACK));
            } else {
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
}

/// Names in their colours at the bottom left of `rect`; returns where the line goes on.
fn legend(painter: &Painter, rect: Rect, entries: &[(&str, Color32)]) -> f32 {
    let mut x = rect.left() + 6.0;
    for (name, color) in entries {
        let r = painter.text(
            pos2(x, rect.bottom() - 3.0),
            Align2::LEFT_BOTTOM,
            *name,
            FontId::proportional(10.0),
            *color,
        );
        x = r.right() + 8.0;
    }
    x
}

/// A vertical colour bar at the right of `rect`: 0 at the bottom, `top` at the top.
fn colour_bar(painter: &Painter, rect: Rect, top: f64, text: Color32) {
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
        short(top),
        font.clone(),
        text,
    );
    painter.text(
        bar.right_bottom() + vec2(3.0, 0.0),
        Align2::LEFT_BOTTOM,
        "0",
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

/// A value in at most five characters or so.
fn short(v: f64) -> String {
    if v == 0.0 || (1e-2..1e3).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
}

/// A scene lit by `lit` (not interactive): the exact solution beside the learned one.
pub fn lit_view(ui: &mut egui::Ui, rect: Rect, title: &str, scene: &Scene, lit: &LitPaint<'_>) {
    let _ = ui.allocate_rect(rect, Sense::hover());
    let painter = ui.painter_at(rect);
    let weak = ui.visuals().weak_text_color();
    panel_frame(&painter, rect, title, ui.visuals().text_color());
    let view = View::of(scene, scene_area(rect, true));
    draw_edges(&painter, &view, scene, Some(lit), weak);
    colour_bar(&painter, rect, lit.top, weak);
    let _ = legend(&painter, rect, &LIT_LEGEND);
}

/// An empty panel with a title and a line saying why it is empty.
pub fn placeholder(ui: &mut egui::Ui, rect: Rect, title: &str, why: &str) {
    let _ = ui.allocate_rect(rect, Sense::hover());
    let painter = ui.painter_at(rect);
    panel_frame(&painter, rect, title, ui.visuals().text_color());
    painter.text(
        rect.center(),
        Align2::CENTER_CENTER,
        why,
        FontId::proportional(12.0),
        ui.visuals().weak_text_color(),
    );
}

/// `B(s)` along the surfaces: the learned solution as steps (one per element), the exact one
/// on the finer mesh as a line, emitters shaded. The axis stops above the brightest
/// non-emitter; emitters leave the plot.
pub fn b_curves(ui: &mut egui::Ui, lit: &Lit, height: f32) {
    let setup = &lit.setup;
    let (mesh, b) = (&setup.mesh, &lit.solve.b);
    let fine = setup.reference.mesh();
    let exact = &setup.reference.solution().radiosity;
    let lit_max = |mesh: &Mesh, b: &[f64]| {
        (0..mesh.len())
            .filter(|&i| mesh.edge_of(i).emission == 0.0)
            .map(|i| b[i])
            .filter(|v| v.is_finite())
            .fold(0.0_f64, f64::max)
    };
    let mut y_max = 1.25 * lit_max(mesh, b).max(lit_max(fine, exact));
    if y_max <= 0.0 || !y_max.is_finite() {
        y_max = 1.0;
    }
    let clip = |v: f64| if v.is_finite() { v.min(y_max) } else { y_max };
    let exact_points: PlotPoints<'static> = fine
        .elements()
        .iter()
        .zip(exact)
        .map(|(e, &v)| [e.s_mid, clip(v)])
        .collect();
    let learned_points: PlotPoints<'static> = mesh
        .elements()
        .iter()
        .zip(b)
        .flat_map(|(e, &v)| [[e.s[0], clip(v)], [e.s[1], clip(v)]])
        .collect();
    let emitters: Vec<[f64; 2]> = mesh
        .edges()
        .iter()
        .filter(|e| e.emission > 0.0)
        .map(|e| e.s)
        .collect();
    Plot::new("b-of-s")
        .height(height)
        .legend(Legend::default())
        .allow_scroll(false)
        .allow_zoom(false)
        .allow_drag(false)
        .allow_double_click_reset(false)
        .show(ui, |p| {
            p.set_plot_bounds_x(0.0..=1.0);
            p.set_plot_bounds_y(0.0..=y_max);
            for (k, [s0, s1]) in emitters.into_iter().enumerate() {
                let name = if k == 0 { "emitter" } else { "" };
                p.polygon(
                    Polygon::new(name, vec![[s0, 0.0], [s1, 0.0], [s1, y_max], [s0, y_max]])
                        .fill_color(EMITTER.gamma_multiply(0.25))
                        .stroke(Stroke::NONE),
                );
            }
            p.line(
                Line::new(format!("exact ({} el.)", fine.len()), exact_points)
                    .color(Color32::from_gray(200))
                    .width(1.5),
            );
            p.line(
                Line::new(format!("learned ({} el.)", mesh.len()), learned_points)
                    .color(Color32::from_rgb(249, 140, 10))
                    .width(2.0),
            );
        });
}

/// A learning curve. Never aggregated into a band: egui_plot fills the span of points that share
/// a pixel column, which turned a vertical drop (errors falling while the rays stay the same)
/// into a filled wedge.
fn curve(name: &str, points: PlotPoints<'static>) -> Line<'static> {
    Line::new(name, points).allow_band(false)
}

/// The learning curves: held-out error of ζ (and, with the lit scene, of the solved `B − E`)
/// against steps and against rays; cells and samples; and `B(s)` when the lit scene exists.
pub fn curves(ui: &mut egui::Ui, snapshot: Option<&Snapshot>, lit: Option<&Lit>) {
    let history = snapshot.map_or(&[][..], |s| &s.history[..]);
    let lit_history = lit.map_or(&[][..], |l| &l.history[..]);
    let h = (ui.available_height() - 22.0).max(60.0);
    let series = |f: &dyn Fn(&kernel_fit::HistoryPoint) -> [f64; 2]| -> PlotPoints<'static> {
        history.iter().map(f).collect()
    };
    let lit_series = |f: &dyn Fn(&LitPoint) -> [f64; 2]| -> PlotPoints<'static> {
        lit_history.iter().map(f).collect()
    };
    let columns = if lit.is_some() { 4 } else { 3 };
    ui.columns(columns, |cols| {
        cols[0].label("rel. L2 vs steps");
        Plot::new("err-steps")
            .height(h)
            .include_y(0.0)
            .legend(Legend::default())
            .allow_scroll(false)
            .allow_zoom(false)
            .allow_drag(false)
            .show(&mut cols[0], |p| {
                p.line(curve(
                    "ζ held out",
                    series(&|h| [h.steps as f64, h.rel_l2_heldout]),
                ));
                if !lit_history.is_empty() {
                    p.line(curve(
                        "solved B − E",
                        lit_series(&|h| [h.steps as f64, h.rel_l2_reflected]),
                    ));
                }
            });
        cols[1].label("rel. L2 vs rays cast");
        Plot::new("err-rays")
            .height(h)
            .include_y(0.0)
            .legend(Legend::default())
            .allow_scroll(false)
            .allow_zoom(false)
            .allow_drag(false)
            .show(&mut cols[1], |p| {
                p.line(curve(
                    "ζ held out",
                    series(&|h| [h.rays as f64, h.rel_l2_heldout]),
                ));
                if !lit_history.is_empty() {
                    p.line(curve(
                        "solved B − E",
                        lit_series(&|h| [h.rays as f64, h.rel_l2_reflected]),
                    ));
                }
            });
        if let Some(lit) = lit {
            cols[3].label("B(s): learned vs exact");
            b_curves(&mut cols[3], lit, h);
        }
        cols[2].label("cells and samples vs steps");
        Plot::new("counts")
            .height(h)
            .include_y(0.0)
            .legend(Legend::default())
            .allow_scroll(false)
            .allow_zoom(false)
            .allow_drag(false)
            .show(&mut cols[2], |p| {
                p.line(curve("cells", series(&|h| [h.steps as f64, h.cells as f64])).width(2.5));
                p.line(
                    curve(
                        "samples / 20",
                        series(&|h| [h.steps as f64, h.samples as f64 / 20.0]),
                    )
                    .style(LineStyle::dashed_dense()),
                );
            });
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every non-ASCII character in the viewer's code (outside comments) is one the default
    /// fonts can draw: egui panics on a missing glyph in debug builds and draws tofu otherwise.
    #[test]
    fn every_character_the_viewer_writes_has_a_glyph() {
        let sources = [
            include_str!("app.rs"),
            include_str!("app/controls.rs"),
            include_str!("views.rs"),
            include_str!("worker.rs"),
            include_str!("lit.rs"),
            include_str!("settings.rs"),
        ];
        let mut used: Vec<char> = sources
            .iter()
            .flat_map(|src| src.lines())
            .filter(|line| !line.trim_start().starts_with("//"))
            .flat_map(|line| line.split("//").next().unwrap_or("").chars())
            .filter(|c| !c.is_ascii())
            .collect();
        used.sort_unstable();
        used.dedup();
        assert!(used.contains(&'ζ'), "the scan finds the code's characters");
        let ctx = egui::Context::default();
        let mut output = ctx.run_ui(egui::RawInput::default(), |_| {});
        output.textures_delta.clear();
        let missing: Vec<char> = ctx.fonts_mut(|f| {
            used.iter()
                .copied()
                .filter(|&c| {
                    !f.has_glyph(&FontId::proportional(12.0), c)
                        || !f.has_glyph(&FontId::monospace(12.0), c)
                })
                .collect()
        });
        assert!(missing.is_empty(), "no glyph for {missing:?}");
    }

    #[test]
    fn plot_frame_round_trips() {
        let f = PlotFrame::new(
            Rect::from_min_size(pos2(10.0, 20.0), vec2(300.0, 300.0)),
            true,
        );
        let p = f.screen(0.25, 0.75);
        let [s, t] = f.at(p).unwrap();
        assert!(
            (s - 0.25).abs() < 1e-4 && (t - 0.75).abs() < 1e-4,
            "{s} {t}"
        );
        assert!(
            f.screen(0.0, 0.0).y > f.screen(1.0, 0.0).y,
            "s goes upwards"
        );
        assert!(f.at(pos2(0.0, 0.0)).is_none());
    }

    #[test]
    fn overlay_draws_cells_and_edges_where_they_are() {
        let cell = |st, critical| kernel_fit::CellSnapshot {
            st: Some(st),
            width: 0.1,
            critical,
            resource: 1.0,
            output: 0.0,
        };
        let snap = Snapshot {
            cells: vec![cell([0.25, 0.75], true), cell([0.75, 0.25], false)],
            edges: vec![[0, 1]],
            ..Snapshot::default()
        };
        let img = overlay_image(100, 1.0, &snap, true, true);
        // Cell 0: t = 0.75 → column 75, s = 0.25 → row 75 (s upwards).
        assert_eq!(img.pixels[75 * 100 + 75], CRITICAL);
        assert_eq!(img.pixels[25 * 100 + 25], CELL);
        assert_ne!(img.pixels[50 * 100 + 50], Color32::TRANSPARENT, "the edge");
        assert_eq!(img.pixels[0], Color32::TRANSPARENT);
        let bare = overlay_image(100, 1.0, &snap, false, false);
        assert!(bare.pixels.iter().all(|p| *p == Color32::TRANSPARENT));
    }

    #[test]
    fn moving_a_shared_corner_moves_both_edges() {
        let scene = flatland_geom::bundled::scene("fig3").unwrap();
        let from = DVec2::new(4.0, 0.0);
        let moved = moved_scene(&scene, from, DVec2::new(4.5, -0.5)).unwrap();
        let hits = moved
            .edges()
            .iter()
            .filter(|e| e.a == DVec2::new(4.5, -0.5) || e.b == DVec2::new(4.5, -0.5))
            .count();
        assert_eq!(hits, 2);
        assert!(moved.edges().iter().all(|e| e.a != from && e.b != from));
        // Collapsing an edge is refused, not panicking.
        assert!(moved_scene(&scene, from, DVec2::new(0.0, 0.0)).is_err());
    }
}

#[cfg(test)]
mod drag_tests {
    use super::*;
    use crate::worker::World;
    use egui::{Event, PointerButton};
    use egui_kittest::Harness;
    use flatland_geom::Kernel;
    use flatland_solve::Reference;

    #[test]
    fn dragging_an_end_point_reports_the_move() {
        let scene = flatland_geom::bundled::scene("fig3").unwrap();
        let kernel = Arc::new(Kernel::new(scene.clone()));
        let world = World {
            id: 1,
            scene: scene.clone(),
            reference: Arc::new(Reference::new(&kernel, 4, 16, 1)),
            kernel,
            exact_small: Vec::new(),
            defined: [true; 2],
        };
        let rect = Rect::from_min_size(pos2(0.0, 0.0), vec2(400.0, 300.0));
        let state = (None::<SceneDrag>, Vec::<(DVec2, DVec2)>::new());
        let mut h = Harness::builder().with_size([400.0, 300.0]).build_ui_state(
            move |ui, state: &mut (Option<SceneDrag>, Vec<(DVec2, DVec2)>)| {
                let frame = SceneFrame {
                    rect,
                    title: "scene",
                    world: &world,
                    lit: None,
                };
                let out = scene_view(ui, &frame, &scene, &Hover::default(), &mut state.0);
                state.1.extend(out.moved);
            },
            state,
        );
        // The blocker's first end point, through the same mapping the view uses.
        let inner = scene_area(rect, false);
        let view = View::of(&flatland_geom::bundled::scene("fig3").unwrap(), inner);
        let from = DVec2::new(1.2, 1.7);
        let p = view.screen(from);
        let press = |pos, pressed| Event::PointerButton {
            pos,
            button: PointerButton::Primary,
            pressed,
            modifiers: Default::default(),
        };
        h.event(Event::PointerMoved(p));
        h.run_steps(1);
        h.event(press(p, true));
        h.run_steps(1);
        for k in 1..=5 {
            h.event(Event::PointerMoved(
                p + vec2(-6.0 * k as f32, -4.0 * k as f32),
            ));
            h.run_steps(1);
        }
        assert!(h.state().0.is_some(), "a drag is under way");
        h.event(press(p + vec2(-30.0, -20.0), false));
        h.run_steps(2);
        let moved = &h.state().1;
        assert_eq!(moved.len(), 1, "{moved:?}");
        assert_eq!(moved[0].0, from);
        assert!(moved[0].1.x < from.x && moved[0].1.y > from.y, "{moved:?}");
    }
}
