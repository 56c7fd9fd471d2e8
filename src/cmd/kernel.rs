//! `flatland kernel`: the exact kernel `k(s,t)` (or `ζ`) on an R×R grid, as CSV or a PNG heatmap.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use flatland_geom::{Kernel, Scene, write_atomic};

/// Largest accepted grid resolution (R² values are kept in memory).
const MAX_RES: usize = 8192;

/// Arguments of `flatland kernel`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (.ron or .json).
    #[arg(long, default_value = "scenes/fig3.ron")]
    pub scene: PathBuf,
    /// Grid resolution R: row i is s = (i+0.5)/R, column j is t = (j+0.5)/R.
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Write zeta = E'(e_x) k (the learning target) instead of k.
    #[arg(long)]
    pub weighted: bool,
    /// PNG only: colour by log10 of the value over the top four decades.
    #[arg(long)]
    pub log: bool,
    /// Output: .csv (R lines of R comma-separated numbers) or .png (heatmap, row 0 at the top).
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

/// Evaluates the grid and writes it (atomically).
pub fn run(args: &Args) -> anyhow::Result<()> {
    let output = output_of(&args.out)?;
    if args.res == 0 || args.res > MAX_RES {
        bail!("--res must be in [1, {MAX_RES}], but is {}", args.res);
    }
    let scene = Scene::load(&args.scene)?;
    let kernel = Kernel::new(scene);
    let grid = kernel.grid(args.res, args.weighted);
    let bytes = match output {
        Output::Csv => csv(&grid, args.res).into_bytes(),
        Output::Png => png(&grid, args.res, args.log)?,
    };
    write_atomic(&args.out, &bytes)?;
    let what = if args.weighted { "zeta" } else { "k" };
    eprintln!(
        "wrote {what} on a {0}x{0} grid to {1}",
        args.res,
        args.out.display()
    );
    Ok(())
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
const LOG_DECADES: f64 = 4.0;

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

fn png(grid: &[f64], res: usize, log: bool) -> anyhow::Result<Vec<u8>> {
    use image::ImageEncoder as _;
    let pixels: Vec<u8> = normalise(grid, log, top_value(grid))
        .into_iter()
        .flat_map(viridis)
        .collect();
    let side = u32::try_from(res).context("resolution too large for a PNG")?;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(&pixels, side, side, image::ExtendedColorType::Rgb8)
        .context("cannot encode the PNG")?;
    Ok(bytes)
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

/// Writes any R×R grid (row ↔ s) as CSV or a PNG heatmap, chosen by `path`'s extension,
/// atomically: what `flatland eval` and `flatland figure` share with this command.
pub fn write_grid(path: &Path, res: usize, grid: &[f64], log: bool) -> anyhow::Result<()> {
    let bytes = match output_of(path)? {
        Output::Csv => csv(grid, res).into_bytes(),
        Output::Png => png(grid, res, log)?,
    };
    write_atomic(path, &bytes).context("cannot write the output")?;
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
