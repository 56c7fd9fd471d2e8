//! One row of each method: built by [`Recipes::build`](flatland_methods::Recipes::build) (the
//! one place a method is built), solved on the scorer's mesh, measured. The exact kernel's rows
//! assemble its operator on a mesh of their own; the tracer is not a kernel and traces.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use flatland_baselines::{TraceBudget, TraceParams, budget_tolerance, trace};
use flatland_geom::Kernel;
use flatland_light::LightStop;
use flatland_methods::{Account, Ask, Built, NetworkAccount};
use flatland_solve::{
    DenseOperator, Errors, ExactMethod, Mesh, Representation, SolveParams, SparseOperator, Stop,
    TransferOperator, exact_operator, solve_errors, solve_operator, sweep_operator,
};

use super::{Method, Scorer, Setting, TimedPlan, TimedRow};

/// What every row is computed with.
pub(crate) struct Context<'a> {
    pub kernel: &'a Arc<Kernel>,
    pub scorer: &'a Scorer,
    pub plan: &'a TimedPlan,
    pub stop: &'a Stop,
    /// Seconds the light-driven learner may take before it stops short of its tolerance: the
    /// plan's `max_seconds`, or less where its share of the time budget is shorter.
    pub light_seconds: f64,
}

/// A representation to score: solved on the scorer's mesh, measured.
struct Piece<'r> {
    method: Method,
    setting: Setting,
    seed: u64,
    rep: &'r dyn Representation,
    build_s: f64,
    rays: u64,
    /// Its errors of ζ̃, where they are measured.
    zeta: Option<Errors>,
}

impl<'a> Context<'a> {
    /// Rows of `plan` on `scorer`'s mesh, the light-driven learner limited to `max_seconds`.
    pub fn new(
        kernel: &'a Arc<Kernel>,
        scorer: &'a Scorer,
        plan: &'a TimedPlan,
        stop: &'a Stop,
    ) -> Context<'a> {
        Context {
            kernel,
            scorer,
            plan,
            stop,
            light_seconds: plan.max_seconds,
        }
    }
}

