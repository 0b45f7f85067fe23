//! The analytical derivatives of RNEA, ABA and the static torque against central finite
//! differences (in Pinocchio's tangent-space convention: `q` moved along
//! [`Model::integrate`]) on trees with every joint type and with mimic joints in every relation
//! to their leaders, with and without external forces; and `M`, `M⁻¹`, `τ`, `q̈` against CRBA,
//! the sparse solve, RNEA and ABA.
#![allow(clippy::needless_range_loop)]

mod support;

use rl_core::algo;
use rl_core::model::DerivativeData;
use rl_core::spatial::ForceVector;
use rl_core::{Data, Model};
use support::{Rng, assert_close, every_joint_type, mimic_tree, random_chain, random_state};

/// The brief's tolerance for finite differences (relative to `max(1, |x|)`).
const FD_TOL: f64 = 1e-6;
const TOL: f64 = 1e-9;
const H: f64 = 1e-6;

/// Columns of `∂f/∂q` by central differences along `q ⊕ ±h e_k`.
fn fd_q<const N: usize>(
    model: &Model<N>,
    q: &[f64],
    mut f: impl FnMut(&[f64]) -> Vec<f64>,
) -> Vec<Vec<f64>> {
    let n = model.dof();
    let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
    (0..n)
        .map(|k| {
            let mut e = vec![0.0; n];
            e[k] = 1.0;
            model.integrate(q, &e, H, &mut qp);
            model.integrate(q, &e, -H, &mut qm);
            let (a, b) = (f(&qp), f(&qm));
            a.iter().zip(&b).map(|(x, y)| (x - y) / (2.0 * H)).collect()
        })
        .collect()
}

/// Columns of `∂f/∂x` by central differences on a plain vector `x`.
fn fd_vec(x: &[f64], mut f: impl FnMut(&[f64]) -> Vec<f64>) -> Vec<Vec<f64>> {
    (0..x.len())
        .map(|k| {
            let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
            xp[k] += H;
            xm[k] -= H;
            let (a, b) = (f(&xp), f(&xm));
            a.iter().zip(&b).map(|(x, y)| (x - y) / (2.0 * H)).collect()
        })
        .collect()
}

/// Column `c` of a view.
fn column<const N: usize>(m: rl_core::model::MatrixView<'_, N>, c: usize) -> Vec<f64> {
    (0..m.dim()).map(|r| m.get(r, c)).collect()
}

fn random_forces<const N: usize>(model: &Model<N>, r: &mut Rng) -> Vec<ForceVector> {
    (0..model.body_count())
        .map(|_| ForceVector::new(r.vec3(2.0), r.vec3(5.0)))
        .collect()
}

/// Every derivative of `model` against finite differences and the other algorithms, on
/// `states` random states (half of them with random external forces).
fn check<const N: usize>(model: &Model<N>, seed: u64, states: usize) {
    let mut r = Rng(seed);
    let n = model.dof();
    let mut d = Box::new(Data::<N>::new());
    let mut scratch = Box::new(Data::<N>::new());
    let mut md = Box::new(Data::<N>::new());
    let mut deriv = Box::new(DerivativeData::<N>::new());
    for s in 0..states {
        let what = |x: &str| format!("{} state {s}: {x}", model.name());
        let (q, qd, qdd) = random_state(model, &mut r);
        let fext = (s % 2 == 1).then(|| random_forces(model, &mut r));
        let fx = fext.as_deref();
        let mut rnea = |q: &[f64], qd: &[f64], qdd: &[f64]| -> Vec<f64> {
            match fx {
                Some(f) => algo::rnea_with_external_forces(model, &mut scratch, q, qd, qdd, f),
                None => algo::rnea(model, &mut scratch, q, qd, qdd),
            }
            .unwrap()
            .to_vec()
        };
        let tau = rnea(&q, &qd, &qdd);
        let fd_dq = fd_q(model, &q, |q| rnea(q, &qd, &qdd));
        let fd_dv = fd_vec(&qd, |qd| rnea(&q, qd, &qdd));
        let res = match fx {
            Some(f) => algo::rnea_derivatives_with_external_forces(
                model, &mut d, &mut deriv, &q, &qd, &qdd, f,
            ),
            None => algo::rnea_derivatives(model, &mut d, &mut deriv, &q, &qd, &qdd),
        }
        .unwrap();
        for c in 0..n {
            assert_close(
                &what(&format!("dtau/dq column {c}")),
                &column(res.dtau_dq, c),
                &fd_dq[c],
                FD_TOL,
            );
            assert_close(
                &what(&format!("dtau/dv column {c}")),
                &column(res.dtau_dv, c),
                &fd_dv[c],
                FD_TOL,
            );
        }
        algo::crba(model, &mut md, &q).unwrap();
        for rr in 0..n {
            let m: Vec<f64> = (0..n).map(|c| md.mass_matrix(rr, c)).collect();
            assert_close(&what("M = CRBA"), res.mass_matrix.row(rr), &m, TOL);
        }

        // Static torque: g(q) − Σ Jᵀ fext.
        let zeros = vec![0.0; n];
        let fd_g = fd_q(model, &q, |q| rnea(q, &zeros, &zeros));
        let g = match fx {
            Some(f) => algo::static_torque_derivatives_with_external_forces(
                model, &mut d, &mut deriv, &q, f,
            ),
            None => algo::static_torque_derivatives(model, &mut d, &mut deriv, &q),
        }
        .unwrap();
        for c in 0..n {
            assert_close(
                &what(&format!("dg/dq column {c}")),
                &column(g, c),
                &fd_g[c],
                FD_TOL,
            );
        }

        // ABA at τ = RNEA(q̈): q̈ back, and its derivatives.
        let mut aba = |q: &[f64], qd: &[f64], tau: &[f64]| -> Vec<f64> {
            match fx {
                Some(f) => algo::aba_with_external_forces(model, &mut scratch, q, qd, tau, f),
                None => algo::aba(model, &mut scratch, q, qd, tau),
            }
            .unwrap()
            .to_vec()
        };
        let fd_aq = fd_q(model, &q, |q| aba(q, &qd, &tau));
        let fd_av = fd_vec(&qd, |qd| aba(&q, qd, &tau));
        let res = match fx {
            Some(f) => algo::aba_derivatives_with_external_forces(
                model, &mut d, &mut deriv, &q, &qd, &tau, f,
            ),
            None => algo::aba_derivatives(model, &mut d, &mut deriv, &q, &qd, &tau),
        }
        .unwrap();
        assert_close(&what("ABA derivatives' qdd"), res.qdd, &qdd, TOL);
        for c in 0..n {
            assert_close(
                &what(&format!("dqdd/dq column {c}")),
                &column(res.ddq_dq, c),
                &fd_aq[c],
                FD_TOL,
            );
            assert_close(
                &what(&format!("dqdd/dv column {c}")),
                &column(res.ddq_dv, c),
                &fd_av[c],
                FD_TOL,
            );
        }
        // M⁻¹ M = 1.
        for rr in 0..n {
            let row: Vec<f64> = (0..n)
                .map(|c| {
                    (0..n)
                        .map(|k| res.minv.get(rr, k) * md.mass_matrix(k, c))
                        .sum()
                })
                .collect();
            let e: Vec<f64> = (0..n).map(|c| f64::from(u8::from(c == rr))).collect();
            assert_close(&what("Minv M = 1"), &row, &e, TOL);
        }
    }
}

