//! Cost of one SGCS learning step at 100, 400 and 4000 cells, in the radiosity shape
//! (n = 4, m = 1, inputs on a 2D surface in the unit box, like γ(s, t) for a square room).
//!
//! Each network is grown with a short insertion interval until it has the wanted size, then
//! `max_cells` freezes it and the bench measures plain steps (growth every λ = 300 steps would add
//! about one insertion's cost / 300 per step). Samples come from a precomputed ring, so only the
//! network is timed. Aim: the step at 4000 cells costs at most 3× the step at 400.
//! Measured with `-- --warm-up-time 1 --measurement-time 3` on 2 cores shared with other builds
//! (load ≈ 7): step 4.3 / 14.0 / 21.5 µs, predict 3.0 / 9.7 / 18.4 µs at 100 / 400 / 4000 cells.
//!
//! `cargo bench --bench sgcs_step` (quick: `-- --warm-up-time 1 --measurement-time 3`).
//! The 10⁷-step soak lives in the sgcs crate as an ignored test:
//! `cargo test --release -p sgcs -- --ignored soak`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sgcs::{Network, Params};

/// A point on the unit square's perimeter, `u ∈ [0, 1)`.
fn perimeter(u: f64) -> (f64, f64) {
    let u = u * 4.0;
    match u as u32 {
        0 => (u, 0.0),
        1 => (1.0, u - 1.0),
        2 => (3.0 - u, 1.0),
        _ => (0.0, 4.0 - u),
    }
}

/// A kernel-like sample: two points on the room's walls, a smooth falloff and a sharp step.
fn sample(rng: &mut ChaCha8Rng) -> ([f64; 4], f64) {
    let (s, t) = (rng.random::<f64>(), rng.random::<f64>());
    let (a, b) = (perimeter(s), perimeter(t));
    let d2 = (a.0 - b.0).powi(2) + (a.1 - b.1).powi(2);
    let shadow = if (s * 7.0).fract() > 0.5 { 1.0 } else { 0.3 };
    ([a.0, a.1, b.0, b.1], shadow / (0.05 + d2))
}

fn grown(cells: usize, rng: &mut ChaCha8Rng) -> Network {
    let simplex = vec![
        vec![0.2, 0.0, 1.0, 0.5],
        vec![0.5, 0.0, 0.5, 1.0],
        vec![0.0, 0.5, 1.0, 0.8],
    ];
    let fast = Params {
        lambda: 30,
        max_cells: cells,
        ..Params::default()
    };
    let mut net = Network::new(fast, 4, 1, &simplex).expect("valid network");
    while net.len() < cells {
        let (x, z) = sample(rng);
        net.step(&x, &[z]);
    }
    // Settle at the paper's λ so positions are not mid-growth.
    net.set_params(Params {
        lambda: 300,
        max_cells: cells,
        ..Params::default()
    })
    .expect("valid params");
    for _ in 0..20 * cells {
        let (x, z) = sample(rng);
        net.step(&x, &[z]);
    }
    net
}

fn step(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let ring: Vec<([f64; 4], f64)> = (0..65_536).map(|_| sample(&mut rng)).collect();
    let mut group = c.benchmark_group("sgcs_step");
    group.throughput(Throughput::Elements(1));
    for cells in [100, 400, 4000] {
        let mut net = grown(cells, &mut rng);
        let mut i = 0usize;
        group.bench_with_input(BenchmarkId::from_parameter(cells), &cells, |b, _| {
            b.iter(|| {
                let (x, z) = &ring[i & 65_535];
                i += 1;
                black_box(net.step(black_box(x), &[*z]))
            })
        });
        let mut j = 0usize;
        group.bench_with_input(BenchmarkId::new("predict", cells), &cells, |b, _| {
            b.iter(|| {
                let (x, _) = &ring[j & 65_535];
                j += 1;
                black_box(net.predict1(black_box(x)))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
