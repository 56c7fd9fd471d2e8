//! Solving `B = E + K B` on `fig3` at 1024 elements: the whole solve (operator and GMRES) with
//! the exact kernel, the learned kernel (400 cells), HR and the uniform grid at 400 basis
//! functions, the linear solve alone, and the geometric operator a visibility learner would
//! use (with a constant Ṽ). The representations are built once, outside the
//! timing: this measures what it costs to *use* a kernel.

use std::ops::ControlFlow;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, Scene};
use kernel_fit::baselines::{HrParams, UniformParams, run_hr_at_budget, run_uniform};
use kernel_fit::solve::{
    KernelRepresentation, Mesh, SolveParams, exact_operator, geometric_operator, never, solve,
    solve_operator,
};
use kernel_fit::{Fit, FitParams, Reference};
use std::hint::black_box;

const ELEMENTS: usize = 1024;
const BASIS: usize = 400;

fn fig3() -> Kernel {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fig3.ron");
    Kernel::new(Scene::load(path).expect("scenes/fig3.ron loads"))
}

fn solves(c: &mut Criterion) {
    let kernel = fig3();
    let mesh = Mesh::new(&kernel, ELEMENTS).expect("mesh");
    let params = SolveParams::default();
    let mut group = c.benchmark_group("solve_fig3_1024_elements");
    group.sample_size(10);

    group.bench_function("exact", |b| {
        b.iter(|| solve(black_box(&kernel), &mesh, &params, &never).expect("solve"))
    });
    let op = exact_operator(&kernel, &mesh, &never).expect("operator");
    group.bench_function("exact_gmres_only", |b| {
        b.iter(|| solve_operator(black_box(&op), &mesh, &params, &never).expect("solve"))
    });

    // What a learner of the visibility alone pays besides its own evaluations: the closed
    // form everywhere, the element-level shadow test, and a (here constant) Ṽ for the few
    // partly shadowed pairs.
    group.bench_function("geometric_constant_visibility", |b| {
        b.iter(|| {
            let op = geometric_operator(black_box(&kernel), &mesh, |_, _| 0.5, &never)
                .expect("operator");
            solve_operator(&op, &mesh, &params, &never).expect("solve")
        })
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

    // The default learner, as `flatland fit --cells 400` fits it.
    let shared = Arc::new(fig3());
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
    assert_eq!(learned.basis_functions(), Some(BASIS));
    group.bench_function("learned_400_cells", |b| {
        b.iter(|| solve(black_box(&learned), &mesh, &params, &never).expect("solve"))
    });
    group.finish();
}

criterion_group!(benches, solves);
criterion_main!(benches);
