//! `flatland bench`: every method judged at equal time — the light-driven learner by
//! tolerance, the other learners, hierarchical radiosity and the uniform grid by basis
//! functions, the exact solve by elements, the light tracer by photons — each row timed to its
//! lit scene and scored against one independent exact reference, within a whole-run time
//! budget (`budget`; `--full` for the long sweep). `--scaling` (cost against scene size) is its
//! own module, `scaling`.

mod budget;
mod scaling;
mod walk;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use flatland_lab::report::timed::{
    OUTPUTS, PARTIAL, RELIGHT, RESULTS, relight_summary, table, within_table, write_plots,
    write_relight, write_rows,
};
use flatland_lab::timed::{
    DEFAULT_MAX_SECONDS, DEFAULT_TRACER_SECONDS, RelightBudget, Scorer, TimedPlan, TimedRow,
    run_timed,
};
use flatland_lab::{interrupt, output};
use flatland_methods::Method;
use flatland_solve::{ExactReference, LitParams, LitScene, ReferenceMesh, SolveParams, Stop};

use super::SceneArgs;

/// Arguments of `flatland bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Methods, comma-separated: light (the light-driven learner), visibility (the network
    /// `flatland fit` trains), paper (the paper's network with the refit), paper-norefit, hr,
    /// clustered (HR with clustering), uniform, exact, tracer. Default: all of these; with
    /// --scaling: light, exact, hr, clustered, tracer.
    #[arg(long, value_delimiter = ',', value_parser = Method::parse)]
    pub methods: Option<Vec<Method>>,
    /// The light-driven learner's tolerances on its estimated error of B − E, each in (0, 1),
    /// comma-separated; one row each.
    #[arg(long, value_delimiter = ',', default_value = "0.3,0.1,0.03,0.01,0.003")]
    pub tolerances: Vec<f64>,
    /// Budgets (numbers of basis functions, each in [3, 10 000 000]) of visibility, paper,
    /// paper-norefit, hr, clustered and uniform, comma-separated: exactly these. Default: 50, 100, 200,
    /// 400, 800, then doubling until a row is over --max-seconds.
    #[arg(long, value_delimiter = ',')]
    pub budgets: Option<Vec<usize>>,
    /// Seeds per random method and setting, in [1, 1000].
    #[arg(long, default_value_t = 1)]
    pub seeds: u64,
    /// Reference grid resolution R of the ζ errors, in [16, 4096].
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Elements every method's radiosity is solved on. Default: what `flatland solve` uses
    /// (the fewest, from 512, whose exact solve's estimated error of B − E is below 1 %).
    #[arg(long, value_name = "N")]
    pub solve_elements: Option<usize>,
    /// A method's sweep stops at its first row whose total time is above this many seconds
    /// (default 30). With --scaling: a method is skipped at a size where its time,
    /// extrapolated from the smaller sizes, is above this (default 120).
    #[arg(long, value_name = "S")]
    pub max_seconds: Option<f64>,
    /// The tracer's photons double until its rows took this many seconds together.
    #[arg(long, value_name = "S", default_value_t = DEFAULT_TRACER_SECONDS)]
    pub tracer_seconds: f64,
    /// Lightings of the relighting comparison (0: none; at most 1000).
    #[arg(long, default_value_t = flatland_lab::timed::relight::LIGHTINGS)]
    pub lightings: usize,
    /// The whole run's time budget in seconds (reference solves, sweeps and relighting), more
    /// than 0: each method's sweep gets its share and is cut, with a note, where its next row
    /// would not fit. Default 120.
    #[arg(long, value_name = "S", conflicts_with = "full")]
    pub budget_seconds: Option<f64>,
    /// The long sweep: no whole-run budget, every method to --max-seconds, every lighting.
    #[arg(long)]
    pub full: bool,
    /// Instead of one scene: cost against scene size, each method with its default arguments
    /// on generated floor plans and halls of --sizes edges (time, peak memory, rays, error,
    /// log–log slopes, relighting up to 10⁴ edges); --scene is not used.
    #[arg(long)]
    pub scaling: bool,
    /// Instead of one scene: a lamp carried along a walk of --positions through generated
    /// floor plans and halls of --sizes edges (their own lamps off, no edge emitting), each
    /// position relit by the exact re-solve (at tolerances 1e-6, 1e-2, 1e-4, 1e-8), clustered
    /// HR, the tracer (given the exact re-solve's time per move), the learned transport and a
    /// uniform grid of light-position probes of the transport's bytes, each against a cold
    /// exact solve there: set-up, bytes, ms per move, errors of B and of the indirect part,
    /// and after how many moves the set-up pays off. --methods: of exact, clustered, tracer,
    /// transport, probes (probes with transport).
    #[arg(long)]
    pub relight: bool,
    /// With --relight: positions of the lamp's walk, in [1, 1000000].
    #[arg(long, value_name = "N", default_value_t = flatland_lab::timed::walk::POSITIONS)]
    pub positions: usize,
    /// With --scaling or --relight: the sizes in edges, ascending, comma-separated, each in
    /// [24, 1000000]. Default: 100,1000,10000 (--scaling), 1000,10000 (--relight; add 100000
    /// for the largest).
    #[arg(long, value_delimiter = ',')]
    pub sizes: Option<Vec<usize>>,
    /// With --scaling or --relight: the kinds of scene, comma-separated: floorplan, hall.
    #[arg(long, value_delimiter = ',', default_value = "floorplan,hall")]
    pub kinds: Vec<String>,
    /// Output folder for results.csv, relight.csv and the plots (with --scaling:
    /// scaling.csv, scaling.md and its plots; with --relight: relight-walk.csv,
    /// relight-walk.md and its plots).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// The methods a bench runs when none are named.
