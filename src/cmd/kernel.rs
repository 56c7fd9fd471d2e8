//! `flatland kernel`: the exact kernel `k(s,t)` (or `ζ`) on an R×R grid, as CSV or a PNG heatmap.

use std::path::PathBuf;

use flatland_geom::Kernel;
use rayon::prelude::*;

use super::SceneArgs;
use flatland_lab::report::grid::{output_of, write_grid};
use flatland_lab::{interrupt, output};
use flatland_pictures::colormap::Scale;
use flatland_pictures::plot::heatmap;

/// Arguments of `flatland kernel`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Grid resolution R in [16, 4096]: row i is s = (i+0.5)/R, column j is t = (j+0.5)/R.
    /// On a scene of more than R surface edges a cell spans several pairs of edges, and a
    /// value at its centre would miss most of what the edges see: each value is then the mean
    /// over m × m points of the cell (m = 4 × edges / R, from 2 to 8).
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Write zeta = E'(e_x) k (the learning target) instead of k.
    #[arg(long)]
    pub weighted: bool,
    /// PNG only: colour by log10 of the value over the top four decades. Default: log where
    /// the values span decades (the top is over 20× their median, as on a floor plan), linear
    /// elsewhere.
    #[arg(long, conflicts_with = "linear")]
    pub log: bool,
    /// PNG only: a linear colour scale even where the values span decades.
    #[arg(long)]
    pub linear: bool,
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
    let m = points_per_side(kernel.scene().surface_edges().len(), args.res);
    if m > 1 {
        eprintln!(
            "each cell is the mean over {m}×{m} points (more edges than the grid has room for)"
        );
    }
    let grid = grid(&kernel, args.res, m, args.weighted)?;
    let quantity = if args.weighted { "ζ(s, t)" } else { "k(s, t)" };
    let log = args.log || (!args.linear && Scale::wants_log(&grid));
    let scale = if log { ", log scale" } else { "" };
    let title = format!("{quantity} of {label}, {0}×{0} grid{scale}", args.res);
    write_grid(
        &args.out,
        args.res,
        &grid,
        &heatmap(title, quantity, kernel.scene(), &grid, log),
    )?;
    eprintln!(
        "wrote {what} on a {0}x{0} grid to {1}",
        args.res,
        args.out.display()
    );
    Ok(())
}

/// Points per side of a cell whose mean is its value: 1 (the centre) while the grid has a cell
/// per surface edge or more, else 4 × edges / R, from 2 to 8.
fn points_per_side(surface_edges: usize, res: usize) -> usize {
    if surface_edges <= res {
        1
    } else {
        (4 * surface_edges).div_ceil(res).clamp(2, 8)
    }
}

/// The value of cell `idx`: the mean of the quantity over `m × m` midpoints of the cell.
fn cell(kernel: &Kernel, res: usize, m: usize, weighted: bool, idx: usize) -> f64 {
    let n = (res * m) as f64;
    let (i, j) = (idx / res, idx % res);
    let mut sum = 0.0;
    for a in 0..m {
        for b in 0..m {
            let s = ((i * m + a) as f64 + 0.5) / n;
            let t = ((j * m + b) as f64 + 0.5) / n;
            sum += if weighted {
                kernel.zeta(s, t)
            } else {
                kernel.k(s, t)
            };
        }
    }
    sum / (m * m) as f64
}

/// [`Kernel::grid`] (or cell means), a few rows at a time so that Ctrl-C stops it.
fn grid(kernel: &Kernel, res: usize, m: usize, weighted: bool) -> anyhow::Result<Vec<f64>> {
    let mut grid = Vec::with_capacity(res * res);
    for rows in (0..res).collect::<Vec<_>>().chunks(ROWS_PER_CHUNK) {
        interrupt::check()?;
        let first = rows[0] * res;
        let chunk: Vec<f64> = (first..first + rows.len() * res)
            .into_par_iter()
            .with_min_len(1024)
            .map(|idx| cell(kernel, res, m, weighted, idx))
            .collect();
        grid.extend(chunk);
    }
    Ok(grid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_testkit::assert_close;

    #[test]
    fn cells_average_only_where_the_grid_is_coarser_than_the_edges() {
        assert_eq!(points_per_side(6, 16), 1);
        assert_eq!(points_per_side(256, 256), 1);
        assert_eq!(points_per_side(257, 256), 5);
        assert_eq!(points_per_side(1000, 256), 8);
        let kernel = Kernel::new(flatland_geom::bundled::scene("fig3").unwrap());
        // One point per side is the kernel at the centre of the cell, exactly.
        let grid = grid(&kernel, 16, 1, false).unwrap();
        assert_eq!(grid[16 * 3 + 5], kernel.k(3.5 / 16.0, 5.5 / 16.0));
        // More points: their mean.
        let mean = cell(&kernel, 16, 2, false, 16 * 3 + 5);
        let points = [(6.5, 10.5), (6.5, 11.5), (7.5, 10.5), (7.5, 11.5)];
        let expected = points
            .iter()
            .map(|(s, t)| kernel.k(s / 32.0, t / 32.0))
            .sum::<f64>()
            / 4.0;
        assert_close!(mean, expected, 1e-15 * expected.abs().max(1.0));
    }
}
