//! `flatland fit`: learn a scene's kernel and report the figures.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use flatland_geom::{Kernel, KernelParams};
use kernel_fit::{Fit, FitParams, FitSummary, ModelFile, Preset, Resampling, StopReason, Target};

use super::SceneArgs;
use flatland_lab::{interrupt, output};

/// `--resampling` values.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum ResamplingArg {
    /// θ(ξ) = ρ_ACC ∨ ¬ρ_A (the paper).
    Theta,
    /// Uniform random (s, t): the control experiment.
    Uniform,
}

/// Arguments of `flatland fit`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Which network: `visibility` (learns V where geometry cannot decide it) or `paper` (the
    /// paper's network, learning ζ).
    #[arg(long, value_name = "NETWORK", default_value = "visibility",
          value_parser = flatland_methods::Method::parse_network)]
    pub preset: Preset,
    /// Stop at this many cells, in [3, 10 000 000].
    #[arg(long, default_value_t = FitParams::default().target_cells)]
    pub cells: usize,
    /// Seed of every random choice (same seed, same fit).
    #[arg(long, default_value_t = FitParams::default().seed)]
    pub seed: u64,
    /// Stop after this many training steps.
    #[arg(long)]
    pub max_steps: Option<u64>,
    /// Stop after this many training rays.
    #[arg(long)]
    pub rays: Option<u64>,
    /// Stop when the held-out relative L2 error reaches this value.
    #[arg(long)]
    pub target_error: Option<f64>,
    /// How new sample sets are chosen: `theta` (the paper) or `uniform` (the control).
    #[arg(long, value_enum, default_value_t = ResamplingArg::Theta)]
    pub resampling: ResamplingArg,
    /// With `--preset paper`: let the network learn k and multiply by the known emission E'
    /// (instead of learning ζ).
    #[arg(long)]
    pub factor_emission: bool,
    /// Skip the final least-squares refit of the output weights.
    #[arg(long)]
    pub no_refit: bool,
    /// Set any numeric parameter of the learner, e.g. `--set eta=0.05 --set phi=0.1`; each is
    /// checked against its range (`flatland params` lists every name, range and default).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Reference grid resolution R for the error on the grid, in [16, 4096].
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Write the model (scene fingerprint, parameters, network) to this JSON file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object with the figures on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Save the whole learning state here (atomically) every `--every` steps and on Ctrl-C.
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Steps between two checkpoints.
    #[arg(long, value_name = "N", default_value_t = 100_000)]
    pub every: u64,
    /// Continue from a checkpoint (its scene and parameters; other fit options are ignored).
    #[arg(long, value_name = "FILE", conflicts_with = "scene")]
    pub resume: Option<PathBuf>,
}

impl Args {
    /// The defaults of `flatland fit` on `scene` (the bundled `fig3` when `None`).
    pub fn for_scene(scene: Option<PathBuf>) -> Args {
        use clap::Parser;
        #[derive(Parser)]
        struct Defaults {
            #[command(flatten)]
            fit: Args,
        }
        let mut args = Defaults::parse_from(["flatland"]).fit;
        args.scene.scene = scene;
        args
    }

    /// The fit parameters these arguments ask for: the preset's, with the flags given.
    pub fn params(&self) -> Result<FitParams> {
        let d = self.preset.params();
        anyhow::ensure!(
            !self.factor_emission || d.target == Target::Zeta,
            "--factor-emission applies to the paper's network (--preset paper), which learns ζ"
        );
        let mut params = FitParams {
            target_cells: self.cells,
            seed: self.seed,
            max_steps: self.max_steps.unwrap_or(d.max_steps),
            ray_budget: self.rays.unwrap_or(d.ray_budget),
            target_error: self.target_error.unwrap_or(d.target_error),
            refit: d.refit && !self.no_refit,
            resampling: match self.resampling {
                ResamplingArg::Theta => Resampling::Theta,
                ResamplingArg::Uniform => Resampling::Uniform,
            },
            target: if self.factor_emission {
                Target::FactoredEmission
            } else {
                d.target
            },
            ..d
        };
        for assignment in &self.set {
            kernel_fit::schema::set_checked(&mut params, assignment)
                .map_err(|e| anyhow::anyhow!("--set {e}"))?;
        }
        Ok(params)
    }
}

/// Steps between two progress callbacks (bar updates, checkpoint and Ctrl-C checks).
const PROGRESS_EVERY: u64 = 1000;

