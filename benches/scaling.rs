//! Cost against scene size: the light-driven learner's fit (`LightFit` to its default tolerance)
//! and solve, and the exact solve, on generated floor plans of 10², 10³ and 10⁴ edges, each
//! on the mesh `flatland solve` chooses (its exact solve's estimated error of B − E as a
//! function below 1 %, `solve_to_tolerance`). Read
//! the ratios between sizes: 10× the edges should cost about 10× (the log–log slope, which
//! `flatland bench --scaling` reports with memory and error, is ≤ 1.3).
//!
//! Run: `cargo bench --bench scaling`. The 10⁴-edge rows take seconds per sample.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, generate};
use flatland_light::{LightFit, LightParams};
use flatland_solve::{
    ExactReference, SolveParams, ToleranceParams, never, solve, solve_to_tolerance,
};

fn scaling(c: &mut Criterion) {
    for edges in [100, 1_000, 10_000] {
        let mut group = c.benchmark_group(format!("scaling_{edges}_edges"));
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(if edges < 10_000 { 10 } else { 60 }));
        let kernel = Arc::new(Kernel::new(
            generate::floor_plan(edges, 1).expect("a floor plan"),
        ));
        let params = SolveParams::default();
        let found = solve_to_tolerance(&kernel, &ToleranceParams::default(), &params, &never)
            .expect("a mesh");
        let mesh = found.solve.coarse.mesh().clone();
        group.bench_function("default_fit_and_solve", |b| {
            b.iter(|| {
                let mut fit =
                    LightFit::new(Arc::clone(&kernel), mesh.clone(), LightParams::default())
                        .expect("fit");
                fit.run(&never, |_| {}).expect("rounds");
                black_box(solve(&fit, &mesh, &params, &never).expect("solve"))
            })
        });
        group.bench_function("exact_solve", |b| {
            b.iter(|| {
                black_box(
                    ExactReference::on_mesh(black_box(&kernel), mesh.clone(), &params, &never)
                        .expect("exact"),
                )
            })
        });
        group.finish();
    }
}

criterion_group!(benches, scaling);
criterion_main!(benches);
