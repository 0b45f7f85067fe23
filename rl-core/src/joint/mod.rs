//! Joint types: the motion a joint allows between its parent and child frames.
//!
//! Every joint here has a motion subspace `S` that is constant in the child frame, so the
//! joint's bias acceleration `c_J = Ṡ q̇` vanishes and the algorithms need only the joint
//! transform `X_J(q)` from the joint. Joints whose configuration is not a vector space
//! (spherical, six-DOF) carry a unit quaternion `(x, y, z, w)` in `q` and have velocities in
//! the child (body) frame, as RL and Pinocchio do; `nq` then differs from `nv`.

mod cylindrical;
mod fixed;
mod helical;
mod planar;
mod prismatic;
mod revolute;
mod six_dof;
mod spherical;

pub use cylindrical::Cylindrical;
pub use fixed::Fixed;
pub use helical::Helical;
pub use planar::Planar;
pub use prismatic::Prismatic;
pub use revolute::Revolute;
pub use six_dof::SixDof;
pub use spherical::Spherical;

use glam::DVec3;

use crate::spatial::{MotionVector, PlueckerTransform};

/// The most velocity coordinates any joint has.
pub const MAX_JOINT_NV: usize = 6;
/// The most position coordinates any joint has.
pub const MAX_JOINT_NQ: usize = 7;

/// A moving joint. (Fixed joints are merged into their parent body when a model is built.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Joint {
    /// One rotation about an axis.
    Revolute(Revolute),
    /// One translation along an axis.
    Prismatic(Prismatic),
    /// A screw: rotation about an axis coupled with translation along it.
    Helical(Helical),
    /// Independent rotation about and translation along one axis.
    Cylindrical(Cylindrical),
    /// Translation in the x-y plane and rotation about z.
    Planar(Planar),
    /// Free rotation about a point (ball joint).
    Spherical(Spherical),
    /// Free motion in space (floating base).
    SixDof(SixDof),
}

/// The kind of a joint, without its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JointKind {
    /// See [`Revolute`].
    Revolute,
    /// See [`Prismatic`].
    Prismatic,
    /// See [`Helical`].
    Helical,
    /// See [`Cylindrical`].
    Cylindrical,
    /// See [`Planar`].
    Planar,
    /// See [`Spherical`].
    Spherical,
    /// See [`SixDof`].
    SixDof,
    /// See [`Fixed`].
    Fixed,
}

impl JointKind {
    /// A short lower-case name, as in RL's XML elements.
    pub fn name(self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
            JointKind::Helical => "helical",
            JointKind::Cylindrical => "cylindrical",
            JointKind::Planar => "planar",
            JointKind::Spherical => "spherical",
            JointKind::SixDof => "sixDof",
            JointKind::Fixed => "fixed",
        }
    }
}

impl Joint {
    /// The kind of this joint.
    pub fn kind(&self) -> JointKind {
        match self {
            Joint::Revolute(_) => JointKind::Revolute,
            Joint::Prismatic(_) => JointKind::Prismatic,
            Joint::Helical(_) => JointKind::Helical,
            Joint::Cylindrical(_) => JointKind::Cylindrical,
            Joint::Planar(_) => JointKind::Planar,
            Joint::Spherical(_) => JointKind::Spherical,
            Joint::SixDof(_) => JointKind::SixDof,
        }
    }

    /// Number of position coordinates.
    #[inline]
    pub fn nq(&self) -> usize {
        match self {
            Joint::Revolute(_) | Joint::Prismatic(_) | Joint::Helical(_) => 1,
            Joint::Cylindrical(_) => 2,
            Joint::Planar(_) => 3,
            Joint::Spherical(_) => 4,
            Joint::SixDof(_) => 7,
        }
    }

    /// Number of velocity coordinates (degrees of freedom).
    #[inline]
    pub fn nv(&self) -> usize {
        match self {
            Joint::Revolute(_) | Joint::Prismatic(_) | Joint::Helical(_) => 1,
            Joint::Cylindrical(_) => 2,
            Joint::Planar(_) | Joint::Spherical(_) => 3,
            Joint::SixDof(_) => 6,
        }
    }

