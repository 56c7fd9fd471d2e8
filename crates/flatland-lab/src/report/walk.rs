//! The outputs of `flatland bench --relight`: its CSV, its Markdown table, and the log–log
//! plots of each method's error against its milliseconds per move.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use flatland_geom::write_atomic;

use crate::timed::walk::{COLD, WalkRow, cold_row, payoff_moves};
use flatland_pictures::plot::{Series, log_log};

/// The rows so far, rewritten after each scene (removed once the results are written).
pub const PARTIAL: &str = "relight-walk.partial.csv";
/// Every row.
pub const CSV: &str = "relight-walk.csv";
/// The table.
pub const MARKDOWN: &str = "relight-walk.md";
/// The plots, one per kind of scene (so a legend of some ten series leaves the points in
/// view): the error of B, and of the indirect part, against ms per move.
pub const PLOTS: [&str; 4] = [
    "relight-walk-floorplan-b.png",
    "relight-walk-floorplan-indirect.png",
    "relight-walk-hall-b.png",
    "relight-walk-hall-indirect.png",
];
/// Every file a relighting bench writes.
pub const OUTPUTS: [&str; 7] = [
    PARTIAL, CSV, MARKDOWN, PLOTS[0], PLOTS[1], PLOTS[2], PLOTS[3],
];

/// The kind of a walk's scene: `floorplan` of `floorplan-1000`.
fn kind(scene: &str) -> &str {
    scene.rsplit_once('-').map_or(scene, |(kind, _)| kind)
}

/// The CSV's columns.
pub const HEADER: [&str; 16] = [
    "scene",
    "edges",
    "elements",
    "method",
    "setting",
    "setup_s",
    "bytes",
    "positions",
    "ms_per_move_median",
    "ms_per_move_p95",
    "work_per_move",
    "rel_l2_b_mean",
    "rel_l2_b_max",
    "rel_l2_indirect_mean",
    "payoff_moves",
    "note",
];

/// Writes `name` in `dir` with `rows`, atomically.
pub fn write_csv(dir: &Path, name: &str, rows: &[WalkRow]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(HEADER)?;
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    for r in rows {
        let f = &r.figures;
        w.write_record([
            r.scene.clone(),
            r.edges.to_string(),
            r.elements.to_string(),
            r.method.name().to_owned(),
            r.setting.clone(),
            r.setup_s.to_string(),
            r.bytes.to_string(),
            f.positions.to_string(),
            f.ms_median.to_string(),
            f.ms_p95.to_string(),
            f.work_mean.to_string(),
            opt(f.rel_l2_b_mean),
            opt(f.rel_l2_b_max),
            opt(f.rel_l2_indirect_mean),
            payoff(rows, r),
            r.note.clone(),
        ])?;
    }
    let bytes = w.into_inner()?;
    crate::interrupt::writing(|| write_atomic(&dir.join(name), &bytes))?;
    Ok(())
}

/// After how many moves `r` pays off against its scene's cold solve per move
/// ([`payoff_moves`]): a count, `never`, or empty for the cold row and an unmeasured one.
fn payoff(rows: &[WalkRow], r: &WalkRow) -> String {
    if r.setting == COLD || r.figures.positions == 0 {
        return String::new();
    }
    match cold_row(rows, &r.scene).map(|cold| payoff_moves(r, cold)) {
        Some(Some(moves)) => moves.to_string(),
        Some(None) => "never".to_owned(),
        None => String::new(),
    }
}

