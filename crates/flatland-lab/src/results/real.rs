//! The lit real scenes in RESULTS.md: every method at equal time on the bundled floor plan and
//! hall and on generated scenes no default was chosen on, relighting, and cost against scene
//! size — measured, and written as the document's first sections.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

use anyhow::{Context as _, Result};
use flatland_geom::generate::{GenerateParams, SceneKind, generate};
use flatland_geom::{Kernel, Scene};
use flatland_solve::{LitParams, LitScene};

use crate::report::timed::{WITHIN_SECONDS, error_within, within_table, write_plots};
use crate::scaling::{Scaling, ScalingPlan, run_scaling};
use crate::timed::relight::{RelightSummary, relight, summaries};
use crate::timed::{Method, Scorer, TimedPlan, TimedRow, run_timed};
use crate::{interrupt, report};

/// The bundled realistic scenes.
pub const BUNDLED: [&str; 2] = ["floorplan", "hall"];

/// Generated scenes beside them, with seeds no default was ever chosen on.
const GENERATED: [(SceneKind, usize, u64); 2] = [
    (SceneKind::FloorPlan, 1000, 31),
    (SceneKind::Hall, 1000, 32),
];

/// Progress stages [`measure`] reports: one per scene and the scaling study.
pub fn stages(quick: bool) -> usize {
    BUNDLED.len() + if quick { 0 } else { GENERATED.len() } + 1
}

/// The methods compared at equal time.
const METHODS: [Method; 5] = [
    Method::Light,
    Method::Exact,
    Method::Hr,
    Method::Clustered,
    Method::Tracer,
];

/// One scene's equal-time comparison.
pub struct RealScene {
    /// How the document names it.
    pub name: String,
    /// Surface and blocker edges.
    pub edges: usize,
    /// Elements every method solves on.
    pub elements: usize,
    /// Elements of the reference.
    pub reference_elements: usize,
    /// Every row of every method's sweep.
    pub rows: Vec<TimedRow>,
    /// Relighting: each method's total over the lightings.
    pub relit: Vec<RelightSummary>,
}

/// Everything the real-scenes sections report.
#[derive(Default)]
pub struct Real {
    /// The equal-time comparisons.
    pub scenes: Vec<RealScene>,
    /// Cost against size.
    pub scaling: Scaling,
    /// Seconds a sweep may take per row (the plan's time budget).
    pub max_seconds: f64,
}

/// The scenes of the comparison: the bundled ones from `scenes` and (unless `quick`) the
/// generated ones.
fn scenes(folder: &Path, quick: bool) -> Result<Vec<(String, Scene)>> {
    let mut out = Vec::new();
    for name in BUNDLED {
        let path = folder.join(format!("{name}.ron"));
        out.push((name.to_owned(), Scene::load(&path)?));
    }
    for (kind, edges, seed) in GENERATED.into_iter().filter(|_| !quick) {
        let scene = generate(&GenerateParams { kind, edges, seed })?;
        let kind = crate::scaling::kind_name(kind);
        out.push((format!("{kind}-{edges} (seed {seed})"), scene));
    }
    Ok(out)
}

/// Runs the comparisons (plots into `plots/<scene>/`) and the scaling study; `stage` is
/// called before each long stage.
pub fn measure(
    folder: &Path,
    plots: &Path,
    quick: bool,
    mut stage: impl FnMut(&str) -> Result<()>,
) -> Result<Real> {
    let max_seconds = if quick { 5.0 } else { 30.0 };
    let mut plan = TimedPlan::new(METHODS.to_vec());
    plan.max_seconds = max_seconds;
    plan.tracer_seconds = max_seconds;
    let stop = &interrupt::requested;
    let mut out = Vec::new();
    for (name, scene) in scenes(folder, quick)? {
        stage(&format!("every method at equal time on {name}"))?;
        let kernel = Arc::new(Kernel::new(scene));
        let lit = LitScene::new(Arc::clone(&kernel), &LitParams::default(), stop)
            .with_context(|| format!("{name}: the exact reference"))?;
        let scorer = Scorer::of_lit(lit);
        let rows = run_timed(&kernel, &scorer, &plan, stop, |_| Ok(()))?;
        let dir = plots.join(file_name(&name));
        std::fs::create_dir_all(&dir)?;
        write_plots(&dir, &name, &rows)?;
        let (relit, _) = relight(
            &scorer,
            &kernel,
            &plan,
            &rows,
            crate::timed::relight::LIGHTINGS,
            stop,
        )?;
        out.push(RealScene {
            name,
            edges: kernel.scene().edges().len(),
            elements: scorer.mesh().len(),
            reference_elements: scorer.reference_elements(),
            rows,
            relit: summaries(&relit),
        });
    }
    stage("cost against scene size (bench --scaling)")?;
    let scaling_plan = ScalingPlan {
        sizes: if quick {
            vec![100, 1000]
        } else {
            vec![100, 1000, 10_000]
        },
        ..ScalingPlan::new()
    };
    let scaling = run_scaling(&scaling_plan, stop, |_| {}, |_| Ok(()))?;
    report::scaling::write_plots(plots, &scaling)?;
    Ok(Real {
        scenes: out,
        scaling,
        max_seconds,
    })
}

