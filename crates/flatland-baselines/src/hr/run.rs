//! What `flatland bench` and `flatland solve` call: HR at a given F_ε, or at a budget of links
//! with a note when the count built is not the count asked for.

use super::HrParams;
use super::budget::{check_budget, note, tune};
use super::elements::Surfaces;
use super::linking::InitialLinks;
use super::tree::HierarchicalRadiosity;
use crate::{BaselineError, BaselineRun};
use flatland_geom::Kernel;
use std::time::Instant;

/// HR at `params.f_eps`. Refuses, naming `max_links` and what HR needs, a scene whose initial
/// linking alone exceeds `params.max_links` (counted before anything per link is built), or a
/// refinement that goes past it.
pub fn run_hr(
    kernel: &Kernel,
    params: &HrParams,
    seed: u64,
) -> Result<BaselineRun<HierarchicalRadiosity>, BaselineError> {
    let start = Instant::now();
    let hr = HierarchicalRadiosity::build(kernel, params, seed)?;
    let wall = start.elapsed();
    let rays = hr.stats().rays;
    Ok(BaselineRun::new(hr, rays, wall, None))
}

/// HR at about `budget` links: the settings of
/// [`hr_params_for_budget`](crate::hr_params_for_budget), then [`run_hr`]. Any budget from 1 to
/// `params.max_links` is served; [`BaselineRun::note`] says when the count built is outside
/// [`budget_tolerance`](crate::budget_tolerance) of it — below HR's initial linking (the least
/// HR can build: that is built), above its finest refinement at the minimum length (the most
/// it can build: that is built), or where the count jumps past the budget (the nearest is
/// built). The search casts no ray and is not part of the reported wall time; the chosen F_ε
/// and minimum length are in `run.approx.stats()`.
pub fn run_hr_at_budget(
    kernel: &Kernel,
    budget: usize,
    seed: u64,
    params: &HrParams,
) -> Result<BaselineRun<HierarchicalRadiosity>, BaselineError> {
    params.check()?;
    check_budget(budget, params)?;
    let surfaces = Surfaces::new(kernel);
    let initial = InitialLinks::within(&surfaces, params.max_links)?;
    let found = tune(&surfaces, &initial, budget, params)?;
    let mut run = run_hr(kernel, &found.params, seed)?;
    debug_assert_eq!(run.basis_functions, found.count);
    run.note = note(budget, initial.len(), &found);
    Ok(run)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BudgetNote;
    use crate::test_support::box_kernel;

    #[test]
    fn oversized_linking_is_refused_and_bad_params_named() {
        let kernel = box_kernel();
        let err = run_hr(
            &kernel,
            &HrParams {
                max_links: 5,
                ..HrParams::default()
            },
            1,
        )
        .unwrap_err();
        assert!(err.to_string().contains("max_links"), "{err}");
        for (params, name) in [
            (
                HrParams {
                    f_eps: 0.0,
                    ..HrParams::default()
                },
                "f_eps",
            ),
            (
                HrParams {
                    f_eps: f64::NAN,
                    ..HrParams::default()
                },
                "f_eps",
            ),
            (
                HrParams {
                    min_length: 1.0,
                    ..HrParams::default()
                },
                "min_length",
            ),
            (
                HrParams {
                    rays_per_link: 0,
                    ..HrParams::default()
                },
                "rays_per_link",
            ),
        ] {
            let err = HierarchicalRadiosity::build(&kernel, &params, 1).unwrap_err();
            assert!(err.to_string().contains(name), "{err}");
        }
    }

    #[test]
    fn the_messages_name_the_real_limit_and_what_to_do() {
        let kernel = box_kernel(); // 4 walls, 12 initial links
        let small = HrParams {
            max_links: 5,
            ..HrParams::default()
        };
        let err = run_hr(&kernel, &small, 1).unwrap_err().to_string();
        assert_eq!(
            err,
            "HR's initial linking needs 12 links (one per ordered pair of the scene's 4 \
             surface edges that face each other), more than `max_links` = 5: raise `max_links` \
             or use a scene with fewer surface edges"
        );
        let fine = HrParams {
            f_eps: 1e-6,
            max_links: 100,
            ..HrParams::default()
        };
        let err = run_hr(&kernel, &fine, 1).unwrap_err().to_string();
        assert_eq!(
            err,
            "HR at F_ε = 0.000001 refines past `max_links` = 100 links: raise F_ε (fewer \
             links) or `max_links`"
        );
        let err = run_hr_at_budget(&kernel, 200, 1, &fine)
            .unwrap_err()
            .to_string();
        assert_eq!(
            err,
            "a budget of 200 links is more than `max_links` = 100: ask for at most 100 \
             links or raise `max_links`"
        );
        let err = run_hr_at_budget(&kernel, 0, 1, &HrParams::default()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "parameter `budget` is 0, but must be at least 1 link"
        );
        let note = BudgetNote::InitialLinking {
            asked: 400,
            built: 25_600,
        };
        assert_eq!(
            note.to_string(),
            "HR's initial linking needs 25 600 links; built that instead of 400"
        );
        let note = BudgetNote::Nearest {
            asked: 1000,
            built: 1_200,
        };
        assert_eq!(
            note.to_string(),
            "HR's link count jumps past 1 000 (no F_ε or minimum length gives 950–1 050 links); \
             built the nearest, 1 200"
        );
    }

    #[test]
    fn budgets_on_the_box_say_when_they_are_not_met() {
        let kernel = box_kernel();
        let params = HrParams::default();
        let below = run_hr_at_budget(&kernel, 5, 1, &params).unwrap();
        assert_eq!(below.basis_functions, 12);
        assert_eq!(
            below.note,
            Some(BudgetNote::InitialLinking {
                asked: 5,
                built: 12
            })
        );
        let at = run_hr_at_budget(&kernel, 12, 1, &params).unwrap();
        assert_eq!((at.basis_functions, at.note), (12, None));
        // The box's counts move in steps of 2 and 4 here: 17 ± 1 is not among them.
        let between = run_hr_at_budget(&kernel, 17, 1, &params).unwrap();
        let note = BudgetNote::Nearest {
            asked: 17,
            built: 15,
        };
        assert_eq!((between.basis_functions, between.note), (15, Some(note)));
    }

    #[test]
    fn a_floor_plan_gets_its_floor_its_budget_and_its_ceiling() {
        // 152 surface edges, thick walls as boxes: the initial linking alone is thousands.
        let kernel = Kernel::new(flatland_geom::generate::floor_plan(200, 1).unwrap());
        let params = HrParams::default();
        let initial = crate::count_initial_links(&kernel) as usize;
        assert!(initial > 4000, "{initial} initial links");

        let below = run_hr_at_budget(&kernel, 400, 1, &params).unwrap();
        assert_eq!(below.basis_functions, initial);
        assert_eq!(
            below.note,
            Some(BudgetNote::InitialLinking {
                asked: 400,
                built: initial
            })
        );
        assert_eq!(
            below.note.unwrap().to_string(),
            format!(
                "HR's initial linking needs {} links; built that instead of 400",
                crate::grouped(initial)
            )
        );

        let at = run_hr_at_budget(&kernel, initial, 1, &params).unwrap();
        assert_eq!((at.basis_functions, at.note), (initial, None));

        for budget in [2 * initial, 5 * initial] {
            let above = run_hr_at_budget(&kernel, budget, 1, &params).unwrap();
            assert!(
                above.basis_functions.abs_diff(budget) <= crate::budget_tolerance(budget),
                "budget {budget}: {} links",
                above.basis_functions
            );
            assert_eq!(above.note, None, "budget {budget}");
        }

        // Past every element at the minimum length HR can refine no further: that is built.
        let budget = 400_000;
        let ceiling = run_hr_at_budget(&kernel, budget, 1, &params).unwrap();
        let built = ceiling.basis_functions;
        assert!(built > 10 * initial && built < budget, "{built} links");
        assert_eq!(
            ceiling.note,
            Some(BudgetNote::Finest {
                asked: budget,
                built
            })
        );
        let (_, finer) = crate::f_eps_for_budget(&kernel, budget, &params).unwrap();
        assert_eq!(finer, built);
    }
}
