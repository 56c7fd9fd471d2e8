//! The paper's Fig. 3 panels (geometry, kernel, cells, approximation, error), shared by
//! `flatland figure` and `flatland results`.

use crate::colormap::Scale;
use anyhow::{Result, anyhow};
use flatland_geom::{Role, Scene};
use flatland_solve::Reference;
use kernel_fit::Fit;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

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

/// The five panels of a finished fit, as PNG bytes in [`PANELS`] order.
pub fn panels(
    fit: &Fit,
    reference: &Reference,
    label: &str,
    log: bool,
) -> Result<Vec<(&'static str, Vec<u8>)>> {
    let res = reference.res();
    let exact = reference.grid();
    let approx = reference.approximate_grid(fit.model());
    let error: Vec<f64> = approx
        .iter()
        .zip(exact)
        .map(|(a, e)| (a - e).abs())
        .collect();
    let top = Scale::fit(exact, log).top;
    let scene = fit.kernel().scene();
    let cells: Vec<Option<[f64; 2]>> = fit.cell_st();
    let edges = fit.network().edges();
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
        cells.len()
    );
    let overlay = Overlay {
        cells: &cells,
        edges: &edges,
    };
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
            heatmap_png(&approx, res, &panel("learned ζ", "learned ζ", None))?,
        ),
        (
            PANELS[4],
            heatmap_png(&error, res, &panel("|learned - exact|", "|error|", None))?,
        ),
    ])
}

/// The scene: emitters yellow, surfaces grey, blockers red; a tick on each edge's front side.
fn geometry(scene: &Scene, label: &str) -> Result<Vec<u8>> {
    register_font();
    let (lo, hi) = scene.bounds();
    let pad = 0.05 * (hi - lo).max_element();
    let (w, h) = (800u32, 800u32);
    let span = (hi - lo).max_element() + 2.0 * pad;
    let centre = (lo + hi) * 0.5;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        let err = |e: String| anyhow!("drawing the geometry: {e}");
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
