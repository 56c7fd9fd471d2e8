//! The bench's outputs, shared by `flatland bench` and `flatland results`: the runner that keeps
//! rows as it goes, `results.csv`, the log–log plots and the Markdown table.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

use crate::bench::{BenchPlan, BenchRow, Method, run_bench};
use anyhow::Result;
use flatland_pictures::plot::{Series, log_log};
use flatland_solve::Reference;

use crate::{Defined, error_text, interrupt};

/// Files `flatland bench` writes into its folder.
pub const OUTPUTS: [&str; 6] = [
    "results.csv",
    "error_vs_basis.png",
    "error_vs_time.png",
    "error_vs_rays.png",
    "solve_vs_basis.png",
    "solve_vs_time.png",
];

/// The header of `results.csv`.
pub const CSV_HEADER: [&str; 18] = [
    "scene",
    "method",
    "budget",
    "seed",
    "basis_functions",
    "rel_l2_grid",
    "rel_l2_heldout",
    "rel_l2_heldout_p05",
    "rel_l2_heldout_p95",
    "rel_l1_grid",
    "rel_l1_heldout",
    "rays",
    "wall_s",
    "memory_bytes",
    "bytes_per_basis",
    "rel_l2_b",
    "rel_l2_reflected",
    "solve_s",
];

/// [`run_bench`] one budget at a time (the same rows in the same order), calling `kept` with
/// the rows so far after each budget and checking for Ctrl-C in between.
pub fn run_kept(
    kernel: &Arc<flatland_geom::Kernel>,
    reference: &Arc<Reference>,
    plan: &BenchPlan,
    mut kept: impl FnMut(&[BenchRow]) -> Result<()>,
) -> Result<Vec<BenchRow>> {
    let mut rows = Vec::new();
    for &budget in &plan.budgets {
        interrupt::check()?;
        let one = BenchPlan {
            budgets: vec![budget],
            ..plan.clone()
        };
        rows.extend(run_bench(kernel, reference, &one, |_, _| {})?);
        kept(&rows)?;
    }
    Ok(rows)
}

/// What a plot puts on its x axis.
type XAxis = fn(&BenchRow) -> f64;

/// `results.csv` and the three log–log plots of one scene's rows. An undefined error (see
/// [`Defined`]) is an empty CSV field and is left out of the plots.
pub fn write_outputs(dir: &Path, scene: &str, rows: &[BenchRow], defined: Defined) -> Result<()> {
    let mut csv = csv::Writer::from_writer(Vec::new());
    csv.write_record(CSV_HEADER)?;
    let field = |ok: bool, v: f64| if ok { v.to_string() } else { String::new() };
    for r in rows {
        let solve = |f: fn(&flatland_solve::SolveErrors) -> f64| {
            r.solve.as_ref().map_or(String::new(), |e| f(e).to_string())
        };
        csv.write_record([
            scene.to_owned(),
            r.method.name().to_owned(),
            r.budget.to_string(),
            r.seed.to_string(),
            r.basis_functions.to_string(),
            field(defined.grid, r.errors.grid),
            field(defined.heldout, r.errors.heldout),
            field(defined.heldout, r.errors.heldout_spread[0]),
            field(defined.heldout, r.errors.heldout_spread[1]),
            field(defined.grid, r.errors.l1_grid),
            field(defined.heldout, r.errors.l1_heldout),
            r.rays.to_string(),
            r.wall_s.to_string(),
            r.memory_bytes.to_string(),
            (r.memory_bytes as f64 / r.basis_functions.max(1) as f64).to_string(),
            solve(|e| e.rel_l2_b),
            solve(|e| e.rel_l2_reflected),
            if r.solve.is_some() {
                r.solve_s.to_string()
            } else {
                String::new()
            },
        ])?;
    }
    let csv = csv
        .into_inner()
        .map_err(|e| anyhow::anyhow!("writing the CSV: {e}"))?;
    interrupt::writing(|| flatland_geom::write_atomic(&dir.join("results.csv"), &csv))?;
    if !defined.heldout {
        return Ok(());
    }
    let axes: [(&str, &str, XAxis); 3] = [
        ("error_vs_basis.png", "basis functions", |r| {
            r.basis_functions as f64
        }),
        ("error_vs_time.png", "wall time (s)", |r| r.wall_s),
        ("error_vs_rays.png", "rays", |r| r.rays as f64),
    ];
    for (file, x_label, x) in axes {
        let series = series(rows, x, |r| Some(r.errors.heldout));
        let title = format!("{scene}: relative L2 (held out) vs {x_label}");
        let png = log_log(&title, x_label, "relative L2 error (held out)", &series)?;
        interrupt::writing(|| flatland_geom::write_atomic(&dir.join(file), &png))?;
    }
    if rows.iter().any(|r| r.solve.is_some()) {
        let solved: [(&str, &str, XAxis); 2] = [
            ("solve_vs_basis.png", "basis functions", |r| {
                r.basis_functions as f64
            }),
            ("solve_vs_time.png", "wall time to build (s)", |r| r.wall_s),
        ];
        for (file, x_label, x) in solved {
            let series = series(rows, x, |r| r.solve.map(|e| e.rel_l2_reflected));
            let title = format!("{scene}: solved radiosity, reflected part, vs {x_label}");
            let png = log_log(&title, x_label, "relative L2 error of B − E", &series)?;
            interrupt::writing(|| flatland_geom::write_atomic(&dir.join(file), &png))?;
        }
    }
    Ok(())
}

