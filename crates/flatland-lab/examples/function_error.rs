//! The measurement behind docs/FUNCTION-ERROR.md: the error of the solved `B − E` read as a
//! function along the surfaces, for today's default (elements doubled until the estimate at
//! the collocation points is within 1 %, B read as steps) and for the function solve
//! (`solve_to_tolerance`: the final gather, the Gauss-refinement estimate, adapted meshes).
//!
//! ```text
//! cargo run --release -p flatland-lab --example function_error -- [--photons N] [--factor F] SCENE…
//! ```
//! A SCENE is a bundled name, `floorplan-EDGES-SEED` or `hall-EDGES-SEED` (generated;
//! `lampplan-` and `lamphall-` lit by point lights instead of emitting edges), a
//! `.json`/`.ron` file, any of them with `@RHO` to give every reflecting edge reflectance RHO.
//! Each prints one Markdown row. The truth is the final gather of a solve on the function
//! solve's mesh with every element cut into F (default 16; 4 above 1500 edges), at 8 evenly
//! spaced points per element of the mesh measured. With `--photons`, the Monte Carlo tracer
//! lights the same scene, its tallies kept per element of the function solve's mesh, and the gap of the reference's bin means
//! to it is printed with the tracer's own noise. With `--learner`, the light-driven learner on
//! the same mesh: its estimate against its errors (to standard error). With
//! `--untimed-doubling`, today's doubling to 1 % is counted, not timed.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use flatland_baselines::{TraceBudget, TraceParams, trace};
use flatland_geom::{Kernel, Scene};
use flatland_solve::{
    DEFAULT_ERROR_BOUND, Discretization, ExactReference, FunctionSolve, Mesh, SamplePoints,
    SolveParams, ToleranceParams, elements_for_error, never, solve_to_tolerance,
};

/// Points per element at which every function error is measured.
const POINTS: usize = 8;

fn scene(spec: &str) -> Result<Scene> {
    if let Some((base, rho)) = spec.rsplit_once('@') {
        let rho: f64 = rho.parse().context("reflectance after @")?;
        let edges = scene(base)?
            .edges()
            .iter()
            .map(|e| {
                let mut e = *e;
                if e.reflectance > 0.0 {
                    e.reflectance = rho;
                }
                e
            })
            .collect();
        return Ok(Scene::new(edges)?);
    }
    let generated = |rest: &str| -> Result<(usize, u64)> {
        let (n, seed) = rest.split_once('-').context("EDGES-SEED")?;
        Ok((n.parse()?, seed.parse()?))
    };
    if let Some(rest) = spec.strip_prefix("lampplan-") {
        let (n, seed) = generated(rest)?;
        return Ok(flatland_geom::generate::floor_plan_lit(n, seed)?);
    }
    if let Some(rest) = spec.strip_prefix("lamphall-") {
        let (n, seed) = generated(rest)?;
        return Ok(flatland_geom::generate::hall_lit(n, seed)?);
    }
    if let Some(rest) = spec.strip_prefix("floorplan-") {
        let (n, seed) = generated(rest)?;
        return Ok(flatland_geom::generate::floor_plan(n, seed)?);
    }
    if let Some(rest) = spec.strip_prefix("hall-") {
        let (n, seed) = generated(rest)?;
        return Ok(flatland_geom::generate::hall(n, seed)?);
    }
    if spec.ends_with(".json") || spec.ends_with(".ron") {
        return Ok(Scene::load(spec)?);
    }
    Ok(flatland_geom::bundled::scene(spec)?)
}

/// B read as steps (each element's value) at the sample points.
fn steps(mesh: &Mesh, b: &[f64], points: &SamplePoints) -> Vec<f64> {
    points.s.iter().map(|&s| b[mesh.element_at(s)]).collect()
}

fn seconds<T>(work: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
    let started = Instant::now();
    let value = work()?;
    Ok((value, started.elapsed().as_secs_f64()))
}

struct Row {
    spec: String,
    edges: usize,
    today: Discretization,
    today_s: f64,
    today_steps: f64,
    ours_elements: usize,
    ours_rounds: usize,
    ours_s: f64,
    ours_true: f64,
    ours_estimate: f64,
    reference_elements: usize,
    tracer: Option<String>,
    learner: Option<String>,
    /// Today's doubling continued until its steps would be within 1 % (their error halves
    /// with each doubling), and the seconds of its last step alone (the solves on that count
    /// and twice it, and their comparison): a lower bound on its whole time.
    today_for_tolerance: (usize, Option<f64>),
}

