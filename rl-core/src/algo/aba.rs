//! Forward dynamics by the articulated-body algorithm (ABA).
//!
//! `q̈ = M(q)⁻¹ (τ − C(q, q̇) − G(q))` in three sweeps without forming `M` (Featherstone,
//! *Rigid Body Dynamics Algorithms*, Table 7.1, here in world coordinates as Pinocchio does). Each joint's
//! `D = Sᵀ Iᴬ S` is at most 6×6 and inverted in place. `q`: `nq`, `qd`, `tau`: `dof`;
//! result: `dof`. O(n). Does not allocate.
//!
//! A mimic joint on another branch than its leader couples the branches, which the
//! articulated-body recursion cannot express (Pinocchio 4 has no ABA for mimic joints). For a
//! model with mimic joints, `q̈` is solved from the same equation through the mass matrix
//! instead: CRBA, the sparse `LᵀDL` factorisation ([`super::factor_mass_matrix`], whose
//! elimination tree covers the coupling) and RNEA with `q̈ = 0` for the bias, O(n·depth²).
//!
//! The model's armature ([`Model::armature`]) adds to each joint's `D`, as it adds to `M`'s
//! diagonal (without mimic joints internal and public coordinates are the same).
//!
//! Errors: [`Error::NotPositiveDefinite`] names the first DOF found whose joint moves no mass
//! or inertia (a massless subtree: its row of `M` vanishes).

use crate::error::{Error, check_len};
use crate::math::invert_spd;
use crate::model::{Data, Model, ROOT};
use crate::spatial::{ArticulatedBodyInertia, ForceVector, MotionVector};

use super::forward_position::world_pose;

/// `q̈ = ABA(q, q̇, τ)`, with the model's gravity.
pub fn aba<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
) -> Result<&'d [f64], Error> {
    run(model, data, q, qd, tau, None)?;
    Ok(&data.qdd[..model.nv])
}

/// `q̈ = ABA(q, q̇, τ)` with external forces: `fext[i]` acts on body `i`, in body `i`'s
/// coordinates (`body_count()` elements).
pub fn aba_with_external_forces<'d, const N: usize>(
    model: &Model<N>,
    data: &'d mut Data<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    fext: &[ForceVector],
) -> Result<&'d [f64], Error> {
    if fext.len() != model.nbodies {
        return Err(Error::Dimension {
            argument: "fext",
            expected: model.nbodies,
            got: fext.len(),
        });
    }
    run(model, data, q, qd, tau, Some(fext))?;
    Ok(&data.qdd[..model.nv])
}

fn run<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    fext: Option<&[ForceVector]>,
) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    check_len("tau", tau, model.nv)?;
    if model.has_mimic {
        return through_mass_matrix(model, data, q, qd, tau, fext);
    }
    // World coordinates throughout (as Pinocchio's ABA): inertias and subspaces are brought to
    // the world frame once, and then articulated inertias, bias forces and accelerations pass
    // between bodies by plain addition, with no transform per edge.
    // Pass 1: velocities, bias accelerations, rigid inertias and bias forces.
    for i in 0..model.nbodies {
        let x = world_pose::<false, N>(model, data, q, i);
        let sv = model.idx_v[i];
        let mut vj = MotionVector::ZERO;
        for k in sv..sv + model.joints[i].nv() {
            let s = model.act_subspace(i, k, &x);
            data.world_subspace[k] = s;
            vj += s * qd[k];
        }
        let p = model.parents[i];
        let v = if p == ROOT { vj } else { data.v[p] + vj };
        data.v[i] = v;
        data.c[i] = v.cross_motion(&vj);
        let inertia = model.world_inertia(i, &x);
        data.articulated[i] = ArticulatedBodyInertia::from(inertia);
        let mut pa = v.cross_force(&inertia.mul_motion(&v));
        if let Some(fext) = fext {
            pa -= x.act_force(&fext[i]);
        }
        data.f[i] = pa;
    }
    articulated_inertias(model, data, tau)?;
    // Pass 3: accelerations, root to leaves.
    let base = MotionVector::new(glam::DVec3::ZERO, -model.gravity);
    for i in 0..model.nbodies {
        let p = model.parents[i];
        let a = if p == ROOT { base } else { data.a[p] } + data.c[i];
        let (x, a) = joint_accelerations(model, data, i, a);
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        data.qdd[sv..sv + nv].copy_from_slice(&x[..nv]);
        data.a[i] = a;
    }
    Ok(())
}

