//! The moving lamp in RESULTS.md: `flatland bench --relight` on generated floor plans and halls
//! (the 10³- and 10⁴-edge ones, 10³ only with `--quick`), measured, its table and plots written
//! beside the document's other plots, and the section "Relighting a moving lamp" with who wins
//! where, read from the numbers.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use flatland_solve::Stop;

use crate::report::walk::{MARKDOWN, table, write_plots};
use crate::timed::Method;
use crate::timed::walk::{
    COLD, DEFAULT_SIZES, POSITIONS, WalkPlan, WalkRow, cold_row, payoff_moves, run_walks,
};

/// The sizes measured: `bench --relight`'s default, or the smallest alone when `quick`.
fn sizes(quick: bool) -> Vec<usize> {
    if quick {
        DEFAULT_SIZES[..1].to_vec()
    } else {
        DEFAULT_SIZES.to_vec()
    }
}

/// What the progress line says of this stage.
pub fn stage(quick: bool) -> String {
    format!(
        "bench --relight: a lamp along {POSITIONS} positions of floor plans and halls of {:?} \
         edges",
        sizes(quick)
    )
}

/// Runs the walk bench at its defaults (the sizes by `quick`) and writes its table and plots
/// in `plots`; `stop` ends the walk where it is, with the positions done kept.
pub fn measure(plots: &Path, quick: bool, stop: &Stop) -> Result<Vec<WalkRow>> {
    let plan = WalkPlan {
        sizes: sizes(quick),
        ..WalkPlan::new()
    };
    let rows = run_walks(&plan, stop, |line| eprintln!("results: {line}"), |_| Ok(()))?;
    let md = table(&rows);
    crate::interrupt::writing(|| {
        flatland_geom::write_atomic(&plots.join(MARKDOWN), md.as_bytes())
    })?;
    write_plots(plots, &rows)?;
    Ok(rows)
}

/// One scene's rows, by role.
struct SceneRows<'r> {
    scene: &'r str,
    edges: usize,
    elements: usize,
    cold: &'r WalkRow,
    /// The exact re-solve's rows, the largest error first.
    exact: Vec<&'r WalkRow>,
    /// Built once, then relit per move: the transport, the probe grid, clustered HR.
    set_up: Vec<&'r WalkRow>,
    tracer: Option<&'r WalkRow>,
}

impl<'r> SceneRows<'r> {
    /// Every scene of `rows` with a cold row, in order.
    fn all(rows: &'r [WalkRow]) -> Vec<SceneRows<'r>> {
        let mut out: Vec<SceneRows<'r>> = Vec::new();
        for r in rows {
            if out.iter().any(|s| s.scene == r.scene) {
                continue;
            }
            let Some(cold) = cold_row(rows, &r.scene) else {
                continue;
            };
            let mine = || rows.iter().filter(|x| x.scene == r.scene && measured(x));
            let mut exact: Vec<&WalkRow> = mine()
                .filter(|x| x.method == Method::Exact && x.setting != COLD)
                .collect();
            exact.sort_by(|a, b| error_b(b).total_cmp(&error_b(a)));
            let set_up = [Method::Transport, Method::Probes, Method::Clustered]
                .iter()
                .filter_map(|&m| mine().find(|x| x.method == m))
                .collect();
            out.push(SceneRows {
                scene: &r.scene,
                edges: r.edges,
                elements: r.elements,
                cold,
                exact,
                set_up,
                tracer: mine().find(|x| x.method == Method::Tracer),
            });
        }
        out
    }

    /// The exact re-solve whose mean error of B is nearest `row`'s (by ratio).
    fn matching(&self, row: &WalkRow) -> Option<&'r WalkRow> {
        let distance = |x: &WalkRow| (error_b(x) / error_b(row)).ln().abs();
        self.exact
            .iter()
            .copied()
            .min_by(|a, b| distance(a).total_cmp(&distance(b)))
    }

    /// The re-solve at the default tolerance (1e-6), else the tightest.
    fn default_exact(&self) -> Option<&'r WalkRow> {
        let default = self.exact.iter().find(|r| r.setting.ends_with("1e-6"));
        default.or(self.exact.last()).copied()
    }

    fn row(&self, method: Method) -> Option<&'r WalkRow> {
        self.set_up.iter().copied().find(|r| r.method == method)
    }
}

fn measured(r: &WalkRow) -> bool {
    r.figures.positions > 0
}

fn error_b(r: &WalkRow) -> f64 {
    r.figures.rel_l2_b_mean.unwrap_or(f64::NAN)
}

fn error_indirect(r: &WalkRow) -> f64 {
    r.figures.rel_l2_indirect_mean.unwrap_or(f64::NAN)
}

