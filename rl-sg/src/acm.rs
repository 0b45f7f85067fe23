//! The allowed-collision set of a model: pairs of its bodies that are never checked against
//! each other (SRDF `<disable_collisions>`, RL's `<ignore idref>`, adjacent links).

use std::collections::BTreeSet;

/// Unordered pairs of body indices of one model that are not checked for self-collision.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AllowedCollisions {
    pairs: BTreeSet<(usize, usize)>,
}

impl AllowedCollisions {
    /// No pair allowed.
    pub fn new() -> Self {
        Self::default()
    }

    /// Allows the pair `(a, b)` (in either order); `a == b` is ignored (a body is never checked
    /// against itself).
    pub fn allow(&mut self, a: usize, b: usize) {
        if a != b {
            self.pairs.insert((a.min(b), a.max(b)));
        }
    }

    /// Checks the pair again.
    pub fn disallow(&mut self, a: usize, b: usize) {
        self.pairs.remove(&(a.min(b), a.max(b)));
    }

    /// Whether the pair is allowed to collide (not checked).
    #[inline]
    pub fn is_allowed(&self, a: usize, b: usize) -> bool {
        a == b || self.pairs.contains(&(a.min(b), a.max(b)))
    }

    /// The allowed pairs, `(smaller, larger)`, in order.
    pub fn pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.pairs.iter().copied()
    }

    /// The number of allowed pairs.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// Whether no pair is allowed.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Forgets every pair.
    pub fn clear(&mut self) {
        self.pairs.clear();
    }
}