/// A folder name for a scene's plots.
fn file_name(name: &str) -> String {
    name.split_whitespace().next().unwrap_or(name).to_owned()
}

/// The least error `method` reached within `seconds`, from [`error_within`].
fn best_within(rows: &[TimedRow], method: Method, seconds: f64) -> Option<f64> {
    error_within(rows, &[seconds])
        .into_iter()
        .find(|(m, _)| *m == method)
        .and_then(|(_, best)| best[0])
}

/// The summary: per scene the least error each method reached within 0.3, 1 and 5 s, and
/// what that says, in words computed from the rows.
pub fn summary(doc: &mut String, real: &Real) -> Result<()> {
    writeln!(
        doc,
        "## Summary: the lit scene at equal time, on realistic scenes\n"
    )?;
    writeln!(
        doc,
        "The measure is the lit scene: the relative L2 error of the solved reflected radiosity \
         B − E as a function along the surfaces against the exact reference's final gather, \
         at 8 points per element (the exact solve read by its own gather, every other method \
         as the line through its element midpoints, the lamps' direct light at each point), \
         reached within a time \
         (build + solve), each method swept over its own knob until a row takes over {} s: the \
         light-driven learner (`light`) by its tolerance, the exact kernel's own solve by elements, hierarchical radiosity by links, \
         the Monte Carlo light tracer by photons. The mesh and the reference are `flatland \
         solve`'s: a mesh refined until the exact B as a function is within 1 %, and the finer \
         solve of that estimate, read by its final gather; how good both are, against much \
         finer solves and the tracer: [docs/FUNCTION-ERROR.md](docs/FUNCTION-ERROR.md). \
         Scenes: the bundled floor plan and hall, and generated ones whose seeds no default \
         was chosen on.\n",
        real.max_seconds
    )?;
    for s in &real.scenes {
        writeln!(
            doc,
            "**{}** ({} edges, {} elements, reference on {}):\n",
            s.name, s.edges, s.elements, s.reference_elements
        )?;
        doc.push_str(&within_table(&s.rows));
        doc.push('\n');
    }
    writeln!(doc, "**What the rows say:**\n")?;
    for line in verdicts(real) {
        writeln!(doc, "- {line}")?;
    }
    doc.push('\n');
    Ok(())
}

/// Two errors printed with the fewest digits (four at least) that tell them apart, so a
/// sentence never says one beats the other at equal numbers; "nothing" for no row.
fn distinguished(a: Option<f64>, b: Option<f64>) -> (String, String) {
    let text =
        |e: Option<f64>, digits: usize| e.map_or("nothing".to_owned(), |e| format!("{e:.digits$}"));
    let digits = (4..=8).find(|&d| text(a, d) != text(b, d)).unwrap_or(8);
    (text(a, digits), text(b, digits))
}

/// Sentences computed from the rows: where the exact solve beats the learner, whether the
/// learner's curve lies at or below HR's, and relighting.
fn verdicts(real: &Real) -> Vec<String> {
    let mut lines = Vec::new();
    for s in &real.scenes {
        let mut exact_wins = Vec::new();
        for t in WITHIN_SECONDS {
            let (d, x) = (
                best_within(&s.rows, Method::Light, t),
                best_within(&s.rows, Method::Exact, t),
            );
            if x.is_some_and(|x| d.is_none_or(|d| x < d)) {
                let (x, d) = distinguished(x, d);
                exact_wins.push(format!("{t} s: exact {x} against {d}"));
            }
        }
        if exact_wins.is_empty() {
            lines.push(format!(
                "{}: the light-driven learner is at least as accurate as the exact solve within \
                 every time listed.",
                s.name
            ));
        } else {
            lines.push(format!(
                "{}: **the exact solve beats the light-driven learner** within {}.",
                s.name,
                exact_wins.join("; ")
            ));
        }
        lines.push(against_hr(s));
        if let (Some(d), Some(x)) = (
            s.relit.iter().find(|r| r.method == Method::Light),
            s.relit.iter().find(|r| r.method == Method::Exact),
        ) {
            lines.push(format!(
                "{}, relighting ({} lightings, each scored as a function): light {:.2} s (mean \
                 error {:.4}), exact {:.2} s ({:.4}){}.",
                s.name,
                crate::timed::relight::LIGHTINGS,
                d.total_s,
                d.mean_error,
                x.total_s,
                x.mean_error,
                if x.total_s < d.total_s && x.mean_error <= d.mean_error {
                    ": the exact operator, built once, relights faster and better"
                } else {
                    ""
                }
            ));
        }
    }
    lines
}

