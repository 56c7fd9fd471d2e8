//! The paper's Fig. 3 panels (geometry, kernel, cells, approximation, error) of a finished fit,
//! drawn from its grids and cells: what `flatland figure` and `flatland results` write.

use flatland_geom::{Role, Scene};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::PictureError;
use crate::colormap::Scale;
use crate::plot::{Heatmap, Overlay, encode_png, heatmap_png, register_font, short_number};

/// Surface edges are labelled in the geometry panel up to this count.
const MAX_EDGE_LABELS: usize = 60;

/// The panels, in order.
pub const PANELS: [&str; 5] = [
    "a_geometry.png",
    "b_kernel.png",
    "c_cells.png",
    "d_approximation.png",
    "e_error.png",
];

/// What the panels show: the exact and the learned ζ on one `res × res` grid (row ↔ `s`), and
/// the network's cells.
#[derive(Clone, Copy)]
pub struct Figure<'a> {
    /// The scene fitted.
    pub scene: &'a Scene,
    /// What is shown, in every panel's title (the scene and the learner).
    pub label: &'a str,
    /// Colour by log10 (all three heatmaps share the exact ζ's scale).
    pub log: bool,
    /// The grids' side.
    pub res: usize,
    /// The exact ζ.
    pub exact: &'a [f64],
    /// The learned ζ̃.
    pub learned: &'a [f64],
    /// The cells at their mean `(s, t)` and the network's edges.
    pub overlay: Overlay<'a>,
}

/// The five panels of `figure`, as PNG bytes in [`PANELS`] order.
pub fn panels_png(figure: &Figure<'_>) -> Result<Vec<(&'static str, Vec<u8>)>, PictureError> {
    let &Figure {
        scene,
        label,
        log,
        res,
        exact,
        learned,
        overlay,
    } = figure;
    let error: Vec<f64> = learned
        .iter()
        .zip(exact)
        .map(|(a, e)| (a - e).abs())
        .collect();
    let top = Scale::fit(exact, log).top;
    let panel = |title: &str, quantity: &'static str, overlay| Heatmap {
        title: format!("{label}: {title}"),
        quantity,
        scene,
        log,
        top,
        overlay,
    };
    let cells_title = format!(
        "{} cells at the mean (s, t) of the samples they won",
        overlay.cells.len()
    );
    Ok(vec![
        (PANELS[0], geometry(scene, label)?),
        (
            PANELS[1],
            heatmap_png(exact, res, &panel("exact ζ", "ζ", None))?,
        ),
        (
            PANELS[2],
            heatmap_png(exact, res, &panel(&cells_title, "ζ", Some(overlay)))?,
        ),
        (
            PANELS[3],
            heatmap_png(learned, res, &panel("learned ζ", "learned ζ", None))?,
        ),
        (
            PANELS[4],
            heatmap_png(&error, res, &panel("|learned - exact|", "|error|", None))?,
        ),
    ])
}

/// The scene: emitters yellow, surfaces grey, blockers red; a tick on each edge's front side.
fn geometry(scene: &Scene, label: &str) -> Result<Vec<u8>, PictureError> {
    register_font();
    let (lo, hi) = scene.bounds();
    let pad = 0.05 * (hi - lo).max_element();
    let (w, h) = (800u32, 800u32);
    let span = (hi - lo).max_element() + 2.0 * pad;
    let centre = (lo + hi) * 0.5;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        let err = PictureError::draw("the geometry");
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{label}: emitters yellow, surfaces grey, blockers red; ticks: front"),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (centre.x - span / 2.0)..(centre.x + span / 2.0),
                (centre.y - span / 2.0)..(centre.y + span / 2.0),
            )
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .light_line_style(WHITE)
            .x_labels(6)
            .y_labels(6)
            .x_label_formatter(&|v| short_number(*v))
            .y_label_formatter(&|v| short_number(*v))
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(|e| err(e.to_string()))?;
        for edge in scene.edges() {
            let color = match (edge.role, edge.emission > 0.0) {
                (Role::Blocker, _) => RGBColor(200, 40, 40),
                (_, true) => RGBColor(235, 170, 0),
                _ => RGBColor(70, 70, 70),
            };
            chart
                .draw_series(LineSeries::new(
                    [(edge.a.x, edge.a.y), (edge.b.x, edge.b.y)],
                    color.stroke_width(4),
                ))
                .map_err(|e| err(e.to_string()))?;
            let mid = (edge.a + edge.b) * 0.5;
            let tick = mid + edge.normal() * 0.025 * span;
            chart
                .draw_series(LineSeries::new(
                    [(mid.x, mid.y), (tick.x, tick.y)],
                    color.stroke_width(2),
                ))
                .map_err(|e| err(e.to_string()))?;
        }
        // Surface edge indices, as on the heatmaps' axes, on the front side.
        let surfaces = scene.surface_edges();
        if surfaces.len() <= MAX_EDGE_LABELS {
            let style = TextStyle::from(("sans-serif", 15).into_font())
                .color(&BLUE)
                .pos(Pos::new(HPos::Center, VPos::Center));
            for &e in surfaces {
                let edge = scene.edge(e);
                let at = (edge.a + edge.b) * 0.5 + edge.normal() * 0.06 * span;
                chart
                    .draw_series([Text::new(e.to_string(), (at.x, at.y), style.clone())])
                    .map_err(|e| err(e.to_string()))?;
            }
        }
        root.present().map_err(|e| err(e.to_string()))?;
    }
    encode_png(&rgb, w, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows of a PNG below its title band (the tenth of its height at the top).
    fn below_title(png: &[u8]) -> Vec<u8> {
        let image = image::load_from_memory(png).unwrap().to_rgb8();
        let skip = (image.height() / 10) as usize * image.width() as usize * 3;
        image.into_raw()[skip..].to_vec()
    }

    /// A ζ̃ at half the exact ζ is off by exactly half of it: the approximation and error panels
    /// show the same picture under their titles, on the exact ζ's scale; the cells panel is the
    /// kernel panel dimmed under the cells.
    #[test]
    fn the_panels_share_the_exact_scale_and_show_the_error() {
        let scene = flatland_geom::bundled::scene("fig3").unwrap();
        let res = 16;
        let exact: Vec<f64> = (0..res * res).map(|k| (k % 7) as f64 + 0.5).collect();
        let learned: Vec<f64> = exact.iter().map(|v| v / 2.0).collect();
        let cells = [Some([0.25, 0.5]), None, Some([0.75, 0.5])];
        let figure = Figure {
            scene: &scene,
            label: "fig3",
            log: false,
            res,
            exact: &exact,
            learned: &learned,
            overlay: Overlay {
                cells: &cells,
                edges: &[(0, 2)],
            },
        };
        let panels = panels_png(&figure).unwrap();
        let names: Vec<&str> = panels.iter().map(|p| p.0).collect();
        assert_eq!(names, PANELS);
        let geometry = image::load_from_memory(&panels[0].1).unwrap();
        assert_eq!((geometry.width(), geometry.height()), (800, 800));
        let [kernel, cells, learned, error] = [1, 2, 3, 4].map(|i| below_title(&panels[i].1));
        assert_eq!(learned, error);
        assert_ne!(learned, kernel, "half of ζ on ζ's scale is darker");
        assert_ne!(cells, kernel);
        assert_eq!(cells.len(), kernel.len());
    }
}