/// A pay-off in words: `at once`, `never`, or a count.
fn pays(moves: Option<u64>) -> String {
    match moves {
        Some(1) => "at once".to_owned(),
        Some(n) => format!("{n}"),
        None => "never".to_owned(),
    }
}

/// The section "Relighting a moving lamp": what is measured, the two tables, who wins where,
/// and the links to every row and to how the transport was chosen.
pub fn section(doc: &mut String, rows: &[WalkRow], quick: bool) -> Result<()> {
    let positions = rows.iter().map(|r| r.figures.positions).max().unwrap_or(0);
    writeln!(
        doc,
        "## Relighting a moving lamp (`flatland relight`, `flatland bench --relight`)\n\n\
         One scene lit again and again by a lamp carried along a walk of {positions} positions \
         through its rooms and doors (`flatland_geom::walk`), its own lamps off and no edge \
         emitting. The exact re-solve (`flatland_solve::Relighter`) builds the operator once, by \
         rows and by columns; per move it computes the direct light by one view of the lamp, the \
         first bounce `K B₀` from the columns of the elements the lamp lights, and the later \
         bounces by GMRES warm-started from the last move's. Each position is checked against a \
         cold exact solve there (a fresh lit mesh solved from `B₀` to 1e-10 with the operator in \
         hand: the \"cold\" row, the time a move costs without the relighter).\n\n\
         `flatland bench --relight` with its defaults (seed 2024, walk seed 7, sizes {:?}{}). \
         Built once, then relit per move: the learned transport of the later bounces (built on \
         the re-solve's operator), a uniform grid of light-position probes given the \
         transport's bytes (what game light-probe grids do), and clustered HR (its senders \
         weighed by what the scene's own lamps, off during the walk, light: `E'` of \
         docs/ALGORITHM.md §2; re-solved per move with the new direct light as source). The tracer is given the exact re-solve's time per move.\n",
        sizes(quick),
        if quick { ", `--quick`" } else { "" }
    )?;
    let scenes = SceneRows::all(rows);
    resolve_table(doc, &scenes)?;
    set_up_table(doc, &scenes)?;
    who_wins(doc, &scenes)?;
    writeln!(
        doc,
        "Every row (all four tolerances) is in \
         [docs/results/relight-walk.md](docs/results/relight-walk.md); the error of B against \
         ms per move, in the floor plans and in the halls:\n\n\
         ![error of B against ms per move, floor plans](docs/results/relight-walk-floorplan-b.png)\n\
         ![error of B against ms per move, halls](docs/results/relight-walk-hall-b.png)\n\n\
         How the transport was chosen over the probe grid (uniform and adaptive) and the \
         paper's growing cells on `M₂(s, t)`, one scene at a time with its own error estimates: \
         [docs/MOVING-LIGHT.md](docs/MOVING-LIGHT.md) (measured by \
         `crates/flatland-transport/examples/compare.rs`).\n"
    )?;
    Ok(())
}

/// The cold solve, the exact re-solve at 1e-6 and at the transport's error, and the tracer.
fn resolve_table(doc: &mut String, scenes: &[SceneRows]) -> Result<()> {
    writeln!(
        doc,
        "| scene | cold solve ms median | re-solve at its default: setting, ms median / p95, products, \
         error of B | re-solve at the transport's error: setting, ms median, error of B | tracer \
         at the re-solve's time: ms, error of B |\n|---|---|---|---|---|"
    )?;
    for s in scenes {
        let tight = s.default_exact().map_or("–".to_owned(), |r| {
            let f = &r.figures;
            format!(
                "{}: {:.2} / {:.1}, {:.1}, {:.1e}",
                r.setting,
                f.ms_median,
                f.ms_p95,
                f.work_mean,
                error_b(r)
            )
        });
        let matched =
            s.row(Method::Transport)
                .and_then(|t| s.matching(t))
                .map_or("–".to_owned(), |r| {
                    format!(
                        "{}: {:.2}, {:.1e}",
                        r.setting,
                        r.figures.ms_median,
                        error_b(r)
                    )
                });
        let tracer = s.tracer.map_or("–".to_owned(), |r| {
            format!("{:.1}, {:.1e}", r.figures.ms_median, error_b(r))
        });
        writeln!(
            doc,
            "| {} ({} edges, {} el.) | {:.1} | {tight} | {matched} | {tracer} |",
            s.scene, s.edges, s.elements, s.cold.figures.ms_median
        )?;
    }
    writeln!(doc)?;
    Ok(())
}

