//! Revolute joint: one rotation about a fixed axis.

use glam::{DMat3, DVec3};

use crate::spatial::PlueckerTransform;

/// Rotation by `q` rad about `axis` (a unit vector in the joint frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Revolute {
    /// Unit rotation axis.
    pub axis: DVec3,
}

impl Revolute {
    /// A revolute joint about `axis` (normalised here).
    pub fn new(axis: DVec3) -> Self {
        Self {
            axis: axis.normalize(),
        }
    }

    /// `X_J(q)`.
    #[inline]
    pub fn transform(&self, q: f64) -> PlueckerTransform {
        PlueckerTransform::from_rotation(rotation(self.axis, q))
    }

    /// `placement · X_J(q)`; about a coordinate axis only two columns change.
    #[inline]
    pub fn placed(&self, placement: &PlueckerTransform, q: f64) -> PlueckerTransform {
        let (s, c) = crate::math::real::sin_cos(q);
        let r = &placement.rotation;
        let rotation = if self.axis == DVec3::Z {
            DMat3::from_cols(
                r.x_axis * c + r.y_axis * s,
                r.y_axis * c - r.x_axis * s,
                r.z_axis,
            )
        } else if self.axis == DVec3::X {
            DMat3::from_cols(
                r.x_axis,
                r.y_axis * c + r.z_axis * s,
                r.z_axis * c - r.y_axis * s,
            )
        } else if self.axis == DVec3::Y {
            DMat3::from_cols(
                r.x_axis * c - r.z_axis * s,
                r.y_axis,
                r.x_axis * s + r.z_axis * c,
            )
        } else {
            *r * rotation_sc(self.axis, s, c)
        };
        PlueckerTransform::new(rotation, placement.translation)
    }
}

/// The rotation matrix by `angle` about the unit vector `axis`, with the common axes exact.
#[inline]
pub(crate) fn rotation(axis: DVec3, angle: f64) -> DMat3 {
    let (s, c) = crate::math::real::sin_cos(angle);
    rotation_sc(axis, s, c)
}

/// [`rotation`] from the angle's sine and cosine.
#[inline]
fn rotation_sc(axis: DVec3, s: f64, c: f64) -> DMat3 {
    if axis == DVec3::Z {
        DMat3::from_cols(DVec3::new(c, s, 0.0), DVec3::new(-s, c, 0.0), DVec3::Z)
    } else if axis == DVec3::X {
        DMat3::from_cols(DVec3::X, DVec3::new(0.0, c, s), DVec3::new(0.0, -s, c))
    } else if axis == DVec3::Y {
        DMat3::from_cols(DVec3::new(c, 0.0, -s), DVec3::Y, DVec3::new(s, 0.0, c))
    } else {
        let t = 1.0 - c;
        let (x, y, z) = (axis.x, axis.y, axis.z);
        DMat3::from_cols(
            DVec3::new(t * x * x + c, t * x * y + s * z, t * x * z - s * y),
            DVec3::new(t * x * y - s * z, t * y * y + c, t * y * z + s * x),
            DVec3::new(t * x * z + s * y, t * y * z - s * x, t * z * z + c),
        )
    }
}
