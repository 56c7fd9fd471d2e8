//! One `(s, t)` panel: the heatmap, the rastered overlays, edge labels that thin out instead of
//! overlapping, the colour bar, the legend of the marks, the hover lines.

use std::f32::consts::FRAC_PI_2;

use egui::{
    Align2, Color32, FontId, Painter, Pos2, Rect, Sense, Stroke, TextureId, Vec2,
    epaint::TextShape, pos2, vec2,
};
use flatland_geom::Scene;
use flatland_pictures::colormap::Scale;

use super::widgets::{gradient, short, uv};
use super::{CELL, CRITICAL, FACE_VISIBLE, NET_EDGE, NEW_CELL, SCENE_MARK, SEEN, TITLE_H};

/// Width of the colour bar beside the big kernel plot, labels included.
const HEAT_BAR_W: f32 = 56.0;
/// Height of the legend row under the big plot.
const LEGEND_H: f32 = 14.0;
/// Axis labels' font size, and the room one digit takes.
const LABEL_PT: f32 = 10.0;
const DIGIT_W: f32 = 6.0;

/// Where the unit square of `(s, t)` sits on screen: `t` to the right, `s` upwards.
#[derive(Clone, Copy, Debug)]
pub struct PlotFrame {
    /// The whole panel (title, axes, plot).
    pub outer: Rect,
    /// The square the unit square maps to.
    pub plot: Rect,
    /// Whether axis titles, edge labels, a colour bar and the legend are drawn.
    pub big: bool,
    /// The colour scale, for the colour bar of a big frame.
    pub scale: Option<Scale>,
    /// What the colour bar measures: `ζ`, or `M₂` when the transport's kernel is shown.
    pub quantity: &'static str,
}

