//! Methods judged at equal time: each swept over its own knob (tolerance, basis functions,
//! elements, photons) until a row takes longer than the time budget; every row timed to its lit
//! scene and scored against one independent exact reference. Relighting ([`relight`]) times
//! ten lightings of the same geometry; [`walk`] a lamp carried through generated plans and
//! halls, every method per move. Every representation is built by
//! [`flatland_methods::Recipes::build`], the one place each method is built.
//!
//! A method that cannot meet a setting gives the nearest row it can with a note; one that
//! fails there gives a failed row with the reason, and the sweep goes on. With a whole-run
//! [`Budget`], each method's sweep gets its share of what is left and is cut, with a note,
//! where its next row would not fit.
//!
//! The R4 table of the results (every network and baseline at the same basis functions) is one
//! plan of this engine: [`TimedPlan::r4`].

mod budget;
pub(crate) mod compute;
pub mod relight;
pub mod walk;

mod row;
mod run;
mod scorer;
mod settings;

use flatland_methods::Recipes;

pub use budget::{Budget, RELIGHT_SHARE, RelightBudget, relight_within};
pub use flatland_methods::Method;
pub use row::{Setting, TimedRow};
pub use run::run_timed;
pub use scorer::Scorer;

use crate::LabError;

/// The light-driven learner's tolerances, one row each.
pub const DEFAULT_TOLERANCES: [f64; 5] = [0.3, 0.1, 0.03, 0.01, 0.003];

/// The budgets of basis functions the budgeted methods start with.
pub const DEFAULT_BUDGETS: [usize; 5] = [50, 100, 200, 400, 800];

/// A sweep stops at the first row that took longer than this many seconds.
pub const DEFAULT_MAX_SECONDS: f64 = 30.0;

/// The tracer's photons double until its rows took this many seconds together.
pub const DEFAULT_TRACER_SECONDS: f64 = 30.0;

/// Photons of the tracer's first row.
pub const FIRST_PHOTONS: u64 = 10_000;

/// Most budgets a sweep adds by doubling past the list (with the time budget, a bound that only
/// a very fast method meets).
pub const MAX_DOUBLINGS: usize = 12;

/// The methods the R4 table compares: the two networks (the paper's with and without its
/// refit) and the baselines at a budget.
pub const R4_METHODS: [Method; 5] = [
    Method::Visibility,
    Method::Paper,
    Method::PaperNorefit,
    Method::Hr,
    Method::Uniform,
];

/// What the timed bench runs.
#[derive(Clone, Debug, PartialEq)]
pub struct TimedPlan {
    /// Methods, in the order they run.
    pub methods: Vec<Method>,
    /// The light-driven learner's tolerances.
    pub tolerances: Vec<f64>,
    /// Budgets of basis functions, ascending.
    pub budgets: Vec<usize>,
    /// Whether budgets go on doubling past the list (until a row is over the time budget).
    pub extend_budgets: bool,
    /// Seeds 1..=seeds of each seeded method and setting.
    pub seeds: u64,
    /// A method's sweep stops after the first setting with a row whose `total_s` is above this.
    pub max_seconds: f64,
    /// The tracer stops doubling once its rows took this many seconds together.
    pub tracer_seconds: f64,
    /// Photons of the tracer's first row (doubling after).
    pub first_photons: u64,
    /// How each method is built (its knob and seed are set per row; the light-driven
    /// learner's time limit is `max_seconds` or what is left of its share of the budget).
    pub recipes: Recipes,
    /// The whole run's time budget (`None`: every sweep runs to its end or to `max_seconds`).
    pub budget: Option<Budget>,
}

impl TimedPlan {
    /// Every method with its default sweep.
    pub fn new(methods: Vec<Method>) -> TimedPlan {
        let mut recipes = Recipes::default();
        // No learning curve: its evaluations would be timed with the fit.
        recipes.visibility.eval_every = 0;
        recipes.paper.eval_every = 0;
        TimedPlan {
            methods,
            tolerances: DEFAULT_TOLERANCES.to_vec(),
            budgets: DEFAULT_BUDGETS.to_vec(),
            extend_budgets: true,
            seeds: 1,
            max_seconds: DEFAULT_MAX_SECONDS,
            tracer_seconds: DEFAULT_TRACER_SECONDS,
            first_photons: FIRST_PHOTONS,
            recipes,
            budget: None,
        }
    }

    /// The R4 table: the networks and the baselines it compares ([`R4_METHODS`]) at exactly
    /// `budgets`, `seeds` seeds each, every row to its end (no time limit). Its scorer needs a
    /// ζ reference, which the networks train against.
    pub fn r4(budgets: Vec<usize>, seeds: u64) -> TimedPlan {
        TimedPlan {
            budgets,
            extend_budgets: false,
            seeds,
            max_seconds: f64::INFINITY,
            ..TimedPlan::new(R4_METHODS.to_vec())
        }
    }

    /// Checks the plan; errors name the parameter and the valid range. A budget no method can
    /// meet is not an error: its row says so.
    pub fn validate(&self) -> Result<(), LabError> {
        let bad =
            |name, value: String, valid| Err(LabError::InvalidParameter { name, value, valid });
        if self.methods.is_empty() {
            return bad("methods", "(none)".into(), "at least one method");
        }
        if let Some(t) = self.tolerances.iter().find(|t| !(**t > 0.0 && **t < 1.0)) {
            return bad("tolerances", t.to_string(), "each in (0, 1)");
        }
        if let Some(b) = self.budgets.iter().find(|&&b| b < 3) {
            return bad("budgets", b.to_string(), "each ≥ 3");
        }
        if let Some(m) = self.methods.iter().find(|m| m.budgeted())
            && self.budgets.is_empty()
        {
            return bad(
                "budgets",
                format!("(none, with {m})"),
                "at least one budget ≥ 3 for a method swept over basis functions",
            );
        }
        if self.methods.contains(&Method::Light) && self.tolerances.is_empty() {
            return bad(
                "tolerances",
                "(none, with light)".into(),
                "at least one tolerance in (0, 1) for the light-driven learner",
            );
        }
        if self.seeds == 0 {
            return bad("seeds", "0".into(), "≥ 1");
        }
        if self.max_seconds.is_nan() || self.max_seconds <= 0.0 {
            return bad("max-seconds", self.max_seconds.to_string(), "more than 0");
        }
        if self.tracer_seconds.is_nan() || self.tracer_seconds <= 0.0 {
            return bad(
                "tracer-seconds",
                self.tracer_seconds.to_string(),
                "more than 0",
            );
        }
        if self.first_photons == 0 {
            return bad("first-photons", "0".into(), "at least 1");
        }
        if let Some(budget) = self.budget {
            budget.check()?;
        }
        let r = &self.recipes;
        r.visibility.validate()?;
        r.paper.validate()?;
        r.hr.check()?;
        r.clustered.check()?;
        r.uniform.check()?;
        Ok(())
    }
}
