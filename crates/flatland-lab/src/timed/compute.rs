//! One row of each method: build, solve on the scorer's mesh, measure.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use flatland_baselines::{
    BaselineRun, TraceBudget, TraceParams, budget_tolerance, run_clustered, run_hr_at_budget,
    run_uniform, trace,
};
use flatland_geom::Kernel;
use flatland_light::{LightFit, LightParams, LightStop};
use flatland_solve::{
    DenseOperator, ExactMethod, Mesh, Representation, SolveParams, SparseOperator, Stop,
    TransferOperator, exact_operator, solve_errors, solve_operator, sweep_operator,
};

use super::{Method, Scorer, Setting, TimedPlan, TimedRow};
use crate::bench::{BenchRow, learner_row, paper_rows};

/// What every row is computed with.
pub(crate) struct Context<'a> {
    pub kernel: &'a Arc<Kernel>,
    pub scorer: &'a Scorer,
    pub plan: &'a TimedPlan,
    pub stop: &'a Stop,
}

/// A row of a built representation: solved on the scorer's mesh and measured.
struct Built<'r> {
    method: Method,
    setting: Setting,
    seed: u64,
    rep: &'r dyn Representation,
    build_s: f64,
    rays: u64,
}

impl Context<'_> {
    fn scored(&self, built: Built<'_>) -> Result<TimedRow> {
        let (errors, solve_s) = self.scorer.solve(built.rep, self.stop)?;
        Ok(TimedRow {
            method: built.method,
            setting: built.setting,
            seed: built.seed,
            basis_functions: built.rep.basis_functions(),
            build_s: built.build_s,
            solve_s,
            total_s: built.build_s + solve_s,
            bytes: built.rep.memory_bytes(),
            rays: built.rays,
            zeta_error: self.scorer.zeta_error(built.rep),
            solve: Some(errors),
            estimated_error: None,
            note: String::new(),
            failed: false,
        })
    }

    /// The light-driven learner to `tolerance` on the scorer's mesh (stopped by the time
    /// budget at the latest), its row, and the fit (relighting re-solves with it).
    pub fn light(&self, tolerance: f64) -> Result<(TimedRow, LightFit)> {
        let params = LightParams {
            tolerance,
            max_seconds: self.plan.max_seconds,
            ..LightParams::default()
        };
        let started = Instant::now();
        let mesh = self.scorer.mesh().clone();
        let mut fit = LightFit::new(Arc::clone(self.kernel), mesh, params)?;
        let stopped = fit.run(self.stop, |_| {})?;
        let build_s = started.elapsed().as_secs_f64();
        let mut row = self.scored(Built {
            method: Method::Light,
            setting: Setting::Tolerance(tolerance),
            seed: 1,
            rep: &fit,
            build_s,
            // Probes sweep a view each, as the exact operator's rows do: no ray is cast.
            rays: 0,
        })?;
        row.estimated_error = fit.estimated_error();
        match stopped {
            LightStop::Tolerance => {}
            LightStop::Exact => row.add_note("no doubt left: the exact operator"),
            LightStop::Cells => row.add_note("stopped by its cell budget before the tolerance"),
            LightStop::Time => row.add_note("stopped by --max-seconds before the tolerance"),
        }
        Ok((row, fit))
    }

    /// The first-shot learner at `budget` cells.
    pub fn first_shot(&self, budget: usize, seed: u64) -> Result<TimedRow> {
        let solver = self.scorer.solver();
        let zeta = self.zeta()?;
        let row = learner_row(
            self.kernel,
            zeta,
            &self.plan.fit,
            budget,
            seed,
            Some(&solver),
        )?;
        let mut row = self.of_bench(Method::Visibility, row);
        if let Some(n) = row
            .basis_functions
            .filter(|&n| n + budget_tolerance(budget) < budget)
        {
            row.add_note(&format!("converged at {n} cells, below the budget"));
        }
        Ok(row)
    }

    /// The paper's network at `budget` cells: the rows with and without its refit.
    pub fn paper(&self, budget: usize, seed: u64) -> Result<(TimedRow, TimedRow)> {
        let solver = self.scorer.solver();
        let zeta = self.zeta()?;
        let (after, before) = paper_rows(
            self.kernel,
            zeta,
            &self.plan.paper,
            budget,
            seed,
            Some(&solver),
        )?;
        Ok((
            self.of_bench(Method::Paper, after),
            self.of_bench(Method::PaperNorefit, before),
        ))
    }

    /// The ζ reference the network learners train against.
    fn zeta(&self) -> Result<&Arc<flatland_solve::Reference>> {
        self.scorer
            .zeta()
            .context("this run measures no ζ, which the network learners are trained against")
    }

    fn of_bench(&self, method: Method, r: BenchRow) -> TimedRow {
        let solve_s = r.solve_s;
        TimedRow {
            method,
            setting: Setting::Budget(r.budget),
            seed: r.seed,
            basis_functions: Some(r.basis_functions),
            build_s: r.wall_s,
            solve_s,
            total_s: r.wall_s + solve_s,
            bytes: r.memory_bytes,
            rays: r.rays,
            zeta_error: self.scorer.defined().heldout.then_some(r.errors.heldout),
            solve: r.solve,
            estimated_error: None,
            note: String::new(),
            failed: false,
        }
    }

    /// HR, clustered HR or the uniform grid at `budget` (or the nearest count it can build,
    /// noted).
    pub fn baseline(&self, method: Method, budget: usize, seed: u64) -> Result<TimedRow> {
        let kernel = self.kernel.as_ref();
        match method {
            Method::Hr => self.baseline_row(
                method,
                budget,
                seed,
                run_hr_at_budget(kernel, budget, seed, &self.plan.hr)?,
            ),
            Method::Clustered => self.baseline_row(
                method,
                budget,
                seed,
                run_clustered(kernel, budget, seed, &self.plan.clustered)?,
            ),
            _ => self.baseline_row(
                method,
                budget,
                seed,
                run_uniform(kernel, budget, seed, &self.plan.uniform)?,
            ),
        }
    }

    fn baseline_row<A: Representation>(
        &self,
        method: Method,
        budget: usize,
        seed: u64,
        run: BaselineRun<A>,
    ) -> Result<TimedRow> {
        let mut row = self.scored(Built {
            method,
            setting: Setting::Budget(budget),
            seed,
            rep: &run.approx,
            build_s: run.wall.as_secs_f64(),
            rays: run.rays,
        })?;
        if let Some(note) = run.note {
            row.add_note(&note.to_string());
        }
        Ok(row)
    }

    /// The exact kernel solved on `elements` elements, measured against the reference
    /// (interpolated by the equation itself onto its collocation points).
    pub fn exact(&self, elements: usize) -> Result<TimedRow> {
        let kernel = self.kernel.as_ref();
        let mesh = Mesh::new(kernel, elements)?;
        let started = Instant::now();
        let (op, bytes) = exact_operator_of(kernel, &mesh, self.stop)?;
        let build_s = started.elapsed().as_secs_f64();
        let solution = solve_operator(op.as_ref(), &mesh, &SolveParams::default(), self.stop)?;
        let errors = self
            .scorer
            .errors_on(&mesh, &solution.radiosity, self.stop)?;
        let mut row = TimedRow::new(Method::Exact, Setting::Elements(elements), 1);
        row.basis_functions = Some(mesh.len());
        row.build_s = build_s;
        row.solve_s = solution.solve_s;
        row.total_s = build_s + solution.solve_s;
        row.bytes = bytes;
        row.solve = Some(errors);
        if mesh.len() >= self.scorer.reference_elements() {
            row.add_note("as fine as the reference itself");
        }
        Ok(row)
    }

    /// The light tracer with `photons` photons on the scorer's mesh.
    pub fn tracer(&self, photons: u64, seed: u64) -> Result<TimedRow> {
        self.traced(TraceBudget::Photons(photons), seed)
    }

    /// The light tracer for about `seconds` of wall time (equal time with another row).
    pub fn tracer_for(&self, seconds: f64, seed: u64) -> Result<TimedRow> {
        self.traced(TraceBudget::Seconds(seconds), seed)
    }

    fn traced(&self, budget: TraceBudget, seed: u64) -> Result<TimedRow> {
        let params = TraceParams { budget, seed };
        let mesh = self.scorer.mesh();
        let traced = trace(self.kernel, mesh, &params, self.stop)?;
        let errors = solve_errors(mesh, &traced.radiosity, self.scorer.exact());
        // A photon budget's row is named by the count asked for; a time budget's by the count
        // it traced.
        let photons = match budget {
            TraceBudget::Photons(asked) => asked,
            TraceBudget::Seconds(_) => traced.photons,
        };
        let mut row = TimedRow::new(Method::Tracer, Setting::Photons(photons), seed);
        row.solve_s = traced.wall_s();
        row.total_s = row.solve_s;
        row.bytes = traced.memory_bytes;
        row.rays = traced.rays;
        row.solve = Some(errors);
        if traced.stopped {
            row.add_note(&format!("stopped after {} photons", traced.photons));
        }
        Ok(row)
    }
}

/// The exact operator on `mesh` (dense from pairs on small scenes, by the sweep on large ones,
/// as the exact kernel builds it) and its bytes.
pub(crate) fn exact_operator_of(
    kernel: &Kernel,
    mesh: &Mesh,
    stop: &Stop,
) -> Result<(Box<dyn TransferOperator>, usize)> {
    let method = ExactMethod::of(kernel);
    method.check(mesh.len())?;
    Ok(match method {
        ExactMethod::Dense => {
            let op: DenseOperator = exact_operator(kernel, mesh, stop)?;
            let bytes = op.memory_bytes();
            (Box::new(op), bytes)
        }
        ExactMethod::Sweep => {
            let op: SparseOperator = sweep_operator(kernel, mesh, stop)?;
            let bytes = op.memory_bytes();
            (Box::new(op), bytes)
        }
    })
}
