//! Shared test helpers: test functions and networks; `assert_close!` and the seeded generator
//! are the workspace's (`flatland_testkit`), re-exported where the crate's tests name them.

use rand::RngExt;

pub(crate) use flatland_testkit::{assert_close, rng};

use crate::{
    CellId, Gate, InsertRule, Insertion, Network, OutputMode, OutputRule, Params, Resource,
};

/// The 2D test function (like the paper's Fig. 1): a smooth Gaussian bump at (0.3, 0.7) plus a
/// sharp Lorentzian ridge of half width 0.02 along the line `y = 0.2 + 0.5 x`.
pub(crate) fn bump_ridge(x: f64, y: f64) -> f64 {
    let bump = (-((x - 0.3).powi(2) + (y - 0.7).powi(2)) / 0.03).exp();
    let ridge = 1.0 / (1.0 + ((y - 0.2 - 0.5 * x) / 0.02).powi(2));
    bump + ridge
}

/// Distance from `(x, y)` to the ridge line of [`bump_ridge`].
pub(crate) fn ridge_distance(x: f64, y: f64) -> f64 {
    (y - 0.2 - 0.5 * x).abs() / 1.25f64.sqrt()
}

/// Distance from `(x, y)` to the bump's centre.
pub(crate) fn bump_distance(x: f64, y: f64) -> f64 {
    ((x - 0.3).powi(2) + (y - 0.7).powi(2)).sqrt()
}

/// `n` uniform points in the unit square.
pub(crate) fn unit_square_points(seed: u64, n: usize) -> Vec<[f64; 2]> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| [r.random::<f64>(), r.random::<f64>()])
        .collect()
}

/// Relative L2 error of `approx` against `f` over `points`.
pub(crate) fn relative_l2(
    points: &[[f64; 2]],
    approx: impl Fn(f64, f64) -> f64,
    f: impl Fn(f64, f64) -> f64,
) -> f64 {
    let (mut e, mut z) = (0.0, 0.0);
    for p in points {
        let v = f(p[0], p[1]);
        e += (approx(p[0], p[1]) - v).powi(2);
        z += v * v;
    }
    (e / z).sqrt()
}

/// `count` uniform samples of [`bump_ridge`]: inputs (flat, two a sample) and targets.
pub(crate) fn bump_ridge_samples(seed: u64, count: usize) -> (Vec<f64>, Vec<f64>) {
    let pts = unit_square_points(seed, count);
    let inputs = pts.iter().flatten().copied().collect();
    let targets = pts.iter().map(|p| bump_ridge(p[0], p[1])).collect();
    (inputs, targets)
}

/// The corners of the unit right triangle: the first simplex of most test networks.
pub(crate) fn unit_triangle() -> Vec<Vec<f64>> {
    vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]]
}

/// A network grown on uniform samples of `f` over the unit square.
pub(crate) fn grown(
    params: Params,
    steps: usize,
    seed: u64,
    f: impl Fn(f64, f64) -> f64,
) -> Network {
    let mut net = Network::new(params, 2, 1, &unit_triangle()).unwrap();
    let mut r = rng(seed);
    for _ in 0..steps {
        let (x, y) = (r.random::<f64>(), r.random::<f64>());
        net.step(&[x, y], &[f(x, y)]);
    }
    net
}

/// A network of `cells` cells (λ = 100) grown on uniform samples of [`bump_ridge`].
pub(crate) fn grown_bump_ridge(cells: usize, seed: u64) -> Network {
    let p = Params {
        lambda: 100,
        max_cells: cells,
        ..Params::default()
    };
    let mut net = Network::new(p, 2, 1, &unit_triangle()).unwrap();
    let mut r = rng(seed);
    while net.len() < cells {
        let (x, y) = (r.random::<f64>(), r.random::<f64>());
        net.step(&[x, y], &[bump_ridge(x, y)]);
    }
    net
}

/// Parameters for the gated tests: local rule, normalised output, insertion at the worst
/// sample with its target, the error-sum resource.
pub(crate) fn gated_params() -> Params {
    Params {
        lambda: 20,
        output_rule: OutputRule::Local,
        output_mode: OutputMode::Normalized,
        insertion: Insertion::WorstSample,
        insert_rule: InsertRule::SampleTarget,
        resource: Resource::ErrorSum,
        ..Params::default()
    }
}

/// What a caller that knows where its target jumps keeps: the side of `x = 0.5` of every
/// cell, and the cells of each side (ascending).
#[derive(Default)]
pub(crate) struct Halves {
    of: Vec<bool>,
    sides: [Vec<CellId>; 2],
}

impl Halves {
    pub(crate) fn update(&mut self, net: &Network) {
        self.of = (0..net.len()).map(|c| net.position(c)[0] > 0.5).collect();
        for side in 0..2 {
            self.sides[side] = (0..net.len())
                .filter(|&c| usize::from(self.of[c]) == side)
                .collect();
        }
    }

    /// The gate of an input at `x`: the cells on its side.
    pub(crate) fn gate(&self, x: f64) -> HalfGate<'_> {
        let right = x > 0.5;
        HalfGate {
            of: &self.of,
            right,
            cells: &self.sides[usize::from(right)],
        }
    }
}

/// The gate [`Halves::gate`] gives: a region, one side of `x = 0.5`.
pub(crate) struct HalfGate<'a> {
    of: &'a [bool],
    right: bool,
    cells: &'a [CellId],
}

impl Gate for HalfGate<'_> {
    fn admits(&self, c: CellId) -> bool {
        self.of[c] == self.right
    }
    fn region(&self) -> Option<&[CellId]> {
        Some(self.cells)
    }
}
