//! The seeded generators of every test: ChaCha8 streams of a seed, by the project's rule
//! (`flatland_solve::seeds::stream`, whose test checks that both draw the same numbers), so a
//! test draws the same on any machine and never depends on the clock.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// The generator of a test's draws from `seed`: stream 0 of the seed.
#[must_use]
pub fn rng(seed: u64) -> ChaCha8Rng {
    stream(seed, 0)
}

/// Stream `stream` of `seed`, for a test that needs independent draws of one seed.
#[must_use]
pub fn stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;

    #[test]
    fn a_seed_repeats_and_streams_differ() {
        let draw = |mut r: ChaCha8Rng| -> Vec<u64> { (0..4).map(|_| r.random()).collect() };
        assert_eq!(draw(rng(7)), draw(rng(7)));
        assert_eq!(draw(rng(7)), draw(ChaCha8Rng::seed_from_u64(7)));
        assert_ne!(draw(rng(7)), draw(rng(8)));
        assert_ne!(draw(stream(7, 1)), draw(rng(7)));
    }
}
