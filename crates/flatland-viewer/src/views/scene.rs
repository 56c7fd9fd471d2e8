//! The scene view: the scene by role or lit, draggable end points, the ray `x(s) → y(t)` of
//! the `(s, t)` under the pointer, and the parameter of the surface point under it.

use egui::{Align2, Color32, FontId, Painter, Pos2, Rect, Sense, Shape, Stroke, pos2, vec2};
use flatland_geom::{DVec2, EdgeId, GeomError, Scene};

use super::edges::{
    LEGEND, LIT_LEGEND, LitPaint, colour_bar, draw_edges, draw_edges_once, scene_area,
};
use super::raster::EdgesTexture;
use super::widgets::{View, legend, panel_frame};
use super::{CRITICAL, Hover, SCENE_MARK, SceneDrag, TITLE_H};
use crate::worker::World;

/// Scenes with more end points than this draw only the hovered or dragged one: thousands of
/// dots would hide the edges.
const MAX_DOTS: usize = 400;

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
            out = out.with_edge(EdgeId::new(i), moved)?;
        }
    }
    Ok(out)
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
    /// Whether end points can be dragged (not while a past moment is shown).
    pub editable: bool,
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
    texture: &mut EdgesTexture,
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
    if !frame.editable {
        *drag = None;
    }
    let mut out = SceneOut {
        moved: if frame.editable {
            follow_drag(ui, &response, &view, &ends, drag)
        } else {
            None
        },
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

    if drag.is_some() {
        // The scene changes with every frame of a drag: no texture would be shown twice.
        draw_edges(&mut &painter, &painter, &view, shown, lit, weak);
    } else {
        draw_edges_once(texture, &painter, rect, &view, shown, lit, weak);
    }
    captions(&painter, frame, scene, lit, weak);
    let pointer = response.hover_pos();
    let hovered_end = pointer
        .filter(|_| frame.editable)
        .and_then(|q| ends.nearest(&view, q));
    if frame.editable {
        ends.draw(&painter, &view, hovered_end, *drag);
    }
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

/// The colour bar (lit), the legend and the line that counts the edges, below the scene.
fn captions(
    painter: &Painter,
    frame: &SceneFrame<'_>,
    scene: &Scene,
    lit: Option<&LitPaint<'_>>,
    weak: Color32,
) {
    let rect = frame.rect;
    if let Some(lit) = lit {
        colour_bar(painter, rect, lit, weak);
    }
    let x = legend(
        painter,
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
            match (frame.editable, lit.is_some()) {
                (false, _) => " · a past moment",
                (true, true) => "",
                (true, false) => " · drag an end point to edit",
            }
        ),
        FontId::proportional(10.0),
        weak,
    );
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

    /// Dots (only the hot one past [`MAX_DOTS`]); the hovered or dragged one big and white, the
    /// dragged one where it is dragged to.
    fn draw(
        &self,
        painter: &Painter,
        view: &View,
        hovered: Option<DVec2>,
        drag: Option<SceneDrag>,
    ) {
        let all = self.0.len() <= MAX_DOTS;
        for p in &self.0 {
            let hot = hovered == Some(*p) || drag.is_some_and(|d| d.from == *p);
            if !hot && !all {
                continue;
            }
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
        let e = scene.edge(i);
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

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
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
                    editable: true,
                };
                let mut texture = EdgesTexture::default();
                let out = scene_view(
                    ui,
                    &frame,
                    &scene,
                    &Hover::default(),
                    &mut state.0,
                    &mut texture,
                );
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
