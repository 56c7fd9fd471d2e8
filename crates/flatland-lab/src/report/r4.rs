//! RESULTS.md's R4 section (every network and baseline at every budget): a scene's rows of
//! the R4 plan ([`TimedPlan::r4`](crate::timed::TimedPlan::r4)) written as the bench writes
//! them (`results.csv` and its plots) with ζ's error against build time and rays beside, the
//! Markdown table with the errors of ζ, the rates, and seed means at one budget.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use flatland_pictures::plot::log_log;

use super::timed::{RESULTS, XAxis, series, write_plots, write_rows};
use crate::timed::{Method, Setting, TimedRow};
use crate::{Defined, error_text, interrupt};

/// Files written into each scene's folder.
pub const OUTPUTS: [&str; 7] = [
    RESULTS,
    "solve_vs_time.png",
    "solve_vs_bytes.png",
    "solve_vs_basis.png",
    "zeta_vs_basis.png",
    "zeta_vs_time.png",
    "zeta_vs_rays.png",
];

/// `results.csv` and the plots of one scene's rows: the bench's, and ζ's held-out error against
/// build time and rays. An undefined error (see [`Defined`]) is an empty CSV field and is left
/// out of the plots.
pub fn write_outputs(dir: &Path, scene: &str, rows: &[TimedRow]) -> Result<()> {
    write_rows(dir, RESULTS, scene, rows)?;
    write_plots(dir, scene, rows)?;
    let axes: [(&str, &str, XAxis); 2] = [
        ("zeta_vs_time.png", "build time (s)", |r| Some(r.build_s)),
        ("zeta_vs_rays.png", "rays", |r| Some(r.rays as f64)),
    ];
    for (file, x_label, x) in axes {
        let series = series(rows, x, TimedRow::zeta_error);
        if series.iter().all(|s| s.points.is_empty()) {
            continue;
        }
        let title = format!("{scene}: relative L2 of ζ̃ (held out) vs {x_label}");
        let png = log_log(&title, x_label, "relative L2 error (held out)", &series)?;
        interrupt::writing(|| flatland_geom::write_atomic(&dir.join(file), &png))?;
    }
    Ok(())
}

/// The rows at each budget and method that did not fail.
fn by_budget(rows: &[TimedRow]) -> BTreeMap<(usize, Method), Vec<&TimedRow>> {
    let mut groups: BTreeMap<(usize, Method), Vec<&TimedRow>> = BTreeMap::new();
    for r in rows.iter().filter(|r| !r.failed) {
        if let Setting::Budget(budget) = r.setting {
            groups.entry((budget, r.method)).or_default().push(r);
        }
    }
    groups
}

/// The mean of `f` over the rows that have it.
fn mean_of(rows: &[&TimedRow], f: impl Fn(&TimedRow) -> Option<f64>) -> Option<f64> {
    let values: Vec<f64> = rows.iter().filter_map(|r| f(r)).collect();
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// A Markdown table of the rows, averaged over seeds; failed rows listed with their reason.
pub fn table(rows: &[TimedRow], defined: Defined) -> String {
    let mut out = String::from(
        "| budget | method | basis fns | rel. L2 grid | rel. L2 held out (min–max) | rel. L1 grid \
         | B − E as a function | rays | build s | bytes / basis fn |\n\
         |---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let zeta = |value: Option<f64>, ok: bool| match value {
        Some(v) => error_text(v, ok, 3),
        None if ok => "–".to_owned(),
        None => "undefined".to_owned(),
    };
    for ((budget, method), g) in by_budget(rows) {
        let heldout = g.iter().filter_map(|r| r.zeta_error());
        let lo = heldout.clone().fold(f64::INFINITY, f64::min);
        let hi = heldout.fold(0.0, f64::max);
        let heldout = match mean_of(&g, TimedRow::zeta_error) {
            Some(mean) if defined.heldout => format!("{mean:.3} ({lo:.3}–{hi:.3})"),
            other => zeta(other, defined.heldout),
        };
        let solved = mean_of(&g, TimedRow::reflected_error)
            .filter(|_| g.iter().all(|r| r.solve.is_some()))
            .map_or("–".to_owned(), |e| format!("{e:.4}"));
        let basis = |r: &TimedRow| r.basis_functions.unwrap_or(0) as f64;
        let _ = writeln!(
            out,
            "| {budget} | {} | {:.0} | {} | {heldout} | {} | {solved} | {:.0} | {:.3} | {:.0} |",
            method.name(),
            mean_of(&g, |r| Some(basis(r))).unwrap_or(0.0),
            zeta(mean_of(&g, |r| r.zeta.map(|e| e.grid)), defined.grid),
            zeta(mean_of(&g, |r| r.zeta.map(|e| e.l1_grid)), defined.grid),
            mean_of(&g, |r| Some(r.rays as f64)).unwrap_or(0.0),
            mean_of(&g, |r| Some(r.build_s)).unwrap_or(0.0),
            mean_of(&g, |r| Some(r.bytes as f64 / basis(r).max(1.0))).unwrap_or(0.0),
        );
    }
    for r in rows.iter().filter(|r| r.failed) {
        let _ = writeln!(
            out,
            "| {} | {} | – | – | – | – | – | – | – | {} |",
            r.setting.value(),
            r.method.name(),
            r.note
        );
    }
    out
}

/// Per method, the slope of log(grid error) against log(basis functions), least squares over
/// the budgets' seed means; `None` with fewer than two budgets of non-zero error (a method that
/// is exact from its smallest budget on has no rate to state).
pub fn slopes(rows: &[TimedRow]) -> Vec<(Method, Option<f64>)> {
    let mut means: BTreeMap<Method, BTreeMap<usize, (f64, f64, f64)>> = BTreeMap::new();
    for ((budget, method), g) in by_budget(rows) {
        let m = means.entry(method).or_default().entry(budget).or_default();
        for r in g {
            let (Some(basis), Some(zeta)) = (r.basis_functions, r.zeta) else {
                continue;
            };
            m.0 += basis as f64;
            m.1 += zeta.grid;
            m.2 += 1.0;
        }
    }
    means
        .into_iter()
        .map(|(method, budgets)| {
            let points: Vec<(f64, f64)> = budgets
                .values()
                .filter(|(_, _, n)| *n > 0.0)
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
    rows: &[TimedRow],
    method: Method,
    budget: usize,
    f: impl Fn(&TimedRow) -> Option<f64>,
) -> Option<f64> {
    let at: Vec<&TimedRow> = rows
        .iter()
        .filter(|r| r.method == method && r.setting == Setting::Budget(budget) && !r.failed)
        .collect();
    mean_of(&at, f)
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
