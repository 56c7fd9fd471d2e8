//! Run time against error: every method at every budget (number of basis functions), on the
//! same kernel, target and error measure, several seeds where random.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Instant;

use flatland_baselines::{BaselineRun, HrParams, UniformParams, run_hr_at_budget, run_uniform};
use flatland_geom::Kernel;
use flatland_solve::{
    Errors, ExactReference, Mesh, Reference, Representation, SolveErrors, SolveParams, never,
    solve_against,
};
use serde::{Deserialize, Serialize};

use kernel_fit::{Fit, FitParams};

use crate::LabError;
pub use flatland_methods::Method;

/// The methods the R4 table compares: the two networks and the baselines at a budget.
pub const METHODS: [Method; 5] = [
    Method::Visibility,
    Method::Paper,
    Method::PaperNorefit,
    Method::Hr,
    Method::Uniform,
];

/// The error of a method the table does not run.
fn not_in_table(method: Method) -> LabError {
    LabError::InvalidParameter {
        name: "methods",
        value: method.name().to_owned(),
        valid: "visibility, paper, paper-norefit, hr or uniform",
    }
}

/// One method at one budget and seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchRow {
    /// The method.
    pub method: Method,
    /// The budget asked for (basis functions).
    pub budget: usize,
    /// The seed.
    pub seed: u64,
    /// Basis functions actually used (HR and uniform land near, not on, the budget).
    pub basis_functions: usize,
    /// Relative L2 errors against the reference.
    pub errors: Errors,
    /// Rays (exact kernel evaluations) spent building the representation.
    pub rays: u64,
    /// Wall time to build it, seconds (errors excluded).
    pub wall_s: f64,
    /// Bytes of the representation.
    pub memory_bytes: usize,
    /// The radiosity solved with it against the exact kernel's, when the plan asks
    /// ([`BenchPlan::solve_elements`]).
    #[serde(default)]
    pub solve: Option<SolveErrors>,
    /// Wall time of that solve (operator and linear solve), seconds.
    #[serde(default)]
    pub solve_s: f64,
}

/// What to run.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchPlan {
    /// Methods, in the order rows are produced.
    pub methods: Vec<Method>,
    /// Budgets (basis functions).
    pub budgets: Vec<usize>,
    /// Seeds 1..=seeds.
    pub seeds: u64,
    /// The learner's parameters (target cells and seed are set per row).
    pub fit: FitParams,
    /// The paper network's parameters (target cells and seed are set per row).
    pub paper: FitParams,
    /// HR parameters (F_ε is searched per budget).
    pub hr: HrParams,
    /// Uniform-grid parameters.
    pub uniform: UniformParams,
    /// Solve the radiosity with every representation on this many elements and report the
    /// error of B against the exact kernel's (`None`: no solve).
    pub solve_elements: Option<usize>,
}

impl BenchPlan {
    /// A plan with every method's default parameters.
    pub fn new(methods: Vec<Method>, budgets: Vec<usize>, seeds: u64) -> BenchPlan {
        BenchPlan {
            methods,
            budgets,
            seeds,
            fit: FitParams::default(),
            paper: FitParams::paper(),
            hr: HrParams::default(),
            uniform: UniformParams::default(),
            solve_elements: None,
        }
    }

    /// Checks the plan; errors name the parameter and the valid range.
    pub fn validate(&self) -> Result<(), LabError> {
        let bad =
            |name, value: String, valid| Err(LabError::InvalidParameter { name, value, valid });
        if self.methods.is_empty() {
            return bad(
                "methods",
                "(none)".into(),
                "at least one of visibility, paper, paper-norefit, hr, uniform",
            );
        }
        if let Some(&m) = self.methods.iter().find(|m| !METHODS.contains(m)) {
            return Err(not_in_table(m));
        }
        if let Some(b) = self.budgets.iter().find(|&&b| b < 3) {
            return bad("budgets", b.to_string(), "each ≥ 3");
        }
        if self.budgets.is_empty() {
            return bad("budgets", "(none)".into(), "at least one budget ≥ 3");
        }
        if self.seeds == 0 {
            return bad("seeds", "0".into(), "≥ 1");
        }
        self.fit.validate()?;
        self.paper.validate()?;
        self.hr.check()?;
        self.uniform.check()?;
        Ok(())
    }
}

