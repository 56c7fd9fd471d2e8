//! `flatland solve`: light the scene — solve `B = E + K B` with a kernel representation and
//! compare the solved radiosity with the exact kernel's.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use flatland_baselines::{
    BlockValue, ClusteredParams, DEFAULT_LINKS_PER_EDGE, HrParams, UniformParams, run_clustered,
    run_hr_at_budget, run_uniform,
};
use flatland_geom::{Kernel, Scene, write_atomic};
use flatland_light::{LightError, LightFit, LightParams, LightStop};
use flatland_solve::{
    Comparison, DEFAULT_ERROR_BOUND, Discretization, ErrorEstimate, ExactMethod, ExactReference,
    Mesh, Representation, SolveError, SolveParams, Stop, elements_for_error, solve_against,
};
use kernel_fit::{Fit, ModelFile};

use super::SceneArgs;
use flatland_lab::interrupt;

/// Arguments of `flatland solve`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The kernel: `exact`, `default` (the light-driven learner: rounds of solving and
    /// learning on this mesh until --tolerance; `sgcs` is the same), `first-shot` (the
    /// θ-driven learner `flatland fit` trains, weighted by the first shot, with --basis
    /// cells), `hr`, `clustered` (HR with clustering: no initial linking, refined from one
    /// link of the root cluster with itself), `uniform` (20 rays per block), `uniform-exact`
    /// (exact block means of k), or a model file (.json) written by `flatland fit --out`.
    #[arg(long, value_name = "KERNEL", default_value = "exact")]
    pub kernel: String,
    /// Basis functions of the representation built: links (hr, clustered), blocks (uniform),
    /// cells (first-shot); default 400 for these, except clustered: 100 links per edge of the
    /// scene. For the default learner, the most cells it may grow (default: as many as the
    /// tolerance takes).
    #[arg(long, value_name = "N")]
    pub basis: Option<usize>,
    /// The default learner stops when its own estimate of the relative L2 error of the
    /// solved B − E is at most this, in (0, 1).
    #[arg(long, value_name = "X", default_value_t = LightParams::default().tolerance)]
    pub tolerance: f64,
    /// Elements of the solve (default: the fewest, doubling from the scene's minimum and at
    /// least 512, whose estimated discretization error of B − E is below 1 %; 512 for the
    /// bundled scenes).
    #[arg(long, value_name = "N")]
    pub elements: Option<usize>,
    /// Elements of the exact reference solve the errors are measured against (default:
    /// 2 × elements, the finer solve the discretization error is estimated from, so it costs
    /// nothing more; at most 8192 on small scenes, whose exact operator is dense).
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

/// `--basis` of the baselines and of `first-shot` when none is given.
const DEFAULT_BASIS: usize = 400;

/// What `--kernel` names.
#[derive(Clone, Debug, PartialEq)]
enum Choice {
    Exact,
    /// The default learner: light-driven rounds on the solve's mesh.
    Default,
    /// The θ-driven learner of `flatland fit`.
    FirstShot,
    Hr,
    /// Hierarchical radiosity with clustering.
    Clustered,
    Uniform,
    UniformExact,
    Model(PathBuf),
}

