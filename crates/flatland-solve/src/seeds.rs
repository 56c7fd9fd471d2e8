//! The rule every seed stream follows. Each random choice draws from its own ChaCha8 stream of
//! the run's seed, so adding draws to one never shifts another, and a run is the same for a seed
//! on any machine and thread count. The named streams live with the code that draws them
//! (`kernel_fit::seeds` for a fit's, `flatland_lab::rooms` for the random rooms); the baselines
//! derive per-item seeds (`flatland_baselines`).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Stream `stream` of `seed`.
#[must_use]
pub fn stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// The held-out points of a reference drawn with `seed` (an offset seed, so they never
/// coincide with a training stream of the same seed).
#[must_use]
pub fn heldout(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9_7f4a_7c15)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;

    #[test]
    fn streams_of_one_seed_differ_and_repeat() {
        let draw = |mut r: ChaCha8Rng| -> Vec<u64> { (0..4).map(|_| r.random()).collect() };
        assert_eq!(draw(stream(7, 3)), draw(stream(7, 3)));
        assert_ne!(draw(stream(7, 3)), draw(stream(7, 2)));
        assert_ne!(draw(heldout(7)), draw(stream(7, 0)));
    }

    /// The tests' generators (`flatland_testkit`, which cannot depend on this crate) follow
    /// this rule: the same numbers for the same seed and stream.
    #[test]
    fn the_tests_generators_follow_the_rule() {
        let draw = |mut r: ChaCha8Rng| -> Vec<u64> { (0..4).map(|_| r.random()).collect() };
        for seed in [0, 7, u64::MAX] {
            assert_eq!(draw(flatland_testkit::rng(seed)), draw(stream(seed, 0)));
            assert_eq!(
                draw(flatland_testkit::stream(seed, 5)),
                draw(stream(seed, 5))
            );
        }
    }
}
