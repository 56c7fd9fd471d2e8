//! `flatland solve`: light the scene — solve `B = E + K B` with a kernel representation (or
//! trace it) and score the solved radiosity against the exact kernel's, on one [`LitScene`]
//! that solves each mesh once.

mod summary;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use flatland_baselines::{TraceBudget, TraceParams, trace};
use flatland_geom::{Kernel, Scene, write_atomic};
use flatland_lab::interrupt;
use flatland_light::LightParams;
use flatland_methods::{Account, Ask, Method, MethodError, Progress, Recipes};
use flatland_solve::{
    Comparison, Elements, LitParams, LitScene, Mesh, ReferenceMesh, Solution, SolveError, Stop,
    check_elements,
};
use kernel_fit::ModelFile;

use super::SceneArgs;
use summary::Summary;

/// Arguments of `flatland solve`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// The kernel: a method (exact, light, visibility, paper, paper-norefit, hr, clustered,
    /// uniform, uniform-exact; tracer traces photons instead) or a model file (.json) written by
    /// `flatland fit --out`.
    #[arg(long, value_name = "KERNEL", default_value = "exact", value_parser = KernelArg::parse)]
    pub kernel: KernelArg,
    /// Basis functions of the representation built: links (hr, clustered), blocks (uniform),
    /// cells (visibility, paper), photons (tracer); default 400, except clustered (100 links per
    /// edge of the scene) and tracer (10⁶). For the light-driven learner, the most cells it may
    /// grow (default: as many as the tolerance takes).
    #[arg(long, value_name = "N")]
    pub basis: Option<usize>,
    /// The light-driven learner stops when its own estimate of the relative L2 error of the
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
    /// Seed of the fit, baseline or trace built.
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

/// What `--kernel` names: a method, or a model file.
#[derive(Clone, Debug, PartialEq)]
pub enum KernelArg {
    /// A method by its one name.
    Method(Method),
    /// A model written by `flatland fit --out`.
    Model(PathBuf),
}

impl KernelArg {
    fn parse(text: &str) -> Result<KernelArg, MethodError> {
        let json = Path::new(text).extension();
        if json.is_some_and(|e| e.eq_ignore_ascii_case("json")) {
            return Ok(KernelArg::Model(PathBuf::from(text)));
        }
        Method::parse(text).map(KernelArg::Method)
    }

    fn label(&self) -> String {
        match self {
            KernelArg::Method(m) => m.name().to_owned(),
            KernelArg::Model(path) => path.display().to_string(),
        }
    }
}

/// Photons of `--kernel tracer` without `--basis`.
const TRACER_PHOTONS: u64 = 1_000_000;

