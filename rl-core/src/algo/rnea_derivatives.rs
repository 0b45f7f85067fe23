//! Analytical derivatives of inverse dynamics: `∂τ/∂q`, `∂τ/∂q̇` and `∂τ/∂q̈ = M` of
//! `τ = RNEA(q, q̇, q̈)`.
//!
//! Carpentier and Mansard, "Analytical Derivatives of Rigid Body Dynamics Algorithms",
//! Robotics: Science and Systems 2018 (Pinocchio's `computeRNEADerivatives`), in world
//! coordinates. `q`: `nq`; `qd`, `qdd`: `dof`; each result is `dof × dof`
//! ([`DerivativeData::dtau_dq`], [`DerivativeData::dtau_dv`], [`DerivativeData::mass_matrix`],
//! row `r` = `τ_r`, column `c` = the coordinate differentiated by). The torques themselves land
//! in `data` as RNEA's do. O(n·depth). Does not allocate.
//!
//! **Tangent-space convention (Pinocchio's).** `∂τ/∂q` is taken along the joints' own motion:
//! column `c` is `d/dε τ(q ⊕ ε e_c)` at `ε = 0`, where `⊕` is [`Model::integrate`] (for a
//! spherical joint `q ⊕ ε e_c = q · exp(ε e_c)`, for a six-DOF joint the SE(3) exponential of a
//! body-frame twist, for a planar joint SE(2)'s). So a quaternion joint has 3 (spherical) or 6
//! (six-DOF) columns, not 4 or 7: the `dof × dof` shape of every matrix here.
//!
//! **The recursion.** Every joint's motion subspace is constant in its child body, so moving
//! coordinate `j` of body `b` by `ε` moves the whole subtree of `b` by the world twist `ε S_j`:
//! each quantity rigidly carried by a body `k ⪰ b` changes by the spatial cross product with
//! `S_j` (`S_j × m` for motions, `S_j ×* f` for forces). With `λ` the parent of `b`, `v`, `a`
//! world spatial velocities and accelerations (gravity as the base's acceleration), `I` world
//! inertias, `f_k = I_k a_k + v_k ×* I_k v_k`, and for `k ⪰ b`:
//!
//! ```text
//! ∂v_k/∂q_j = S_j × v_k + dV_j,              dV_j = v_λ × S_j
//! ∂a_k/∂q_j = S_j × a_k + dV_j × v_k + dA_j,  dA_j = a_λ × S_j + v_λ × dV_j
//! ∂f_k/∂q_j = S_j ×* f_k + I_k dA_j + B_k dV_j
//! ∂a_k/∂q̇_j = S_j × v_k + dAv_j,             dAv_j = (v_λ + v_b) × S_j
//! ∂f_k/∂q̇_j = I_k dAv_j + B_k S_j
//! B_k x = v_k ×* I_k x − I_k (v_k × x) + x ×* I_k v_k
//! ```
//!
//! `B_k` acts on the angular part `ω` of `x` only (the linear parts cancel):
//! `B_k x = (B̄_k ω, 2 ω × p_k)` with `p_k` the body's linear momentum and
//! `B̄_k = [w]× Ī − Ī [w]× − [Ī w]× − 2 [h]× [v_lin]×` (`w` the angular velocity, `Ī`, `h` the
//! rotational inertia and first moment about the world origin). Summed over a subtree, `I^c`,
//! `B̄^c`, `p^c` and `F = Σ f` are composites, and with `τ_r = S_rᵀ F_body(r)`:
//!
//! ```text
//! r on b or a descendant of b:  ∂τ_r/∂q_j = S_r · (I^c dA_j + B^c dV_j)         (composites of r's body)
//! r on an ancestor of b:        ∂τ_r/∂q_j = S_r · (I^c dA_j + B^c dV_j + S_j ×* F)  (composites of b)
//! ```
//!
//! (on `r`'s own body the rotation of `S_r` cancels `S_j ×* F`), the same for `q̇` with
//! `dAv`, `S_j` and without the last term, and `M_rj = S_r · I^c S_j`. Entries between
//! coordinates on different branches are zero. Pinocchio computes the same quantities with its
//! `doYcrb`, `dVdq`, `dAdq`, `dAdv`, `dFdq`.
//!
//! With mimic joints the sweeps run on the internal coordinates and each matrix is `Gᵀ X_int G`
//! ([`crate::model::mimic`]): a public coordinate moves its mimic joints with it
//! (Pinocchio 4.1 has no derivatives for mimic models; these are checked against finite
//! differences).

