//! The candidates for the later bounces measured on one scene along one walk, each against the
//! exact solve at every position: set-up, bytes, ms per move, errors of B, of the indirect part
//! and of the later bounces; and the exact re-solve (warm GMRES) at several tolerances.
//!
//! `cargo run --release -p flatland-transport --example compare -- SCENE [key=value ...]`
//! SCENE: `plan:EDGES:SEED` (a generated floor plan lit by lamps, lamps removed),
//! `bundled:NAME` (emitters off), or a scene file. Keys: `tolerance`, `per` (elements per
//! section), `positions`, `walk` (its seed), `candidates` (comma list of `lowrank`, `grid`,
//! `adaptive`, `network`), `resolve` (comma list of GMRES tolerances, or `none`), `budget` (the
//! low rank's bytes; the probes get what it holds), `tracer` (positions checked against the
//! point-light tracer), and for the network `cells`, `steps`, `senders`, `gated`.

use std::time::Instant;

use flatland_geom::{DVec2, Kernel, PointLight, Scene, generate};
use flatland_solve::{
    DirectLight, LightBuffers, Mesh, SolveParams, SparseOperator, never, solve_linear,
    sweep_operator,
};
use flatland_transport::{
    CellNetwork, Columns, LaterBounces, LightProbes, Move, NetworkParams, Placement, ProbeParams,
    QueryBuffers, Transport, TransportParams, lit_source,
};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn clearance(kernel: &Kernel, p: DVec2) -> f64 {
    (0..16)
        .map(|k| {
            let a = std::f64::consts::TAU * (k as f64 + 0.5) / 16.0;
            kernel
                .first_hit(p, DVec2::new(a.cos(), a.sin()), None)
                .map_or(f64::INFINITY, |h| h.distance)
        })
        .fold(f64::INFINITY, f64::min)
}

fn free_point(kernel: &Kernel, mesh: &Mesh, rng: &mut ChaCha8Rng) -> DVec2 {
    loop {
        let i = rng.random_range(0..mesh.len());
        let e = mesh.elements()[i];
        let n = mesh.edge_of(i).normal;
        let t: f64 = rng.random_range(-1.2..1.2);
        let d = DVec2::new(t.cos() * n.x - t.sin() * n.y, t.sin() * n.x + t.cos() * n.y);
        if let Some(h) = kernel.first_hit(e.midpoint, d, Some(e.edge)) {
            let p = e.midpoint + d * h.distance * rng.random_range(0.2..0.8);
            if clearance(kernel, p) > 0.1 {
                return p;
            }
        }
    }
}

/// `count` positions: walks of 20 steps of 0.4 turning smoothly, never through an edge nor
/// nearer than 0.1 to one, each walk from a fresh free point (a stand-in for the relight
/// branch's walk through rooms and doors).
fn walk(kernel: &Kernel, mesh: &Mesh, count: usize, seed: u64) -> Vec<DVec2> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::new();
    let mut p = free_point(kernel, mesh, &mut rng);
    let mut heading: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    while out.len() < count {
        if out.len() % 20 == 0 && !out.is_empty() {
            p = free_point(kernel, mesh, &mut rng);
        }
        out.push(p);
        for _ in 0..50 {
            heading += rng.random_range(-0.6..0.6);
            let d = DVec2::new(heading.cos(), heading.sin());
            let free = kernel
                .first_hit(p, d, None)
                .map_or(f64::INFINITY, |h| h.distance);
            if free > 0.6 && clearance(kernel, p + d * 0.4) > 0.1 {
                p += d * 0.4;
                break;
            }
            heading += std::f64::consts::FRAC_PI_2;
        }
    }
    out
}

fn scene_of(spec: &str) -> Scene {
    let parts: Vec<&str> = spec.split(':').collect();
    match parts[0] {
        "plan" => generate::floor_plan_lit(parts[1].parse().unwrap(), parts[2].parse().unwrap())
            .unwrap()
            .with_lights(Vec::new())
            .unwrap(),
        "bundled" => emitters_off(flatland_geom::bundled::scene(parts[1]).unwrap()),
        _ => emitters_off(Scene::load(spec).unwrap()),
    }
}

