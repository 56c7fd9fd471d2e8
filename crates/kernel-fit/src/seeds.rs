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

/// A seed for item `item` of a run with `seed` (the baselines' per-link and per-grid draws):
/// the SplitMix64 finaliser, so neighbouring items get unrelated seeds.
#[must_use]
pub fn item(seed: u64, item: u64) -> u64 {
    let mut z = seed
        ^ item
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .wrapping_add(0x632b_e59b_d9b4_e019);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

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
        assert_ne!(item(7, 0), item(7, 1));
        assert_eq!(item(7, 3), item(7, 3));
    }
}
