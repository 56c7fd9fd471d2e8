//! [`Prefix`]: a vector that only grows, shared by the moments of a run that each see a prefix
//! of it (the samples and curves the learner publishes and the timeline keeps).

use std::sync::Arc;

/// A vector that only grows, shared by the moments that each see a prefix of it.
#[derive(Clone, Debug)]
pub struct Prefix<T> {
    all: Arc<Vec<T>>,
    len: usize,
}

impl<T> Default for Prefix<T> {
    fn default() -> Self {
        Prefix {
            all: Arc::new(Vec::new()),
            len: 0,
        }
    }
}

impl<T: PartialEq> Prefix<T> {
    /// All of `all`.
    #[must_use]
    pub fn new(all: Arc<Vec<T>>) -> Prefix<T> {
        let len = all.len();
        Prefix { all, len }
    }

    /// The part this moment sees.
    #[must_use]
    pub fn as_slice(&self) -> &[T] {
        &self.all[..self.len]
    }

    /// Its length.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether it is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether `self` and `other` share one vector (nothing to rebase).
    #[must_use]
    pub fn shares(&self, other: &Prefix<T>) -> bool {
        Arc::ptr_eq(&self.all, &other.all)
    }

    /// Sees the same prefix in `newer`'s vector when that vector extends this one (checked on
    /// the last element seen), so the older vector can be freed.
    pub fn rebase(&mut self, newer: &Prefix<T>) {
        if self.shares(newer) || newer.all.len() < self.len {
            return;
        }
        if self.len == 0 || newer.all[self.len - 1] == self.all[self.len - 1] {
            self.all = Arc::clone(&newer.all);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prefix_is_not_rebased_onto_a_vector_it_does_not_start() {
        let mut a = Prefix::new(Arc::new(vec![1, 2, 3]));
        a.rebase(&Prefix::new(Arc::new(vec![1, 2, 9, 4])));
        assert_eq!(a.as_slice(), &[1, 2, 3]);
        a.rebase(&Prefix::new(Arc::new(vec![1, 2, 3, 4])));
        assert_eq!(a.as_slice(), &[1, 2, 3]);
        assert_eq!(a.all.len(), 4, "rebased");
    }
}
