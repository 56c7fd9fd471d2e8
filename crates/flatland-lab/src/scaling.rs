//! Cost against scene size: every method with its default arguments on generated floor plans
//! and halls of growing size — time to the lit scene, the peak memory it added, rays, and the
//! error of its solved `B − E` against the exact reference `flatland solve` uses — and the log–log
//! slopes of time and memory against edges (`flatland bench --scaling`).
//!
//! Every scene is measured as `flatland solve` measures it: the mesh refined until the exact
//! B as a function is estimated within 1 %, and the finer solve of that estimate is the
//! reference. A method whose time at the next size, extrapolated from its smaller sizes, is
//! over the time budget is skipped there with a row that says so, rather than run for hours.

mod slopes;

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context as _, Result};
use flatland_geom::Kernel;
use flatland_geom::generate::{GenerateParams, SceneKind, generate};
use flatland_solve::{LitParams, LitScene, Stop};

pub use slopes::{Slope, slopes};

use crate::memory;
use crate::timed::compute::Context;
use crate::timed::relight::{RelightSummary, relight, summaries};
use crate::timed::{Method, Scorer, Setting, TimedPlan, TimedRow};

/// The sizes (edges asked of the generator) measured by default.
pub const DEFAULT_SIZES: [usize; 3] = [100, 1_000, 10_000];

/// A method is skipped at a size where its extrapolated time is above this many seconds.
pub const DEFAULT_MAX_SECONDS: f64 = 120.0;

/// The slope assumed for a method measured at one size only: quadratic, as a method that links
/// every pair of edges grows, so a method is never run for hours on a guess.
const FIRST_SLOPE: f64 = 2.0;

/// The methods a scaling run can measure: each one's default, as `flatland solve` builds it.
pub const METHODS: [Method; 5] = [
    Method::Light,
    Method::Exact,
    Method::Hr,
    Method::Clustered,
    Method::Tracer,
];

/// What a scaling run measures.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalingPlan {
    /// Kinds of generated scene.
    pub kinds: Vec<SceneKind>,
    /// Sizes, in edges asked of the generator, ascending.
    pub sizes: Vec<usize>,
    /// The generator's seed.
    pub seed: u64,
    /// Methods, of [`METHODS`]; the tracer runs for as long as the light-driven learner took (ten
    /// seconds without it).
    pub methods: Vec<Method>,
    /// Extrapolated seconds above which a method is skipped at a size.
    pub max_seconds: f64,
    /// Lightings of the relighting comparison per scene (0: none).
    pub lightings: usize,
    /// Largest scene size (edges asked of the generator, which lands within a fifth of it)
    /// relit: each lighting costs an exact reference solve.
    pub relight_max_edges: usize,
}

impl ScalingPlan {
    /// Floor plans and halls of [`DEFAULT_SIZES`], every method, ten lightings up to 10⁴ edges.
    pub fn new() -> ScalingPlan {
        ScalingPlan {
            kinds: vec![SceneKind::FloorPlan, SceneKind::Hall],
            sizes: DEFAULT_SIZES.to_vec(),
            seed: 101,
            methods: METHODS.to_vec(),
            max_seconds: DEFAULT_MAX_SECONDS,
            lightings: crate::timed::relight::LIGHTINGS,
            relight_max_edges: 10_000,
        }
    }

    /// Checks the plan; errors name the parameter and the valid range.
    pub fn validate(&self) -> Result<(), crate::LabError> {
        let bad = |name, value: String, valid| {
            Err(crate::LabError::InvalidParameter { name, value, valid })
        };
        if self.kinds.is_empty() {
            return bad("kinds", "(none)".into(), "floorplan, hall or both");
        }
        if self.sizes.is_empty() || !self.sizes.windows(2).all(|w| w[0] < w[1]) {
            return bad(
                "sizes",
                format!("{:?}", self.sizes),
                "at least one, ascending without repeats",
            );
        }
        for &size in &self.sizes {
            let params = GenerateParams {
                kind: self.kinds[0],
                edges: size,
                seed: self.seed,
            };
            if params.check().is_err() {
                return bad(
                    "sizes",
                    size.to_string(),
                    "each in [24, 1000000] (what the generator builds)",
                );
            }
        }
        if let Some(m) = self.methods.iter().find(|m| !METHODS.contains(m)) {
            return bad(
                "methods",
                m.name().to_owned(),
                "a comma-separated list of default, exact, hr, clustered, tracer",
            );
        }
        if self.methods.is_empty() {
            return bad("methods", "(none)".into(), "at least one method");
        }
        if self.max_seconds.is_nan() || self.max_seconds <= 0.0 {
            return bad("max-seconds", self.max_seconds.to_string(), "more than 0");
        }
        if self.lightings > 1000 {
            return bad("lightings", self.lightings.to_string(), "in [0, 1000]");
        }
        Ok(())
    }
}

