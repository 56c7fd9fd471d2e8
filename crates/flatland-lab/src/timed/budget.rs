//! The whole run's time budget: a deadline shared fairly by the methods still to run (each
//! sweep gets its share of what is left when it starts, so time a fast method leaves flows to
//! the next), the cost of a method's next row predicted from its rows so far, and relighting
//! fitted into what is left after the sweeps.

use std::time::Instant;

use flatland_methods::{Knob, Method};

use super::{Setting, TimedPlan, TimedRow};
use crate::LabError;

/// A time budget for a whole run, counted from a start the caller chose (the command's own
/// start, so the reference solves before the sweeps count too).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    started: Instant,
    seconds: f64,
}

impl Budget {
    /// `seconds` counted from `started`.
    pub fn since(started: Instant, seconds: f64) -> Budget {
        Budget { started, seconds }
    }

    /// The seconds it has in all.
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// Seconds spent since its start.
    pub fn spent(&self) -> f64 {
        self.started.elapsed().as_secs_f64()
    }

    /// Seconds left (0 once spent).
    pub fn left(&self) -> f64 {
        (self.seconds - self.spent()).max(0.0)
    }

    /// The same start with `reserve` seconds kept back for what comes after (at least nothing).
    #[must_use]
    pub fn keeping(self, reserve: f64) -> Budget {
        Budget {
            seconds: (self.seconds - reserve).max(0.0),
            ..self
        }
    }

    /// Checks the seconds: more than 0, finite.
    pub fn check(&self) -> Result<(), LabError> {
        if self.seconds.is_finite() && self.seconds > 0.0 {
            return Ok(());
        }
        Err(LabError::InvalidParameter {
            name: "budget-seconds",
            value: self.seconds.to_string(),
            valid: "more than 0 and finite",
        })
    }
}

/// Each method's weight in the shares: 1, except that the paper's network with and without its
/// refit come from one fit, so the first of the two to run takes both shares and the second's
/// rows are already made.
pub(crate) fn weights(methods: &[Method]) -> Vec<f64> {
    let paper = |m: &Method| matches!(m, Method::Paper | Method::PaperNorefit);
    let both = methods.iter().filter(|m| paper(m)).count() == 2;
    let mut seen = false;
    methods
        .iter()
        .map(|m| match (paper(m) && both, seen) {
            (false, _) => 1.0,
            (true, false) => {
                seen = true;
                2.0
            }
            (true, true) => 0.0,
        })
        .collect()
}

/// The share of `left` seconds of the method at `index`, by `weights`, among it and the
/// methods after it.
pub(crate) fn share(left: f64, weights: &[f64], index: usize) -> f64 {
    let rest: f64 = weights[index..].iter().sum();
    if rest > 0.0 {
        left * weights[index] / rest
    } else {
        0.0
    }
}

/// How much longer a method's next setting takes than its last, when its rows cannot tell:
/// photons cost in proportion, a dense operator on twice the elements four times as much,
/// a tighter tolerance or a doubled budget about twice as much or more.
fn first_growth(knob: Knob) -> f64 {
    match knob {
        Knob::Elements => 4.0,
        Knob::Tolerance => 3.0,
        Knob::Budget | Knob::Photons => 2.0,
    }
}

/// The seconds `method`'s next setting should take, from the wall seconds its settings took so
/// far (`None` before its first: nothing to go on). The last time grows by the ratio of the
/// last two, within [the knob's first growth, 8], so a sweep that speeds up is still predicted
/// to cost more than its last row.
pub(crate) fn predicted(method: Method, walls: &[f64]) -> Option<f64> {
    let (&last, before) = walls.split_last()?;
    let least = first_growth(method.knob());
    let growth = match before.last() {
        Some(&previous) if previous > 0.0 => (last / previous).clamp(least, 8.0),
        _ => least,
    };
    Some(last * growth)
}

/// The note of a sweep cut because its next row would not fit its share.
pub(crate) fn cut_note(next: Setting, predicted: f64, left: f64) -> String {
    format!(
        "cut by the time budget: {} {} would take about {predicted:.1} s, {left:.1} s of its \
         share left (--full runs every setting)",
        next.kind(),
        next.value()
    )
}

/// Share of the whole budget kept back for relighting when there is any.
pub const RELIGHT_SHARE: f64 = 0.2;

/// Relighting fitted into a time: how many lightings, with which methods and at which of their
/// rows, and what was left out.
#[derive(Clone, Debug, PartialEq)]
pub struct RelightBudget {
    /// Lightings to relight (0: none fit).
    pub lightings: usize,
    /// The plan to relight with: the methods that fit, the light-driven learner's time limit
    /// its share.
    pub plan: TimedPlan,
    /// The sweep's rows relighting may match (those it can repeat for every lighting in time).
    pub rows: Vec<TimedRow>,
    /// What was left out and why, one line each.
    pub notes: Vec<String>,
}

