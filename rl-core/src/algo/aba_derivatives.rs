//! Analytical derivatives of forward dynamics: `∂q̈/∂q`, `∂q̈/∂q̇` and `∂q̈/∂τ = M⁻¹` of
//! `q̈ = ABA(q, q̇, τ)`.
//!
//! Carpentier and Mansard, "Analytical Derivatives of Rigid Body Dynamics Algorithms", RSS
//! 2018, §IV (Pinocchio's `computeABADerivatives`): differentiating `RNEA(q, q̇, ABA(q, q̇, τ)) =
//! τ` gives
//!
//! ```text
//! ∂q̈/∂q = −M⁻¹ ∂τ/∂q,   ∂q̈/∂q̇ = −M⁻¹ ∂τ/∂q̇,   ∂q̈/∂τ = M⁻¹,
//! ```
//!
//! with the RNEA derivatives ([`super::rnea_derivatives`], whose docs give the recursion and the
//! tangent-space convention) taken at the `q̈` ABA returns. One fused run in world coordinates:
//! a forward sweep for poses, velocities and everything velocity-dependent; a backward sweep
//! for ABA's articulated inertias and the backward half of `M⁻¹` (Carpentier, "Analytical
//! inverse of the joint space inertia matrix", 2018: each body's articulated bias force per
//! column of its subtree, one force per column as world coordinates need no transform between
//! bodies); a forward sweep for `q̈`, the accelerations and the forward half of `M⁻¹`,
//! `M⁻¹_{r,c≥r} −= D⁻¹ Uᵀ S_k M⁻¹_{k,c}` summed over the ancestor coordinates `k` (the
//! parent's acceleration per column, `Σ S_k M⁻¹_{k,c}`, without storing it); the RNEA
//! derivatives' backward sweep; and the two products, which skip the zeros of `∂τ` (column
//! `j` is nonzero only on `j`'s ancestors and subtree): `O(n · nnz)`.
//!
//! `q`: `nq`; `qd`, `tau`: `dof`; results `dof × dof` in [`DerivativeData::ddq_dq`],
//! [`DerivativeData::ddq_dv`], [`DerivativeData::minv`] (both triangles), `q̈` in
//! [`DerivativeData::qdd`], and the RNEA derivatives at `q̈` in [`DerivativeData::dtau_dq`],
//! [`DerivativeData::dtau_dv`]. O(n²) for `M⁻¹` and the products. Does not allocate.
//!
//! With mimic joints, which ABA cannot recurse over (see [`super::aba`]), `q̈` comes through the
//! mass matrix, the RNEA derivatives are the mimic ones (`Gᵀ X G`) and `M⁻¹` is solved column
//! by column from the sparse `LᵀDL` factorisation; the products are dense, O(n³).
//!
//! Errors: [`Error::NotPositiveDefinite`] as [`super::aba`].

use crate::error::Error;
use crate::model::{Data, DerivativeData, DerivativeWorkspace, MatrixView, Model, ROOT};
use crate::spatial::{ArticulatedBodyInertia, ForceVector, MotionVector};

use super::forward_position::world_pose;
use super::rnea_derivatives::{b_angular, backward, check, mul_add, symmetrize};

/// The results of [`aba_derivatives`]: views into the [`DerivativeData`].
#[derive(Clone, Copy, Debug)]
pub struct AbaDerivatives<'a, const N: usize> {
    /// `∂q̈/∂q` (tangent space), `dof × dof`.
    pub ddq_dq: MatrixView<'a, N>,
    /// `∂q̈/∂q̇`, `dof × dof`.
    pub ddq_dv: MatrixView<'a, N>,
    /// `∂q̈/∂τ = M(q)⁻¹`, `dof × dof`, symmetric (both triangles written).
    pub minv: MatrixView<'a, N>,
    /// `q̈ = ABA(q, q̇, τ)`.
    pub qdd: &'a [f64],
}

