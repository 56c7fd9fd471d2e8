//! The timed bench's runner: each method's sweep in turn, every row kept as it is made, a
//! failure or panic at one setting turned into a row that says so, and with a time budget each
//! sweep in its share of what is left, cut with a note where its next row would not fit.

use std::collections::HashMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use flatland_geom::Kernel;
use flatland_solve::Stop;

use super::budget::{self, Budget, cut_note, predicted};
use super::compute::Context;
use super::settings::{ElementRange, Sweep};
use super::{Method, Scorer, Setting, TimedPlan, TimedRow};
use crate::interrupt;

/// Rows computed by a fit that gives two (the paper's network with and without its refit),
/// waiting for the other method's sweep to reach them.
type Spare = HashMap<(Method, usize, u64), TimedRow>;

/// What is called with the rows so far after each row.
type Kept<'k> = dyn FnMut(&[TimedRow]) -> Result<()> + 'k;

/// Runs every method's sweep on `scorer`'s mesh, calling `kept` with the rows so far after each
/// row (so they are on disk before the next one starts). A setting that fails gives a failed
/// row and the sweep goes on; Ctrl-C (`stop`, [`interrupt`]) ends the run between rows. With
/// the plan's [`Budget`], each method's sweep gets its share of what is left when it starts
/// (its first setting always runs) and ends where its next setting is predicted not to fit.
pub fn run_timed(
    kernel: &Arc<Kernel>,
    scorer: &Scorer,
    plan: &TimedPlan,
    stop: &Stop,
    mut kept: impl FnMut(&[TimedRow]) -> Result<()>,
) -> Result<Vec<TimedRow>> {
    plan.validate()?;
    let mut runner = Runner {
        cx: Context::new(kernel, scorer, plan, stop),
        elements: ElementRange::new(kernel, scorer.mesh().len(), scorer.reference_elements()),
        rows: Vec::new(),
        spare: Spare::new(),
    };
    let weights = budget::weights(&plan.methods);
    for (index, &method) in plan.methods.iter().enumerate() {
        let share = plan
            .budget
            .map(|b| Budget::since(Instant::now(), budget::share(b.left(), &weights, index)));
        runner.sweep(method, share, &mut kept)?;
    }
    Ok(runner.rows)
}

/// A run under way: what rows are computed with, and the rows so far.
struct Runner<'a> {
    cx: Context<'a>,
    elements: ElementRange,
    rows: Vec<TimedRow>,
    spare: Spare,
}

impl Runner<'_> {
    /// `method`'s sweep, within `share` if there is one.
    fn sweep(&mut self, method: Method, share: Option<Budget>, kept: &mut Kept<'_>) -> Result<()> {
        let plan = self.cx.plan;
        let mut sweep = Sweep::new(method);
        // Wall seconds of each setting, scoring included: what the next one is predicted from.
        let mut walls = Vec::new();
        let mut next = sweep.next(plan, &self.elements, &self.mine(method));
        while let Some(setting) = next {
            let started = Instant::now();
            self.cx.light_seconds = share.map_or(plan.max_seconds, |s| {
                plan.max_seconds.min(s.left().max(MIN_LIGHT_SECONDS))
            });
            let over = self.setting_rows(method, setting, kept)?;
            walls.push(started.elapsed().as_secs_f64());
            next = if over {
                self.note_last("over --max-seconds: the sweep stops here");
                None
            } else {
                sweep.next(plan, &self.elements, &self.mine(method))
            };
            if let (Some(setting), Some(share)) = (next, share)
                && !self.made(method, setting)
                && let Some(seconds) = predicted(method, &walls).filter(|&p| p > share.left())
            {
                if method != Method::PaperNorefit {
                    self.note_last(&cut_note(setting, seconds, share.left()));
                } else {
                    // The second of the paper's pair: its rows came from the first's fit.
                    self.note_last(
                        "cut by the time budget where the fit it shares with the paper's other \
                         row was (--full runs every setting)",
                    );
                }
                next = None;
            }
            kept(&self.rows)?;
        }
        Ok(())
    }

    /// Every seed's row of `method` at `setting`, each kept as it is made but the last (kept
    /// once the sweep knows whether it goes on); whether one was over `--max-seconds`.
    fn setting_rows(
        &mut self,
        method: Method,
        setting: Setting,
        kept: &mut Kept<'_>,
    ) -> Result<bool> {
        let seeds = if method.seeded() {
            self.cx.plan.seeds
        } else {
            1
        };
        let mut over = false;
        for seed in 1..=seeds {
            let row = isolated(&self.cx, method, setting, seed, &mut self.spare);
            interrupt::check()?;
            if (self.cx.stop)() {
                anyhow::bail!("stopped");
            }
            over |= row.total_s > self.cx.plan.max_seconds;
            self.rows.push(row);
            if seed < seeds {
                kept(&self.rows)?;
            }
        }
        Ok(over)
    }

    /// `method`'s rows so far.
    fn mine(&self, method: Method) -> Vec<&TimedRow> {
        self.rows.iter().filter(|r| r.method == method).collect()
    }

    /// Whether every seed's row of `method` at `setting` is already made (by the fit of the
    /// other of the paper's two rows): it costs nothing more.
    fn made(&self, method: Method, setting: Setting) -> bool {
        let Setting::Budget(b) = setting else {
            return false;
        };
        let seeds = if method.seeded() {
            self.cx.plan.seeds
        } else {
            1
        };
        (1..=seeds).all(|seed| self.spare.contains_key(&(method, b, seed)))
    }

    /// Adds `note` to the last row.
    fn note_last(&mut self, note: &str) {
        if let Some(last) = self.rows.last_mut() {
            last.add_note(note);
        }
    }
}

