//! A whole SGCS fit of `fig3`: S₀, θ-resampling, growth to the target cells, refit — what
//! `flatland fit` does, minus the reference grid (built once, outside the timing).

use std::ops::ControlFlow;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_geom::{Kernel, Scene};
use kernel_fit::{Fit, FitParams, Reference};

fn fig3() -> Arc<Kernel> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fig3.ron");
    Arc::new(Kernel::new(
        Scene::load(path).expect("scenes/fig3.ron loads"),
    ))
}

fn whole_fit(c: &mut Criterion) {
    let kernel = fig3();
    let reference = Arc::new(Reference::new(&kernel, 64, 1024, 0));
    let mut group = c.benchmark_group("fit_fig3");
    group.sample_size(10);
    for cells in [100, 400] {
        for refit in [false, true] {
            let params = FitParams {
                target_cells: cells,
                refit,
                eval_every: 0,
                ..FitParams::default()
            };
            let name = format!("{cells}_cells{}", if refit { "_refit" } else { "" });
            group.bench_function(name, |b| {
                b.iter(|| {
                    let mut fit = Fit::new(Arc::clone(&kernel), Arc::clone(&reference), params)
                        .expect("valid parameters");
                    fit.train(u64::MAX, |_| ControlFlow::Continue(()));
                    if refit {
                        fit.refit().expect("refit");
                    }
                    fit.network().len()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, whole_fit);
criterion_main!(benches);
