//! Helical (screw) joint: rotation about an axis coupled with translation along it.

use glam::DVec3;

use super::revolute::rotation;
use crate::spatial::PlueckerTransform;

/// Rotation by `q` rad about `axis` together with translation `pitch · q` m along it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Helical {
    /// Unit screw axis.
    pub axis: DVec3,
    /// Translation per radian, m/rad.
    pub pitch: f64,
}

impl Helical {
    /// A helical joint about `axis` (normalised here) with `pitch` m/rad.
    pub fn new(axis: DVec3, pitch: f64) -> Self {
        Self {
            axis: axis.normalize(),
            pitch,
        }
    }

    /// `X_J(q)`.
    #[inline]
    pub fn transform(&self, q: f64) -> PlueckerTransform {
        PlueckerTransform::new(rotation(self.axis, q), self.axis * (self.pitch * q))
    }
}
