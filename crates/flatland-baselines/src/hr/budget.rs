//! The parameter rule: F_ε (and, where F_ε alone jumps, the minimum length) by bisection so the
//! link count lands on a budget, found without rays; and the note when it cannot.

use super::HrParams;
use super::elements::Surfaces;
use super::linking::InitialLinks;
use super::refine::count_links;
use crate::{BaselineError, BudgetNote, budget_tolerance};
use flatland_geom::Kernel;

/// Above every form factor (at most 1 between two segments that do not cross): no link is
/// refined, so the count is the initial linking's.
const COARSEST_F_EPS: f64 = 1.5;

/// Where the bisection stops looking: below it every element pair that still interacts is at
/// the minimum length.
const FINEST_F_EPS: f64 = 1e-12;

/// How many times [`hr_params_for_budget`] doubles the minimum length.
const MIN_LENGTH_DOUBLINGS: u32 = 6;

/// The F_ε whose link count is closest to `budget`, and that count (bisection on log F_ε; the
/// count is monotone in F_ε because a smaller threshold only refines further). When even the
/// initial linking exceeds `budget`, that is the answer (F_ε above every form factor).
pub fn f_eps_for_budget(
    kernel: &Kernel,
    budget: usize,
    params: &HrParams,
) -> Result<(f64, usize), BaselineError> {
    params.check()?;
    check_budget(budget, params)?;
    let surfaces = Surfaces::new(kernel);
    let initial = InitialLinks::within(&surfaces, params.max_links)?;
    let found = search_f_eps(&surfaces, &initial, budget, params)?;
    Ok((found.params.f_eps, found.count))
}

/// `params` with F_ε and the minimum length chosen so the link count is as close to `budget` as
/// HR can get, and that count.
///
/// Why both: F_ε alone moves the count in jumps. Two elements meeting at a corner have a form
/// factor that does not shrink when both are halved (≈ 0.29 for a right angle), so once F_ε
/// drops below it every corner refines down to the minimum length at once — on a symmetric room
/// that is a jump of over a hundred links. So F_ε is searched ([`f_eps_for_budget`]) for the
/// minimum lengths `params.min_length · 2^k`, `k = 0..=6` (while below 1), finest first, and the
/// first within [`budget_tolerance`] (5 %) of `budget` wins: a finer minimum length resolves the
/// `1/r` corners, which dominate the L2 error (measured on `fig3`, `maze`, `corners`: the finest
/// candidate within tolerance was best or within 10 % of best). If none is within it, the
/// closest count wins ([`run_hr_at_budget`](crate::run_hr_at_budget) then says so in its note).
pub fn hr_params_for_budget(
    kernel: &Kernel,
    budget: usize,
    params: &HrParams,
) -> Result<(HrParams, usize), BaselineError> {
    params.check()?;
    check_budget(budget, params)?;
    let surfaces = Surfaces::new(kernel);
    let initial = InitialLinks::within(&surfaces, params.max_links)?;
    let found = tune(&surfaces, &initial, budget, params)?;
    Ok((found.params, found.count))
}

/// A budget HR can be asked for: at least one link, at most `max_links`.
pub(super) fn check_budget(budget: usize, params: &HrParams) -> Result<(), BaselineError> {
    if budget == 0 {
        return Err(BaselineError::InvalidParameter {
            name: "budget",
            value: budget.to_string(),
            valid: "at least 1 link",
        });
    }
    if budget > params.max_links {
        return Err(BaselineError::BudgetAboveMaxLinks {
            budget,
            max_links: params.max_links,
        });
    }
    Ok(())
}

/// What a search found: the settings, their link count, and whether that count is the most
/// the settings' minimum length allows (F_ε down to the search's floor never passed the budget).
#[derive(Clone, Copy, Debug)]
pub(super) struct Found {
    pub(super) params: HrParams,
    pub(super) count: usize,
    pub(super) finest: bool,
}

/// [`hr_params_for_budget`] on surfaces and initial links already made.
pub(super) fn tune(
    surfaces: &Surfaces,
    initial: &InitialLinks,
    budget: usize,
    params: &HrParams,
) -> Result<Found, BaselineError> {
    let tolerance = budget_tolerance(budget);
    let mut best: Option<Found> = None;
    for k in 0..=MIN_LENGTH_DOUBLINGS {
        let min_length = params.min_length * f64::from(1u32 << k);
        if min_length >= 1.0 {
            break;
        }
        let candidate = HrParams {
            min_length,
            ..*params
        };
        let found = search_f_eps(surfaces, initial, budget, &candidate)?;
        let count = found.count;
        if best.is_none_or(|b| count.abs_diff(budget) < b.count.abs_diff(budget)) {
            best = Some(found);
        }
        // A coarser minimum length only lowers the most HR can build.
        if count.abs_diff(budget) <= tolerance || found.finest {
            break;
        }
    }
    Ok(best.expect("the first minimum length is below 1 (checked)"))
}