impl Default for ScalingPlan {
    fn default() -> Self {
        ScalingPlan::new()
    }
}

/// The scene a row was measured on.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaledScene {
    /// `floorplan-1000`: the kind and the size asked for.
    pub name: String,
    /// The kind.
    pub kind: SceneKind,
    /// Edges the generator built.
    pub edges: usize,
    /// Elements every method solves on.
    pub elements: usize,
    /// Elements of the reference.
    pub reference_elements: usize,
    /// Seconds to choose the mesh and solve the reference (the exact solves on N and 2N).
    pub reference_s: f64,
    /// The peak memory the reference added, bytes.
    pub reference_peak: Option<u64>,
}

/// One method on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalingRow {
    /// The scene (index into [`Scaling::scenes`]).
    pub scene: usize,
    /// The method's row, as the timed bench measures it.
    pub row: TimedRow,
    /// The peak memory the method added over what the process held before it, bytes.
    pub peak: Option<u64>,
    /// Whether it was skipped (its note says why).
    pub skipped: bool,
}

/// Everything a scaling run measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scaling {
    /// The scenes, in the order measured.
    pub scenes: Vec<ScaledScene>,
    /// The rows.
    pub rows: Vec<ScalingRow>,
    /// Relighting per scene: its index and each method's summary.
    pub relit: Vec<(usize, Vec<RelightSummary>)>,
}

/// A measurement and the heap's peak above what was held before it.
fn measured<T>(work: impl FnOnce() -> T) -> (T, Option<u64>) {
    memory::heap_peak_of(work)
}

/// Runs the plan; `kept` is called with everything so far after each row (so it is on disk
/// before the next starts) and `progress` with a line per stage. Ctrl-C (`stop`) ends the run
/// between rows with what is done kept.
pub fn run_scaling(
    plan: &ScalingPlan,
    stop: &Stop,
    mut progress: impl FnMut(&str),
    mut kept: impl FnMut(&Scaling) -> Result<()>,
) -> Result<Scaling> {
    plan.validate()?;
    let mut all = Scaling::default();
    for &kind in &plan.kinds {
        for &size in &plan.sizes {
            let name = format!("{}-{size}", kind_name(kind));
            progress(&format!("{name}: generating and solving the reference"));
            let scene = generate(&GenerateParams {
                kind,
                edges: size,
                seed: plan.seed,
            })?;
            let kernel = Arc::new(Kernel::new(scene));
            let started = Instant::now();
            let (lit, reference_peak) =
                measured(|| LitScene::new(Arc::clone(&kernel), &LitParams::default(), stop));
            let lit = lit.with_context(|| format!("{name}: the exact reference"))?;
            let index = all.scenes.len();
            all.scenes.push(ScaledScene {
                name: name.clone(),
                kind,
                edges: kernel.scene().edges().len(),
                elements: lit.mesh().len(),
                reference_elements: lit.reference().mesh().len(),
                reference_s: started.elapsed().as_secs_f64(),
                reference_peak,
            });
            let scorer = Scorer::of_lit(lit);
            scene_rows(
                plan,
                &kernel,
                &scorer,
                index,
                stop,
                &mut all,
                &mut progress,
                &mut kept,
            )?;
            if plan.lightings > 0 && size <= plan.relight_max_edges {
                progress(&format!(
                    "{name}: relighting ({} lightings)",
                    plan.lightings
                ));
                let timed = timed_plan(plan);
                let sweep: Vec<TimedRow> = all
                    .rows
                    .iter()
                    .filter(|r| r.scene == index && !r.skipped)
                    .map(|r| r.row.clone())
                    .collect();
                let (rows, failures) =
                    relight(&scorer, &kernel, &timed, &sweep, plan.lightings, stop)?;
                for (method, why) in failures {
                    progress(&format!(
                        "{name}: {} could not relight: {why}",
                        method.name()
                    ));
                }
                all.relit.push((index, summaries(&rows)));
                kept(&all)?;
            }
        }
    }
    Ok(all)
}

