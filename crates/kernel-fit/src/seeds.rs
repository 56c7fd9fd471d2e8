//! The learner's seed streams. Each random choice draws from its own ChaCha8 stream of the
//! run's seed ([`stream`], the rule of `flatland_solve::seeds`), so adding draws to one never
//! shifts another, and a run is the same for a seed on any machine and thread count.

pub use flatland_solve::seeds::stream;

/// A fit's initial sample set S₀.
pub const FIT_INITIAL: u64 = 1;
/// A fit's resampled sets S₁, S₂, ….
pub const FIT_RESAMPLE: u64 = 2;
/// The order a fit presents its samples in.
pub const FIT_TRAIN: u64 = 3;

#[cfg(test)]
mod tests {
    use super::*;
    use rand::RngExt;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn streams_of_one_seed_differ_and_repeat() {
        let draw = |mut r: ChaCha8Rng| -> Vec<u64> { (0..4).map(|_| r.random()).collect() };
        assert_eq!(draw(stream(7, FIT_TRAIN)), draw(stream(7, FIT_TRAIN)));
        assert_ne!(draw(stream(7, FIT_TRAIN)), draw(stream(7, FIT_RESAMPLE)));
    }
}