/// `∂q̈/∂q`, `∂q̈/∂q̇`, `M⁻¹` and `q̈` of `q̈ = ABA(q, q̇, τ)` with the model's gravity.
pub fn aba_derivatives<'d, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &'d mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
) -> Result<AbaDerivatives<'d, N>, Error> {
    check(model, q, qd, tau, None).map_err(rename_tau)?;
    run(model, data, deriv, q, qd, tau, None)?;
    Ok(views(deriv))
}

/// [`aba_derivatives`] with external forces: `fext[i]` acts on body `i`, in body `i`'s
/// coordinates (`body_count()` elements), as in [`super::aba_with_external_forces`].
pub fn aba_derivatives_with_external_forces<'d, const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &'d mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    fext: &[ForceVector],
) -> Result<AbaDerivatives<'d, N>, Error> {
    check(model, q, qd, tau, Some(fext)).map_err(rename_tau)?;
    run(model, data, deriv, q, qd, tau, Some(fext))?;
    Ok(views(deriv))
}

fn rename_tau(e: Error) -> Error {
    match e {
        Error::Dimension {
            argument: "qdd",
            expected,
            got,
        } => Error::Dimension {
            argument: "tau",
            expected,
            got,
        },
        e => e,
    }
}

fn views<const N: usize>(deriv: &DerivativeData<N>) -> AbaDerivatives<'_, N> {
    AbaDerivatives {
        ddq_dq: deriv.ddq_dq(),
        ddq_dv: deriv.ddq_dv(),
        minv: deriv.minv(),
        qdd: deriv.qdd(),
    }
}

fn run<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    fext: Option<&[ForceVector]>,
) -> Result<(), Error> {
    deriv.n = model.nv;
    if model.has_mimic {
        return run_mimic(model, data, deriv, q, qd, tau, fext);
    }
    let n = model.nv;
    let d = &mut *deriv;
    velocities(model, data, &mut d.ws, q, qd, fext);
    super::aba::articulated_inertias(model, data, tau)?;
    minv_backward(model, data, &mut d.minv);
    accelerations(model, data, &mut d.ws, &mut d.minv, &mut d.qdd);
    backward::<false, N>(
        model,
        data,
        &mut d.ws,
        &mut d.dtau_dq,
        &mut d.dtau_dv,
        &mut d.mass_matrix,
    );
    symmetrize(&mut d.minv, n);
    multiply_minv(
        model,
        &d.minv,
        &d.dtau_dq,
        &d.dtau_dv,
        &mut d.ddq_dq,
        &mut d.ddq_dv,
    );
    Ok(())
}

/// Pass 1, root to leaves: world poses and subspaces, velocities, ABA's bias accelerations,
/// world inertias (in `data.composite`), velocity-dependent forces (ABA's bias in `data.f`, kept
/// in `ws.bias`), and the RNEA derivatives' velocity terms.
#[inline]
fn velocities<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    ws: &mut DerivativeWorkspace<N>,
    q: &[f64],
    qd: &[f64],
    fext: Option<&[ForceVector]>,
) {
    for i in 0..model.nbodies {
        let x = world_pose::<false, N>(model, data, q, i);
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let p = model.parents[i];
        let vp = if p == ROOT {
            MotionVector::ZERO
        } else {
            data.v[p]
        };
        let mut vj = MotionVector::ZERO;
        for k in sv..sv + nv {
            let s = model.act_subspace(i, k, &x);
            data.world_subspace[k] = s;
            vj += s * qd[k];
        }
        let v = vp + vj;
        data.v[i] = v;
        data.c[i] = v.cross_motion(&vj);
        for k in sv..sv + nv {
            let s = data.world_subspace[k];
            ws.dv[k] = vp.cross_motion(&s);
            ws.dadv[k] = (vp + v).cross_motion(&s);
        }
        let inertia = model.world_inertia(i, &x);
        data.composite[i] = inertia;
        data.articulated[i] = ArticulatedBodyInertia::from(inertia);
        let h = inertia.mul_motion(&v);
        let mut bias = v.cross_force(&h);
        if let Some(fext) = fext {
            bias -= x.act_force(&fext[i]);
        }
        data.f[i] = bias;
        ws.bias[i] = bias;
        ws.bn[i] = b_angular(&inertia, &v, &h);
        ws.hf[i] = h.force;
    }
}

