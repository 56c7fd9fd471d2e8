//! Scratch: variants of the learner against HR on the bundled scenes.
use flatland_geom::{Kernel, Scene};
use kernel_fit::baselines::{HrParams, run_hr_at_budget};
use kernel_fit::{Approximation, Fit, FitParams, Gating, Reference, Target};
use std::sync::Arc;

fn scene(name: &str) -> Scene {
    if let Some(seed) = name.strip_prefix("rand") {
        return random_room(seed.parse().unwrap());
    }
    Scene::load(format!("scenes/{name}.ron")).unwrap()
}

/// A random room (rectangle, notched or convex polygon), lights cut into its walls, blockers,
/// shelves and partitions: validation scenes the method is never tuned on.
fn random_room(seed: u64) -> Scene {
    use flatland_geom::{DVec2, Edge};
    use rand::{RngExt, SeedableRng};
    let mut r = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5ce7e);
    let v = |x: f64, y: f64| DVec2::new(x, y);
    let (w, h) = (r.random_range(2.0..8.0), r.random_range(2.0..5.0));
    let kind = r.random_range(0..3);
    let corners: Vec<DVec2> = match kind {
        0 => vec![v(0.0, 0.0), v(w, 0.0), v(w, h), v(0.0, h)],
        1 => {
            // A notch hanging from the ceiling.
            let (a, b) = (r.random_range(0.2..0.5) * w, r.random_range(0.55..0.85) * w);
            let d = r.random_range(0.3..0.6) * h;
            vec![
                v(0.0, 0.0),
                v(w, 0.0),
                v(w, h),
                v(b, h),
                v(b, h - d),
                v(a, h - d),
                v(a, h),
                v(0.0, h),
            ]
        }
        _ => {
            let n = r.random_range(5..9);
            (0..n)
                .map(|i| {
                    let a =
                        std::f64::consts::TAU * (i as f64 + r.random_range(-0.3..0.3)) / n as f64;
                    v(w / 2.0 * (1.0 + a.cos()), h / 2.0 * (1.0 + a.sin()))
                })
                .collect()
        }
    };
    let n = corners.len();
    let lights = r.random_range(1..=2);
    let light_walls: Vec<usize> = (0..lights).map(|_| r.random_range(0..n)).collect();
    let mut edges = Vec::new();
    for i in 0..n {
        let (a, b) = (corners[i], corners[(i + 1) % n]);
        let rho = r.random_range(0.2..0.9);
        if light_walls.contains(&i) {
            let (u0, u1) = (r.random_range(0.1..0.45), r.random_range(0.55..0.9));
            let (p0, p1) = (a + (b - a) * u0, a + (b - a) * u1);
            edges.push(Edge::surface(a, p0, rho));
            edges.push(Edge::surface(p0, p1, rho).with_emission(r.random_range(0.5..2.0)));
            edges.push(Edge::surface(p1, b, rho));
        } else {
            edges.push(Edge::surface(a, b, rho));
        }
    }
    let inside = |p: DVec2| {
        (0..n).all(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % n]);
            (b - a).perp_dot(p - a) > 0.05 * w.min(h)
        })
    };
    let blockers = r.random_range(0..=12);
    let mut placed = 0;
    let mut tries = 0;
    while placed < blockers && tries < 1000 {
        tries += 1;
        let c = v(r.random_range(0.0..w), r.random_range(0.0..h));
        let len = r.random_range(0.05..0.25) * w.min(h);
        let a = r.random_range(0.0..std::f64::consts::PI);
        let d = v(a.cos(), a.sin()) * len / 2.0;
        let (p, q) = (c - d, c + d);
        if !(inside(p) && inside(q)) {
            continue;
        }
        let e = match r.random_range(0..4) {
            0 => Edge::surface(p, q, r.random_range(0.2..0.9)).with_two_sided(true),
            _ => Edge::blocker(p, q),
        };
        edges.push(e);
        placed += 1;
    }
    if kind == 0 && r.random_bool(0.5) {
        // A partition standing on the floor.
        let x = r.random_range(0.2..0.8) * w;
        edges.push(
            Edge::surface(v(x, 0.0), v(x, r.random_range(0.3..0.7) * h), 0.5).with_two_sided(true),
        );
    }
    Scene::new(edges).unwrap()
}

