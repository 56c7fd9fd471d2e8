//! The shafts of pairs of surface edges, classified on first use and kept in bounded memory.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;
use std::ops::Deref;
use std::sync::{Arc, OnceLock, RwLock};

use crate::hashing::{WordHasher, mix};
use crate::visibility::Shaft;

/// Up to this many surface parents every pair has a cell of its own (n² lazily filled cells,
/// 12 MB at most), which the hot loop of visibility indexes directly. Above it a table over
/// all pairs would grow with the square of the scene: pairs are kept in bounded shards instead.
pub(super) const MAX_DENSE_SURFACES: usize = 512;

/// Shards of the bounded cache (threads asking for different pairs rarely share a lock).
const SHARDS: usize = 64;

/// What the bounded cache may hold, in bytes (shafts, their occluders and events, the maps):
/// a shard that would grow past its share is emptied and fills again with what is asked next.
/// Classification is a pure function of the pair, so what was dropped comes back the same.
const CACHE_BYTES: usize = 64 << 20;

/// The shafts of one scene's pairs of surface parents, by rank.
pub(super) enum PairCache {
    /// `cells[r0 * n + r1]` for ranks `r0 < r1`.
    Dense {
        n: usize,
        cells: Vec<OnceLock<Shaft>>,
    },
    /// Pairs by `r0 << 32 | r1`, and the bytes each shard may hold.
    Sharded {
        shards: Box<[RwLock<Shard>]>,
        shard_bytes: usize,
    },
}

/// One shard of [`PairCache::Sharded`].
#[derive(Default)]
pub(super) struct Shard {
    map: HashMap<u64, Arc<Shaft>, BuildHasherDefault<WordHasher>>,
    bytes: usize,
}

/// A shaft from the cache: borrowed from the dense table, or shared with a shard (which may
/// drop its own copy meanwhile).
#[derive(Debug)]
pub(crate) enum ShaftRef<'a> {
    Borrowed(&'a Shaft),
    Shared(Arc<Shaft>),
}

impl Deref for ShaftRef<'_> {
    type Target = Shaft;

    fn deref(&self) -> &Shaft {
        match self {
            ShaftRef::Borrowed(shaft) => shaft,
            ShaftRef::Shared(shaft) => shaft,
        }
    }
}

impl PairCache {
    /// An empty cache for `n` surface parents.
    pub(super) fn new(n: usize) -> PairCache {
        if n <= MAX_DENSE_SURFACES {
            PairCache::Dense {
                n,
                cells: (0..n * n).map(|_| OnceLock::new()).collect(),
            }
        } else {
            PairCache::sharded(CACHE_BYTES)
        }
    }

    /// An empty sharded cache holding at most about `bytes`.
    fn sharded(bytes: usize) -> PairCache {
        PairCache::Sharded {
            shards: (0..SHARDS).map(|_| RwLock::default()).collect(),
            shard_bytes: bytes / SHARDS,
        }
    }

    /// The shaft of ranks `r0 < r1`: kept, or made by `classify` and kept.
    #[inline]
    pub(super) fn get(
        &self,
        r0: usize,
        r1: usize,
        classify: impl FnOnce() -> Shaft,
    ) -> ShaftRef<'_> {
        match self {
            PairCache::Dense { n, cells } => {
                ShaftRef::Borrowed(cells[r0 * n + r1].get_or_init(classify))
            }
            PairCache::Sharded {
                shards,
                shard_bytes,
            } => ShaftRef::Shared(shared(shards, *shard_bytes, r0, r1, classify)),
        }
    }

    /// The dense table's shaft of ranks `r0 < r1` (made by `classify` if new); `None` for a
    /// sharded cache, where a pair met once costs less as a ray than as a classification.
    #[inline(always)]
    pub(super) fn dense(
        &self,
        r0: usize,
        r1: usize,
        classify: impl FnOnce() -> Shaft,
    ) -> Option<&Shaft> {
        match self {
            PairCache::Dense { n, cells } => Some(cells[r0 * n + r1].get_or_init(classify)),
            PairCache::Sharded { .. } => None,
        }
    }

    /// How many cells the dense table has (0 for a sharded cache).
    #[cfg(test)]
    pub(super) fn dense_cells(&self) -> usize {
        match self {
            PairCache::Dense { cells, .. } => cells.len(),
            PairCache::Sharded { .. } => 0,
        }
    }

    /// Pairs and bytes the sharded cache holds now (`None` for a dense table).
    #[cfg(test)]
    pub(super) fn sharded_size(&self) -> Option<(usize, usize)> {
        let PairCache::Sharded { shards, .. } = self else {
            return None;
        };
        Some(shards.iter().fold((0, 0), |(n, b), s| {
            let s = s.read().unwrap_or_else(std::sync::PoisonError::into_inner);
            (n + s.map.len(), b + s.bytes)
        }))
    }
}

