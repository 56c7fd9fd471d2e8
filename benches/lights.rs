//! Point lights: one view of a light (`DirectLight::view`, the two half-plane envelopes of the
//! sweep from where the light stands, and the angle each element it lights subtends) on
//! generated floor plans lit by a lamp per room, of 10³, 10⁴ and 10⁵ edges (three elements per
//! edge); the hierarchy is built once per scene, outside the timing, as a moving light uses
//! it. Each iteration views the next lamp of the plan, so the figure is a mean over rooms.
//! Also, at 10⁴ edges, the mean irradiance of every lamp at once (`mean_irradiance`, what
//! `Mesh::new` adds to the source) and the whole lit mesh.
//!
//! Run: `cargo bench --bench lights`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, generate};
use flatland_solve::{DirectLight, LightBuffers, Mesh};

/// Elements per edge, as in the sweep's bench.
const PER_EDGE: usize = 3;

fn mesh_of(kernel: &Kernel) -> Mesh {
    let n = PER_EDGE * kernel.scene().edges().len();
    Mesh::new(kernel, n.max(Mesh::min_elements(kernel.scene()))).expect("mesh")
}

fn views(c: &mut Criterion) {
    let mut group = c.benchmark_group("light_view");
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(5));
    for edges in [1_000, 10_000, 100_000] {
        let kernel = Kernel::new(generate::floor_plan_lit(edges, 1).expect("a lit floor plan"));
        let mesh = mesh_of(&kernel);
        let direct = DirectLight::new(&kernel, &mesh).expect("the hierarchy");
        let lamps = kernel.scene().lights();
        let mut buffers = LightBuffers::default();
        let mut next = 0;
        group.bench_function(format!("floor_plan_{edges}"), |b| {
            b.iter(|| {
                next = (next + 1) % lamps.len();
                black_box(direct.view(&mesh, lamps[next].at, &mut buffers).len())
            })
        });
        if edges == 10_000 {
            group.bench_function("floor_plan_10000_every_lamp", |b| {
                b.iter(|| direct.mean_irradiance(&mesh, black_box(lamps)))
            });
            group.bench_function("floor_plan_10000_lit_mesh", |b| {
                b.iter(|| mesh_of(black_box(&kernel)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, views);
criterion_main!(benches);
