//! Measures the transport on a generated lit floor plan: set-up, bytes, ms per move and errors
//! against the exact solve along a walk.
use std::time::Instant;

use flatland_geom::{DVec2, Kernel, PointLight, generate};
use flatland_solve::*;
use flatland_transport::*;
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
            if clearance(kernel, p) > 0.15 {
                return p;
            }
        }
    }
}

/// 200 positions: walks of 20 steps of up to 0.4, turning smoothly, never through an edge,
/// each walk starting at a fresh free point.
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
            let step = 0.4;
            let free = kernel
                .first_hit(p, d, None)
                .map_or(f64::INFINITY, |h| h.distance);
            if free > step + 0.2 {
                let q = p + d * step;
                if clearance(kernel, q) > 0.15 {
                    p = q;
                    break;
                }
            }
            heading += std::f64::consts::PI / 2.0;
        }
    }
    out
}

fn weighted(mesh: &Mesh, a: &[f64], b: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (i, e) in mesh.elements().iter().enumerate() {
        num += e.length * (a[i] - b[i]).powi(2);
        den += e.length * b[i].powi(2);
    }
    (num / den).sqrt()
}

fn pct(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let edges: usize = args[1].parse().unwrap();
    let tolerance: f64 = args.get(2).map_or(0.02, |s| s.parse().unwrap());
    let cluster: usize = args.get(3).map_or(64, |s| s.parse().unwrap());
    let per: usize = args.get(4).map_or(4, |s| s.parse().unwrap());
    let positions: usize = args.get(5).map_or(200, |s| s.parse().unwrap());
    let scene = generate::floor_plan_lit(edges, 11)
        .unwrap()
        .with_lights(vec![])
        .unwrap();
    let kernel = Kernel::new(scene);
    let mesh = Mesh::new(&kernel, per * Mesh::min_elements(kernel.scene())).unwrap();
    let t = Instant::now();
    let k = sweep_operator(&kernel, &mesh, &never).unwrap();
    let k_s = t.elapsed().as_secs_f64();
    let columns = Columns::of(&k);
    println!(
        "edges {} N {} K nnz {} ({:.1}s, {} MB)",
        kernel.scene().edges().len(),
        mesh.len(),
        k.nonzeros(),
        k_s,
        k.memory_bytes() / 1_000_000
    );
    let params = TransportParams {
        tolerance,
        cluster_elements: cluster,
        ..TransportParams::default()
    };
    let transport = Transport::build(&kernel, &mesh, &k, &params, &never).unwrap();
    let (clusters, rank, rows) = transport.shape();
    println!(
        "setup {:.1}s bytes {:.1} MB clusters {clusters} mean rank {rank:.1} mean rows {rows:.0}",
        transport.setup_s(),
        transport.bytes() as f64 / 1e6
    );
    println!("estimate {:?}", transport.estimated_error());
    let direct = DirectLight::new(&kernel, &mesh).unwrap();
    let mut buffers = LightBuffers::default();
    let walk = walk(&kernel, &mesh, positions, 99);
    let (mut ms, mut eb, mut ei, mut el, mut exact_ms, mut its) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut previous = vec![0.0; mesh.len()];
    for p in &walk {
        let light = PointLight { at: *p, power: 8.0 };
        let t = Instant::now();
        let lit = lit_source(&direct, &mesh, &[light], &mut buffers);
        let mut b = vec![0.0; mesh.len()];
        for &(j, v) in &lit {
            b[j as usize] += v;
            let (rows, values) = columns.column(j as usize);
            for (&i, &kv) in rows.iter().zip(values) {
                b[i as usize] += kv * v;
            }
        }
        transport.add_later_bounces(&lit, &mut b).unwrap();
        ms.push(t.elapsed().as_secs_f64() * 1e3);
        let mut b0 = vec![0.0; mesh.len()];
        for &(j, v) in &lit {
            b0[j as usize] = v;
        }
        let t = Instant::now();
        let exact =
            solve_linear(&k, &b0, previous.clone(), &SolveParams::default(), &never).unwrap();
        exact_ms.push(t.elapsed().as_secs_f64() * 1e3);
        its.push(exact.iterations as f64);
        let x = exact.radiosity;
        eb.push(weighted(&mesh, &b, &x));
        let ind: Vec<f64> = (0..mesh.len()).map(|i| b[i] - b0[i]).collect();
        let ind_x: Vec<f64> = (0..mesh.len()).map(|i| x[i] - b0[i]).collect();
        ei.push(weighted(&mesh, &ind, &ind_x));
        let mut first = vec![0.0; mesh.len()];
        k.apply(&b0, &mut first);
        let later: Vec<f64> = (0..mesh.len()).map(|i| ind[i] - first[i]).collect();
        let later_x: Vec<f64> = (0..mesh.len()).map(|i| ind_x[i] - first[i]).collect();
        el.push(weighted(&mesh, &later, &later_x));
        previous = x;
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let max = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    println!(
        "move ms median {:.3} p95 {:.3}",
        pct(&mut ms.clone(), 0.5),
        pct(&mut ms.clone(), 0.95)
    );
    println!(
        "rel_l2_b mean {:.4} max {:.4}  indirect mean {:.4}  later mean {:.4} max {:.4}",
        mean(&eb),
        max(&eb),
        mean(&ei),
        mean(&el),
        max(&el)
    );
    println!(
        "exact gmres 1e-10 warm: median {:.1} ms, iterations mean {:.1}",
        pct(&mut exact_ms, 0.5),
        mean(&its)
    );
}
