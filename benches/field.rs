//! B as a function (`flatland_solve::field`, `FunctionSolve`, `solve_to_tolerance`) on generated
//! floor plans and halls of 10³ edges:
//! - `gather`: the final gather at 8 points per element of a solved mesh (what
//!   `flatland solve --samples 8` writes), per call;
//! - `at_equal_elements`: the function solve on a mesh of 4 elements per edge (its solve, the
//!   Gauss refinement's and the gather: three views per element) against the older estimate
//!   on the same mesh (the solves on N and 2N and the comparison at N points), which the
//!   default may cost at most twice;
//! - `to_tolerance`: the whole default, rounds to 1 % with the error read as a function,
//!   against the doubling to 1 % at the collocation points (whose steps then miss 1 % by
//!   3–8 times; see docs/FUNCTION-ERROR.md).
//!
//! Run: `cargo bench --bench field`. Samples of the last two groups take about a second.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, Scene, generate};
use flatland_solve::{
    DEFAULT_ERROR_BOUND, Discretization, ExactReference, FunctionSolve, Mesh, SamplePoints,
    SolveParams, ToleranceParams, elements_for_error, never, solve_to_tolerance,
};

/// Elements per edge of the fixed meshes.
const PER_EDGE: usize = 4;

fn scenes() -> [(&'static str, Scene); 2] {
    [
        (
            "floor_plan_1000",
            generate::floor_plan(1_000, 3).expect("a floor plan"),
        ),
        ("hall_1000", generate::hall(1_000, 3).expect("a hall")),
    ]
}

fn mesh_of(kernel: &Kernel) -> Mesh {
    let n = PER_EDGE * kernel.scene().edges().len();
    Mesh::new(kernel, n.max(Mesh::min_elements(kernel.scene()))).expect("mesh")
}

fn field(c: &mut Criterion) {
    let params = SolveParams::default();
    for (name, scene) in scenes() {
        let kernel = Kernel::new(scene);
        let mesh = mesh_of(&kernel);
        let solve = FunctionSolve::new(&kernel, mesh.clone(), &params, &never).expect("solve");
        let points = SamplePoints::evenly(&mesh, 8);

        let mut group = c.benchmark_group(format!("field_{name}"));
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(15));
        group.bench_function("gather_8_per_element", |b| {
            b.iter(|| {
                solve
                    .radiosity_at(black_box(&points.s), &never)
                    .expect("gather")
            })
        });
        group.bench_function("at_equal_elements/function_solve", |b| {
            b.iter(|| FunctionSolve::new(&kernel, black_box(mesh.clone()), &params, &never))
        });
        group.bench_function("at_equal_elements/collocation_estimate", |b| {
            b.iter(|| {
                let coarse = ExactReference::new(&kernel, black_box(mesh.len()), &params, &never)
                    .expect("solve");
                Discretization::of(coarse, &kernel, &params, &never).expect("estimate")
            })
        });
        group.bench_function("to_tolerance/function_solve", |b| {
            b.iter(|| {
                solve_to_tolerance(
                    black_box(&kernel),
                    &ToleranceParams::default(),
                    &params,
                    &never,
                )
            })
        });
        group.bench_function("to_tolerance/collocation_doubling", |b| {
            b.iter(|| elements_for_error(black_box(&kernel), DEFAULT_ERROR_BOUND, &params, &never))
        });
        group.finish();
    }
}

criterion_group!(benches, field);
criterion_main!(benches);