/// The backward half of `M⁻¹` (its upper triangle; the rest zeroed): for each column `c`, ABA's
/// backward sweep for `τ = e_c` at rest, which only meets `c`'s body and its ancestors: the
/// own block `D⁻¹`, then up the tree `M⁻¹_{r,c} = −(D⁻¹ Sᵀ F)_r` with `F` the articulated
/// bias force the column leaves on each ancestor, `F ← F + U M⁻¹_{·,c}`. World coordinates:
/// `F` passes from body to parent unchanged.
#[inline]
fn minv_backward<const N: usize>(model: &Model<N>, data: &Data<N>, minv: &mut [[f64; N]; N]) {
    let n = model.nv;
    for r in 0..n {
        minv[r][r..n].fill(0.0);
    }
    for i in 0..model.nbodies {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let d_inv = &data.d_inv[i];
        for r in 0..nv {
            minv[sv + r][sv..sv + nv].copy_from_slice(&d_inv[r][..nv]);
        }
        for c in sv..sv + nv {
            let mut f = ForceVector::ZERO;
            for r in 0..nv {
                f += data.u[sv + r] * d_inv[r][c - sv];
            }
            let mut b = model.parents[i];
            while b != ROOT {
                let sb = model.idx_v[b];
                let nb = model.joints[b].nv();
                let d_inv = &data.d_inv[b];
                let mut t = [0.0; 6];
                for (s, t) in t.iter_mut().enumerate().take(nb) {
                    *t = data.world_subspace[sb + s].dot(&f);
                }
                for r in 0..nb {
                    let mut x = 0.0;
                    for s in 0..nb {
                        x += d_inv[r][s] * t[s];
                    }
                    minv[sb + r][c] = -x;
                    f -= data.u[sb + r] * x;
                }
                b = model.parents[b];
            }
        }
    }
}

/// Pass 3, root to leaves: `q̈` and the world accelerations, the forward half of `M⁻¹`, the
/// RNEA derivatives' acceleration terms and the bodies' forces `f = I a + bias`.
#[inline]
fn accelerations<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    ws: &mut DerivativeWorkspace<N>,
    minv: &mut [[f64; N]; N],
    qdd: &mut [f64; N],
) {
    let n = model.nv;
    let base = MotionVector::new(glam::DVec3::ZERO, -model.gravity);
    let mut unused = [0.0; N];
    for i in 0..model.nbodies {
        let sv = model.idx_v[i];
        let nv = model.joints[i].nv();
        let p = model.parents[i];
        let (vp, ap) = if p == ROOT {
            (MotionVector::ZERO, base)
        } else {
            (data.v[p], data.a[p])
        };
        let d_inv = data.d_inv[i];
        let (x, a) = super::aba::joint_accelerations(model, data, i, ap + data.c[i]);
        qdd[sv..sv + nv].copy_from_slice(&x[..nv]);
        data.a[i] = a;
        // M⁻¹_{r, c ≥ sv} −= Σ_k (D⁻¹ Uᵀ S_k)_r M⁻¹_{k, c ≥ sv} over the ancestor coordinates k.
        let mut terms = [(0usize, 0.0, 0.0); N];
        for r in 0..nv {
            let mut len = 0;
            let mut b = p;
            while b != ROOT {
                let sb = model.idx_v[b];
                for k in sb..sb + model.joints[b].nv() {
                    let s = data.world_subspace[k];
                    let mut coef = 0.0;
                    for l in 0..nv {
                        coef += d_inv[r][l] * s.dot(&data.u[sv + l]);
                    }
                    terms[len] = (k, -coef, 0.0);
                    len += 1;
                }
                b = model.parents[b];
            }
            let (head, tail) = minv.split_at_mut(sv);
            let row = &mut tail[r];
            combine_rows::<false, N>(head, &terms[..len], sv, n, row, &mut unused);
        }
        for k in sv..sv + nv {
            let s = data.world_subspace[k];
            ws.da[k] = ap.cross_motion(&s) + vp.cross_motion(&ws.dv[k]);
        }
        data.f[i] = data.composite[i].mul_motion(&a) + ws.bias[i];
    }
}