/// Per method and budget: x and the mean, min and max of `y` over seeds (rows without a `y`
/// are left out).
fn series(
    rows: &[BenchRow],
    x: fn(&BenchRow) -> f64,
    y: fn(&BenchRow) -> Option<f64>,
) -> Vec<Series> {
    let mut by_method: BTreeMap<Method, BTreeMap<usize, Vec<&BenchRow>>> = BTreeMap::new();
    for r in rows {
        by_method
            .entry(r.method)
            .or_default()
            .entry(r.budget)
            .or_default()
            .push(r);
    }
    by_method
        .into_iter()
        .map(|(method, budgets)| Series {
            label: method.name().to_owned(),
            points: budgets
                .values()
                .filter_map(|group| {
                    let group: Vec<&&BenchRow> = group.iter().filter(|r| y(r).is_some()).collect();
                    if group.is_empty() {
                        return None;
                    }
                    let n = group.len() as f64;
                    let errors: Vec<f64> = group.iter().filter_map(|r| y(r)).collect();
                    let mean_x = group.iter().map(|r| x(r)).sum::<f64>() / n;
                    let mean = errors.iter().sum::<f64>() / n;
                    let min = errors.iter().copied().fold(f64::INFINITY, f64::min);
                    let max = errors.iter().copied().fold(0.0, f64::max);
                    Some((mean_x, mean, min, max))
                })
                .collect(),
        })
        .collect()
}

/// A Markdown table of the rows, averaged over seeds.
pub fn table(rows: &[BenchRow], defined: Defined) -> String {
    let mut groups: BTreeMap<(usize, Method), Vec<&BenchRow>> = BTreeMap::new();
    for r in rows {
        groups.entry((r.budget, r.method)).or_default().push(r);
    }
    let mut out = String::from(
        "| budget | method | basis fns | rel. L2 grid | rel. L2 held out (min–max) | rel. L1 grid \
         | solved B − E | rays | build s | bytes / basis fn |\n\
         |---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for ((budget, method), g) in groups {
        let n = g.len() as f64;
        let mean = |f: &dyn Fn(&BenchRow) -> f64| g.iter().map(|r| f(r)).sum::<f64>() / n;
        let lo = g
            .iter()
            .map(|r| r.errors.heldout)
            .fold(f64::INFINITY, f64::min);
        let hi = g.iter().map(|r| r.errors.heldout).fold(0.0, f64::max);
        let heldout = if defined.heldout {
            format!("{:.3} ({lo:.3}–{hi:.3})", mean(&|r| r.errors.heldout))
        } else {
            "undefined".to_owned()
        };
        let solved = if g.iter().all(|r| r.solve.is_some()) {
            format!(
                "{:.4}",
                mean(&|r| r.solve.map_or(0.0, |e| e.rel_l2_reflected))
            )
        } else {
            "–".to_owned()
        };
        let _ = writeln!(
            out,
            "| {budget} | {} | {:.0} | {} | {heldout} | {} | {solved} | {:.0} | {:.3} | {:.0} |",
            method.name(),
            mean(&|r| r.basis_functions as f64),
            error_text(mean(&|r| r.errors.grid), defined.grid, 3),
            error_text(mean(&|r| r.errors.l1_grid), defined.grid, 3),
            mean(&|r| r.rays as f64),
            mean(&|r| r.wall_s),
            mean(&|r| r.memory_bytes as f64 / r.basis_functions.max(1) as f64),
        );
    }
    out
}

/// Per method, the slope of log(grid error) against log(basis functions), least squares over
/// the budgets' seed means; `None` with fewer than two budgets of non-zero error (a method that
/// is exact from its smallest budget on has no rate to state).
pub fn slopes(rows: &[BenchRow]) -> Vec<(Method, Option<f64>)> {
    let mut means: BTreeMap<Method, BTreeMap<usize, (f64, f64, f64)>> = BTreeMap::new();
    for r in rows {
        let m = means
            .entry(r.method)
            .or_default()
            .entry(r.budget)
            .or_default();
        m.0 += r.basis_functions as f64;
        m.1 += r.errors.grid;
        m.2 += 1.0;
    }
    means
        .into_iter()
        .map(|(method, budgets)| {
            let points: Vec<(f64, f64)> = budgets
                .values()
                .map(|(x, y, n)| (x / n, y / n))
                .filter(|(x, y)| *x > 0.0 && *y > 1e-12)
                .map(|(x, y)| (x.ln(), y.ln()))
                .collect();
            (method, least_squares_slope(&points))
        })
        .collect()
}

fn least_squares_slope(points: &[(f64, f64)]) -> Option<f64> {
    let n = points.len() as f64;
    let mean_x = points.iter().map(|p| p.0).sum::<f64>() / n;
    let mean_y = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum();
    (points.len() >= 2 && sxx > 1e-12).then(|| sxy / sxx)
}

/// The seed mean of `f` over `method`'s rows at `budget`, `None` without rows.
pub fn mean_at(
    rows: &[BenchRow],
    method: Method,
    budget: usize,
    f: impl Fn(&BenchRow) -> Option<f64>,
) -> Option<f64> {
    let values: Vec<f64> = rows
        .iter()
        .filter(|r| r.method == method && r.budget == budget)
        .filter_map(f)
        .collect();
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slope_of_a_power_law_is_its_exponent() {
        let points: Vec<(f64, f64)> = [10.0f64, 20.0, 40.0, 80.0]
            .iter()
            .map(|x| (x.ln(), (3.0 * x.powf(-1.5)).ln()))
            .collect();
        let slope = least_squares_slope(&points).unwrap();
        assert!((slope + 1.5).abs() < 1e-12, "{slope}");
        assert_eq!(least_squares_slope(&points[..1]), None);
        let flat = [(1.0, 0.0), (1.0, 1.0)];
        assert_eq!(least_squares_slope(&flat), None, "one x: no slope");
    }
}
