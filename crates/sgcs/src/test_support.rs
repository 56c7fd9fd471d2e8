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
