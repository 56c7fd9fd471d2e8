//! Kernel samples per second: `fig3` and `fig3` subdivided ×1000, naive (every ray against every
//! edge of the scene, no culling: 7 edges, then 6001) vs accelerated (shaft cache per parent
//! edge pair + BVH), single thread vs the rayon batch API (on every core, and in a pool of one
//! thread: the batch path's cost per sample against the single path's). `scaling/*`: a box room
//! with 10 to 10 000 random blockers, single and batch. `varying_pairs/*`: listing the pairs
//! whose visibility varies (what the default network learner samples) on generated plans of
//! about 1000 and 3000 edges, a new kernel each time (a kernel keeps its list).
//!
//! Run: `cargo bench --bench kernel`. Throughput is reported in samples (elements) per second.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use flatland_geom::Kernel;

mod support;

const SAMPLES: usize = 200_000;
/// The naive ×1000 kernel tests 6001 edges per ray: fewer samples keep the bench short.
const NAIVE_FINE_SAMPLES: usize = 2_000;

fn kernel_samples(c: &mut Criterion) {
    let st = support::samples(SAMPLES, 1);
    let fig3 = support::scene("fig3");
    let scenes = [
        ("fig3", fig3.clone()),
        ("fig3x1000", fig3.subdivide(1000).expect("subdivide")),
    ];
    let mut group = c.benchmark_group("kernel");
    for (name, scene) in scenes {
        let kernel = Kernel::new(scene);
        let _ = kernel.k_batch(&st); // fill the lazy shaft cache once
        let naive = if name == "fig3" {
            &st[..]
        } else {
            &st[..NAIVE_FINE_SAMPLES]
        };
        group.throughput(Throughput::Elements(naive.len() as u64));
        group.bench_function(format!("{name}/naive/single"), |b| {
            b.iter(|| {
                naive
                    .iter()
                    .map(|&[s, t]| kernel.k_naive(s, t))
                    .sum::<f64>()
            })
        });
        group.throughput(Throughput::Elements(SAMPLES as u64));
        group.bench_function(format!("{name}/accelerated/single"), |b| {
            b.iter(|| st.iter().map(|&[s, t]| kernel.k(s, t)).sum::<f64>())
        });
        group.bench_function(format!("{name}/accelerated/batch"), |b| {
            b.iter(|| kernel.k_batch(black_box(&st)))
        });
        let one = one_thread();
        group.bench_function(format!("{name}/accelerated/batch_1_thread"), |b| {
            b.iter(|| one.install(|| kernel.k_batch(black_box(&st))))
        });
    }
    group.finish();
}

/// Brute-force visibility over the *pieces* of the ×1000 scene: what culling at the parent level
/// saves (one ray against ~6000 edges).
fn brute_force_pieces(c: &mut Criterion) {
    let st = support::samples(2_000, 2);
    let kernel = Kernel::new(support::scene("fig3").subdivide(1000).expect("subdivide"));
    let scene = kernel.scene();
    let pairs: Vec<_> = st
        .iter()
        .map(|&[s, t]| (scene.point(s), scene.point(t)))
        .collect();
    let mut group = c.benchmark_group("visibility");
    group.throughput(Throughput::Elements(pairs.len() as u64));
    group.bench_function("fig3x1000/brute_force_pieces", |b| {
        b.iter(|| {
            pairs
                .iter()
                .filter(|(x, y)| kernel.visible_brute_force(x.position, x.edge, y.position, y.edge))
                .count()
        })
    });
    group.bench_function("fig3x1000/accelerated", |b| {
        b.iter(|| {
            pairs
                .iter()
                .filter(|(x, y)| kernel.visible(x.position, x.edge, y.position, y.edge))
                .count()
        })
    });
    group.finish();
}

/// How the accelerated kernel scales with the number of occluders (BVH: about `log n`).
fn blocker_scaling(c: &mut Criterion) {
    let st = support::samples(20_000, 3);
    let mut group = c.benchmark_group("scaling");
    group.throughput(Throughput::Elements(st.len() as u64));
    for n in [10, 100, 1_000, 10_000] {
        let kernel = Kernel::new(support::box_with_blockers(n, 4));
        let _ = kernel.k_batch(&st);
        group.bench_function(format!("box_blockers_{n}/accelerated/single"), |b| {
            b.iter(|| st.iter().map(|&[s, t]| kernel.k(s, t)).sum::<f64>())
        });
        group.bench_function(format!("box_blockers_{n}/accelerated/batch"), |b| {
            b.iter(|| kernel.k_batch(black_box(&st)))
        });
    }
    group.finish();
}

fn varying_pairs(c: &mut Criterion) {
    let mut group = c.benchmark_group("varying_pairs");
    group.sample_size(10);
    for (name, scene) in [
        (
            "floorplan_1000",
            flatland_geom::generate::floor_plan(1000, 5),
        ),
        ("hall_1000", flatland_geom::generate::hall(1000, 6)),
        (
            "floorplan_3000",
            flatland_geom::generate::floor_plan(3000, 5),
        ),
    ] {
        let scene = scene.expect("a generated scene");
        group.bench_function(name, |b| {
            b.iter(|| {
                let kernel = Kernel::new(scene.clone());
                black_box(kernel.varying_pairs().pairs.len())
            });
        });
    }
    group.finish();
}

fn one_thread() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool of one thread")
}

fn quick() -> Criterion {
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
}

criterion_group! { name = benches; config = quick(); targets = kernel_samples, brute_force_pieces, blocker_scaling, varying_pairs }
criterion_main!(benches);