/// Lists the pairs of surface edges whose visibility varies (where the visibility network draws
/// its samples; the kernel keeps the list for `Fit::new`), with a bar of the pairs decided:
/// on a floor plan of 10⁴ edges it takes most of the set-up. Ctrl-C during it ends the
/// command through the handler's grace period, with nothing computed yet to keep.
fn list_varying_pairs(kernel: &Kernel, label: &str) {
    let start = Instant::now();
    let bar = super::progress_bar(kernel.surface_pairs(), "pairs of edges decided");
    let decided = AtomicU64::new(0);
    let listed = std::thread::scope(|s| {
        let waiting = std::thread::current();
        let (kernel, decided) = (kernel, &decided);
        let walk = s.spawn(move || {
            let listed = kernel.varying_pairs_counting(decided).pairs.len();
            waiting.unpark();
            listed
        });
        while !walk.is_finished() {
            bar.set_position(decided.load(Ordering::Relaxed));
            std::thread::park_timeout(Duration::from_millis(100));
        }
        walk.join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    });
    bar.finish_and_clear();
    eprintln!(
        "fit of {label}: visibility varies between {listed} pairs of surface edges (of {}), \
         listed in {:.1} s",
        kernel.surface_pairs(),
        start.elapsed().as_secs_f64()
    );
}

/// The fit `args` ask for, resumed from its checkpoint or new, and its label.
fn started(args: &Args) -> Result<(Fit, String)> {
    let started = match &args.resume {
        Some(path) => {
            let fit = Fit::resume(path, KernelParams::default())?;
            interrupt::keep(format!(
                "nothing new was saved; {} still holds the state at step {}",
                path.display(),
                fit.steps()
            ));
            (fit, format!("{} (resumed)", path.display()))
        }
        None => {
            let (kernel, label) = args.scene.kernel()?;
            let params = args.params()?;
            params.validate()?;
            let reference = Arc::new(flatland_lab::reference(&kernel, args.res, &params));
            interrupt::check()?;
            if params.target == Target::Visibility {
                list_varying_pairs(&kernel, &label);
                // Its importance tiles take a few seconds on 10⁵ pairs and more.
                eprintln!("fit of {label}: drawing the first samples and the importance tiles");
            }
            (Fit::new(Arc::new(kernel), reference, params)?, label)
        }
    };
    Ok(started)
}

