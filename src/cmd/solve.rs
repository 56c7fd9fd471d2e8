//! `flatland solve`: light the scene — solve `B = E + K B` with a kernel representation and
//! compare the solved radiosity with the exact kernel's.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use flatland_geom::{Kernel, Role, Scene, write_atomic};
use kernel_fit::baselines::{BlockValue, HrParams, UniformParams, run_hr_at_budget, run_uniform};
use kernel_fit::solve::{
    Comparison, ExactReference, KernelRepresentation, Mesh, SolveParams, Stop, solve_against,
};
use kernel_fit::{Fit, FitError, ModelFile};
use plotters::prelude::*;

use super::SceneArgs;
use crate::interrupt;
use crate::plot::{register_font, write_rgb_png};

/// Arguments of `flatland solve`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The kernel: `exact`, `sgcs` (fit the default learner with --basis cells), `hr`,
    /// `uniform` (20 rays per block), `uniform-exact` (exact block means of k), or a model file
    /// (.json) written by `flatland fit --out`.
    #[arg(long, value_name = "KERNEL", default_value = "exact")]
    pub kernel: String,
    /// Basis functions of the representation built: cells (sgcs), links (hr), blocks (uniform).
    #[arg(long, value_name = "N", default_value_t = 400)]
    pub basis: usize,
    /// Elements of the solve (default: chosen from the scene, 512 for the bundled scenes).
    #[arg(long, value_name = "N")]
    pub elements: Option<usize>,
    /// Elements of the exact reference solve the errors are measured against
    /// (default: 4 × elements, at least 2048, at most 8192).
    #[arg(long, value_name = "N")]
    pub reference_elements: Option<usize>,
    /// Seed of the fit or baseline built.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the solution: `.csv` (header `edge,s,x,y,b`, one row per element midpoint in
    /// order of s) or `.png` (the lit scene beside B(s) against the exact solution).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print one JSON object with the figures instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// What `--kernel` names.
#[derive(Clone, Debug, PartialEq)]
enum Choice {
    Exact,
    Sgcs,
    Hr,
    Uniform,
    UniformExact,
    Model(PathBuf),
}

impl Choice {
    fn parse(text: &str) -> Result<Choice> {
        Ok(match text {
            "exact" => Choice::Exact,
            "sgcs" => Choice::Sgcs,
            "hr" => Choice::Hr,
            "uniform" => Choice::Uniform,
            "uniform-exact" => Choice::UniformExact,
            _ if Path::new(text)
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("json")) =>
            {
                Choice::Model(PathBuf::from(text))
            }
            _ => bail!(
                "--kernel `{text}` is not known: expected exact, sgcs, hr, uniform, uniform-exact \
                 or a model file (.json) written by `flatland fit --out`"
            ),
        })
    }

    fn label(&self) -> String {
        match self {
            Choice::Exact => "exact".into(),
            Choice::Sgcs => "sgcs".into(),
            Choice::Hr => "hr".into(),
            Choice::Uniform => "uniform".into(),
            Choice::UniformExact => "uniform-exact".into(),
            Choice::Model(path) => path.display().to_string(),
        }
    }
}

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Output {
    Csv,
    Png,
}

fn output_of(path: &Path) -> Result<Output> {
    let output = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("csv") => Output::Csv,
        Some("png") => Output::Png,
        _ => bail!(
            "{}: unknown output format (expected a .csv or .png file name)",
            path.display()
        ),
    };
    Ok(output)
}

/// A built representation and what building it cost.
struct Built {
    rep: Box<dyn KernelRepresentation>,
    build_s: f64,
}

