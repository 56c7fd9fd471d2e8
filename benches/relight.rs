//! Relighting: one move of a lamp along a walk through a generated floor plan of 10³ and 10⁴
//! edges (its own lamps off), by the exact re-solve (`Relighter::relight` at its default
//! tolerance, 1e-6: the direct light by one view, the first bounce from the lit elements'
//! columns, the later bounces by GMRES from the last move's), against a cold exact solve at
//! the same positions (a fresh lit mesh solved from `B₀` to 1e-10, the operator in hand). The
//! operator is built once per scene, outside the timing; each iteration moves the lamp one step
//! along a walk of 200 positions, back and forth, so every move is a step of the walk. The
//! mesh is `bench --relight`'s (four elements per section, at least 4096).
//!
//! Run: `cargo bench --bench relight`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, generate};
use flatland_lab::timed::walk::{POSITIONS, lamp_moves, relight_elements};
use flatland_solve::{Mesh, RelightParams, Relighter, SolveParams, cold_solve, never};

/// The generator's seed (as `bench --relight`'s; no default was chosen on it).
const SEED: u64 = 2024;

fn moves(c: &mut Criterion) {
    let mut group = c.benchmark_group("relight");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(8));
    for edges in [1_000, 10_000] {
        let scene = generate::floor_plan_lit(edges, SEED).expect("a lit floor plan");
        let power = scene.lights()[0].power;
        let kernel = Kernel::new(scene.with_lights(Vec::new()).expect("no lights"));
        let mesh = Mesh::new(&kernel, relight_elements(kernel.scene())).expect("mesh");
        let walk = lamp_moves(&kernel, POSITIONS, 7, power).expect("a walk");
        let params = RelightParams::default();
        let mut relighter = Relighter::new(&kernel, &mesh, params, &never).expect("relighter");
        // Back and forth along the walk: 0, 1, …, 199, 198, …, 1, 0, 1, …
        let order: Vec<usize> = (0..walk.len()).chain((1..walk.len() - 1).rev()).collect();
        let mut next = 0;
        relighter.relight(&walk[0], &never).expect("the first move");
        group.bench_function(format!("move/floor_plan_{edges}"), |b| {
            b.iter(|| {
                next = (next + 1) % order.len();
                let relit = relighter
                    .relight(&walk[order[next]], &never)
                    .expect("a move");
                black_box(relit.radiosity[0])
            })
        });
        let solve = SolveParams::default();
        group.bench_function(format!("cold/floor_plan_{edges}"), |b| {
            b.iter(|| {
                next = (next + 1) % order.len();
                let rows = relighter.rows();
                let lights = &walk[order[next]];
                let cold = cold_solve(&kernel, rows, mesh.len(), lights, &solve, &never);
                black_box(cold.expect("a cold solve").solution.iterations)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, moves);
criterion_main!(benches);
