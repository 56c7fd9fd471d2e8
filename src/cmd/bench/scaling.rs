//! `flatland bench --scaling`: cost against scene size on generated floor plans and halls.

use anyhow::{Result, bail};
use flatland_geom::generate::SceneKind;
use flatland_lab::report::scaling::{
    CSV, MARKDOWN, OUTPUTS, PARTIAL, markdown, write_csv, write_plots,
};
use flatland_lab::scaling::{DEFAULT_SIZES, ScalingPlan, run_scaling};
use flatland_lab::{interrupt, output};
use flatland_solve::Stop;

use super::Args;

/// The plan `args` ask for, checked before any work.
fn plan(args: &Args) -> Result<ScalingPlan> {
    if args.scene.scene.is_some() || args.scene.subdivide != 1 {
        bail!("--scaling generates its scenes: drop --scene and --subdivide (or drop --scaling)");
    }
    let mut plan = ScalingPlan::new();
    plan.sizes = args.sizes.clone().unwrap_or_else(|| DEFAULT_SIZES.to_vec());
    plan.kinds = kinds(&args.kinds)?;
    if let Some(methods) = &args.methods {
        plan.methods = methods.clone();
    }
    if let Some(seconds) = args.max_seconds {
        plan.max_seconds = seconds;
    }
    plan.lightings = args.lightings;
    plan.validate()?;
    Ok(plan)
}

/// The kinds of scene `--kinds` names.
pub(super) fn kinds(names: &[String]) -> Result<Vec<SceneKind>> {
    names
        .iter()
        .map(|k| match k.trim() {
            "floorplan" => Ok(SceneKind::FloorPlan),
            "hall" => Ok(SceneKind::Hall),
            other => bail!("--kinds: `{other}` is not a kind of scene; valid: floorplan, hall"),
        })
        .collect()
}

/// Runs `flatland bench --scaling`.
pub fn run(args: &Args) -> Result<()> {
    let plan = plan(args)?;
    output::folder(&args.out, &OUTPUTS, &[])?;
    let stop: &Stop = &interrupt::requested;
    let partial = args.out.join(PARTIAL);
    eprintln!(
        "bench --scaling: sizes {:?}; rows are kept in {} as they are made (Ctrl-C stops)",
        plan.sizes,
        partial.display()
    );
    let all = run_scaling(
        &plan,
        stop,
        |line| eprintln!("bench: {line}"),
        |all| {
            write_csv(&args.out, PARTIAL, all)?;
            interrupt::keep(format!(
                "{} rows kept in {}",
                all.rows.len(),
                partial.display()
            ));
            Ok(())
        },
    )?;
    write_csv(&args.out, CSV, &all)?;
    let md = markdown(&all);
    interrupt::writing(|| flatland_geom::write_atomic(&args.out.join(MARKDOWN), md.as_bytes()))?;
    super::remove_partial(&partial)?;
    write_plots(&args.out, &all)?;
    print!("{md}");
    println!(
        "wrote {}, {} and plots",
        args.out.join(CSV).display(),
        args.out.join(MARKDOWN).display()
    );
    Ok(())
}
