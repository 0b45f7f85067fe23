//! Spheres first, exact geometry last: a checker whose every verdict is the exact geometry's,
//! at close to the sphere checker's speed where the robot is clear.
//!
//! Three models of the robot: `cover`, spheres that contain the collision meshes
//! ([`super::SphereSet::cover`]); optionally `inner`, the original (not conservative)
//! spheres; and `exact`, rl-sg's meshes. For a batch of configurations:
//!
//! 1. the lanes where `cover` touches nothing are valid — the meshes cannot touch anything
//!    either;
//! 2. every other lane is decided by `exact`: a sphere verdict is never final where the meshes
//!    may disagree. `inner` only orders them: lanes its spheres find in collision are asked
//!    first (most are in collision, so a batch that collides ends after one exact check).
//!
//! So "valid" and "invalid" are both the exact geometry's at every checked configuration: the
//! start and goal of a problem are refused only when the meshes collide (the inner spheres
//! refused UR5 starts 7–14 mm from a self-contact that the meshes do not make).

use super::SphereChecker;
use crate::scene::SceneValidity;
use crate::space::JointSpace;
use crate::validity::Validity;

/// The three-model checker (see the module docs).
#[derive(Clone, Debug)]
pub struct HybridChecker {
    cover: SphereChecker,
    inner: Option<SphereChecker>,
    exact: SceneValidity,
    q: Vec<f64>,
    checks: u64,
    free: u64,
}

impl HybridChecker {
    /// A checker from covering spheres, optional inner spheres and the exact geometry.
    pub fn new(cover: SphereChecker, inner: Option<SphereChecker>, exact: SceneValidity) -> Self {
        Self {
            cover,
            inner,
            exact,
            q: Vec::new(),
            checks: 0,
            free: 0,
        }
    }

    /// Configurations the exact geometry decided.
    pub fn exact_checks(&self) -> u64 {
        self.exact.checks()
    }

    fn decide(&mut self, space: &JointSpace, a: &[f64], b: &[f64], ts: &[f64]) -> bool {
        let band = self.cover.segment_mask(space, a, b, ts);
        if band == 0 {
            return true;
        }
        let first = match &mut self.inner {
            Some(inner) => inner.segment_mask(space, a, b, ts) & band,
            None => 0,
        };
        self.q.resize(space.nq(), 0.0);
        for lanes in [first, band & !first] {
            for (i, &t) in ts.iter().enumerate() {
                if lanes & (1 << i) != 0 {
                    space.interpolate(a, b, t, &mut self.q);
                    if !self.exact.is_valid(&self.q) {
                        return false;
                    }
                }
            }
        }
        true
    }
}

impl Validity for HybridChecker {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        let space = self.exact.space().clone();
        if !space.contains(q) {
            return false;
        }
        let ok = self.decide(&space, q, q, &[0.0]);
        self.free += u64::from(ok);
        ok
    }

    fn lanes(&self) -> usize {
        self.cover.batch()
    }

    fn segment_valid(
        &mut self,
        space: &JointSpace,
        a: &[f64],
        b: &[f64],
        ts: &[f64],
        _scratch: &mut Vec<f64>,
    ) -> bool {
        for chunk in ts.chunks(self.cover.batch()) {
            self.checks += chunk.len() as u64;
            if !self.decide(space, a, b, chunk) {
                return false;
            }
            self.free += chunk.len() as u64;
        }
        true
    }

    fn exact_checker(&mut self) -> Option<&mut SceneValidity> {
        Some(&mut self.exact)
    }

    fn checks(&self) -> u64 {
        self.checks
    }

    fn free_checks(&self) -> u64 {
        self.free
    }
}
