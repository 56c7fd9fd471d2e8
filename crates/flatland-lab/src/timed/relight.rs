//! Relighting: ten lightings of one scene's geometry (the emitters rescaled or off, a wall
//! glowing), and the time each method takes to all ten lit scenes — the learners learn once
//! and re-solve with their operator, the exact solve builds its operator once, the tracer
//! traces every lighting from scratch.

use std::collections::HashMap;
use std::time::Instant;

use anyhow::{Context as _, Result};
use flatland_baselines::{LightTracer, Lighting, TraceBudget, TraceParams};
use flatland_geom::{EdgeId, Kernel, Scene};
use flatland_methods::Ask;
use flatland_solve::{
    ExactReference, FinalGather, FunctionReference, Mesh, SolveErrors, SolveParams,
    TransferOperator, solve_linear,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::compute::{Context, exact_operator_of};
use super::{Method, Setting, TimedRow};

/// Lightings of a relighting run.
pub const LIGHTINGS: usize = 10;

/// The chance that an emitter is off in a random lighting.
const OFF: f64 = 0.25;

/// One lighting of the scene: emission overrides per scene edge, and what they are in words.
#[derive(Clone, Debug, PartialEq)]
pub struct Relit {
    /// The overrides (the tracer's form).
    pub lighting: Lighting,
    /// What changed, for the CSV.
    pub description: String,
}

/// `count` lightings of `scene` drawn with `seed`: the first is the scene as it is, the last a
/// non-emitting surface edge glowing beside the emitters, the others each emitter's emission
/// times a factor in [0, 2], or off (at least one stays on).
pub fn lightings(scene: &Scene, count: usize, seed: u64) -> Vec<Relit> {
    let edge = |i: EdgeId| scene.edge(i);
    let surfaces = scene.surface_edges();
    let emitters: Vec<EdgeId> = surfaces
        .iter()
        .copied()
        .filter(|&i| edge(i).emission > 0.0)
        .collect();
    let dark: Vec<EdgeId> = surfaces
        .iter()
        .copied()
        .filter(|&i| edge(i).emission == 0.0 && edge(i).reflectance > 0.0)
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = vec![Relit {
        lighting: Lighting::default(),
        description: "as the scene is".to_owned(),
    }];
    for k in 1..count {
        let glow = k + 1 == count && !dark.is_empty() && !emitters.is_empty();
        if glow {
            let wall = dark[rng.random_range(0..dark.len())];
            let mean =
                emitters.iter().map(|&i| edge(i).emission).sum::<f64>() / emitters.len() as f64;
            out.push(Relit {
                lighting: Lighting::default().with_emission(wall, mean),
                description: format!("edge {wall} glowing at {mean:.3}"),
            });
            continue;
        }
        let mut lighting = Lighting::default();
        let mut on = 0;
        for &i in &emitters {
            let factor = if rng.random::<f64>() < OFF {
                0.0
            } else {
                2.0 * rng.random::<f64>()
            };
            on += usize::from(factor > 0.0);
            lighting = lighting.with_emission(i, factor * edge(i).emission);
        }
        if on == 0
            && let Some(&first) = emitters.first()
        {
            lighting = lighting.with_emission(first, edge(first).emission);
        }
        out.push(Relit {
            lighting,
            description: format!("emitters rescaled, {} of {} on", on.max(1), emitters.len()),
        });
    }
    out
}

/// `scene` lit by `lighting`: every piece of an overridden edge's mesh edge emitting as
/// asked (the tracer's rule).
fn relit_scene(scene: &Scene, mesh: &Mesh, lighting: &Lighting) -> Result<Scene> {
    let mut scene = scene.clone();
    for (edge, pieces) in overridden(mesh, lighting) {
        for piece in pieces {
            let mut e = scene.edges()[piece];
            e.emission = edge;
            scene = scene.with_edge(EdgeId::new(piece), e)?;
        }
    }
    Ok(scene)
}

/// Per override, its mesh edge (the one holding the overridden scene edge) and its emission.
fn overrides_by_mesh_edge(mesh: &Mesh, lighting: &Lighting) -> Vec<(usize, f64)> {
    let mesh_edge_of: HashMap<usize, usize> = mesh
        .edges()
        .iter()
        .enumerate()
        .flat_map(|(m, e)| e.pieces.clone().map(move |p| (p, m)))
        .collect();
    lighting
        .overrides()
        .iter()
        .filter_map(|&(edge, emission)| Some((*mesh_edge_of.get(&edge.index())?, emission)))
        .collect()
}

/// Per override, its emission and the scene edges (pieces) of its mesh edge.
fn overridden(mesh: &Mesh, lighting: &Lighting) -> Vec<(f64, Vec<usize>)> {
    overrides_by_mesh_edge(mesh, lighting)
        .into_iter()
        .map(|(m, emission)| (emission, mesh.edges()[m].pieces.clone().collect()))
        .collect()
}

/// `mesh` under `lighting`: each overridden mesh edge emitting as asked (the lights and their
/// direct light unchanged).
pub fn relit_mesh(mesh: &Mesh, lighting: &Lighting) -> Result<Mesh> {
    let mut emission: Vec<f64> = mesh.edges().iter().map(|e| e.emission).collect();
    for (m, e) in overrides_by_mesh_edge(mesh, lighting) {
        emission[m] = e;
    }
    Ok(mesh.with_edge_emission(&emission)?)
}

/// A method that could not relight, and why.
pub type Failure = (Method, String);

/// One method's lit scene under one lighting.
#[derive(Clone, Debug, PartialEq)]
pub struct RelightRow {
    /// The method.
    pub method: Method,
    /// Which lighting (0: the scene as it is).
    pub lighting: usize,
    /// Seconds spent on this lighting (the first includes building the representation).
    pub seconds: f64,
    /// Errors of its B against the exact B of this lighting.
    pub errors: SolveErrors,
    /// What the method was run at, and why.
    pub note: String,
}

/// The exact B of every lighting as a function: `mesh` under the lighting
/// ([`relit_mesh`]) and an independent solve of the relit scene on `reference_elements`,
/// gathered at that mesh's scoring points ([`FunctionReference`]), as the first lighting is
/// scored.
pub fn exact_lit(
    scene: &Scene,
    mesh: &Mesh,
    relits: &[Relit],
    reference_elements: usize,
    stop: &flatland_solve::Stop,
) -> Result<Vec<FunctionReference>> {
    relits
        .iter()
        .map(|relit| {
            let kernel = Kernel::new(relit_scene(scene, mesh, &relit.lighting)?);
            let fine =
                ExactReference::new(&kernel, reference_elements, &SolveParams::default(), stop)?;
            let relit = relit_mesh(mesh, &relit.lighting)?;
            Ok(FunctionReference::new(&fine, &relit, stop)?)
        })
        .collect()
}

/// How a method's element values are read as a function: as the line through their
/// midpoints, or (the exact solve) by its own final gather, as every single lighting is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Reading {
    Midpoints,
    Gathered,
}

