//! `flatland figure`: the paper's Fig. 3 panels as PNGs — geometry, kernel, cells, approximation
//! and error.

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Result, anyhow};
use flatland_geom::{Role, Scene};
use kernel_fit::{Approximation, Fit, FitParams};
use plotters::prelude::*;

use super::SceneArgs;
use super::kernel::top_value;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::plot::{Heatmap, Overlay, encode_png, heatmap_png, register_font, short_number};
use crate::{interrupt, output};

/// Arguments of `flatland figure`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Which learner: `default` (the project's) or `paper` (the paper's network).
    #[arg(long, value_enum, default_value_t = super::fit::PresetArg::Default)]
    pub preset: super::fit::PresetArg,
    /// Cells of the fit shown.
    #[arg(long, default_value_t = FitParams::default().target_cells)]
    pub cells: usize,
    /// Seed of the fit.
    #[arg(long, default_value_t = FitParams::default().seed)]
    pub seed: u64,
    /// Resolution R of the (s, t) panels' grid, in [16, 4096].
    #[arg(long, default_value_t = 512)]
    pub res: usize,
    /// Colour the kernel panels by log10 over four decades.
    #[arg(long)]
    pub log: bool,
    /// Output folder.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

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

/// Runs `flatland figure`.
pub fn run(args: &Args) -> Result<()> {
    super::check_res(args.res)?;
    super::check_cells("--cells", args.cells)?;
    let (kernel, label) = args.scene.kernel()?;
    let kernel = Arc::new(kernel);
    let params = FitParams {
        target_cells: args.cells,
        seed: args.seed,
        ..args.preset.preset().params()
    };
    params.validate()?;
    output::folder(
        &args.out,
        &PANELS,
        &args.scene.path().into_iter().collect::<Vec<_>>(),
    )?;
    let reference = Arc::new(super::reference(&kernel, args.res, &params));
    let mut fit = Fit::new(Arc::clone(&kernel), Arc::clone(&reference), params)?;
    eprintln!(
        "figure of {label}: fitting {} cells (Ctrl-C stops; nothing is written before the fit ends)",
        args.cells
    );
    fit.train(1000, |_| {
        if interrupt::requested() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    interrupt::check()?;
    let summary = fit.finish()?;
    interrupt::check()?;

    let res = args.res;
    let exact = reference.grid();
    let approx = reference.approximate_grid(fit.model());
    let error: Vec<f64> = approx
        .iter()
        .zip(exact)
        .map(|(a, e)| (a - e).abs())
        .collect();
    let top = top_value(exact);
    let scene = kernel.scene();
    let cells: Vec<Option<[f64; 2]>> = fit.cell_st();
    let edges = fit.network().edges();
    let panel = |title: &str, quantity: &'static str, overlay| Heatmap {
        title: format!("{label}: {title}"),
        quantity,
        scene,
        log: args.log,
        top,
        overlay,
    };
    let cells_title = format!(
        "{} cells at the mean (s, t) of the samples they won",
        cells.len()
    );
    let pictures: Vec<(&str, Vec<u8>)> = vec![
        (PANELS[0], geometry(scene, &label)?),
        (
            PANELS[1],
            heatmap_png(exact, res, &panel("exact ζ", "ζ", None))?,
        ),
        (
            PANELS[2],
            heatmap_png(
                exact,
                res,
                &panel(
                    &cells_title,
                    "ζ",
                    Some(Overlay {
                        cells: &cells,
                        edges: &edges,
                    }),
                ),
            )?,
        ),
        (
            PANELS[3],
            heatmap_png(&approx, res, &panel("learned ζ", "learned ζ", None))?,
        ),
        (
            PANELS[4],
            heatmap_png(&error, res, &panel("|learned - exact|", "|error|", None))?,
        ),
    ];
    for (i, (name, png)) in pictures.iter().enumerate() {
        interrupt::check()?;
        interrupt::writing(|| flatland_geom::write_atomic(&args.out.join(name), png))?;
        interrupt::keep(format!(
            "{} of the {} panels written to {}",
            i + 1,
            PANELS.len(),
            args.out.display()
        ));
    }
    let defined = super::Defined::of(&reference);
    println!(
        "{label}: {} cells, relative L2 {}; wrote a_geometry, b_kernel, c_cells, \
         d_approximation, e_error (.png) to {}",
        fit.basis_functions(),
        defined.format(&summary.errors),
        args.out.display()
    );
    Ok(())
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
                let edge = scene.edges()[e];
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
