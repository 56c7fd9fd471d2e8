//! Shared test helpers: the one seeded generator and `assert_close!`.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The seeded generator every test uses.
pub(crate) fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// `assert_close!(a, b, tol)`: `|a − b| ≤ tol`, printing both values and the difference.
macro_rules! assert_close {
    ($a:expr, $b:expr, $tol:expr $(,)?) => {{
        let (a, b, tol): (f64, f64, f64) = ($a, $b, $tol);
        assert!(
            (a - b).abs() <= tol,
            "assert_close!({}, {}): {} vs {}, difference {:e} > tolerance {:e}",
            stringify!($a),
            stringify!($b),
            a,
            b,
            (a - b).abs(),
            tol
        );
    }};
}
pub(crate) use assert_close;

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
    use rand::RngExt;
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
