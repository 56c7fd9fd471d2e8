//! The settings each method's sweep goes through, one after another: what comes next given the
//! rows so far.

use flatland_baselines::budget_tolerance;
use flatland_solve::{ExactMethod, MAX_MESH_ELEMENTS, Mesh};

use super::{MAX_DOUBLINGS, Method, Setting, TimedPlan, TimedRow};

/// The largest budget a sweep doubles to (the `--budgets` range).
const MAX_BUDGET: usize = 10_000_000;

/// The most photons the tracer doubles to.
const MAX_PHOTONS: u64 = 1 << 36;

/// The element counts the exact sweep spans.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ElementRange {
    /// The scene's fewest elements ([`Mesh::min_elements`]).
    pub min: usize,
    /// Four times the solve's elements, within what the exact operator can have, and below
    /// the reference's own count (a solve on the reference's mesh is the reference: its
    /// "error" of 0 would measure nothing).
    pub max: usize,
    /// How the exact operator of the scene is assembled (its size limit).
    pub method: ExactMethod,
}

impl ElementRange {
    /// The range of a scene whose solve has `elements` elements, measured against a reference
    /// on `reference` elements.
    pub fn new(kernel: &flatland_geom::Kernel, elements: usize, reference: usize) -> ElementRange {
        ElementRange {
            min: Mesh::min_elements(kernel.scene()).max(1),
            max: (4 * elements)
                .min(MAX_MESH_ELEMENTS)
                .min(reference.saturating_sub(1)),
            method: ExactMethod::of(kernel),
        }
    }

    fn fits(&self, n: usize) -> bool {
        n <= self.max && self.method.check(n).is_ok()
    }
}

/// One method's sweep: the settings handed out so far.
pub(crate) struct Sweep {
    method: Method,
    issued: usize,
    doublings: usize,
}

impl Sweep {
    /// A sweep of `method` that has run nothing.
    pub fn new(method: Method) -> Sweep {
        Sweep {
            method,
            issued: 0,
            doublings: 0,
        }
    }

    /// The next setting after `rows` (this method's rows so far), `None` when the sweep is
    /// done.
    pub fn next(
        &mut self,
        plan: &TimedPlan,
        elements: &ElementRange,
        rows: &[&TimedRow],
    ) -> Option<Setting> {
        let last = rows.last().map(|r| r.setting);
        let next = match (self.method, last) {
            (Method::Light, _) => plan
                .tolerances
                .get(self.issued)
                .map(|&t| Setting::Tolerance(t)),
            (m, _) if m.budgeted() => self.next_budget(plan, rows),
            (Method::Exact, None) => Some(Setting::Elements(elements.min)),
            (Method::Exact, Some(Setting::Elements(n))) => {
                elements.fits(2 * n).then_some(Setting::Elements(2 * n))
            }
            (Method::Tracer, None) => Some(Setting::Photons(plan.first_photons)),
            (Method::Tracer, Some(Setting::Photons(p))) => {
                let spent: f64 = rows.iter().map(|r| r.total_s).sum();
                (spent < plan.tracer_seconds && 2 * p <= MAX_PHOTONS)
                    .then_some(Setting::Photons(2 * p))
            }
            _ => None,
        };
        self.issued += usize::from(next.is_some());
        next
    }

    /// The first listed budget above both the last budget and the basis functions it reached
    /// (so a method that built more than asked — HR's initial linking — does not repeat that
    /// row), then doublings past the list. A failed setting past the list ends the sweep.
    fn next_budget(&mut self, plan: &TimedPlan, rows: &[&TimedRow]) -> Option<Setting> {
        let Some(last) = rows.last() else {
            return plan.budgets.first().map(|&b| Setting::Budget(b));
        };
        let Setting::Budget(asked) = last.setting else {
            return None;
        };
        let at_last: Vec<&&TimedRow> = rows.iter().filter(|r| r.setting == last.setting).collect();
        let reached = at_last
            .iter()
            .filter_map(|r| r.basis_functions)
            .max()
            .unwrap_or(0);
        let floor = asked.max(reached);
        if let Some(&b) = plan.budgets.iter().find(|&&b| b > floor) {
            return Some(Setting::Budget(b));
        }
        let failed = at_last.iter().all(|r| r.failed);
        let past_list = plan.budgets.last().is_none_or(|&b| asked > b);
        // Past the list, a method that built less than asked (HR's finest linking, a learner
        // that converged) cannot grow: more would repeat the row.
        let capped = reached + budget_tolerance(asked) < asked;
        if !plan.extend_budgets
            || self.doublings >= MAX_DOUBLINGS
            || (past_list && (failed || capped))
        {
            return None;
        }
        self.doublings += 1;
        let next = 2 * floor;
        (next <= MAX_BUDGET).then_some(Setting::Budget(next))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: Method, setting: Setting, basis: usize, total_s: f64) -> TimedRow {
        let mut r = TimedRow::new(method, setting, 1);
        r.basis_functions = Some(basis);
        r.total_s = total_s;
        r
    }

    #[test]
    fn a_budget_below_what_was_built_is_not_repeated() {
        let plan = TimedPlan::new(vec![Method::Hr]);
        let range = ElementRange {
            min: 8,
            max: 64,
            method: ExactMethod::Dense,
        };
        let mut sweep = Sweep::new(Method::Hr);
        assert_eq!(sweep.next(&plan, &range, &[]), Some(Setting::Budget(50)));
        // HR built 300 links at budget 50: the next row is past them, at 400.
        let first = row(Method::Hr, Setting::Budget(50), 300, 0.1);
        assert_eq!(
            sweep.next(&plan, &range, &[&first]),
            Some(Setting::Budget(400))
        );
        // 5000 links at 800, the end of the list: doubling from what was built.
        let last = row(Method::Hr, Setting::Budget(800), 5000, 0.1);
        assert_eq!(
            sweep.next(&plan, &range, &[&first, &last]),
            Some(Setting::Budget(10_000))
        );
        // Its finest linking, 7000 links, at 10 000: nothing more to build.
        let finest = row(Method::Hr, Setting::Budget(10_000), 7000, 0.1);
        assert_eq!(sweep.next(&plan, &range, &[&first, &last, &finest]), None);
    }

    #[test]
    fn exact_doubles_to_four_times_the_solve_and_the_tracer_to_its_time() {
        let plan = TimedPlan::new(vec![Method::Exact, Method::Tracer]);
        let range = ElementRange {
            min: 8,
            max: 32,
            method: ExactMethod::Dense,
        };
        let mut exact = Sweep::new(Method::Exact);
        let mut done = Vec::new();
        while let Some(s) = exact.next(&plan, &range, &done.iter().collect::<Vec<_>>()) {
            done.push(row(Method::Exact, s, 0, 0.0));
        }
        let counts: Vec<Setting> = done.iter().map(|r| r.setting).collect();
        assert_eq!(
            counts,
            [8, 16, 32].map(Setting::Elements).to_vec(),
            "{counts:?}"
        );
        let mut tracer = Sweep::new(Method::Tracer);
        let first = row(Method::Tracer, Setting::Photons(10_000), 0, 20.0);
        assert!(tracer.next(&plan, &range, &[]).is_some());
        assert_eq!(
            tracer.next(&plan, &range, &[&first]),
            Some(Setting::Photons(20_000))
        );
        let second = row(Method::Tracer, Setting::Photons(20_000), 0, 11.0);
        assert_eq!(tracer.next(&plan, &range, &[&first, &second]), None);
    }
}
