//! Analytical derivative of the static torque, `∂g/∂q` of `g(q) = RNEA(q, 0, 0)` (gravity,
//! and with external forces `g(q) − Σ Jᵢᵀ fᵢ`).
//!
//! The RNEA derivatives of [`super::rnea_derivatives`] at rest (Carpentier and Mansard, RSS
//! 2018; Pinocchio's `computeStaticTorqueDerivatives`), where they collapse: every body has the
//! world acceleration `a₀ = (0, −g)`, so `dV = 0` and `dA_j = a₀ × S_j = (0, ω_j × g)` with
//! `ω_j` the angular part of the world column `S_j`, and a composite inertia acts on it through
//! its mass `m` and first moment `h` only: `I^c dA_j = (h × u_j, m u_j)`, `u_j = ω_j × g`.
//! With `F = (h × (−g), −m g) − Σ fext` the subtree force,
//!
//! ```text
//! r on b or below:  ∂g_r/∂q_j = S_r · (h × u_j, m u_j) = u_j · (ω_r × h + m v_r)   (composites of r's body)
//! r above b:        ∂g_r/∂q_j = S_r · ((h × u_j, m u_j) + S_j ×* F)                (composites of b)
//! ```
//!
//! `q`: `nq`; result: `dof × dof` in [`DerivativeData::dtau_dq`] (Pinocchio's tangent-space
//! convention, see [`super::rnea_derivatives`]), the torques in `data` as [`super::gravity`]
//! writes them. O(n·depth). Does not allocate. With mimic joints `Gᵀ X_int G`.

use glam::DVec3;

use crate::error::{Error, check_len};
use crate::model::{Data, DerivativeData, MatrixView, Model, ROOT};
use crate::spatial::{ForceVector, MotionVector};

use super::forward_position::world_pose;

/// `∂g/∂q` of the generalized gravity `g(q)` (`dof × dof`).
pub fn static_torque_derivatives<'d, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &'d mut DerivativeData<N>,
    q: &[f64],
) -> Result<MatrixView<'d, N>, Error> {
    check_len("q", q, model.nq)?;
    run(model, data, deriv, q, None);
    Ok(deriv.dtau_dq())
}

/// `∂/∂q` of the static torque `g(q) − Σ Jᵢᵀ fᵢ`: `fext[i]` acts on body `i`, in body `i`'s
/// coordinates (`body_count()` elements), and turns with it.
pub fn static_torque_derivatives_with_external_forces<'d, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &'d mut DerivativeData<N>,
    q: &[f64],
    fext: &[ForceVector],
) -> Result<MatrixView<'d, N>, Error> {
    check_len("q", q, model.nq)?;
    super::rnea_derivatives::check_fext(model, fext)?;
    run(model, data, deriv, q, Some(fext));
    Ok(deriv.dtau_dq())
}

fn run<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &mut DerivativeData<N>,
    q: &[f64],
    fext: Option<&[ForceVector]>,
) {
    deriv.n = model.nv;
    if model.has_mimic {
        run_mimic(model, data, deriv, q, fext);
    } else {
        let d = &mut *deriv;
        sweeps::<false, N>(model, data, &mut d.ws, &mut d.dtau_dq, q, fext);
    }
}

/// `Gᵀ X_int G`, for models with mimic joints (out of line).
#[cold]
#[inline(never)]
fn run_mimic<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &mut DerivativeData<N>,
    q: &[f64],
    fext: Option<&[ForceVector]>,
) {
    let d = &mut *deriv;
    sweeps::<true, N>(model, data, &mut d.ws, &mut d.ddq_dq, q, fext);
    super::rnea_derivatives::contract(model, &d.ddq_dq, &mut d.dtau_dq);
    super::mimic::contract_tau(model, data);
}

/// The two sweeps over internal coordinates into `dq`. Composite mass and first moment (world
/// coordinates) in `data.composite`, the subtree force in `data.f`; `u_j` in the linear part
/// of `ws.da`, `∂F/∂q` in `ws.dfdq`.
#[inline]
fn sweeps<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    ws: &mut crate::model::DerivativeWorkspace<N>,
    dq: &mut [[f64; N]; N],
    q: &[f64],
    fext: Option<&[ForceVector]>,
) {
    let n = model.nv_ext;
    let g = model.gravity;
    for row in dq[..n].iter_mut() {
        row[..n].fill(0.0);
    }
    for i in 0..model.nbodies {
        let x = world_pose::<MIMIC, N>(model, data, q, i);
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        for k in sv..sv + nv {
            let s = model.act_subspace(i, k, &x);
            data.world_subspace[k] = s;
            ws.da[k] = MotionVector::new(DVec3::ZERO, s.angular.cross(g));
        }
        let m = model.inertias[i].mass;
        data.composite[i].mass = m;
        data.composite[i].first_moment = x.transform_point(model.coms[i]) * m;
        data.f[i] = match fext {
            Some(fext) => -x.act_force(&fext[i]),
            None => ForceVector::ZERO,
        };
    }
    for i in (0..model.nbodies).rev() {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let own = sv..sv + nv;
        let (m, h) = (data.composite[i].mass, data.composite[i].first_moment);
        let f = data.f[i]
            + ForceVector {
                moment: g.cross(h),
                force: -g * m,
            };
        for k in own.clone() {
            let u = ws.da[k].linear;
            ws.dfdq[k] = ForceVector {
                moment: h.cross(u),
                force: u * m,
            };
        }
        let mut y = [DVec3::ZERO; 6];
        for r in own.clone() {
            let s = data.world_subspace[r];
            data.tau[r] = s.dot(&f);
            for c in own.clone() {
                dq[r][c] = s.dot(&ws.dfdq[c]);
            }
            y[r - sv] = s.angular.cross(h) + s.linear * m;
        }
        for k in own.clone() {
            ws.dfdq[k] += data.world_subspace[k].cross_force(&f);
        }
        let mut b = model.parents[i];
        while b != ROOT {
            let sb = model.idx_v[b];
            for a in sb..sb + model.joints[b].nv() {
                let sa = data.world_subspace[a];
                let ua = ws.da[a].linear;
                for r in own.clone() {
                    dq[r][a] = y[r - sv].dot(ua);
                    dq[a][r] = sa.dot(&ws.dfdq[r]);
                }
            }
            b = model.parents[b];
        }
        let p = model.parents[i];
        if p != ROOT {
            data.composite[p].mass += m;
            data.composite[p].first_moment += h;
            // Only the external forces travel in `f`; gravity's part is rebuilt from (m, h).
            let fe = data.f[i];
            data.f[p] += fe;
        }
    }
}
