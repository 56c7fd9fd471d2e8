//! The uniform baseline on `fig3`: a 20 × 20 grid (400 basis functions), 20 rays per block.

use criterion::{Criterion, criterion_group, criterion_main};
use flatland_baselines::{UniformGrid, UniformParams};
use flatland_geom::{Kernel, Scene};
use std::hint::black_box;

fn fig3() -> Kernel {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fig3.ron");
    Kernel::new(Scene::load(path).expect("scenes/fig3.ron loads"))
}

fn uniform(c: &mut Criterion) {
    let kernel = fig3();
    let params = UniformParams::default();
    let mut group = c.benchmark_group("uniform_fig3");
    group.sample_size(20);
    group.bench_function("grid_20x20_20_rays", |b| {
        b.iter(|| UniformGrid::build(black_box(&kernel), 20, &params, 1).expect("build"))
    });
    group.finish();
}

criterion_group!(benches, uniform);
criterion_main!(benches);
