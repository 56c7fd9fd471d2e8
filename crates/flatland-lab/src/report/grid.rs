//! A grid of values written as CSV or as a PNG heatmap ([`flatland_pictures::plot::heatmap_png`]),
//! chosen by the file name: what `flatland kernel` and `flatland eval` write.

use std::path::Path;

use anyhow::{Context, bail};
use flatland_geom::write_atomic;
use flatland_pictures::plot::{Heatmap, heatmap_png};

use crate::interrupt;

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// Comma-separated values.
    Csv,
    /// A heatmap image.
    Png,
}

/// The output format of `path`, by its extension (`.csv` or `.png`, any case).
pub fn output_of(path: &Path) -> anyhow::Result<Output> {
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

/// Writes any R×R grid (row ↔ s) as CSV or the PNG heatmap `map`, chosen by `path`'s
/// extension, atomically (Ctrl-C waits for the write): what `flatland kernel` and `flatland eval`
/// share.
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
    fn csv_has_res_lines_of_res_values() {
        let text = csv(&[1.0, 0.5, 0.0, 0.25], 2);
        assert_eq!(text, "1,0.5\n0,0.25\n");
    }
}