use glam::{DMat3, DVec3};

use crate::error::{Error, check_len};
use crate::model::{Data, DerivativeData, DerivativeWorkspace, MatrixView, Model, ROOT};
use crate::spatial::{ForceVector, MotionVector, RigidBodyInertia, skew};

use super::forward_position::world_pose;

/// The results of [`rnea_derivatives`]: views into the [`DerivativeData`].
#[derive(Clone, Copy, Debug)]
pub struct RneaDerivatives<'a, const N: usize> {
    /// `∂τ/∂q` (tangent space), `dof × dof`.
    pub dtau_dq: MatrixView<'a, N>,
    /// `∂τ/∂q̇`, `dof × dof`.
    pub dtau_dv: MatrixView<'a, N>,
    /// `∂τ/∂q̈ = M(q)`, `dof × dof`, symmetric (both triangles written).
    pub mass_matrix: MatrixView<'a, N>,
}

/// `∂τ/∂q`, `∂τ/∂q̇` and `M` of `τ = RNEA(q, q̇, q̈)` with the model's gravity; `τ` itself goes
/// to `data` (as [`super::rnea`] would write it, though not returned here).
pub fn rnea_derivatives<'d, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &'d mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<RneaDerivatives<'d, N>, Error> {
    check(model, q, qd, qdd, None)?;
    run(model, data, deriv, q, qd, qdd, None);
    Ok(views(deriv))
}

/// [`rnea_derivatives`] with external forces: `fext[i]` acts on body `i`, in body `i`'s
/// coordinates (`body_count()` elements), as in [`super::rnea_with_external_forces`]; they
/// turn with their bodies.
pub fn rnea_derivatives_with_external_forces<'d, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &'d mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    fext: &[ForceVector],
) -> Result<RneaDerivatives<'d, N>, Error> {
    check(model, q, qd, qdd, Some(fext))?;
    run(model, data, deriv, q, qd, qdd, Some(fext));
    Ok(views(deriv))
}

fn views<const N: usize>(deriv: &DerivativeData<N>) -> RneaDerivatives<'_, N> {
    RneaDerivatives {
        dtau_dq: deriv.dtau_dq(),
        dtau_dv: deriv.dtau_dv(),
        mass_matrix: deriv.mass_matrix(),
    }
}

/// The length checks shared by the derivative algorithms (`qdd` stands for `τ` in ABA's).
pub(crate) fn check<const N: usize>(
    model: &Model<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    fext: Option<&[ForceVector]>,
) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    check_len("qd", qd, model.nv)?;
    check_len("qdd", qdd, model.nv)?;
    match fext {
        Some(fext) => check_fext(model, fext),
        None => Ok(()),
    }
}

/// `fext` has one force per body.
pub(crate) fn check_fext<const N: usize>(
    model: &Model<N>,
    fext: &[ForceVector],
) -> Result<(), Error> {
    if fext.len() == model.nbodies {
        Ok(())
    } else {
        Err(Error::Dimension {
            argument: "fext",
            expected: model.nbodies,
            got: fext.len(),
        })
    }
}

/// RNEA derivatives on public coordinates into `deriv` (lengths checked).
pub(crate) fn run<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    fext: Option<&[ForceVector]>,
) {
    deriv.n = model.nv;
    if model.has_mimic {
        run_mimic(model, data, deriv, q, qd, qdd, fext);
        return;
    }
    let d = &mut *deriv;
    forward::<false, N>(model, data, &mut d.ws, q, qd, qdd, fext);
    backward::<true, N>(
        model,
        data,
        &mut d.ws,
        &mut d.dtau_dq,
        &mut d.dtau_dv,
        &mut d.mass_matrix,
    );
    symmetrize(&mut d.mass_matrix, model.nv);
    model.add_armature_to_diagonal(&mut d.mass_matrix);
    model.add_armature_torque(&mut data.tau, qdd);
}

