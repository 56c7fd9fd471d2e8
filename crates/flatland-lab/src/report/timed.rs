//! The timed bench's outputs: `results.csv` (kept row by row while it runs), the log–log plots
//! of the solved `B − E` error against total time, bytes and basis functions, and the tables
//! `flatland bench` prints.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use flatland_pictures::plot::{Series, log_log};

use crate::interrupt;
use crate::timed::relight::{RelightRow, summaries};
use crate::timed::{Method, TimedRow};

/// The file the rows are kept in while the bench runs; renamed to [`RESULTS`] at the end.
pub const PARTIAL: &str = "results.partial.csv";

/// The rows of a finished bench.
pub const RESULTS: &str = "results.csv";

/// Files `flatland bench` writes into its folder.
pub const OUTPUTS: [&str; 7] = [
    RESULTS,
    PARTIAL,
    RELIGHT,
    "solve_vs_time.png",
    "solve_vs_bytes.png",
    "solve_vs_basis.png",
    "zeta_vs_basis.png",
];

/// The relighting rows: one per method and lighting.
pub const RELIGHT: &str = "relight.csv";

/// The header of `relight.csv`.
pub const RELIGHT_HEADER: [&str; 7] = [
    "scene",
    "method",
    "lighting",
    "seconds",
    "rel_l2_reflected",
    "rel_l2_b",
    "note",
];

/// Writes the relighting rows to `dir/relight.csv` atomically.
pub fn write_relight(dir: &Path, scene: &str, rows: &[RelightRow]) -> Result<()> {
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record(RELIGHT_HEADER)?;
    for r in rows {
        csv.write_record([
            scene.to_owned(),
            r.method.name().to_owned(),
            r.lighting.to_string(),
            r.seconds.to_string(),
            r.errors.rel_l2_reflected.to_string(),
            r.errors.rel_l2_b.to_string(),
            r.note.clone(),
        ])?;
    }
    let text = csv
        .into_inner()
        .map_err(|e| anyhow::anyhow!("writing the CSV: {e}"))?;
    interrupt::writing(|| flatland_geom::write_atomic(&dir.join(RELIGHT), &text))?;
    Ok(())
}

/// One line per method: the time to every lit scene and the errors.
pub fn relight_summary(rows: &[RelightRow]) -> String {
    let mut out = String::new();
    let lightings = rows.iter().map(|r| r.lighting + 1).max().unwrap_or(0);
    for s in summaries(rows) {
        let _ = writeln!(
            out,
            "relighting, {lightings} lightings: {} {:.3} s in all, B − E error mean {:.4}, max \
             {:.4} ({})",
            s.method.name(),
            s.total_s,
            s.mean_error,
            s.max_error,
            s.note
        );
    }
    out
}

/// The header of `results.csv`.
pub const CSV_HEADER: [&str; 17] = [
    "scene",
    "method",
    "setting",
    "value",
    "seed",
    "basis_functions",
    "build_s",
    "solve_s",
    "total_s",
    "bytes",
    "rays",
    "rel_l2_zeta_heldout",
    "rel_l2_reflected",
    "rel_l2_b",
    "estimated_error",
    "note",
    "failed",
];

/// The total times the summary reports the error reached within.
pub const WITHIN_SECONDS: [f64; 3] = [0.3, 1.0, 5.0];

fn optional(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| v.to_string())
}

/// The rows as CSV text.
pub fn csv_text(scene: &str, rows: &[TimedRow]) -> Result<Vec<u8>> {
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record(CSV_HEADER)?;
    for r in rows {
        csv.write_record([
            scene.to_owned(),
            r.method.name().to_owned(),
            r.setting.kind().to_owned(),
            r.setting.value(),
            r.seed.to_string(),
            r.basis_functions.map_or(String::new(), |n| n.to_string()),
            r.build_s.to_string(),
            r.solve_s.to_string(),
            r.total_s.to_string(),
            r.bytes.to_string(),
            r.rays.to_string(),
            optional(r.zeta_error()),
            optional(r.reflected_error()),
            optional(r.solve.map(|e| e.rel_l2_b)),
            optional(r.estimated_error),
            r.note.clone(),
            r.failed.to_string(),
        ])?;
    }
    csv.into_inner()
        .map_err(|e| anyhow::anyhow!("writing the CSV: {e}"))
}

/// Writes `rows` to `dir/name` atomically (never cut by Ctrl-C).
pub fn write_rows(dir: &Path, name: &str, scene: &str, rows: &[TimedRow]) -> Result<()> {
    let text = csv_text(scene, rows)?;
    interrupt::writing(|| flatland_geom::write_atomic(&dir.join(name), &text))?;
    Ok(())
}

/// What a plot puts on its x axis (`None`: the row is not drawn).
pub(crate) type XAxis = fn(&TimedRow) -> Option<f64>;

/// The plots of one scene's rows: the solved `B − E` error against total time, bytes and basis
/// functions (one curve per method), and ζ's held-out error against basis functions.
pub fn write_plots(dir: &Path, scene: &str, rows: &[TimedRow]) -> Result<()> {
    let solved: [(&str, &str, XAxis); 3] = [
        ("solve_vs_time.png", "total time, build + solve (s)", |r| {
            Some(r.total_s)
        }),
        ("solve_vs_bytes.png", "bytes", |r| Some(r.bytes as f64)),
        ("solve_vs_basis.png", "basis functions", |r| {
            r.basis_functions.map(|n| n as f64)
        }),
    ];
    for (file, x_label, x) in solved {
        let title = format!("{scene}: solved radiosity, reflected part, vs {x_label}");
        let series = series(rows, x, TimedRow::reflected_error);
        let png = log_log(&title, x_label, "relative L2 error of B − E", &series)?;
        interrupt::writing(|| flatland_geom::write_atomic(&dir.join(file), &png))?;
    }
    let zeta = series(
        rows,
        |r| r.basis_functions.map(|n| n as f64),
        TimedRow::zeta_error,
    );
    if zeta.iter().any(|s| !s.points.is_empty()) {
        let png = log_log(
            &format!("{scene}: relative L2 of ζ̃ (held out) vs basis functions"),
            "basis functions",
            "relative L2 error (held out)",
            &zeta,
        )?;
        interrupt::writing(|| flatland_geom::write_atomic(&dir.join("zeta_vs_basis.png"), &png))?;
    }
    Ok(())
}

