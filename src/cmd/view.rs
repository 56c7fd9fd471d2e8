//! `flatland view`: the desktop viewer, or the headless fit when there is no display.

use std::path::PathBuf;

use anyhow::Result;

/// Arguments of `flatland view`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (.ron or .json). Default: the scene of the last session, else bundled `fig3`.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
}

/// Runs `flatland view`: the viewer when a display is available; otherwise one line saying so,
/// then the headless fit of the same scene.
pub fn run(args: &Args) -> Result<()> {
    if flatland_viewer::display_available() {
        return Ok(flatland_viewer::run(args.scene.clone())?);
    }
    eprintln!("no display available (DISPLAY is not set): running the headless fit instead");
    let fit_args = super::fit::Args::for_scene(args.scene.clone());
    super::fit::run(&fit_args)
}
