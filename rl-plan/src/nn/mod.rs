//! Nearest-neighbour structures over a [`JointSpace`] (RL's `LinearNearestNeighbors`,
//! `KdtreeNearestNeighbors`, `GnatNearestNeighbors`).
//!
//! All three answer the same two queries — the `k` nearest points, and every point within a
//! radius — with the space's metric, so wrap-around joints are near across `±π`:
//!
//! - [`Linear`]: compares with every point; any metric; the reference the others are tested
//!   against, and the fastest for the small trees of a quick RRT.
//! - [`Kdtree`]: a bucketed k-d tree grown by insertion, for spaces of intervals and circles; a
//!   subtree is skipped when the distance from the query to its box — measured around the
//!   circle for circle coordinates — exceeds the current k-th distance.
//! - [`Gnat`]: Brin's geometric near-neighbour access tree (VLDB 1995) for any metric (also
//!   rotations): split points with tables of distance ranges prune by the triangle inequality.
//! - [`KdtreeF32`]: the fast path's k-d tree over `f32`, leaves laid out for vector lanes, for
//!   spaces of intervals ([`NnKind::Fast`] takes it where the space allows, else [`Kdtree`] or
//!   [`Gnat`]).
//!
//! Results are sorted by distance, ties by id, so the structures agree exactly
//! (`tests/nearest_neighbors.rs` repeats RL's test: the same k nearest and radius results as
//! linear search on random points, wrap-around coordinates included).

mod gnat;
mod kdtree;
mod kdtree_f32;
mod linear;

pub use gnat::Gnat;
pub use kdtree::Kdtree;
pub use kdtree_f32::KdtreeF32;
pub use linear::Linear;

use crate::error::PlanError;
use crate::space::JointSpace;

/// A point found by a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// Its distance to the query.
    pub distance: f64,
    /// The id it was inserted with.
    pub id: usize,
}

/// The queries every structure answers.
pub trait NearestNeighbors {
    /// Adds point `q` under `id`.
    fn insert(&mut self, space: &JointSpace, id: usize, q: &[f64]);

    /// The `k` points nearest to `q`, nearest first (fewer if it holds fewer).
    fn nearest(&self, space: &JointSpace, q: &[f64], k: usize) -> Vec<Neighbor>;

    /// Every point within `radius` of `q` (distance ≤ radius), nearest first.
    fn within(&self, space: &JointSpace, q: &[f64], radius: f64) -> Vec<Neighbor>;

    /// The nearest point, without allocating.
    fn nearest_one(&self, space: &JointSpace, q: &[f64]) -> Option<Neighbor> {
        self.nearest(space, q, 1).first().copied()
    }

    /// The number of points.
    fn len(&self) -> usize;

    /// Whether it holds no point.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Forgets every point.
    fn clear(&mut self);
}

/// Which structure to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NnKind {
    /// [`Linear`].
    #[default]
    Linear,
    /// [`Kdtree`].
    Kdtree,
    /// [`Gnat`].
    Gnat,
    /// [`KdtreeF32`] for spaces of intervals; [`Kdtree`] with circles, [`Gnat`] with
    /// rotations.
    Fast,
}

impl NnKind {
    /// RL's element name (`linearNearestNeighbors`, …) or a short one (`linear`, `kdtree`,
    /// `gnat`).
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "linear" | "linearNearestNeighbors" => Some(Self::Linear),
            "kdtree" | "kdtreeNearestNeighbors" | "kdtreeBoundingBoxNearestNeighbors" => {
                Some(Self::Kdtree)
            }
            "gnat" | "gnatNearestNeighbors" => Some(Self::Gnat),
            "fast" | "kdtree-f32" => Some(Self::Fast),
            _ => None,
        }
    }
}

