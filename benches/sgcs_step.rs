//! Cost of one SGCS learning step at 100, 400 and 4000 cells, in the radiosity shape
//! (n = 4, m = 1, inputs on a 2D surface in the unit box, like γ(s, t) for a square room), for
//! both networks the project trains:
//!
//! - `sgcs_step/paper/*`: the paper's network (`Params::default()`: summed output, NLMS,
//!   insertion at edge midpoints), ungated;
//! - `sgcs_step/default/*`: a network configured like the visibility network (normalised output,
//!   local rule, insertion at the worst sample, error-sum resource), stepped with a region gate
//!   like kernel-fit's `FaceGate`: the regions are the cells of an arrangement of hyperplanes
//!   (as a face is the cell of an arrangement of event-point curves), a region's cells are
//!   named and the cells of its "pair" (the region of the first few hyperplanes) are the
//!   fallback. The caller's upkeep of the regions after each step (re-filing the cells that
//!   moved, as `Fit` does) is part of the timed step.
//!
//! Each network is grown with a short insertion interval until it has the wanted size, then
//! `max_cells` freezes it and the bench measures plain steps (growth every λ = 300 steps would add
//! about one insertion's cost / 300 per step). Samples come from a precomputed ring, so only the
//! network is timed. Aim: the step at 4000 cells costs at most 3× the step at 400 (figures:
//! README's benchmark section).
//!
//! `cargo bench --bench sgcs_step` (quick: `-- --warm-up-time 1 --measurement-time 3`).
//! The 10⁷-step soak lives in the sgcs crate as an ignored test:
//! `cargo test --release -p sgcs -- --ignored soak`.

use std::collections::HashMap;
use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use sgcs::{CellId, Gate, Insertion, Network, OutputMode, OutputRule, Params, Resource};

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

fn simplex() -> Vec<Vec<f64>> {
    vec![
        vec![0.2, 0.0, 1.0, 0.5],
        vec![0.5, 0.0, 0.5, 1.0],
        vec![0.0, 0.5, 1.0, 0.8],
    ]
}

fn grown_paper(cells: usize, rng: &mut ChaCha8Rng) -> Network {
    let fast = Params {
        lambda: 30,
        max_cells: cells,
        ..Params::default()
    };
    let mut net = Network::new(fast, 4, 1, &simplex()).expect("valid network");
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

/// Cells of regions that an arrangement of hyperplanes cuts the input space into, kept up to
/// date as cells move: what kernel-fit's `Faces` is for the faces of the visibility structure.
struct Regions {
    /// Hyperplanes `(normal, offset)`: the side of `x` is `normal · x > offset`.
    planes: Vec<([f64; 4], f64)>,
    /// Per cell its region (one bit per hyperplane).
    of: Vec<u128>,
    cells: HashMap<u128, Vec<CellId>>,
    /// Per "pair" (the bits of the first `pair_bits` hyperplanes) its cells.
    pairs: HashMap<u128, Vec<CellId>>,
    pair_mask: u128,
}

impl Regions {
    /// `count` hyperplanes through random sample inputs, with random normals; the first
    /// `pair_bits` of them cut out the pairs.
    fn new(count: usize, pair_bits: usize, rng: &mut ChaCha8Rng) -> Regions {
        assert!(count <= 128);
        let planes = (0..count)
            .map(|_| {
                let (x, _) = sample(rng);
                let normal: [f64; 4] = std::array::from_fn(|_| rng.random::<f64>() - 0.5);
                let offset = (0..4).map(|d| normal[d] * x[d]).sum();
                (normal, offset)
            })
            .collect();
        Regions {
            planes,
            of: Vec::new(),
            cells: HashMap::new(),
            pairs: HashMap::new(),
            pair_mask: (1 << pair_bits) - 1,
        }
    }

    fn key(&self, x: &[f64]) -> u128 {
        let mut key = 0u128;
        for (i, (normal, offset)) in self.planes.iter().enumerate() {
            let side = (0..4).map(|d| normal[d] * x[d]).sum::<f64>() > *offset;
            key |= u128::from(side) << i;
        }
        key
    }

    fn pair(&self, key: u128) -> u128 {
        key & self.pair_mask
    }

    /// The target: a constant per region (0 or 1, as visibility is on a face).
    fn target(&self, x: &[f64]) -> f64 {
        let key = self.key(x);
        let mixed = key.wrapping_mul(0x9E37_79B9_7F4A_7C15_F39C_C060_5CED_C835);
        f64::from(u8::from((mixed >> 64) & 1 == 1))
    }

    /// Files `cell` under the region of its position.
    fn place(&mut self, net: &Network, cell: CellId) {
        let key = self.key(net.position(cell));
        if cell == self.of.len() {
            self.of.push(key);
        } else if self.of[cell] == key {
            return;
        } else {
            let old = self.of[cell];
            let old_pair = self.pair(old);
            remove_sorted(self.cells.get_mut(&old).expect("filed"), cell);
            remove_sorted(self.pairs.get_mut(&old_pair).expect("filed"), cell);
            self.of[cell] = key;
        }
        let pair = self.pair(key);
        insert_sorted(self.cells.entry(key).or_default(), cell);
        insert_sorted(self.pairs.entry(pair).or_default(), cell);
    }

    fn gate(&self, x: &[f64]) -> RegionGate<'_> {
        let key = self.key(x);
        RegionGate {
            of: &self.of,
            key,
            region: self.cells.get(&key).map_or(&[][..], Vec::as_slice),
            fallback: self
                .pairs
                .get(&self.pair(key))
                .map_or(&[][..], Vec::as_slice),
        }
    }

    /// One gated step, then the cells that moved are re-filed.
    fn step(&mut self, net: &mut Network, x: &[f64; 4], target: f64) -> sgcs::StepOutcome {
        let gate = self.gate(x);
        let outcome = net
            .try_step_gated(x, &[target], 1.0, &gate)
            .expect("finite sample");
        for i in 0..net.moved_cells().len() {
            let c = net.moved_cells()[i];
            self.place(net, c);
        }
        outcome
    }
}

