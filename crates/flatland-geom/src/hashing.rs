//! The crate's one cheap hasher, for keys made of whole 64-bit words (a pair's key, a point's
//! bit patterns): SipHash's resistance to chosen keys buys nothing there, and it took a tenth
//! of listing a floor plan's varying pairs.

use std::hash::Hasher;

/// SplitMix64's finaliser: spreads a word over all 64 bits (shards take the top ones).
#[inline]
pub(crate) fn mix(key: u64) -> u64 {
    let mut z = key.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Folds each 64-bit word in with [`mix`]: a key of one word hashes to `mix(word)`.
#[derive(Default)]
pub(crate) struct WordHasher(u64);

impl Hasher for WordHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_u64(&mut self, word: u64) {
        self.0 = mix(self.0 ^ word);
    }

    fn write_usize(&mut self, word: usize) {
        self.write_u64(word as u64);
    }
}

#[cfg(test)]
mod tests {
    use std::hash::{BuildHasher, BuildHasherDefault};

    use super::*;

    #[test]
    fn one_word_hashes_to_its_mix_and_two_words_both_count() {
        let build = BuildHasherDefault::<WordHasher>::default();
        assert_eq!(build.hash_one(42_u64), mix(42));
        let (a, b) = (build.hash_one([1_u64, 2]), build.hash_one([3_u64, 2]));
        assert_ne!(a, b, "the first word counts");
        assert_ne!(
            build.hash_one([1_u64, 2]),
            build.hash_one([1_u64, 4]),
            "so does the last"
        );
    }
}