fn variant(name: &str, cells: usize) -> FitParams {
    let mut parts = name.split('+');
    let mut p = match parts.next().unwrap() {
        "paper" => FitParams::paper(),
        "default" => FitParams::default(),
        other => panic!("unknown base {other}"),
    };
    p.target_cells = cells;
    p.eval_every = 0;
    for part in parts {
        match part {
            "-faces" => p.gating = Gating::Pairs,
            "-gate" => p.gating = Gating::Off,
            "-imp" => p.importance = 0.0,
            "-w" => p.weighted = false,
            "-norm" => p.network.output_mode = sgcs::OutputMode::Sum,
            "-local" => p.network.output_rule = sgcs::OutputRule::Normalized,
            "-worst" => {
                p.network.insertion = sgcs::Insertion::Midpoint;
                p.network.insert_rule = sgcs::InsertRule::PreserveOutput;
            }
            "-sum" => p.network.resource = sgcs::Resource::MeanTimesVolume,
            "vis" => {
                p.target = Target::Visibility;
                p.refit = false;
            }
            s if s.starts_with("imp") => p.importance = s[3..].parse().unwrap(),
            s if s.starts_with("phi") => p.phi = s[3..].parse().unwrap(),
            s if s.starts_with("lam") => p.network.lambda = s[3..].parse().unwrap(),
            s if s.starts_with("psi") => p.psi = s[3..].parse().unwrap(),
            s if s.starts_with("cut") => p.network.activation_cutoff = s[3..].parse().unwrap(),
            s if s.starts_with("eta") => p.network.eta = s[3..].parse().unwrap(),
            other => panic!("unknown part {other}"),
        }
    }
    p
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cells: usize = args.first().map_or(400, |a| a.parse().unwrap());
    let seeds: u64 = args.get(1).map_or(3, |a| a.parse().unwrap());
    let scenes: Vec<String> = args
        .get(2)
        .map_or(vec!["fig3".into(), "maze".into(), "corners".into()], |a| {
            a.split(',').map(String::from).collect()
        });
    let variants: Vec<String> = args[3..].to_vec();
    for name in &scenes {
        let kernel = Arc::new(Kernel::new(scene(name)));
        if std::env::var("FACES").is_ok() {
            print!("{name}: ");
            face_stats(&kernel);
        }
        let mut hr = (0.0, 0.0);
        for seed in 1..=seeds {
            let reference = Reference::new(&kernel, 256, 4096, seed);
            let h = run_hr_at_budget(&kernel, cells, seed, &HrParams::default()).unwrap();
            let e = reference.errors(&h.approx);
            hr.0 += e.grid / seeds as f64;
            hr.1 += e.heldout / seeds as f64;
        }
        println!("{name:8} {:<40} grid {:.3} held {:.3}", "hr", hr.0, hr.1);
        for v in &variants {
            let (mut g, mut h, mut t, mut rays, mut steps, mut cells_sum) =
                (0.0, 0.0, 0.0, 0, 0, 0);
            let mut per = Vec::new();
            for seed in 1..=seeds {
                let reference = Arc::new(Reference::new(&kernel, 256, 4096, seed));
                let mut params = variant(v, cells);
                params.seed = seed;
                let started = std::time::Instant::now();
                let mut fit =
                    Fit::new(Arc::clone(&kernel), Arc::clone(&reference), params).unwrap();
                let summary = fit
                    .run(100000, |_| std::ops::ControlFlow::Continue(()))
                    .unwrap();
                t += started.elapsed().as_secs_f64() / seeds as f64;
                let e = summary.errors;
                g += e.grid / seeds as f64;
                h += e.heldout / seeds as f64;
                rays += summary.rays;
                steps += summary.steps;
                cells_sum += summary.cells;
                per.push(format!("{:.3}", e.grid));
                if std::env::var("WORST").is_ok() {
                    worst_points(&kernel, &reference, fit.model());
                }
                let _ = fit.model().basis_functions();
            }
            println!(
                "{name:8} {v:<40} grid {g:.3} held {h:.3}  ratio {:.2}/{:.2}  t {t:.2}s rays {} steps {} cells {} [{}]",
                g / hr.0,
                h / hr.1,
                rays / seeds,
                steps / seeds,
                cells_sum / seeds as usize,
                per.join(" ")
            );
        }
    }
}

