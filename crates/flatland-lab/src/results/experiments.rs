//! The experiments behind RESULTS.md. Each returns data; [`super::render`] turns it into the
//! document. Nothing here formats text.

use std::sync::Arc;
use std::time::Instant;

use crate::ablation::{self, VariantRow};
use anyhow::Result;
use flatland_baselines::{HrParams, Oracle, count_initial_links, run_hr_at_budget};
use flatland_geom::Kernel;
use flatland_solve::{
    Errors, ExactReference, Reference, SolveErrors, density_ratio, discontinuity_mask,
};
use kernel_fit::{Fit, FitParams, FitSummary, Preset, Resampling};

use crate::timed::{Method, Scorer, TimedPlan, TimedRow, run_timed};
use crate::{Defined, interrupt};

/// The reference grid's resolution.
pub const RES: usize = 256;

/// The budget the paper's R4 and the acceptance are stated at.
pub const HEADLINE_BUDGET: usize = 400;

/// Elements of the radiosity solves in the benches.
pub const SOLVE_ELEMENTS: usize = 256;

/// The reference of every experiment: the one `flatland fit` builds (same grid, same held-out
/// points), so the documented command prints the number the document reports.
pub fn reference_of(kernel: &Kernel) -> Reference {
    crate::reference(kernel, RES, &FitParams::default())
}

/// A finished fit: its summary, its cells' re-projected (s, t) and the fit itself.
pub struct Fitted {
    pub summary: FitSummary,
    pub cells: Vec<[f64; 2]>,
    pub fit: Fit,
}

/// Fits `params` to `kernel`, stopping promptly on Ctrl-C.
pub fn fit(kernel: &Arc<Kernel>, reference: &Arc<Reference>, params: FitParams) -> Result<Fitted> {
    let mut fit = Fit::new(Arc::clone(kernel), Arc::clone(reference), params)?;
    let summary = interrupt::train_to_end(&mut fit)?;
    let cells = fit.cell_st().into_iter().flatten().collect();
    Ok(Fitted {
        summary,
        cells,
        fit,
    })
}

/// The parameters of `preset` with `seed`.
pub fn preset_params(preset: Preset, seed: u64) -> FitParams {
    FitParams {
        seed,
        ..preset.params()
    }
}

/// R1: cells per unit area near the kernel's jumps over cells per unit area elsewhere.
pub struct Density {
    /// Share of the (s, t) square counted as "near a jump".
    pub near_area: f64,
    /// (preset, resampling, ratio); `None` where a fit has no cell on one side.
    pub rows: Vec<(Preset, Resampling, Option<f64>)>,
}

/// R1 on `kernel` for every preset, θ against uniform resampling.
pub fn density(kernel: &Arc<Kernel>, reference: &Arc<Reference>) -> Result<Density> {
    let grid = reference.grid();
    let mut sorted = grid.to_vec();
    sorted.sort_by(f64::total_cmp);
    let mask = discontinuity_mask(grid, RES, 0.1 * sorted[sorted.len() * 99 / 100], 4);
    let near_area = mask.iter().filter(|m| **m).count() as f64 / mask.len() as f64;
    let mut rows = Vec::new();
    for preset in Preset::ALL {
        for resampling in [Resampling::Theta, Resampling::Uniform] {
            let params = FitParams {
                resampling,
                ..preset.params()
            };
            let fitted = fit(kernel, reference, params)?;
            rows.push((preset, resampling, density_ratio(&mask, RES, &fitted.cells)));
        }
    }
    Ok(Density { near_area, rows })
}

/// R2 and R3: a scene against the same scene with every edge split in `parts`.
pub struct Subdivision {
    pub parts: usize,
    pub fine_edges: usize,
    /// Seconds to build the fine scene's kernel (its visibility structures).
    pub fine_build_s: f64,
    /// (preset, coarse fit, fine fit).
    pub fits: Vec<(Preset, FitSummary, FitSummary)>,
    /// HR's initial links on the coarse and the fine scene.
    pub links: (u64, u64),
}

/// R2 and R3 on `kernel`.
pub fn subdivision(
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    parts: usize,
) -> Result<Subdivision> {
    let fine_scene = kernel.scene().subdivide(parts)?;
    let fine_edges = fine_scene.edges().len();
    let started = Instant::now();
    let fine = Arc::new(Kernel::new(fine_scene));
    let fine_build_s = started.elapsed().as_secs_f64();
    let fine_reference = Arc::new(reference_of(&fine));
    let mut fits = Vec::new();
    for preset in Preset::ALL {
        let coarse = fit(kernel, reference, preset.params())?.summary;
        let split = fit(&fine, &fine_reference, preset.params())?.summary;
        fits.push((preset, coarse, split));
    }
    Ok(Subdivision {
        parts,
        fine_edges,
        fine_build_s,
        fits,
        links: (count_initial_links(kernel), count_initial_links(&fine)),
    })
}

/// θ against uniform resampling: mean held-out relative L2 over seeds.
pub struct ThetaRow {
    pub scene: String,
    pub preset: Preset,
    pub theta: f64,
    pub uniform: f64,
}

/// θ against uniform resampling on one scene, for every preset.
pub fn theta_against_uniform(
    name: &str,
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    seeds: u64,
) -> Result<Vec<ThetaRow>> {
    let mut rows = Vec::new();
    for preset in Preset::ALL {
        let (mut theta, mut uniform) = (0.0, 0.0);
        for seed in 1..=seeds {
            let params = preset_params(preset, seed);
            theta += fit(kernel, reference, params)?.summary.errors.heldout;
            let params = FitParams {
                resampling: Resampling::Uniform,
                ..params
            };
            uniform += fit(kernel, reference, params)?.summary.errors.heldout;
        }
        rows.push(ThetaRow {
            scene: name.to_owned(),
            preset,
            theta: theta / seeds as f64,
            uniform: uniform / seeds as f64,
        });
    }
    Ok(rows)
}

