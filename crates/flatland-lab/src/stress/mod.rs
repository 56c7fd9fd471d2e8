//! The adversarial suite behind `flatland stress`: numerical stability of the kernel and of the
//! learning under extreme scenes and parameters. Its own module tree, apart from the commands.
//!
//! Every case checks a property and prints one row: case, what was checked, pass/FAIL, and the
//! figures: the largest |value| among the kernel values, ζ, predictions and output weights it
//! saw; how many numbers (of those and of positions, widths, counters, errors) were NaN or
//! infinite; the error of the case (the learned held-out relative L2 error, or for the energy
//! cases the largest |∫ k/ρ dl − 1|, for the independent 10k edges the relative L2 distance to
//! the maze's kernel, for out-of-range parameters the number accepted); and the wall time. The
//! command fails (exit 1) if any case fails; the reasons follow the table. A panic inside a case
//! is caught and reported as that case's failure.
//!
//! The comparisons of learned errors run the *same* small fit (same seed, same sample stream) on
//! the original and on the transformed scene: the fit works in a unit-box input frame, so up to
//! rounding it is the same fit, and its relative errors must agree within 5 %.

#![allow(clippy::wildcard_imports)]

mod cases;
mod support;

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use flatland_geom::bundled;

use cases::*;
use support::*;

/// Relative tolerance on learned errors under scaling, translation and emission changes.
pub const SAME_ERROR: f64 = 0.05;
/// Errors both below this are the same fit whatever their ratio.
pub const TINY_ERROR: f64 = 0.005;
/// Cells of the small fits the comparisons run.
pub const FIT_CELLS: usize = 60;
/// Reference used by every small fit: grid resolution and held-out points.
pub const REF_RES: usize = 64;
/// See [`REF_RES`].
pub const REF_HELDOUT: usize = 1024;
/// Seed of every small fit.
pub const SEED: u64 = 7;
/// Tolerance of the energy check `∫ k/ρ dl = 1` in a closed room (angle quadrature).
pub const ENERGY_TOL: f64 = 0.01;
/// A prediction is "bounded" if it stays within this factor of the largest exact ζ.
pub const BOUND_FACTOR: f64 = 10.0;
/// An extreme but valid parameter may learn poorly, but not diverge: its held-out error stays
/// below this (predicting ζ̃ ≡ 0 scores exactly 1).
pub const NOT_DIVERGED: f64 = 1.5;

/// One row of the table.
struct Row {
    case: String,
    checked: String,
    failures: Vec<String>,
    max_abs: f64,
    non_finite: usize,
    error: Option<f64>,
    secs: f64,
}

impl Row {
    fn new(case: impl Into<String>, checked: impl Into<String>) -> Row {
        Row {
            case: case.into(),
            checked: checked.into(),
            failures: Vec::new(),
            max_abs: 0.0,
            non_finite: 0,
            error: None,
            secs: 0.0,
        }
    }

    /// Records a value: its magnitude, or that it is not finite.
    fn see(&mut self, v: f64) {
        if v.is_finite() {
            self.max_abs = self.max_abs.max(v.abs());
        } else {
            self.non_finite += 1;
        }
    }

    /// Records a value that only has to be finite (positions, widths, counters, errors): it
    /// does not enter the largest |value|, which is about k, ζ, predictions and weights.
    fn finite(&mut self, v: f64) {
        if !v.is_finite() {
            self.non_finite += 1;
        }
    }

    fn see_all(&mut self, values: impl IntoIterator<Item = f64>) {
        for v in values {
            self.see(v);
        }
    }

    /// Adds a failure reason unless `ok`.
    fn require(&mut self, ok: bool, reason: impl FnOnce() -> String) {
        if !ok {
            self.failures.push(reason());
        }
    }

    fn passed(&self) -> bool {
        self.failures.is_empty() && self.non_finite == 0
    }
}

/// The suite's configuration.
struct Suite {
    quick: bool,
    soak_steps: u64,
    only: Option<String>,
    rows: Vec<Row>,
}

impl Suite {
    fn wants(&self, case: &str) -> bool {
        self.only.as_deref().is_none_or(|o| case.contains(o))
    }

