//! Prismatic joint: one translation along a fixed axis.

use glam::DVec3;

use crate::spatial::PlueckerTransform;

/// Translation by `q` m along `axis` (a unit vector in the joint frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prismatic {
    /// Unit translation axis.
    pub axis: DVec3,
}

impl Prismatic {
    /// A prismatic joint along `axis` (normalised here).
    pub fn new(axis: DVec3) -> Self {
        Self {
            axis: axis.normalize(),
        }
    }

    /// `X_J(q)`.
    #[inline]
    pub fn transform(&self, q: f64) -> PlueckerTransform {
        PlueckerTransform::from_translation(self.axis * q)
    }
}