/// Runs `flatland solve`.
pub fn run(args: &Args) -> Result<()> {
    let output = args.out.as_deref().map(output_of).transpose()?;
    if let Some(out) = &args.out {
        let mut inputs: Vec<&Path> = args.scene.scene.iter().map(PathBuf::as_path).collect();
        if let KernelArg::Model(model) = &args.kernel {
            inputs.push(model);
        }
        flatland_lab::output::file(out, &inputs)?;
    }
    if args.kernel != KernelArg::Method(Method::Exact) && args.basis == Some(0) {
        bail!("--basis must be at least 1, got 0");
    }
    let (scene, label) = scene_for(args)?;
    let kernel = Arc::new(Kernel::new(scene));
    let params = lit_params(args);
    // Check the sizes asked for before any (maybe long) solve or build.
    if let Some(n) = args.elements {
        check_elements(&kernel, n).context("--elements")?;
    }
    if let Some(n) = args.reference_elements {
        check_elements(&kernel, n).context("--reference-elements")?;
    }
    // Every long loop below polls Ctrl-C; nothing is written before the end.
    let stop: &Stop = &interrupt::requested;
    let lit = LitScene::new(Arc::clone(&kernel), &params, stop)
        .map_err(interrupted)
        .context("the exact solve and its discretization error")?;
    let (comparison, built) = light(args, &lit, stop)?;
    interrupt::check()?;
    let kernel_label = args.kernel.label();
    if let (Some(path), Some(output)) = (&args.out, output) {
        write(path, output, &lit, &label, &kernel_label, &comparison)?;
    }
    let summary = Summary::new(&label, &kernel_label, &lit, &comparison, &built);
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

/// The lit scene's settings from the arguments.
fn lit_params(args: &Args) -> LitParams {
    LitParams {
        elements: args
            .elements
            .map_or(LitParams::default().elements, Elements::Exactly),
        reference: args
            .reference_elements
            .map_or(ReferenceMesh::Finer, ReferenceMesh::Elements),
        ..LitParams::default()
    }
}

/// What was built, as the summary reports it.
pub(crate) struct BuiltInfo {
    pub basis: Option<usize>,
    pub bytes: usize,
    pub build_s: f64,
    pub note: Option<String>,
    pub account: Account,
}

/// Lights `lit`'s scene with `--kernel`: the exact solve already made, a trace, or a built
/// representation solved on the mesh; scored against the reference.
fn light(args: &Args, lit: &LitScene, stop: &Stop) -> Result<(Comparison, BuiltInfo)> {
    let method = match &args.kernel {
        KernelArg::Method(Method::Exact) => {
            let reused = lit.exact_scored().context("the exact solve")?;
            return Ok((reused, info(None, 0, 0.0, None, Account::None)));
        }
        KernelArg::Method(Method::Tracer) => return traced(args, lit, stop),
        KernelArg::Model(path) => {
            let model = ModelFile::load(path)?.model;
            let compared = lit.score(&model, stop).map_err(interrupted)?;
            let basis = flatland_solve::Representation::basis_functions(&model);
            let bytes = flatland_solve::Representation::memory_bytes(&model);
            return Ok((compared, info(basis, bytes, 0.0, None, Account::None)));
        }
        KernelArg::Method(method) => *method,
    };
    let ask = Ask {
        basis: args.basis,
        tolerance: Some(args.tolerance),
        seed: args.seed,
        ..Ask::new(method)
    };
    let bar = super::progress_bar(0, "cells");
    let built = Recipes::default()
        .build(
            ask,
            lit.kernel(),
            lit.mesh(),
            None,
            stop,
            &mut |p| match p {
                Progress::Cells { cells, target } => {
                    bar.set_length(target as u64);
                    bar.set_position(cells as u64);
                }
                Progress::Probes { cells, estimate } => {
                    bar.set_position(cells as u64);
                    if let Some(e) = estimate {
                        bar.set_message(format!("estimated error {e:.4}"));
                    }
                }
            },
        )
        .map_err(|e| match e.is_interrupted() {
            true => interrupt::stopped().into(),
            false => anyhow::Error::from(e),
        })
        .with_context(|| format!("--kernel {method}"))?;
    bar.finish_and_clear();
    interrupt::check()?;
    let compared = lit
        .score(built.rep.as_ref(), stop)
        .map_err(interrupted)
        .with_context(|| format!("solving with the {method} kernel"))?;
    let (basis, bytes) = (built.rep.basis_functions(), built.rep.memory_bytes());
    Ok((
        compared,
        info(basis, bytes, built.build_s, built.note, built.account),
    ))
}

fn info(basis: Option<usize>, bytes: usize, s: f64, note: Option<String>, a: Account) -> BuiltInfo {
    BuiltInfo {
        basis,
        bytes,
        build_s: s,
        note,
        account: a,
    }
}

/// The Monte Carlo tracer on the mesh: no kernel, `--basis` photons.
fn traced(args: &Args, lit: &LitScene, stop: &Stop) -> Result<(Comparison, BuiltInfo)> {
    let photons = args.basis.map_or(TRACER_PHOTONS, |n| n as u64);
    let params = TraceParams {
        budget: TraceBudget::Photons(photons),
        seed: args.seed,
    };
    let traced = trace(lit.kernel(), lit.mesh(), &params, stop)?;
    interrupt::check()?;
    let solution = Solution {
        radiosity: traced.radiosity,
        iterations: 0,
        residual: 0.0,
        assembly_s: 0.0,
        solve_s: traced.wall.as_secs_f64(),
    };
    let note = format!("{} photons, {} rays", traced.photons, traced.rays);
    let built = info(None, traced.memory_bytes, 0.0, Some(note), Account::None);
    Ok((lit.scored(solution), built))
}

/// A solver's interruption as the command's, anything else as it is.
fn interrupted(e: SolveError) -> anyhow::Error {
    match e {
        SolveError::Interrupted => interrupt::stopped().into(),
        other => other.into(),
    }
}

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Output {
    Csv,
    Png,
}

fn output_of(path: &Path) -> Result<Output> {
    let extension = path.extension().and_then(|e| e.to_str());
    match extension.map(str::to_ascii_lowercase).as_deref() {
        Some("csv") => Ok(Output::Csv),
        Some("png") => Ok(Output::Png),
        _ => bail!(
            "{}: unknown output format (expected a .csv or .png file name)",
            path.display()
        ),
    }
}

/// Writes the solution as `--out` asks.
fn write(
    path: &Path,
    output: Output,
    lit: &LitScene,
    label: &str,
    kernel: &str,
    c: &Comparison,
) -> Result<()> {
    let b = &c.solution.radiosity;
    match output {
        Output::Csv => interrupt::writing(|| write_atomic(path, csv(lit.mesh(), b).as_bytes()))?,
        Output::Png => flatland_lab::report::lit::lit_scene_png(
            path,
            &flatland_lab::report::lit::Picture {
                scene: lit.kernel().scene(),
                label,
                kernel,
                mesh: lit.mesh(),
                b,
                reference: lit.reference(),
                rel_l2_reflected: c.errors.rel_l2_reflected,
            },
        )?,
    }
    Ok(())
}

/// The scene to solve: `--scene` (subdivided), or a model's own scene when none is given.
fn scene_for(args: &Args) -> Result<(Scene, String)> {
    let KernelArg::Model(path) = &args.kernel else {
        return args.scene.load();
    };
    let file = ModelFile::load(path)?;
    let Some(scene_path) = &args.scene.scene else {
        let label = format!("{} (model's scene)", path.display());
        return Ok((file.model.scene().clone(), label));
    };
    let (scene, label) = args.scene.load()?;
    file.check_scene(&scene, scene_path)?;
    Ok((scene, label))
}

/// `edge,s,x,y,b`: one row per element midpoint, in order of s (shortest round-trip decimals).
fn csv(mesh: &Mesh, b: &[f64]) -> String {
    let mut out = String::from("edge,s,x,y,b\n");
    for (e, value) in mesh.elements().iter().zip(b) {
        let (x, y) = (e.midpoint.x, e.midpoint.y);
        out.push_str(&format!("{},{},{x},{y},{value}\n", e.edge, e.s_mid));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_parse_and_old_names_are_refused_with_the_new_one() {
        let parse = KernelArg::parse;
        assert_eq!(parse("exact").unwrap(), KernelArg::Method(Method::Exact));
        assert_eq!(parse("light").unwrap(), KernelArg::Method(Method::Light));
        let model = KernelArg::Model(PathBuf::from("runs/m.JSON"));
        assert_eq!(parse("runs/m.JSON").unwrap(), model);
        for (old, new) in [
            ("sgcs", "`light`"),
            ("default", "`light`"),
            ("first-shot", "`visibility`"),
        ] {
            let err = parse(old).unwrap_err().to_string();
            assert!(err.contains(new), "{old}: {err}");
        }
        let err = parse("sgsc").unwrap_err().to_string();
        assert!(err.contains("`sgsc`") && err.contains("exact, "), "{err}");
    }
}
