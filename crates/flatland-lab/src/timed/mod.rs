//! Methods judged at equal time: each swept over its own knob (tolerance, basis functions,
//! elements, photons) until a row takes longer than the time budget; every row timed to its lit
//! scene and scored against one independent exact reference. Relighting ([`relight`]) times
//! ten lightings of the same geometry; [`walk`] a lamp carried through generated plans and
//! halls, every method per move.
//!
//! A method that cannot meet a setting gives the nearest row it can with a note; one that
//! fails there gives a failed row with the reason, and the sweep goes on.

pub(crate) mod compute;
pub mod relight;
pub mod walk;

mod row;
mod run;
mod scorer;
mod settings;

use flatland_baselines::{ClusteredParams, HrParams, UniformParams};
use kernel_fit::FitParams;

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
    /// The first-shot learner's parameters (cells and seed set per row).
    pub fit: FitParams,
    /// The paper network's parameters (cells and seed set per row).
    pub paper: FitParams,
    /// HR parameters.
    pub hr: HrParams,
    /// Clustered-HR parameters.
    pub clustered: ClusteredParams,
    /// Uniform-grid parameters.
    pub uniform: UniformParams,
}

impl TimedPlan {
    /// Every method with its default sweep.
    pub fn new(methods: Vec<Method>) -> TimedPlan {
        TimedPlan {
            methods,
            tolerances: DEFAULT_TOLERANCES.to_vec(),
            budgets: DEFAULT_BUDGETS.to_vec(),
            extend_budgets: true,
            seeds: 1,
            max_seconds: DEFAULT_MAX_SECONDS,
            tracer_seconds: DEFAULT_TRACER_SECONDS,
            first_photons: FIRST_PHOTONS,
            fit: FitParams::default(),
            paper: FitParams::paper(),
            hr: HrParams::default(),
            clustered: ClusteredParams::default(),
            uniform: UniformParams::default(),
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
        Ok(())
    }
}
