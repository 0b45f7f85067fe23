//! Poses between rl-core (rotation matrix + translation) and parry (unit quaternion +
//! translation). Both use glam 0.33's `f64` types, so only the rotation changes form.

use glam::{DMat3, DQuat, DVec3};
use parry3d_f64::math::Pose;
use rl_core::spatial::PlueckerTransform;

use crate::error::SgError;

/// parry's pose of `x`.
#[inline]
pub(crate) fn to_parry(x: &PlueckerTransform) -> Pose {
    Pose::from_parts(x.translation, DQuat::from_mat3(&x.rotation).normalize())
}

/// rl-core's pose of `p`.
#[inline]
pub(crate) fn from_parry(p: &Pose) -> PlueckerTransform {
    PlueckerTransform::new(DMat3::from_quat(p.rotation), p.translation)
}

/// Checks that `x` is a rigid transform: finite, and its rotation orthonormal with determinant
/// +1 (to 1e-6, what files written with 6–7 digits reach).
pub(crate) fn check(what: &str, x: &PlueckerTransform) -> Result<(), SgError> {
    let r = x.rotation;
    let finite = x.translation.is_finite()
        && r.x_axis.is_finite()
        && r.y_axis.is_finite()
        && r.z_axis.is_finite();
    if !finite {
        return Err(SgError::invalid(what, format_pose(x), "not finite"));
    }
    let e = (r.transpose() * r - DMat3::IDENTITY).abs();
    let off = e
        .x_axis
        .max_element()
        .max(e.y_axis.max_element())
        .max(e.z_axis.max_element());
    if off > 1e-6 || (r.determinant() - 1.0).abs() > 1e-6 {
        return Err(SgError::invalid(what, format_pose(x), "not a rotation"));
    }
    Ok(())
}

/// `xyz (…) rotation (…)` for messages.
pub(crate) fn format_pose(x: &PlueckerTransform) -> String {
    let q = DQuat::from_mat3(&x.rotation);
    format!(
        "xyz ({}, {}, {}) quaternion ({}, {}, {}, {})",
        x.translation.x, x.translation.y, x.translation.z, q.x, q.y, q.z, q.w
    )
}

/// The pose from a translation and a quaternion `(x, y, z, w)` that must be finite and
/// non-zero (it is normalised).
pub(crate) fn from_xyz_quat(
    what: &str,
    xyz: DVec3,
    q: [f64; 4],
) -> Result<PlueckerTransform, SgError> {
    let quat = DQuat::from_xyzw(q[0], q[1], q[2], q[3]);
    if !xyz.is_finite() || !quat.is_finite() {
        return Err(SgError::invalid(
            what,
            format!("{xyz:?} {q:?}"),
            "not finite",
        ));
    }
    let n = quat.length();
    if n < 1e-9 {
        return Err(SgError::invalid(what, format!("{q:?}"), "zero quaternion"));
    }
    Ok(PlueckerTransform::from_quat_translation(quat / n, xyz))
}

/// The rotation of roll, pitch, yaw (URDF's `rpy`: `Rz(y) Ry(p) Rx(r)`).
pub(crate) fn rpy(r: f64, p: f64, y: f64) -> DMat3 {
    DMat3::from_rotation_z(y) * DMat3::from_rotation_y(p) * DMat3::from_rotation_x(r)
}

/// The rotation about the unit of `axis` by `angle` (a zero axis: identity, as VRML viewers
/// treat it).
pub(crate) fn axis_angle(axis: DVec3, angle: f64) -> DMat3 {
    let n = axis.length();
    if n < 1e-12 || angle == 0.0 {
        DMat3::IDENTITY
    } else {
        DMat3::from_axis_angle(axis / n, angle)
    }
}