/// The ablation on one scene: HR at the same budget, the path from the paper's network to the
/// default, and the default with each idea taken out.
pub struct Ablation {
    pub scene: String,
    pub hr: Errors,
    pub path: Vec<VariantRow>,
    pub leave_one_out: Vec<VariantRow>,
}

/// The ablation at [`HEADLINE_BUDGET`] cells on one scene.
pub fn ablation(
    name: &str,
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    seeds: u64,
) -> Result<Ablation> {
    let stop = || interrupt::requested();
    let hr = run_hr_at_budget(kernel, HEADLINE_BUDGET, 1, &HrParams::default())?;
    let rows = |variants: Vec<ablation::Variant>| {
        ablation::run_variants(kernel, reference, &variants, HEADLINE_BUDGET, seeds, &stop)
    };
    let path = rows(ablation::path());
    interrupt::check()?;
    let leave_one_out = rows(ablation::leave_one_out());
    interrupt::check()?;
    Ok(Ablation {
        scene: name.to_owned(),
        hr: reference.errors(&hr.approx),
        path: path?,
        leave_one_out: leave_one_out?,
    })
}

/// Every method at every budget on one scene (R4, the time–error curves, the solved radiosity).
pub struct SceneBench {
    pub scene: String,
    pub defined: Defined,
    /// The rows of the R4 plan ([`plan`]).
    pub rows: Vec<TimedRow>,
    /// HR with the plain form-factor oracle at [`HEADLINE_BUDGET`]: (links, errors).
    pub hr_form_factor: Option<(usize, Errors)>,
    /// The radiosity solved with exact 20 × 20 block means of k (no rays; the best
    /// piecewise-constant kernel at 400 blocks): the floor a learned kernel must halve.
    pub exact_blocks: Option<SolveErrors>,
}

/// What the R4 rows of `kernel` are scored against: the radiosity solved on
/// [`SOLVE_ELEMENTS`] against the exact solve on four times as many (2048 at least), ζ on
/// `reference`.
fn scorer(kernel: &Arc<Kernel>, reference: &Arc<Reference>) -> Result<Scorer> {
    let reference_elements = ExactReference::default_elements_for(kernel, SOLVE_ELEMENTS);
    Scorer::new(
        kernel,
        SOLVE_ELEMENTS,
        reference_elements,
        Arc::clone(reference),
        &interrupt::requested,
    )
}

/// The solve errors of exact `g × g` block means of k at [`HEADLINE_BUDGET`] blocks.
fn exact_blocks(kernel: &Arc<Kernel>, scorer: &Scorer) -> Result<Option<SolveErrors>> {
    let mut plan = plan(vec![HEADLINE_BUDGET], 1);
    plan.methods = vec![Method::UniformExact];
    let rows = run_timed(kernel, scorer, &plan, &interrupt::requested, |_| Ok(()))?;
    Ok(rows.first().and_then(|r| r.solve))
}

/// The plan every scene is benched with: the R4 table at `budgets`.
pub fn plan(budgets: Vec<usize>, seeds: u64) -> TimedPlan {
    TimedPlan::r4(budgets, seeds)
}

/// `plan` on one scene; `kept` sees the rows after each row (to write them).
pub fn bench(
    name: &str,
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    plan: &TimedPlan,
    kept: impl FnMut(&[TimedRow]) -> Result<()>,
) -> Result<SceneBench> {
    let scorer = scorer(kernel, reference)?;
    let rows = run_timed(kernel, &scorer, plan, &interrupt::requested, kept)?;
    let form_factor = HrParams {
        oracle: Oracle::FormFactor,
        ..HrParams::default()
    };
    let ff = run_hr_at_budget(kernel, HEADLINE_BUDGET, 1, &form_factor)?;
    Ok(SceneBench {
        scene: name.to_owned(),
        defined: Defined::of(reference),
        rows,
        hr_form_factor: Some((ff.basis_functions, reference.errors(&ff.approx))),
        exact_blocks: exact_blocks(kernel, &scorer)?,
    })
}

/// Random rooms the project was never tuned on: every method at [`HEADLINE_BUDGET`], one seed.
pub fn room(seed: u64) -> Result<SceneBench> {
    let kernel = Arc::new(Kernel::new(crate::rooms::random_room(seed)?));
    let reference = Arc::new(reference_of(&kernel));
    let scorer = scorer(&kernel, &reference)?;
    let plan = plan(vec![HEADLINE_BUDGET], 1);
    let rows = run_timed(&kernel, &scorer, &plan, &interrupt::requested, |_| Ok(()))?;
    interrupt::check()?;
    Ok(SceneBench {
        scene: format!("room {seed}"),
        defined: Defined::of(&reference),
        rows,
        hr_form_factor: None,
        exact_blocks: exact_blocks(&kernel, &scorer)?,
    })
}

/// The stress suite's report and exit code, run as a separate process (a crash there must not
/// take the document with it).
pub fn stress(quick: bool) -> Result<(String, Option<i32>)> {
    use anyhow::Context as _;
    let exe = std::env::current_exe().context("locating this program to run the stress suite")?;
    let mut cmd = std::process::Command::new(exe);
    cmd.arg("stress");
    if quick {
        cmd.arg("--quick");
    }
    let output = cmd.output().context("running the stress suite")?;
    Ok((
        String::from_utf8_lossy(&output.stdout).into_owned(),
        output.status.code(),
    ))
}