/// Runs the plan on one kernel; `progress(done, total)` after each row. The paper's network
/// with and without its refit come from one fit (the error before and after the refit), so
/// asking for both costs one fit; its wall time is the training time (plus the refit for
/// `paper`).
pub fn run_bench(
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    plan: &BenchPlan,
    mut progress: impl FnMut(usize, usize),
) -> Result<Vec<BenchRow>, LabError> {
    plan.validate()?;
    let total = plan.methods.len() * plan.budgets.len() * plan.seeds as usize;
    let mut rows = Vec::with_capacity(total);
    let solver = plan
        .solve_elements
        .map(|n| Solver::new(kernel, n))
        .transpose()?;
    for &budget in &plan.budgets {
        for seed in 1..=plan.seeds {
            let wants_paper = plan
                .methods
                .iter()
                .any(|m| matches!(m, Method::Paper | Method::PaperNorefit));
            let paper = if wants_paper {
                Some(paper_rows(
                    kernel,
                    reference,
                    &plan.paper,
                    budget,
                    seed,
                    solver.as_ref(),
                )?)
            } else {
                None
            };
            for &method in &plan.methods {
                let s = solver.as_ref();
                let row = match method {
                    Method::Visibility => {
                        learner_row(kernel, reference, &plan.fit, budget, seed, s)?
                    }
                    Method::Paper => paper.as_ref().map(|r| r.0.clone()).expect("fitted above"),
                    Method::PaperNorefit => {
                        paper.as_ref().map(|r| r.1.clone()).expect("fitted above")
                    }
                    Method::Hr => baseline_row(
                        method,
                        budget,
                        seed,
                        run_hr_at_budget(kernel, budget, seed, &plan.hr)?,
                        reference,
                        s,
                    )?,
                    Method::Uniform => baseline_row(
                        method,
                        budget,
                        seed,
                        run_uniform(kernel, budget, seed, &plan.uniform)?,
                        reference,
                        s,
                    )?,
                    other => return Err(not_in_table(other)),
                };
                rows.push(row);
                progress(rows.len(), total);
            }
        }
    }
    Ok(rows)
}

/// The radiosity solve every row is scored with: one mesh and the exact kernel's B on it.
pub(crate) struct Solver {
    mesh: Mesh,
    exact: Vec<f64>,
}

impl Solver {
    fn new(kernel: &Kernel, elements: usize) -> Result<Solver, LabError> {
        let mesh = Mesh::new(kernel, elements)?;
        let reference = ExactReference::new(
            kernel,
            ExactReference::default_elements(elements),
            &SolveParams::default(),
            &never,
        )?;
        let exact = reference.radiosity_on(&mesh, &never)?;
        Ok(Solver { mesh, exact })
    }

    /// The solver of `mesh` whose exact B (at its collocation points) is `exact`.
    pub(crate) fn of(mesh: Mesh, exact: Vec<f64>) -> Solver {
        Solver { mesh, exact }
    }

    /// The errors of B solved with `rep`, and the solve's wall time.
    fn score(&self, rep: &dyn Representation) -> Result<(SolveErrors, f64), LabError> {
        let started = Instant::now();
        let c = solve_against(
            rep,
            &self.mesh,
            &self.exact,
            &SolveParams::default(),
            &never,
        )?;
        Ok((c.errors, started.elapsed().as_secs_f64()))
    }
}

/// The row of `approx`, whose errors against the reference are `errors`.
#[allow(clippy::too_many_arguments)]
fn row(
    method: Method,
    budget: usize,
    seed: u64,
    approx: &impl Representation,
    errors: Errors,
    rays: u64,
    wall_s: f64,
    solver: Option<&Solver>,
) -> Result<BenchRow, LabError> {
    let (solve, solve_s) = match solver {
        Some(solver) => {
            let (errors, s) = solver.score(approx)?;
            (Some(errors), s)
        }
        None => (None, 0.0),
    };
    Ok(BenchRow {
        method,
        budget,
        seed,
        basis_functions: approx.basis_functions().unwrap_or_default(),
        errors,
        rays,
        wall_s,
        memory_bytes: approx.memory_bytes(),
        solve,
        solve_s,
    })
}

/// The row of a baseline run.
fn baseline_row<A: Representation>(
    method: Method,
    budget: usize,
    seed: u64,
    run: BaselineRun<A>,
    reference: &Reference,
    solver: Option<&Solver>,
) -> Result<BenchRow, LabError> {
    let wall_s = run.wall.as_secs_f64();
    let errors = reference.errors(&run.approx);
    row(
        method,
        budget,
        seed,
        &run.approx,
        errors,
        run.rays,
        wall_s,
        solver,
    )
}

/// The visibility network at `budget` cells (it may stop with fewer when it has converged).
pub(crate) fn learner_row(
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    fit: &FitParams,
    budget: usize,
    seed: u64,
    solver: Option<&Solver>,
) -> Result<BenchRow, LabError> {
    let mut learner = fitted(kernel, reference, fit, budget, seed)?;
    let summary = learner.finish()?;
    row(
        Method::Visibility,
        budget,
        seed,
        learner.model(),
        summary.errors,
        summary.rays,
        summary.wall_s,
        solver,
    )
}