/// `∂q̈/∂q = −M⁻¹ ∂τ/∂q` and `∂q̈/∂q̇ = −M⁻¹ ∂τ/∂q̇` over the nonzeros of `∂τ` only: column
/// `j` is nonzero on the coordinates of `j`'s ancestors, its own joint and its subtree. Column `j`
/// of the result is `Σ_k ∂τ_kj` times row `k` of the symmetric `M⁻¹`, accumulated in row `j`
/// ([`combine_rows`]) and transposed at the end. With the bodies in depth-first order (as the
/// loaders number them) a subtree's coordinates are one range; otherwise each pair of related
/// coordinates is visited from the lower body's walk up the tree.
#[inline]
fn multiply_minv<const N: usize>(
    model: &Model<N>,
    minv: &[[f64; N]; N],
    dq: &[[f64; N]; N],
    dv: &[[f64; N]; N],
    out_q: &mut [[f64; N]; N],
    out_v: &mut [[f64; N]; N],
) {
    let n = model.nv;
    let mut end = [0usize; N];
    let depth_first = subtree_ends(model, &mut end);
    if depth_first {
        let mut terms = [(0usize, 0.0, 0.0); N];
        for j in 0..n {
            let body = model.dof_body[j];
            let mut len = 0;
            let mut push = |k: usize| {
                let (x, y) = (dq[k][j], dv[k][j]);
                if x != 0.0 || y != 0.0 {
                    terms[len] = (k, x, y);
                    len += 1;
                }
            };
            let mut a = model.parents[body];
            while a != ROOT {
                let sa = model.idx_v[a];
                for k in sa..sa + model.joints[a].nv() {
                    push(k);
                }
                a = model.parents[a];
            }
            for k in model.idx_v[body]..end[body] {
                push(k);
            }
            combine_rows::<true, N>(minv, &terms[..len], 0, n, &mut out_q[j], &mut out_v[j]);
        }
    } else {
        for j in 0..n {
            out_q[j][..n].fill(0.0);
            out_v[j][..n].fill(0.0);
        }
        let mut add = |k: usize, j: usize| {
            let (x, y) = (dq[k][j], dv[k][j]);
            let oq = &mut out_q[j][..n];
            let ov = &mut out_v[j][..n];
            for ((a, b), m) in oq.iter_mut().zip(ov.iter_mut()).zip(&minv[k][..n]) {
                *a += x * m;
                *b += y * m;
            }
        };
        for i in 0..model.nbodies {
            let sv = model.idx_v[i];
            let own = sv..sv + model.joints[i].nv();
            for x in own.clone() {
                for y in own.clone() {
                    add(x, y);
                }
            }
            let mut b = model.parents[i];
            while b != ROOT {
                let sb = model.idx_v[b];
                for y in sb..sb + model.joints[b].nv() {
                    for x in own.clone() {
                        add(x, y);
                        add(y, x);
                    }
                }
                b = model.parents[b];
            }
        }
    }
    transpose_negate(out_q, n);
    transpose_negate(out_v, n);
}

/// One past the last coordinate of each body's subtree into `end`, assuming depth-first order;
/// returns whether the bodies are in depth-first order (each body's parent on the path from the
/// body before it to the root), where that assumption holds.
fn subtree_ends<const N: usize>(model: &Model<N>, end: &mut [usize; N]) -> bool {
    for i in 0..model.nbodies {
        end[i] = model.idx_v[i] + model.joints[i].nv();
        if i > 0 {
            let p = model.parents[i];
            let mut b = i - 1;
            while b != ROOT && b != p {
                b = model.parents[b];
            }
            if b != p {
                return false;
            }
        }
    }
    for i in (1..model.nbodies).rev() {
        let p = model.parents[i];
        if p != ROOT && end[p] < end[i] {
            end[p] = end[i];
        }
    }
    true
}