impl PlotFrame {
    /// Fits the square plot into `outer`, leaving room for a title and (if `big`) axis labels.
    #[must_use]
    pub fn new(outer: Rect, big: bool) -> PlotFrame {
        let (left, bottom, right) = if big {
            (34.0, 30.0 + LEGEND_H, HEAT_BAR_W)
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
            quantity: "ζ",
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

/// What a panel's marks need beyond its image (whose layers are composited beforehand: the
/// heatmap, the boundaries, the samples and the cells; `app::heatmaps`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Overlay<'a> {
    /// The parameters of the surface edges' boundaries drawn (for the axis ticks).
    pub ticks: &'a [f64],
    /// The cells are the light-driven learner's probes: the legend says so.
    pub probes: bool,
}

/// One (s, t) panel: its image (heatmap and overlays), axes, labels, hover marks. Returns
/// `(s, t)` under the pointer.
pub fn kernel_plot(
    ui: &mut egui::Ui,
    frame: &PlotFrame,
    title: &str,
    heatmap: Option<TextureId>,
    scene: &Scene,
    overlay: &Overlay<'_>,
    hover: &super::Hover,
) -> Option<[f64; 2]> {
    let response = ui.allocate_rect(frame.plot, Sense::hover());
    let painter = ui.painter_at(frame.outer.expand(2.0));
    let plot = frame.plot;
    let weak = ui.visuals().weak_text_color();
    painter.text(
        pos2(plot.left(), frame.outer.top()),
        Align2::LEFT_TOP,
        title,
        FontId::proportional(13.0),
        ui.visuals().text_color(),
    );
    match heatmap {
        // Opaque: no background under it (the software rasterizer pays for every layer).
        Some(tex) => {
            painter.image(tex, plot, uv(), Color32::WHITE);
        }
        None => {
            painter.rect_filled(plot, 0.0, Color32::BLACK);
            painter.text(
                plot.center(),
                Align2::CENTER_CENTER,
                "…",
                FontId::proportional(14.0),
                weak,
            );
        }
    }
    if frame.big {
        axis_ticks(&painter, frame, overlay.ticks, weak);
        edge_labels(&painter, frame, scene, weak);
        axis_titles(&painter, frame, weak);
        marks_legend(&painter, frame, weak, overlay.probes);
        if let Some(scale) = frame.scale {
            scale_bar(&painter, frame, scale, weak);
        }
    }
    hover_lines(&painter, frame, hover);
    response.hover_pos().and_then(|p| frame.at(p))
}

/// The hovered `(s, t)` (white) and the `s` of a hovered scene point (green, on the diagonal).
fn hover_lines(painter: &Painter, frame: &PlotFrame, hover: &super::Hover) {
    let plot = frame.plot;
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
}

/// A short tick outside the plot at each drawn boundary, on both axes.
fn axis_ticks(painter: &Painter, frame: &PlotFrame, ticks: &[f64], color: Color32) {
    let plot = frame.plot;
    let stroke = Stroke::new(1.0, color);
    for &s in ticks {
        let p = frame.screen(s, s);
        painter.vline(p.x, plot.bottom()..=plot.bottom() + 5.0, stroke);
        painter.hline(plot.left() - 5.0..=plot.left(), p.y, stroke);
    }
}

/// The surface edges' indices on both axes, at the middle of their range: the widest ranges
/// first, each only where it overlaps no label placed before, so labels thin out on a scene
/// of many edges instead of overlapping.
fn edge_labels(painter: &Painter, frame: &PlotFrame, scene: &Scene, color: Color32) {
    let plot = frame.plot;
    let mut ranges: Vec<(usize, f64, f64)> = scene
        .surface_edges()
        .iter()
        .filter_map(|&e| {
            scene
                .edge_param_range(e)
                .map(|(s0, s1)| (e.index(), s0, s1))
        })
        .collect();
    ranges.sort_by(|a, b| (b.2 - b.1).total_cmp(&(a.2 - a.1)));
    let label_w = |e: usize| DIGIT_W * (e.max(1).ilog10() + 1) as f32;
    let placed_t = thin_labels(&ranges, |e, mid| {
        let x = plot.left() + mid * plot.width();
        let half = label_w(e) / 2.0 + 1.5;
        (x - half, x + half)
    });
    let placed_s = thin_labels(&ranges, |_, mid| {
        let y = plot.bottom() - mid * plot.height();
        (y - LABEL_PT / 2.0 - 1.0, y + LABEL_PT / 2.0 + 1.0)
    });
    let font = FontId::proportional(LABEL_PT);
    for (e, mid) in placed_t {
        let x = plot.left() + mid * plot.width();
        painter.text(
            pos2(x, plot.bottom() + 2.0),
            Align2::CENTER_TOP,
            e.to_string(),
            font.clone(),
            color,
        );
    }
    for (e, mid) in placed_s {
        let y = plot.bottom() - mid * plot.height();
        painter.text(
            pos2(plot.left() - 3.0, y),
            Align2::RIGHT_CENTER,
            e.to_string(),
            font.clone(),
            color,
        );
    }
}

/// The labels among `ranges` (edge, s₀, s₁; widest first) that fit: each takes the screen
/// interval `extent(edge, middle)` and is kept when it overlaps none kept before.
fn thin_labels(
    ranges: &[(usize, f64, f64)],
    extent: impl Fn(usize, f32) -> (f32, f32),
) -> Vec<(usize, f32)> {
    let mut taken: Vec<(f32, f32)> = Vec::new();
    let mut kept = Vec::new();
    for &(e, s0, s1) in ranges {
        let mid = ((s0 + s1) / 2.0) as f32;
        let (lo, hi) = extent(e, mid);
        if taken.iter().all(|&(a, b)| hi <= a || lo >= b) {
            taken.push((lo, hi));
            kept.push((e, mid));
        }
    }
    kept
}

/// "t (receiver edge)" under the plot, "s (sender edge)" up its left side.
fn axis_titles(painter: &Painter, frame: &PlotFrame, color: Color32) {
    let plot = frame.plot;
    painter.text(
        pos2(plot.center().x, plot.bottom() + 14.0),
        Align2::CENTER_TOP,
        "t (receiver edge)",
        FontId::proportional(12.0),
        color,
    );
    let galley =
        painter.layout_no_wrap("s (sender edge)".into(), FontId::proportional(12.0), color);
    let pos = pos2(frame.outer.left(), plot.center().y + galley.size().x / 2.0);
    painter.add(TextShape::new(pos, galley, color).with_angle(-FRAC_PI_2));
}

/// What each mark over the kernel means, on a row under the plot (drawn as the marks are).
fn marks_legend(painter: &Painter, frame: &PlotFrame, color: Color32, probes: bool) {
    let y = frame.plot.bottom() + 30.0 + LEGEND_H / 2.0;
    let mut x = frame.plot.left();
    let font = FontId::proportional(10.0);
    let entry = |x: &mut f32, draw: &dyn Fn(Pos2), text: &str| {
        draw(pos2(*x + 4.0, y));
        let r = painter.text(
            pos2(*x + 11.0, y),
            Align2::LEFT_CENTER,
            text,
            font.clone(),
            color,
        );
        *x = r.right() + 10.0;
    };
    let disc = |fill: Color32, rim: Color32| {
        move |p: Pos2| {
            painter.circle(p, 3.0, fill, Stroke::new(1.0, rim));
        }
    };
    if probes {
        entry(
            &mut x,
            &disc(FACE_VISIBLE, Color32::BLACK),
            "probe (exact view)",
        );
        entry(
            &mut x,
            &|p: Pos2| {
                painter.line_segment(
                    [p - egui::vec2(0.0, 5.0), p + egui::vec2(0.0, 5.0)],
                    Stroke::new(2.0, SEEN),
                );
            },
            "what it sees (V = 1)",
        );
        entry(&mut x, &disc(FACE_VISIBLE, NEW_CELL), "newest round");
        return;
    }
    entry(&mut x, &disc(CELL, Color32::BLACK), "cell (size ~ δ_c)");
    entry(&mut x, &disc(CRITICAL, Color32::BLACK), "critical");
    entry(&mut x, &disc(CELL, NEW_CELL), "new (last second)");
    entry(
        &mut x,
        &|p: Pos2| {
            painter.line_segment(
                [p - vec2(4.0, 0.0), p + vec2(4.0, 0.0)],
                Stroke::new(1.5, NET_EDGE),
            );
        },
        "edge within a face",
    );
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
        frame.quantity,
        FontId::proportional(12.0),
        text,
    );
    let ticks: Vec<f64> = if scale.log {
        let decades = flatland_pictures::colormap::LOG_DECADES;
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

#[cfg(test)]
mod tests {
    use super::*;

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
    fn labels_thin_out_instead_of_overlapping() {
        // 1000 equal edges on 500 pixels: a few dozen labels, none overlapping.
        let ranges: Vec<(usize, f64, f64)> = (0..1000)
            .map(|e| (e, e as f64 / 1000.0, (e + 1) as f64 / 1000.0))
            .collect();
        let kept = thin_labels(&ranges, |e, mid| {
            let x = mid * 500.0;
            let half = DIGIT_W * (e.max(1).ilog10() + 1) as f32 / 2.0 + 1.5;
            (x - half, x + half)
        });
        assert!(kept.len() > 10 && kept.len() < 60, "{}", kept.len());
        let mut xs: Vec<f32> = kept.iter().map(|k| k.1 * 500.0).collect();
        xs.sort_by(f32::total_cmp);
        assert!(
            xs.windows(2).all(|w| w[1] - w[0] >= DIGIT_W + 3.0 - 1e-3),
            "{xs:?}"
        );
        // A few wide edges: every label fits.
        let wide = [(0, 0.0, 0.3), (1, 0.3, 0.7), (2, 0.7, 1.0)];
        assert_eq!(
            thin_labels(&wide, |_, m| (m * 500.0 - 5.0, m * 500.0 + 5.0)).len(),
            3
        );
    }
}