const ALL_METHODS: [Method; 9] = [
    Method::Light,
    Method::Visibility,
    Method::Paper,
    Method::PaperNorefit,
    Method::Hr,
    Method::Clustered,
    Method::Uniform,
    Method::Exact,
    Method::Tracer,
];

/// Most seeds per method and setting (each is a whole run).
const MAX_SEEDS: u64 = 1000;

impl Args {
    /// The plan the arguments ask for, checked before any work.
    fn plan(&self) -> Result<TimedPlan> {
        let methods = self.methods.clone().unwrap_or_else(|| ALL_METHODS.to_vec());
        let mut plan = TimedPlan::new(methods);
        plan.tolerances = self.tolerances.clone();
        if let Some(budgets) = &self.budgets {
            for &budget in budgets {
                super::check_cells("--budgets", budget)?;
            }
            plan.budgets = budgets.clone();
            plan.extend_budgets = false;
        }
        anyhow::ensure!(
            (1..=MAX_SEEDS).contains(&self.seeds),
            "--seeds must be in [1, {MAX_SEEDS}], but is {}",
            self.seeds
        );
        plan.seeds = self.seeds;
        plan.max_seconds = self.max_seconds.unwrap_or(DEFAULT_MAX_SECONDS);
        plan.tracer_seconds = self.tracer_seconds;
        plan.validate()?;
        super::check_res(self.res)?;
        anyhow::ensure!(
            self.lightings <= 1000,
            "--lightings must be in [0, 1000], but is {}",
            self.lightings
        );
        Ok(plan)
    }
}

/// Runs `flatland bench`.
pub fn run(args: &Args) -> Result<()> {
    if args.relight {
        return walk::run(args);
    }
    if args.scaling {
        return scaling::run(args);
    }
    let started = Instant::now();
    let mut plan = args.plan()?;
    let budget = budget::of(args, started)?;
    let (kernel, label) = args.scene.kernel()?;
    output::folder(
        &args.out,
        &OUTPUTS,
        &args.scene.path().into_iter().collect::<Vec<_>>(),
    )?;
    let kernel = Arc::new(kernel);
    let stop: &Stop = &interrupt::requested;
    let (scorer, reference_s) = scorer(&kernel, args, &plan, stop)?;
    plan.budget = budget.map(|b| budget::sweeps(b, args.lightings));
    let partial = args.out.join(PARTIAL);
    eprintln!(
        "bench of {label}: solving on {} elements against a reference on {}; rows are kept in \
         {} as they are made (Ctrl-C stops)",
        scorer.mesh().len(),
        scorer.reference_elements(),
        partial.display()
    );
    let rows = run_timed(&kernel, &scorer, &plan, stop, |rows| {
        write_rows(&args.out, PARTIAL, &label, rows)?;
        let last = rows.last().expect("called after a row");
        report_row(last, rows.len(), &partial);
        budget::progress(&plan, last);
        Ok(())
    })?;
    write_rows(&args.out, RESULTS, &label, &rows)?;
    remove_partial(&partial)?;
    write_plots(&args.out, &label, &rows)?;
    print!("{}", table(&rows));
    println!();
    print!("{}", within_table(&rows));
    println!("wrote {} and plots", args.out.join(RESULTS).display());
    if args.lightings > 0 {
        let fitted = budget::relighting(budget, reference_s, &scorer, &plan, &rows, args.lightings);
        if fitted.lightings > 0 {
            relight(args, &kernel, &scorer, &fitted, &label)?;
        }
    }
    if let Some(budget) = budget {
        eprintln!(
            "bench: done in {:.0} s of a {:.0} s budget",
            budget.spent(),
            budget.seconds()
        );
    }
    Ok(())
}