/// `Gᵀ X G` of the internal sweeps, for models with mimic joints (out of line).
#[cold]
#[inline(never)]
fn run_mimic<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    fext: Option<&[ForceVector]>,
) {
    let qd = super::mimic::expand(model, qd);
    let qdd_int = super::mimic::expand(model, qdd);
    let d = &mut *deriv;
    forward::<true, N>(model, data, &mut d.ws, q, &qd, &qdd_int, fext);
    // The internal matrices go to the ABA results' storage, unused here.
    backward::<true, N>(
        model,
        data,
        &mut d.ws,
        &mut d.ddq_dq,
        &mut d.ddq_dv,
        &mut d.minv,
    );
    let ne = model.nv_ext;
    symmetrize(&mut d.minv, ne);
    contract(model, &d.ddq_dq, &mut d.dtau_dq);
    contract(model, &d.ddq_dv, &mut d.dtau_dv);
    contract(model, &d.minv, &mut d.mass_matrix);
    super::mimic::contract_tau(model, data);
    model.add_armature_to_diagonal(&mut d.mass_matrix);
    model.add_armature_torque(&mut data.tau, qdd);
}

/// `X = Gᵀ X_int G` for a full internal matrix: each internal entry, scaled by both
/// coordinates' factors, added to the public entry of the coordinates they follow.
pub(crate) fn contract<const N: usize>(
    model: &Model<N>,
    internal: &[[f64; N]; N],
    out: &mut [[f64; N]; N],
) {
    let (n, ne) = (model.nv, model.nv_ext);
    for row in out[..n].iter_mut() {
        row[..n].fill(0.0);
    }
    for i in 0..ne {
        let (a, si) = (model.ext_v[i], model.ext_scale[i]);
        for j in 0..ne {
            let x = internal[i][j];
            if x != 0.0 {
                out[a][model.ext_v[j]] += si * model.ext_scale[j] * x;
            }
        }
    }
}

/// Copies the upper triangle of the leading `n × n` block onto the lower one.
pub(crate) fn symmetrize<const N: usize>(m: &mut [[f64; N]; N], n: usize) {
    for r in 1..n {
        for c in 0..r {
            m[r][c] = m[c][r];
        }
    }
}

/// The forward sweep: world poses, subspaces, velocities, accelerations, forces, and per
/// coordinate `dV`, `dA`, `dAv`; per body the inertia, `B̄`, the linear momentum.
#[inline]
#[allow(clippy::too_many_arguments)]
fn forward<const MIMIC: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    ws: &mut DerivativeWorkspace<N>,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    fext: Option<&[ForceVector]>,
) {
    let base = MotionVector::new(DVec3::ZERO, -model.gravity);
    for i in 0..model.nbodies {
        let x = world_pose::<MIMIC, N>(model, data, q, i);
        let p = model.parents[i];
        let (vp, ap) = if p == ROOT {
            (MotionVector::ZERO, base)
        } else {
            (data.v[p], data.a[p])
        };
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let mut vj = MotionVector::ZERO;
        let mut aj = MotionVector::ZERO;
        for k in sv..sv + nv {
            let s = model.act_subspace(i, k, &x);
            data.world_subspace[k] = s;
            vj += s * qd[k];
            aj += s * qdd[k];
        }
        let v = vp + vj;
        let a = ap + aj + v.cross_motion(&vj);
        for k in sv..sv + nv {
            let s = data.world_subspace[k];
            let dv = vp.cross_motion(&s);
            ws.dv[k] = dv;
            ws.da[k] = ap.cross_motion(&s) + vp.cross_motion(&dv);
            ws.dadv[k] = (vp + v).cross_motion(&s);
        }
        let inertia = model.world_inertia(i, &x);
        let h = inertia.mul_motion(&v);
        let mut f = inertia.mul_motion(&a) + v.cross_force(&h);
        if let Some(fext) = fext {
            f -= x.act_force(&fext[i]);
        }
        data.v[i] = v;
        data.a[i] = a;
        data.f[i] = f;
        data.composite[i] = inertia;
        ws.bn[i] = b_angular(&inertia, &v, &h);
        ws.hf[i] = h.force;
    }
}