/// The methods relighting compares.
const RELIT: [Method; 5] = [
    Method::Light,
    Method::Exact,
    Method::Hr,
    Method::Clustered,
    Method::Tracer,
];

/// Relighting within `left` seconds: as many of `lightings` as leave half the time to the
/// methods after their exact references (`reference_s` each, the lit scene's own solve), then
/// each method relit in its share of the rest at the rows of `rows` it can repeat for every
/// lighting in that share (the exact operator on the solve's `elements`). A method with no such
/// row is left out with a note.
pub fn relight_within(
    left: f64,
    reference_s: f64,
    elements: usize,
    plan: &TimedPlan,
    rows: &[TimedRow],
    lightings: usize,
) -> RelightBudget {
    let methods: Vec<Method> = plan
        .methods
        .iter()
        .copied()
        .filter(|m| RELIT.contains(m))
        .collect();
    let by_references = 1 + (0.5 * left / reference_s.max(1e-9)).floor() as usize;
    let count = lightings.min(by_references);
    let mut out = RelightBudget {
        lightings: count,
        plan: TimedPlan {
            methods: Vec::new(),
            ..plan.clone()
        },
        rows: Vec::new(),
        notes: Vec::new(),
    };
    if count < 2 || methods.is_empty() {
        out.lightings = 0;
        out.notes.push(format!(
            "relighting skipped: each lighting's exact reference takes about {reference_s:.1} s \
             and {left:.1} s of the budget are left (--full or a larger --budget-seconds \
             relights)"
        ));
        return out;
    }
    if count < lightings {
        out.notes.push(format!(
            "relighting {count} of {lightings} lightings: each one's exact reference takes \
             about {reference_s:.1} s of the {left:.1} s left (--full relights them all)"
        ));
    }
    let per = (left - (count - 1) as f64 * reference_s) / methods.len() as f64;
    let cost = Cost {
        lightings: count as f64,
        elements,
    };
    for method in methods {
        fit_method(&mut out, method, rows, &cost, per);
    }
    out
}

/// Adds `method` to `out`'s plan with the rows of `rows` it can repeat for every lighting in
/// `per` seconds, or a note that it is left out.
fn fit_method(out: &mut RelightBudget, method: Method, rows: &[TimedRow], cost: &Cost, per: f64) {
    let mine: Vec<&TimedRow> = rows
        .iter()
        .filter(|r| r.method == method && !r.failed && r.solve.is_some())
        .collect();
    let (fits, affordable) = match method {
        Method::Light => {
            // It learns once in what its re-solves leave of the share.
            let solves = cost.lightings * mine.iter().map(|r| r.solve_s).fold(0.0, f64::max);
            let learn = per - solves;
            if learn > 0.0 {
                out.plan.max_seconds = out.plan.max_seconds.min(learn);
            }
            (learn > 0.0, Vec::new())
        }
        Method::Exact => (cost.exact(&mine).is_some_and(|s| s <= per), Vec::new()),
        _ => {
            let rows: Vec<TimedRow> = mine
                .iter()
                .filter(|r| cost.of_row(r) <= per)
                .map(|r| (*r).clone())
                .collect();
            (!rows.is_empty(), rows)
        }
    };
    if fits {
        out.plan.methods.push(method);
        out.rows.extend(affordable);
    } else {
        out.notes.push(format!(
            "relighting without {}: none of its rows can be repeated for {} lightings in its \
             share of {per:.1} s (--full relights it)",
            method.name(),
            out.lightings
        ));
    }
}

/// What relighting with a row costs.
struct Cost {
    lightings: f64,
    elements: usize,
}

impl Cost {
    /// A row built once and solved per lighting, or (the tracer) traced per lighting.
    fn of_row(&self, r: &TimedRow) -> f64 {
        match r.method {
            Method::Tracer => self.lightings * r.total_s,
            _ => r.build_s + self.lightings * r.solve_s,
        }
    }

