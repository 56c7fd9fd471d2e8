//! One side of a shaft: a parent surface edge, and which points it faces or hides.

use glam::DVec2;

use super::predicates::orient;

/// One side of a shaft: a parent surface edge (one-sided: its front is the left of `a → b`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Side {
    pub index: usize,
    pub a: DVec2,
    pub b: DVec2,
}

impl Side {
    /// Whether `p` is strictly in front: the facing condition the classification assumes for
    /// the *other* end of a segment.
    #[inline]
    pub(crate) fn faces(&self, p: DVec2) -> bool {
        orient(self.a, self.b, p) > 0.0
    }

    /// Whether the closed segment `[p, q]` is entirely on or behind this edge's line, where no
    /// facing segment can reach it.
    pub(crate) fn hides(&self, p: DVec2, q: DVec2) -> bool {
        orient(self.a, self.b, p) <= 0.0 && orient(self.a, self.b, q) <= 0.0
    }
}