/// Pass 3 for body `i`: its joint accelerations `q̈ = D⁻¹ (u − Uᵀ a)` (the first `nv` of the
/// array) and its own acceleration `a + S q̈`, where `a` is the parent's acceleration plus the
/// body's bias `c`. Shared with [`super::aba_derivatives`].
#[inline(always)]
pub(crate) fn joint_accelerations<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    i: usize,
    mut a: MotionVector,
) -> ([f64; 6], MotionVector) {
    let sv = model.idx_v[i];
    let nv = model.joints[i].nv();
    let d_inv = &data.d_inv[i];
    let mut out = [0.0; 6];
    if nv == 1 {
        let x = d_inv[0][0] * (data.u_bias[sv] - a.dot(&data.u[sv]));
        out[0] = x;
        return (out, a + data.world_subspace[sv] * x);
    }
    let mut rhs = [0.0; 6];
    for (k, r) in rhs.iter_mut().enumerate().take(nv) {
        *r = data.u_bias[sv + k] - a.dot(&data.u[sv + k]);
    }
    for k in 0..nv {
        let mut x = 0.0;
        for (l, r) in rhs.iter().enumerate().take(nv) {
            x += d_inv[k][l] * r;
        }
        out[k] = x;
        a += data.world_subspace[sv + k] * x;
    }
    (out, a)
}

/// Pass 2, leaves to root: each joint's `U = Iᴬ S`, `D⁻¹` and `u = τ − Sᵀ pᴬ`, and the
/// articulated inertias and bias forces handed to the parents (world coordinates, after pass 1
/// left each body's rigid inertia in `data.articulated` and its bias force in `data.f`). Shared
/// with [`super::aba_derivatives`].
#[inline]
pub(crate) fn articulated_inertias<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    tau: &[f64],
) -> Result<(), Error> {
    for i in (0..model.nbodies).rev() {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let p = model.parents[i];
        if nv == 1 {
            let s = data.world_subspace[sv];
            let u = data.articulated[i].mul_motion(&s);
            let d = s.dot(&u) + model.armature[sv];
            if d.is_nan() || d <= 0.0 {
                return Err(Error::NotPositiveDefinite { dof: sv });
            }
            let d_inv = 1.0 / d;
            let bias = tau[sv] - s.dot(&data.f[i]);
            data.u[sv] = u;
            data.u_bias[sv] = bias;
            data.d_inv[i][0][0] = d_inv;
            if p != ROOT {
                let mut ia = data.articulated[i];
                ia.sub_rank_one(&u, d_inv);
                let pa = data.f[i] + ia.mul_motion(&data.c[i]) + u * (d_inv * bias);
                data.articulated[p] += ia;
                data.f[p] += pa;
            }
            continue;
        }
        let ia = data.articulated[i];
        let pa = data.f[i];
        let mut d = [[0.0; 6]; 6];
        for k in 0..nv {
            let u = ia.mul_motion(&data.world_subspace[sv + k]);
            data.u[sv + k] = u;
            data.u_bias[sv + k] = tau[sv + k] - data.world_subspace[sv + k].dot(&pa);
            for l in 0..=k {
                let x = data.world_subspace[sv + l].dot(&u);
                d[l][k] = x;
                d[k][l] = x;
            }
        }
        for k in 0..nv {
            d[k][k] += model.armature[sv + k];
        }
        let mut d_inv = [[0.0; 6]; 6];
        if !invert_spd(&d, nv, &mut d_inv) {
            return Err(Error::NotPositiveDefinite { dof: sv });
        }
        data.d_inv[i] = d_inv;
        if p == ROOT {
            continue;
        }
        // Ia = Iᴬ − U D⁻¹ Uᵀ ; pa = pᴬ + Ia c + U D⁻¹ u
        let mut ia_child = ia;
        let mut pa_child = pa;
        for k in 0..nv {
            let mut w = ForceVector::ZERO;
            let mut coef = 0.0;
            for l in 0..nv {
                w += data.u[sv + l] * d_inv[k][l];
                coef += d_inv[k][l] * data.u_bias[sv + l];
            }
            ia_child.sub_outer(&data.u[sv + k], &w);
            pa_child += data.u[sv + k] * coef;
        }
        pa_child += ia_child.mul_motion(&data.c[i]);
        data.articulated[p] += ia_child;
        data.f[p] += pa_child;
    }
    Ok(())
}

/// `q̈ = M⁻¹ (τ − RNEA(q, q̇, 0))` into `data.qdd`, for models with mimic joints (out of line:
/// the common path stays as it was).
#[cold]
#[inline(never)]
fn through_mass_matrix<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    fext: Option<&[ForceVector]>,
) -> Result<(), Error> {
    super::crba(model, data, q)?;
    super::factor_mass_matrix(model, data)?;
    super::rnea::inverse_dynamics(model, data, q, Some(qd), None, true, fext);
    let n = model.nv;
    let mut x = [0.0; N];
    for k in 0..n {
        x[k] = tau[k] - data.tau[k];
    }
    super::solve_mass_matrix(model, data, &mut x[..n])?;
    data.qdd[..n].copy_from_slice(&x[..n]);
    Ok(())
}