    /// The exact operator on the solve's elements, from the exact row on the fewest elements
    /// at least as many, or the largest row scaled up (assembly with the square of the
    /// elements, solves in proportion); `None` without rows.
    fn exact(&self, rows: &[&TimedRow]) -> Option<f64> {
        let n = |r: &TimedRow| r.basis_functions.unwrap_or(0);
        if let Some(r) = rows
            .iter()
            .filter(|r| n(r) >= self.elements)
            .min_by_key(|r| n(r))
        {
            return Some(self.of_row(r));
        }
        let r = rows.iter().max_by_key(|r| n(r))?;
        let scale = self.elements as f64 / n(r).max(1) as f64;
        Some(r.build_s * scale * scale + self.lightings * r.solve_s * scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn the_paper_pair_shares_one_weight_and_shares_follow_what_is_left() {
        let methods = [
            Method::Light,
            Method::Paper,
            Method::PaperNorefit,
            Method::Hr,
        ];
        assert_eq!(weights(&methods), [1.0, 2.0, 0.0, 1.0]);
        assert_eq!(weights(&[Method::PaperNorefit, Method::Hr]), [1.0, 1.0]);
        let w = weights(&methods);
        assert_eq!(share(100.0, &w, 0), 25.0);
        assert_eq!(share(60.0, &w, 1), 40.0);
        assert_eq!(share(10.0, &w, 2), 0.0);
        assert_eq!(share(10.0, &w, 3), 10.0);
    }

    #[test]
    fn the_next_row_is_predicted_to_cost_more_than_the_last() {
        assert_eq!(predicted(Method::Hr, &[]), None);
        assert_eq!(predicted(Method::Hr, &[1.0]), Some(2.0));
        assert_eq!(predicted(Method::Exact, &[1.0]), Some(4.0));
        // The ratio of the last two, at least the knob's growth, at most 8.
        assert_eq!(predicted(Method::Hr, &[1.0, 3.0]), Some(9.0));
        assert_eq!(predicted(Method::Hr, &[2.0, 1.0]), Some(2.0));
        assert_eq!(predicted(Method::Tracer, &[0.1, 10.0]), Some(80.0));
    }

    #[test]
    fn a_budget_counts_from_its_start_and_keeps_a_reserve() {
        let long_ago = Instant::now() - Duration::from_secs(10);
        let spent = Budget::since(long_ago, 5.0);
        assert_eq!(spent.left(), 0.0);
        let ample = Budget::since(Instant::now(), 1e6);
        assert!(ample.left() > 0.99e6 && ample.keeping(4e5).seconds() == 6e5);
        assert!(Budget::since(long_ago, 0.0).check().is_err());
        let msg = Budget::since(long_ago, f64::NAN)
            .check()
            .unwrap_err()
            .to_string();
        assert!(msg.contains("budget-seconds"), "{msg}");
    }

    fn row(method: Method, setting: Setting, build_s: f64, solve_s: f64) -> TimedRow {
        let mut r = TimedRow::new(method, setting, 1);
        r.build_s = build_s;
        r.solve_s = solve_s;
        r.total_s = build_s + solve_s;
        r.basis_functions = Some(match setting {
            Setting::Budget(n) | Setting::Elements(n) => n,
            _ => 0,
        });
        r.solve = Some(flatland_solve::SolveErrors {
            rel_l2_b: 0.1,
            rel_l2_reflected: 0.1,
        });
        r
    }

    #[test]
    fn relighting_keeps_the_lightings_and_rows_that_fit() {
        let plan = TimedPlan::new(vec![Method::Exact, Method::Hr, Method::Tracer]);
        let rows = vec![
            row(Method::Exact, Setting::Elements(512), 1.0, 0.1),
            row(Method::Hr, Setting::Budget(50), 1.0, 0.1),
            row(Method::Hr, Setting::Budget(800), 20.0, 0.1),
            row(Method::Tracer, Setting::Photons(10_000), 0.0, 0.3),
            row(Method::Tracer, Setting::Photons(20_000), 0.0, 10.0),
        ];
        // Nine references of 1 s (the first lighting is the scene's own) leave 11 s: 3.7 s per
        // method, and ten lightings cost each row ten solves or traces.
        let fitted = relight_within(20.0, 1.0, 512, &plan, &rows, 10);
        assert_eq!(fitted.lightings, 10);
        assert_eq!(fitted.plan.methods, plan.methods);
        let kept: Vec<Setting> = fitted.rows.iter().map(|r| r.setting).collect();
        assert_eq!(kept, [Setting::Budget(50), Setting::Photons(10_000)]);
        assert!(fitted.notes.is_empty(), "{:?}", fitted.notes);
        // References of 4 s: two lightings fit in half of 20 s; HR's cheap row fits, and the
        // exact operator on four times the elements (16 s) does not.
        let fitted = relight_within(20.0, 4.0, 2048, &plan, &rows, 10);
        assert_eq!(fitted.lightings, 3);
        assert_eq!(fitted.plan.methods, [Method::Hr, Method::Tracer]);
        assert!(fitted.notes[0].contains("3 of 10"), "{:?}", fitted.notes);
        assert!(
            fitted.notes[1].contains("without exact"),
            "{:?}",
            fitted.notes
        );
        // Not one lighting beside the scene's own: nothing relit, and why.
        let none = relight_within(1.0, 4.0, 512, &plan, &rows, 10);
        assert_eq!(none.lightings, 0);
        assert!(none.notes[0].contains("skipped"), "{:?}", none.notes);
    }
}
