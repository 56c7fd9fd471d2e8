//! The measurement behind docs/FUNCTION-ERROR.md: the error of the solved `B − E` read as a
//! function along the surfaces for the function solve (`solve_to_tolerance`: the final
//! gather, the Gauss-refinement estimate, adapted meshes), against its estimate. (The older
//! default, the doubling to 1 % at the collocation points, was removed; its columns in the
//! doc come from this example at commit 22084a5.)
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
//! the same mesh, in a second table: its own estimate and the estimate with the mesh's error
//! as a function added (`flatland_light::LightEstimate`), against its errors on the elements,
//! read by the exact final gather (what the added estimate covers) and as the lit scene scores
//! it (the line through its midpoints, the lamps' direct light at the point).

use std::time::Instant;

use anyhow::{Context, Result, bail};
use flatland_baselines::{TraceBudget, TraceParams, trace};
use flatland_geom::{Kernel, Scene};
use flatland_solve::{
    ExactReference, FunctionReference, FunctionSolve, SamplePoints, SolveParams, ToleranceParams,
    never, solve_to_tolerance,
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

fn seconds<T>(work: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
    let started = Instant::now();
    let value = work()?;
    Ok((value, started.elapsed().as_secs_f64()))
}

struct Row {
    spec: String,
    edges: usize,
    ours_elements: usize,
    ours_rounds: usize,
    ours_s: f64,
    ours_true: f64,
    /// The same solve's element values read as the line through their midpoints.
    ours_line: f64,
    ours_estimate: f64,
    reference_elements: usize,
    tracer: Option<String>,
    learner: Option<String>,
}

fn measure(spec: &str, factor: Option<usize>, photons: u64, learner: bool) -> Result<Row> {
    let kernel = Kernel::new(scene(spec)?);
    let params = SolveParams::default();
    let edges = kernel.scene().edges().len();
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
    let points = SamplePoints::evenly(mesh, POINTS);
    let exact = reference.radiosity_at(&points.s, &never)?;
    let ours_true = points.relative_l2_reflected(&solve.radiosity_at(&points.s, &never)?, &exact);
    let ours_line = FunctionReference::new(&reference, mesh, &never)?
        .errors(&solve.coarse.solution().radiosity)
        .rel_l2_reflected;
    let learner = learner
        .then(|| learner_errors(&kernel, solve, &reference))
        .transpose()?;
    let tracer = (photons > 0)
        .then(|| tracer_gap(&kernel, solve, &reference, photons))
        .transpose()?;
    Ok(Row {
        spec: spec.to_owned(),
        edges,
        ours_elements: mesh.len(),
        ours_rounds: ours.rounds.len(),
        ours_s,
        ours_true,
        ours_line,
        ours_estimate: solve.estimate.estimate,
        reference_elements: reference.mesh().len(),
        tracer,
        learner,
    })
}

/// The light-driven learner (`flatland_light::LightFit`, default parameters) on the function
/// solve's mesh: its own estimate (against the exact solve on the same elements) and with the
/// mesh's error as a function added; its error on the elements, as the lit scene scores it
/// (the line through its midpoints), and read by the exact final gather of its values.
fn learner_errors(
    kernel: &Kernel,
    solve: &FunctionSolve,
    reference: &ExactReference,
) -> Result<String> {
    let mesh = solve.coarse.mesh();
    let shared = std::sync::Arc::new(Kernel::new(kernel.scene().clone()));
    let mut fit = flatland_light::LightFit::new(shared, mesh.clone(), Default::default())?;
    let (stopped, s) = seconds(|| Ok(fit.run(&never, |_| {})?))?;
    let own = fit.error_estimate().context("the learner ran no round")?;
    let whole = own
        .with_discretization(&solve.estimate)
        .context("the learner's mesh is the function solve's")?;
    let on_elements =
        flatland_solve::solve_errors(mesh, fit.radiosity(), &solve.coarse.solution().radiosity)
            .rel_l2_reflected;
    let scoring = FunctionReference::new(reference, mesh, &never)?;
    let as_line = scoring.errors(fit.radiosity()).rel_l2_reflected;
    let gathered = scoring
        .gathered_errors(&solve.gather, fit.radiosity(), &never)?
        .rel_l2_reflected;
    Ok(format!(
        "| {} ({stopped:?}, {s:.2} s) | {:.4} | {on_elements:.4} | {:.2} | {:.4} | {gathered:.4} | {:.2} | {as_line:.4} |",
        mesh.len(),
        own.estimate(),
        own.estimate() / on_elements,
        whole.estimate(),
        whole.estimate() / gathered,
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
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--photons" => photons = args.next().context("--photons N")?.parse()?,
            "--factor" => factor = Some(args.next().context("--factor F")?.parse()?),
            "--learner" => learner = true,
            _ if arg.starts_with("--") => bail!("unknown option {arg}"),
            _ => specs.push(arg),
        }
    }
    println!(
        "| scene | edges | function solve: elements (rounds) | s | error | estimate | ratio | its values as the line through the midpoints | reference | tracer |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut learners = Vec::new();
    for spec in specs {
        let r = measure(&spec, factor, photons, learner).with_context(|| spec.clone())?;
        println!(
            "| {} | {} | {} ({}) | {:.2} | {:.4} | {:.4} | {:.2} | {:.4} | {} | {} |",
            r.spec,
            r.edges,
            r.ours_elements,
            r.ours_rounds,
            r.ours_s,
            r.ours_true,
            r.ours_estimate,
            r.ours_estimate / r.ours_true,
            r.ours_line,
            r.reference_elements,
            r.tracer.as_deref().unwrap_or("—"),
        );
        if let Some(row) = r.learner {
            learners.push(format!("| {} {row}", r.spec));
        }
    }
    if !learners.is_empty() {
        println!(
            "\n| scene | elements (stop, s) | its estimate | its error on the elements | ratio | with the mesh's | error, gathered | ratio | error, scored (line) |"
        );
        println!("|---|---|---|---|---|---|---|---|---|");
        for row in learners {
            println!("{row}");
        }
    }
    Ok(())
}