#[test]
fn every_joint_type_against_finite_differences() {
    for seed in [1, 2, 3] {
        check(&every_joint_type::<32>(seed), 40 + seed, 6);
    }
}

#[test]
fn mimic_joints_against_finite_differences() {
    for seed in [1, 2] {
        check(&mimic_tree::<32>(seed), 50 + seed, 6);
    }
}

#[test]
fn serial_chain_against_finite_differences() {
    check(&random_chain::<16>(9, 7), 60, 4);
}

/// Every entry is written by every call: results on a workspace that held other results (with
/// external forces, of other algorithms) equal those on a fresh one, bit for bit.
#[test]
fn results_do_not_depend_on_what_the_workspace_held() {
    let model = every_joint_type::<32>(4);
    let mut r = Rng(70);
    let mut d = Box::new(Data::<32>::new());
    let mut fresh = Box::new(DerivativeData::<32>::new());
    let mut used = Box::new(DerivativeData::<32>::new());
    let (q1, qd1, qdd1) = random_state(&model, &mut r);
    let f = random_forces(&model, &mut r);
    let (q, qd, qdd) = random_state(&model, &mut r);
    let rows = |m: rl_core::model::MatrixView<'_, 32>| -> Vec<Vec<f64>> {
        m.rows().map(|r| r.to_vec()).collect()
    };
    algo::aba_derivatives_with_external_forces(&model, &mut d, &mut used, &q1, &qd1, &qdd1, &f)
        .unwrap();
    algo::rnea_derivatives_with_external_forces(&model, &mut d, &mut used, &q1, &qd1, &qdd1, &f)
        .unwrap();
    let a = algo::rnea_derivatives(&model, &mut d, &mut used, &q, &qd, &qdd).unwrap();
    let a = (rows(a.dtau_dq), rows(a.dtau_dv), rows(a.mass_matrix));
    let b = algo::rnea_derivatives(&model, &mut d, &mut fresh, &q, &qd, &qdd).unwrap();
    assert_eq!(a, (rows(b.dtau_dq), rows(b.dtau_dv), rows(b.mass_matrix)));
    let a = rows(algo::static_torque_derivatives(&model, &mut d, &mut used, &q).unwrap());
    let b = rows(algo::static_torque_derivatives(&model, &mut d, &mut fresh, &q).unwrap());
    assert_eq!(a, b);
    let tau = algo::rnea(&model, &mut d, &q, &qd, &qdd).unwrap().to_vec();
    let a = algo::aba_derivatives(&model, &mut d, &mut used, &q, &qd, &tau).unwrap();
    let a = (rows(a.ddq_dq), rows(a.ddq_dv), rows(a.minv));
    let b = algo::aba_derivatives(&model, &mut d, &mut fresh, &q, &qd, &tau).unwrap();
    assert_eq!(a, (rows(b.ddq_dq), rows(b.ddq_dv), rows(b.minv)));
}
