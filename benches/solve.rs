//! Solving `B = E + K B` at 1024 elements on `fig3` and `maze`: the whole solve (operator and
//! GMRES) with the exact kernel, the default learned kernel (`flatland fit --cells 400`; on
//! `fig3` it converges with fewer cells), HR and the uniform grid at 400 basis functions, and the
//! linear solve alone. The representations are built once, outside the timing: this measures
//! what it costs to *use* a kernel.

use std::ops::ControlFlow;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_baselines::{HrParams, UniformParams, run_hr_at_budget, run_uniform};
use flatland_geom::Kernel;
use flatland_solve::{Mesh, Reference, SolveParams, exact_operator, never, solve, solve_operator};
use kernel_fit::{Fit, FitParams};
use std::hint::black_box;

const ELEMENTS: usize = 1024;
const BASIS: usize = 400;

fn bundled(name: &str) -> Kernel {
    Kernel::new(flatland_geom::bundled::scene(name).expect("a bundled scene loads"))
}

fn solves(c: &mut Criterion) {
    for name in ["fig3", "maze"] {
        let kernel = bundled(name);
        let mesh = Mesh::new(&kernel, ELEMENTS).expect("mesh");
        let params = SolveParams::default();
        let mut group = c.benchmark_group(format!("solve_{name}_1024_elements"));
        group.sample_size(10);

        group.bench_function("exact", |b| {
            b.iter(|| solve(black_box(&kernel), &mesh, &params, &never).expect("solve"))
        });
        let op = exact_operator(&kernel, &mesh, &never).expect("operator");
        group.bench_function("exact_gmres_only", |b| {
            b.iter(|| solve_operator(black_box(&op), &mesh, &params, &never).expect("solve"))
        });

        let hr = run_hr_at_budget(&kernel, BASIS, 1, &HrParams::default())
            .expect("hr")
            .approx;
        group.bench_function("hr_400_links", |b| {
            b.iter(|| solve(black_box(&hr), &mesh, &params, &never).expect("solve"))
        });
        let uniform = run_uniform(&kernel, BASIS, 1, &UniformParams::default())
            .expect("uniform")
            .approx;
        group.bench_function("uniform_400_blocks", |b| {
            b.iter(|| solve(black_box(&uniform), &mesh, &params, &never).expect("solve"))
        });

        // The visibility network, as `flatland fit --cells 400` fits it.
        let shared = Arc::new(bundled(name));
        let reference = Arc::new(Reference::new(&shared, 64, 1024, 0));
        let fit_params = FitParams {
            target_cells: BASIS,
            eval_every: 0,
            ..FitParams::default()
        };
        let mut fit = Fit::new(shared, reference, fit_params).expect("fit");
        fit.run(u64::MAX, |_| ControlFlow::Continue(()))
            .expect("fit runs");
        let learned = fit.model().clone();
        let cells = fit.network().len();
        group.bench_function(format!("learned_{cells}_cells"), |b| {
            b.iter(|| solve(black_box(&learned), &mesh, &params, &never).expect("solve"))
        });
        group.finish();
    }
}

criterion_group!(benches, solves);
criterion_main!(benches);
