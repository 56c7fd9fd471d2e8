//! Closest-hit rays and the light tracer.
//!
//! `first_hit/*`: rays per second of `Kernel::first_hit` on `fig3`, a generated hall of 10⁴
//! edges and the 4 × 4 box with 10⁴ random blockers, for rays as the tracer casts them (from a
//! random surface point, cosine-distributed about its normal); against the scan of every edge,
//! and against an any-hit query along the same rays (`visible` to a point beyond the scene),
//! which may stop at the first edge it finds. `tracer/*`: photons per second of the light
//! tracer on a generated floor plan of 10³ edges, on every core and in a pool of one thread.
//!
//! Run: `cargo bench --bench tracer`. Throughput is reported in rays or photons per second.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use flatland_baselines::{TraceBudget, TraceParams, trace};
use flatland_geom::{DVec2, EdgeId, Kernel, generate};
use flatland_solve::{Mesh, never};

mod support;

const RAYS: usize = 100_000;
/// The scan tests every edge of a 10⁴-edge scene per ray: fewer rays keep the bench short.
const BRUTE_FORCE_RAYS: usize = 1_000;
const PHOTONS: u64 = 20_000;

/// A ray as the tracer casts it: origin, direction, the edge it leaves.
type CastRay = (DVec2, DVec2, EdgeId);

/// `n` rays from uniformly random surface points, cosine-distributed (`sin θ` uniform).
fn rays(kernel: &Kernel, n: usize, seed: u64) -> Vec<CastRay> {
    let scene = kernel.scene();
    let rays = support::samples(n, seed).into_iter().map(|[s, t]| {
        let p = scene.point(s);
        let sin = 2.0 * t - 1.0;
        let d = p.normal * (1.0 - sin * sin).sqrt() + p.normal.perp() * sin;
        (p.position, d, p.edge)
    });
    rays.collect()
}

fn first_hit(c: &mut Criterion) {
    let scenes = [
        ("fig3", support::scene("fig3")),
        ("hall10k", generate::hall(10_000, 1).expect("a hall")),
        ("box_blockers10k", support::box_with_blockers(10_000, 4)),
    ];
    let mut group = c.benchmark_group("first_hit");
    for (name, scene) in scenes {
        let kernel = Kernel::new(scene);
        let rays = rays(&kernel, RAYS, 5);
        let (lo, hi) = kernel.scene().bounds();
        let reach = 2.0 * (hi - lo).length();
        // The far end of a ray is on no edge: an id past the scene's edges excludes nothing.
        let nowhere = EdgeId::new(kernel.scene().edges().len());
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function(format!("{name}/bvh"), |b| {
            b.iter(|| {
                rays.iter()
                    .filter_map(|&(o, d, e)| kernel.first_hit(o, d, Some(e)))
                    .count()
            })
        });
        group.bench_function(format!("{name}/any_hit_same_rays"), |b| {
            b.iter(|| {
                rays.iter()
                    .filter(|&&(o, d, e)| kernel.visible(o, e, o + d * reach, nowhere))
                    .count()
            })
        });
        let few = &rays[..BRUTE_FORCE_RAYS];
        group.throughput(Throughput::Elements(few.len() as u64));
        group.bench_function(format!("{name}/brute_force"), |b| {
            b.iter(|| {
                few.iter()
                    .filter_map(|&(o, d, e)| kernel.first_hit_brute_force(o, d, Some(e)))
                    .count()
            })
        });
    }
    group.finish();
}

fn tracer(c: &mut Criterion) {
    let kernel = Kernel::new(generate::floor_plan(1_000, 1).expect("a floor plan"));
    let mesh = Mesh::new(&kernel, Mesh::default_elements(kernel.scene())).expect("a mesh");
    let params = TraceParams {
        budget: TraceBudget::Photons(PHOTONS),
        seed: 1,
    };
    let photons = trace(&kernel, &mesh, &params, &never)
        .expect("a trace")
        .photons;
    let mut group = c.benchmark_group("tracer");
    group.throughput(Throughput::Elements(photons));
    group.bench_function("floor_plan1k/all_threads", |b| {
        b.iter(|| trace(black_box(&kernel), &mesh, &params, &never).expect("a trace"))
    });
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool of one thread");
    group.bench_function("floor_plan1k/1_thread", |b| {
        b.iter(|| one.install(|| trace(black_box(&kernel), &mesh, &params, &never)))
    });
    group.finish();
}

fn quick() -> Criterion {
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
}

criterion_group! { name = benches; config = quick(); targets = first_hit, tracer }
criterion_main!(benches);