impl Choice {
    fn parse(text: &str) -> Result<Choice> {
        Ok(match text {
            "exact" => Choice::Exact,
            // `sgcs` was the default learner's name before it was called so.
            "default" | "sgcs" => Choice::Default,
            "first-shot" => Choice::FirstShot,
            "hr" => Choice::Hr,
            "clustered" => Choice::Clustered,
            "uniform" => Choice::Uniform,
            "uniform-exact" => Choice::UniformExact,
            _ if Path::new(text)
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("json")) =>
            {
                Choice::Model(PathBuf::from(text))
            }
            _ => bail!(
                "--kernel `{text}` is not known: expected exact, default, hr, clustered, uniform, \
                 uniform-exact, first-shot or a model file (.json) written by `flatland fit --out`"
            ),
        })
    }

    fn label(&self) -> String {
        match self {
            Choice::Exact => "exact".into(),
            Choice::Default => "default".into(),
            Choice::FirstShot => "first-shot".into(),
            Choice::Hr => "hr".into(),
            Choice::Clustered => "clustered".into(),
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

/// A built representation, what building it cost, and the baseline's note when it built a
/// count other than `--basis` (HR below its initial linking, a grid that is not square).
struct Built {
    rep: Box<dyn Representation>,
    build_s: f64,
    note: Option<String>,
    /// What the default learner says of itself.
    learned: Option<Learned>,
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
        flatland_lab::output::file(out, &inputs)?;
    }
    if choice != Choice::Exact && args.basis == Some(0) {
        bail!("--basis must be at least 1, got 0");
    }
    let (scene, label) = scene_for(args, &choice)?;
    let kernel = Kernel::new(scene.clone());
    let params = SolveParams::default();
    // Check the sizes asked for before any (maybe long) solve or build.
    if let Some(elements) = args.elements {
        check_elements(&kernel, elements).context("--elements")?;
    }
    if let Some(reference_elements) = args.reference_elements {
        check_elements(&kernel, reference_elements).context("--reference-elements")?;
    }

    // Every long loop below polls Ctrl-C; nothing is written before the end.
    let stop: &Stop = &interrupt::requested;
    let interrupted = |e: SolveError| -> anyhow::Error {
        match e {
            SolveError::Interrupted => interrupt::stopped().into(),
            other => other.into(),
        }
    };
    let found = discretization(&kernel, args.elements, &params, stop)
        .map_err(interrupted)
        .context("estimating the discretization error of the exact solve")?;
    let discretization = found.estimate;
    let mesh = found.coarse.mesh().clone();
    let built = build(&choice, &kernel, &mesh, args, stop)?;
    interrupt::check()?;
    // The reference: the finer solve the estimate was made with, unless another is asked for.
    let (reference, exact) = match args.reference_elements {
        Some(n) if n != found.finer.mesh().len() => {
            let reference = ExactReference::new(&kernel, n, &params, stop)
                .map_err(interrupted)
                .context("the exact reference solve")?;
            let exact = reference.radiosity_on(&mesh, stop).map_err(interrupted)?;
            (reference, exact)
        }
        _ => (found.finer, found.finer_on_coarse),
    };
    let reference_elements = reference.mesh().len();
    let comparison = solve_against(built.rep.as_ref(), &mesh, &exact, &params, stop)
        .map_err(interrupted)
        .with_context(|| format!("solving with the {} kernel", choice.label()))?;
    interrupt::check()?;

    if let (Some(path), Some(output)) = (&args.out, output) {
        match output {
            Output::Csv => interrupt::writing(|| {
                write_atomic(path, csv(&mesh, &comparison.solution.radiosity).as_bytes())
            })?,
            Output::Png => flatland_lab::report::lit::lit_scene_png(
                path,
                &flatland_lab::report::lit::Picture {
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
    let summary = Summary {
        scene: &label,
        choice: &choice,
        mesh: &mesh,
        reference_elements,
        basis: built.rep.basis_functions(),
        kernel_bytes: built.rep.memory_bytes(),
        comparison: &comparison,
        build_s: built.build_s,
        note: built.note.as_deref(),
        learned: built.learned.as_ref(),
        discretization: &discretization,
    };
    if args.json {
        println!("{}", summary.json());
    } else {
        summary.print();
        if let Some(path) = &args.out {
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// Refuses an element count no mesh, or no exact operator of this scene, can have.
fn check_elements(kernel: &Kernel, elements: usize) -> Result<(), SolveError> {
    ExactMethod::of(kernel).check(elements)?;
    Mesh::new(kernel, elements).map(|_| ())
}

/// The exact solve on `elements` with the solve on twice as many its discretization error is
/// estimated from, or, without a count, the fewest elements whose estimate is below 1 %.
fn discretization(
    kernel: &Kernel,
    elements: Option<usize>,
    params: &SolveParams,
    stop: &Stop,
) -> Result<Discretization, SolveError> {
    match elements {
        Some(n) => Discretization::of(
            ExactReference::new(kernel, n, params, stop)?,
            kernel,
            params,
            stop,
        ),
        None => elements_for_error(kernel, DEFAULT_ERROR_BOUND, params, stop),
    }
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

/// The default learner's account of its fit.
struct Learned {
    /// Its estimate of the relative L2 error of the solved `B − E`.
    estimated_error: f64,
    rounds: usize,
    /// Probes: exact views swept (its cells).
    probes: usize,
    stopped: LightStop,
}

/// Builds the representation `choice` names (fits, baselines) on `kernel`; the default
/// learner learns on `mesh`, the solve's.
fn build(choice: &Choice, kernel: &Kernel, mesh: &Mesh, args: &Args, stop: &Stop) -> Result<Built> {
    let started = Instant::now();
    let mut note = None;
    let mut learned = None;
    let basis = args.basis.unwrap_or(DEFAULT_BASIS);
    let rep: Box<dyn Representation> = match choice {
        Choice::Exact => Box::new(Kernel::new(kernel.scene().clone())),
        Choice::Model(path) => Box::new(ModelFile::load(path)?.model),
        Choice::Hr => {
            let run = run_hr_at_budget(kernel, basis, args.seed, &HrParams::default())?;
            note = run.note.map(|n| n.to_string());
            Box::new(run.approx)
        }
        Choice::Clustered => {
            // Clustered HR has no initial linking to set its floor: its default follows the
            // scene, as HR's does through that linking.
            let edges = kernel.scene().edges().len();
            let links = args.basis.unwrap_or(DEFAULT_LINKS_PER_EDGE * edges);
            let run = run_clustered(kernel, links, args.seed, &ClusteredParams::default())?;
            note = run.note.map(|n| n.to_string());
            Box::new(run.approx)
        }
        Choice::Uniform | Choice::UniformExact => {
            let params = UniformParams {
                block_value: if *choice == Choice::Uniform {
                    BlockValue::Rays
                } else {
                    BlockValue::ExactKernelMean
                },
                ..UniformParams::default()
            };
            let run = run_uniform(kernel, basis, args.seed, &params)?;
            note = run.note.map(|n| n.to_string());
            Box::new(run.approx)
        }
        Choice::Default => {
            let (fit, summary) = learn(kernel, mesh, args, stop)?;
            learned = Some(summary);
            Box::new(fit)
        }
        Choice::FirstShot => {
            // Exactly what `flatland fit --cells N --seed S` fits.
            let mut fit_args = super::fit::Args::for_scene(None);
            fit_args.cells = basis;
            fit_args.seed = args.seed;
            let fit_params = fit_args.params()?;
            fit_params.validate().context("--basis")?;
            let kernel = Arc::new(Kernel::new(kernel.scene().clone()));
            // The fit's own errors are not reported here: a small reference will do.
            let reference = Arc::new(flatland_lab::reference(&kernel, 16, &fit_params));
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
            fit.finish()?;
            Box::new(fit.model().clone())
        }
    };
    Ok(Built {
        rep,
        build_s: started.elapsed().as_secs_f64(),
        note,
        learned,
    })
}

/// The default learner on the solve's mesh, to `--tolerance` or `--basis` cells.
fn learn(kernel: &Kernel, mesh: &Mesh, args: &Args, stop: &Stop) -> Result<(LightFit, Learned)> {
    let params = LightParams {
        tolerance: args.tolerance,
        max_cells: args.basis.unwrap_or(usize::MAX),
        ..LightParams::default()
    };
    params
        .check()
        .map_err(|e| anyhow::anyhow!("--tolerance: {e}"))?;
    let interrupted = |e: LightError| -> anyhow::Error {
        match e {
            LightError::Interrupted => interrupt::stopped().into(),
            other => other.into(),
        }
    };
    let kernel = Arc::new(Kernel::new(kernel.scene().clone()));
    let mut fit = LightFit::new(kernel, mesh.clone(), params, stop).map_err(interrupted)?;
    let bar = super::progress_bar(0, "cells");
    let stopped = fit
        .run(stop, |f| {
            bar.set_position(f.cells().len() as u64);
            if let Some(e) = f.estimated_error() {
                bar.set_message(format!("estimated error {e:.4}"));
            }
        })
        .map_err(interrupted)?;
    bar.finish_and_clear();
    let summary = Learned {
        estimated_error: fit.estimated_error().unwrap_or(f64::INFINITY),
        rounds: fit.history().len(),
        probes: fit.cells().len(),
        stopped,
    };
    Ok((fit, summary))
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

/// What `flatland solve` reports.
struct Summary<'a> {
    scene: &'a str,
    choice: &'a Choice,
    mesh: &'a Mesh,
    reference_elements: usize,
    basis: Option<usize>,
    /// Bytes the representation holds (`Representation::memory_bytes`).
    kernel_bytes: usize,
    comparison: &'a Comparison,
    build_s: f64,
    /// The baseline's note when it built another count than asked.
    note: Option<&'a str>,
    /// What the default learner says of itself.
    learned: Option<&'a Learned>,
    discretization: &'a ErrorEstimate,
}

impl Summary<'_> {
    /// The `--json` object; `note` is there only when the baseline built a count other than
    /// asked.
    fn json(&self) -> serde_json::Value {
        let c = self.comparison;
        let mut json = serde_json::json!({
            "scene": self.scene,
            "kernel": self.choice.label(),
            "elements": self.mesh.len(),
            "basis_functions": self.basis,
            "kernel_bytes": self.kernel_bytes,
            "rel_l2_b": c.errors.rel_l2_b,
            "rel_l2_reflected": c.errors.rel_l2_reflected,
            "iterations": c.solution.iterations,
            "residual": c.solution.residual,
            "wall_s": c.solution.wall_s(),
            "peak_memory_bytes": flatland_lab::memory::peak_bytes(),
            "build_s": self.build_s,
            "reference_elements": self.reference_elements,
            "discretization_error_estimate": self.discretization.estimate,
        });
        if let Some(note) = self.note {
            json["note"] = note.into();
        }
        if let Some(l) = self.learned {
            json["estimated_rel_l2_reflected"] = l.estimated_error.into();
            json["rounds"] = l.rounds.into();
            json["probes"] = l.probes.into();
            json["stopped"] = stop_name(l.stopped).into();
        }
        json
    }

    /// The human-readable summary.
    fn print(&self) {
        let c = self.comparison;
        let row = |k: &str, v: String| println!("  {k:<26} {v}");
        println!(
            "solve of {} with the {} kernel",
            self.scene,
            self.choice.label()
        );
        row(
            "basis functions",
            self.basis
                .map_or_else(|| "exact (none)".to_owned(), |b| b.to_string()),
        );
        if let Some(note) = self.note {
            row("note", note.to_owned());
        }
        row(
            "elements",
            format!(
                "{} (exact reference: {})",
                self.mesh.len(),
                self.reference_elements
            ),
        );
        row(
            "discretization error",
            format!(
                "≈ {:.1e} (estimated from a solve on 2N = {} elements)",
                self.discretization.estimate, self.discretization.finer_elements
            ),
        );
        row("rel. L2 of B", format!("{:.5}", c.errors.rel_l2_b));
        row(
            "rel. L2 of B − E",
            format!("{:.5}   (the reflected part)", c.errors.rel_l2_reflected),
        );
        if let Some(l) = self.learned {
            row(
                "  estimated by the learner",
                format!(
                    "{:.5}   (against the exact kernel on these elements; {} rounds, {} probes, \
                     stopped: {})",
                    l.estimated_error,
                    l.rounds,
                    l.probes,
                    stop_name(l.stopped)
                ),
            );
        }
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
        row("building the kernel", format!("{:.3} s", self.build_s));
        row(
            "kernel's memory",
            format!(
                "{:.1} MB (the representation)",
                self.kernel_bytes as f64 / 1e6
            ),
        );
        if let Some(peak) = flatland_lab::memory::peak_bytes() {
            row(
                "peak memory",
                format!("{:.0} MB (the whole command)", peak as f64 / 1e6),
            );
        }
    }
}

/// How `--json` and the table name why the default learner stopped.
fn stop_name(stop: LightStop) -> &'static str {
    match stop {
        LightStop::Tolerance => "tolerance",
        LightStop::Exact => "exact",
        LightStop::Cells => "cells",
        LightStop::Time => "time",
    }
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
        // The default learner, also by the name it had before it was called so.
        assert_eq!(Choice::parse("default").unwrap(), Choice::Default);
        assert_eq!(Choice::parse("sgcs").unwrap(), Choice::Default);
        assert_eq!(Choice::parse("clustered").unwrap(), Choice::Clustered);
        let err = Choice::parse("sgsc").unwrap_err().to_string();
        assert!(
            err.contains("`sgsc`") && err.contains("exact, default, hr, clustered"),
            "{err}"
        );
    }
}
