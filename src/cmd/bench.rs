//! `flatland bench`: run time against error for SGCS, hierarchical radiosity and a uniform grid.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result};
use kernel_fit::Reference;
use kernel_fit::bench::{BenchPlan, BenchRow, Method, run_bench};

use super::SceneArgs;
use crate::plot::{Series, log_log};

/// Arguments of `flatland bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Methods, comma-separated: sgcs, sgcs-norefit, hr, uniform.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "sgcs,sgcs-norefit,hr,uniform"
    )]
    pub methods: Vec<String>,
    /// Budgets (numbers of basis functions), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "50,100,200,400,800")]
    pub budgets: Vec<usize>,
    /// Seeds per random method and budget.
    #[arg(long, default_value_t = 3)]
    pub seeds: u64,
    /// Reference grid resolution R.
    #[arg(long, default_value_t = 256)]
    pub res: usize,
    /// Output folder for results.csv and the plots.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Runs `flatland bench`.
pub fn run(args: &Args) -> Result<()> {
    let methods = args
        .methods
        .iter()
        .map(|m| Method::parse(m.trim()))
        .collect::<Result<Vec<_>, _>>()?;
    let plan = BenchPlan::new(methods, args.budgets.clone(), args.seeds);
    plan.validate()?;
    anyhow::ensure!(args.res >= 1, "--res must be at least 1, got {}", args.res);
    let (kernel, label) = args.scene.kernel()?;
    let kernel = Arc::new(kernel);
    let reference = Arc::new(Reference::new(&kernel, args.res, plan.fit.heldout, 0));
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating the output folder {}", args.out.display()))?;
    let total = plan.methods.len() * plan.budgets.len() * plan.seeds as usize;
    let bar = super::progress_bar(total as u64, "runs");
    let rows = run_bench(&kernel, &reference, &plan, |done, _| {
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    write_outputs(&args.out, &label, &rows)?;
    print!("{}", table(&rows));
    println!("wrote {}/results.csv and plots", args.out.display());
    Ok(())
}

/// What a plot puts on its x axis.
type XAxis = fn(&BenchRow) -> f64;

/// `results.csv` and the three log–log plots of one scene's rows.
pub fn write_outputs(dir: &Path, scene: &str, rows: &[BenchRow]) -> Result<()> {
    let mut csv = String::from(
        "scene,method,budget,seed,basis_functions,rel_l2_grid,rel_l2_heldout,rays,wall_s,memory_bytes\n",
    );
    for r in rows {
        writeln!(
            csv,
            "{scene},{},{},{},{},{},{},{},{},{}",
            r.method.name(),
            r.budget,
            r.seed,
            r.basis_functions,
            r.errors.grid,
            r.errors.heldout,
            r.rays,
            r.wall_s,
            r.memory_bytes
        )?;
    }
    flatland_geom::write_atomic(&dir.join("results.csv"), csv.as_bytes())?;
    let axes: [(&str, &str, XAxis); 3] = [
        ("error_vs_basis.png", "basis functions", |r| {
            r.basis_functions as f64
        }),
        ("error_vs_time.png", "wall time (s)", |r| r.wall_s),
        ("error_vs_rays.png", "rays", |r| r.rays as f64),
    ];
    for (file, x_label, x) in axes {
        let series = series(rows, x);
        let title = format!("{scene}: relative L2 (held out) vs {x_label}");
        log_log(
            &dir.join(file),
            &title,
            x_label,
            "relative L2 error (held out)",
            &series,
        )?;
    }
    Ok(())
}

/// Per method and budget: x and the mean, min and max held-out error over seeds.
fn series(rows: &[BenchRow], x: fn(&BenchRow) -> f64) -> Vec<Series> {
    let mut by_method: BTreeMap<Method, BTreeMap<usize, Vec<&BenchRow>>> = BTreeMap::new();
    for r in rows {
        by_method
            .entry(r.method)
            .or_default()
            .entry(r.budget)
            .or_default()
            .push(r);
    }
    by_method
        .into_iter()
        .map(|(method, budgets)| Series {
            label: method.name().to_owned(),
            points: budgets
                .values()
                .map(|group| {
                    let n = group.len() as f64;
                    let errors: Vec<f64> = group.iter().map(|r| r.errors.heldout).collect();
                    let mean_x = group.iter().map(|r| x(r)).sum::<f64>() / n;
                    let mean = errors.iter().sum::<f64>() / n;
                    let min = errors.iter().copied().fold(f64::INFINITY, f64::min);
                    let max = errors.iter().copied().fold(0.0, f64::max);
                    (mean_x, mean, min, max)
                })
                .collect(),
        })
        .collect()
}

/// A Markdown table of the rows, averaged over seeds.
pub fn table(rows: &[BenchRow]) -> String {
    let mut groups: BTreeMap<(usize, Method), Vec<&BenchRow>> = BTreeMap::new();
    for r in rows {
        groups.entry((r.budget, r.method)).or_default().push(r);
    }
    let mut out = String::from(
        "| budget | method | basis fns | rel. L2 grid | rel. L2 held out (min–max) | rays | wall s | bytes |\n\
         |---:|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for ((budget, method), g) in groups {
        let n = g.len() as f64;
        let mean = |f: &dyn Fn(&BenchRow) -> f64| g.iter().map(|r| f(r)).sum::<f64>() / n;
        let lo = g
            .iter()
            .map(|r| r.errors.heldout)
            .fold(f64::INFINITY, f64::min);
        let hi = g.iter().map(|r| r.errors.heldout).fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "| {budget} | {} | {:.0} | {:.3} | {:.3} ({lo:.3}–{hi:.3}) | {:.0} | {:.3} | {:.0} |",
            method.name(),
            mean(&|r| r.basis_functions as f64),
            mean(&|r| r.errors.grid),
            mean(&|r| r.errors.heldout),
            mean(&|r| r.rays as f64),
            mean(&|r| r.wall_s),
            mean(&|r| r.memory_bytes as f64),
        );
    }
    out
}