    /// Runs `body` as case `case` if selected, timing it and turning an error into a failure.
    fn case(&mut self, case: &str, checked: &str, body: impl FnOnce(&mut Row) -> Result<()>) {
        if !self.wants(case) {
            return;
        }
        let mut row = Row::new(case, checked);
        let started = Instant::now();
        // A panic is a failure of this case, not the end of the suite.
        let hook = std::panic::take_hook();
        std::panic::set_hook(Box::new(|_| {}));
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| body(&mut row)));
        std::panic::set_hook(hook);
        match outcome {
            Ok(Ok(())) => {}
            Ok(Err(err)) => {
                let chain: Vec<String> = err.chain().map(|c| c.to_string()).collect();
                row.failures.push(format!("error: {}", chain.join(": ")));
            }
            Err(payload) => {
                let message = payload
                    .downcast_ref::<String>()
                    .map(String::as_str)
                    .or_else(|| payload.downcast_ref::<&str>().copied())
                    .unwrap_or("(no message)");
                row.failures.push(format!("panicked: {message}"));
            }
        }
        row.secs = started.elapsed().as_secs_f64();
        eprintln!(
            "stress: {:<28} {} ({:.2} s)",
            row.case,
            if row.passed() { "pass" } else { "FAIL" },
            row.secs
        );
        self.rows.push(row);
    }
}

/// Runs `flatland stress`.
pub fn run(quick: bool, soak_steps: Option<u64>, only: Option<String>) -> Result<()> {
    let mut suite = Suite {
        quick,
        soak_steps: soak_steps.unwrap_or(if quick { 500_000 } else { 10_000_000 }),
        only: only.clone(),
        rows: Vec::new(),
    };
    let started = Instant::now();
    let fig3 = bundled::scene(bundled::DEFAULT).context("the bundled fig3 scene")?;
    let maze = flatland_geom::bundled::scene("maze").context("maze")?;

    // The fit every comparison is made against, run once by the first case that needs it.
    let mut baseline = Baseline {
        scene: &fig3,
        summary: None,
    };
    scale_cases(&mut suite, &fig3, &mut baseline);
    emission_cases(&mut suite, &fig3, &mut baseline);
    reflectance_cases(&mut suite);
    geometry_cases(&mut suite);
    many_edges_case(&mut suite, &maze);
    parameter_cases(&mut suite, &fig3);
    soak_case(&mut suite, &fig3);

    print!(
        "{}",
        table(&suite.rows, quick, started.elapsed().as_secs_f64())
    );
    let failed = suite.rows.iter().filter(|r| !r.passed()).count();
    if suite.rows.is_empty() {
        bail!(
            "no stress case matches --only {:?}",
            only.as_deref().unwrap_or("")
        );
    }
    if failed > 0 {
        bail!("{failed} of {} stress cases failed", suite.rows.len());
    }
    Ok(())
}

