//! `flatland bench`'s whole-run time budget: the default, the part the sweeps get (the rest is
//! kept for relighting), relighting fitted into what is left, and progress that says what is
//! left.

use std::time::Instant;

use anyhow::Result;
use flatland_lab::timed::{
    Budget, RELIGHT_SHARE, RelightBudget, Scorer, TimedPlan, TimedRow, relight_within,
};

use super::Args;

/// The whole run's seconds when `--budget-seconds` is not given: with the reference solves,
/// plots and relighting, the defaults finish in under three minutes on two cores for scenes of
/// a few hundred edges.
pub const DEFAULT_BUDGET_SECONDS: f64 = 120.0;

/// The run's budget from `started` (`None` with `--full`), checked.
pub fn of(args: &Args, started: Instant) -> Result<Option<Budget>> {
    if args.full {
        return Ok(None);
    }
    let seconds = args.budget_seconds.unwrap_or(DEFAULT_BUDGET_SECONDS);
    let budget = Budget::since(started, seconds);
    budget.check()?;
    Ok(Some(budget))
}

/// What the sweeps may spend of `budget`: all of it without relighting, else all but the
/// relighting's share.
pub fn sweeps(budget: Budget, lightings: usize) -> Budget {
    if lightings == 0 {
        budget
    } else {
        budget.keeping(RELIGHT_SHARE * budget.seconds())
    }
}

/// The relighting that fits in what is left of `budget` (every lighting with every row without
/// one), its notes printed on stderr.
pub fn relighting(
    budget: Option<Budget>,
    reference_s: f64,
    scorer: &Scorer,
    plan: &TimedPlan,
    rows: &[TimedRow],
    lightings: usize,
) -> RelightBudget {
    let Some(budget) = budget else {
        return RelightBudget {
            lightings,
            plan: plan.clone(),
            rows: rows.to_vec(),
            notes: Vec::new(),
        };
    };
    let elements = scorer.mesh().len();
    let fitted = relight_within(budget.left(), reference_s, elements, plan, rows, lightings);
    for note in &fitted.notes {
        eprintln!("bench: {note}");
    }
    fitted
}

/// One line on stderr after `last`: the methods done and left, and the seconds of the budget
/// left.
pub fn progress(plan: &TimedPlan, last: &TimedRow) {
    let at = plan
        .methods
        .iter()
        .position(|&m| m == last.method)
        .unwrap_or(0);
    let after: Vec<&str> = plan.methods[at + 1..].iter().map(|m| m.name()).collect();
    let left = if after.is_empty() {
        "no method after it".to_owned()
    } else {
        format!("{} after it ({})", after.len(), after.join(", "))
    };
    let seconds = plan.budget.map_or(String::new(), |b| {
        format!(
            "; {:.0} s of the sweeps' {:.0} s left",
            b.left(),
            b.seconds()
        )
    });
    eprintln!(
        "bench: method {} of {} ({}), {left}{seconds}",
        at + 1,
        plan.methods.len(),
        last.method.name()
    );
}
