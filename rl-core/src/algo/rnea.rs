//! Inverse dynamics by the recursive Newton–Euler algorithm (RNEA).
//!
//! `τ = M(q) q̈ + C(q, q̇) + G(q) − Σ Jᵢᵀ fᵢ`: the joint forces that produce `q̈` (Featherstone,
//! *Rigid Body Dynamics Algorithms*, Table 5.1, body coordinates). `q`: `nq`, `qd`, `qdd`:
//! `dof` elements; the result has `dof` elements. Gravity enters as a fictitious
//! acceleration of the base, `a₀ = −g`. O(n). Does not allocate.

use crate::error::{Error, check_len};
use crate::model::{Data, Model, ROOT};
use crate::spatial::{ForceVector, MotionVector};

use super::forward_position::local_pose;

/// `τ = RNEA(q, q̇, q̈)`, with the model's gravity.
pub fn rnea<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'d [f64], Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    check_len("qdd", qdd, model.nv)?;
    run(model, data, q, Some(qd), Some(qdd), true, None);
    Ok(&data.tau[..model.nv])
}

/// `τ = RNEA(q, q̇, q̈)` with external forces: `fext[i]` acts on body `i`, in body `i`'s
/// coordinates (`body_count()` elements).
pub fn rnea_with_external_forces<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    fext: &[ForceVector],
) -> Result<&'d [f64], Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    check_len("qdd", qdd, model.nv)?;
    if fext.len() != model.nbodies {
        return Err(Error::Dimension {
            argument: "fext",
            expected: model.nbodies,
            got: fext.len(),
        });
    }
    run(model, data, q, Some(qd), Some(qdd), true, Some(fext));
    Ok(&data.tau[..model.nv])
}

/// The RNEA sweeps; `None` velocities or accelerations are zero (and skipped).
#[inline]
pub(crate) fn run<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
    with_gravity: bool,
    fext: Option<&[ForceVector]>,
) {
    let base = MotionVector::new(
        glam::DVec3::ZERO,
        if with_gravity {
            -model.gravity
        } else {
            glam::DVec3::ZERO
        },
    );
    for i in 0..model.nbodies {
        local_pose(model, data, q, i);
        let p = model.parents[i];
        let x = &data.parent_pose[i];
        let inertia = &model.inertias[i];
        let ap = if p == ROOT { base } else { data.a[p] };
        let mut a = x.inv_act_motion(&ap);
        if let Some(qdd) = qdd {
            a += model.joint_motion(i, qdd);
        }
        let mut f;
        if let Some(qd) = qd {
            let vj = model.joint_motion(i, qd);
            let v = if p == ROOT {
                vj
            } else {
                x.inv_act_motion(&data.v[p]) + vj
            };
            a += v.cross_motion(&vj);
            f = inertia.mul_motion(&a) + v.cross_force(&inertia.mul_motion(&v));
            data.v[i] = v;
        } else {
            f = inertia.mul_motion(&a);
        }
        if let Some(fext) = fext {
            f -= fext[i];
        }
        data.a[i] = a;
        data.f[i] = f;
    }
    for i in (0..model.nbodies).rev() {
        let f = data.f[i];
        model.joint_force(i, &f, &mut data.tau);
        let p = model.parents[i];
        if p != ROOT {
            let fp = data.parent_pose[i].act_force(&f);
            data.f[p] += fp;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::{Joint, Revolute};
    use crate::model::ModelBuilder;
    use crate::spatial::{PlueckerTransform, RigidBodyInertia};
    use glam::{DMat3, DVec3};

    /// A point mass m on a massless rod of length l, pivoting about y, hanging along −z
    /// at q = 0: τ = m l² q̈ + m g l sin q.
    #[test]
    fn pendulum_matches_the_closed_form() {
        let (m, l, g) = (2.0, 0.5, 9.81);
        let mut b = ModelBuilder::<1>::new();
        b.gravity(DVec3::new(0.0, 0.0, -g));
        b.add_body(
            ROOT,
            "j",
            Joint::Revolute(Revolute::new(DVec3::Y)),
            PlueckerTransform::IDENTITY,
            "rod",
            RigidBodyInertia::from_com(m, DVec3::new(0.0, 0.0, -l), DMat3::ZERO),
        )
        .unwrap();
        let model = b.build();
        let mut data = Data::new();
        let (q, qd, qdd) = (0.3, 0.7, -1.1);
        let tau = rnea(&model, &mut data, &[q], &[qd], &[qdd]).unwrap()[0];
        // Rotation about +y moves the −z mass towards −x; gravity's torque about y is
        // m g l sin q restoring.
        let expected = m * l * l * qdd + m * g * l * libm::sin(q);
        assert!((tau - expected).abs() < 1e-12, "{tau} vs {expected}");
        assert_eq!(
            rnea(&model, &mut data, &[q, 0.0], &[qd], &[qdd]),
            Err(Error::Dimension {
                argument: "q",
                expected: 1,
                got: 2
            })
        );
    }
}