/// The result table, then one line per failure.
fn table(rows: &[Row], quick: bool, secs: f64) -> String {
    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(
        w,
        "flatland stress{}: {} cases, {:.1} s",
        if quick { " --quick" } else { "" },
        rows.len(),
        secs
    );
    let _ = writeln!(
        w,
        "{:<28} {:<58} {:<6} {:>10} {:>5} {:>10} {:>8}",
        "case", "checked", "result", "max|value|", "NaN", "error", "time"
    );
    for r in rows {
        let error = r.error.map_or("-".to_owned(), |e| {
            if e == 0.0 || e >= 1e-3 {
                format!("{e:.4}")
            } else {
                format!("{e:.2e}")
            }
        });
        let _ = writeln!(
            w,
            "{:<28} {:<58} {:<6} {:>10.3e} {:>5} {:>10} {:>7.2}s",
            r.case,
            r.checked,
            if r.passed() { "pass" } else { "FAIL" },
            r.max_abs,
            r.non_finite,
            error,
            r.secs
        );
    }
    for r in rows.iter().filter(|r| !r.passed()) {
        if r.non_finite > 0 {
            let _ = writeln!(w, "FAIL {}: {} non-finite values", r.case, r.non_finite);
        }
        for f in &r.failures {
            let _ = writeln!(w, "FAIL {}: {f}", r.case);
        }
    }
    let failed = rows.iter().filter(|r| !r.passed()).count();
    let _ = writeln!(w, "{} passed, {failed} failed", rows.len() - failed);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_geom::{Edge, Kernel, Scene};
    use flatland_solve::Errors;
    use flatland_testkit::assert_close;

    fn unit_box(rho: f64) -> Kernel {
        let mut edges = room(&flatland_testkit::rooms::unit_square(), rho);
        edges[0].emission = 1.0;
        Kernel::new(Scene::new(edges).unwrap())
    }

    #[test]
    fn row_integral_is_one_in_a_closed_room() {
        let kernel = unit_box(0.5);
        for s in [0.125, 0.3, 0.5 + 1e-9, 0.999] {
            let integral = row_integral(&kernel, s, 500);
            assert_close!(integral, 1.0, 1e-4, "s = {s}: {integral}");
        }
        // (The paper's printed 1/(2πr) would give 1/π: far outside the 1 % tolerance.)
        let mut row = Row::new("box", "energy");
        check_energy(&mut row, &kernel, 500, 4);
        assert!(row.passed(), "{:?}", row.failures);
    }

    #[test]
    fn an_open_scene_fails_the_energy_check_with_a_reason() {
        // Two facing walls: most of what leaves the floor escapes.
        let edges = vec![
            Edge::surface(v(0.0, 0.0), v(1.0, 0.0), 0.5).with_emission(1.0),
            Edge::surface(v(1.0, 1.0), v(0.0, 1.0), 0.5),
        ];
        let kernel = Kernel::new(Scene::new(edges).unwrap());
        let mut row = Row::new("open", "energy");
        check_energy(&mut row, &kernel, 500, 2);
        assert!(!row.passed());
        assert!(row.failures[0].contains("energy"), "{:?}", row.failures);
    }

    #[test]
    fn the_adversarial_scenes_are_valid_and_closed() {
        for (name, scene) in [
            ("tiny", tiny_edges_scene().unwrap()),
            ("junctions", junctions_scene().unwrap()),
            ("fan", fan_scene(12).unwrap()),
        ] {
            assert!(scene.max_emission() > 0.0, "{name} has no light");
        }
        assert_eq!(fan_scene(12).unwrap().edges().len(), 36);
        let tiny = tiny_edges_scene().unwrap();
        let shortest = tiny
            .edges()
            .iter()
            .map(Edge::length)
            .fold(f64::MAX, f64::min);
        let longest = tiny.edges().iter().map(Edge::length).fold(0.0, f64::max);
        assert!(
            shortest <= 1.0001e-9 && longest >= 1e3,
            "{shortest} {longest}"
        );
    }

    #[test]
    fn a_row_fails_on_a_reason_or_a_non_finite_value_and_the_table_says_so() {
        let mut ok = Row::new("fine", "nothing");
        ok.see_all([1.0, -3.0]);
        assert!(ok.passed());
        assert_eq!(ok.max_abs, 3.0);
        let mut nan = Row::new("nan", "values");
        nan.see(f64::NAN);
        assert!(!nan.passed());
        let mut failed = Row::new("failed", "a rule");
        failed.require(false, || "the rule broke".into());
        let text = table(&[ok, nan, failed], true, 0.0);
        assert!(text.contains("FAIL nan: 1 non-finite values"), "{text}");
        assert!(text.contains("FAIL failed: the rule broke"), "{text}");
        assert!(text.ends_with("1 passed, 2 failed\n"), "{text}");
    }

    #[test]
    fn same_errors_allows_five_percent() {
        let errors = |e: f64| Errors {
            grid: e,
            heldout: e,
            l1_grid: e,
            l1_heldout: e,
            heldout_spread: [e, e],
        };
        let mut row = Row::new("x", "y");
        same_errors(&mut row, "x", errors(0.52), errors(0.5));
        assert!(row.passed());
        same_errors(&mut row, "x", errors(0.53), errors(0.5));
        assert_eq!(row.failures.len(), 2, "{:?}", row.failures);
    }

    #[test]
    fn the_generator_is_seeded_and_uniform() {
        let a = random_pairs(1000, 5);
        assert_eq!(a, random_pairs(1000, 5));
        assert_ne!(a, random_pairs(1000, 6));
        let mean = a.iter().map(|p| p[0]).sum::<f64>() / 1000.0;
        assert_close!(mean, 0.5, 0.05);
        assert!(
            a.iter()
                .all(|p| (0.0..1.0).contains(&p[0]) && (0.0..1.0).contains(&p[1]))
        );
    }
}
