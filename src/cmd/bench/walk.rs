//! `flatland bench --relight`: a lamp carried along a walk through generated floor plans and
//! halls, every method relighting the scene at each position against a cold exact solve there.

use anyhow::{Result, bail};
use flatland_lab::report::walk::{CSV, MARKDOWN, OUTPUTS, PARTIAL, table, write_csv, write_plots};
use flatland_lab::timed::walk::{DEFAULT_SIZES, WalkPlan, run_walks};
use flatland_lab::{interrupt, output};
use flatland_solve::Stop;

use super::Args;

/// The plan `args` ask for, checked before any work.
fn plan(args: &Args) -> Result<WalkPlan> {
    if args.scene.scene.is_some() || args.scene.subdivide != 1 {
        bail!("--relight generates its scenes: drop --scene and --subdivide (or drop --relight)");
    }
    if args.scaling {
        bail!("--relight and --scaling are two benches: give one");
    }
    let mut plan = WalkPlan::new();
    plan.sizes = args.sizes.clone().unwrap_or_else(|| DEFAULT_SIZES.to_vec());
    plan.kinds = super::scaling::kinds(&args.kinds)?;
    if let Some(methods) = &args.methods {
        plan.methods = methods.clone();
    }
    plan.positions = args.positions;
    plan.validate()?;
    Ok(plan)
}

/// Runs `flatland bench --relight`.
pub fn run(args: &Args) -> Result<()> {
    let plan = plan(args)?;
    output::folder(&args.out, &OUTPUTS, &[])?;
    let stop: &Stop = &interrupt::requested;
    let partial = args.out.join(PARTIAL);
    eprintln!(
        "bench --relight: sizes {:?}, {} positions each; rows are kept in {} after each scene \
         (Ctrl-C ends the walk at the position it is at)",
        plan.sizes,
        plan.positions,
        partial.display()
    );
    let rows = run_walks(
        &plan,
        stop,
        |line| eprintln!("bench: {line}"),
        |rows| {
            write_csv(&args.out, PARTIAL, rows)?;
            interrupt::keep(format!("{} rows kept in {}", rows.len(), partial.display()));
            Ok(())
        },
    )?;
    interrupt::check()?;
    write_csv(&args.out, CSV, &rows)?;
    let md = table(&rows);
    interrupt::writing(|| flatland_geom::write_atomic(&args.out.join(MARKDOWN), md.as_bytes()))?;
    super::remove_partial(&partial)?;
    write_plots(&args.out, &rows)?;
    print!("{md}");
    println!(
        "wrote {}, {} and plots",
        args.out.join(CSV).display(),
        args.out.join(MARKDOWN).display()
    );
    Ok(())
}
