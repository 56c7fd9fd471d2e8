//! What `flatland bench` and `flatland solve` call: clustered HR at a budget of links, with a
//! note when it could not refine that far.

use super::{ClusteredParams, ClusteredRadiosity};
use crate::{BaselineError, BaselineRun, BudgetNote, budget_tolerance};
use flatland_geom::Kernel;
use std::time::Instant;

/// Clustered HR at `budget` links. Any budget from 1 to `params.max_links` is served: the
/// refinement stops at the budget (or up to 3 links past it, where a cluster's link with itself
/// splits into four), or below it when every link is at the minimum length or certain, which
/// [`BaselineRun::note`] then says.
pub fn run_clustered(
    kernel: &Kernel,
    budget: usize,
    seed: u64,
    params: &ClusteredParams,
) -> Result<BaselineRun<ClusteredRadiosity>, BaselineError> {
    let start = Instant::now();
    let built = ClusteredRadiosity::build(kernel, budget, params, seed)?;
    let wall = start.elapsed();
    let stats = *built.stats();
    let note =
        (stats.links + budget_tolerance(budget) < budget).then_some(BudgetNote::ClusteredFinest {
            asked: budget,
            built: stats.links,
        });
    Ok(BaselineRun::new(built, stats.rays, wall, note))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::box_kernel;

    #[test]
    fn a_budget_past_the_finest_linking_says_so() {
        let kernel = box_kernel();
        let params = ClusteredParams {
            min_length: 0.5, // walls halve once at most
            ..ClusteredParams::default()
        };
        let run = run_clustered(&kernel, 10_000, 1, &params).unwrap();
        let built = run.basis_functions;
        assert!(built < 1000 && run.approx.stats().finest, "{built}");
        assert_eq!(
            run.note,
            Some(BudgetNote::ClusteredFinest {
                asked: 10_000,
                built
            })
        );
        assert!(run.note.unwrap().to_string().contains("min_length"));
        let fits = run_clustered(&kernel, 20, 1, &params).unwrap();
        assert_eq!(fits.note, None);
        assert!(fits.basis_functions.abs_diff(20) <= 3);
        let err = run_clustered(&kernel, 0, 1, &params).unwrap_err();
        assert!(err.to_string().contains("budget"), "{err}");
    }
}