/// One of the structures, chosen at run time.
#[derive(Clone, Debug)]
pub enum Nn {
    /// Linear search.
    Linear(Linear),
    /// k-d tree.
    Kdtree(Kdtree),
    /// GNAT.
    Gnat(Gnat),
    /// `f32` k-d tree.
    KdtreeF32(KdtreeF32),
}

impl Nn {
    /// An empty structure of `kind` for `space` (a k-d tree refuses spaces with rotations).
    pub fn new(kind: NnKind, space: &JointSpace) -> Result<Self, PlanError> {
        Ok(match kind {
            NnKind::Linear => Self::Linear(Linear::new(space)),
            NnKind::Kdtree => Self::Kdtree(Kdtree::new(space)?),
            NnKind::Gnat => Self::Gnat(Gnat::new(space)),
            NnKind::Fast => match KdtreeF32::new(space) {
                Ok(t) => Self::KdtreeF32(t),
                Err(_) if space.is_vector() => Self::Kdtree(Kdtree::new(space)?),
                Err(_) => Self::Gnat(Gnat::new(space)),
            },
        })
    }
}

macro_rules! dispatch {
    ($self:ident, $n:ident => $e:expr) => {
        match $self {
            Nn::Linear($n) => $e,
            Nn::Kdtree($n) => $e,
            Nn::Gnat($n) => $e,
            Nn::KdtreeF32($n) => $e,
        }
    };
}

impl NearestNeighbors for Nn {
    fn insert(&mut self, space: &JointSpace, id: usize, q: &[f64]) {
        dispatch!(self, n => n.insert(space, id, q))
    }
    fn nearest(&self, space: &JointSpace, q: &[f64], k: usize) -> Vec<Neighbor> {
        dispatch!(self, n => n.nearest(space, q, k))
    }
    fn within(&self, space: &JointSpace, q: &[f64], radius: f64) -> Vec<Neighbor> {
        dispatch!(self, n => n.within(space, q, radius))
    }
    fn nearest_one(&self, space: &JointSpace, q: &[f64]) -> Option<Neighbor> {
        dispatch!(self, n => n.nearest_one(space, q))
    }
    fn len(&self) -> usize {
        dispatch!(self, n => n.len())
    }
    fn clear(&mut self) {
        dispatch!(self, n => n.clear())
    }
}

/// The best `k` candidates seen so far, by squared distance then id (a sorted small vector:
/// `k` is a few dozen at most in planning).
#[derive(Clone, Debug)]
pub(crate) struct Best {
    k: usize,
    items: Vec<(f64, usize)>,
}

impl Best {
    pub(crate) fn new(k: usize) -> Self {
        Self {
            k,
            items: Vec::with_capacity(k.min(64)),
        }
    }

    /// The squared distance a candidate must beat (∞ until `k` are held).
    #[inline]
    pub(crate) fn bound(&self) -> f64 {
        if self.items.len() < self.k {
            f64::INFINITY
        } else {
            self.items.last().map_or(f64::INFINITY, |x| x.0)
        }
    }

    #[inline]
    pub(crate) fn offer(&mut self, d2: f64, id: usize) {
        if self.k == 0 {
            return;
        }
        let full = self.items.len() == self.k;
        if full {
            let (wd, wid) = self.items[self.k - 1];
            if (d2, id) >= (wd, wid) {
                return;
            }
        }
        let at = self.items.partition_point(|&(d, i)| (d, i) < (d2, id));
        if full {
            self.items.pop();
        }
        self.items.insert(at, (d2, id));
    }

    pub(crate) fn into_neighbors(self) -> Vec<Neighbor> {
        self.items
            .into_iter()
            .map(|(d2, id)| Neighbor {
                distance: d2.sqrt(),
                id,
            })
            .collect()
    }
}

/// Sorts radius results by distance, then id.
pub(crate) fn sorted(mut v: Vec<(f64, usize)>) -> Vec<Neighbor> {
    v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    v.into_iter()
        .map(|(d2, id)| Neighbor {
            distance: d2.sqrt(),
            id,
        })
        .collect()
}