/// The bisection of [`f_eps_for_budget`], on log F_ε from [`COARSEST_F_EPS`] down to
/// [`FINEST_F_EPS`].
fn search_f_eps(
    surfaces: &Surfaces,
    initial: &InitialLinks,
    budget: usize,
    params: &HrParams,
) -> Result<Found, BaselineError> {
    let count =
        |f_eps: f64, cap| count_links(surfaces, initial, &HrParams { f_eps, ..*params }, cap);
    let too_many = |f_eps| BaselineError::RefinementTooLarge {
        f_eps,
        max_links: params.max_links,
    };
    let mut hi = COARSEST_F_EPS;
    let hi_count = count(hi, params.max_links).ok_or_else(|| too_many(hi))?;
    let found = |f_eps, count, finest| Found {
        params: HrParams { f_eps, ..*params },
        count,
        finest,
    };
    if hi_count >= budget {
        return Ok(found(hi, hi_count, false));
    }
    // Counts past 8 × budget cannot be the closest (the coarsest is nearer): stop counting there.
    let cap = budget.saturating_mul(8).max(64).min(params.max_links);
    let (mut best, mut best_count) = (hi, hi_count);
    let mut lo = FINEST_F_EPS;
    for _ in 0..80 {
        let mid = (lo * hi).sqrt();
        match count(mid, cap) {
            Some(c) => {
                if c.abs_diff(budget) < best_count.abs_diff(budget)
                    || (c.abs_diff(budget) == best_count.abs_diff(budget) && c < best_count)
                {
                    (best, best_count) = (mid, c);
                }
                if c == budget {
                    break;
                }
                if c > budget { lo = mid } else { hi = mid }
            }
            None => lo = mid,
        }
        if hi / lo < 1.0 + 1e-9 {
            break;
        }
    }
    // No count past the budget was ever seen: the count is as high as this minimum length goes.
    let finest = lo == FINEST_F_EPS && best_count < budget;
    Ok(found(best, best_count, finest))
}

/// What a build of `found` says about `budget`: nothing within tolerance; otherwise whether the
/// initial linking was the floor, the finest refinement the ceiling, or the count jumped past.
pub(super) fn note(budget: usize, initial_links: usize, found: &Found) -> Option<BudgetNote> {
    let (asked, built) = (budget, found.count);
    if built.abs_diff(budget) <= budget_tolerance(budget) {
        None
    } else if initial_links > budget {
        Some(BudgetNote::InitialLinking { asked, built })
    } else if found.finest {
        Some(BudgetNote::Finest { asked, built })
    } else {
        Some(BudgetNote::Nearest { asked, built })
    }
}

#[cfg(test)]
mod tests {
    use super::super::refine::count_links;
    use super::*;
    use crate::run_hr;
    use crate::test_support::blocker_kernel;

    #[test]
    fn budget_search_lands_near_the_target() {
        let kernel = blocker_kernel();
        let params = HrParams::default();
        for budget in [50, 200, 400, 800] {
            let (tuned, count) = hr_params_for_budget(&kernel, budget, &params).unwrap();
            let run = run_hr(&kernel, &tuned, 1).unwrap();
            assert_eq!(run.basis_functions, count);
            // The box is symmetric: counts move in steps of 8 (4 corners, both directions).
            assert!(
                count.abs_diff(budget) <= budget * 3 / 20,
                "budget {budget}: {count} links, {tuned:?}"
            );
            let again = crate::run_hr_at_budget(&kernel, budget, 1, &params).unwrap();
            assert_eq!(again.approx.links(), run.approx.links());
            // With the minimum length fixed the count is monotone in F_eps.
            let (f_eps, fixed) = f_eps_for_budget(&kernel, budget, &params).unwrap();
            let surfaces = Surfaces::new(&kernel);
            let initial = InitialLinks::within(&surfaces, usize::MAX).unwrap();
            let finer = count_links(
                &surfaces,
                &initial,
                &HrParams {
                    f_eps: f_eps * 0.5,
                    ..params
                },
                usize::MAX,
            );
            assert!(finer.unwrap() >= fixed);
        }
        // Below the initial linking the initial links are the answer.
        let (_, count) = hr_params_for_budget(&kernel, 3, &params).unwrap();
        assert_eq!(count, 12);
    }
}
