//! Hierarchical-radiosity refinement on `fig3`: the ray-free F_ε search for a budget, and one
//! whole build (refinement + 20 rays per link) at the F_ε that gives about 400 links.

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_baselines::{HierarchicalRadiosity, HrParams, f_eps_for_budget};
use flatland_geom::{Kernel, Scene};
use std::hint::black_box;

fn fig3() -> Kernel {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fig3.ron");
    Kernel::new(Scene::load(path).expect("scenes/fig3.ron loads"))
}

fn hr(c: &mut Criterion) {
    let kernel = fig3();
    let params = HrParams::default();
    let (f_eps, links) = f_eps_for_budget(&kernel, 400, &params).expect("budget search");
    let at = HrParams { f_eps, ..params };
    let mut group = c.benchmark_group("hr_fig3");
    group.sample_size(20);
    group.bench_function(format!("build_{links}_links"), |b| {
        b.iter(|| HierarchicalRadiosity::build(black_box(&kernel), &at, 1).expect("build"))
    });
    group.bench_function("f_eps_search_400", |b| {
        b.iter(|| f_eps_for_budget(black_box(&kernel), 400, &params).expect("search"))
    });
    group.finish();
}

criterion_group!(benches, hr);
criterion_main!(benches);
