//! `flatland kernel`: the exact kernel `k(s,t)` (or `ζ`) on an R×R grid, as CSV or a PNG heatmap.

use std::path::PathBuf;

use flatland_geom::Kernel;
use rayon::prelude::*;

use super::SceneArgs;
use flatland_lab::report::grid::{heatmap, output_of, write_grid};
use flatland_lab::{interrupt, output};

/// Arguments of `flatland kernel`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Grid resolution R in [16, 4096]: row i is s = (i+0.5)/R, column j is t = (j+0.5)/R.
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Write zeta = E'(e_x) k (the learning target) instead of k.
    #[arg(long)]
    pub weighted: bool,
    /// PNG only: colour by log10 of the value over the top four decades.
    #[arg(long)]
    pub log: bool,
    /// Output: .csv (R lines of R comma-separated numbers, line i ↔ s) or .png (heatmap with
    /// axes: t to the right, s upwards, a colour bar).
    #[arg(long)]
    pub out: PathBuf,
}

/// Rows of the grid computed between two Ctrl-C checks.
const ROWS_PER_CHUNK: usize = 16;

/// Evaluates the grid and writes it (atomically).
pub fn run(args: &Args) -> anyhow::Result<()> {
    output_of(&args.out)?;
    super::check_res(args.res)?;
    let (scene, label) = args.scene.load()?;
    output::file(
        &args.out,
        &args.scene.path().into_iter().collect::<Vec<_>>(),
    )?;
    let kernel = Kernel::new(scene);
    let what = if args.weighted { "zeta" } else { "k" };
    eprintln!(
        "computing {what} on a {0}×{0} grid of {label} (Ctrl-C stops)",
        args.res
    );
    let grid = grid(&kernel, args.res, args.weighted)?;
    let quantity = if args.weighted { "ζ(s, t)" } else { "k(s, t)" };
    let title = format!("{quantity} of {label}, {0}×{0} grid", args.res);
    write_grid(
        &args.out,
        args.res,
        &grid,
        &heatmap(title, quantity, kernel.scene(), &grid, args.log),
    )?;
    eprintln!(
        "wrote {what} on a {0}x{0} grid to {1}",
        args.res,
        args.out.display()
    );
    Ok(())
}

/// [`Kernel::grid`], a few rows at a time so that Ctrl-C stops it (the same values).
fn grid(kernel: &Kernel, res: usize, weighted: bool) -> anyhow::Result<Vec<f64>> {
    let mut grid = Vec::with_capacity(res * res);
    let n = res as f64;
    for rows in (0..res).collect::<Vec<_>>().chunks(ROWS_PER_CHUNK) {
        interrupt::check()?;
        let first = rows[0] * res;
        let chunk: Vec<f64> = (first..first + rows.len() * res)
            .into_par_iter()
            .with_min_len(1024)
            .map(|idx| {
                let s = ((idx / res) as f64 + 0.5) / n;
                let t = ((idx % res) as f64 + 0.5) / n;
                if weighted {
                    kernel.zeta(s, t)
                } else {
                    kernel.k(s, t)
                }
            })
            .collect();
        grid.extend(chunk);
    }
    Ok(grid)
}