fn emitters_off(scene: Scene) -> Scene {
    let edges = scene
        .edges()
        .iter()
        .map(|e| flatland_geom::Edge {
            emission: 0.0,
            ..*e
        })
        .collect();
    Scene::new(edges).unwrap()
}

/// Relative L2 (element lengths as weights) of `a` against `b`.
fn weighted(mesh: &Mesh, a: &[f64], b: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (i, e) in mesh.elements().iter().enumerate() {
        num += e.length * (a[i] - b[i]).powi(2);
        den += e.length * b[i].powi(2);
    }
    if den > 0.0 { (num / den).sqrt() } else { 0.0 }
}

fn quantile(v: &[f64], q: f64) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

/// One position's exact answer: B₀ (dense), B.
struct Exact {
    direct: Vec<f64>,
    b: Vec<f64>,
}

/// Errors and times of one method along the walk.
#[derive(Default)]
struct Row {
    ms: Vec<f64>,
    b: Vec<f64>,
    indirect: Vec<f64>,
    negative: usize,
}

impl Row {
    fn push(&mut self, mesh: &Mesh, ms: f64, b: &[f64], exact: &Exact) {
        self.ms.push(ms);
        self.b.push(weighted(mesh, b, &exact.b));
        let ind: Vec<f64> = b.iter().zip(&exact.direct).map(|(b, d)| b - d).collect();
        let ind_x: Vec<f64> = exact
            .b
            .iter()
            .zip(&exact.direct)
            .map(|(b, d)| b - d)
            .collect();
        self.indirect.push(weighted(mesh, &ind, &ind_x));
        self.negative += b.iter().filter(|&&v| v < 0.0).count();
    }

    fn print(&self, name: &str, setup: f64, bytes: usize, note: &str) {
        println!(
            "| {name} | {setup:.1} | {:.2} | {:.3} | {:.3} | {:.4} | {:.4} | {:.4} | {} | {note} |",
            bytes as f64 / 1e6,
            quantile(&self.ms, 0.5),
            quantile(&self.ms, 0.95),
            mean(&self.b),
            max(&self.b),
            mean(&self.indirect),
            self.negative,
        );
    }
}

struct Setup {
    kernel: std::sync::Arc<Kernel>,
    mesh: Mesh,
    k: SparseOperator,
    columns: Columns,
    direct: DirectLight,
}

/// B by one form of the later bounces: B₀ by one view, K B₀ from the lit columns, `M₂ B₀`.
fn relight(
    s: &Setup,
    form: &dyn LaterBounces,
    light: PointLight,
    view: &mut LightBuffers,
    query: &mut QueryBuffers,
    b: &mut [f64],
) {
    let lit = lit_source(&s.direct, &s.mesh, &[light], view);
    b.fill(0.0);
    for &(j, v) in &lit {
        b[j as usize] += v;
        let (rows, values) = s.columns.column(j as usize);
        for (&i, &kv) in rows.iter().zip(values) {
            b[i as usize] += kv * v;
        }
    }
    let lights = [light];
    form.add_later_bounces(
        Move {
            lights: &lights,
            lit: &lit,
        },
        b,
        query,
    )
    .unwrap();
}

