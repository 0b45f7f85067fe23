//! The maps between the public coordinates and the sweeps' internal ones for models with mimic
//! joints ([`crate::model::mimic`]): `x_int = G x` on the way in, `Gᵀ` on the way out, and
//! `M = Gᵀ M_int G`, `J = J_int G`. Only called when [`Model::has_mimic`]; each map is one
//! pass over the internal coordinates (the mass matrix: over its upper triangle). Does not
//! allocate (stack arrays of `N`).

use glam::DVec3;

use crate::model::{Data, Model, ROOT};

use super::Jacobian;

/// `G x`: a public velocity-sized vector in internal coordinates (`nv_ext` entries used).
#[inline]
pub(crate) fn expand<const N: usize>(model: &Model<N>, x: &[f64]) -> [f64; N] {
    let mut out = [0.0; N];
    for (k, o) in out.iter_mut().enumerate().take(model.nv_ext) {
        *o = model.ext_scale[k] * x[model.ext_v[k]];
    }
    out
}

/// `τ = Gᵀ τ_int`: `data.tau[..nv_ext]` (internal) becomes `data.tau[..nv]` (public).
#[inline]
pub(crate) fn contract_tau<const N: usize>(model: &Model<N>, data: &mut Data<N>) {
    let mut t = [0.0; N];
    for k in 0..model.nv_ext {
        t[model.ext_v[k]] += model.ext_scale[k] * data.tau[k];
    }
    data.tau[..model.nv].copy_from_slice(&t[..model.nv]);
}

/// `M = Gᵀ M_int G` from the internal upper triangle in `data.factor` into the public upper
/// triangle of `data.mass_matrix`: `M[a][b] = Σ s_i s_j M_int[i][j]` over the internal
/// coordinates `i` of `a` and `j` of `b`.
pub(crate) fn contract_mass_matrix<const N: usize>(model: &Model<N>, data: &mut Data<N>) {
    let (n, ne) = (model.nv, model.nv_ext);
    let m = &mut data.mass_matrix;
    for (r, row) in m[..n].iter_mut().enumerate() {
        row[r..n].fill(0.0);
    }
    for i in 0..ne {
        let (a, si) = (model.ext_v[i], model.ext_scale[i]);
        for j in i..ne {
            let x = data.factor[i][j];
            if x == 0.0 {
                continue;
            }
            let (b, sj) = (model.ext_v[j], model.ext_scale[j]);
            let v = si * sj * x;
            // (i, j) and (j, i) both land in one stored cell; on the diagonal in the same one.
            if a == b && i != j {
                m[a][a] += 2.0 * v;
            } else {
                m[a.min(b)][a.max(b)] += v;
            }
        }
    }
}

/// Tool `tool`'s world Jacobian (at world point `p`) from the world poses of its ancestors:
/// each internal column, scaled, added to the public column it follows.
pub(crate) fn fill_jacobian<const N: usize>(
    model: &Model<N>,
    data: &Data<N>,
    body: usize,
    p: DVec3,
    out: &mut Jacobian<N>,
) {
    for row in out.iter_mut() {
        row[..model.nv].fill(0.0);
    }
    let mut b = body;
    while b != ROOT {
        let sv = model.idx_v[b];
        let x = &data.world_pose[b];
        for k in sv..sv + model.joints[b].nv() {
            let s = model.act_subspace(b, k, x);
            let (c, f) = (model.ext_v[k], model.ext_scale[k]);
            let lin = s.linear + s.angular.cross(p);
            for (row, v) in
                out.iter_mut()
                    .zip([lin.x, lin.y, lin.z, s.angular.x, s.angular.y, s.angular.z])
            {
                row[c] += f * v;
            }
        }
        b = model.parents[b];
    }
}
