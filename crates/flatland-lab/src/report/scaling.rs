//! The scaling run's outputs: its CSV, its Markdown tables (rows, slopes, relighting) and its
//! log–log plots of time, memory and error against edges.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use flatland_geom::write_atomic;
use flatland_pictures::plot::{Series, log_log};

use crate::scaling::{Scaling, ScalingRow, kind_name, slopes};

/// The rows so far, rewritten after each (removed once the results are written).
pub const PARTIAL: &str = "scaling.partial.csv";
/// Every row.
pub const CSV: &str = "scaling.csv";
/// The tables.
pub const MARKDOWN: &str = "scaling.md";
/// The plots.
pub const PLOTS: [&str; 3] = [
    "scaling-time.png",
    "scaling-memory.png",
    "scaling-error.png",
];
/// Every file a scaling run writes.
pub const OUTPUTS: [&str; 6] = [PARTIAL, CSV, MARKDOWN, PLOTS[0], PLOTS[1], PLOTS[2]];

/// The CSV's columns.
pub const HEADER: [&str; 14] = [
    "scene",
    "edges",
    "elements",
    "method",
    "setting",
    "build_s",
    "solve_s",
    "total_s",
    "peak_bytes",
    "bytes",
    "rays",
    "rel_l2_reflected",
    "skipped",
    "note",
];

/// The CSV of `all`'s rows.
pub fn csv_text(all: &Scaling) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(HEADER)?;
    for r in &all.rows {
        let scene = &all.scenes[r.scene];
        let row = &r.row;
        w.write_record([
            scene.name.clone(),
            scene.edges.to_string(),
            scene.elements.to_string(),
            row.method.name().to_owned(),
            format!("{} {}", row.setting.kind(), row.setting.value()),
            row.build_s.to_string(),
            row.solve_s.to_string(),
            row.total_s.to_string(),
            r.peak.map_or(String::new(), |p| p.to_string()),
            row.bytes.to_string(),
            row.rays.to_string(),
            row.reflected_error()
                .map_or(String::new(), |e| e.to_string()),
            r.skipped.to_string(),
            row.note.clone(),
        ])?;
    }
    Ok(w.into_inner()?)
}

/// Writes `name` in `dir` with `all`'s rows, atomically.
pub fn write_csv(dir: &Path, name: &str, all: &Scaling) -> Result<()> {
    let bytes = csv_text(all)?;
    crate::interrupt::writing(|| write_atomic(&dir.join(name), &bytes))?;
    Ok(())
}

fn mb(bytes: Option<u64>) -> String {
    bytes.map_or("–".into(), |b| format!("{:.0}", b as f64 / 1e6))
}

/// The Markdown tables: per scene the reference and every method; the slopes from 10² to 10⁴
/// edges; the relighting.
pub fn markdown(all: &Scaling) -> String {
    let mut md = String::new();
    md.push_str(
        "| scene | edges | elements | method | time s | peak MB | rays | B − E error as a function | note |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    for (i, scene) in all.scenes.iter().enumerate() {
        let _ = writeln!(
            md,
            "| {} | {} | {} | reference (exact, {} elements) | {:.2} | {} | | | |",
            scene.name,
            scene.edges,
            scene.elements,
            scene.reference_elements,
            scene.reference_s,
            mb(scene.reference_peak)
        );
        for r in all.rows.iter().filter(|r| r.scene == i) {
            md.push_str(&row_line(
                scene.name.as_str(),
                scene.edges,
                scene.elements,
                r,
            ));
        }
    }
    md.push_str(
        "\nLog–log slopes against edges, from 10² to 10⁴ edges (least squares over the sizes \
         measured):\n\n| scene | method | time | peak memory | edges |\n|---|---|---|---|---|\n",
    );
    let slope = |s: Option<f64>| s.map_or("–".into(), |s| format!("{s:.2}"));
    for s in slopes(all, 12_000) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {}–{} |",
            kind_name(s.kind),
            s.method.name(),
            slope(s.time),
            slope(s.memory),
            s.edges.0,
            s.edges.1
        );
    }
    if !all.relit.is_empty() {
        md.push_str(
            "\nRelighting: the same scene under ten lightings, total seconds to all of them \
             and the mean (largest) error of B − E:\n\n| scene | method | total s | mean error | \
             largest | note |\n|---|---|---|---|---|---|\n",
        );
        for (i, summaries) in &all.relit {
            for s in summaries {
                let _ = writeln!(
                    md,
                    "| {} | {} | {:.2} | {:.4} | {:.4} | {} |",
                    all.scenes[*i].name,
                    s.method.name(),
                    s.total_s,
                    s.mean_error,
                    s.max_error,
                    s.note
                );
            }
        }
    }
    md
}

