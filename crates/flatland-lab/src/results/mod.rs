//! `flatland results`: regenerate the results document (RESULTS.md and its plots) by running
//! every experiment the paper reports, and ours. `experiments` measure and return data;
//! `render` writes the document from it. Nothing in it is typed by hand.

mod experiments;
mod render;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use flatland_geom::{Kernel, Scene};
use kernel_fit::Preset;

use crate::report::bench::{OUTPUTS, write_outputs};
use crate::report::figure::PANELS;
use crate::{interrupt, output};
use experiments::{Ablation, Density, SceneBench, Subdivision, ThetaRow, fit, preset_params};

pub use experiments::{RES, reference_of};

/// What `flatland results` writes and how long it takes.
#[derive(Clone, Debug)]
pub struct Options {
    /// The document to write; plots go to `<its folder>/docs/results/`.
    pub out: PathBuf,
    /// Fewer seeds, budgets and rooms (minutes instead of tens of minutes).
    pub quick: bool,
    /// Folder of the bundled scenes.
    pub scenes: PathBuf,
}

/// The bundled scenes the experiments read from `--scenes`.
const SCENES: [&str; 3] = ["fig3", "maze", "corners"];

/// Everything the document reports.
pub(crate) struct Findings {
    pub quick: bool,
    pub seeds: u64,
    pub cores: usize,
    /// The default fit of fig3 for each preset.
    pub headline: Vec<(Preset, kernel_fit::FitSummary)>,
    pub density: Density,
    pub subdivision: Subdivision,
    pub theta: Vec<ThetaRow>,
    pub ablations: Vec<Ablation>,
    pub benches: Vec<SceneBench>,
    pub rooms: Vec<SceneBench>,
    pub stress: (String, Option<i32>),
    pub elapsed_s: f64,
}

/// Reports the stage on stderr and honours Ctrl-C between stages.
struct Progress {
    started: Instant,
    stage: usize,
    stages: usize,
}

impl Progress {
    fn next(&mut self, what: &str) -> Result<()> {
        interrupt::check()?;
        self.stage += 1;
        eprintln!(
            "results [{}/{}] {what} ({:.0} s so far; Ctrl-C stops)",
            self.stage,
            self.stages,
            self.started.elapsed().as_secs_f64()
        );
        Ok(())
    }
}

/// Runs `flatland results`.
pub fn run(args: &Options) -> Result<()> {
    let seeds: u64 = if args.quick { 1 } else { 3 };
    let budgets: Vec<usize> = if args.quick {
        vec![50, 100, 200, 400]
    } else {
        vec![50, 100, 200, 400, 800]
    };
    let rooms: u64 = if args.quick { 2 } else { 6 };
    let root = args.out.parent().map(Path::to_path_buf).unwrap_or_default();
    let plots = root.join("docs").join("results");
    let scene_files: Vec<PathBuf> = SCENES
        .iter()
        .map(|name| args.scenes.join(format!("{name}.ron")))
        .collect();
    let mut kernels = Vec::new();
    for path in &scene_files {
        kernels.push(Arc::new(Kernel::new(Scene::load(path)?)));
    }
    let inputs: Vec<&Path> = scene_files.iter().map(PathBuf::as_path).collect();
    output::file(&args.out, &inputs)?;
    for dir in figure_dirs(&plots) {
        output::folder(&dir, &PANELS, &inputs)?;
    }
    for name in SCENES {
        output::folder(&plots.join(name), &OUTPUTS, &inputs)?;
    }
    interrupt::keep(format!(
        "{} was not written (plots made so far are in {})",
        args.out.display(),
        plots.display()
    ));
    let mut progress = Progress {
        started: Instant::now(),
        stage: 0,
        stages: 4 + 2 * SCENES.len() + 2,
    };
    let references: Vec<_> = kernels.iter().map(|k| Arc::new(reference_of(k))).collect();
    let (fig3, fig3_reference) = (&kernels[0], &references[0]);

    progress.next("the default fit of fig3 for each preset, and its Fig. 3 panels")?;
    let mut headline = Vec::new();
    for (preset, dir) in Preset::ALL.into_iter().zip(figure_dirs(&plots)) {
        let fitted = fit(fig3, fig3_reference, preset_params(preset, 1))?;
        let label = format!("fig3, {} learner", preset.name());
        for (name, png) in
            crate::report::figure::panels(&fitted.fit, fig3_reference, &label, false)?
        {
            interrupt::writing(|| flatland_geom::write_atomic(&dir.join(name), &png))?;
        }
        headline.push((preset, fitted.summary));
    }
    progress.next("R1: cells near the jumps, θ against uniform resampling")?;
    let density = experiments::density(fig3, fig3_reference)?;
    progress.next("R2, R3: fig3 with every edge split in 1000")?;
    let subdivision = experiments::subdivision(fig3, fig3_reference, 1000)?;
    progress.next(&format!("θ against uniform resampling, {seeds} seed(s)"))?;
    let mut theta = Vec::new();
    for i in 0..2 {
        theta.extend(experiments::theta_against_uniform(
            SCENES[i],
            &kernels[i],
            &references[i],
            seeds,
        )?);
    }
    let mut ablations = Vec::new();
    for (i, name) in SCENES.iter().enumerate() {
        progress.next(&format!("ablation on {name}, {seeds} seed(s)"))?;
        ablations.push(experiments::ablation(
            name,
            &kernels[i],
            &references[i],
            seeds,
        )?);
    }
    let plan = experiments::plan(budgets, seeds);
    let mut benches = Vec::new();
    for (i, name) in SCENES.iter().enumerate() {
        progress.next(&format!("flatland bench on {name}"))?;
        let dir = plots.join(name);
        let defined = crate::Defined::of(&references[i]);
        benches.push(experiments::bench(
            name,
            &kernels[i],
            &references[i],
            &plan,
            |rows| write_outputs(&dir, name, rows, defined),
        )?);
    }
    progress.next(&format!("{rooms} random rooms at 400 basis functions"))?;
    let rooms = (1..=rooms)
        .map(experiments::room)
        .collect::<Result<Vec<_>>>()?;
    progress.next("the stability suite (flatland stress)")?;
    let stress = experiments::stress(args.quick)?;
    let findings = Findings {
        quick: args.quick,
        seeds,
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        headline,
        density,
        subdivision,
        theta,
        ablations,
        benches,
        rooms,
        stress,
        elapsed_s: progress.started.elapsed().as_secs_f64(),
    };
    let doc = render::document(&findings)?;
    interrupt::check()?;
    interrupt::writing(|| flatland_geom::write_atomic(&args.out, doc.as_bytes()))?;
    println!("wrote {} and {}", args.out.display(), plots.display());
    Ok(())
}

/// The Fig. 3 panel folders, one per preset in [`Preset::ALL`] order.
fn figure_dirs(plots: &Path) -> Vec<PathBuf> {
    Preset::ALL
        .iter()
        .map(|p| plots.join(format!("figure-{}", p.name())))
        .collect()
}