/// Prints the grid points with the largest share of the squared error.
#[allow(dead_code)]
pub fn worst_points(kernel: &Kernel, reference: &Reference, model: &kernel_fit::LearnedKernel) {
    let approx = reference.approximate_grid(model);
    let exact = reference.grid();
    let res = reference.res();
    let total: f64 = exact.iter().map(|v| v * v).sum();
    let mut idx: Vec<usize> = (0..exact.len()).collect();
    idx.sort_by(|&a, &b| {
        ((approx[b] - exact[b]).powi(2)).total_cmp(&(approx[a] - exact[a]).powi(2))
    });
    let err: f64 = idx.iter().map(|&i| (approx[i] - exact[i]).powi(2)).sum();
    println!("rel l2 {:.4}", (err / total).sqrt());
    for &i in idx.iter().take(12) {
        let (s, t) = kernel_fit::grid_point(res, i);
        let u = kernel.unoccluded(s, t);
        println!(
            "  s {s:.4} t {t:.4} pair ({},{}) exact {:.4} approx {:.4} share {:.3} class {:?}",
            u.sender,
            u.receiver,
            exact[i],
            approx[i],
            (approx[i] - exact[i]).powi(2) / err,
            kernel.pair_class(u.sender, u.receiver)
        );
        println!(
            "     face cells {:?} occupied faces {:?}",
            model.face_cells(s, t),
            model.occupied_faces()
        );
    }
}

/// Counts faces (distinct (pair, sub-pair, sign vector)) among uniform draws, and the mass share of the largest ones.
#[allow(dead_code)]
pub fn face_stats(kernel: &Kernel) {
    use flatland_geom::{PairClass, PairEvents};
    use rand::{RngExt, SeedableRng};
    use std::collections::HashMap;
    let mut r = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut faces: HashMap<(usize, usize, usize, Vec<bool>), f64> = HashMap::new();
    let mut total = 0.0;
    let mut varies_mass = 0.0;
    for _ in 0..400_000 {
        let (s, t) = (r.random::<f64>(), r.random::<f64>());
        let u = kernel.unoccluded(s, t);
        let w = u.zeta * u.zeta;
        total += w;
        if kernel.pair_class(u.sender, u.receiver) != PairClass::Varies || u.zeta == 0.0 {
            continue;
        }
        varies_mass += w;
        let e = kernel.visibility_events(u.sender, u.receiver).unwrap();
        let sub = e.sub_pair(u.x, u.y);
        let signs: Vec<bool> = e
            .points(sub)
            .iter()
            .map(|&v| PairEvents::side(u.x, u.y, v))
            .collect();
        *faces.entry((u.sender, u.receiver, sub, signs)).or_default() += w;
    }
    let mut m: Vec<f64> = faces.values().copied().collect();
    m.sort_by(|a, b| b.total_cmp(a));
    let cum = |k: usize| m.iter().take(k).sum::<f64>() / varies_mass;
    let mut pairs = 0;
    let mut events = 0;
    for a in 0..kernel.surface_parents() {
        for b in 0..kernel.surface_parents() {
            if kernel.pair_class(a, b) == PairClass::Varies {
                pairs += 1;
                let e = kernel.visibility_events(a, b).unwrap();
                events += (0..4).map(|k| e.points(k).len()).sum::<usize>();
            }
        }
    }
    println!(
        "varies pairs {pairs} events {events} faces seen {} varies mass share {:.3}; top 50/100/200/400 faces hold {:.3} {:.3} {:.3} {:.3}",
        m.len(),
        varies_mass / total,
        cum(50),
        cum(100),
        cum(200),
        cum(400)
    );
}