/// `B̄ = [w]× Ī − Ī [w]× − [Ī w]× − 2 [h]× [v_lin]×`: the angular block of
/// `B x = v ×* I x − I (v × x) + x ×* I v` (whose linear block is `2 ω × p`); `mom = I v`.
#[inline]
pub(crate) fn b_angular(inertia: &RigidBodyInertia, v: &MotionVector, mom: &ForceVector) -> DMat3 {
    let (w, vl, hc, r) = (
        v.angular,
        v.linear,
        inertia.first_moment,
        &inertia.rotational,
    );
    // [w]× Ī (Ī symmetric, so Ī [w]× = −([w]× Ī)ᵀ).
    let wi = DMat3::from_cols(w.cross(r.x_axis), w.cross(r.y_axis), w.cross(r.z_axis));
    // Ī w = mom.moment − h × v_lin; −2 [h]×[v]× = −2 (v hᵀ − (h·v) 1).
    let iw = mom.moment - hc.cross(vl);
    let hv2 = 2.0 * hc.dot(vl);
    let m = wi + wi.transpose() - skew(iw);
    DMat3::from_cols(
        m.x_axis - vl * (2.0 * hc.x) + DVec3::new(hv2, 0.0, 0.0),
        m.y_axis - vl * (2.0 * hc.y) + DVec3::new(0.0, hv2, 0.0),
        m.z_axis - vl * (2.0 * hc.z) + DVec3::new(0.0, 0.0, hv2),
    )
}

/// `a b + c`, fused into one instruction where the target has one and the standard library's
/// `mul_add` can reach it (x86-64 built with FMA, e.g. `-C target-cpu=native`; every aarch64);
/// otherwise a multiplication and an addition (`core` has no `mul_add`, and the `libm` crate's
/// goes through a function pointer). The results differ from the unfused ones by rounding only.
#[inline(always)]
pub(crate) fn mul_add(a: f64, b: f64, c: f64) -> f64 {
    #[cfg(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64")))]
    {
        a.mul_add(b, c)
    }
    #[cfg(not(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64"))))]
    {
        a * b + c
    }
}

/// `B^c x` for the composite `(B̄, p)` and a motion whose angular part is `om`.
#[inline(always)]
fn b_apply(bn: &DMat3, p: DVec3, om: DVec3) -> ForceVector {
    ForceVector {
        moment: *bn * om,
        force: om.cross(p) * 2.0,
    }
}

