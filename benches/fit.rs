//! Whole fits and single fit steps, as `flatland fit` runs them (the reference grid is built
//! once, outside the timing):
//!
//! - `fit/default_maze_400`: the visibility network (visibility only) on `maze` to 400 cells;
//! - `fit/default_convex_4096_400`: the same on issue 20's convex room (4096 inward walls
//!   around a box of 4 blockers, `examples/convex_room.rs`), a new kernel each time (so no
//!   pair classified in one run is kept for the next): its pairs where visibility varies are
//!   found by the kernel's bundle walk and drawn by a binary search (issue 20: 270 s and more
//!   before, when the draws were rejected on the whole square);
//! - `fit/paper_fig3_400`: the paper's network on `fig3` to 400 cells, without its refit;
//! - `fit/paper_fig3_400_finish`: how that fit ends (`Fit::finish`): its least-squares refit
//!   (ridge chosen on held-back samples, then the final solve) and the final errors against a
//!   64² grid and 1024 held-out points;
//! - `fit_step/*`: one `Fit::step` of each learner at 400 cells, growth done (the network is
//!   full, no new sample sets): the network step plus what the driver does around it.
//!
//! `cargo bench --bench fit`.

use std::ops::ControlFlow;
use std::sync::Arc;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use flatland_geom::{Kernel, Scene};
use flatland_solve::Reference;
use kernel_fit::{Fit, FitParams};

fn kernel(name: &str) -> Arc<Kernel> {
    let path = format!("{}/scenes/{name}.ron", env!("CARGO_MANIFEST_DIR"));
    Arc::new(Kernel::new(Scene::load(path).expect("bundled scene loads")))
}

/// Issue 20's convex room of `walls` inward walls around a box of 4 blockers.
fn convex_room(walls: usize) -> Arc<Kernel> {
    use flatland_geom::Edge;
    use flatland_testkit::rooms;
    let mut edges = Edge::polygon(&rooms::regular_polygon(walls, 10.0), 0.5);
    edges[0] = edges[0].with_emission(1.0);
    let c = rooms::off_centre_box();
    edges.extend((0..4).map(|i| Edge::blocker(c[i], c[(i + 1) % 4])));
    Arc::new(Kernel::new(Scene::new(edges).expect("a valid room")))
}

fn new_fit(kernel: &Arc<Kernel>, params: FitParams) -> Fit {
    let reference = Arc::new(Reference::new(kernel, 64, 1024, 0));
    Fit::new(Arc::clone(kernel), reference, params).expect("valid parameters")
}

fn params(paper: bool, cells: usize) -> FitParams {
    let base = if paper {
        FitParams::paper()
    } else {
        FitParams::default()
    };
    FitParams {
        target_cells: cells,
        eval_every: 0,
        ..base
    }
}

fn train(fit: &mut Fit) {
    fit.train(u64::MAX, |_| ControlFlow::Continue(()));
}

fn whole_fit(c: &mut Criterion) {
    let (maze, fig3) = (kernel("maze"), kernel("fig3"));
    let mut group = c.benchmark_group("fit");
    group.sample_size(10);
    group.bench_function("default_maze_400", |b| {
        b.iter(|| {
            let mut fit = new_fit(&maze, params(false, 400));
            train(&mut fit);
            fit.network().len()
        })
    });
    let convex = convex_room(4096);
    group.bench_function("default_convex_4096_400", |b| {
        b.iter(|| {
            // A kernel of its own each time: the pairs it classified are not kept from the last.
            let kernel = Arc::new(Kernel::new(convex.scene().clone()));
            let mut fit = new_fit(&kernel, params(false, 400));
            train(&mut fit);
            fit.network().len()
        })
    });
    group.bench_function("paper_fig3_400", |b| {
        b.iter(|| {
            let mut fit = new_fit(&fig3, params(true, 400));
            train(&mut fit);
            fit.network().len()
        })
    });
    let mut trained = new_fit(&fig3, params(true, 400));
    train(&mut trained);
    group.bench_function("paper_fig3_400_finish", |b| {
        b.iter_batched(
            || trained.clone(),
            |mut fit| fit.finish().expect("finish"),
            BatchSize::LargeInput,
        )
    });
    group.finish();
}

/// A fit at `cells` cells that keeps stepping without growing or resampling.
fn full(kernel: &Arc<Kernel>, paper: bool, cells: usize) -> Fit {
    let mut fit = new_fit(kernel, params(paper, cells));
    train(&mut fit);
    assert_eq!(fit.network().len(), cells, "grown to the target");
    let mut p = *fit.params();
    // No growth period can end, so the target-cells rule never stops it.
    p.network.lambda = u32::MAX;
    p.max_steps = 1 << 50; // the most it takes: no step budget ends it either
    fit.set_params(p.live()).expect("valid parameters");
    fit
}

fn fit_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("fit_step");
    group.throughput(Throughput::Elements(1));
    for (name, scene, paper) in [
        ("default_maze", "maze", false),
        ("paper_fig3", "fig3", true),
    ] {
        let mut fit = full(&kernel(scene), paper, 400);
        group.bench_function(format!("{name}_400"), |b| {
            b.iter(|| {
                fit.step();
            })
        });
    }
    group.finish();
}

criterion_group!(benches, whole_fit, fit_step);
criterion_main!(benches);
