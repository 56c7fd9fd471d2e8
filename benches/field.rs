//! B as a function (`flatland_solve::field`, `FunctionSolve`, `solve_to_tolerance`) on generated
//! floor plans and halls of 10³ edges:
//! - `gather`: the final gather at 8 points per element of a solved mesh (what
//!   `flatland solve --samples 8` writes), per call;
//! - `at_equal_elements/function_solve`: the function solve on a mesh of 4 elements per edge
//!   (its solve, the Gauss refinement's and the gather: three views per element);
//! - `to_tolerance/function_solve`: the whole default, rounds to 1 % with the error read as a
//!   function;
//! - `score`: what scoring a lighting as a function costs a lit scene of the bench (the mesh
//!   of 4 per edge, its reference that mesh cut in four): the reference gathered at 8 points
//!   per element, once per lit scene (`reference_8_per_element`), beside the reference solve
//!   it comes with (`reference_solve`), and one solution read and scored there
//!   (`read_and_score`, per method row).
//!
//! The older estimate at the collocation points and its doubling were removed; their figures
//! are in docs/FUNCTION-ERROR.md.
//!
//! Run: `cargo bench --bench field`. Samples of the solve groups take about a second.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, Scene, generate};
use flatland_solve::{
    ExactReference, FunctionReference, FunctionSolve, Mesh, SamplePoints, SolveParams,
    ToleranceParams, never, solve_to_tolerance,
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
        let fine = mesh
            .split(&kernel, &vec![4; mesh.len()])
            .expect("fine mesh");
        group.bench_function("score/reference_solve", |b| {
            b.iter(|| ExactReference::on_mesh(&kernel, black_box(fine.clone()), &params, &never))
        });
        let reference = ExactReference::on_mesh(&kernel, fine, &params, &never).expect("solve");
        group.bench_function("score/reference_8_per_element", |b| {
            b.iter(|| FunctionReference::new(black_box(&reference), &mesh, &never))
        });
        let scoring = FunctionReference::new(&reference, &mesh, &never).expect("gather");
        let b_mesh = &solve.coarse.solution().radiosity;
        group.bench_function("score/read_and_score", |b| {
            b.iter(|| scoring.errors(black_box(b_mesh)))
        });
        group.finish();
    }
}

criterion_group!(benches, field);
criterion_main!(benches);
