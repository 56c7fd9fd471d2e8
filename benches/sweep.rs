//! The exact operator at scale: assembly by the visibility sweep on generated floor plans and
//! halls of 10³ and 10⁴ edges (three elements per edge), the mesh of 10⁴ edges, and the dense
//! operator from the pair table at 10³ edges, the largest size both can build (10⁴ edges need
//! more than 8192 elements).
//!
//! Run: `cargo bench --bench sweep`. The dense rows take several seconds per sample.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, Scene, generate};
use flatland_solve::{Mesh, exact_operator, never, sweep_operator};

/// Elements per edge, as in the figures of the README (`flatland solve`).
const PER_EDGE: usize = 3;

fn scenes(edges: usize) -> [(&'static str, Scene); 2] {
    [
        (
            "floor_plan",
            generate::floor_plan(edges, 1).expect("a floor plan"),
        ),
        ("hall", generate::hall(edges, 1).expect("a hall")),
    ]
}

fn mesh_of(kernel: &Kernel) -> Mesh {
    let n = PER_EDGE * kernel.scene().edges().len();
    Mesh::new(kernel, n.max(Mesh::min_elements(kernel.scene()))).expect("mesh")
}

fn sweep(c: &mut Criterion) {
    for edges in [1_000, 10_000] {
        let mut group = c.benchmark_group(format!("sweep_{edges}_edges"));
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(20));
        for (name, scene) in scenes(edges) {
            let kernel = Kernel::new(scene);
            let mesh = mesh_of(&kernel);
            group.bench_function(name, |b| {
                b.iter(|| sweep_operator(black_box(&kernel), &mesh, &never).expect("sweep"))
            });
            if edges == 10_000 {
                group.bench_function(format!("{name}_mesh"), |b| {
                    b.iter(|| mesh_of(black_box(&kernel)))
                });
            }
        }
        group.finish();
    }
}

fn dense(c: &mut Criterion) {
    let mut group = c.benchmark_group("dense_1000_edges");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(60));
    for (name, scene) in scenes(1_000) {
        let mesh = mesh_of(&Kernel::new(scene.clone()));
        // A fresh kernel each time: the pair table fills the kernel's shaft cache.
        group.bench_function(name, |b| {
            b.iter_with_setup(
                || Kernel::new(scene.clone()),
                |kernel| exact_operator(&kernel, &mesh, &never).expect("dense"),
            )
        });
    }
    group.finish();
}

criterion_group!(benches, sweep, dense);
criterion_main!(benches);