/// What is set up once: set-up, bytes, ms per move, errors, and after how many moves it pays
/// off against the cold solve and against the re-solve at its error.
fn set_up_table(doc: &mut String, scenes: &[SceneRows]) -> Result<()> {
    writeln!(
        doc,
        "| scene | method | setting | set-up s | MB | ms/move median / p95 | error of B mean / \
         max | indirect mean | pays off after (moves): against the cold solve | against the \
         re-solve at its error |\n|---|---|---|---:|---:|---|---|---:|---:|---:|"
    )?;
    for s in scenes {
        for r in &s.set_up {
            let f = &r.figures;
            let against = s.matching(r).map_or("–".to_owned(), |m| {
                format!("{} ({})", pays(payoff_moves(r, m)), m.setting)
            });
            writeln!(
                doc,
                "| {} | {} | {} | {:.2} | {:.1} | {:.2} / {:.2} | {:.1e} / {:.1e} | {:.1e} | {} | \
                 {against} |",
                s.scene,
                r.method.name(),
                r.setting,
                r.setup_s,
                r.bytes as f64 / 1e6,
                f.ms_median,
                f.ms_p95,
                error_b(r),
                f.rel_l2_b_max.unwrap_or(f64::NAN),
                error_indirect(r),
                pays(payoff_moves(r, s.cold)),
            )?;
        }
    }
    writeln!(doc)?;
    Ok(())
}

/// `lo–hi` of `values` (in `e` notation when `exp`), or one value when they show alike.
fn span(values: impl IntoIterator<Item = f64>, exp: bool) -> String {
    let values: Vec<f64> = values.into_iter().collect();
    let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let show = |v: f64| if exp { format!("{v:.1e}") } else { number(v) };
    if values.is_empty() {
        "–".to_owned()
    } else if show(lo) == show(hi) {
        show(lo)
    } else {
        format!("{}–{}", show(lo), show(hi))
    }
}

/// "Who wins", read from the rows: per scene the transport against the re-solve at its error
/// (speed, pay-off), then the exact re-solve's accuracy, the probe grid, clustered HR and the
/// tracer over all scenes, and in short who wins where.
fn who_wins(doc: &mut String, scenes: &[SceneRows]) -> Result<()> {
    writeln!(
        doc,
        "Who wins, read from the rows above:
"
    )?;
    let (mut wins, mut ties) = (Vec::new(), Vec::new());
    for s in scenes {
        let Some(t) = s.row(Method::Transport) else {
            continue;
        };
        let Some(m) = s.matching(t) else { continue };
        let ratio = m.figures.ms_median / t.figures.ms_median;
        if ratio > 1.0 {
            wins.push(format!("{} ({ratio:.1}×)", s.scene));
        } else {
            ties.push(s.scene.to_owned());
        }
        writeln!(
            doc,
            "- {}: the transport answers a move in {} ms at a mean error of B of {:.1e}, the \
             re-solve at its error ({}, {:.1e}) in {} ms: {ratio:.1}× {}. Its set-up of {:.1} s \
             pays off {} against that re-solve, {} against a cold solve per move.",
            s.scene,
            number(t.figures.ms_median),
            error_b(t),
            m.setting,
            error_b(m),
            number(m.figures.ms_median),
            if ratio > 1.0 { "faster" } else { "the time" },
            t.setup_s,
            after(payoff_moves(t, m)),
            after(payoff_moves(t, s.cold)),
        )?;
    }
    let tight: Vec<&WalkRow> = scenes.iter().filter_map(SceneRows::default_exact).collect();
    if let Some(first) = tight.first() {
        writeln!(
            doc,
            "- The exact re-solve, when more accuracy is asked for: at {} its error of B is {} \
             at {} ms per move.",
            first.setting,
            span(tight.iter().map(|r| error_b(r)), true),
            span(tight.iter().map(|r| r.figures.ms_median), false),
        )?;
    }
    others(doc, scenes)?;
    write!(doc, "\nIn short: ")?;
    if !wins.is_empty() {
        write!(
            doc,
            "at equal error the transport wins a move on {}; ",
            wins.join(", ")
        )?;
    }
    if !ties.is_empty() {
        write!(
            doc,
            "the exact re-solve is as fast on {}; ",
            ties.join(", ")
        )?;
    }
    writeln!(
        doc,
        "the exact re-solve wins wherever more accuracy is asked for, and a set-up is worth \
         building only for a light moved at least as many times as its pay-off above.\n"
    )?;
    Ok(())
}