/// The least time limit the light-driven learner is given (it checks it between rounds, so it
/// makes one round at least).
const MIN_LIGHT_SECONDS: f64 = 1e-3;

/// The row of `method` at `setting`, or a failed row with the error or panic that stopped it.
fn isolated(
    cx: &Context<'_>,
    method: Method,
    setting: Setting,
    seed: u64,
    spare: &mut Spare,
) -> TimedRow {
    match catch_unwind(AssertUnwindSafe(|| {
        computed(cx, method, setting, seed, spare)
    })) {
        Ok(Ok(row)) => row,
        Ok(Err(e)) => TimedRow::failed(method, setting, seed, &format!("{e:#}")),
        Err(panic) => {
            let why = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".to_owned());
            TimedRow::failed(method, setting, seed, &format!("panicked: {why}"))
        }
    }
}

fn computed(
    cx: &Context<'_>,
    method: Method,
    setting: Setting,
    seed: u64,
    spare: &mut Spare,
) -> Result<TimedRow> {
    match (method, setting) {
        (Method::Light, Setting::Tolerance(t)) => Ok(cx.light(t)?.0),
        (Method::Visibility, Setting::Budget(b)) => cx.visibility(b, seed),
        (Method::Paper | Method::PaperNorefit, Setting::Budget(b)) => {
            if let Some(row) = spare.remove(&(method, b, seed)) {
                return Ok(row);
            }
            let (refit, norefit) = cx.paper(b, seed)?;
            let (mine, other) = if method == Method::Paper {
                (refit, norefit)
            } else {
                (norefit, refit)
            };
            spare.insert((other.method, b, seed), other);
            Ok(mine)
        }
        (Method::Hr | Method::Clustered | Method::Uniform, Setting::Budget(b)) => {
            cx.baseline(method, b, seed)
        }
        (Method::Exact, Setting::Elements(n)) => cx.exact(n),
        (Method::Tracer, Setting::Photons(p)) => cx.tracer(p, seed),
        _ => anyhow::bail!("{} has no {} setting", method.name(), setting.kind()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timed::scorer::tiny;
    use flatland_solve::never;

    /// Runs `plan`, recording the row count at every call of `kept`.
    fn run(plan: &TimedPlan) -> (Vec<TimedRow>, Vec<Vec<TimedRow>>) {
        let (kernel, scorer) = tiny();
        let mut snapshots = Vec::new();
        let rows = run_timed(&kernel, &scorer, plan, &never, |rows| {
            snapshots.push(rows.to_vec());
            Ok(())
        })
        .unwrap();
        (rows, snapshots)
    }

    #[test]
    fn a_failing_method_gives_failed_rows_and_the_rows_before_are_kept_first() {
        let mut plan = TimedPlan::new(vec![Method::Uniform, Method::Hr]);
        plan.budgets = vec![16, 36];
        plan.extend_budgets = false;
        // An HR that may not build its initial linking fails at every budget.
        plan.recipes.hr.max_links = 5;
        let (rows, snapshots) = run(&plan);
        assert_eq!(snapshots.len(), rows.len(), "kept after every row");
        for (k, s) in snapshots.iter().enumerate() {
            assert_eq!(s[..], rows[..=k], "snapshot {k}");
        }
        let first_failure = rows.iter().position(|r| r.failed).expect("HR fails");
        assert!(first_failure >= 2, "{rows:?}");
        assert!(
            rows[..first_failure]
                .iter()
                .all(|r| r.method == Method::Uniform)
        );
        let hr: Vec<&TimedRow> = rows.iter().filter(|r| r.method == Method::Hr).collect();
        assert_eq!(hr.len(), 2, "each budget tried: {hr:?}");
        assert!(
            hr.iter()
                .all(|r| r.failed && r.note.starts_with("failed: ")),
            "{hr:?}"
        );
        assert!(
            rows.iter()
                .filter(|r| r.method == Method::Uniform)
                .all(|r| { !r.failed && r.reflected_error().is_some_and(f64::is_finite) })
        );
    }

    #[test]
    fn a_budget_below_what_hr_can_build_gives_one_noted_row() {
        let mut plan = TimedPlan::new(vec![Method::Hr]);
        plan.budgets = vec![3, 4, 5];
        plan.extend_budgets = false;
        let (rows, _) = run(&plan);
        assert_eq!(rows.len(), 1, "not repeated: {rows:?}");
        let row = &rows[0];
        assert!(!row.failed && row.basis_functions.unwrap() > 5, "{row:?}");
        assert!(row.note.contains("initial linking"), "{row:?}");
        assert!(row.reflected_error().is_some_and(f64::is_finite));
    }

    #[test]
    fn clustered_rows_land_on_their_budgets_and_light_the_scene() {
        let mut plan = TimedPlan::new(vec![Method::Clustered]);
        plan.budgets = vec![16, 256, 4096];
        plan.extend_budgets = false;
        let (rows, _) = run(&plan);
        assert_eq!(rows.len(), 3, "{rows:?}");
        for r in &rows {
            let Setting::Budget(b) = r.setting else {
                panic!("{r:?}")
            };
            assert!(!r.failed && r.note.is_empty(), "{r:?}");
            assert!(r.basis_functions.unwrap().abs_diff(b) <= 3, "{r:?}");
            assert!(r.rays > 0 && r.bytes > 0, "{r:?}");
        }
        let error = |k: usize| rows[k].reflected_error().unwrap();
        assert!(error(2) < error(0), "{rows:?}");
    }

    #[test]
    fn default_rows_have_their_estimated_and_measured_errors() {
        let mut plan = TimedPlan::new(vec![Method::Light]);
        plan.tolerances = vec![0.3, 0.05];
        let (rows, _) = run(&plan);
        assert_eq!(rows.len(), 2);
        for r in &rows {
            assert!(!r.failed, "{r:?}");
            assert!(r.estimated_error.is_some_and(f64::is_finite), "{r:?}");
            assert!(r.reflected_error().is_some_and(f64::is_finite), "{r:?}");
            assert!(r.basis_functions.is_some() && r.bytes > 0, "{r:?}");
            assert_eq!(r.total_s, r.build_s + r.solve_s);
        }
        let est = |r: &TimedRow| r.estimated_error.unwrap();
        assert!(est(&rows[1]) <= est(&rows[0]), "{rows:?}");
    }

    #[test]
    fn exact_doubles_its_elements_and_the_tracer_its_photons_within_its_time() {
        let mut plan = TimedPlan::new(vec![Method::Exact, Method::Tracer]);
        plan.tracer_seconds = 0.2;
        plan.first_photons = 2_000;
        let (rows, _) = run(&plan);
        let elements: Vec<usize> = rows
            .iter()
            .filter(|r| r.method == Method::Exact)
            .filter_map(|r| r.basis_functions)
            .collect();
        assert!(
            elements.len() >= 2 && *elements.last().unwrap() <= 4 * 64,
            "{elements:?}"
        );
        assert!(
            elements.windows(2).all(|w| w[1] == 2 * w[0]),
            "{elements:?}"
        );
        let traced: Vec<&TimedRow> = rows.iter().filter(|r| r.method == Method::Tracer).collect();
        assert!(!traced.is_empty());
        assert!(
            traced.iter().all(|r| r.zeta.is_none() && r.rays > 0),
            "{traced:?}"
        );
        // It stops once its rows took the time asked for (the last may go over).
        let before_last: f64 = traced[..traced.len() - 1].iter().map(|r| r.total_s).sum();
        assert!(before_last < plan.tracer_seconds, "{traced:?}");
    }

    #[test]
    fn a_spent_budget_cuts_every_sweep_after_its_first_setting_with_a_note() {
        let mut plan = TimedPlan::new(vec![Method::Uniform, Method::Clustered]);
        plan.budgets = vec![16, 36, 64];
        plan.extend_budgets = false;
        // Spent before the run starts: each method's first setting runs, nothing after it.
        let long_ago = Instant::now() - std::time::Duration::from_secs(3600);
        plan.budget = Some(Budget::since(long_ago, 1.0));
        let (rows, snapshots) = run(&plan);
        assert_eq!(snapshots.len(), rows.len(), "kept after every row");
        let methods: Vec<Method> = rows.iter().map(|r| r.method).collect();
        assert_eq!(methods, [Method::Uniform, Method::Clustered], "{rows:?}");
        for r in &rows {
            assert_eq!(r.setting, Setting::Budget(16), "{r:?}");
            assert!(!r.failed && r.reflected_error().is_some(), "{r:?}");
            assert!(
                r.note.contains("cut by the time budget: budget 36"),
                "{r:?}"
            );
        }
        // Without the budget the same plan runs every setting.
        plan.budget = None;
        let (all, _) = run(&plan);
        assert_eq!(all.len(), 6, "{all:?}");
        assert!(all.iter().all(|r| !r.note.contains("cut by")), "{all:?}");
    }

    #[test]
    fn a_sweep_stops_at_its_first_row_over_the_time_budget() {
        let mut plan = TimedPlan::new(vec![Method::Uniform]);
        plan.budgets = vec![16, 36, 64];
        plan.extend_budgets = false;
        plan.max_seconds = 1e-9;
        let (rows, _) = run(&plan);
        assert_eq!(rows.len(), 1, "{rows:?}");
        assert!(rows[0].note.contains("--max-seconds"), "{rows:?}");
    }
}
