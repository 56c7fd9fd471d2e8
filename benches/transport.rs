//! One move of a point light relit by the learned transport
//! (`flatland_transport::TransportRelighter`: the exact relighter's direct light B₀ and first
//! bounce K B₀, the transport's later bounces M₂ B₀, no linear solve) on generated floor plans
//! of 10³ and 10⁴ edges, their lamps removed, four elements per section. The model is built
//! once outside the timing with its default parameters; each iteration moves the light to the
//! next lamp position of the plan (one a room), so the figure is a mean over rooms. Beside it,
//! the later bounces alone (`Transport::add_later_bounces_of`). At 10⁵ edges the set-up takes
//! minutes, too long for a bench: `crates/flatland-transport/examples/compare.rs` measures a
//! walk there.
//!
//! Run: `cargo bench --bench transport`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, PointLight, generate};
use flatland_solve::{LightBuffers, Mesh, RelightParams, Relighter, never};
use flatland_transport::{
    QueryBuffers, Transport, TransportParams, TransportRelighter, lit_source,
};

/// Elements per section of a surface edge, as `flatland relight` meshes by default.
const PER_SECTION: usize = 4;

fn moves(c: &mut Criterion) {
    let mut group = c.benchmark_group("transport_move");
    group.sample_size(30);
    group.measurement_time(Duration::from_secs(5));
    for edges in [1_000, 10_000] {
        let lit = generate::floor_plan_lit(edges, 1).expect("a lit floor plan");
        let lamps: Vec<PointLight> = lit.lights().to_vec();
        let kernel = Kernel::new(lit.with_lights(Vec::new()).expect("lamps removed"));
        let mesh =
            Mesh::new(&kernel, PER_SECTION * Mesh::min_elements(kernel.scene())).expect("mesh");
        let relighter = Relighter::new(&kernel, &mesh, RelightParams::default(), &never)
            .expect("the exact relighter");
        let params = TransportParams::default();
        let transport = Transport::build(&kernel, &mesh, relighter.rows(), &params, &never)
            .expect("the transport");
        let lit_of: Vec<Vec<(u32, f64)>> = lamps
            .iter()
            .map(|lamp| {
                let view = &mut LightBuffers::default();
                lit_source(relighter.direct(), &mesh, std::slice::from_ref(lamp), view)
            })
            .collect();
        let mut later = vec![0.0; mesh.len()];
        let mut query = QueryBuffers::default();
        let mut next = 0;
        group.bench_function(format!("later_bounces_{edges}"), |bench| {
            bench.iter(|| {
                next = (next + 1) % lamps.len();
                transport
                    .add_later_bounces_of(&lit_of[next], &mut later, &mut query)
                    .expect("a query");
                black_box(&later);
            });
        });
        let mut relit =
            TransportRelighter::new(&kernel, relighter, transport, &never).expect("the relighter");
        group.bench_function(format!("floor_plan_{edges}"), |bench| {
            bench.iter(|| {
                next = (next + 1) % lamps.len();
                black_box(relit.relight(&lamps[next..=next]).expect("a move"));
            });
        });
    }
    group.finish();
}

criterion_group!(benches, moves);
criterion_main!(benches);
