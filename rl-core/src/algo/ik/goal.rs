//! Goals: where a tool should be, and the error twist that says how far it is.

use glam::{DMat3, DQuat, DVec3};

use super::IkError;
use crate::rotation;
use crate::spatial::PlueckerTransform;

/// What a goal constrains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkTarget {
    /// Position and orientation of the tool in world coordinates (6 error rows).
    Pose(PlueckerTransform),
    /// Only the position of the tool's origin in world coordinates, m (3 error rows); the
    /// orientation is free.
    Position(DVec3),
}

/// One goal: tool `tool` (an index into [`crate::Model::tools`]) at `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkGoal {
    /// The tool's index.
    pub tool: usize,
    /// Where it should be.
    pub target: IkTarget,
}

impl IkGoal {
    /// A full pose goal (world frame).
    pub fn pose(tool: usize, target: PlueckerTransform) -> Self {
        Self {
            tool,
            target: IkTarget::Pose(target),
        }
    }

    /// A position-only goal (world frame, m).
    pub fn position(tool: usize, target: DVec3) -> Self {
        Self {
            tool,
            target: IkTarget::Position(target),
        }
    }

    /// Number of error rows this goal adds: 6 for a pose, 3 for a position.
    pub fn rows(&self) -> usize {
        match self.target {
            IkTarget::Pose(_) => 6,
            IkTarget::Position(_) => 3,
        }
    }

    /// Checks that the target is finite and, for a pose, that its rotation is orthonormal
    /// and right-handed (to 1e-6).
    pub(super) fn validate(&self, index: usize) -> Result<(), IkError> {
        let bad = |reason| {
            Err(IkError::InvalidGoal {
                goal: index,
                reason,
            })
        };
        match &self.target {
            IkTarget::Position(p) => {
                if !p.is_finite() {
                    return bad("target position is not finite");
                }
            }
            IkTarget::Pose(x) => {
                if !x.translation.is_finite() {
                    return bad("target position is not finite");
                }
                if !x.rotation.is_finite() {
                    return bad("target rotation is not finite");
                }
                let r = x.rotation;
                let err = r.transpose() * r - DMat3::IDENTITY;
                let worst = err
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, e| m.max(libm::fabs(*e)));
                if worst > 1e-6 || r.determinant() < 0.0 {
                    return bad("target rotation is not a rotation matrix");
                }
            }
        }
        Ok(())
    }

    /// The error twist from `current` to the target in world coordinates, rows
    /// `[linear xyz; angular xyz]` (angular only for pose goals), into `out[..rows()]`.
    ///
    /// Linear: `p_target − p`. Angular: the rotation vector `log(R_target Rᵀ)` (axis times
    /// angle, the short way round), which is what `J q̇` must produce for a unit time step.
    pub(super) fn error(&self, current: &PlueckerTransform, out: &mut [f64]) {
        let (p, rot) = match &self.target {
            IkTarget::Pose(x) => (x.translation, Some(x.rotation)),
            IkTarget::Position(p) => (*p, None),
        };
        let dp = p - current.translation;
        out[..3].copy_from_slice(&dp.to_array());
        if let Some(r) = rot {
            out[3..6].copy_from_slice(&rotation_error(&r, &current.rotation).to_array());
        }
    }
}

/// `log(R_target R_currentᵀ)` as a world-frame rotation vector, angle in `[0, π]`.
fn rotation_error(target: &DMat3, current: &DMat3) -> DVec3 {
    let mut q = DQuat::from_mat3(&(*target * current.transpose()));
    if q.w < 0.0 {
        q = -q;
    }
    // exp(v) rotates by 2|v|, so the rotation vector is twice the logarithm.
    rotation::log(q.normalize()) * 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_error_is_axis_times_angle() {
        let axis = DVec3::new(1.0, -2.0, 0.5).normalize();
        let base = DMat3::from_euler(glam::EulerRot::ZYX, 0.3, -0.2, 1.0);
        for angle in [1e-9, 1e-3, 0.5, 3.0] {
            let target = DMat3::from_axis_angle(axis, angle) * base;
            let e = rotation_error(&target, &base);
            assert!((e - axis * angle).length() < 1e-12, "angle {angle}: {e:?}");
        }
    }

    #[test]
    fn pose_error_rows() {
        let cur = PlueckerTransform::from_translation(DVec3::new(1.0, 2.0, 3.0));
        let goal = IkGoal::pose(
            0,
            PlueckerTransform::new(DMat3::from_rotation_z(0.25), DVec3::new(1.5, 2.0, 2.0)),
        );
        let mut e = [0.0; 6];
        goal.error(&cur, &mut e);
        let want = [0.5, 0.0, -1.0, 0.0, 0.0, 0.25];
        for (a, b) in e.iter().zip(want) {
            assert!((a - b).abs() < 1e-14, "{e:?}");
        }
    }

    #[test]
    fn rejects_non_rotations() {
        let mut x = PlueckerTransform::IDENTITY;
        x.rotation = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0));
        assert!(matches!(
            IkGoal::pose(0, x).validate(3),
            Err(IkError::InvalidGoal { goal: 3, .. })
        ));
        x.rotation = DMat3::from_diagonal(DVec3::splat(2.0));
        assert!(IkGoal::pose(0, x).validate(0).is_err());
        assert!(
            IkGoal::position(0, DVec3::new(f64::NAN, 0.0, 0.0))
                .validate(0)
                .is_err()
        );
    }
}
