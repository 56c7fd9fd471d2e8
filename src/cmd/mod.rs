//! Subcommands. Each module has `Args` (clap) and `run(&Args) -> anyhow::Result<()>`;
//! what several of them share (scene loading, input limits, progress bars) lives here.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use flatland_geom::{Kernel, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use kernel_fit::limits;

pub mod bench;
pub mod check;
pub mod eval;
pub mod figure;
pub mod fit;
pub mod kernel;
pub mod relight;
pub mod results;
pub mod scene;
pub mod solve;
pub mod stress;
pub mod view;

/// The scene a command works on: a file, or the bundled default, optionally subdivided.
#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene file: .ron, .json, or an .svg drawing (imported: docs/SVG.md), or a bundled
    /// scene's name (fig3, box, maze, corners, floorplan, hall). Default: the bundled
    /// `fig3` scene.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// An SVG scene's curves become segments no farther than this from them, in drawing units
    /// (default: a thousandth of the drawing's diagonal).
    #[arg(long, value_name = "T")]
    pub flatten: Option<f64>,
    /// Scene units per SVG drawing unit (0.001 reads a drawing in millimetres as metres).
    #[arg(long, value_name = "U")]
    pub unit: Option<f64>,
    /// Split every surface edge into M equal edges (the kernel over (s, t) does not change);
    /// at most 1 000 000 edges in all.
    #[arg(long, value_name = "M", default_value_t = 1)]
    pub subdivide: usize,
}

impl SceneArgs {
    /// Loads (or takes the bundled) scene, subdivides it, and names it for reports. Warns on
    /// stderr about overlapping surface edges.
    pub fn load(&self) -> Result<(Scene, String)> {
        let (scene, mut label) = match &self.scene {
            Some(path) if is_svg(path) => (self.import(path)?, path.display().to_string()),
            Some(path) if let Some(name) = bundled_name(path) => (
                flatland_geom::bundled::scene(name)?,
                format!("{name} (bundled)"),
            ),
            Some(path) => {
                anyhow::ensure!(
                    self.flatten.is_none() && self.unit.is_none(),
                    "--flatten and --unit apply to SVG drawings, and {} is not one",
                    path.display()
                );
                let scene = match Scene::load(path) {
                    Err(flatland_geom::GeomError::Format { .. }) => anyhow::bail!(
                        "{}: unknown scene format: --scene takes a .ron, .json or .svg file, or a \
                         bundled scene's name ({})",
                        path.display(),
                        flatland_geom::bundled::names()
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                    loaded => loaded?,
                };
                (scene, path.display().to_string())
            }
            None => (
                flatland_geom::bundled::scene(flatland_geom::bundled::DEFAULT)
                    .context("the bundled fig3 scene")?,
                "fig3 (bundled)".to_owned(),
            ),
        };
        warn_overlaps(&scene, &label);
        if self.subdivide != 1 {
            let scene = subdivide(&scene, self.subdivide)?;
            label = format!("{label} ×{}", self.subdivide);
            return Ok((scene, label));
        }
        Ok((scene, label))
    }

    /// The scene a model is used on: `--scene` (subdivided), checked to be the model's, or the
    /// model's own scene when none is given.
    pub fn load_for_model(&self, model: &Path) -> Result<(Scene, String)> {
        let file = kernel_fit::ModelFile::load(model)?;
        let Some(scene_path) = &self.scene else {
            let label = format!("{} (model's scene)", model.display());
            return Ok((file.model.scene().clone(), label));
        };
        let (scene, label) = self.load()?;
        file.check_scene(&scene, scene_path)?;
        Ok((scene, label))
    }

    /// An SVG drawing as a scene; its warnings on stderr, a few of each kind.
    fn import(&self, path: &Path) -> Result<Scene> {
        let params = flatland_svg::ImportParams {
            flatten: self.flatten,
            unit: self.unit.unwrap_or(1.0),
            ..flatland_svg::ImportParams::default()
        };
        let drawing = flatland_svg::import_file(path, &params)?;
        print_warnings(path, drawing.warnings());
        drawing
            .into_scene()
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }

    /// The input file, if any (outputs must never overwrite it).
    pub fn path(&self) -> Option<&Path> {
        self.scene.as_deref()
    }

    /// The scene's exact kernel with default parameters.
    pub fn kernel(&self) -> Result<(Kernel, String)> {
        let (scene, label) = self.load()?;
        Ok((Kernel::new(scene), label))
    }
}

/// A scene file as it is: .ron, .json, or an SVG drawing imported with default settings.
pub fn scene_file(path: &Path) -> Result<Scene> {
    let args = SceneArgs {
        scene: Some(path.to_owned()),
        flatten: None,
        unit: None,
        subdivide: 1,
    };
    Ok(args.load()?.0)
}

/// The bundled scene `path` names: a bare name (no extension, no such file) that is one.
fn bundled_name(path: &Path) -> Option<&'static str> {
    if path.extension().is_some() || path.exists() {
        return None;
    }
    let name = path.to_str()?;
    flatland_geom::bundled::names().find(|&n| n == name)
}