/// The backward sweep: composites, and the entries of each body's coordinates against its own
/// and its ancestors' coordinates, both ways: its rows against the ancestors' columns from its
/// composites, the ancestors' rows against its columns from its `∂F`. (One walk up the tree per
/// body, so the bodies need only come parents first, not depth-first.) `dq`, `dv`, `m` are
/// indexed by internal coordinates; `m` gets its upper triangle only, and only when `WITH_M`.
/// Entries between branches are zeroed.
#[inline]
pub(crate) fn backward<const WITH_M: bool, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    ws: &mut DerivativeWorkspace<N>,
    dq: &mut [[f64; N]; N],
    dv: &mut [[f64; N]; N],
    m: &mut [[f64; N]; N],
) {
    let n = model.nv_ext;
    for r in 0..n {
        dq[r][..n].fill(0.0);
        dv[r][..n].fill(0.0);
        if WITH_M {
            m[r][..n].fill(0.0);
        }
    }
    for a in 0..n {
        let (da, dadv, dv, s) = (
            &ws.da[a],
            &ws.dadv[a],
            ws.dv[a].angular,
            &data.world_subspace[a],
        );
        ws.lower[a] = [
            [da.angular.x, dadv.angular.x],
            [da.angular.y, dadv.angular.y],
            [da.angular.z, dadv.angular.z],
            [da.linear.x, dadv.linear.x],
            [da.linear.y, dadv.linear.y],
            [da.linear.z, dadv.linear.z],
            [dv.x, s.angular.x],
            [dv.y, s.angular.y],
            [dv.z, s.angular.z],
        ];
        ws.subspace[a] = [
            s.angular.x,
            s.angular.y,
            s.angular.z,
            s.linear.x,
            s.linear.y,
            s.linear.z,
        ];
    }
    for i in (0..model.nbodies).rev() {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let own = sv..sv + nv;
        let ic = data.composite[i];
        let (bn, hf) = (ws.bn[i], ws.hf[i]);
        let f = data.f[i];
        for k in own.clone() {
            let s = data.world_subspace[k];
            ws.dfda[k] = ic.mul_motion(&s);
            ws.dfdq[k] = ic.mul_motion(&ws.da[k]) + b_apply(&bn, hf, ws.dv[k].angular);
            ws.dfdv[k] = ic.mul_motion(&ws.dadv[k]) + b_apply(&bn, hf, s.angular);
        }
        // The joint's own block (on its own body the turn of S_r cancels S_c ×* F).
        let mut z = [DVec3::ZERO; 6];
        for r in own.clone() {
            let s = data.world_subspace[r];
            data.tau[r] = s.dot(&f);
            for c in own.clone() {
                dq[r][c] = s.dot(&ws.dfdq[c]);
                dv[r][c] = s.dot(&ws.dfdv[c]);
                if WITH_M && c >= r {
                    m[r][c] = s.dot(&ws.dfda[c]);
                }
            }
            z[r - sv] = bn.transpose() * s.angular + hf.cross(s.linear) * 2.0;
        }
        for k in own.clone() {
            ws.dfdq[k] += data.world_subspace[k].cross_force(&f);
        }
        // Against each ancestor coordinate a: row r, column a from the composites,
        // S_r · (I^c X + B^c Y) = (I^c S_r) · X + z_r · ω(Y), two sums over the nine numbers of
        // `ws.lower[a]`; row a, column r from ∂F_r, three sums over the six numbers of `S_a`.
        // Packed so that each pair is a few vector multiply-adds.
        for r in own.clone() {
            let (w, zr) = (&ws.dfda[r], z[r - sv]);
            let lo = [
                w.moment.x, w.moment.y, w.moment.z, w.force.x, w.force.y, w.force.z, zr.x, zr.y,
                zr.z,
            ];
            let (fq, fv) = (&ws.dfdq[r], &ws.dfdv[r]);
            let up = [
                [fq.moment.x, fv.moment.x, w.moment.x, 0.0],
                [fq.moment.y, fv.moment.y, w.moment.y, 0.0],
                [fq.moment.z, fv.moment.z, w.moment.z, 0.0],
                [fq.force.x, fv.force.x, w.force.x, 0.0],
                [fq.force.y, fv.force.y, w.force.y, 0.0],
                [fq.force.z, fv.force.z, w.force.z, 0.0],
            ];
            let mut b = model.parents[i];
            while b != ROOT {
                let sb = model.idx_v[b];
                for a in sb..sb + model.joints[b].nv() {
                    let pa = &ws.lower[a];
                    let mut acc = [0.0; 2];
                    for e in 0..9 {
                        for l in 0..2 {
                            acc[l] = mul_add(lo[e], pa[e][l], acc[l]);
                        }
                    }
                    dq[r][a] = acc[0];
                    dv[r][a] = acc[1];
                    let sa = &ws.subspace[a];
                    let mut u = [0.0; 4];
                    for e in 0..6 {
                        for l in 0..4 {
                            u[l] = mul_add(sa[e], up[e][l], u[l]);
                        }
                    }
                    dq[a][r] = u[0];
                    dv[a][r] = u[1];
                    if WITH_M {
                        m[a][r] = u[2];
                    }
                }
                b = model.parents[b];
            }
        }
        let p = model.parents[i];
        if p != ROOT {
            data.composite[p] += ic;
            ws.bn[p] += bn;
            ws.hf[p] += hf;
            data.f[p] += f;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pendulum of `rnea`'s test: `τ = m l² q̈ + m g l sin q`, so `∂τ/∂q = m g l cos q`,
    /// `∂τ/∂q̇ = 0`, `M = m l²`.
    #[test]
    fn pendulum_matches_the_closed_form() {
        let (m, l, g) = (2.0, 0.5, 9.81);
        let model = crate::algo::rnea::tests::pendulum(m, l, g);
        let mut data = Data::new();
        let mut deriv = DerivativeData::new();
        let (q, qd, qdd) = (0.3, 0.7, -1.1);
        let r = rnea_derivatives(&model, &mut data, &mut deriv, &[q], &[qd], &[qdd]).unwrap();
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12 * (1.0 + b.abs());
        assert!(close(r.dtau_dq.get(0, 0), m * g * l * libm::cos(q)));
        assert!(close(r.dtau_dv.get(0, 0), 0.0));
        assert!(close(r.mass_matrix.get(0, 0), m * l * l));
        assert!(close(
            data.tau[0],
            m * l * l * qdd + m * g * l * libm::sin(q)
        ));
    }
}
