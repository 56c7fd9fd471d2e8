//! Every moment of a run the learner published, kept with bounded memory, for scrubbing back.
//!
//! A [`Moment`] is whatever the learner published at one time: the network (cells, the edges
//! within faces, counts and curves), the learned ζ̃ on the display grid and the lit scene as
//! they were then — not a training step, so a learner that alternates learning and solving
//! records the same way. The timeline keeps every moment until it holds [`MAX_MOMENTS`] or
//! [`MAX_BYTES`]; then it keeps every second one, then every fourth, …: moment `i` (counted from
//! the first publication) stays while `i` is a multiple of the current stride `2^k`. The first
//! moment and the latest are always kept. Samples and curves only grow during a fit, so the
//! moments share the newest vectors and each sees its own prefix ([`Prefix::rebase`](crate::Prefix::rebase)).

use std::sync::Arc;
use std::time::Duration;

use crate::worker::{LearnedGrid, Lit, Status, World};

/// Most moments kept.
pub const MAX_MOMENTS: usize = 512;
/// Most bytes the kept moments may take (cells, edges, learned grids; estimated).
pub const MAX_BYTES: usize = 160 << 20;

/// What the learner had published at one time.
#[derive(Clone, Debug)]
pub struct Moment {
    /// The scene and its references then (a scene edit starts another world in the same run).
    pub world: Arc<World>,
    /// The network then.
    pub status: Status,
    /// The learned ζ̃ on the display grid, as last computed by then.
    pub learned: Option<Arc<LearnedGrid>>,
    /// The lit scene, as last solved by then.
    pub lit: Option<Arc<Lit>>,
}

impl Moment {
    /// Training time of the run at this moment (pauses excluded).
    #[must_use]
    pub fn at(&self) -> Duration {
        self.status.growth.run_time
    }

    /// Training steps at this moment.
    #[must_use]
    pub fn steps(&self) -> u64 {
        self.status.growth.steps
    }

    /// Cells at this moment.
    #[must_use]
    pub fn cells(&self) -> usize {
        self.status.growth.cells.len()
    }

    /// Estimated bytes it holds on its own (shared vectors are counted once, elsewhere).
    #[must_use]
    pub fn bytes(&self) -> usize {
        let g = &self.status.growth;
        let cells = g.cells.len() * std::mem::size_of::<crate::worker::CellMark>();
        let edges = g.face_edges.len() * std::mem::size_of::<[u32; 2]>();
        let learned = self
            .learned
            .as_ref()
            .map_or(0, |l| l.values.len() * std::mem::size_of::<f64>());
        let lit = self.lit.as_ref().map_or(0, |l| {
            (l.solve.b.len() + 3 * l.history.len()) * std::mem::size_of::<f64>()
        });
        std::mem::size_of::<Moment>() + cells + edges + learned + lit
    }
}

/// A kept moment and its number among all the moments recorded.
#[derive(Clone, Debug)]
struct Kept {
    index: u64,
    moment: Moment,
}

/// The moments of one run (cleared by a new fit).
#[derive(Clone, Debug)]
pub struct Timeline {
    kept: Vec<Kept>,
    /// Moments recorded so far (the next one's index).
    recorded: u64,
    /// Kept moments are those whose index is a multiple of this (a power of two).
    stride: u64,
    max_moments: usize,
    max_bytes: usize,
}

impl Default for Timeline {
    fn default() -> Self {
        Timeline::with_limits(MAX_MOMENTS, MAX_BYTES)
    }
}

impl Timeline {
    /// A timeline that keeps at most `max_moments` (at least 2) and about `max_bytes`.
    #[must_use]
    pub fn with_limits(max_moments: usize, max_bytes: usize) -> Timeline {
        Timeline {
            kept: Vec::new(),
            recorded: 0,
            stride: 1,
            max_moments: max_moments.max(2),
            max_bytes,
        }
    }

    /// Forgets every moment (a new fit).
    pub fn clear(&mut self) {
        *self = Timeline::with_limits(self.max_moments, self.max_bytes);
    }

