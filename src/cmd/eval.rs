//! `flatland eval`: the learned ζ̃ on the grid of `flatland kernel`, and its errors.

use std::path::PathBuf;

use anyhow::{Context, Result};
use flatland_geom::{Kernel, Scene};
use kernel_fit::ModelFile;

use flatland_lab::{interrupt, output};

/// Arguments of `flatland eval`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A model written by `flatland fit --out`.
    #[arg(long, value_name = "FILE")]
    pub model: PathBuf,
    /// The scene to evaluate on (must be the model's scene). Default: the scene in the model.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Subdivision applied to `--scene` before comparing it with the model's scene.
    #[arg(long, value_name = "M", default_value_t = 1)]
    pub subdivide: usize,
    /// Grid resolution R in [16, 4096].
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Output: `.csv` (R lines of R numbers, line i ↔ s=(i+½)/R) or `.png` (heatmap with axes
    /// and a colour bar, on the exact ζ's colour scale).
    #[arg(long, value_name = "OUT")]
    pub out: PathBuf,
    /// Log colour scale for a PNG.
    #[arg(long)]
    pub log: bool,
    /// Print the errors as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// Runs `flatland eval`.
pub fn run(args: &Args) -> Result<()> {
    super::check_res(args.res)?;
    let file = ModelFile::load(&args.model)?;
    let scene: Scene = match &args.scene {
        Some(path) => {
            let mut scene = super::scene_file(path)?;
            if args.subdivide != 1 {
                scene = super::subdivide(&scene, args.subdivide)?;
            }
            file.check_scene(&scene, path)?;
            scene
        }
        None => file.model.scene().clone(),
    };
    let mut inputs = vec![args.model.as_path()];
    inputs.extend(args.scene.as_deref());
    output::file(&args.out, &inputs)?;
    eprintln!(
        "evaluating {} on a {r}×{r} grid (Ctrl-C stops)",
        args.model.display(),
        r = args.res
    );
    let kernel = Kernel::new(scene);
    let reference = flatland_lab::reference(&kernel, args.res, &file.params);
    interrupt::check()?;
    let values = reference.approximate_grid(&file.model);
    interrupt::check()?;
    let cells = file.model.network().len();
    let title = format!(
        "learned ζ of {} ({cells} cells), {r}×{r} grid",
        args.model.display(),
        r = args.res
    );
    let map = flatland_pictures::plot::heatmap(
        title,
        "learned ζ",
        kernel.scene(),
        reference.grid(),
        args.log,
    );
    flatland_lab::report::grid::write_grid(&args.out, args.res, &values, &map)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let errors = reference.errors(&file.model);
    let defined = flatland_lab::Defined::of(&reference);
    if args.json {
        let json = serde_json::json!({
            "cells": cells,
            "res": args.res,
            "rel_l2_grid": defined.grid.then_some(errors.grid),
            "rel_l2_heldout": defined.heldout.then_some(errors.heldout),
            "rel_l2_heldout_p05": defined.heldout.then_some(errors.heldout_spread[0]),
            "rel_l2_heldout_p95": defined.heldout.then_some(errors.heldout_spread[1]),
            "rel_l1_grid": defined.grid.then_some(errors.l1_grid),
            "rel_l1_heldout": defined.heldout.then_some(errors.l1_heldout),
        });
        println!("{json}");
    } else {
        println!(
            "{cells} cells; on the {r}×{r} grid relative L2 {}, L1 {}; held out relative L2 {} \
             (bootstrap 90 %: {} – {}), L1 {}; wrote {}",
            flatland_lab::error_text(errors.grid, defined.grid, 4),
            flatland_lab::error_text(errors.l1_grid, defined.grid, 4),
            flatland_lab::error_text(errors.heldout, defined.heldout, 4),
            flatland_lab::error_text(errors.heldout_spread[0], defined.heldout, 4),
            flatland_lab::error_text(errors.heldout_spread[1], defined.heldout, 4),
            flatland_lab::error_text(errors.l1_heldout, defined.heldout, 4),
            args.out.display(),
            r = args.res
        );
        if let Some(why) = defined.note() {
            println!("{why}");
        }
    }
    Ok(())
}