fn row_line(scene: &str, edges: usize, elements: usize, r: &ScalingRow) -> String {
    let row = &r.row;
    let (time, error) = if r.skipped || row.failed {
        ("–".to_owned(), "–".to_owned())
    } else {
        (
            format!("{:.2}", row.total_s),
            row.reflected_error()
                .map_or("–".into(), |e| format!("{e:.4}")),
        )
    };
    format!(
        "| {scene} | {edges} | {elements} | {} | {time} | {} | {} | {error} | {} |\n",
        row.method.name(),
        mb(r.peak),
        row.rays,
        row.note.replace('|', "/")
    )
}

/// The three log–log plots against edges: time, peak memory and error, a line per method and
/// kind of scene.
pub fn write_plots(dir: &Path, all: &Scaling) -> Result<()> {
    type Measure = fn(&ScalingRow) -> Option<f64>;
    let measures: [(&str, &str, &str, Measure); 3] = [
        ("Time to the lit scene", "seconds", PLOTS[0], |r| {
            Some(r.row.total_s)
        }),
        ("Peak memory added", "bytes", PLOTS[1], |r| {
            r.peak.map(|p| p as f64)
        }),
        (
            "Error of the solved B − E",
            "relative L2",
            PLOTS[2],
            |r| r.row.reflected_error(),
        ),
    ];
    for (title, y_label, file, measure) in measures {
        let mut series: Vec<Series> = Vec::new();
        for r in all.rows.iter().filter(|r| !r.skipped && !r.row.failed) {
            let scene = &all.scenes[r.scene];
            let Some(y) = measure(r) else { continue };
            let label = format!("{} ({})", r.row.method.name(), kind_name(scene.kind));
            let point = (scene.edges as f64, y, y, y);
            match series.iter_mut().find(|s| s.label == label) {
                Some(s) => s.points.push(point),
                None => series.push(Series {
                    label,
                    points: vec![point],
                }),
            }
        }
        for s in &mut series {
            s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        if !series.is_empty() {
            let png = log_log(title, "edges", y_label, &series)?;
            crate::interrupt::writing(|| write_atomic(&dir.join(file), &png))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scaling::{ScaledScene, ScalingRow};
    use crate::timed::{Method, Setting, TimedRow};
    use flatland_geom::generate::SceneKind;

    #[test]
    fn every_row_is_a_csv_line_and_a_table_line() {
        let mut all = Scaling::default();
        for edges in [100, 1000] {
            all.scenes.push(ScaledScene {
                name: format!("hall-{edges}"),
                kind: SceneKind::Hall,
                edges,
                elements: 4 * edges,
                reference_elements: 8 * edges,
                reference_s: 0.5,
                reference_peak: Some(3_000_000),
            });
            let mut row = TimedRow::new(Method::Exact, Setting::Elements(4 * edges), 1);
            row.total_s = edges as f64 / 100.0;
            all.rows.push(ScalingRow {
                scene: all.scenes.len() - 1,
                row,
                peak: Some(edges as u64 * 1000),
                skipped: false,
            });
        }
        let text = String::from_utf8(csv_text(&all).unwrap()).unwrap();
        assert_eq!(text.lines().count(), 3);
        let md = markdown(&all);
        assert_eq!(md.matches("| hall-1000 |").count(), 2, "{md}");
        // Time and memory both grow linearly here: slopes of 1.
        assert!(
            md.contains("| hall | exact | 1.00 | 1.00 | 100–1000 |"),
            "{md}"
        );
    }
}