    /// Adds the newest moment; thins the older ones when over a limit.
    pub fn record(&mut self, moment: Moment) {
        let index = self.recorded;
        self.recorded += 1;
        // The previous latest was kept only for being the latest.
        if self.kept.len() > 1
            && self
                .kept
                .last()
                .is_some_and(|k| !k.index.is_multiple_of(self.stride))
        {
            self.kept.pop();
        }
        for k in &mut self.kept {
            rebase(&mut k.moment, &moment);
        }
        self.kept.push(Kept { index, moment });
        self.thin();
    }

    /// Doubles the stride until the moments fit the limits; the first and latest stay.
    fn thin(&mut self) {
        while self.kept.len() > 2
            && (self.kept.len() > self.max_moments || self.bytes() > self.max_bytes)
        {
            self.stride *= 2;
            let stride = self.stride;
            let last = self.kept.len() - 1;
            let mut position = 0;
            self.kept.retain(|k| {
                let keep = position == 0 || position == last || k.index.is_multiple_of(stride);
                position += 1;
                keep
            });
        }
    }

    /// Estimated bytes of the kept moments.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.kept.iter().map(|k| k.moment.bytes()).sum()
    }

    /// Number of kept moments.
    #[must_use]
    pub fn len(&self) -> usize {
        self.kept.len()
    }

    /// Whether nothing is kept.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.kept.is_empty()
    }

    /// Moments recorded since the run started (kept or not).
    #[must_use]
    pub fn recorded(&self) -> u64 {
        self.recorded
    }

    /// The kept moment at `position` (0: the first).
    #[must_use]
    pub fn get(&self, position: usize) -> Option<&Moment> {
        self.kept.get(position).map(|k| &k.moment)
    }

    /// The newest moment.
    #[must_use]
    pub fn latest(&self) -> Option<&Moment> {
        self.kept.last().map(|k| &k.moment)
    }

    /// The newest moment, to complete with what arrives after it (a learned grid, a lit scene).
    pub fn latest_mut(&mut self) -> Option<&mut Moment> {
        self.kept.last_mut().map(|k| &mut k.moment)
    }

    /// The number the moment at `position` was recorded as (it stays while others are thinned
    /// out around it).
    #[must_use]
    pub fn number(&self, position: usize) -> Option<u64> {
        self.kept.get(position).map(|k| k.index)
    }

    /// The position of the moment recorded as `number`, while it is kept.
    #[must_use]
    pub fn position_of(&self, number: u64) -> Option<usize> {
        self.kept.binary_search_by_key(&number, |k| k.index).ok()
    }

    /// The position of the last kept moment at or before training time `at` (the first if
    /// `at` is before it).
    #[must_use]
    pub fn position_at(&self, at: Duration) -> Option<usize> {
        if self.kept.is_empty() {
            return None;
        }
        let after = self.kept.partition_point(|k| k.moment.at() <= at);
        Some(after.saturating_sub(1))
    }

    /// Cells in the network at training time `at` (the last moment at or before it; 0 before
    /// the first): what "new cells" are counted from.
    #[must_use]
    pub fn cells_at(&self, at: Duration) -> usize {
        let after = self.kept.partition_point(|k| k.moment.at() <= at);
        match after {
            0 => 0,
            n => self.kept[n - 1].moment.cells(),
        }
    }
}

