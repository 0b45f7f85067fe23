//! Cylindrical joint: independent rotation about and translation along one axis.

use glam::DVec3;

use super::revolute::rotation;
use crate::spatial::PlueckerTransform;

/// `q = [angle (rad), translation (m)]` about and along `axis`, in RL's order (rotation first).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cylindrical {
    /// Unit axis.
    pub axis: DVec3,
}

impl Cylindrical {
    /// A cylindrical joint about `axis` (normalised here).
    pub fn new(axis: DVec3) -> Self {
        Self {
            axis: axis.normalize(),
        }
    }

    /// `X_J(q)`.
    #[inline]
    pub fn transform(&self, angle: f64, translation: f64) -> PlueckerTransform {
        PlueckerTransform::new(rotation(self.axis, angle), self.axis * translation)
    }
}