/// The relighting comparison `fitted` asks for: `relight.csv` and a summary line per method.
fn relight(
    args: &Args,
    kernel: &Arc<flatland_geom::Kernel>,
    scorer: &Scorer,
    fitted: &RelightBudget,
    label: &str,
) -> Result<()> {
    eprintln!(
        "bench: relighting {label} under {} lightings",
        fitted.lightings
    );
    let stop: &Stop = &interrupt::requested;
    let (relit, failures) = flatland_lab::timed::relight::relight(
        scorer,
        kernel,
        &fitted.plan,
        &fitted.rows,
        fitted.lightings,
        stop,
    )?;
    interrupt::check()?;
    for (method, why) in failures {
        eprintln!("bench: relighting with {} failed: {why}", method.name());
    }
    write_relight(&args.out, label, &relit)?;
    print!("{}", relight_summary(&relit));
    println!("wrote {}", args.out.join(RELIGHT).display());
    Ok(())
}

/// The mesh as `flatland solve` chooses it (or `--solve-elements`) and the exact reference on
/// four times as many elements, and the seconds the lit scene took (about what each
/// relighting's exact reference costs).
fn scorer(
    kernel: &Arc<flatland_geom::Kernel>,
    args: &Args,
    plan: &TimedPlan,
    stop: &Stop,
) -> Result<(Scorer, f64)> {
    let zeta = Arc::new(flatland_lab::reference(
        kernel,
        args.res,
        &plan.recipes.visibility,
    ));
    let started = Instant::now();
    let lit = match args.solve_elements {
        Some(n) => {
            let reference = ExactReference::default_elements_for(kernel, n);
            let params = SolveParams::default();
            LitScene::scoring(Arc::clone(kernel), n, reference, &params, stop)
        }
        None => {
            let params = LitParams {
                reference: ReferenceMesh::FourTimes,
                ..LitParams::default()
            };
            LitScene::new(Arc::clone(kernel), &params, stop)
        }
    };
    let lit = lit.context("the exact reference solve")?;
    let lit_s = started.elapsed().as_secs_f64();
    interrupt::check()?;
    Ok((Scorer::with_zeta(lit, zeta), lit_s))
}

/// One line on stderr per row (a failure with its reason), and the Ctrl-C note.
fn report_row(row: &TimedRow, kept: usize, partial: &Path) {
    let what = format!(
        "{} {} {}",
        row.method.name(),
        row.setting.kind(),
        row.setting.value()
    );
    let rows = if kept == 1 { "row" } else { "rows" };
    let note = format!("{kept} {rows} kept in {}", partial.display());
    if row.failed {
        eprintln!("bench: {what} {}; {note}", row.note);
    } else {
        let error = row
            .reflected_error()
            .map_or("–".to_owned(), |e| format!("{e:.4}"));
        eprintln!(
            "bench: {what} done in {:.2} s, B − E error {error}; {note}",
            row.total_s
        );
    }
    interrupt::keep(note);
}

/// Removes the partial file once the results are written.
fn remove_partial(partial: &Path) -> Result<()> {
    interrupt::writing(|| match std::fs::remove_file(partial) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(e).with_context(|| format!("removing {}", partial.display()))
        }
        _ => Ok(()),
    })
}