/// Runs `flatland solve`.
pub fn run(args: &Args) -> Result<()> {
    let output = args.out.as_deref().map(output_of).transpose()?;
    let choice = Choice::parse(&args.kernel)?;
    if let Some(out) = &args.out {
        let mut inputs: Vec<&Path> = args.scene.scene.iter().map(PathBuf::as_path).collect();
        if let Choice::Model(model) = &choice {
            inputs.push(model);
        }
        crate::output::file(out, &inputs)?;
    }
    if choice != Choice::Exact && args.basis == 0 {
        bail!("--basis must be at least 1, got 0");
    }
    let (scene, label) = scene_for(args, &choice)?;
    let kernel = Kernel::new(scene.clone());
    let elements = args
        .elements
        .unwrap_or_else(|| Mesh::default_elements(&scene));
    let mesh = Mesh::new(&kernel, elements).context("--elements")?;
    let reference_elements = args
        .reference_elements
        .unwrap_or_else(|| ExactReference::default_elements(elements));
    let params = SolveParams::default();
    // Check the reference size before the (maybe long) build of the representation.
    Mesh::new(&kernel, reference_elements).context("--reference-elements")?;

    // Every long loop below polls Ctrl-C; nothing is written before the end.
    let stop: &Stop = &interrupt::requested;
    let interrupted = |e: FitError| -> anyhow::Error {
        match e {
            FitError::Interrupted => interrupt::stopped().into(),
            other => other.into(),
        }
    };
    let built = build(&choice, &kernel, args)?;
    interrupt::check()?;
    let reference = ExactReference::new(&kernel, reference_elements, &params, stop)
        .map_err(interrupted)
        .context("the exact reference solve")?;
    let exact = reference.radiosity_on(&mesh, stop).map_err(interrupted)?;
    let comparison = solve_against(built.rep.as_ref(), &mesh, &exact, &params, stop)
        .map_err(interrupted)
        .with_context(|| format!("solving with the {} kernel", choice.label()))?;
    interrupt::check()?;

    if let (Some(path), Some(output)) = (&args.out, output) {
        match output {
            Output::Csv => interrupt::writing(|| {
                write_atomic(path, csv(&mesh, &comparison.solution.radiosity).as_bytes())
            })?,
            Output::Png => lit_scene_png(
                path,
                &Picture {
                    scene: &scene,
                    label: &label,
                    kernel: &choice.label(),
                    mesh: &mesh,
                    b: &comparison.solution.radiosity,
                    reference: &reference,
                    rel_l2_reflected: comparison.errors.rel_l2_reflected,
                },
            )?,
        }
    }
    let basis = built.rep.basis_functions();
    if args.json {
        println!(
            "{}",
            summary_json(
                &label,
                &choice,
                &mesh,
                reference_elements,
                basis,
                &comparison,
                built.build_s
            )
        );
    } else {
        print_summary(
            &label,
            &choice,
            &mesh,
            reference_elements,
            basis,
            &comparison,
            built.build_s,
        );
        if let Some(path) = &args.out {
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// The scene to solve: `--scene` (subdivided), or a model's own scene when none is given.
fn scene_for(args: &Args, choice: &Choice) -> Result<(Scene, String)> {
    let Choice::Model(path) = choice else {
        return args.scene.load();
    };
    let file = ModelFile::load(path)?;
    match &args.scene.scene {
        Some(scene_path) => {
            let (scene, label) = args.scene.load()?;
            file.check_scene(&scene, scene_path)?;
            Ok((scene, label))
        }
        None => Ok((
            file.model.scene().clone(),
            format!("{} (model's scene)", path.display()),
        )),
    }
}

/// Builds the representation `choice` names (fits, baselines) on `kernel`.
fn build(choice: &Choice, kernel: &Kernel, args: &Args) -> Result<Built> {
    let started = Instant::now();
    let rep: Box<dyn KernelRepresentation> = match choice {
        Choice::Exact => Box::new(Kernel::new(kernel.scene().clone())),
        Choice::Model(path) => Box::new(ModelFile::load(path)?.model),
        Choice::Hr => {
            Box::new(run_hr_at_budget(kernel, args.basis, args.seed, &HrParams::default())?.approx)
        }
        Choice::Uniform => {
            Box::new(run_uniform(kernel, args.basis, args.seed, &UniformParams::default())?.approx)
        }
        Choice::UniformExact => {
            let params = UniformParams {
                block_value: BlockValue::ExactKernelMean,
                ..UniformParams::default()
            };
            Box::new(run_uniform(kernel, args.basis, args.seed, &params)?.approx)
        }
        Choice::Sgcs => {
            // Exactly what `flatland fit --cells N --seed S` fits.
            let mut fit_args = super::fit::Args::for_scene(None);
            fit_args.cells = args.basis;
            fit_args.seed = args.seed;
            let fit_params = fit_args.params()?;
            fit_params.validate().context("--basis")?;
            let kernel = Arc::new(Kernel::new(kernel.scene().clone()));
            // The fit's own errors are not reported here: a small reference will do.
            let reference = Arc::new(super::reference(&kernel, 16, &fit_params));
            let mut fit = Fit::new(kernel, reference, fit_params)?;
            let bar = super::progress_bar(fit_params.target_cells as u64, "cells");
            fit.train(1000, |f| {
                bar.set_position(f.network().len() as u64);
                if interrupt::requested() {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            });
            bar.finish_and_clear();
            interrupt::check()?;
            if fit_params.refit {
                fit.refit()?;
            }
            Box::new(fit.model().clone())
        }
    };
    Ok(Built {
        rep,
        build_s: started.elapsed().as_secs_f64(),
    })
}

/// `edge,s,x,y,b`: one row per element midpoint, in order of s (shortest round-trip decimals).
fn csv(mesh: &Mesh, b: &[f64]) -> String {
    let mut out = String::from("edge,s,x,y,b\n");
    for (e, value) in mesh.elements().iter().zip(b) {
        out.push_str(&format!(
            "{},{},{},{},{}\n",
            e.edge, e.s_mid, e.midpoint.x, e.midpoint.y, value
        ));
    }
    out
}

/// The `--json` object.
fn summary_json(
    scene: &str,
    choice: &Choice,
    mesh: &Mesh,
    reference_elements: usize,
    basis: Option<usize>,
    c: &Comparison,
    build_s: f64,
) -> serde_json::Value {
    serde_json::json!({
        "scene": scene,
        "kernel": choice.label(),
        "elements": mesh.len(),
        "basis_functions": basis,
        "rel_l2_b": c.errors.rel_l2_b,
        "rel_l2_reflected": c.errors.rel_l2_reflected,
        "iterations": c.solution.iterations,
        "residual": c.solution.residual,
        "wall_s": c.solution.wall_s(),
        "build_s": build_s,
        "reference_elements": reference_elements,
    })
}

/// The human-readable summary.
fn print_summary(
    scene: &str,
    choice: &Choice,
    mesh: &Mesh,
    reference_elements: usize,
    basis: Option<usize>,
    c: &Comparison,
    build_s: f64,
) {
    let row = |k: &str, v: String| println!("  {k:<26} {v}");
    println!("solve of {scene} with the {} kernel", choice.label());
    row(
        "basis functions",
        basis.map_or_else(|| "exact (none)".to_owned(), |b| b.to_string()),
    );
    row(
        "elements",
        format!("{} (exact reference: {reference_elements})", mesh.len()),
    );
    row("rel. L2 of B", format!("{:.5}", c.errors.rel_l2_b));
    row(
        "rel. L2 of B − E",
        format!("{:.5}   (the reflected part)", c.errors.rel_l2_reflected),
    );
    row(
        "iterations",
        format!(
            "{} (residual {:.1e})",
            c.solution.iterations, c.solution.residual
        ),
    );
    row(
        "wall time",
        format!(
            "{:.3} s (operator {:.3} s, linear solve {:.3} s)",
            c.solution.wall_s(),
            c.solution.assembly_s,
            c.solution.solve_s
        ),
    );
    row("building the kernel", format!("{build_s:.3} s"));
}

// ----- the picture -----

/// What the PNG shows.
struct Picture<'a> {
    scene: &'a Scene,
    label: &'a str,
    kernel: &'a str,
    mesh: &'a Mesh,
    b: &'a [f64],
    reference: &'a ExactReference,
    rel_l2_reflected: f64,
}

const WIDTH: u32 = 1600;
const HEIGHT: u32 = 760;
const SCENE_WIDTH: u32 = 760;

fn inferno(x: f64) -> RGBColor {
    let [r, g, b] = kernel_fit::colormap::inferno(x);
    RGBColor(r, g, b)
}

/// The brightest non-emitting element (emitters are drawn above the scale): the top colour.
fn colour_top(mesh: &Mesh, b: &[f64]) -> f64 {
    let lit = (0..mesh.len())
        .filter(|&i| mesh.edge_of(i).emission == 0.0)
        .map(|i| b[i])
        .fold(0.0_f64, f64::max);
    if lit > 0.0 {
        lit
    } else {
        b.iter().copied().fold(0.0_f64, f64::max).max(1e-300)
    }
}

fn lit_scene_png(path: &Path, p: &Picture<'_>) -> Result<()> {
    register_font();
    let mut rgb = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        let (left, right) = root.split_horizontally(SCENE_WIDTH);
        draw_scene(&left, p).map_err(|e| anyhow!("drawing the lit scene: {e}"))?;
        draw_curves(&right, p).map_err(|e| anyhow!("drawing B(s): {e}"))?;
        root.present()
            .map_err(|e| anyhow!("drawing {}: {e}", path.display()))?;
    }
    write_rgb_png(path, &rgb, WIDTH, HEIGHT)
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;
type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// Each element in the colour of its B, blockers grey, emitters marked, a colour bar.
fn draw_scene(area: &Area<'_>, p: &Picture<'_>) -> DrawResult {
    let (plot, bar) = area.split_horizontally(SCENE_WIDTH - 110);
    let (lo, hi) = p.scene.bounds();
    let span = (hi - lo).max_element() * 1.1;
    let centre = (lo + hi) * 0.5;
    let mut chart = ChartBuilder::on(&plot)
        .caption(
            format!("{}: lit by the {} kernel", p.label, p.kernel),
            ("sans-serif", 20),
        )
        .margin(12)
        .build_cartesian_2d(
            (centre.x - span / 2.0)..(centre.x + span / 2.0),
            (centre.y - span / 2.0)..(centre.y + span / 2.0),
        )?;
    let top = colour_top(p.mesh, p.b);
    for edge in p.scene.edges().iter().filter(|e| e.role == Role::Blocker) {
        chart.draw_series(LineSeries::new(
            [(edge.a.x, edge.a.y), (edge.b.x, edge.b.y)],
            RGBColor(140, 140, 140).stroke_width(3),
        ))?;
    }
    for (e, &b) in p.mesh.elements().iter().zip(p.b) {
        chart.draw_series(LineSeries::new(
            [(e.a.x, e.a.y), (e.b.x, e.b.y)],
            inferno(b / top).stroke_width(8),
        ))?;
    }
    // Emitters: a sun on the front side of each, with its emission.
    for edge in p.mesh.edges().iter().filter(|e| e.emission > 0.0) {
        let mid = (edge.a + edge.b) * 0.5;
        let sign = if edge.two_sided { 0.0 } else { 1.0 };
        let at = mid + edge.normal * (0.045 * span * sign);
        let at = (at.x, at.y);
        chart.draw_series([Circle::new(at, 9, RGBColor(255, 200, 0).filled())])?;
        chart.draw_series([Circle::new(at, 9, BLACK.stroke_width(1))])?;
        let text = format!("E = {}", edge.emission);
        chart.draw_series([Text::new(
            text,
            (at.0 + 0.025 * span, at.1 + 0.01 * span),
            ("sans-serif", 16).into_font(),
        )])?;
    }
    // The colour bar: 0 at the bottom, the brightest non-emitter at the top.
    let (_, h) = bar.dim_in_pixel();
    let (x0, y0, bar_h) = (20_i32, (h as i32) / 5, (h as i32) * 3 / 5);
    for k in 0..bar_h {
        let v = 1.0 - f64::from(k) / f64::from(bar_h - 1);
        bar.draw(&Rectangle::new(
            [(x0, y0 + k), (x0 + 24, y0 + k + 1)],
            inferno(v).filled(),
        ))?;
    }
    bar.draw(&Rectangle::new(
        [(x0, y0), (x0 + 24, y0 + bar_h)],
        BLACK.stroke_width(1),
    ))?;
    let font = ("sans-serif", 15).into_font();
    for (frac, value) in [(0.0, 0.0), (0.5, 0.5 * top), (1.0, top)] {
        let y = y0 + ((1.0 - frac) * f64::from(bar_h)) as i32;
        bar.draw(&PathElement::new([(x0 + 24, y), (x0 + 30, y)], BLACK))?;
        bar.draw(&Text::new(
            format!("{value:.3}"),
            (x0 + 33, y - 7),
            font.clone(),
        ))?;
    }
    bar.draw(&Text::new(
        "B",
        (x0 + 6, y0 - 28),
        ("sans-serif", 18).into_font(),
    ))?;
    bar.draw(&Text::new(
        "emitters",
        (x0 - 12, y0 + bar_h + 14),
        ("sans-serif", 13).into_font(),
    ))?;
    bar.draw(&Text::new(
        "above scale",
        (x0 - 12, y0 + bar_h + 30),
        ("sans-serif", 13).into_font(),
    ))?;
    Ok(())
}

/// The B axis of the curves: emitters are 10–100× brighter than what they light, so the axis
/// stops above the brightest non-emitter (emitters' values are written where they leave the
/// plot); a poor kernel can give negative radiosity, shown down to a quarter of the range.
fn curve_range(p: &Picture<'_>) -> (f64, f64) {
    let (fine, exact) = (p.reference.mesh(), &p.reference.solution().radiosity);
    let lit = |mesh: &Mesh, b: &[f64]| {
        (0..mesh.len())
            .filter(|&i| mesh.edge_of(i).emission == 0.0)
            .map(|i| b[i])
            .fold(0.0_f64, f64::max)
    };
    let mut y_max = lit(p.mesh, p.b).max(lit(fine, exact)) * 1.25;
    if y_max <= 0.0 || !y_max.is_finite() {
        y_max =
            p.b.iter()
                .chain(exact)
                .copied()
                .fold(0.0_f64, f64::max)
                .max(1e-300)
                * 1.08;
    }
    let lowest = p.b.iter().copied().fold(0.0_f64, f64::min);
    let y_min = lowest.max(-0.25 * y_max);
    (y_min, y_max)
}

/// B(s): the solution as steps, the exact reference as a line, emitters shaded, edges marked.
fn draw_curves(area: &Area<'_>, p: &Picture<'_>) -> DrawResult {
    let fine = p.reference.mesh();
    let exact = &p.reference.solution().radiosity;
    let (y_min, y_max) = curve_range(p);
    let clip = |b: f64| b.clamp(y_min, y_max);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!(
                "B(s): {} kernel on {} elements vs exact on {} (rel. L2 of B − E: {:.2} %)",
                p.kernel,
                p.mesh.len(),
                fine.len(),
                100.0 * p.rel_l2_reflected
            ),
            ("sans-serif", 18),
        )
        .margin(14)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(0.0..1.0, y_min..y_max)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("s (arc length / L)")
        .y_desc("radiosity B")
        .label_style(("sans-serif", 15))
        .draw()?;
    for edge in p.mesh.edges() {
        if edge.emission > 0.0 {
            chart.draw_series([Rectangle::new(
                [(edge.s[0], y_min), (edge.s[1], y_max)],
                RGBColor(255, 215, 80).mix(0.25).filled(),
            )])?;
        }
        chart.draw_series(LineSeries::new(
            [(edge.s[0], y_min), (edge.s[0], y_max)],
            RGBColor(200, 200, 200).stroke_width(1),
        ))?;
    }
    for edge in fine.edges() {
        let points: Vec<(f64, f64)> = edge
            .elements
            .clone()
            .map(|i| (fine.elements()[i].s_mid, clip(exact[i])))
            .collect();
        chart.draw_series(LineSeries::new(points, BLACK.stroke_width(2)))?;
    }
    let solution = RGBColor(220, 80, 30);
    for edge in p.mesh.edges() {
        // Steps, joined within an edge.
        let steps: Vec<(f64, f64)> = edge
            .elements
            .clone()
            .flat_map(|i| {
                let e = &p.mesh.elements()[i];
                [(e.s[0], clip(p.b[i])), (e.s[1], clip(p.b[i]))]
            })
            .collect();
        chart.draw_series(LineSeries::new(steps, solution.stroke_width(2)))?;
    }
    for edge in p.mesh.edges().iter().filter(|e| e.emission > 0.0) {
        let range = edge.elements.clone();
        let mean = range.clone().map(|i| p.b[i]).sum::<f64>() / range.len().max(1) as f64;
        if mean > y_max {
            chart.draw_series([Text::new(
                format!("B = {mean:.3} (off the axis)"),
                (edge.s[0], y_max * 0.97),
                ("sans-serif", 14).into_font(),
            )])?;
        }
    }
    // Legend entries drawn by hand (one per kind, not one per segment).
    chart
        .draw_series(LineSeries::new(std::iter::empty(), BLACK.stroke_width(2)))?
        .label(format!("exact kernel, {} elements", fine.len()))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 22, y)], BLACK.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(
            std::iter::empty(),
            solution.stroke_width(2),
        ))?
        .label(format!("{} kernel, {} elements", p.kernel, p.mesh.len()))
        .legend(move |(x, y)| PathElement::new([(x, y), (x + 22, y)], solution.stroke_width(2)));
    chart
        .draw_series([Rectangle::new(
            [(0.0, 0.0), (0.0, 0.0)],
            RGBColor(255, 215, 80).mix(0.25).filled(),
        )])?
        .label("emitters")
        .legend(|(x, y)| {
            Rectangle::new(
                [(x, y - 6), (x + 22, y + 6)],
                RGBColor(255, 215, 80).mix(0.5).filled(),
            )
        });
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 15))
        .draw()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_choices_parse_and_unknown_ones_are_named() {
        assert_eq!(Choice::parse("exact").unwrap(), Choice::Exact);
        assert_eq!(
            Choice::parse("uniform-exact").unwrap(),
            Choice::UniformExact
        );
        assert_eq!(
            Choice::parse("runs/m.JSON").unwrap(),
            Choice::Model(PathBuf::from("runs/m.JSON"))
        );
        let err = Choice::parse("sgsc").unwrap_err().to_string();
        assert!(
            err.contains("`sgsc`") && err.contains("exact, sgcs, hr"),
            "{err}"
        );
    }

    #[test]
    fn inferno_runs_from_black_to_pale_yellow() {
        assert_eq!(inferno(0.0), RGBColor(0, 0, 4));
        assert_eq!(inferno(1.0), RGBColor(252, 255, 164));
        assert_eq!(inferno(f64::NAN), inferno(0.0));
        assert_eq!(inferno(7.0), inferno(1.0));
    }
}