impl Context<'_> {
    /// `ask` built by the plan's recipes: the light-driven learner on the scorer's mesh, the
    /// networks trained against the scorer's ζ reference.
    pub fn build(&self, ask: Ask) -> Result<Built> {
        let mut recipes = self.plan.recipes.clone();
        recipes.light.max_seconds = self.light_seconds;
        let built = recipes.build(
            ask,
            self.kernel,
            self.scorer.mesh(),
            self.scorer.zeta(),
            self.stop,
            &mut |_| {},
        )?;
        Ok(built)
    }

    fn scored(&self, piece: Piece<'_>) -> Result<TimedRow> {
        let (errors, solve_s) = self.scorer.solve(piece.rep, self.stop)?;
        let mut row = TimedRow::new(piece.method, piece.setting, piece.seed);
        row.basis_functions = piece.rep.basis_functions();
        row.build_s = piece.build_s;
        row.solve_s = solve_s;
        row.total_s = piece.build_s + solve_s;
        row.bytes = piece.rep.memory_bytes();
        row.rays = piece.rays;
        row.zeta = piece.zeta;
        row.solve = Some(errors);
        Ok(row)
    }

    /// The light-driven learner to `tolerance` on the scorer's mesh (stopped by its time limit
    /// at the latest), its row, and what was built (relighting re-solves with it).
    pub fn light(&self, tolerance: f64) -> Result<(TimedRow, Built)> {
        let ask = Ask {
            tolerance: Some(tolerance),
            ..Ask::new(Method::Light)
        };
        let built = self.build(ask)?;
        let rep = built.rep.as_ref();
        let mut row = self.scored(Piece {
            method: Method::Light,
            setting: Setting::Tolerance(tolerance),
            seed: 1,
            rep,
            build_s: built.build_s,
            // Probes sweep a view each, as the exact operator's rows do: no ray is cast.
            rays: 0,
            zeta: self.scorer.zeta_errors(rep),
        })?;
        if let Account::Light(account) = &built.account {
            row.estimated_error = account.estimated_error;
            match account.stopped {
                LightStop::Tolerance => {}
                LightStop::Exact => row.add_note("no doubt left: the exact operator"),
                LightStop::Cells => row.add_note("stopped by its cell budget before the tolerance"),
                LightStop::Time if self.light_seconds < self.plan.max_seconds => {
                    row.add_note("stopped by its share of the time budget before the tolerance");
                }
                LightStop::Time => row.add_note("stopped by --max-seconds before the tolerance"),
            }
        }
        Ok((row, built))
    }

    /// A network at `budget` cells and `seed`.
    fn network(&self, method: Method, budget: usize, seed: u64) -> Result<Built> {
        let ask = Ask {
            basis: Some(budget),
            seed,
            ..Ask::new(method)
        };
        self.build(ask)
    }

    /// The visibility network at `budget` cells.
    pub fn visibility(&self, budget: usize, seed: u64) -> Result<TimedRow> {
        let built = self.network(Method::Visibility, budget, seed)?;
        let account = account_of(&built)?;
        let mut row = self.scored(Piece {
            method: Method::Visibility,
            setting: Setting::Budget(budget),
            seed,
            rep: built.rep.as_ref(),
            build_s: built.build_s,
            rays: built.rays,
            zeta: self.scorer.defined_zeta(account.summary.errors),
        })?;
        if let Some(n) = row
            .basis_functions
            .filter(|&n| n + budget_tolerance(budget) < budget)
        {
            row.add_note(&format!("converged at {n} cells, below the budget"));
        }
        Ok(row)
    }

    /// The paper's network at `budget` cells: the rows with and without its refit, from one
    /// fit (the model read before the refit).
    pub fn paper(&self, budget: usize, seed: u64) -> Result<(TimedRow, TimedRow)> {
        let built = self.network(Method::Paper, budget, seed)?;
        let account = account_of(&built)?;
        let summary = &account.summary;
        let (before, before_errors) = account
            .before_refit
            .as_ref()
            .context("the paper's network ends with its refit")?;
        let after = self.scored(Piece {
            method: Method::Paper,
            setting: Setting::Budget(budget),
            seed,
            rep: built.rep.as_ref(),
            build_s: built.build_s,
            rays: built.rays,
            zeta: self.scorer.defined_zeta(summary.errors),
        })?;
        let before = self.scored(Piece {
            method: Method::PaperNorefit,
            setting: Setting::Budget(budget),
            seed,
            rep: before,
            build_s: summary.wall_s - summary.refit_s,
            rays: built.rays,
            zeta: self.scorer.defined_zeta(*before_errors),
        })?;
        Ok((after, before))
    }

    /// HR, clustered HR or a uniform grid at `budget` (or the nearest count it can build,
    /// noted).
    pub fn baseline(&self, method: Method, budget: usize, seed: u64) -> Result<TimedRow> {
        let ask = Ask {
            basis: Some(budget),
            seed,
            ..Ask::new(method)
        };
        let built = self.build(ask)?;
        let rep = built.rep.as_ref();
        let mut row = self.scored(Piece {
            method,
            setting: Setting::Budget(budget),
            seed,
            rep,
            build_s: built.build_s,
            rays: built.rays,
            zeta: self.scorer.zeta_errors(rep),
        })?;
        if let Some(note) = &built.note {
            row.add_note(note);
        }
        Ok(row)
    }

    /// The exact kernel solved on `elements` elements, read by its final gather and measured
    /// as a function against the reference.
    pub fn exact(&self, elements: usize) -> Result<TimedRow> {
        let kernel = self.kernel.as_ref();
        let mesh = Mesh::new(kernel, elements)?;
        let started = Instant::now();
        let (op, bytes) = exact_operator_of(kernel, &mesh, self.stop)?;
        let build_s = started.elapsed().as_secs_f64();
        let solution = solve_operator(op.as_ref(), &mesh, &SolveParams::default(), self.stop)?;
        let errors = self
            .scorer
            .gathered_errors_on(&mesh, &solution.radiosity, self.stop)?;
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

/// A network's account of its fit.
fn account_of(built: &Built) -> Result<&NetworkAccount> {
    match &built.account {
        Account::Network(account) => Ok(account),
        _ => anyhow::bail!("{} gave no account of its fit", built.method),
    }
}

/// The exact kernel's operator on `mesh` (dense from pairs on small scenes, by the sweep on
/// large ones, as its [`Representation::operator`] assembles it) and its bytes, which only the
/// concrete operators know.
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
