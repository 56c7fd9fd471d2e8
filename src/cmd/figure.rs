//! `flatland figure`: the paper's Fig. 3 panels as PNGs — geometry, kernel, cells, approximation
//! and error.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Result;
use kernel_fit::{Fit, FitParams};

use super::SceneArgs;
use flatland_lab::report::figure::panels;
use flatland_lab::{interrupt, output};
use flatland_pictures::figure::PANELS;

/// Arguments of `flatland figure`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Which network: `visibility` (learns V where geometry cannot decide it) or `paper` (the
    /// paper's network, learning ζ).
    #[arg(long, value_name = "NETWORK", default_value = "visibility",
          value_parser = flatland_methods::Method::parse_network)]
    pub preset: kernel_fit::Preset,
    /// Cells of the fit shown.
    #[arg(long, default_value_t = FitParams::default().target_cells)]
    pub cells: usize,
    /// Seed of the fit.
    #[arg(long, default_value_t = FitParams::default().seed)]
    pub seed: u64,
    /// Resolution R of the (s, t) panels' grid, in [16, 4096].
    #[arg(long, default_value_t = 512)]
    pub res: usize,
    /// Colour the kernel panels by log10 over four decades.
    #[arg(long)]
    pub log: bool,
    /// Output folder.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Runs `flatland figure`.
pub fn run(args: &Args) -> Result<()> {
    super::check_res(args.res)?;
    super::check_cells("--cells", args.cells)?;
    let (kernel, label) = args.scene.kernel()?;
    let kernel = Arc::new(kernel);
    let params = FitParams {
        target_cells: args.cells,
        seed: args.seed,
        ..args.preset.params()
    };
    params.validate()?;
    output::folder(
        &args.out,
        &PANELS,
        &args.scene.path().into_iter().collect::<Vec<_>>(),
    )?;
    let reference = Arc::new(flatland_lab::reference(&kernel, args.res, &params));
    let mut fit = Fit::new(Arc::clone(&kernel), Arc::clone(&reference), params)?;
    eprintln!(
        "figure of {label}: fitting {} cells (Ctrl-C stops; nothing is written before the fit ends)",
        args.cells
    );
    let summary = flatland_lab::interrupt::train_to_end(&mut fit)?;
    interrupt::check()?;

    let pictures = panels(&fit, &reference, &label, args.log)?;
    for (i, (name, png)) in pictures.iter().enumerate() {
        interrupt::check()?;
        interrupt::writing(|| flatland_geom::write_atomic(&args.out.join(name), png))?;
        interrupt::keep(format!(
            "{} of the {} panels written to {}",
            i + 1,
            PANELS.len(),
            args.out.display()
        ));
    }
    let defined = flatland_lab::Defined::of(&reference);
    println!(
        "{label}: {} cells, relative L2 {}; wrote a_geometry, b_kernel, c_cells, \
         d_approximation, e_error (.png) to {}",
        fit.network().len(),
        defined.format(&summary.errors),
        args.out.display()
    );
    Ok(())
}