    /// The joint transform `X_J(q)`: the child frame's pose in the joint's parent frame.
    /// `q` holds this joint's `nq` coordinates.
    #[inline]
    pub fn transform(&self, q: &[f64]) -> PlueckerTransform {
        match self {
            Joint::Revolute(j) => j.transform(q[0]),
            Joint::Prismatic(j) => j.transform(q[0]),
            Joint::Helical(j) => j.transform(q[0]),
            Joint::Cylindrical(j) => j.transform(q[0], q[1]),
            Joint::Planar(j) => j.transform(q[0], q[1], q[2]),
            Joint::Spherical(j) => j.transform(q),
            Joint::SixDof(j) => j.transform(q),
        }
    }

    /// `placement · X_J(q)`: the child frame's pose in the frame the joint is placed in,
    /// with the common joints' products written out (a rotation about a coordinate axis
    /// touches two columns).
    #[inline(always)]
    pub fn placed_transform(&self, placement: &PlueckerTransform, q: &[f64]) -> PlueckerTransform {
        match self {
            Joint::Revolute(j) => j.placed(placement, q[0]),
            Joint::Prismatic(j) => PlueckerTransform::new(
                placement.rotation,
                placement.translation + placement.rotation * (j.axis * q[0]),
            ),
            // A floating base is usually placed at the identity: skip the product.
            Joint::SixDof(j) if *placement == PlueckerTransform::IDENTITY => j.transform(q),
            _ => *placement * self.transform(q),
        }
    }

    /// The columns of the motion subspace `S` in child coordinates, written to `out[..nv]`.
    pub fn motion_subspace(&self, out: &mut [MotionVector]) {
        match self {
            Joint::Revolute(j) => out[0] = MotionVector::new(j.axis, DVec3::ZERO),
            Joint::Prismatic(j) => out[0] = MotionVector::new(DVec3::ZERO, j.axis),
            Joint::Helical(j) => out[0] = MotionVector::new(j.axis, j.axis * j.pitch),
            Joint::Cylindrical(j) => {
                out[0] = MotionVector::new(j.axis, DVec3::ZERO);
                out[1] = MotionVector::new(DVec3::ZERO, j.axis);
            }
            Joint::Planar(_) => {
                out[0] = MotionVector::new(DVec3::ZERO, DVec3::X);
                out[1] = MotionVector::new(DVec3::ZERO, DVec3::Y);
                out[2] = MotionVector::new(DVec3::Z, DVec3::ZERO);
            }
            Joint::Spherical(_) => {
                out[0] = MotionVector::new(DVec3::X, DVec3::ZERO);
                out[1] = MotionVector::new(DVec3::Y, DVec3::ZERO);
                out[2] = MotionVector::new(DVec3::Z, DVec3::ZERO);
            }
            Joint::SixDof(_) => {
                out[0] = MotionVector::new(DVec3::ZERO, DVec3::X);
                out[1] = MotionVector::new(DVec3::ZERO, DVec3::Y);
                out[2] = MotionVector::new(DVec3::ZERO, DVec3::Z);
                out[3] = MotionVector::new(DVec3::X, DVec3::ZERO);
                out[4] = MotionVector::new(DVec3::Y, DVec3::ZERO);
                out[5] = MotionVector::new(DVec3::Z, DVec3::ZERO);
            }
        }
    }

    /// The configuration reached from `q` by moving with the constant velocity `v` for `dt`
    /// seconds (`q ⊕ v dt`), written to `out[..nq]`. Exact for every joint type (for spherical
    /// and six-DOF joints the exponential map with a body-frame velocity).
    pub fn integrate(&self, q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
        match self {
            Joint::Revolute(_) | Joint::Prismatic(_) | Joint::Helical(_) => {
                out[0] = q[0] + v[0] * dt
            }
            Joint::Cylindrical(_) => {
                out[0] = q[0] + v[0] * dt;
                out[1] = q[1] + v[1] * dt;
            }
            Joint::Planar(_) => Planar::integrate(q, v, dt, out),
            Joint::Spherical(_) => Spherical::integrate(q, v, dt, out),
            Joint::SixDof(_) => SixDof::integrate(q, v, dt, out),
        }
    }

