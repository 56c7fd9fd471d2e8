//! `flatland solve`: light the scene — solve `B = E + K B` with a kernel representation and
//! compare the solved radiosity with the exact kernel's.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use flatland_baselines::{BlockValue, HrParams, UniformParams, run_hr_at_budget, run_uniform};
use flatland_geom::{Kernel, Scene, write_atomic};
use flatland_solve::{
    Comparison, ExactReference, Mesh, Representation, SolveError, SolveParams, Stop, solve_against,
};
use kernel_fit::{Fit, ModelFile};

use super::SceneArgs;
use flatland_lab::interrupt;

/// Arguments of `flatland solve`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The kernel: `exact`, `default` (fit the default learner with --basis cells; `sgcs` is
    /// the same), `hr`,
    /// `uniform` (20 rays per block), `uniform-exact` (exact block means of k), or a model file
    /// (.json) written by `flatland fit --out`.
    #[arg(long, value_name = "KERNEL", default_value = "exact")]
    pub kernel: String,
    /// Basis functions of the representation built: cells (default), links (hr), blocks
    /// (uniform).
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
    /// The default learner.
    Default,
    Hr,
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
                "--kernel `{text}` is not known: expected exact, default, hr, uniform, uniform-exact \
                 or a model file (.json) written by `flatland fit --out`"
            ),
        })
    }

    fn label(&self) -> String {
        match self {
            Choice::Exact => "exact".into(),
            Choice::Default => "default".into(),
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

/// A built representation, what building it cost, and the baseline's note when it built a
/// count other than `--basis` (HR below its initial linking, a grid that is not square).
struct Built {
    rep: Box<dyn Representation>,
    build_s: f64,
    note: Option<String>,
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
    let interrupted = |e: SolveError| -> anyhow::Error {
        match e {
            SolveError::Interrupted => interrupt::stopped().into(),
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
    if args.json {
        println!(
            "{}",
            summary_json(
                &label,
                &choice,
                &mesh,
                reference_elements,
                &built,
                &comparison
            )
        );
    } else {
        print_summary(
            &label,
            &choice,
            &mesh,
            reference_elements,
            &built,
            &comparison,
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
    let mut note = None;
    let rep: Box<dyn Representation> = match choice {
        Choice::Exact => Box::new(Kernel::new(kernel.scene().clone())),
        Choice::Model(path) => Box::new(ModelFile::load(path)?.model),
        Choice::Hr => {
            let run = run_hr_at_budget(kernel, args.basis, args.seed, &HrParams::default())?;
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
            let run = run_uniform(kernel, args.basis, args.seed, &params)?;
            note = run.note.map(|n| n.to_string());
            Box::new(run.approx)
        }
        Choice::Default => {
            // Exactly what `flatland fit --cells N --seed S` fits.
            let mut fit_args = super::fit::Args::for_scene(None);
            fit_args.cells = args.basis;
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

/// The `--json` object; `note` is there only when the baseline built a count other than asked.
fn summary_json(
    scene: &str,
    choice: &Choice,
    mesh: &Mesh,
    reference_elements: usize,
    built: &Built,
    c: &Comparison,
) -> serde_json::Value {
    let mut summary = serde_json::json!({
        "scene": scene,
        "kernel": choice.label(),
        "elements": mesh.len(),
        "basis_functions": built.rep.basis_functions(),
        "rel_l2_b": c.errors.rel_l2_b,
        "rel_l2_reflected": c.errors.rel_l2_reflected,
        "iterations": c.solution.iterations,
        "residual": c.solution.residual,
        "wall_s": c.solution.wall_s(),
        "build_s": built.build_s,
        "reference_elements": reference_elements,
    });
    if let Some(note) = &built.note {
        summary["note"] = note.as_str().into();
    }
    summary
}

/// The human-readable summary.
fn print_summary(
    scene: &str,
    choice: &Choice,
    mesh: &Mesh,
    reference_elements: usize,
    built: &Built,
    c: &Comparison,
) {
    let row = |k: &str, v: String| println!("  {k:<26} {v}");
    println!("solve of {scene} with the {} kernel", choice.label());
    row(
        "basis functions",
        built
            .rep
            .basis_functions()
            .map_or_else(|| "exact (none)".to_owned(), |b| b.to_string()),
    );
    if let Some(note) = &built.note {
        row("note", note.clone());
    }
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
    row("building the kernel", format!("{:.3} s", built.build_s));
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
        let err = Choice::parse("sgsc").unwrap_err().to_string();
        assert!(
            err.contains("`sgsc`") && err.contains("exact, default, hr"),
            "{err}"
        );
    }
}
