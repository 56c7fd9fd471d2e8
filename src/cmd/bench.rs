//! `flatland bench`: run time against error for the learners, hierarchical radiosity and a
//! uniform grid.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Result;
use flatland_lab::bench::{BenchPlan, Method};

use super::SceneArgs;
use flatland_lab::report::bench::{OUTPUTS, run_kept, table, write_outputs};
use flatland_lab::{interrupt, output};

/// Arguments of `flatland bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Methods, comma-separated: default (the default learner), paper (the paper's network
    /// with the refit), paper-norefit, hr, uniform (`sgcs`, `sgcs-paper` and
    /// `sgcs-paper-norefit` still name the first three).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "default,paper,paper-norefit,hr,uniform"
    )]
    pub methods: Vec<String>,
    /// Budgets (numbers of basis functions, each in [3, 10 000 000]), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "50,100,200,400,800")]
    pub budgets: Vec<usize>,
    /// Seeds per random method and budget, in [1, 1000].
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// Reference grid resolution R in [16, 4096].
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Solve the radiosity with every representation on N elements and report the error of
    /// the solved B against the exact kernel's (0: no solve).
    #[arg(long, value_name = "N", default_value_t = 256)]
    pub solve_elements: usize,
    /// Output folder for results.csv and the plots.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Most seeds per method and budget (each is a whole run).
const MAX_SEEDS: u64 = 1000;

/// Runs `flatland bench`.
pub fn run(args: &Args) -> Result<()> {
    let methods = args
        .methods
        .iter()
        .map(|m| Method::parse(m.trim()))
        .collect::<Result<Vec<_>, _>>()?;
    let mut plan = BenchPlan::new(methods, args.budgets.clone(), args.seeds);
    plan.solve_elements = (args.solve_elements > 0).then_some(args.solve_elements);
    plan.validate()?;
    for &budget in &plan.budgets {
        super::check_cells("--budgets", budget)?;
    }
    anyhow::ensure!(
        (1..=MAX_SEEDS).contains(&args.seeds),
        "--seeds must be in [1, {MAX_SEEDS}], but is {}",
        args.seeds
    );
    super::check_res(args.res)?;
    let (kernel, label) = args.scene.kernel()?;
    output::folder(
        &args.out,
        &OUTPUTS,
        &args.scene.path().into_iter().collect::<Vec<_>>(),
    )?;
    let kernel = Arc::new(kernel);
    let reference = Arc::new(flatland_lab::reference(&kernel, args.res, &plan.fit));
    let defined = flatland_lab::Defined::of(&reference);
    let total = plan.methods.len() * plan.budgets.len() * plan.seeds as usize;
    eprintln!(
        "bench of {label}: {total} runs (Ctrl-C stops; the rows so far are kept in {})",
        args.out.join("results.csv").display()
    );
    let bar = super::progress_bar(total as u64, "runs");
    let rows = run_kept(&kernel, &reference, &plan, |rows| {
        bar.set_position(rows.len() as u64);
        write_outputs(&args.out, &label, rows, defined)?;
        let kept = format!(
            "{} of {total} runs kept in {} (and its plots)",
            rows.len(),
            args.out.join("results.csv").display()
        );
        let budget = rows.last().map_or(0, |r| r.budget);
        bar.suspend(|| eprintln!("bench: budget {budget} done; {kept}"));
        interrupt::keep(kept);
        Ok(())
    })?;
    bar.finish_and_clear();
    print!("{}", table(&rows, defined));
    println!("wrote {}/results.csv and plots", args.out.display());
    Ok(())
}