    /// The neutral configuration (zero angles and translations, identity rotation), written
    /// to `out[..nq]`.
    pub fn neutral(&self, out: &mut [f64]) {
        for x in out.iter_mut().take(self.nq()) {
            *x = 0.0;
        }
        match self {
            Joint::Spherical(_) => out[3] = 1.0,
            Joint::SixDof(_) => out[6] = 1.0,
            _ => {}
        }
    }

    /// Whether this joint's position coordinates include a unit quaternion that must be kept
    /// normalised.
    pub fn has_quaternion(&self) -> bool {
        matches!(self, Joint::Spherical(_) | Joint::SixDof(_))
    }

    /// Renormalises the quaternion part of `q[..nq]`, if any.
    pub fn normalize(&self, q: &mut [f64]) {
        let range = match self {
            Joint::Spherical(_) => 0..4,
            Joint::SixDof(_) => 3..7,
            _ => return,
        };
        let n = libm::sqrt(q[range.clone()].iter().map(|x| x * x).sum::<f64>());
        if n > 0.0 {
            for x in &mut q[range] {
                *x /= n;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Finite differences of the joint transform along `integrate` recover `S v`.
    fn check_subspace(j: Joint, q: &[f64], v: &[f64]) {
        let h = 1e-6;
        let mut qp = [0.0; 7];
        let mut qm = [0.0; 7];
        j.integrate(q, v, h, &mut qp);
        j.integrate(q, v, -h, &mut qm);
        let x0 = j.transform(q);
        let xp = j.transform(&qp[..j.nq()]);
        let xm = j.transform(&qm[..j.nq()]);
        // body velocity: X0⁻¹ dX/dt; ω from skew part of R0ᵀ Ṙ, v = R0ᵀ ṗ
        let rdot = (xp.rotation - xm.rotation) * (0.5 / h);
        let pdot = (xp.translation - xm.translation) * (0.5 / h);
        let w = x0.rotation.transpose() * rdot;
        let omega = DVec3::new(w.col(1).z, w.col(2).x, w.col(0).y);
        let lin = x0.rotation.transpose() * pdot;
        let mut s = [MotionVector::ZERO; 6];
        j.motion_subspace(&mut s);
        let mut sv = MotionVector::ZERO;
        for k in 0..j.nv() {
            sv += s[k] * v[k];
        }
        assert!(
            (sv.angular - omega).length() < 1e-8,
            "{j:?}: {sv:?} vs {omega}"
        );
        assert!((sv.linear - lin).length() < 1e-8, "{j:?}: {sv:?} vs {lin}");
    }

    #[test]
    fn motion_subspaces_match_the_transforms() {
        let axis = DVec3::new(0.3, -0.5, 0.8).normalize();
        check_subspace(Joint::Revolute(Revolute::new(axis)), &[0.7], &[1.3]);
        check_subspace(Joint::Prismatic(Prismatic::new(axis)), &[0.2], &[-0.4]);
        check_subspace(Joint::Helical(Helical::new(axis, 0.05)), &[0.9], &[2.0]);
        check_subspace(
            Joint::Cylindrical(Cylindrical::new(axis)),
            &[0.4, 0.1],
            &[0.3, -0.2],
        );
        check_subspace(Joint::Planar(Planar), &[0.2, -0.3, 0.8], &[0.5, 0.1, -0.9]);
        let q = glam::DQuat::from_axis_angle(axis, 0.6);
        check_subspace(
            Joint::Spherical(Spherical),
            &[q.x, q.y, q.z, q.w],
            &[0.2, -0.7, 0.4],
        );
        check_subspace(
            Joint::SixDof(SixDof),
            &[0.1, 0.2, 0.3, q.x, q.y, q.z, q.w],
            &[0.5, -0.2, 0.1, 0.2, -0.7, 0.4],
        );
    }
}
