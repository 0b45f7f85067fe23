//! Forward dynamics by the articulated-body algorithm (ABA).
//!
//! `q̈ = M(q)⁻¹ (τ − C(q, q̇) − G(q))` in three sweeps without forming `M` (Featherstone,
//! *Rigid Body Dynamics Algorithms*, Table 7.1, body coordinates). Each joint's
//! `D = Sᵀ Iᴬ S` is at most 6×6 and inverted in place. `q`: `nq`, `qd`, `tau`: `dof`;
//! result: `dof`. O(n). Does not allocate.

use crate::error::{Error, check_len};
use crate::math::invert_spd;
use crate::model::{Data, Model, ROOT};
use crate::spatial::{ArticulatedBodyInertia, ForceVector, MotionVector};

use super::forward_position::body_pose;

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
    // Pass 1: velocities, bias accelerations, rigid inertias and bias forces.
    for i in 0..model.nbodies {
        body_pose(model, data, q, i);
        let sv = model.idx_v[i];
        let mut vj = MotionVector::ZERO;
        for k in sv..sv + model.joints[i].nv() {
            vj += model.subspace[k] * qd[k];
        }
        let p = model.parents[i];
        let v = if p == ROOT {
            vj
        } else {
            data.parent_pose[i].inv_act_motion(&data.v[p]) + vj
        };
        data.v[i] = v;
        data.c[i] = v.cross_motion(&vj);
        let inertia = &model.inertias[i];
        data.articulated[i] = ArticulatedBodyInertia::from(*inertia);
        let mut pa = v.cross_force(&inertia.mul_motion(&v));
        if let Some(fext) = fext {
            pa -= fext[i];
        }
        data.f[i] = pa;
    }
    // Pass 2: articulated inertias and bias forces, leaves to root.
    for i in (0..model.nbodies).rev() {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let ia = data.articulated[i];
        let pa = data.f[i];
        let mut d = [[0.0; 6]; 6];
        for k in 0..nv {
            let u = ia.mul_motion(&model.subspace[sv + k]);
            data.u[sv + k] = u;
            data.u_bias[sv + k] = tau[sv + k] - model.subspace[sv + k].dot(&pa);
            for l in 0..=k {
                let x = model.subspace[sv + l].dot(&u);
                d[l][k] = x;
                d[k][l] = x;
            }
        }
        let mut d_inv = [[0.0; 6]; 6];
        if !invert_spd(&d, nv, &mut d_inv) {
            return Err(Error::NotPositiveDefinite);
        }
        data.d_inv[i] = d_inv;
        let p = model.parents[i];
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
        let x = &data.parent_pose[i];
        let ia_parent = ia_child.transform_to_parent(x);
        let pa_parent = x.act_force(&pa_child);
        data.articulated[p] += ia_parent;
        data.f[p] += pa_parent;
    }
    // Pass 3: accelerations, root to leaves.
    let base = MotionVector::new(glam::DVec3::ZERO, -model.gravity);
    for i in 0..model.nbodies {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let p = model.parents[i];
        let ap = if p == ROOT { base } else { data.a[p] };
        let mut a = data.parent_pose[i].inv_act_motion(&ap) + data.c[i];
        let mut rhs = [0.0; 6];
        for (k, r) in rhs.iter_mut().enumerate().take(nv) {
            *r = data.u_bias[sv + k] - a.dot(&data.u[sv + k]);
        }
        let d_inv = &data.d_inv[i];
        for k in 0..nv {
            let mut x = 0.0;
            for (l, r) in rhs.iter().enumerate().take(nv) {
                x += d_inv[k][l] * r;
            }
            data.qdd[sv + k] = x;
            a += model.subspace[sv + k] * x;
        }
        data.a[i] = a;
    }
    Ok(())
}
