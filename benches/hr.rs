//! Hierarchical-radiosity link building: on `fig3`, the ray-free F_ε search for 400 links and
//! one whole build (refinement + 20 rays per link) there; on a generated floor plan of 200
//! edges, the budget search and the build at twice its initial linking.

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_baselines::{
    HierarchicalRadiosity, HrParams, count_initial_links, f_eps_for_budget, hr_params_for_budget,
};
use flatland_geom::{Kernel, Scene, generate};
use std::hint::black_box;
use std::time::Duration;

fn fig3() -> Kernel {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fig3.ron");
    Kernel::new(Scene::load(path).expect("scenes/fig3.ron loads"))
}

fn hr_fig3(c: &mut Criterion) {
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

fn hr_floor_plan(c: &mut Criterion) {
    let kernel = Kernel::new(generate::floor_plan(200, 1).expect("a floor plan"));
    let params = HrParams::default();
    let budget = 2 * count_initial_links(&kernel) as usize;
    let (at, links) = hr_params_for_budget(&kernel, budget, &params).expect("budget search");
    let mut group = c.benchmark_group("hr_floor_plan_200");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    group.bench_function(format!("params_for_budget_{budget}"), |b| {
        b.iter(|| hr_params_for_budget(black_box(&kernel), budget, &params).expect("search"))
    });
    group.bench_function(format!("build_{links}_links"), |b| {
        b.iter(|| HierarchicalRadiosity::build(black_box(&kernel), &at, 1).expect("build"))
    });
    group.finish();
}

criterion_group!(benches, hr_fig3, hr_floor_plan);
criterion_main!(benches);