/// Trains `fit` to its cells with a progress bar, saving the checkpoint every `--every` steps;
/// why it stopped (Ctrl-C included).
fn train(fit: &mut Fit, args: &Args) -> Result<StopReason> {
    let params = *fit.params();
    let bar = super::progress_bar(params.target_cells as u64, "cells");
    let mut save_error = None;
    let reason = fit.train(PROGRESS_EVERY, |f| {
        bar.set_position(f.network().len() as u64);
        bar.set_message(format!("{} rays", f.rays()));
        if let Some(path) = &args.checkpoint
            && f.steps() % args.every < PROGRESS_EVERY
        {
            match save_checkpoint(f, path) {
                Ok(()) => {}
                Err(e) => {
                    save_error = Some(e);
                    return ControlFlow::Break(());
                }
            }
        }
        if interrupt::requested() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    bar.finish_and_clear();
    if let Some(e) = save_error {
        return Err(e).context("saving the checkpoint");
    }
    Ok(reason)
}

/// Runs `flatland fit`.
pub fn run(args: &Args) -> Result<()> {
    // Everything that can be refused is refused before any work: ranges, then outputs.
    super::check_res(args.res)?;
    super::check_cells("--cells", args.cells)?;
    anyhow::ensure!(args.every >= 1, "--every must be at least 1, but is 0");
    check_outputs(args)?;
    let (mut fit, label) = started(args)?;
    let params = *fit.params();
    eprintln!(
        "fit of {label}: training to {} cells (Ctrl-C stops{})",
        params.target_cells,
        if args.checkpoint.is_some() {
            " and saves the checkpoint"
        } else {
            ""
        }
    );
    let reason = train(&mut fit, args)?;
    if let Some(path) = &args.checkpoint {
        save_checkpoint(&fit, path).context("saving the checkpoint")?;
    }
    if reason == StopReason::Interrupted {
        return Err(interrupt::stopped().into());
    }
    if fit.head().refit().is_some() {
        eprintln!("least-squares refit and final errors (Ctrl-C stops)");
    } else {
        eprintln!("final errors");
    }
    let summary = finish(&mut fit)?;
    interrupt::check()?;
    let defined = flatland_lab::Defined::of(fit.reference());
    if let Some(out) = &args.out {
        interrupt::writing(|| {
            ModelFile::new(fit.model().clone(), params, Some(summary.clone())).save(out)
        })
        .with_context(|| format!("writing the model to {}", out.display()))?;
    }
    if args.json {
        println!("{}", summary_json(&summary, &label, defined));
    } else {
        print_summary(&summary, &label, defined);
        if let Some(out) = &args.out {
            println!("model written to {}", out.display());
        }
    }
    Ok(())
}

/// The refit (with a progress bar on a terminal) and the final errors; Ctrl-C stops it.
fn finish(fit: &mut Fit) -> Result<kernel_fit::FitSummary> {
    let refit_bar = super::progress_bar(0, "");
    let summary = match fit.finish_with(|p| {
        let unit = match p.stage {
            sgcs::RefitStage::Assembling => "samples assembled",
            sgcs::RefitStage::Solving => "ridges solved",
        };
        refit_bar.set_length(p.total as u64);
        refit_bar.set_position(p.done as u64);
        refit_bar.set_message(unit);
        if interrupt::requested() {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }) {
        Err(kernel_fit::FitError::Interrupted) => return Err(interrupt::stopped().into()),
        other => other?,
    };
    refit_bar.finish_and_clear();
    Ok(summary)
}

/// The outputs asked for are writable and never an input, before any work.
fn check_outputs(args: &Args) -> Result<()> {
    let scene_input: Vec<&Path> = args.scene.path().into_iter().collect();
    if let Some(out) = &args.out {
        let mut inputs = scene_input.clone();
        inputs.extend(args.resume.as_deref());
        output::file(out, &inputs)?;
    }
    if let Some(checkpoint) = &args.checkpoint {
        // The checkpoint may be the one resumed from: it is the fit's state, kept up to date.
        output::file(checkpoint, &scene_input)?;
        if let Some(out) = &args.out {
            output::distinct(out, checkpoint, "is both --out and --checkpoint")?;
        }
    }
    Ok(())
}

/// Saves the checkpoint (Ctrl-C waits for the write) and records it as what an interruption
/// keeps.
fn save_checkpoint(fit: &Fit, path: &Path) -> Result<(), kernel_fit::FitError> {
    interrupt::writing(|| fit.save_checkpoint(path))?;
    interrupt::keep(format!(
        "checkpoint saved to {path} after {} steps (continue with `flatland fit --resume {path}`)",
        fit.steps(),
        path = path.display()
    ));
    Ok(())
}

/// The `--json` object: flat figures first, then the details. An undefined error (the exact ζ
/// is 0 everywhere it was measured) is `null`.
pub fn summary_json(
    s: &FitSummary,
    scene: &str,
    defined: flatland_lab::Defined,
) -> serde_json::Value {
    let (grid, heldout) = (defined.grid, defined.heldout);
    let or_null = |ok: bool, v: f64| ok.then_some(v);
    serde_json::json!({
        "scene": scene,
        "cells": s.cells,
        "samples": s.samples,
        "sets": s.sets,
        "rays": s.rays,
        "steps": s.steps,
        "samples_per_cell": s.samples as f64 / s.cells as f64,
        "rel_l2_grid": or_null(grid, s.errors.grid),
        "rel_l2_heldout": or_null(heldout, s.errors.heldout),
        "rel_l2_heldout_p05": or_null(heldout, s.errors.heldout_spread[0]),
        "rel_l2_heldout_p95": or_null(heldout, s.errors.heldout_spread[1]),
        "rel_l1_grid": or_null(grid, s.errors.l1_grid),
        "rel_l1_heldout": or_null(heldout, s.errors.l1_heldout),
        "rel_l2_grid_before_refit": s.errors_before_refit.and_then(|e| or_null(grid, e.grid)),
        "rel_l2_heldout_before_refit": s.errors_before_refit.and_then(|e| or_null(heldout, e.heldout)),
        "wall_s": s.wall_s,
        "time_training_s": s.train_s,
        "time_resampling_s": s.resample_s,
        "time_refit_s": s.refit_s,
        "time_reference_s": s.reference_s,
        "time_errors_s": s.errors_s,
        "stop": s.stop,
    })
}

/// The human-readable summary table.
pub fn print_summary(s: &FitSummary, scene: &str, defined: flatland_lab::Defined) {
    let row = |k: &str, v: String| println!("  {k:<24} {v}");
    println!("fit of {scene}");
    row("cells", s.cells.to_string());
    row("samples (sets)", format!("{} ({})", s.samples, s.sets));
    row("rays", s.rays.to_string());
    row("steps", s.steps.to_string());
    row(
        "samples / cell",
        format!("{:.1}", s.samples as f64 / s.cells as f64),
    );
    if let Some(b) = s.errors_before_refit {
        row("rel. L2 before refit", defined.format(&b));
    }
    row("rel. L2", defined.format(&s.errors));
    if defined.heldout {
        let [lo, hi] = s.errors.heldout_spread;
        row("held out, bootstrap 90 %", format!("{lo:.4} – {hi:.4}"));
    }
    row(
        "rel. L1",
        format!(
            "grid {}   held out {}",
            flatland_lab::error_text(s.errors.l1_grid, defined.grid, 4),
            flatland_lab::error_text(s.errors.l1_heldout, defined.heldout, 4)
        ),
    );
    if let Some(why) = defined.note() {
        row("", why.to_owned());
    }
    row("wall time", format!("{:.3} s", s.wall_s));
    row(
        "  of which",
        format!(
            "training {:.3} s, resampling {:.3} s, refit {:.3} s",
            s.train_s, s.resample_s, s.refit_s
        ),
    );
    row(
        "not counted",
        format!(
            "reference {:.3} s, measuring errors {:.3} s",
            s.reference_s, s.errors_s
        ),
    );
    row("stopped by", format!("{:?}", s.stop));
}
