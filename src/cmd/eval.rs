//! `flatland eval`: the learned ζ̃ on the grid of `flatland kernel`, and its errors.

use std::path::PathBuf;

use anyhow::{Context, Result};
use flatland_geom::{Kernel, Scene};
use kernel_fit::{Approximation, ModelFile, Reference};

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
    /// Grid resolution R.
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Output: `.csv` (R lines of R numbers, line i ↔ s=(i+½)/R) or `.png` (heatmap).
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
    anyhow::ensure!(args.res >= 1, "--res must be at least 1, got {}", args.res);
    let file = ModelFile::load(&args.model)?;
    let scene: Scene = match &args.scene {
        Some(path) => {
            let mut scene = Scene::load(path)?;
            if args.subdivide != 1 {
                scene = scene.subdivide(args.subdivide)?;
            }
            file.check_scene(&scene, path)?;
            scene
        }
        None => file.model.scene().clone(),
    };
    let kernel = Kernel::new(scene);
    let reference = Reference::new(&kernel, args.res, file.params.heldout, file.params.seed);
    let values = reference.approximate_grid(&file.model);
    super::kernel::write_grid(&args.out, args.res, &values, args.log)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let errors = reference.errors(&file.model);
    if args.json {
        let json = serde_json::json!({
            "cells": file.model.basis_functions(),
            "res": args.res,
            "rel_l2_grid": errors.grid,
            "rel_l2_heldout": errors.heldout,
        });
        println!("{json}");
    } else {
        println!(
            "{} cells; relative L2 on the {r}×{r} grid {:.4}, held out {:.4}; wrote {}",
            file.model.basis_functions(),
            errors.grid,
            errors.heldout,
            args.out.display(),
            r = args.res
        );
    }
    Ok(())
}
