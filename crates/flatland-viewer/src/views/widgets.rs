//! Small pieces the panels share: where a scene sits on screen, a panel's frame and title,
//! legends, the colour gradient, short numbers, the placeholder of an empty panel, the readout
//! box under the pointer.

use egui::{Align2, Color32, FontId, Painter, Pos2, Rect, Sense, Stroke, pos2, vec2};
use flatland_geom::{DVec2, Scene};

use crate::colormap::colour;

/// The whole texture.
pub(super) fn uv() -> Rect {
    Rect::from_min_max(Pos2::ZERO, pos2(1.0, 1.0))
}

/// The panel background and its title.
pub(super) fn panel_frame(painter: &Painter, rect: Rect, title: &str, text: Color32) {
    painter.rect_filled(rect, 4.0, Color32::from_gray(16));
    painter.text(
        rect.left_top() + egui::vec2(6.0, 3.0),
        Align2::LEFT_TOP,
        title,
        FontId::proportional(13.0),
        text,
    );
}

/// Names in their colours at the bottom left of `rect`; returns where the line goes on.
pub(super) fn legend(painter: &Painter, rect: Rect, entries: &[(&str, Color32)]) -> f32 {
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

/// The colour map drawn upwards in `bar` (0 at the bottom, 1 at the top) in `steps` slices,
/// outlined in `text`.
pub(super) fn gradient(painter: &Painter, bar: Rect, steps: usize, text: Color32) {
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

/// A value in at most five characters or so.
pub(super) fn short(v: f64) -> String {
    if v == 0.0 || (1e-2..1e3).contains(&v.abs()) {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
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
    let offset = egui::vec2(
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

/// Where a scene sits on screen: centred in a rectangle, at the largest scale that fits.
pub(super) struct View {
    centre: Pos2,
    mid: DVec2,
    scale: f64,
}

impl View {
    pub(super) fn of(scene: &Scene, rect: Rect) -> View {
        let (lo, hi) = scene.bounds();
        let size = (hi - lo).max(DVec2::splat(1e-9));
        let scale = (f64::from(rect.width()) / size.x).min(f64::from(rect.height()) / size.y);
        View {
            centre: rect.center(),
            mid: (lo + hi) / 2.0,
            scale,
        }
    }
    pub(super) fn screen(&self, p: DVec2) -> Pos2 {
        let d = (p - self.mid) * self.scale;
        self.centre + vec2(d.x as f32, -d.y as f32)
    }
    pub(super) fn at(&self, q: Pos2) -> DVec2 {
        let d = q - self.centre;
        self.mid + DVec2::new(f64::from(d.x), -f64::from(d.y)) / self.scale
    }
}