/// Every method's row on one scene.
#[allow(clippy::too_many_arguments)]
fn scene_rows(
    plan: &ScalingPlan,
    kernel: &Arc<Kernel>,
    scorer: &Scorer,
    scene: usize,
    stop: &Stop,
    all: &mut Scaling,
    progress: &mut impl FnMut(&str),
    kept: &mut impl FnMut(&Scaling) -> Result<()>,
) -> Result<()> {
    let timed = timed_plan(plan);
    let cx = Context::new(kernel, scorer, &timed, stop);
    let name = all.scenes[scene].name.clone();
    let edges = all.scenes[scene].edges;
    for &method in &plan.methods {
        let row = match predicted(all, method, all.scenes[scene].kind, edges) {
            Some(seconds) if seconds > plan.max_seconds => {
                let mut row = TimedRow::new(method, setting_of(method, scorer, edges), 1);
                row.add_note(&format!(
                    "skipped: extrapolated to {seconds:.0} s from the smaller scenes, over \
                     --max-seconds {}",
                    plan.max_seconds
                ));
                ScalingRow {
                    scene,
                    row,
                    peak: None,
                    skipped: true,
                }
            }
            _ => {
                progress(&format!("{name}: {}", method.name()));
                let equal_time = all
                    .rows
                    .iter()
                    .find(|r| r.scene == scene && r.row.method == Method::Light && !r.skipped)
                    .map_or(10.0, |r| r.row.total_s.max(0.01));
                let (row, peak) = measured(|| one(&cx, method, equal_time));
                ScalingRow {
                    scene,
                    row,
                    peak,
                    skipped: false,
                }
            }
        };
        crate::interrupt::check()?;
        anyhow::ensure!(!stop(), "stopped");
        let r = &row.row;
        progress(&format!(
            "{name}: {} {} in {:.2} s, B − E error {}",
            method.name(),
            if row.skipped { "skipped" } else { "done" },
            r.total_s,
            r.reflected_error()
                .map_or("–".into(), |e| format!("{e:.4}"))
        ));
        all.rows.push(row);
        kept(all)?;
    }
    Ok(())
}

/// The row of `method` with its default arguments (the tracer for `equal_time` seconds), or a
/// failed row saying why.
fn one(cx: &Context<'_>, method: Method, equal_time: f64) -> TimedRow {
    let setting = setting_of(method, cx.scorer, cx.kernel.scene().edges().len());
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match method {
        Method::Light => cx
            .light(flatland_light::LightParams::default().tolerance)
            .map(|r| r.0),
        Method::Exact => cx.exact(cx.scorer.mesh().len()),
        Method::Hr => cx.baseline(Method::Hr, HR_BASIS, 1),
        Method::Clustered => cx.baseline(
            Method::Clustered,
            flatland_baselines::DEFAULT_LINKS_PER_EDGE * cx.kernel.scene().edges().len(),
            1,
        ),
        Method::Tracer => cx.tracer_for(equal_time, 1).map(|mut row| {
            row.add_note("as long as the light-driven learner took");
            row
        }),
        _ => Err(anyhow::anyhow!(
            "{} is not measured at scale",
            method.name()
        )),
    }));
    match result {
        Ok(Ok(row)) => row,
        Ok(Err(e)) => TimedRow::failed(method, setting, 1, &format!("{e:#}")),
        Err(_) => TimedRow::failed(method, setting, 1, "panicked"),
    }
}

/// HR's links, as `flatland solve --kernel hr` builds by default (its initial linking where
/// that is more).
const HR_BASIS: usize = 400;

/// What `method` is run at, for its row's setting.
fn setting_of(method: Method, scorer: &Scorer, edges: usize) -> Setting {
    match method {
        Method::Light => Setting::Tolerance(flatland_light::LightParams::default().tolerance),
        Method::Exact => Setting::Elements(scorer.mesh().len()),
        Method::Tracer => Setting::Photons(0),
        Method::Clustered => Setting::Budget(flatland_baselines::DEFAULT_LINKS_PER_EDGE * edges),
        _ => Setting::Budget(HR_BASIS),
    }
}

/// The timed bench's plan the rows are computed under: a learner stopped by the time budget.
fn timed_plan(plan: &ScalingPlan) -> TimedPlan {
    let mut timed = TimedPlan::new(plan.methods.clone());
    timed.max_seconds = plan.max_seconds;
    timed
}