fn insert_sorted(list: &mut Vec<CellId>, cell: CellId) {
    if let Err(at) = list.binary_search(&cell) {
        list.insert(at, cell);
    }
}

fn remove_sorted(list: &mut Vec<CellId>, cell: CellId) {
    if let Ok(at) = list.binary_search(&cell) {
        list.remove(at);
    }
}

struct RegionGate<'a> {
    of: &'a [u128],
    key: u128,
    region: &'a [CellId],
    fallback: &'a [CellId],
}

impl Gate for RegionGate<'_> {
    fn admits(&self, cell: CellId) -> bool {
        self.of[cell] == self.key
    }
    fn region(&self) -> Option<&[CellId]> {
        Some(self.region)
    }
    fn fallback(&self) -> Option<&[CellId]> {
        Some(self.fallback)
    }
}

fn default_params(lambda: u32, cells: usize) -> Params {
    Params {
        lambda,
        max_cells: cells,
        output_mode: OutputMode::Normalized,
        output_rule: OutputRule::Local,
        insertion: Insertion::WorstSample,
        insert_rule: sgcs::InsertRule::SampleTarget,
        resource: Resource::ErrorSum,
        ..Params::default()
    }
}

/// A default-learner network of `cells` cells and its regions: about two regions per cell, so
/// most regions hold zero or one cell, as the faces of a default fit do (measured on `maze` at
/// 400 cells: 400 occupied faces, one cell each), and pairs of about eight cells.
fn grown_default(cells: usize, rng: &mut ChaCha8Rng) -> (Network, Regions) {
    // k lines cut a surface into about k²/2 regions.
    let planes = ((4.0 * cells as f64).sqrt() as usize).clamp(8, 128);
    let pair_bits = ((cells as f64 / 4.0).sqrt() as usize).clamp(2, planes);
    let mut regions = Regions::new(planes, pair_bits, rng);
    let mut net = Network::new(default_params(30, cells), 4, 1, &simplex()).expect("valid");
    for c in 0..3 {
        let t = regions.target(net.position(c));
        net.set_output(c, &[t]).expect("finite");
        regions.place(&net, c);
    }
    let mut steps = 0u64;
    while net.len() < cells {
        let (x, _) = sample(rng);
        let t = regions.target(&x);
        regions.step(&mut net, &x, t);
        steps += 1;
        assert!(
            steps < 1_000 * cells as u64,
            "growth stalled at {}",
            net.len()
        );
    }
    net.set_params(default_params(300, cells)).expect("valid");
    for _ in 0..20 * cells {
        let (x, _) = sample(rng);
        let t = regions.target(&x);
        regions.step(&mut net, &x, t);
    }
    (net, regions)
}

fn step(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(2026);
    let ring: Vec<([f64; 4], f64)> = (0..65_536).map(|_| sample(&mut rng)).collect();
    let mut group = c.benchmark_group("sgcs_step");
    group.throughput(Throughput::Elements(1));
    for cells in [100, 400, 4000] {
        let mut net = grown_paper(cells, &mut rng);
        let mut i = 0usize;
        group.bench_with_input(BenchmarkId::new("paper", cells), &cells, |b, _| {
            b.iter(|| {
                let (x, z) = &ring[i & 65_535];
                i += 1;
                black_box(net.step(black_box(x), &[*z]))
            })
        });
        let mut j = 0usize;
        group.bench_with_input(BenchmarkId::new("paper_predict", cells), &cells, |b, _| {
            b.iter(|| {
                let (x, _) = &ring[j & 65_535];
                j += 1;
                black_box(net.predict1(black_box(x)))
            })
        });

        let (mut net, mut regions) = grown_default(cells, &mut rng);
        let targets: Vec<f64> = ring.iter().map(|(x, _)| regions.target(x)).collect();
        let mut k = 0usize;
        group.bench_with_input(BenchmarkId::new("default", cells), &cells, |b, _| {
            b.iter(|| {
                let (x, _) = &ring[k & 65_535];
                let t = targets[k & 65_535];
                k += 1;
                black_box(regions.step(&mut net, black_box(x), t))
            })
        });
        let mut l = 0usize;
        group.bench_with_input(
            BenchmarkId::new("default_predict", cells),
            &cells,
            |b, _| {
                b.iter(|| {
                    let (x, _) = &ring[l & 65_535];
                    l += 1;
                    black_box(net.predict1_gated(black_box(x), &regions.gate(x)))
                })
            },
        );
    }
    group.finish();
}

criterion_group!(benches, step);
criterion_main!(benches);