/// One fit of the paper's network at `budget` cells, ended with its refit: the row after the
/// refit and the row before it.
pub(crate) fn paper_rows(
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    paper: &FitParams,
    budget: usize,
    seed: u64,
    solver: Option<&Solver>,
) -> Result<(BenchRow, BenchRow), LabError> {
    let paper = FitParams {
        refit: true,
        ..*paper
    };
    let mut fit = fitted(kernel, reference, &paper, budget, seed)?;
    let learned = fit.model().clone();
    let summary = fit.finish()?;
    let before = summary
        .errors_before_refit
        .expect("the paper's network ends with its refit");
    let train_s = summary.wall_s - summary.refit_s;
    let before = row(
        Method::PaperNorefit,
        budget,
        seed,
        &learned,
        before,
        summary.rays,
        train_s,
        solver,
    )?;
    let after = row(
        Method::Paper,
        budget,
        seed,
        fit.model(),
        summary.errors,
        summary.rays,
        summary.wall_s,
        solver,
    )?;
    Ok((after, before))
}

/// A fit of `params` at `budget` cells and `seed`, trained to its stop (not yet finished).
fn fitted(
    kernel: &Arc<Kernel>,
    reference: &Arc<Reference>,
    params: &FitParams,
    budget: usize,
    seed: u64,
) -> Result<Fit, LabError> {
    let params = FitParams {
        target_cells: budget,
        seed,
        eval_every: 0,
        ..*params
    };
    let mut fit = Fit::new(Arc::clone(kernel), Arc::clone(reference), params)?;
    fit.train(u64::MAX, |_| ControlFlow::Continue(()));
    Ok(fit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_method_reports_errors_that_recompute() {
        let scene = flatland_geom::bundled::scene("fig3").unwrap();
        let kernel = Arc::new(Kernel::new(scene));
        let reference = Arc::new(Reference::new(&kernel, 48, 512, 3));
        let mut plan = BenchPlan::new(METHODS.to_vec(), vec![30, 60], 2);
        plan.solve_elements = Some(64);
        let mut calls = 0;
        let rows = run_bench(&kernel, &reference, &plan, |done, total| {
            calls += 1;
            assert!(done <= total);
        })
        .unwrap();
        assert_eq!((rows.len(), calls), (20, 20));
        for r in &rows {
            assert!(
                r.errors.grid.is_finite() && r.errors.heldout.is_finite(),
                "{r:?}"
            );
            assert!(
                r.rays > 0 && r.basis_functions > 0 && r.memory_bytes > 0,
                "{r:?}"
            );
            let solve = r.solve.expect("the plan asks for a solve");
            assert!(
                solve.rel_l2_reflected.is_finite() && r.solve_s > 0.0,
                "{r:?}"
            );
        }
        // The uniform row's error equals an independent recomputation from its saved output.
        let u = rows
            .iter()
            .find(|r| r.method == Method::Uniform && r.budget == 60)
            .unwrap();
        let grid = run_uniform(&kernel, 60, u.seed, &UniformParams::default()).unwrap();
        let again = reference.errors(&grid.approx);
        assert_eq!(again, u.errors);
        let pick = |m, budget| {
            rows.iter()
                .find(|r| r.method == m && r.budget == budget && r.seed == 1)
                .unwrap()
        };
        for budget in [30, 60] {
            // The refit never makes the paper's network worse on the samples it validates on.
            assert!(
                pick(Method::Paper, budget).errors.heldout
                    <= pick(Method::PaperNorefit, budget).errors.heldout * 1.05
            );
            // The learner beats hierarchical radiosity by far at the same budget (R4), and so
            // does the scene it lights.
            let (learned, hr) = (pick(Method::Visibility, budget), pick(Method::Hr, budget));
            assert!(
                learned.errors.grid < 0.5 * hr.errors.grid,
                "{learned:?} vs {hr:?}"
            );
            let reflected = |r: &BenchRow| r.solve.unwrap().rel_l2_reflected;
            assert!(reflected(learned) < reflected(hr), "{learned:?} vs {hr:?}");
        }
    }

    #[test]
    fn bad_plans_are_refused_with_the_parameter_named() {
        let base = BenchPlan::new(vec![Method::Uniform], vec![10], 1);
        for (plan, name) in [
            (
                BenchPlan {
                    methods: vec![],
                    ..base.clone()
                },
                "methods",
            ),
            (
                BenchPlan {
                    budgets: vec![2],
                    ..base.clone()
                },
                "budgets",
            ),
            (
                BenchPlan {
                    seeds: 0,
                    ..base.clone()
                },
                "seeds",
            ),
        ] {
            let msg = plan.validate().unwrap_err().to_string();
            assert!(msg.contains(name), "{msg}");
        }
        // A method the table does not run is refused, naming those it does.
        let plan = BenchPlan {
            methods: vec![Method::Light],
            ..base.clone()
        };
        let msg = plan.validate().unwrap_err().to_string();
        assert!(
            msg.contains("light") && msg.contains("paper-norefit"),
            "{msg}"
        );
    }
}