/// The shaft of ranks `r0 < r1` from its shard, classified outside the lock if it is not there
/// (two threads may both classify a new pair; they find the same shaft).
fn shared(
    shards: &[RwLock<Shard>],
    shard_bytes: usize,
    r0: usize,
    r1: usize,
    classify: impl FnOnce() -> Shaft,
) -> Arc<Shaft> {
    let key = ((r0 as u64) << 32) | r1 as u64;
    let shard = &shards[(mix(key) >> 58) as usize % SHARDS];
    // A poisoned lock only means a panic elsewhere; the map itself is always consistent.
    if let Some(found) = shard
        .read()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
        .map
        .get(&key)
    {
        return Arc::clone(found);
    }
    let shaft = Arc::new(classify());
    let bytes = bytes_of(&shaft);
    let mut shard = shard
        .write()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if shard.bytes + bytes > shard_bytes {
        *shard = Shard::default();
    }
    if shard.map.insert(key, Arc::clone(&shaft)).is_none() {
        shard.bytes += bytes;
    }
    shaft
}

/// About the heap a kept shaft takes: its entry in the map, its allocation, its occluders and
/// event points.
fn bytes_of(shaft: &Shaft) -> usize {
    const ENTRY: usize = 2 * size_of::<u64>() + size_of::<usize>();
    let extra = match shaft {
        Shaft::Candidates(c) => {
            let events = c.events.as_ref().map_or(0, |e| {
                e.iter()
                    .map(|e| {
                        size_of_val(e) + (0..4).map(|k| size_of_val(e.points(k))).sum::<usize>()
                    })
                    .sum()
            });
            size_of_val(&*c.occluders) + events
        }
        _ => 0,
    };
    ENTRY + 2 * size_of::<usize>() + size_of::<Shaft>() + extra
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shard_stays_within_its_share_and_gives_back_what_it_dropped() {
        // 2 MB: the pairs below take about 15 MB, so shards are emptied many times.
        let budget = 2 << 20;
        let cache = PairCache::sharded(budget);
        let made = |r0: usize, r1: usize| {
            // A shaft as big as a pair's: many occluders, unique to the pair.
            let occluders: Box<[u32]> = (0..64).map(|k| (r0 * 7 + r1 * 13 + k) as u32).collect();
            Shaft::Candidates(crate::visibility::Candidates {
                occluders,
                events: None,
                interior: Some(r0.is_multiple_of(2)),
            })
        };
        for r0 in 0..300 {
            for r1 in r0 + 1..300 {
                let shaft = cache.get(r0, r1, || made(r0, r1));
                assert_eq!(*shaft, made(r0, r1));
            }
        }
        let (pairs, bytes) = cache.sharded_size().unwrap();
        assert!(bytes <= budget, "{bytes} bytes");
        assert!(pairs > 0 && pairs < 300 * 299 / 2, "{pairs} pairs kept");
        // Asked again, every pair is the same, whether it was kept or not.
        for r0 in (0..300).step_by(7) {
            for r1 in r0 + 1..300 {
                assert_eq!(*cache.get(r0, r1, || made(r0, r1)), made(r0, r1));
            }
        }
    }
}