/// The errors of `b` under the lighting of `reference`, read as `reading` says.
fn scored(
    cx: &Context<'_>,
    reference: &FunctionReference,
    b: &[f64],
    reading: Reading,
) -> Result<SolveErrors> {
    Ok(match reading {
        Reading::Midpoints => reference.errors(b),
        Reading::Gathered => {
            let gather = FinalGather::new(cx.kernel, reference.mesh())?;
            reference.gathered_errors(&gather, b, cx.stop)?
        }
    })
}

/// Solves every lighting (one reference each) with one operator; the first lighting's time
/// includes `build_s`.
fn resolved(
    method: Method,
    cx: &Context<'_>,
    op: &dyn TransferOperator,
    build_s: f64,
    exact: &[FunctionReference],
    note: &str,
    reading: Reading,
) -> Result<Vec<RelightRow>> {
    let mut rows = Vec::new();
    for (l, exact) in exact.iter().enumerate() {
        let started = Instant::now();
        // The relit mesh's emission: the lighting's, with the lamps' direct light.
        let e = exact.mesh().emission();
        let solution = solve_linear(op, &e, e.clone(), &SolveParams::default(), cx.stop)?;
        let seconds = started.elapsed().as_secs_f64() + if l == 0 { build_s } else { 0.0 };
        rows.push(RelightRow {
            method,
            lighting: l,
            seconds,
            errors: scored(cx, exact, &solution.radiosity, reading)?,
            note: note.to_owned(),
        });
    }
    Ok(rows)
}

/// The light-driven learner at `tolerance`, learned on the first lighting and re-solved with
/// its operator for the others.
fn default_relit(
    cx: &Context<'_>,
    tolerance: f64,
    exact: &[FunctionReference],
) -> Result<Vec<RelightRow>> {
    let started = Instant::now();
    let (_, built) = cx.light(tolerance)?;
    let op = built
        .rep
        .operator(cx.scorer.mesh(), &SolveParams::default(), cx.stop)?;
    let build_s = started.elapsed().as_secs_f64();
    let note = format!("learned once at tolerance {tolerance}");
    resolved(
        Method::Light,
        cx,
        op.as_ref(),
        build_s,
        exact,
        &note,
        Reading::Midpoints,
    )
}