/// Whether the light-driven learner's rows lie at or below HR's best error at their time.
fn against_hr(s: &RealScene) -> String {
    let mut above = Vec::new();
    let mut compared = 0;
    for r in s.rows.iter().filter(|r| r.method == Method::Light) {
        let (Some(d), Some(hr)) = (
            r.reflected_error(),
            best_within(&s.rows, Method::Hr, r.total_s),
        ) else {
            continue;
        };
        compared += 1;
        if d > hr {
            above.push(format!("{:.2} s: {d:.4} against {hr:.4}", r.total_s));
        }
    }
    if compared == 0 {
        format!(
            "{}: HR had no row as fast as any of the light-driven learner's (its initial linking \
             takes longer).",
            s.name
        )
    } else if above.is_empty() {
        format!(
            "{}: the light-driven learner's error is at or below HR's at equal time at each of its \
             {compared} point(s) where HR has a row.",
            s.name
        )
    } else {
        format!(
            "{}: **the light-driven learner is above HR** at {}.",
            s.name,
            above.join("; ")
        )
    }
}

/// The detailed sections: each scene's rows and plots, relighting, and the scaling study.
pub fn sections(doc: &mut String, real: &Real) -> Result<()> {
    writeln!(doc, "## Real scenes: every row\n")?;
    for s in &real.scenes {
        let dir = file_name(&s.name);
        writeln!(doc, "### {}\n", s.name)?;
        doc.push_str(&crate::report::timed::table(&s.rows));
        writeln!(
            doc,
            "\n![{0}: error against time](docs/results/{dir}/solve_vs_time.png)\n\nRelighting \
             ({1} lightings of the same geometry; the learner and the exact operator are built \
             once, HR and the tracer at the setting that matched the learner's error):\n",
            s.name,
            crate::timed::relight::LIGHTINGS
        )?;
        doc.push_str(
            "| method | total s | mean error | largest | note |\n|---|---:|---:|---:|---|\n",
        );
        for r in &s.relit {
            writeln!(
                doc,
                "| {} | {:.2} | {:.4} | {:.4} | {} |",
                r.method.name(),
                r.total_s,
                r.mean_error,
                r.max_error,
                r.note
            )?;
        }
        doc.push('\n');
    }
    writeln!(doc, "## Cost against scene size\n")?;
    writeln!(
        doc,
        "`flatland bench --scaling`: each method with its default arguments on generated floor \
         plans and halls; time to the lit scene, the heap's peak while it ran, rays, and the \
         error of B − E as a function against the exact reference of `flatland solve`. A method whose time, \
         extrapolated from the smaller scenes, is over the time budget is skipped there (HR's \
         initial linking grows with the square of the edges).\n"
    )?;
    doc.push_str(&crate::report::scaling::markdown(&real.scaling));
    writeln!(
        doc,
        "\n![time against edges](docs/results/scaling-time.png)\n\n![memory against \
         edges](docs/results/scaling-memory.png)\n"
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timed::Setting;

    #[test]
    fn errors_that_differ_are_printed_so_they_differ() {
        let pair = |a, b| distinguished(Some(a), Some(b));
        assert_eq!(pair(0.0021, 0.0048), ("0.0021".into(), "0.0048".into()));
        assert_eq!(pair(0.00402, 0.00404), ("0.00402".into(), "0.00404".into()));
        assert_eq!(pair(0.5, 0.5), ("0.50000000".into(), "0.50000000".into()));
        assert_eq!(
            distinguished(Some(0.1), None),
            ("0.1000".into(), "nothing".into())
        );
    }

    fn row(method: Method, total_s: f64, error: f64) -> TimedRow {
        let mut r = TimedRow::new(method, Setting::Budget(1), 1);
        r.total_s = total_s;
        r.solve = Some(flatland_solve::SolveErrors {
            rel_l2_b: error,
            rel_l2_reflected: error,
        });
        r
    }

    #[test]
    fn verdicts_say_where_the_exact_solve_and_hr_win() {
        let scene = RealScene {
            name: "plan".into(),
            edges: 10,
            elements: 64,
            reference_elements: 128,
            rows: vec![
                row(Method::Light, 0.2, 0.05),
                row(Method::Light, 2.0, 0.01),
                row(Method::Exact, 0.1, 0.02),
                row(Method::Hr, 0.1, 0.03),
            ],
            relit: Vec::new(),
        };
        let real = Real {
            scenes: vec![scene],
            scaling: Scaling::default(),
            max_seconds: 30.0,
        };
        let lines = verdicts(&real);
        assert!(lines[0].contains("exact solve beats"), "{lines:?}");
        assert!(
            lines[0].contains("0.3 s: exact 0.0200 against 0.0500"),
            "{lines:?}"
        );
        assert!(
            !lines[0].contains("5 s"),
            "at 5 s the learner is better: {lines:?}"
        );
        assert!(
            lines[1].contains("above HR") && lines[1].contains("0.20 s"),
            "{lines:?}"
        );
    }

    #[test]
    fn the_bundled_real_scenes_load() {
        let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let all = scenes(&folder, false).unwrap();
        assert_eq!(all.len(), BUNDLED.len() + GENERATED.len());
        // Realistic: hundreds of edges each, two lamps in the floor plan.
        assert!(all.iter().all(|(_, scene)| scene.edges().len() >= 200));
        let lamps = all[0].1.edges().iter().filter(|e| e.emission > 0.0).count();
        assert!(lamps >= 2, "{lamps}");
    }
}