fn measure(
    spec: &str,
    factor: Option<usize>,
    photons: u64,
    learner: bool,
    timed_doubling: bool,
) -> Result<Row> {
    let kernel = Kernel::new(scene(spec)?);
    let params = SolveParams::default();
    let edges = kernel.scene().edges().len();
    let (today, today_s) = seconds(|| {
        Ok(elements_for_error(
            &kernel,
            DEFAULT_ERROR_BOUND,
            &params,
            &never,
        )?)
    })?;
    let (ours, ours_s) = seconds(|| {
        Ok(solve_to_tolerance(
            &kernel,
            &ToleranceParams::default(),
            &params,
            &never,
        )?)
    })?;
    let solve: &FunctionSolve = &ours.solve;
    let mesh = solve.coarse.mesh();
    let factor = factor.unwrap_or(if edges > 1500 { 4 } else { 16 });
    let reference = ExactReference::on_mesh(
        &kernel,
        mesh.split(&kernel, &vec![factor; mesh.len()])?,
        &params,
        &never,
    )?;
    let truth_on = |mesh: &Mesh| -> Result<(SamplePoints, Vec<f64>)> {
        let points = SamplePoints::evenly(mesh, POINTS);
        let exact = reference.radiosity_at(&points.s, &never)?;
        Ok((points, exact))
    };
    let (points, exact) = truth_on(today.coarse.mesh())?;
    let today_steps = points.relative_l2_reflected(
        &steps(
            today.coarse.mesh(),
            &today.coarse.solution().radiosity,
            &points,
        ),
        &exact,
    );
    let (points, exact) = truth_on(mesh)?;
    let ours_true = points.relative_l2_reflected(&solve.radiosity_at(&points.s, &never)?, &exact);
    let (needed, needed_s) = doubling_for_tolerance(&kernel, &today, today_steps, timed_doubling)?;
    let learner = learner
        .then(|| learner_errors(&kernel, solve, &reference))
        .transpose()?;
    let tracer = (photons > 0)
        .then(|| tracer_gap(&kernel, solve, &reference, photons))
        .transpose()?;
    Ok(Row {
        spec: spec.to_owned(),
        edges,
        today_s,
        today_steps,
        ours_elements: mesh.len(),
        ours_rounds: ours.rounds.len(),
        ours_s,
        ours_true,
        ours_estimate: solve.estimate.estimate,
        reference_elements: reference.mesh().len(),
        tracer,
        learner,
        today,
        today_for_tolerance: (needed, needed_s),
    })
}

/// The elements today's doubling would need for its steps to reach 1 % (their error halves
/// with each doubling), and, when asked and affordable, the seconds of that doubling's last
/// step alone.
fn doubling_for_tolerance(
    kernel: &Kernel,
    today: &Discretization,
    today_steps: f64,
    timed: bool,
) -> Result<(usize, Option<f64>)> {
    let params = SolveParams::default();
    let doublings = (today_steps / DEFAULT_ERROR_BOUND).log2().ceil().max(0.0) as u32;
    let needed = today.coarse.mesh().len() << doublings;
    if !(timed && needed <= 40_000 && doublings > 0) {
        return Ok((needed, None));
    }
    let (_, s) = seconds(|| {
        let coarse = ExactReference::new(kernel, needed, &params, &never)?;
        Ok(Discretization::of(coarse, kernel, &params, &never)?)
    })?;
    Ok((needed, Some(s)))
}

/// The light-driven learner (`flatland_light::LightFit`, default parameters) on the function
/// solve's mesh: its own estimate, its error on the same elements against the exact solve
/// there (what the estimate is about), and its B read as a function (the exact final gather
/// of its element values) against the reference.
fn learner_errors(
    kernel: &Kernel,
    solve: &FunctionSolve,
    reference: &ExactReference,
) -> Result<String> {
    let mesh = solve.coarse.mesh();
    let shared = std::sync::Arc::new(Kernel::new(kernel.scene().clone()));
    let mut fit = flatland_light::LightFit::new(shared, mesh.clone(), Default::default())?;
    let (stopped, s) = seconds(|| Ok(fit.run(&never, |_| {})?))?;
    let estimate = fit.estimated_error().unwrap_or(f64::NAN);
    let on_elements =
        flatland_solve::solve_errors(mesh, fit.radiosity(), &solve.coarse.solution().radiosity)
            .rel_l2_reflected;
    let points = SamplePoints::evenly(mesh, POINTS);
    let exact = reference.radiosity_at(&points.s, &never)?;
    let gathered = solve.gather.at(fit.radiosity(), &points.s, &never)?;
    let as_function = points.relative_l2_reflected(&gathered, &exact);
    let as_steps = points.relative_l2_reflected(&steps(mesh, fit.radiosity(), &points), &exact);
    Ok(format!(
        "learner {s:.2}s ({stopped:?}): estimate {estimate:.4}, error on the elements {on_elements:.4} (ratio {:.2}); as a function (exact gather of its values) {as_function:.4}, as steps {as_steps:.4}",
        estimate / on_elements
    ))
}

