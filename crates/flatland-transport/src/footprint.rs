//! Where a block of `M₂` lies in `(s, t)`: the light a cluster of elements sends (its columns,
//! the senders) to the elements it reaches (its rows, the receivers), each set as runs of
//! consecutive elements — elements are in parameter order, so a run is one interval of the
//! parameter. What a viewer draws over the kernel plot as the build makes the blocks.

use std::ops::Range;

/// One block of `M₂` as built: its cluster, senders and receivers as runs of element indices,
/// and the rank it was cut to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BlockFootprint {
    /// The cluster (the block's index among the transport's blocks).
    pub cluster: usize,
    /// The cluster's elements (the block's columns) as runs `first..end`, ascending.
    pub senders: Vec<Range<u32>>,
    /// The receivers kept (the block's rows) as runs, ascending.
    pub receivers: Vec<Range<u32>>,
    /// Singular triplets kept: 0 for a block whose light was all cut.
    pub rank: usize,
}

impl BlockFootprint {
    /// The footprint of cluster `cluster`'s block: its `senders` and kept `receivers`
    /// (both ascending) and its rank.
    pub(crate) fn of(
        cluster: usize,
        senders: &[u32],
        receivers: &[u32],
        rank: usize,
    ) -> BlockFootprint {
        BlockFootprint {
            cluster,
            senders: runs(senders),
            receivers: runs(receivers),
            rank,
        }
    }

    /// Element pairs (sender, receiver) the block covers.
    #[must_use]
    pub fn pairs(&self) -> usize {
        let count = |runs: &[Range<u32>]| runs.iter().map(|r| r.len()).sum::<usize>();
        count(&self.senders) * count(&self.receivers)
    }
}

/// What sees each block of a build as it is made
/// ([`Transport::build_watched`](crate::Transport::build_watched)); called from the build's
/// threads.
pub type Watch<'a> = dyn Fn(BlockFootprint) + Sync + 'a;

/// Ascending indices as runs of consecutive ones.
fn runs(ascending: &[u32]) -> Vec<Range<u32>> {
    let mut out: Vec<Range<u32>> = Vec::new();
    for &i in ascending {
        match out.last_mut() {
            Some(run) if run.end == i => run.end = i + 1,
            _ => out.push(i..i + 1),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_become_runs_of_consecutive_ones() {
        assert_eq!(runs(&[]), Vec::<Range<u32>>::new());
        assert_eq!(runs(&[4]), vec![4..5]);
        assert_eq!(runs(&[1, 2, 3, 7, 8, 10]), vec![1..4, 7..9, 10..11]);
    }
}