/// B of `form` and of the exact solve against the independent point-light tracer (element
/// means, 4 million photons) at `count` positions spread over the walk.
fn against_tracer(
    s: &Setup,
    form: &dyn LaterBounces,
    lights: &[PointLight],
    exact: &[Exact],
    count: usize,
) {
    use flatland_baselines::{TraceBudget, TraceParams, trace};
    let step = (lights.len() / count).max(1);
    let (mut view, mut query) = (LightBuffers::default(), QueryBuffers::default());
    let mut b = vec![0.0; s.mesh.len()];
    let norm = |f: &dyn Fn(usize) -> f64| {
        s.mesh
            .elements()
            .iter()
            .enumerate()
            .map(|(i, e)| e.length * f(i).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    for k in (0..lights.len()).step_by(step).take(count) {
        let light = lights[k];
        relight(s, form, light, &mut view, &mut query, &mut b);
        let lit = Kernel::new(s.kernel.scene().clone().with_lights(vec![light]).unwrap());
        let params = TraceParams {
            budget: TraceBudget::Photons(4_000_000),
            seed: k as u64,
        };
        let traced = trace(&lit, &s.mesh, &params, &never).unwrap();
        let t = &traced.radiosity;
        let size = norm(&|i| t[i]);
        println!(
            "  tracer at ({:.2}, {:.2}): |B - traced| / |traced| = {:.4} (exact solve: {:.4}), noise {:.4}",
            light.at.x,
            light.at.y,
            norm(&|i| b[i] - t[i]) / size,
            norm(&|i| exact[k].b[i] - t[i]) / size,
            norm(&|i| traced.std_error[i]) / size,
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |key: &str, default: &str| -> String {
        args.iter()
            .find_map(|a| a.strip_prefix(&format!("{key}=")).map(str::to_owned))
            .unwrap_or_else(|| default.to_owned())
    };
    let tolerance: f64 = get("tolerance", "0.05").parse().unwrap();
    let per: usize = get("per", "4").parse().unwrap();
    let positions: usize = get("positions", "200").parse().unwrap();
    let walk_seed: u64 = get("walk", "99").parse().unwrap();
    let candidates = get("candidates", "lowrank,grid,adaptive");
    let resolve = get("resolve", "1e-2,1e-3,1e-4");
    let traced: usize = get("tracer", "0").parse().unwrap();
    let kernel = std::sync::Arc::new(Kernel::new(scene_of(&args[1])));
    let mesh = Mesh::new(&kernel, per * Mesh::min_elements(kernel.scene())).unwrap();
    let started = Instant::now();
    let k = sweep_operator(&kernel, &mesh, &never).unwrap();
    let k_s = started.elapsed().as_secs_f64();
    let s = Setup {
        columns: Columns::of(&k),
        direct: DirectLight::new(&kernel, &mesh).unwrap(),
        kernel: kernel.clone(),
        mesh,
        k,
    };
    let mesh = &s.mesh;
    println!(
        "{}: {} edges, {} elements, K {} non-zeros ({:.1} s, {:.1} MB); walk seed {walk_seed}, {positions} positions",
        args[1],
        kernel.scene().edges().len(),
        mesh.len(),
        s.k.nonzeros(),
        k_s,
        s.k.memory_bytes() as f64 / 1e6
    );
    print_rooms(&args[1]);
    let walk = walk(&s.kernel, mesh, positions, walk_seed);
    let lights: Vec<PointLight> = walk
        .iter()
        .map(|&at| PointLight { at, power: 8.0 })
        .collect();
    let exact = exact_answers(&s, &lights);
    let mut view = LightBuffers::default();
    println!(
        "| method | set-up s | MB | ms/move median | p95 | rel_l2_b mean | max | indirect mean | negative | note |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut budget = None;
    for candidate in candidates.split(',') {
        let form = build_candidate(candidate, &s, tolerance, &mut budget, &get);
        let mut row = Row::default();
        let mut query = QueryBuffers::default();
        let mut b = vec![0.0; mesh.len()];
        for (light, exact) in lights.iter().zip(&exact) {
            let started = Instant::now();
            relight(&s, form.as_ref(), *light, &mut view, &mut query, &mut b);
            row.push(mesh, started.elapsed().as_secs_f64() * 1e3, &b, exact);
        }
        if traced > 0 {
            against_tracer(&s, form.as_ref(), &lights, &exact, traced);
        }
        let e = form.estimated_error();
        let note = format!(
            "estimate: b {:.4}, indirect {:.4}, later {:.4}",
            e.b_mean, e.indirect_mean, e.later_mean
        );
        row.print(candidate, form.setup_s(), form.bytes(), &note);
    }
    if resolve != "none" {
        for tol in resolve.split(',') {
            resolves(&s, &lights, &exact, tol.parse().unwrap());
        }
    }
}

/// The exact re-solve along the walk: per move B₀ by one view, then GMRES to `tolerance`
/// warm-started from the last position's B.
fn resolves(s: &Setup, lights: &[PointLight], exact: &[Exact], tolerance: f64) {
    let mesh = &s.mesh;
    let mut view = LightBuffers::default();
    let params = SolveParams {
        tolerance,
        ..SolveParams::default()
    };
    let mut row = Row::default();
    let mut previous = vec![0.0; mesh.len()];
    let mut iterations = Vec::new();
    for (light, exact) in lights.iter().zip(exact) {
        let started = Instant::now();
        let lit = lit_source(&s.direct, mesh, &[*light], &mut view);
        let mut direct = vec![0.0; mesh.len()];
        for &(j, v) in &lit {
            direct[j as usize] = v;
        }
        let solved = solve_linear(&s.k, &direct, previous, &params, &never).unwrap();
        row.push(
            mesh,
            started.elapsed().as_secs_f64() * 1e3,
            &solved.radiosity,
            exact,
        );
        iterations.push(solved.iterations as f64);
        previous = solved.radiosity;
    }
    let note = format!("warm GMRES, {:.1} iterations a move", mean(&iterations));
    row.print(
        &format!("exact re-solve {tolerance}"),
        0.0,
        s.k.memory_bytes(),
        &note,
    );
}

/// One candidate form of the later bounces, built with its default parameters (the probes
/// and the network given `budget`, the low rank's bytes, where they take one).
fn build_candidate(
    candidate: &str,
    s: &Setup,
    tolerance: f64,
    budget: &mut Option<usize>,
    get: &dyn Fn(&str, &str) -> String,
) -> Box<dyn LaterBounces> {
    let (kernel, mesh) = (&s.kernel, &s.mesh);
    match candidate {
        "lowrank" => {
            let params = TransportParams {
                tolerance,
                budget: get("budget", "").parse().ok(),
                ..TransportParams::default()
            };
            let t = Transport::build(kernel, mesh, &s.k, &params, &never).unwrap();
            *budget = Some(LaterBounces::bytes(&t));
            let (clusters, rank, rows) = t.shape();
            eprintln!("lowrank: {clusters} clusters, mean rank {rank:.1}, mean rows {rows:.0}");
            Box::new(t)
        }
        "grid" | "adaptive" => {
            let params = ProbeParams {
                placement: if candidate == "grid" {
                    Placement::Grid
                } else {
                    Placement::Adaptive
                },
                ..ProbeParams::grid(budget.expect("lowrank first: the probes get its bytes"))
            };
            let p = LightProbes::build(kernel, mesh, &s.k, &params, &never).unwrap();
            eprintln!(
                "{candidate}: {} probes, spacing {:.2}",
                p.len(),
                p.spacing()
            );
            Box::new(p)
        }
        "network" => {
            let params = NetworkParams {
                max_cells: get("cells", "4000").parse().unwrap(),
                steps: get("steps", "2000000").parse().unwrap(),
                senders: get("senders", "0.25").parse().unwrap(),
                gated: get("gated", "true").parse().unwrap(),
                ..NetworkParams::default()
            };
            let net = CellNetwork::build(kernel, mesh, &s.k, &params, &never).unwrap();
            let (cells, samples) = net.shape();
            eprintln!("network: {cells} cells from {samples} samples");
            Box::new(net)
        }
        other => panic!("unknown candidate {other}"),
    }
}

/// The exact answer at every position: a cold GMRES solve to 1e-10.
fn exact_answers(s: &Setup, lights: &[PointLight]) -> Vec<Exact> {
    let mesh = &s.mesh;
    let mut view = LightBuffers::default();
    lights
        .iter()
        .map(|&light| {
            let mut direct = vec![0.0; mesh.len()];
            for (j, v) in lit_source(&s.direct, mesh, &[light], &mut view) {
                direct[j as usize] = v;
            }
            let b = solve_linear(
                &s.k,
                &direct,
                direct.clone(),
                &SolveParams::default(),
                &never,
            )
            .unwrap()
            .radiosity;
            Exact { direct, b }
        })
        .collect()
}

/// The number of rooms of a generated plan (its lamps: one a room).
fn print_rooms(spec: &str) {
    if spec.starts_with("plan:") {
        let parts: Vec<&str> = spec.split(':').collect();
        let plan =
            generate::floor_plan_lit(parts[1].parse().unwrap(), parts[2].parse().unwrap()).unwrap();
        println!(
            "{} rooms (a lamp per room in the generated plan)",
            plan.lights().len()
        );
    }
}
