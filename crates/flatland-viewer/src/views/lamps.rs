//! The relit scene: the scene lit by its moving point lights, each light a small mark the user
//! can grab and drag; a click on the floor adds a light, a right click on one deletes it.

use egui::{Color32, Pos2, Rect, Sense, Stroke};
use flatland_geom::{DVec2, PointLight, Scene};

use super::edges::{LIT_LEGEND, LitPaint, colour_bar, draw_edges_once, scene_area};
use super::raster::EdgesTexture;
use super::widgets::{View, legend, panel_frame};

/// A light's mark: a small white disc ringed in black (any colour of the map shows it).
const MARK_R: f32 = 4.0;
/// Past this many lights their marks are small white dots (a plan of hundreds of lamps would
/// be covered by full marks, and each costs the software renderer a ringed disc per frame);
/// the light under the pointer or held is marked in full.
const MANY_MARKS: usize = 64;
/// A mark among many.
const SMALL_MARK_R: f32 = 1.5;
/// How near the pointer must be to a mark to grab or delete it, in points.
const GRAB_R: f32 = 10.0;

/// What the user did in the relit view this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LampsOut {
    /// A grabbed light (by index) and where the pointer has it now.
    pub moved: Option<(usize, DVec2)>,
    /// A click on the floor: a light there.
    pub added: Option<DVec2>,
    /// A right click on a light: delete it.
    pub deleted: Option<usize>,
}

/// Where and what the relit view draws.
pub struct RelitFrameView<'a> {
    /// The panel.
    pub rect: Rect,
    /// Its title.
    pub title: &'a str,
    /// The scene (as the user sees it).
    pub scene: &'a Scene,
    /// B to colour it by, when there is one.
    pub lit: Option<&'a LitPaint<'a>>,
    /// The lights.
    pub lights: &'a [PointLight],
    /// A line at the foot of the panel (what answers the moves), right of the legend.
    pub note: &'a str,
}

/// Draws the relit scene and its lights' marks, follows a grab (`grabbed`: the light being
/// dragged); returns what the user did and where each mark was drawn.
pub fn relit_view(
    ui: &mut egui::Ui,
    frame: &RelitFrameView<'_>,
    grabbed: &mut Option<usize>,
    texture: &mut EdgesTexture,
) -> (LampsOut, Vec<Pos2>) {
    let rect = frame.rect;
    let response = ui.allocate_rect(rect, Sense::click_and_drag());
    let painter = ui.painter_at(rect);
    let weak = ui.visuals().weak_text_color();
    panel_frame(&painter, rect, frame.title, ui.visuals().text_color());
    let view = View::of(frame.scene, scene_area(rect, true));
    if let Some(lit) = frame.lit {
        draw_edges_once(texture, &painter, rect, &view, frame.scene, Some(lit), weak);
        colour_bar(&painter, rect, lit, weak);
    }
    let legend_end = legend(&painter, rect, &LIT_LEGEND);
    painter.text(
        egui::pos2(legend_end + 4.0, rect.bottom() - 3.0),
        egui::Align2::LEFT_BOTTOM,
        frame.note,
        egui::FontId::proportional(11.0),
        weak,
    );
    let marks: Vec<Pos2> = frame.lights.iter().map(|l| view.screen(l.at)).collect();
    let near = |q: Pos2| {
        marks
            .iter()
            .enumerate()
            .map(|(i, m)| (i, m.distance(q)))
            .filter(|(_, d)| *d <= GRAB_R)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    };
    let mut out = LampsOut::default();
    if response.drag_started_by(egui::PointerButton::Primary) {
        // Where the button went down, not where the drag was recognised.
        *grabbed = ui.input(|i| i.pointer.press_origin()).and_then(near);
    }
    if let (Some(i), Some(q)) = (*grabbed, response.interact_pointer_pos()) {
        out.moved = Some((i, view.at(q)));
    }
    if response.drag_stopped() {
        *grabbed = None;
    }
    if response.clicked()
        && let Some(q) = response.interact_pointer_pos()
        && near(q).is_none()
    {
        out.added = Some(view.at(q));
    }
    if response.secondary_clicked()
        && let Some(q) = response.interact_pointer_pos()
    {
        out.deleted = near(q);
    }
    let hovered = response.hover_pos().and_then(near);
    let many = marks.len() > MANY_MARKS;
    for (i, &m) in marks.iter().enumerate() {
        let hot = hovered == Some(i) || *grabbed == Some(i);
        // The first light is the one that wanders: always in full.
        let r = match (hot, many && i > 0) {
            (true, _) => MARK_R + 1.5,
            (false, true) => SMALL_MARK_R,
            (false, false) => MARK_R,
        };
        painter.circle_filled(m, r, Color32::WHITE);
        if r > SMALL_MARK_R {
            painter.circle_stroke(m, r, Stroke::new(1.0, Color32::BLACK));
        }
    }
    if hovered.is_some() || grabbed.is_some() {
        ui.ctx().set_cursor_icon(egui::CursorIcon::Grab);
    }
    (out, marks)
}