/// Lets `old` see its samples and curves in `newer`'s vectors (samples only within one world:
/// an edited scene starts new samples; the curve runs through the whole fit).
fn rebase(old: &mut Moment, newer: &Moment) {
    if old.world.id == newer.world.id {
        old.status.samples.rebase(&newer.status.samples);
    }
    old.status.history.rebase(&newer.status.history);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{moment, world};

    fn timeline_of(n: u64, max: usize) -> Timeline {
        let w = world(1);
        let mut t = Timeline::with_limits(max, usize::MAX);
        for i in 0..n {
            t.record(moment(&w, i, i as usize + 3));
        }
        t
    }

    fn indices(t: &Timeline) -> Vec<u64> {
        t.kept.iter().map(|k| k.index).collect()
    }

    #[test]
    fn every_moment_is_kept_until_the_cap() {
        let t = timeline_of(10, 16);
        assert_eq!(indices(&t), (0..10).collect::<Vec<_>>());
        assert_eq!(t.recorded(), 10);
    }

    #[test]
    fn over_the_cap_every_second_then_every_fourth_is_kept_with_the_first_and_latest() {
        for n in [17_u64, 40, 100, 1000, 4097] {
            let t = timeline_of(n, 16);
            let kept = indices(&t);
            assert!(kept.len() <= 16, "{n}: {kept:?}");
            assert_eq!(kept[0], 0, "the first stays");
            assert_eq!(*kept.last().unwrap(), n - 1, "the latest stays");
            let stride = t.stride;
            assert!(stride.is_power_of_two());
            for &i in &kept[..kept.len() - 1] {
                assert!(i.is_multiple_of(stride), "{n}: {i} with stride {stride}");
            }
            // Exactly the multiples of the stride, and the latest.
            let mut expected: Vec<u64> = (0..n).filter(|i| i.is_multiple_of(stride)).collect();
            if !(n - 1).is_multiple_of(stride) {
                expected.push(n - 1);
            }
            assert_eq!(kept, expected, "{n}");
        }
    }

    #[test]
    fn the_byte_limit_thins_too() {
        let w = world(1);
        let one = moment(&w, 0, 1000).bytes();
        let mut t = Timeline::with_limits(1_000_000, 20 * one);
        for i in 0..500 {
            t.record(moment(&w, i, 1000));
        }
        assert!(t.bytes() <= 20 * one, "{} > {}", t.bytes(), 20 * one);
        assert!(t.len() >= 10, "{}", t.len());
        assert_eq!(t.get(0).unwrap().steps(), 0);
        assert_eq!(t.latest().unwrap().steps(), 499 * 100);
    }

    #[test]
    fn moments_are_found_by_training_time() {
        let t = timeline_of(10, 64);
        // moment i is at i × 100 ms with i + 3 cells.
        let at = |ms| Duration::from_millis(ms);
        assert_eq!(t.position_at(at(0)), Some(0));
        assert_eq!(t.position_at(at(250)), Some(2));
        assert_eq!(t.position_at(at(10_000)), Some(9));
        assert_eq!(t.cells_at(at(250)), 5);
        assert_eq!(t.cells_at(at(0)), 3);
        assert_eq!(Timeline::default().position_at(at(5)), None);
    }

    #[test]
    fn a_moment_is_found_again_by_its_number_while_the_timeline_thins() {
        let mut t = timeline_of(16, 16);
        let number = t.number(4).unwrap();
        assert_eq!((number, t.position_of(number)), (4, Some(4)));
        let w = world(1);
        t.record(moment(&w, 16, 3)); // over the cap: every second one stays
        assert_eq!(t.position_of(4), Some(2), "kept, two places earlier");
        assert_eq!(t.position_of(5), None, "thinned out");
        assert_eq!(t.number(t.len()), None);
    }

    #[test]
    fn older_moments_share_the_newest_samples_and_see_their_own_prefix() {
        let w = world(1);
        let mut t = Timeline::with_limits(64, usize::MAX);
        for i in 0..5 {
            t.record(moment(&w, i, 3));
        }
        let latest = t.latest().unwrap().status.samples.clone();
        for p in 0..t.len() {
            let m = t.get(p).unwrap();
            assert!(
                m.status.samples.shares(&latest),
                "moment {p} shares the newest vector"
            );
            assert_eq!(m.status.samples.len(), 10 * (p + 1));
            assert_eq!(m.status.history.len(), p + 1);
        }
        // Another world (an edited scene) has its own samples.
        let other = world(2);
        t.record(moment(&other, 5, 3));
        assert!(
            !t.get(0)
                .unwrap()
                .status
                .samples
                .shares(&t.latest().unwrap().status.samples)
        );
        assert!(
            t.get(0)
                .unwrap()
                .status
                .history
                .shares(&t.latest().unwrap().status.history)
        );
    }
}