/// The exact operator built once, solved for every lighting.
fn exact_relit(cx: &Context<'_>, exact: &[FunctionReference]) -> Result<Vec<RelightRow>> {
    let started = Instant::now();
    let (op, _) = exact_operator_of(cx.kernel, cx.scorer.mesh(), cx.stop)?;
    let build_s = started.elapsed().as_secs_f64();
    let note = format!("{} elements", cx.scorer.mesh().len());
    resolved(
        Method::Exact,
        cx,
        op.as_ref(),
        build_s,
        exact,
        &note,
        Reading::Gathered,
    )
}

/// The first of `rows` (of one method, in sweep order) whose solved error is at most `target`,
/// or the most accurate when none is, with a note saying which.
fn matching(rows: &[TimedRow], method: Method, target: f64) -> Option<(Setting, String)> {
    let mine: Vec<&TimedRow> = rows
        .iter()
        .filter(|r| r.method == method && !r.failed && r.solve.is_some())
        .collect();
    let error = |r: &&TimedRow| r.reflected_error().unwrap_or(f64::INFINITY);
    if let Some(r) = mine.iter().find(|r| error(r) <= target) {
        let note = format!(
            "{} {}: the first to match default's error",
            r.setting.kind(),
            r.setting.value()
        );
        return Some((r.setting, note));
    }
    let best = mine.iter().min_by(|a, b| error(a).total_cmp(&error(b)))?;
    let note = format!(
        "{} {}: its best row, never as close as default",
        best.setting.kind(),
        best.setting.value()
    );
    Some((best.setting, note))
}

/// HR or clustered HR built once at the budget that matched the learner's error, solved for every lighting.
fn links_relit(
    cx: &Context<'_>,
    method: Method,
    budget: usize,
    note: &str,
    exact: &[FunctionReference],
) -> Result<Vec<RelightRow>> {
    let started = Instant::now();
    let ask = Ask {
        basis: Some(budget),
        ..Ask::new(method)
    };
    let built = cx.build(ask)?;
    let op = built
        .rep
        .operator(cx.scorer.mesh(), &SolveParams::default(), cx.stop)?;
    let build_s = started.elapsed().as_secs_f64();
    resolved(
        method,
        cx,
        op.as_ref(),
        build_s,
        exact,
        note,
        Reading::Midpoints,
    )
}

/// The tracer at the photon count that matched the learner's error, tracing every lighting.
fn tracer_relit(
    cx: &Context<'_>,
    photons: u64,
    note: &str,
    relits: &[Relit],
    exact: &[FunctionReference],
) -> Result<Vec<RelightRow>> {
    let tracer = LightTracer::new(cx.kernel, cx.scorer.mesh())?;
    let params = TraceParams {
        budget: TraceBudget::Photons(photons),
        seed: 1,
    };
    let mut rows = Vec::new();
    for (l, (relit, exact)) in relits.iter().zip(exact).enumerate() {
        let started = Instant::now();
        let traced = tracer.trace(&relit.lighting, &params, cx.stop)?;
        rows.push(RelightRow {
            method: Method::Tracer,
            lighting: l,
            seconds: started.elapsed().as_secs_f64(),
            errors: scored(cx, exact, &traced.radiosity, Reading::Midpoints)?,
            note: note.to_owned(),
        });
    }
    Ok(rows)
}

/// A method's relighting: its total time and errors over the lightings.
#[derive(Clone, Debug, PartialEq)]
pub struct RelightSummary {
    /// The method.
    pub method: Method,
    /// Seconds to all the lit scenes: the sum of its rows' seconds.
    pub total_s: f64,
    /// The mean relative L2 error of `B − E` over the lightings.
    pub mean_error: f64,
    /// The largest.
    pub max_error: f64,
    /// What it was run at (or why it failed).
    pub note: String,
}

/// Per method with rows, the total time and the errors.
pub fn summaries(rows: &[RelightRow]) -> Vec<RelightSummary> {
    let mut out: Vec<RelightSummary> = Vec::new();
    for r in rows {
        let e = r.errors.rel_l2_reflected;
        match out.iter_mut().find(|s| s.method == r.method) {
            Some(s) => {
                s.total_s += r.seconds;
                s.mean_error += e;
                s.max_error = s.max_error.max(e);
            }
            None => out.push(RelightSummary {
                method: r.method,
                total_s: r.seconds,
                mean_error: e,
                max_error: e,
                note: r.note.clone(),
            }),
        }
    }
    for s in &mut out {
        let n = rows.iter().filter(|r| r.method == s.method).count();
        s.mean_error /= n as f64;
    }
    out
}

