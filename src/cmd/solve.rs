//! `flatland solve`: light the scene — solve `B = E + K B` with a kernel representation (or
//! trace it) and score the solved radiosity against the exact kernel's, on one [`LitScene`]
//! that solves each mesh once.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use flatland_geom::{Kernel, write_atomic};
use flatland_lab::interrupt;
use flatland_lab::report::solution::Solution;
use flatland_light::LightParams;
use flatland_methods::{Ask, KernelArg, Lit, Method, MethodError, Recipes};
use flatland_solve::{Elements, LitParams, LitScene, ReferenceMesh, Stop};

use super::SceneArgs;

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
    /// Elements of the solve, spread evenly (default: a mesh refined where the error of B as
    /// a function is, until its estimated relative L2 error of B − E along the surfaces is
    /// within 1 %).
    #[arg(long, value_name = "N")]
    pub elements: Option<usize>,
    /// Elements of the exact reference solve the errors are measured against (default: the
    /// finer solve the discretization error is estimated from, every element cut in three at
    /// its Gauss points, so it costs nothing more).
    #[arg(long, value_name = "N")]
    pub reference_elements: Option<usize>,
    /// With `--out B.csv`: B as a function, N rows per element at evenly spaced points inside
    /// it (the final gather E + ρ(H + ∫ G V B) of the solved B at each point; H the point
    /// lights' direct light there). Without it, one row per element, b the mean of the
    /// function over the element (for the exact kernel; another kernel's element value).
    #[arg(long, value_name = "N")]
    pub samples: Option<usize>,
    /// Seed of the fit, baseline or trace built.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the solution: `.csv` (header `edge,s,x,y,b`, one row per element midpoint in
    /// order of s, or `--samples` rows), `.png` (the lit scene beside B(s) against the exact
    /// solution) or `.svg` (the lit plan: each element a segment in its B colour, `data-b` its
    /// value, lights marked, a colour bar; it opens in any browser).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print one JSON object with the figures instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `flatland solve`.
pub fn run(args: &Args) -> Result<()> {
    let format = (args.out.as_deref())
        .map(|out| flatland_lab::output::format(out, &["csv", "png", "svg"]))
        .transpose()?;
    if let Some(out) = &args.out {
        let mut inputs: Vec<&Path> = args.scene.path().into_iter().collect();
        if let KernelArg::Model(model) = &args.kernel {
            inputs.push(model);
        }
        flatland_lab::output::file(out, &inputs)?;
    }
    if args.kernel != KernelArg::Method(Method::Exact) && args.basis == Some(0) {
        bail!("--basis must be at least 1, got 0");
    }
    match (args.samples, format) {
        (Some(0), _) => bail!("--samples must be at least 1 point per element, got 0"),
        (Some(_), Some("csv")) | (None, _) => {}
        (Some(_), _) => bail!("--samples needs --out FILE.csv (the rows it writes)"),
    }
    let (scene, label) = match &args.kernel {
        KernelArg::Model(model) => args.scene.load_for_model(model)?,
        KernelArg::Method(_) => args.scene.load()?,
    };
    let kernel = Arc::new(Kernel::new(scene));
    let params = LitParams {
        elements: args
            .elements
            .map_or(LitParams::default().elements, Elements::Exactly),
        reference: args
            .reference_elements
            .map_or(ReferenceMesh::Finer, ReferenceMesh::Elements),
        ..LitParams::default()
    };
    // The sizes asked for are checked before any (maybe long) solve or build.
    (params.check(&kernel)).context("the mesh asked for (--elements, --reference-elements)")?;
    // Every long loop below polls Ctrl-C; nothing is written before the end.
    let stop: &Stop = &interrupt::requested;
    let lit = LitScene::new(Arc::clone(&kernel), &params, stop)
        .map_err(|e| super::interrupted(MethodError::from(e)))
        .context("the exact solve and its discretization error")?;
    let lighting = light(args, &lit, stop)?;
    interrupt::check()?;
    let kernel_label = args.kernel.label();
    let solution = Solution {
        lit: &lit,
        lighting: &lighting,
        exact: args.kernel == KernelArg::Method(Method::Exact),
        label: &label,
        kernel: &kernel_label,
    };
    if let (Some(path), Some(format)) = (&args.out, format) {
        let bytes = match format {
            "csv" => (solution.csv(args.samples, stop))
                .map_err(|e| super::interrupted(MethodError::from(e)))?
                .into_bytes(),
            picture => {
                let along =
                    (solution.along(stop)).map_err(|e| super::interrupted(MethodError::from(e)))?;
                if picture == "svg" {
                    solution.svg(&along).into_bytes()
                } else {
                    solution.png(&along)?
                }
            }
        };
        interrupt::writing(|| write_atomic(path, &bytes))?;
    }
    if args.json {
        println!("{}", solution.json());
    } else {
        solution.print();
        if let Some(path) = &args.out {
            println!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// Lights `lit` with `--kernel`, a bar showing a learner's cells.
fn light(args: &Args, lit: &LitScene, stop: &Stop) -> Result<Lit> {
    let ask = Ask {
        basis: args.basis,
        tolerance: Some(args.tolerance),
        seed: args.seed,
        ..Ask::new(Method::Exact)
    };
    let bar = super::progress_bar(0, "cells");
    let lighting = Recipes::default()
        .light(
            &args.kernel,
            ask,
            lit,
            None,
            stop,
            &mut super::learning(&bar),
        )
        .map_err(super::interrupted)
        .with_context(|| format!("lighting with the {} kernel", args.kernel.label()))?;
    bar.finish_and_clear();
    Ok(lighting)
}