/// The probe grid, clustered HR and the tracer, each over every scene.
fn others(doc: &mut String, scenes: &[SceneRows]) -> Result<()> {
    let probes: Vec<(&WalkRow, &WalkRow)> = scenes
        .iter()
        .filter_map(|s| Some((s.row(Method::Probes)?, s.row(Method::Transport)?)))
        .collect();
    if !probes.is_empty() {
        writeln!(
            doc,
            "- The probe grid of the transport's bytes: a move in {} ms ({}× the transport's \
             speed), but {}× its error of B ({}).",
            span(probes.iter().map(|(p, _)| p.figures.ms_median), false),
            span(
                probes
                    .iter()
                    .map(|(p, t)| t.figures.ms_median / p.figures.ms_median),
                false
            ),
            span(probes.iter().map(|(p, t)| error_b(p) / error_b(t)), false),
            span(probes.iter().map(|(p, _)| error_b(p)), true),
        )?;
    }
    let clustered: Vec<(&WalkRow, &WalkRow)> = scenes
        .iter()
        .filter_map(|s| Some((s.row(Method::Clustered)?, s.cold)))
        .collect();
    if !clustered.is_empty() {
        let moves: Vec<String> = clustered
            .iter()
            .map(|(r, cold)| format!("{} on {}", after(payoff_moves(r, cold)), r.scene))
            .collect();
        writeln!(
            doc,
            "- Clustered HR, its links refined towards the senders the scene's own lamps light: \
             an error of B of {} at {} ms per move; against a cold solve per move it pays off {}.",
            span(clustered.iter().map(|(r, _)| error_b(r)), true),
            span(clustered.iter().map(|(r, _)| r.figures.ms_median), false),
            moves.join(", "),
        )?;
    }
    let tracer: Vec<&WalkRow> = scenes.iter().filter_map(|s| s.tracer).collect();
    if !tracer.is_empty() {
        writeln!(
            doc,
            "- The tracer, given the re-solve's time per move: {} ms and an error of B of {}.",
            span(tracer.iter().map(|r| r.figures.ms_median), false),
            span(tracer.iter().map(|r| error_b(r)), true),
        )?;
    }
    Ok(())
}

/// A time in ms at about two significant digits.
fn number(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

fn after(moves: Option<u64>) -> String {
    match moves {
        Some(1) => "at once".to_owned(),
        Some(n) => format!("after {n} moves"),
        None => "never".to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timed::walk::WalkFigures;

    fn row(method: Method, setting: &str, setup_s: f64, ms: f64, error: f64) -> WalkRow {
        WalkRow {
            scene: "plan-100".into(),
            edges: 97,
            elements: 400,
            method,
            setting: setting.into(),
            setup_s,
            bytes: 1_000_000,
            figures: WalkFigures {
                positions: 5,
                ms_median: ms,
                ms_p95: ms,
                work_mean: 3.0,
                rel_l2_b_mean: Some(error),
                rel_l2_b_max: Some(error),
                rel_l2_indirect_mean: Some(error),
            },
            note: String::new(),
        }
    }

    #[test]
    fn who_wins_is_read_from_the_numbers() {
        let rows = vec![
            row(Method::Exact, COLD, 1.0, 50.0, 0.0),
            row(Method::Exact, "tolerance 1e-6", 1.0, 20.0, 1e-6),
            row(Method::Exact, "tolerance 1e-2", 1.0, 5.0, 5e-3),
            row(Method::Tracer, "time", 0.0, 20.0, 4e-2),
            row(Method::Transport, "t", 3.0, 0.5, 4e-3),
            row(Method::Probes, "p", 4.0, 0.25, 1.2e-2),
        ];
        let mut doc = String::new();
        section(&mut doc, &rows, true).unwrap();
        // Matched with the re-solve at 1e-2: 10× faster; 2 s more set-up over 4.5 ms saved a
        // move: 445 moves; against the cold solve, 2 s over 49.5 ms: 41 moves.
        let has = |text: &str| assert!(doc.contains(text), "{text} not in {doc}");
        has("in 5.0 ms: 10.0× faster");
        has("pays off after 445 moves against that re-solve");
        has("after 41 moves against a cold solve");
        has("the transport wins a move on plan-100 (10.0×)");
        // The probes: twice the transport's speed, three times its error.
        has("(2.0× the transport's speed), but 3.0× its error");
        has("at tolerance 1e-6 its error of B is 1.0e-6 at 20 ms");
        has("20 ms and an error of B of 4.0e-2");
        has("a walk of 5 positions");
        has("docs/MOVING-LIGHT.md");
        // A row per scene in the first table, one per method set up in the second.
        has("| plan-100 (97 edges, 400 el.) | 50.0 | tolerance 1e-6: ");
        has("| plan-100 | probes | p | 4.00 | 1.0 |");
    }
}