/// The Markdown table: a row per method and setting, scenes one after another.
#[must_use]
pub fn table(rows: &[WalkRow]) -> String {
    let mut out = String::from(
        "| scene | edges | elements | method | setting | set-up s | MB | ms/move median | p95 | \
         work/move | rel. L2 B mean | max | indirect mean | pays off after (moves) | note |\n\
         |---|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    let e = |v: Option<f64>| v.map_or("–".to_owned(), |v| format!("{v:.2e}"));
    for r in rows {
        let f = &r.figures;
        let measured = f.positions > 0;
        let ms = |v: f64| {
            if measured {
                format!("{v:.2}")
            } else {
                "–".to_owned()
            }
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {:.2} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.scene,
            r.edges,
            r.elements,
            r.method.name(),
            r.setting,
            r.setup_s,
            r.bytes as f64 / 1e6,
            ms(f.ms_median),
            ms(f.ms_p95),
            if measured {
                format!("{:.1}", f.work_mean)
            } else {
                "–".to_owned()
            },
            e(f.rel_l2_b_mean),
            e(f.rel_l2_b_max),
            e(f.rel_l2_indirect_mean),
            match payoff(rows, r).as_str() {
                "" => "–".to_owned(),
                p => p.to_owned(),
            },
            r.note
        );
    }
    out
}

/// Writes the two plots in `dir`: per scene and method a line through its settings, error
/// (mean over the positions) against the median ms per move.
pub fn write_plots(dir: &Path, rows: &[WalkRow]) -> Result<()> {
    let error_b = |r: &WalkRow| r.figures.rel_l2_b_mean;
    let indirect = |r: &WalkRow| r.figures.rel_l2_indirect_mean;
    let mut kinds: Vec<&str> = rows.iter().map(|r| kind(&r.scene)).collect();
    kinds.dedup();
    for scenes in kinds {
        let mine: Vec<WalkRow> = rows
            .iter()
            .filter(|r| kind(&r.scene) == scenes)
            .cloned()
            .collect();
        for (suffix, error, what) in [
            ("b", &error_b as &dyn Fn(&WalkRow) -> Option<f64>, "B"),
            ("indirect", &indirect, "the indirect part B − B₀"),
        ] {
            let series = series(&mine, error);
            let png = log_log(
                &format!("a moving lamp, {scenes}s: error of {what} against time per move"),
                "ms per move (median)",
                &format!("relative L2 error of {what} (mean over the walk)"),
                &series,
            )?;
            let name = format!("relight-walk-{scenes}-{suffix}.png");
            crate::interrupt::writing(|| write_atomic(&dir.join(&name), &png))?;
        }
    }
    Ok(())
}

/// One series per scene and method, its points in order of time; its label says after how
/// many moves its set-up pays off against the cold solves (the soonest of its settings).
fn series(rows: &[WalkRow], error: &dyn Fn(&WalkRow) -> Option<f64>) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    let mut soonest: Vec<Option<u64>> = Vec::new();
    for r in rows.iter().filter(|r| r.setting != COLD) {
        let Some(e) = error(r) else { continue };
        let label = format!("{} {}", r.scene, r.method.name());
        let pays = cold_row(rows, &r.scene).and_then(|cold| payoff_moves(r, cold));
        let point = (r.figures.ms_median, e, e, e);
        match out.iter().position(|s| s.label == label) {
            Some(i) => {
                out[i].points.push(point);
                soonest[i] = match (soonest[i], pays) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                };
            }
            None => {
                out.push(Series {
                    label,
                    points: vec![point],
                });
                soonest.push(pays);
            }
        }
    }
    for (s, pays) in out.iter_mut().zip(soonest) {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
        match pays {
            Some(1) => s.label.push_str(", pays off at once"),
            Some(n) => s.label.push_str(&format!(", pays off after {n} moves")),
            None => s.label.push_str(", never pays off"),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timed::Method;
    use crate::timed::walk::WalkFigures;

    fn row(method: Method, setting: &str, ms: f64, error: Option<f64>) -> WalkRow {
        WalkRow {
            scene: "floorplan-100".into(),
            edges: 97,
            elements: 512,
            method,
            setting: setting.into(),
            setup_s: 0.5,
            bytes: 2_000_000,
            figures: WalkFigures {
                positions: 3,
                ms_median: ms,
                ms_p95: 2.0 * ms,
                work_mean: 8.0,
                rel_l2_b_mean: error,
                rel_l2_b_max: error,
                rel_l2_indirect_mean: error,
            },
            note: String::new(),
        }
    }

    #[test]
    fn a_series_per_method_through_its_settings_and_a_table_row_per_row() {
        let rows = vec![
            row(Method::Exact, COLD, 9.0, None),
            row(Method::Exact, "tolerance 1e-6", 3.0, Some(1e-6)),
            row(Method::Exact, "tolerance 1e-2", 1.0, Some(1e-2)),
            row(Method::Tracer, "time", 3.0, Some(0.1)),
        ];
        let s = series(&rows, &|r: &WalkRow| r.figures.rel_l2_b_mean);
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].label, "floorplan-100 exact, pays off at once");
        assert_eq!(
            s[0].points,
            vec![(1.0, 1e-2, 1e-2, 1e-2), (3.0, 1e-6, 1e-6, 1e-6)]
        );
        assert_eq!(kind("floorplan-100"), "floorplan");
        for k in ["floorplan", "hall"] {
            for what in ["b", "indirect"] {
                assert!(PLOTS.contains(&format!("relight-walk-{k}-{what}.png").as_str()));
            }
        }
        let t = table(&rows);
        assert_eq!(t.lines().count(), 2 + rows.len());
        // The cold row pays nothing off; the same set-up at 3 ms instead of 9: the first move.
        assert!(t.contains("| 1.00e-6 | 1.00e-6 | 1.00e-6 | 1 |"), "{t}");
        assert!(t.contains("| – | – | – | – |  |"), "{t}");
        assert!(
            t.contains("| exact | tolerance 1e-6 | 0.50 | 2.0 | 3.00 | 6.00 | 8.0 | 1.00e-6 |"),
            "{t}"
        );
    }
}
