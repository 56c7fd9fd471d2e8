//! What each idea of the visibility network earns: the path from the paper's network to the
//! default one idea at a time, and the default with one idea taken out at a time. `flatland
//! results` runs both on the bundled scenes and on random rooms (docs/ALGORITHM.md §4).

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

use flatland_geom::Kernel;
use flatland_solve::Reference;
use kernel_fit::{Fit, FitError, FitParams, FitSummary, Gating, Target};
use serde::{Deserialize, Serialize};

/// One configuration of the learner.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Variant {
    /// A short name for tables.
    pub name: &'static str,
    /// The parameters (cells and seed are set per run).
    pub params: FitParams,
}

/// From the paper's network to the visibility network, adding one idea at a time; the last
/// variant is [`FitParams::default`].
pub fn path() -> Vec<Variant> {
    let paper = FitParams::paper();
    let mut p = FitParams {
        refit: false,
        ..paper
    };
    let mut out = vec![Variant {
        name: "paper's network (no refit)",
        params: p,
    }];
    out.push(Variant {
        name: "+ least-squares refit",
        params: paper,
    });
    let mut step = |name: &'static str, change: &dyn Fn(&mut FitParams)| {
        change(&mut p);
        out.push(Variant { name, params: p });
    };
    step("+ learn V only, ζ_unoccluded exact", &|p| {
        p.target = Target::Visibility;
    });
    step("+ importance sampling and weights", &|p| {
        p.importance = 0.7;
        p.weighted = true;
    });
    step("+ normalised output", &|p| {
        p.network.output_mode = sgcs::OutputMode::Normalized;
    });
    step("+ cells gated by pair", &|p| p.gating = Gating::Pairs);
    step("+ cells gated by face", &|p| p.gating = Gating::Faces);
    step("+ growth at the worst sample, local rule", &|p| {
        p.network.insertion = sgcs::Insertion::WorstSample;
        p.network.insert_rule = sgcs::InsertRule::SampleTarget;
        p.network.output_rule = sgcs::OutputRule::Local;
    });
    step("+ error-sum resource", &|p| {
        p.network.resource = sgcs::Resource::ErrorSum;
    });
    step("+ φ = 0.01 (the default)", &|p| p.phi = 0.01);
    out
}

/// The visibility network, then the default with one idea taken out at a time.
pub fn leave_one_out() -> Vec<Variant> {
    let d = FitParams::default();
    let without = |name: &'static str, change: &dyn Fn(&mut FitParams)| {
        let mut params = d;
        change(&mut params);
        Variant { name, params }
    };
    vec![
        Variant {
            name: "visibility",
            params: d,
        },
        without("− gating by face (by pair only)", &|p| {
            p.gating = Gating::Pairs
        }),
        without("− gating", &|p| p.gating = Gating::Off),
        without("− importance sampling", &|p| p.importance = 0.0),
        without("− error weights", &|p| p.weighted = false),
        without("− normalised output", &|p| {
            p.network.output_mode = sgcs::OutputMode::Sum;
        }),
        without("− local rule (NLMS)", &|p| {
            p.network.output_rule = sgcs::OutputRule::Normalized;
        }),
        without("− growth at the worst sample", &|p| {
            p.network.insertion = sgcs::Insertion::Midpoint;
            p.network.insert_rule = sgcs::InsertRule::PreserveOutput;
        }),
        without("− error-sum resource", &|p| {
            p.network.resource = sgcs::Resource::MeanTimesVolume;
        }),
        without("− φ = 0.01 (φ = 1)", &|p| p.phi = 1.0),
    ]
}

/// A variant's figures on one scene, averaged over seeds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariantRow {
    /// [`Variant::name`].
    pub variant: String,
    /// Mean relative L2 on the grid.
    pub grid: f64,
    /// Mean relative L2 held out.
    pub heldout: f64,
    /// Mean relative L1 on the grid.
    pub l1_grid: f64,
    /// Mean cells at the end.
    pub cells: f64,
    /// Mean rays.
    pub rays: f64,
    /// Mean wall time of a fit, seconds.
    pub wall_s: f64,
}

/// Runs every variant at `cells` cells with seeds `1..=seeds` on `kernel`, errors against
/// `reference`. `stop()` is polled between fits (Ctrl-C); an interrupted run returns
/// [`FitError::Interrupted`].
pub fn run_variants(
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    variants: &[Variant],
    cells: usize,
    seeds: u64,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Vec<VariantRow>, FitError> {
    let mut rows = Vec::with_capacity(variants.len());
    for variant in variants {
        let mut runs: Vec<(FitSummary, f64)> = Vec::new();
        for seed in 1..=seeds {
            if stop() {
                return Err(FitError::Interrupted);
            }
            let params = FitParams {
                target_cells: cells,
                seed,
                eval_every: 0,
                ..variant.params
            };
            let started = Instant::now();
            let mut fit = Fit::new(Arc::clone(kernel), Arc::clone(reference), params)?;
            let summary = fit.run(10_000, |_| {
                if stop() {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            })?;
            runs.push((summary, started.elapsed().as_secs_f64()));
        }
        let mean = |f: &dyn Fn(&(FitSummary, f64)) -> f64| {
            runs.iter().map(f).sum::<f64>() / runs.len() as f64
        };
        rows.push(VariantRow {
            variant: variant.name.to_owned(),
            grid: mean(&|r| r.0.errors.grid),
            heldout: mean(&|r| r.0.errors.heldout),
            l1_grid: mean(&|r| r.0.errors.l1_grid),
            cells: mean(&|r| r.0.cells as f64),
            rays: mean(&|r| r.0.rays as f64),
            wall_s: mean(&|r| r.1),
        });
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_path_ends_at_the_default_and_leaving_out_changes_one_thing() {
        let path = path();
        assert_eq!(path.last().unwrap().params, FitParams::default());
        assert_eq!(path[0].params.target, Target::Zeta);
        for v in path.iter().chain(&leave_one_out()) {
            v.params.validate().unwrap();
        }
        let loo = leave_one_out();
        assert_eq!(loo[0].params, FitParams::default());
        for v in &loo[1..] {
            assert_ne!(v.params, FitParams::default(), "{}", v.name);
        }
    }
}
