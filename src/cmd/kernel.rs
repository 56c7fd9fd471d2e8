//! `flatland kernel`: the exact kernel `k(s,t)` (or `ζ`) on an R×R grid, as CSV or a PNG heatmap.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use flatland_geom::{Kernel, write_atomic};
use rayon::prelude::*;

use super::SceneArgs;
use crate::plot::{Heatmap, heatmap_png};
use crate::{interrupt, output};

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

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Output {
    Csv,
    Png,
}

fn output_of(path: &Path) -> anyhow::Result<Output> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("csv") => Ok(Output::Csv),
        Some("png") => Ok(Output::Png),
        _ => bail!(
            "{}: unknown output format (expected a .csv or .png file name)",
            path.display()
        ),
    }
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

/// A heatmap of `grid` over `scene` whose top colour is [`top_value`] of the grid.
pub fn heatmap<'a>(
    title: String,
    quantity: &'a str,
    scene: &'a flatland_geom::Scene,
    grid: &[f64],
    log: bool,
) -> Heatmap<'a> {
    Heatmap {
        title,
        quantity,
        scene,
        log,
        top: top_value(grid),
        overlay: None,
    }
}

/// R lines of R comma-separated values (shortest round-trip decimal form).
fn csv(grid: &[f64], res: usize) -> String {
    let mut out = String::with_capacity(grid.len() * 12);
    for row in grid.chunks(res) {
        let line: Vec<String> = row.iter().map(f64::to_string).collect();
        out.push_str(&line.join(","));
        out.push('\n');
    }
    out
}

/// Decades shown by `--log`.
pub(crate) const LOG_DECADES: f64 = 4.0;

/// The value that maps to the top colour: the 99.5th percentile of the positive values, since
/// the kernel is unbounded (≈ 1/r) at shared corners and the maximum would wash out the rest.
pub(crate) fn top_value(grid: &[f64]) -> f64 {
    let mut positive: Vec<f64> = grid.iter().copied().filter(|&v| v > 0.0).collect();
    if positive.is_empty() {
        return 1.0;
    }
    positive.sort_by(f64::total_cmp);
    positive[((positive.len() - 1) as f64 * 0.995) as usize]
}

/// Maps each value to `[0, 1]` (linear from 0, or log over [`LOG_DECADES`]), clamped.
pub(crate) fn normalise(grid: &[f64], log: bool, top: f64) -> Vec<f64> {
    grid.iter()
        .map(|&v| {
            let x = if log {
                if v <= 0.0 {
                    0.0
                } else {
                    1.0 + (v / top).log10() / LOG_DECADES
                }
            } else {
                v / top
            };
            x.clamp(0.0, 1.0)
        })
        .collect()
}

/// Viridis (perceptually uniform; matplotlib's, sampled at 17 points), linearly interpolated.
const VIRIDIS: [[u8; 3]; 17] = [
    [68, 1, 84],
    [72, 21, 104],
    [72, 38, 119],
    [69, 55, 129],
    [63, 71, 136],
    [57, 85, 140],
    [50, 100, 142],
    [45, 113, 142],
    [40, 125, 142],
    [35, 138, 141],
    [31, 150, 139],
    [32, 163, 134],
    [41, 175, 127],
    [62, 188, 116],
    [86, 198, 103],
    [119, 209, 83],
    [253, 231, 37],
];

/// The colour of `x ∈ [0, 1]`.
pub(crate) fn viridis(x: f64) -> [u8; 3] {
    let f = x.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let i = (f as usize).min(VIRIDIS.len() - 2);
    let w = f - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    std::array::from_fn(|c| (f64::from(a[c]) * (1.0 - w) + f64::from(b[c]) * w).round() as u8)
}

/// Writes any R×R grid (row ↔ s) as CSV or the PNG heatmap `map`, chosen by `path`'s
/// extension, atomically (Ctrl-C waits for the write): what `flatland eval` shares with this
/// command.
pub fn write_grid(path: &Path, res: usize, grid: &[f64], map: &Heatmap<'_>) -> anyhow::Result<()> {
    let bytes = match output_of(path)? {
        Output::Csv => csv(grid, res).into_bytes(),
        Output::Png => heatmap_png(grid, res, map)?,
    };
    interrupt::writing(|| write_atomic(path, &bytes)).context("cannot write the output")?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_runs_from_dark_purple_to_yellow_and_brightens() {
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(viridis(f64::NAN.max(-1.0)), viridis(0.0));
        let luma =
            |c: [u8; 3]| 0.3 * f64::from(c[0]) + 0.59 * f64::from(c[1]) + 0.11 * f64::from(c[2]);
        for i in 0..100 {
            assert!(luma(viridis(f64::from(i) / 100.0)) <= luma(viridis(f64::from(i + 1) / 100.0)));
        }
    }

    #[test]
    fn normalise_clamps_and_logs() {
        let grid = [0.0, 1e-9, 0.01, 1.0, 1e9];
        let lin = normalise(&grid, false, top_value(&grid));
        assert!(lin.iter().all(|x| (0.0..=1.0).contains(x)));
        assert_eq!(normalise(&[0.5], false, 1.0), vec![0.5]);
        let log = normalise(&[0.0, 1e-3, 1e-2, 1.0], true, 1.0);
        assert_eq!(log[0], 0.0);
        assert!((log[2] - 0.5).abs() < 1e-12, "{log:?}");
        assert_eq!(log[3], 1.0);
    }

    #[test]
    fn top_value_ignores_the_corner_spikes() {
        let mut grid: Vec<f64> = (0..1000).map(|i| f64::from(i) / 1000.0).collect();
        grid.push(1e12);
        assert!(top_value(&grid) < 1.0);
        assert_eq!(top_value(&[0.0, 0.0]), 1.0);
    }

    #[test]
    fn csv_has_res_lines_of_res_values() {
        let text = csv(&[1.0, 0.5, 0.0, 0.25], 2);
        assert_eq!(text, "1,0.5\n0,0.25\n");
    }
}
