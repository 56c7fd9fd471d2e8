//! `flatland results`: regenerate the results document (RESULTS.md and its plots) by running
//! every experiment the paper reports, and ours. `experiments` measure and return data;
//! `render` writes the document from it. Nothing in it is typed by hand.

mod experiments;
mod real;
mod relight;
mod render;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use flatland_geom::{Kernel, Scene};
use flatland_pictures::figure::PANELS;
use flatland_solve::Reference;
use kernel_fit::Preset;

use crate::report::r4::{OUTPUTS, write_outputs};
use crate::report::timed::{RESULTS, write_rows};
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
    /// The lit real scenes at equal time, and cost against scene size.
    pub real: real::Real,
    /// The moving lamp: `bench --relight`'s rows.
    pub relight: Vec<crate::timed::walk::WalkRow>,
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

/// How much `flatland results` measures: seeds per experiment, the bench's budgets, random rooms.
struct Sizes {
    seeds: u64,
    budgets: Vec<usize>,
    rooms: u64,
}

impl Sizes {
    fn of(quick: bool) -> Self {
        if quick {
            Self {
                seeds: 1,
                budgets: vec![50, 100, 200, 400],
                rooms: 2,
            }
        } else {
            Self {
                seeds: 3,
                budgets: vec![50, 100, 200, 400, 800],
                rooms: 6,
            }
        }
    }
}

/// The scenes' kernels and references, and the plots' folder, all outputs checked.
struct Inputs {
    kernels: Vec<Arc<Kernel>>,
    references: Vec<Arc<Reference>>,
    plots: PathBuf,
    /// The folder of the bundled scenes.
    scenes: PathBuf,
}

/// Runs `flatland results`.
pub fn run(args: &Options) -> Result<()> {
    let sizes = Sizes::of(args.quick);
    let mut progress = Progress {
        started: Instant::now(),
        stage: 0,
        stages: 4 + 2 * SCENES.len() + 2 + real::stages(args.quick) + 1,
    };
    let inputs = prepare(args)?;
    let findings = measure(&inputs, &sizes, args.quick, &mut progress)?;
    let doc = render::document(&findings)?;
    interrupt::check()?;
    interrupt::writing(|| flatland_geom::write_atomic(&args.out, doc.as_bytes()))?;
    println!(
        "wrote {} and {}",
        args.out.display(),
        inputs.plots.display()
    );
    Ok(())
}

/// Loads the scenes, checks every output path before any work, and says what Ctrl-C keeps.
fn prepare(args: &Options) -> Result<Inputs> {
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
    let walk = &crate::report::walk::OUTPUTS[2..];
    output::folder(&plots, walk, &inputs)?;
    interrupt::keep(format!(
        "{} was not written (plots made so far are in {})",
        args.out.display(),
        plots.display()
    ));
    let references = kernels.iter().map(|k| Arc::new(reference_of(k))).collect();
    Ok(Inputs {
        kernels,
        references,
        plots,
        scenes: args.scenes.clone(),
    })
}

/// Every experiment, in the document's order, one progress stage each.
fn measure(
    inputs: &Inputs,
    sizes: &Sizes,
    quick: bool,
    progress: &mut Progress,
) -> Result<Findings> {
    let Inputs {
        kernels,
        references,
        plots,
        ..
    } = inputs;
    let seeds = sizes.seeds;
    let (fig3, fig3_reference) = (&kernels[0], &references[0]);

    progress.next("the default fit of fig3 for each preset, and its Fig. 3 panels")?;
    let headline = headline(fig3, fig3_reference, plots)?;
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
    let benches = benches(inputs, sizes, progress)?;
    progress.next(&format!(
        "{} random rooms at 400 basis functions",
        sizes.rooms
    ))?;
    let rooms = (1..=sizes.rooms)
        .map(experiments::room)
        .collect::<Result<Vec<_>>>()?;
    progress.next("the stability suite (flatland stress)")?;
    let stress = experiments::stress(quick)?;
    let real = real::measure(&inputs.scenes, plots, quick, |what| progress.next(what))?;
    progress.next(&relight::stage(quick))?;
    let relight = relight::measure(plots, quick, &interrupt::requested)?;
    Ok(Findings {
        quick,
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
        real,
        relight,
        elapsed_s: progress.started.elapsed().as_secs_f64(),
    })
}

/// The default fit of fig3 for each preset; writes its Fig. 3 panels.
fn headline(
    fig3: &Arc<Kernel>,
    reference: &Arc<Reference>,
    plots: &Path,
) -> Result<Vec<(Preset, kernel_fit::FitSummary)>> {
    let mut headline = Vec::new();
    for (preset, dir) in Preset::ALL.into_iter().zip(figure_dirs(plots)) {
        let fitted = fit(fig3, reference, preset_params(preset, 1))?;
        let label = format!("fig3, {} learner", preset.name());
        for (name, png) in crate::report::figure::panels(&fitted.fit, reference, &label, false)? {
            interrupt::writing(|| flatland_geom::write_atomic(&dir.join(name), &png))?;
        }
        headline.push((preset, fitted.summary));
    }
    Ok(headline)
}

/// `flatland bench` on every scene; writes its CSV and plots.
fn benches(inputs: &Inputs, sizes: &Sizes, progress: &mut Progress) -> Result<Vec<SceneBench>> {
    let plan = experiments::plan(sizes.budgets.clone(), sizes.seeds);
    let mut benches = Vec::new();
    for (i, name) in SCENES.iter().enumerate() {
        progress.next(&format!("flatland bench on {name}"))?;
        let dir = inputs.plots.join(name);
        let bench = experiments::bench(
            name,
            &inputs.kernels[i],
            &inputs.references[i],
            &plan,
            |rows| write_rows(&dir, RESULTS, name, rows),
        )?;
        write_outputs(&dir, name, &bench.rows)?;
        benches.push(bench);
    }
    Ok(benches)
}

/// The Fig. 3 panel folders, one per preset in [`Preset::ALL`] order.
fn figure_dirs(plots: &Path) -> Vec<PathBuf> {
    Preset::ALL
        .iter()
        .map(|p| plots.join(format!("figure-{}", p.name())))
        .collect()
}
