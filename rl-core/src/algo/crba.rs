//! The joint-space mass matrix `M(q)` by the composite rigid-body algorithm (CRBA).
//!
//! Featherstone, *Rigid Body Dynamics Algorithms*, §6.2, in body coordinates (Pinocchio's
//! default convention). The forward pass needs only each body's pose in its parent, no world
//! poses. Going back, each body's composite inertia `I^c` is complete when its turn comes; each
//! of its DOFs gives a force `F = I^c S_k`, which walks up the ancestors, one transform per
//! edge, and meets each ancestor DOF `l` as `M[l][k] = S_lᵀ F` in that body's own coordinates.
//! There the common subspaces are an axis or unit vectors: a revolute `F` is `(Ī a, a × h)` and
//! its entry `a · n`; a floating base reads its six entries straight off `F` and its own block
//! off `I^c`. The composite then moves to the parent. (The world-frame variant, as in
//! Pinocchio's `WORLD` convention, needs a world pose and a world inertia per body and six
//! scalar products per descendant column on a floating base: 2–18 % slower here.)
//!
//! `q`: `nq`; result: the symmetric `dof × dof` matrix in [`Data::mass_matrix`] (upper
//! triangle stored). O(n·depth). Does not allocate.
//!
//! With mimic joints the sweep fills the internal matrix (in `Data`'s factorisation scratch)
//! and `M = Gᵀ M_int G` is gathered from it ([`crate::model::mimic`]): the leader's row and
//! column collect the mimic joint's, as in Pinocchio. That last step is O(n_int²).
//!
//! The model's armature ([`Model::armature`]) is added to the diagonal.

use crate::error::{Error, check_len};
use crate::joint::Joint;
use crate::model::{Data, Model, ROOT};
use crate::spatial::{ForceVector, RigidBodyInertia};

use super::forward_position::local_pose;

/// Computes `M(q)` into `data` (read it with [`Data::mass_matrix`]).
pub fn crba<const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) -> Result<(), Error> {
    check_len("q", q, model.nq)?;
    if model.has_mimic {
        run_mimic(model, data, q);
    } else {
        run::<false, N>(model, data, q);
    }
    model.add_armature_to_diagonal(&mut data.mass_matrix);
    Ok(())
}

/// `Gᵀ M_int G`, for models with mimic joints (out of line: the common path stays as it was).
#[cold]
#[inline(never)]
fn run_mimic<const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) {
    run::<true, N>(model, data, q);
    super::mimic::contract_mass_matrix(model, data);
}

/// The sweeps over internal coordinates, into `data.mass_matrix` or, with mimic joints, into
/// `data.factor`.
#[inline]
fn run<const MIMIC: bool, const N: usize>(model: &Model<N>, data: &mut Data<N>, q: &[f64]) {
    let n = model.nv_ext;
    // Only the upper triangle is kept. Entries between DOFs on different branches are zero
    // and never written below.
    let target = if MIMIC {
        &mut data.factor
    } else {
        &mut data.mass_matrix
    };
    for (r, row) in target[..n].iter_mut().enumerate() {
        row[r..n].fill(0.0);
    }
    for i in 0..model.nbodies {
        local_pose::<MIMIC, N>(model, data, q, i);
        data.composite[i] = model.inertias[i];
    }
    let target = if MIMIC {
        &mut data.factor
    } else {
        &mut data.mass_matrix
    };
    for i in (0..model.nbodies).rev() {
        let ic = &data.composite[i];
        let sv = model.idx_v[i];
        let six_dof = matches!(model.joints[i], Joint::SixDof(_));
        if six_dof {
            six_dof_block(ic, sv, target);
        }
        let p = model.parents[i];
        for k in sv..sv + model.joints[i].nv() {
            if six_dof && p == ROOT {
                break;
            }
            let mut f = match &model.joints[i] {
                // S = (axis, 0): F = (Ī axis, axis × h).
                Joint::Revolute(j) => ForceVector {
                    moment: ic.rotational * j.axis,
                    force: j.axis.cross(ic.first_moment),
                },
                _ => ic.mul_motion(&model.subspace[k]),
            };
            if !six_dof {
                // This joint's own block (upper triangle: rows sv..=k).
                write_dots(model, i, &f, k, target, sv..=k);
            }
            let mut b = i;
            let mut a = p;
            while a != ROOT {
                f = data.parent_pose[b].act_force(&f);
                let sa = model.idx_v[a];
                write_dots(model, a, &f, k, target, sa..sa + 6);
                b = a;
                a = model.parents[b];
            }
        }
        if p != ROOT {
            let moved = ic.transform_to_parent(&data.parent_pose[i]);
            data.composite[p] += moved;
        }
    }
}

