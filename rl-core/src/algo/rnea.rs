//! Inverse dynamics by the recursive Newton–Euler algorithm (RNEA).
//!
//! `τ = M(q) q̈ + C(q, q̇) + G(q) − Σ Jᵢᵀ fᵢ`: the joint forces that produce `q̈` (Featherstone,
//! *Rigid Body Dynamics Algorithms*, Table 5.1, body coordinates). `q`: `nq`, `qd`, `qdd`:
//! `dof` elements; the result has `dof` elements. Gravity enters as a fictitious
//! acceleration of the base, `a₀ = −g`. O(n). Does not allocate.
//!
//! With mimic joints the sweeps run on the internal coordinates, `q̇_int = G q̇`,
//! `q̈_int = G q̈`, and the result is `τ = Gᵀ τ_int` ([`crate::model::mimic`]): a mimic joint's
//! torque reaches its leader times the multiplier.
//!
//! The model's armature ([`Model::armature`]) adds `armature · q̈` per DOF.

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
    inverse_dynamics(model, data, q, Some(qd), Some(qdd), true, None);
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
    inverse_dynamics(model, data, q, Some(qd), Some(qdd), true, Some(fext));
    Ok(&data.tau[..model.nv])
}

/// RNEA on public coordinates into `data.tau[..nv]` (lengths already checked); `None`
/// velocities or accelerations are zero (and skipped).
#[inline]
pub(crate) fn inverse_dynamics<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
    with_gravity: bool,
    fext: Option<&[ForceVector]>,
) {
    if model.has_mimic {
        inverse_dynamics_mimic(model, data, q, qd, qdd, with_gravity, fext);
    } else {
        run::<false, N>(model, data, q, qd, qdd, with_gravity, fext);
    }
    if let Some(qdd) = qdd {
        model.add_armature_torque(&mut data.tau, qdd);
    }
}

/// `Gᵀ RNEA(q, G q̇, G q̈)`, for models with mimic joints (out of line: the common path stays
/// as it was).
#[cold]
#[inline(never)]
fn inverse_dynamics_mimic<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
    with_gravity: bool,
    fext: Option<&[ForceVector]>,
) {
    let qd = qd.map(|x| super::mimic::expand(model, x));
    let qdd = qdd.map(|x| super::mimic::expand(model, x));
    run::<true, N>(
        model,
        data,
        q,
        qd.as_ref().map(|x| &x[..]),
        qdd.as_ref().map(|x| &x[..]),
        with_gravity,
        fext,
    );
    super::mimic::contract_tau(model, data);
}

/// The RNEA sweeps over internal coordinates; `None` velocities or accelerations are zero
/// (and skipped).
#[inline]
fn run<const MIMIC: bool, const N: usize>(
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
        local_pose::<MIMIC, N>(model, data, q, i);
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
pub(crate) mod tests {
    use super::*;
    use crate::joint::{Joint, Revolute};
    use crate::model::ModelBuilder;
    use crate::spatial::{PlueckerTransform, RigidBodyInertia};
    use glam::{DMat3, DVec3};

    /// A point mass `m` on a massless rod of length `l`, pivoting about y, hanging along −z at
    /// q = 0, under gravity `g` along −z (also the derivatives' test model).
    pub(crate) fn pendulum(m: f64, l: f64, g: f64) -> crate::Model<1> {
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
        b.build()
    }

    /// τ = m l² q̈ + m g l sin q.
    #[test]
    fn pendulum_matches_the_closed_form() {
        let (m, l, g) = (2.0, 0.5, 9.81);
        let model = pendulum(m, l, g);
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

    /// With armature `a_r` the pendulum's inertia about its axis is `m l² + a_r`: RNEA, CRBA and
    /// ABA all see it; a negative, non-finite or wrongly sized armature is refused.
    #[test]
    fn armature_adds_to_the_pendulums_inertia() {
        let (m, l, g, ar) = (2.0, 0.5, 9.81, 0.3);
        let mut model = pendulum(m, l, g);
        model.set_armature(&[ar]).unwrap();
        assert_eq!(model.armature(), &[ar]);
        let mut data = Data::new();
        let (q, qd, qdd) = (0.3, 0.7, -1.1);
        let tau = rnea(&model, &mut data, &[q], &[qd], &[qdd]).unwrap()[0];
        let expected = (m * l * l + ar) * qdd + m * g * l * libm::sin(q);
        assert!((tau - expected).abs() < 1e-12, "{tau} vs {expected}");
        crate::algo::crba(&model, &mut data, &[q]).unwrap();
        assert!((data.mass_matrix(0, 0) - (m * l * l + ar)).abs() < 1e-12);
        let back = crate::algo::aba(&model, &mut data, &[q], &[qd], &[tau]).unwrap()[0];
        assert!((back - qdd).abs() < 1e-12, "{back} vs {qdd}");
        for bad in [-1e-3, f64::NAN, f64::INFINITY] {
            assert_eq!(
                model.set_armature(&[bad]),
                Err(Error::NotPhysical {
                    argument: "armature",
                    index: 0
                })
            );
        }
        assert!(matches!(
            model.set_armature(&[0.1, 0.2]),
            Err(Error::Dimension {
                argument: "armature",
                ..
            })
        ));
        // Refused values leave the armature as it was; zeros take it away.
        assert_eq!(model.armature(), &[ar]);
        model.set_armature(&[0.0]).unwrap();
        let tau = rnea(&model, &mut data, &[q], &[qd], &[qdd]).unwrap()[0];
        let expected = m * l * l * qdd + m * g * l * libm::sin(q);
        assert!((tau - expected).abs() < 1e-12);
    }
}