/// The rows of each method and setting, in the order they ran.
fn groups(rows: &[TimedRow]) -> BTreeMap<Method, Vec<Vec<&TimedRow>>> {
    let mut by_method: BTreeMap<Method, Vec<Vec<&TimedRow>>> = BTreeMap::new();
    for r in rows.iter().filter(|r| !r.failed) {
        let settings = by_method.entry(r.method).or_default();
        match settings.last_mut() {
            Some(group) if group[0].setting == r.setting => group.push(r),
            _ => settings.push(vec![r]),
        }
    }
    by_method
}

/// Per method and setting: the mean x and the mean, min and max of `y` over seeds.
pub(crate) fn series(rows: &[TimedRow], x: XAxis, y: fn(&TimedRow) -> Option<f64>) -> Vec<Series> {
    groups(rows)
        .into_iter()
        .map(|(method, settings)| {
            let mut points: Vec<(f64, f64, f64, f64)> = settings
                .iter()
                .filter_map(|group| {
                    let xy: Vec<(f64, f64)> =
                        group.iter().filter_map(|r| Some((x(r)?, y(r)?))).collect();
                    if xy.is_empty() {
                        return None;
                    }
                    let n = xy.len() as f64;
                    let mean_x = xy.iter().map(|p| p.0).sum::<f64>() / n;
                    let mean = xy.iter().map(|p| p.1).sum::<f64>() / n;
                    let min = xy.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
                    let max = xy.iter().map(|p| p.1).fold(0.0, f64::max);
                    Some((mean_x, mean, min, max))
                })
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                label: method.name().to_owned(),
                points,
            }
        })
        .collect()
}

/// A Markdown table of the rows, averaged over seeds; failed rows listed with their reason.
pub fn table(rows: &[TimedRow]) -> String {
    let mut out = String::from(
        "| method | setting | basis fns | build s | solve s | total s | bytes | ζ held out \
         | B − E as a function | estimated | note |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    let text = |v: Option<f64>| v.map_or("–".to_owned(), |v| format!("{v:.4}"));
    for (method, settings) in groups(rows) {
        for g in settings {
            let n = g.len() as f64;
            let mean = |f: &dyn Fn(&TimedRow) -> f64| g.iter().map(|r| f(r)).sum::<f64>() / n;
            let mean_of = |f: &dyn Fn(&TimedRow) -> Option<f64>| {
                let v: Vec<f64> = g.iter().filter_map(|r| f(r)).collect();
                (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
            };
            let basis = mean_of(&|r| r.basis_functions.map(|b| b as f64));
            let _ = writeln!(
                out,
                "| {} | {} {} | {} | {:.3} | {:.3} | {:.3} | {:.0} | {} | {} | {} | {} |",
                method.name(),
                g[0].setting.kind(),
                g[0].setting.value(),
                basis.map_or("–".to_owned(), |b| format!("{b:.0}")),
                mean(&|r| r.build_s),
                mean(&|r| r.solve_s),
                mean(&|r| r.total_s),
                mean(&|r| r.bytes as f64),
                text(mean_of(&TimedRow::zeta_error)),
                text(mean_of(&TimedRow::reflected_error)),
                text(mean_of(&|r| r.estimated_error)),
                g.last().map_or("", |r| r.note.as_str()),
            );
        }
    }
    for r in rows.iter().filter(|r| r.failed) {
        let _ = writeln!(
            out,
            "| {} | {} {} | – | – | – | – | – | – | – | – | {} |",
            r.method.name(),
            r.setting.kind(),
            r.setting.value(),
            r.note
        );
    }
    out
}

/// Per method, the least solved `B − E` error among its rows whose total time is within each
/// of `seconds` (`None`: no row was that fast).
pub fn error_within(rows: &[TimedRow], seconds: &[f64]) -> Vec<(Method, Vec<Option<f64>>)> {
    groups(rows)
        .into_iter()
        .map(|(method, settings)| {
            let best = seconds
                .iter()
                .map(|&limit| {
                    settings
                        .iter()
                        .flatten()
                        .filter(|r| r.total_s <= limit)
                        .filter_map(|r| r.reflected_error())
                        .min_by(f64::total_cmp)
                })
                .collect();
            (method, best)
        })
        .collect()
}

/// [`error_within`] as a Markdown table.
pub fn within_table(rows: &[TimedRow]) -> String {
    let mut out = String::from("| method |");
    for s in WITHIN_SECONDS {
        let _ = write!(out, " B − E within {s} s |");
    }
    out.push_str("\n|---|");
    out.push_str(&"---:|".repeat(WITHIN_SECONDS.len()));
    out.push('\n');
    for (method, best) in error_within(rows, &WITHIN_SECONDS) {
        let _ = write!(out, "| {} |", method.name());
        for b in best {
            let _ = write!(
                out,
                " {} |",
                b.map_or("–".to_owned(), |e| format!("{e:.4}"))
            );
        }
        out.push('\n');
    }
    out
}
