//! The validity check the planners are generic over (RL's `SimpleModel::isColliding`, OMPL's
//! `StateValidityChecker`): whether a configuration is allowed — collision-free, within bounds,
//! whatever the application decides.
//!
//! A checker may check several configurations at once ([`Validity::lanes`]): the verifiers
//! then hand it the points of an edge in batches of that size through
//! [`Validity::segment_valid`], so a SIMD checker such as [`crate::fast::SphereChecker`]
//! evaluates a batch in one pass and stops at the first batch with a collision.

use crate::space::JointSpace;

/// Decides whether configurations are valid.
pub trait Validity {
    /// Whether `q` is valid (one check).
    fn is_valid(&mut self, q: &[f64]) -> bool;

    /// How many configurations it checks in one pass (1 for one-at-a-time checkers).
    fn lanes(&self) -> usize {
        1
    }

    /// Whether every configuration `space.interpolate(a, b, t)` for `t` in `ts` is valid
    /// (`ts.len()` at most [`Validity::lanes`] when called by the verifiers). The default
    /// interpolates and calls [`Validity::is_valid`] in order, stopping at the first invalid
    /// one.
    fn segment_valid(
        &mut self,
        space: &JointSpace,
        a: &[f64],
        b: &[f64],
        ts: &[f64],
        scratch: &mut Vec<f64>,
    ) -> bool {
        scratch.resize(space.nq(), 0.0);
        for &t in ts {
            space.interpolate(a, b, t, scratch);
            if !self.is_valid(scratch) {
                return false;
            }
        }
        true
    }

    /// The number of configurations checked so far.
    fn checks(&self) -> u64;

    /// Of those, the number found valid (a checker that tests batches counts the
    /// configurations of batches that passed: a lower bound).
    fn free_checks(&self) -> u64;

    /// The exact geometry behind this checker, where it has one: what certifies a path's edges
    /// ([`SceneValidity::certify_path`](crate::scene::SceneValidity::certify_path)).
    fn exact_checker(&mut self) -> Option<&mut crate::scene::SceneValidity> {
        None
    }
}

/// Every configuration within the space's bounds is valid: for tests and for measuring a
/// planner's own overhead.
#[derive(Clone, Debug)]
pub struct AlwaysValid {
    space: JointSpace,
    checks: u64,
    free: u64,
}

impl AlwaysValid {
    /// A checker that accepts every configuration of `space`.
    pub fn new(space: JointSpace) -> Self {
        Self {
            space,
            checks: 0,
            free: 0,
        }
    }
}

impl Validity for AlwaysValid {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        let ok = self.space.contains(q);
        self.free += u64::from(ok);
        ok
    }

    fn checks(&self) -> u64 {
        self.checks
    }

    fn free_checks(&self) -> u64 {
        self.free
    }
}

/// A validity check from a closure (`true` = valid), counting its calls.
pub struct FnValidity<F: FnMut(&[f64]) -> bool> {
    f: F,
    checks: u64,
    free: u64,
}

impl<F: FnMut(&[f64]) -> bool> FnValidity<F> {
    /// Wraps `f`.
    pub fn new(f: F) -> Self {
        Self {
            f,
            checks: 0,
            free: 0,
        }
    }
}

impl<F: FnMut(&[f64]) -> bool> Validity for FnValidity<F> {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        let ok = (self.f)(q);
        self.free += u64::from(ok);
        ok
    }

    fn checks(&self) -> u64 {
        self.checks
    }

    fn free_checks(&self) -> u64 {
        self.free
    }
}
