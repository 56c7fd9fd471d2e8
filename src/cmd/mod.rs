//! Subcommands. Each module has `Args` (clap) and `run(&Args) -> anyhow::Result<()>`;
//! what several of them share (scene loading, progress bars, references) lives here.

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Context, Result};
use flatland_geom::{Kernel, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use kernel_fit::{FitParams, Reference};

pub mod bench;
pub mod check;
pub mod eval;
pub mod figure;
pub mod fit;
pub mod kernel;
pub mod results;
pub mod solve;
pub mod stress;
pub mod view;

/// The scene a command works on: a file, or the bundled default, optionally subdivided.
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene file (.ron or .json). Default: the bundled `fig3` scene.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Split every surface edge into M equal edges (the kernel over (s, t) does not change).
    #[arg(long, value_name = "M", default_value_t = 1)]
    pub subdivide: usize,
}

impl SceneArgs {
    /// Loads (or takes the bundled) scene, subdivides it, and names it for reports.
    pub fn load(&self) -> Result<(Scene, String)> {
        let (scene, mut label) = match &self.scene {
            Some(path) => (Scene::load(path)?, path.display().to_string()),
            None => (
                Scene::from_ron_str(BUNDLED_FIG3).context("the bundled fig3 scene")?,
                "fig3 (bundled)".to_owned(),
            ),
        };
        if self.subdivide != 1 {
            label = format!("{label} ×{}", self.subdivide);
            return Ok((scene.subdivide(self.subdivide)?, label));
        }
        Ok((scene, label))
    }

    /// The scene's exact kernel with default parameters.
    pub fn kernel(&self) -> Result<(Kernel, String)> {
        let (scene, label) = self.load()?;
        Ok((Kernel::new(scene), label))
    }
}

/// The bundled default scene (the paper's Fig. 3), so the binary runs from any folder.
pub const BUNDLED_FIG3: &str = include_str!("../../scenes/fig3.ron");

/// The reference every error of a fit is measured against.
pub fn reference(kernel: &Kernel, res: usize, params: &FitParams) -> Reference {
    Reference::new(kernel, res, params.heldout, params.seed)
}

/// A progress bar on a terminal, nothing otherwise (so piped output stays clean).
pub fn progress_bar(len: u64, unit: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    let template = format!("{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit} {{msg}}");
    bar.set_style(ProgressStyle::with_template(&template).expect("static template"));
    bar
}

/// What `cargo run --release` does with no arguments: the viewer on the bundled scene, or,
/// without a display, the headless fit and its summary.
pub fn default_job() -> Result<()> {
    view::run(&view::Args { scene: None })
}
