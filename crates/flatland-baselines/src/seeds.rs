//! The baselines' per-item seeds (one per HR link, one per uniform grid), derived from the run's
//! seed; the streams of the learner and of the references follow `flatland_solve::seeds`.

/// A seed for item `item` of a run with `seed` (the baselines' per-link and per-grid draws):
/// the SplitMix64 finaliser, so neighbouring items get unrelated seeds.
#[must_use]
pub(crate) fn item(seed: u64, item: u64) -> u64 {
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

    #[test]
    fn item_seeds_differ_and_repeat() {
        assert_ne!(item(7, 0), item(7, 1));
        assert_eq!(item(7, 3), item(7, 3));
    }
}