/// Relights `cx`'s scene under `relits` (the first its own lighting) with `default` at
/// `tolerance`, `exact`, and HR and the tracer at the settings of `sweep` (the timed bench's
/// rows) that matched default's error. A method that fails is reported in `failures` and left
/// out.
pub(crate) fn relight_all(
    cx: &Context<'_>,
    tolerance: f64,
    sweep: &[TimedRow],
    relits: &[Relit],
    exact: &[FunctionReference],
) -> (Vec<RelightRow>, Vec<Failure>) {
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    let asked = |method: Method| cx.plan.methods.contains(&method);
    let mut keep =
        |method, result: Result<Vec<RelightRow>>, rows: &mut Vec<RelightRow>| match result {
            Ok(r) => rows.extend(r),
            Err(e) => failures.push((method, format!("{e:#}"))),
        };
    let learned = if asked(Method::Light) {
        default_relit(cx, tolerance, exact)
    } else {
        Ok(Vec::new())
    };
    let target = learned
        .as_ref()
        .ok()
        .and_then(|r| r.first())
        .map_or(0.0, |r| r.errors.rel_l2_reflected);
    keep(Method::Light, learned, &mut rows);
    if asked(Method::Exact) {
        keep(Method::Exact, exact_relit(cx, exact), &mut rows);
    }
    for method in [Method::Hr, Method::Clustered] {
        if asked(method) {
            let result = match matching(sweep, method, target) {
                Some((Setting::Budget(b), note)) => links_relit(cx, method, b, &note, exact),
                _ => Err(anyhow::anyhow!(
                    "no {} row in the sweep to match",
                    method.name()
                )),
            };
            keep(method, result, &mut rows);
        }
    }
    if asked(Method::Tracer) {
        let result = match matching(sweep, Method::Tracer, target) {
            Some((Setting::Photons(p), note)) => tracer_relit(cx, p, &note, relits, exact),
            _ => Err(anyhow::anyhow!("no tracer row in the sweep to match")),
        };
        keep(Method::Tracer, result, &mut rows);
    }
    (rows, failures)
}