/// The tracer on the elements of the function solve's mesh as bins: the gap of the
/// reference's and the function solve's bin means to it, and its noise (all relative L2 of
/// `B − E`).
fn tracer_gap(
    kernel: &Kernel,
    solve: &FunctionSolve,
    reference: &ExactReference,
    photons: u64,
) -> Result<String> {
    let mesh = solve.coarse.mesh();
    let bins = mesh.clone();
    let params = TraceParams {
        budget: TraceBudget::Photons(photons),
        seed: 7,
    };
    let traced = trace(kernel, &bins, &params, &never)?;
    // Bin means of a function by 16 points per bin (the tracer's are exact in expectation).
    let inside = SamplePoints::evenly(&bins, 16);
    let mean = |values: Vec<f64>| -> Vec<f64> {
        values
            .chunks(16)
            .map(|c| c.iter().sum::<f64>() / 16.0)
            .collect()
    };
    let reference_means = mean(reference.radiosity_at(&inside.s, &never)?);
    let solve_means = mean(solve.radiosity_at(&inside.s, &never)?);
    let per_bin = SamplePoints::evenly(&bins, 1);
    // The noise: the standard errors' L2 against B − E's.
    let norm: f64 = traced
        .radiosity
        .iter()
        .zip(&per_bin.emission)
        .zip(&per_bin.weights)
        .map(|((b, e), w)| w * (b - e) * (b - e))
        .sum();
    let noise2: f64 = traced
        .std_error
        .iter()
        .zip(&per_bin.weights)
        .map(|(s, w)| w * s * s)
        .sum();
    let noise = (noise2 / norm).sqrt();
    let gap = per_bin.relative_l2_reflected(&reference_means, &traced.radiosity);
    let beyond = (gap * gap - noise * noise).max(0.0).sqrt();
    let ours = per_bin.relative_l2_reflected(&solve_means, &traced.radiosity);
    Ok(format!(
        "{:.1e} photons: reference {gap:.4} (noise {noise:.4}, beyond it {beyond:.4}), function solve {ours:.4}",
        photons as f64
    ))
}

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let (mut photons, mut factor, mut learner, mut specs) = (0, None, false, Vec::new());
    let mut timed_doubling = true;
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--photons" => photons = args.next().context("--photons N")?.parse()?,
            "--factor" => factor = Some(args.next().context("--factor F")?.parse()?),
            "--learner" => learner = true,
            "--untimed-doubling" => timed_doubling = false,
            _ if arg.starts_with("--") => bail!("unknown option {arg}"),
            _ => specs.push(arg),
        }
    }
    println!(
        "| scene | edges | today: elements | s | estimate | steps' error | ratio | today for 1 %: elements | s (≥) | function solve: elements (rounds) | s | error | estimate | ratio | reference | tracer |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for spec in specs {
        let r = measure(&spec, factor, photons, learner, timed_doubling)
            .with_context(|| spec.clone())?;
        let estimate = r.today.estimate.estimate;
        println!(
            "| {} | {} | {} | {:.2} | {:.4} | {:.4} | {:.2} | {} | {} | {} ({}) | {:.2} | {:.4} | {:.4} | {:.2} | {} | {} |",
            r.spec,
            r.edges,
            r.today.coarse.mesh().len(),
            r.today_s,
            estimate,
            r.today_steps,
            estimate / r.today_steps,
            r.today_for_tolerance.0,
            r.today_for_tolerance
                .1
                .map_or("—".to_owned(), |s| format!("{s:.2}")),
            r.ours_elements,
            r.ours_rounds,
            r.ours_s,
            r.ours_true,
            r.ours_estimate,
            r.ours_estimate / r.ours_true,
            r.reference_elements,
            r.tracer.as_deref().unwrap_or("—"),
        );
        if let Some(learner) = &r.learner {
            eprintln!("{}: {learner}", r.spec);
        }
    }
    Ok(())
}