/// `method`'s time at `edges`, extrapolated from its rows on smaller scenes of `kind` (the
/// slope of its last two, at least 1, or [`FIRST_SLOPE`] from one); `None` without any.
fn predicted(all: &Scaling, method: Method, kind: SceneKind, edges: usize) -> Option<f64> {
    let mine: Vec<(f64, f64)> = all
        .rows
        .iter()
        .filter(|r| r.row.method == method && !r.skipped && !r.row.failed)
        .filter(|r| all.scenes[r.scene].kind == kind && all.scenes[r.scene].edges < edges)
        .map(|r| (all.scenes[r.scene].edges as f64, r.row.total_s.max(1e-3)))
        .collect();
    let &(n1, t1) = mine.last()?;
    let slope = match mine.len() {
        1 => FIRST_SLOPE,
        k => {
            let (n0, t0) = mine[k - 2];
            ((t1 / t0).ln() / (n1 / n0).ln()).max(1.0)
        }
    };
    Some(t1 * (edges as f64 / n1).powf(slope))
}

/// The name `flatland scene` gives a kind.
pub fn kind_name(kind: SceneKind) -> &'static str {
    match kind {
        SceneKind::FloorPlan => "floorplan",
        SceneKind::Hall => "hall",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flatland_solve::never;
    use flatland_testkit::assert_close;

    #[test]
    fn small_scenes_give_a_row_per_method_and_relighting() {
        let plan = ScalingPlan {
            kinds: vec![SceneKind::FloorPlan],
            sizes: vec![40, 80],
            lightings: 2,
            ..ScalingPlan::new()
        };
        let mut calls = 0;
        let all = run_scaling(
            &plan,
            &never,
            |_| {},
            |_| {
                calls += 1;
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(all.scenes.len(), 2);
        assert_eq!(all.rows.len(), 2 * METHODS.len());
        assert_eq!(
            calls,
            all.rows.len() + 2,
            "kept after every row and relighting"
        );
        for r in &all.rows {
            assert!(!r.row.failed && !r.skipped, "{r:?}");
            let e = r.row.reflected_error().expect("solved");
            assert!(e.is_finite() && e < 0.5, "{r:?}");
            assert!(r.row.total_s > 0.0, "{r:?}");
        }
        // The exact solve on the chosen mesh is within the discretization bound of the
        // reference, the finer solve of its estimate (with room: the bound is on an estimate).
        for r in all.rows.iter().filter(|r| r.row.method == Method::Exact) {
            assert!(
                r.row.reflected_error().unwrap() < 2.0 * flatland_solve::DEFAULT_ERROR_BOUND,
                "{r:?}"
            );
        }
        assert_eq!(all.relit.len(), 2);
        for (_, summaries) in &all.relit {
            assert!(summaries.iter().any(|s| s.method == Method::Light));
        }
    }

    #[test]
    fn a_method_predicted_over_the_budget_is_skipped_with_a_note() {
        let mut all = Scaling::default();
        for (edges, seconds) in [(100, 1.0), (1000, 10.0)] {
            all.scenes.push(ScaledScene {
                name: format!("hall-{edges}"),
                kind: SceneKind::Hall,
                edges,
                elements: 0,
                reference_elements: 0,
                reference_s: 0.0,
                reference_peak: None,
            });
            let mut row = TimedRow::new(Method::Hr, Setting::Budget(400), 1);
            row.total_s = seconds;
            all.rows.push(ScalingRow {
                scene: all.scenes.len() - 1,
                row,
                peak: None,
                skipped: false,
            });
        }
        // Linear from 100 to 1000 edges: 100 s at 10⁴.
        let p = predicted(&all, Method::Hr, SceneKind::Hall, 10_000).unwrap();
        assert_close!(p, 100.0, 1e-9);
        // Nothing measured on floor plans: no prediction.
        assert_eq!(
            predicted(&all, Method::Hr, SceneKind::FloorPlan, 10_000),
            None
        );
        // One size only: quadratic.
        all.rows.pop();
        let p = predicted(&all, Method::Hr, SceneKind::Hall, 1000).unwrap();
        assert_close!(p, 100.0, 1e-9);
    }

    #[test]
    fn bad_plans_are_refused_with_the_parameter_named() {
        for (plan, name) in [
            (
                ScalingPlan {
                    sizes: vec![1000, 100],
                    ..ScalingPlan::new()
                },
                "sizes",
            ),
            (
                ScalingPlan {
                    sizes: vec![10],
                    ..ScalingPlan::new()
                },
                "[24, 1000000]",
            ),
            (
                ScalingPlan {
                    methods: vec![Method::Paper],
                    ..ScalingPlan::new()
                },
                "methods",
            ),
            (
                ScalingPlan {
                    max_seconds: 0.0,
                    ..ScalingPlan::new()
                },
                "max-seconds",
            ),
        ] {
            let msg = plan.validate().unwrap_err().to_string();
            assert!(msg.contains(name), "{msg}");
        }
    }
}