/// Relights `kernel`'s scene under `count` lightings: their exact B, then each method asked
/// for — `default` at its default tolerance, `exact`, and HR and the tracer at the settings of
/// `sweep` (the timed bench's rows) that matched default's error. A method that fails is
/// returned with its reason.
pub fn relight(
    scorer: &super::Scorer,
    kernel: &std::sync::Arc<Kernel>,
    plan: &super::TimedPlan,
    sweep: &[TimedRow],
    count: usize,
    stop: &flatland_solve::Stop,
) -> Result<(Vec<RelightRow>, Vec<Failure>)> {
    let cx = Context::new(kernel, scorer, plan, stop);
    let relits = lightings(kernel.scene(), count, 1);
    let mut exact = vec![scorer.lit().function_reference().clone()];
    let others = exact_lit(
        kernel.scene(),
        scorer.mesh(),
        &relits[1..],
        scorer.reference_elements(),
        stop,
    )
    .context("the exact solves of the lightings")?;
    exact.extend(others);
    let tolerance = flatland_light::LightParams::default().tolerance;
    Ok(relight_all(&cx, tolerance, sweep, &relits, &exact))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::timed::scorer::tiny;
    use crate::timed::{TimedPlan, run_timed};
    use flatland_solve::{LitParams, LitScene, never};
    use flatland_testkit::assert_close;
    use std::sync::Arc;

    #[test]
    fn ten_lightings_the_first_as_is_the_last_a_glowing_wall() {
        let scene = flatland_geom::bundled::scene("fig3").unwrap();
        let relits = lightings(&scene, LIGHTINGS, 1);
        assert_eq!(relits.len(), LIGHTINGS);
        assert!(relits[0].lighting.overrides().is_empty());
        let (wall, glow) = relits[LIGHTINGS - 1].lighting.overrides()[0];
        assert!(scene.edge(wall).emission == 0.0 && glow > 0.0);
        assert_eq!(lightings(&scene, LIGHTINGS, 1), relits, "seeded");
        for r in &relits[1..LIGHTINGS - 1] {
            assert!(
                r.lighting
                    .overrides()
                    .iter()
                    .all(|o| (0.0..=2.0 * scene.max_emission()).contains(&o.1))
            );
            assert!(
                r.lighting.overrides().iter().any(|o| o.1 > 0.0),
                "one stays on"
            );
        }
    }

    #[test]
    fn relighting_totals_are_the_sums_of_the_lightings() {
        let (kernel, scorer) = tiny();
        let mut plan = TimedPlan::new(Method::ALL.to_vec());
        plan.methods = vec![Method::Hr, Method::Clustered, Method::Tracer];
        plan.budgets = vec![200];
        plan.extend_budgets = false;
        plan.tracer_seconds = 0.1;
        plan.first_photons = 2_000;
        let sweep = run_timed(&kernel, &scorer, &plan, &never, |_| Ok(())).unwrap();
        plan.methods = Method::ALL.to_vec();
        let (rows, failures) = relight(&scorer, &kernel, &plan, &sweep, 4, &never).unwrap();
        assert!(failures.is_empty(), "{failures:?}");
        let all = summaries(&rows);
        let methods: Vec<Method> = all.iter().map(|s| s.method).collect();
        assert_eq!(
            methods,
            [
                Method::Light,
                Method::Exact,
                Method::Hr,
                Method::Clustered,
                Method::Tracer
            ]
        );
        for s in &all {
            let mine: Vec<&RelightRow> = rows.iter().filter(|r| r.method == s.method).collect();
            assert_eq!(mine.len(), 4);
            let total: f64 = mine.iter().map(|r| r.seconds).sum();
            assert_close!(total, s.total_s, 1e-12 * total.max(1.0), "{s:?}");
            assert!(mine.iter().all(|r| r.errors.rel_l2_reflected.is_finite()));
            assert!(s.max_error >= s.mean_error);
        }
        // The exact operator on the solve's mesh is close under every lighting (only its
        // discretization differs from the reference).
        let exact = all.iter().find(|s| s.method == Method::Exact).unwrap();
        assert!(exact.max_error < 0.2, "{exact:?}");
    }

    #[test]
    fn every_lighting_is_scored_as_a_function_on_the_lit_scenes_own_elements() {
        // The lit scene's mesh is refined where its first lighting needed it: an even mesh of
        // the same count puts its elements elsewhere, and compared there every other lighting
        // was ~100 % off (RESULTS.md's relighting lines read 0.7-1.08 before this test).
        let kernel = Arc::new(Kernel::new(
            flatland_geom::bundled::scene("floorplan").unwrap(),
        ));
        let lit = LitScene::new(Arc::clone(&kernel), &LitParams::default(), &never).unwrap();
        let scorer = crate::timed::scorer::Scorer::of_lit(lit);
        let mesh = scorer.mesh();
        let relits = lightings(kernel.scene(), LIGHTINGS, 1);
        let exact = exact_lit(
            kernel.scene(),
            mesh,
            &relits[1..],
            scorer.reference_elements(),
            &never,
        )
        .unwrap();
        let (op, _) = exact_operator_of(&kernel, mesh, &never).unwrap();
        let plan = crate::timed::TimedPlan::new(vec![Method::Exact]);
        let cx = Context::new(&kernel, &scorer, &plan, &never);
        for (relit, reference) in relits[1..].iter().zip(&exact) {
            assert_eq!(reference.mesh().len(), mesh.len());
            // The glowing wall glows in the reference's mesh, not in the scene's.
            for &(edge, e) in relit.lighting.overrides() {
                let m = reference
                    .mesh()
                    .edges()
                    .iter()
                    .position(|m| m.pieces.contains(&edge.index()))
                    .unwrap();
                assert_eq!(reference.mesh().edges()[m].emission, e);
            }
            let e = reference.mesh().emission();
            let params = SolveParams::default();
            let solved = solve_linear(op.as_ref(), &e, e.clone(), &params, &never).unwrap();
            let gathered = scored(&cx, reference, &solved.radiosity, Reading::Gathered).unwrap();
            let midpoints = scored(&cx, reference, &solved.radiosity, Reading::Midpoints).unwrap();
            // By its gather the exact solve is within the mesh's tolerance as the first
            // lighting is (1 %); read as a line through its midpoints it is worse.
            assert!(
                gathered.rel_l2_reflected < 0.02,
                "{}: {gathered:?}",
                relit.description
            );
            assert!(
                midpoints.rel_l2_reflected > gathered.rel_l2_reflected,
                "{}: {midpoints:?} vs {gathered:?}",
                relit.description
            );
        }
    }
}