/// Chunk width of [`combine_rows`]: sixteen doubles, two AVX-512 registers or four AVX ones (8
/// measured 4 % slower on talos: the per-term overhead is shared by fewer multiply-adds).
const W: usize = 16;

/// `q[c] (+)= Σ_t x_t rows[k_t][c]` (and, when `TWO`, `v[c] (+)= Σ_t y_t rows[k_t][c]`) for
/// `c` in `from..n`, over the terms `(k_t, x_t, y_t)`: `TWO` sets the outputs, otherwise `q`
/// is updated in place. Chunks of [`W`] columns are accumulated in registers over all terms
/// before one store, so each row element is loaded once per chunk and each output element
/// stored once.
#[inline(always)]
fn combine_rows<const TWO: bool, const N: usize>(
    rows: &[[f64; N]],
    terms: &[(usize, f64, f64)],
    from: usize,
    n: usize,
    q: &mut [f64; N],
    v: &mut [f64; N],
) {
    let mut c0 = from;
    while c0 < n {
        let e = (n - c0).min(W);
        match (q[c0..].first_chunk_mut::<W>(), c0 + W <= N) {
            (Some(qc), true) => {
                let mut aq = if TWO { [0.0; W] } else { *qc };
                let mut av = [0.0; W];
                for &(k, x, y) in terms {
                    if let Some(m) = rows[k][c0..].first_chunk::<W>() {
                        for l in 0..W {
                            aq[l] = mul_add(x, m[l], aq[l]);
                            if TWO {
                                av[l] = mul_add(y, m[l], av[l]);
                            }
                        }
                    }
                }
                qc[..e].copy_from_slice(&aq[..e]);
                if TWO {
                    v[c0..c0 + e].copy_from_slice(&av[..e]);
                }
            }
            _ => {
                for c in c0..c0 + e {
                    let (mut aq, mut av) = (if TWO { 0.0 } else { q[c] }, 0.0);
                    for &(k, x, y) in terms {
                        aq += x * rows[k][c];
                        av += y * rows[k][c];
                    }
                    q[c] = aq;
                    if TWO {
                        v[c] = av;
                    }
                }
            }
        }
        c0 += W;
    }
}

/// `m ← −mᵀ` on the leading `n × n` block.
fn transpose_negate<const N: usize>(m: &mut [[f64; N]; N], n: usize) {
    for r in 0..n {
        m[r][r] = -m[r][r];
        for c in r + 1..n {
            let x = m[r][c];
            m[r][c] = -m[c][r];
            m[c][r] = -x;
        }
    }
}

/// Through the mass matrix, for models with mimic joints (out of line).
#[cold]
#[inline(never)]
fn run_mimic<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    deriv: &mut DerivativeData<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    fext: Option<&[ForceVector]>,
) -> Result<(), Error> {
    let n = model.nv;
    match fext {
        Some(fext) => super::aba_with_external_forces(model, data, q, qd, tau, fext)?,
        None => super::aba(model, data, q, qd, tau)?,
    };
    let mut qdd = [0.0; N];
    qdd[..n].copy_from_slice(&data.qdd[..n]);
    super::rnea_derivatives::run(model, data, deriv, q, qd, &qdd[..n], fext);
    deriv.qdd = qdd;
    // M⁻¹ column by column from the sparse factorisation of M.
    for r in 0..n {
        data.mass_matrix[r][r..n].copy_from_slice(&deriv.mass_matrix[r][r..n]);
    }
    super::factor_mass_matrix(model, data)?;
    for c in 0..n {
        let mut e = [0.0; N];
        e[c] = 1.0;
        super::solve_mass_matrix(model, data, &mut e[..n])?;
        deriv.minv[c][..n].copy_from_slice(&e[..n]);
    }
    let d = &mut *deriv;
    for r in 0..n {
        for c in 0..n {
            let (mut x, mut y) = (0.0, 0.0);
            for k in 0..n {
                x += d.minv[r][k] * d.dtau_dq[k][c];
                y += d.minv[r][k] * d.dtau_dv[k][c];
            }
            d.ddq_dq[r][c] = -x;
            d.ddq_dv[r][c] = -y;
        }
    }
    Ok(())
}