/// Whether `path` names an SVG drawing (by its extension, in any case).
pub fn is_svg(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"))
}

/// Most warnings of one kind printed for a drawing; the rest are counted.
const WARNINGS_PER_KIND: usize = 3;

/// An import's warnings on stderr, one line each, at most [`WARNINGS_PER_KIND`] of a kind.
fn print_warnings(path: &Path, warnings: &[flatland_svg::Warning]) {
    let mut seen = std::collections::HashMap::new();
    for w in warnings {
        let count = seen
            .entry(std::mem::discriminant(&w.kind))
            .or_insert(0usize);
        *count += 1;
        if *count <= WARNINGS_PER_KIND {
            eprintln!("warning: {}: {w}", path.display());
        }
    }
    let hidden: usize = seen
        .values()
        .map(|n| n.saturating_sub(WARNINGS_PER_KIND))
        .sum();
    if hidden > 0 {
        eprintln!(
            "warning: {}: {hidden} more warnings like these",
            path.display()
        );
    }
}

/// Refuses a grid resolution outside the range every command shares, before anything is
/// allocated.
pub fn check_res(res: usize) -> Result<()> {
    let (lo, hi) = (limits::GRID_RES.start(), limits::GRID_RES.end());
    anyhow::ensure!(
        limits::GRID_RES.contains(&res),
        "--res must be in [{lo}, {hi}], but is {res}"
    );
    Ok(())
}

/// Refuses a cell count or budget (`--cells`, `--budgets`: basis functions) outside the range
/// every command and file shares, before anything is allocated.
pub fn check_cells(flag: &str, n: usize) -> Result<()> {
    let max = limits::MAX_CELLS;
    anyhow::ensure!(
        (3..=max).contains(&n),
        "{flag} must be in [3, {max}], but is {n}"
    );
    Ok(())
}

/// Largest scene `--subdivide` may produce, in edges.
pub const MAX_EDGES: usize = 1_000_000;

/// Splits every surface edge into `m`, refusing (before allocating) a count outside
/// `[1, MAX_EDGES]` or a result of more than [`MAX_EDGES`] edges.
pub fn subdivide(scene: &Scene, m: usize) -> Result<Scene> {
    let surfaces = scene.surface_edges().len();
    let blockers = scene.edges().len() - surfaces;
    let edges = surfaces
        .checked_mul(m)
        .and_then(|e| e.checked_add(blockers));
    let most = MAX_EDGES.saturating_sub(blockers) / surfaces;
    match edges {
        Some(e) if m >= 1 && e <= MAX_EDGES => Ok(scene.subdivide(m)?),
        _ => anyhow::bail!(
            "--subdivide must be in [1, {most}] for this scene ({surfaces} surface edges; at most \
             {MAX_EDGES} edges in all), but is {m}"
        ),
    }
}

/// Warns (stderr, one line) when surface edges overlap: light is then counted on each copy.
pub fn warn_overlaps(scene: &Scene, label: &str) {
    let pairs = scene.overlapping_surface_edges();
    if let Some(&(a, b)) = pairs.first() {
        eprintln!(
            "warning: {label}: {} pair(s) of surface edges overlap (first: edges {a} and {b}); \
             each copy carries its own light, doubling it there (`flatland check` lists them)",
            pairs.len()
        );
    }
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

/// A bar's updates from a method's build: a network's cells of its target, the light-driven
/// learner's probes and estimate.
pub fn learning(bar: &ProgressBar) -> impl FnMut(flatland_methods::Progress) + '_ {
    move |p| match p {
        flatland_methods::Progress::Cells { cells, target } => {
            bar.set_length(target as u64);
            bar.set_position(cells as u64);
        }
        flatland_methods::Progress::Probes { cells, estimate } => {
            bar.set_position(cells as u64);
            if let Some(e) = estimate {
                bar.set_message(format!("estimated error {e:.4}"));
            }
        }
    }
}

/// A build's interruption as the command's (what was kept, exit code 130), anything else as
/// it is.
pub fn interrupted(e: flatland_methods::MethodError) -> anyhow::Error {
    if e.is_interrupted() {
        flatland_lab::interrupt::stopped().into()
    } else {
        e.into()
    }
}

/// What `cargo run --release` does with no arguments: the viewer, or, without a display, the
/// headless fit of the bundled scene and its summary.
pub fn default_job() -> Result<()> {
    view::run(&view::Args::default())
}