/// `M[l][k] = S_lᵀ f` for the DOFs `l` of body `i`'s joint that lie in `rows`, with `f` in
/// body `i`'s coordinates.
#[inline(always)]
fn write_dots<const N: usize>(
    model: &Model<N>,
    i: usize,
    f: &ForceVector,
    k: usize,
    m: &mut [[f64; N]; N],
    rows: impl Iterator<Item = usize>,
) {
    let sv = model.idx_v[i];
    match &model.joints[i] {
        Joint::Revolute(j) => m[sv][k] = j.axis.dot(f.moment),
        Joint::Prismatic(j) => m[sv][k] = j.axis.dot(f.force),
        // Translations along x, y, z, then rotations about them.
        Joint::SixDof(_) => {
            let v = [
                f.force.x, f.force.y, f.force.z, f.moment.x, f.moment.y, f.moment.z,
            ];
            for (a, x) in v.into_iter().enumerate() {
                m[sv + a][k] = x;
            }
        }
        j => {
            for l in rows.take(j.nv()) {
                m[l][k] = model.subspace[l].dot(f);
            }
        }
    }
}

/// The upper triangle of a six-DOF joint's own block, `Sᵀ I^c S` with `S` the identity in
/// the order `[linear xyz; angular xyz]`: `[[m 1, −[h]×], [[h]×, Ī]]`.
fn six_dof_block<const N: usize>(ic: &RigidBodyInertia, sv: usize, m: &mut [[f64; N]; N]) {
    let (h, r) = (ic.first_moment, &ic.rotational);
    let rows = [
        [ic.mass, 0.0, 0.0, 0.0, h.z, -h.y],
        [0.0, ic.mass, 0.0, -h.z, 0.0, h.x],
        [0.0, 0.0, ic.mass, h.y, -h.x, 0.0],
        [0.0, 0.0, 0.0, r.x_axis.x, r.y_axis.x, r.z_axis.x],
        [0.0, 0.0, 0.0, 0.0, r.y_axis.y, r.z_axis.y],
        [0.0, 0.0, 0.0, 0.0, 0.0, r.z_axis.z],
    ];
    for (a, row) in rows.iter().enumerate() {
        m[sv + a][sv + a..sv + 6].copy_from_slice(&row[a..]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::joint::{Cylindrical, Helical, Planar, Prismatic, Revolute, SixDof, Spherical};
    use crate::model::ModelBuilder;
    use crate::spatial::PlueckerTransform;
    use glam::{DMat3, DQuat, DVec3};

    /// On a forest with every joint type, `M` column by column from RNEA: `M e_j` =
    /// `RNEA(q, 0, e_j) − G(q)`. The matrix starts as NaN: every entry must be written, the
    /// zeros between branches and between the two trees too.
    #[test]
    fn columns_match_rnea_on_a_forest_with_every_joint_type() {
        let joints = [
            Joint::SixDof(SixDof),
            Joint::Revolute(Revolute::new(DVec3::new(0.3, -1.0, 0.2))),
            Joint::Prismatic(Prismatic::new(DVec3::X)),
            Joint::Spherical(Spherical),
            Joint::Helical(Helical::new(DVec3::Y, 0.05)),
            Joint::Cylindrical(Cylindrical::new(DVec3::Z)),
            Joint::Planar(Planar),
            Joint::Revolute(Revolute::new(DVec3::Z)),
            // A second tree, floating, after the first one's DOFs.
            Joint::SixDof(SixDof),
            Joint::Revolute(Revolute::new(DVec3::X)),
        ];
        let parents = [ROOT, 0, 1, 0, 3, 1, 5, 3, ROOT, 8];
        let mut b = ModelBuilder::<32>::new();
        for (i, (j, p)) in joints.into_iter().zip(parents).enumerate() {
            let f = i as f64;
            let placement = PlueckerTransform::from_quat_translation(
                DQuat::from_scaled_axis(DVec3::new(0.2 * f, -0.1, 0.3)),
                DVec3::new(0.1, 0.05 * f, -0.2),
            );
            let inertia = RigidBodyInertia::from_com(
                1.0 + f,
                DVec3::new(0.02 * f, -0.03, 0.1),
                DMat3::from_diagonal(DVec3::new(0.1, 0.2 + 0.01 * f, 0.15)),
            );
            let name = ["b0", "b1", "b2", "b3", "b4", "b5", "b6", "b7", "b8", "b9"][i];
            b.add_body(p, name, j, placement, name, inertia).unwrap();
        }
        let model = b.build();
        let mut q = [0.0; 32];
        let mut seed = 3u64;
        let mut u = || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        model.random_configuration(&mut q[..model.nq()], &mut u);
        let q = &q[..model.nq()];
        let n = model.dof();
        let mut data = Data::<32>::new();
        data.mass_matrix = [[f64::NAN; 32]; 32];
        crba(&model, &mut data, q).unwrap();
        let mut scratch = Data::<32>::new();
        let g = crate::algo::gravity(&model, &mut scratch, q)
            .unwrap()
            .to_vec();
        let zero = [0.0; 32];
        for c in 0..n {
            let mut e = [0.0; 32];
            e[c] = 1.0;
            let tau = crate::algo::rnea(&model, &mut scratch, q, &zero[..n], &e[..n]).unwrap();
            for r in 0..n {
                let (m, want) = (data.mass_matrix(r, c), tau[r] - g[r]);
                assert!(
                    (m - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "M[{r}][{c}]: {m} vs {want}"
                );
            }
        }
    }
}
