//! `flatland figure`: the paper's Fig. 3 panels as PNGs — geometry, kernel, cells, approximation
//! and error.

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, Result, anyhow};
use flatland_geom::{Role, Scene};
use kernel_fit::{Approximation, Fit, FitParams};
use plotters::prelude::*;

use super::SceneArgs;
use super::kernel::{normalise, top_value, viridis};
use crate::plot::{register_font, write_rgb_png};

/// Arguments of `flatland figure`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Cells of the fit shown.
    #[arg(long, default_value_t = FitParams::default().target_cells)]
    pub cells: usize,
    /// Seed of the fit.
    #[arg(long, default_value_t = FitParams::default().seed)]
    pub seed: u64,
    /// Resolution of the (s, t) panels in pixels.
    #[arg(long, default_value_t = 512)]
    pub res: usize,
    /// Colour the kernel panels by log10 over four decades.
    #[arg(long)]
    pub log: bool,
    /// Output folder.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Runs `flatland figure`.
pub fn run(args: &Args) -> Result<()> {
    anyhow::ensure!(
        (16..=4096).contains(&args.res),
        "--res must be in [16, 4096], got {}",
        args.res
    );
    let (kernel, label) = args.scene.kernel()?;
    let kernel = Arc::new(kernel);
    let params = FitParams {
        target_cells: args.cells,
        seed: args.seed,
        ..FitParams::default()
    };
    params.validate()?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating the output folder {}", args.out.display()))?;
    let reference = Arc::new(super::reference(&kernel, args.res, &params));
    let mut fit = Fit::new(Arc::clone(&kernel), Arc::clone(&reference), params)?;
    let summary = fit.run(10_000, |_| ControlFlow::Continue(()))?;

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
    let out = |name: &str| args.out.join(name);

    geometry(&out("a_geometry.png"), scene, &label)?;
    heatmap(&out("b_kernel.png"), exact, res, args.log, top, scene, None)?;
    let cells: Vec<Option<[f64; 2]>> = fit.cell_st();
    let edges = fit.network().edges();
    heatmap(
        &out("c_cells.png"),
        exact,
        res,
        args.log,
        top,
        scene,
        Some(Overlay {
            cells: &cells,
            edges: &edges,
        }),
    )?;
    heatmap(
        &out("d_approximation.png"),
        &approx,
        res,
        args.log,
        top,
        scene,
        None,
    )?;
    heatmap(&out("e_error.png"), &error, res, args.log, top, scene, None)?;
    println!(
        "{label}: {} cells, relative L2 grid {:.4} held out {:.4}; wrote a_geometry, b_kernel, \
         c_cells, d_approximation, e_error (.png) to {}",
        fit.basis_functions(),
        summary.errors.grid,
        summary.errors.heldout,
        args.out.display()
    );
    Ok(())
}

/// The network drawn over a kernel panel: cells at their re-projected (s, t), and its edges.
#[derive(Clone, Copy)]
struct Overlay<'a> {
    cells: &'a [Option<[f64; 2]>],
    edges: &'a [(usize, usize)],
}

/// A heat map of an R × R grid (row ↔ s, top to bottom; column ↔ t), surface-edge boundaries
/// marked on both axes, optionally the cells (re-projected to their mean (s, t)) and the
/// network's edges on top.
fn heatmap(
    path: &std::path::Path,
    grid: &[f64],
    res: usize,
    log: bool,
    top: f64,
    scene: &Scene,
    overlay: Option<Overlay<'_>>,
) -> Result<()> {
    let side = res as u32;
    let dim = if overlay.is_some() { 0.55 } else { 1.0 };
    let mut rgb: Vec<u8> = normalise(grid, log, top)
        .into_iter()
        .flat_map(|v| viridis(v).map(|c| (f64::from(c) * dim) as u8))
        .collect();
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (side, side)).into_drawing_area();
        let err = |e: String| anyhow!("drawing {}: {e}", path.display());
        let px = |u: f64| (u * res as f64).round() as i32;
        let boundary = RGBColor(255, 255, 255).mix(0.35);
        for &e in scene.surface_edges() {
            if let Some((s0, _)) = scene.edge_param_range(e) {
                let p = px(s0);
                root.draw(&PathElement::new([(0, p), (res as i32, p)], boundary))
                    .map_err(|e| err(e.to_string()))?;
                root.draw(&PathElement::new([(p, 0), (p, res as i32)], boundary))
                    .map_err(|e| err(e.to_string()))?;
            }
        }
        if let Some(Overlay { cells, edges }) = overlay {
            let at = |c: usize| cells.get(c).copied().flatten().map(|[s, t]| (px(t), px(s)));
            for &(a, b) in edges {
                if let (Some(p), Some(q)) = (at(a), at(b)) {
                    root.draw(&PathElement::new([p, q], RGBColor(230, 230, 230).mix(0.8)))
                        .map_err(|e| err(e.to_string()))?;
                }
            }
            for c in 0..cells.len() {
                if let Some(p) = at(c) {
                    root.draw(&Circle::new(p, 3, RGBColor(255, 80, 60).filled()))
                        .map_err(|e| err(e.to_string()))?;
                }
            }
        }
        root.present().map_err(|e| err(e.to_string()))?;
    }
    write_rgb_png(path, &rgb, side, side)
}

/// The scene: emitters yellow, surfaces grey, blockers red; a tick on each edge's front side.
fn geometry(path: &std::path::Path, scene: &Scene, label: &str) -> Result<()> {
    register_font();
    let (lo, hi) = scene.bounds();
    let pad = 0.05 * (hi - lo).max_element();
    let (w, h) = (800u32, 800u32);
    let span = (hi - lo).max_element() + 2.0 * pad;
    let centre = (lo + hi) * 0.5;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        let err = |e: String| anyhow!("drawing {}: {e}", path.display());
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("{label}: geometry"), ("sans-serif", 22))
            .margin(10)
            .build_cartesian_2d(
                (centre.x - span / 2.0)..(centre.x + span / 2.0),
                (centre.y - span / 2.0)..(centre.y + span / 2.0),
            )
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
        root.present().map_err(|e| err(e.to_string()))?;
    }
    write_rgb_png(path, &rgb, w, h)
}
