//! The analytical derivatives against Pinocchio 4.1's `computeRNEADerivatives`,
//! `computeABADerivatives` and `computeStaticTorqueDerivatives` to 1e-9, and against central
//! finite differences (five-point stencil) of our own RNEA and ABA (themselves checked against Pinocchio in
//! `pinocchio.rs`) to 1e-6, on ur5, the KUKA iiwa, panda, talos (floating base, 38 DOF) and
//! the Unitree G1 humanoid (floating base, 35 DOF).
//!
//! Fixtures: `tests/data/pinocchio/derivatives/<robot>.json` (made by
//! `scripts/gen-pinocchio-fixtures`, which checked Pinocchio's matrices against finite
//! differences before writing them); the model is the one the robot's main fixture describes.
//! Every other state has external forces on every body.
#![allow(clippy::needless_range_loop)]

mod support;

use rl_core::model::{DerivativeData, MatrixView};
use rl_core::spatial::ForceVector;
use rl_core::{Data, Model, algo};
use serde_json::Value;
use support::assert_close;
use support::fixture::{build, f64s, fixture};

const N: usize = 64;
const TOL: f64 = 1e-9;
const FD_TOL: f64 = 1e-6;
/// The step of the five-point stencil: its truncation error is `O(h⁴)`, so a step this large
/// keeps the rounding of ABA on the floating humanoids (amplified by `1/h`) far below the
/// tolerance while the truncation stays below 1e-10.
const H: f64 = 1e-3;

fn compare(what: &str, ours: MatrixView<'_, N>, theirs: &Value, tol: f64) {
    let rows = theirs.as_array().unwrap();
    assert_eq!(rows.len(), ours.dim(), "{what}: dimension");
    for (r, row) in rows.iter().enumerate() {
        assert_close(&format!("{what} row {r}"), ours.row(r), &f64s(row), tol);
    }
}

/// Our matrix against the five-point central difference
/// `(−f(2h) + 8 f(h) − 8 f(−h) + f(−2h)) / 12h` of `f` along `q ⊕ t e_k` (`T`, the tangent
/// space) or `x + t e_k`.
fn compare_fd<const T: bool>(
    what: &str,
    model: &Model<N>,
    ours: MatrixView<'_, N>,
    x: &[f64],
    mut f: impl FnMut(&[f64]) -> Vec<f64>,
) {
    let n = model.dof();
    let mut xt = x.to_vec();
    for k in 0..n {
        let mut at = |t: f64| {
            if T {
                let mut e = vec![0.0; n];
                e[k] = 1.0;
                model.integrate(x, &e, t, &mut xt);
            } else {
                xt.copy_from_slice(x);
                xt[k] += t;
            }
            f(&xt)
        };
        let (p2, p1, m1, m2) = (at(2.0 * H), at(H), at(-H), at(-2.0 * H));
        let fd: Vec<f64> = (0..n)
            .map(|r| (-p2[r] + 8.0 * p1[r] - 8.0 * m1[r] + m2[r]) / (12.0 * H))
            .collect();
        let col: Vec<f64> = (0..n).map(|r| ours.get(r, k)).collect();
        assert_close(&format!("{what} column {k}"), &col, &fd, FD_TOL);
    }
}

fn check(robot: &str) {
    let model = build::<N>(&fixture(robot));
    let fx = fixture(&format!("derivatives/{robot}"));
    assert_eq!(fx["nv"].as_u64(), Some(model.dof() as u64));
    let mut d = Box::new(Data::<N>::new());
    let mut scratch = Box::new(Data::<N>::new());
    let mut deriv = Box::new(DerivativeData::<N>::new());
    let states = fx["states"].as_array().unwrap();
    assert!(states.len() >= 3);
    let mut with_forces = 0;
    for (k, s) in states.iter().enumerate() {
        let what = |x: &str| format!("{robot} state {k}: {x}");
        let q = f64s(s.get("q_angles").unwrap_or(&s["q"]));
        let (v, a, tau_in) = (f64s(&s["v"]), f64s(&s["a"]), f64s(&s["tau_in"]));
        let fext: Option<Vec<ForceVector>> = s["fext"].as_array().map(|rows| {
            rows.iter()
                .map(|r| {
                    let x = f64s(r);
                    ForceVector::new(
                        glam::DVec3::new(x[3], x[4], x[5]),
                        glam::DVec3::new(x[0], x[1], x[2]),
                    )
                })
                .collect()
        });
        with_forces += usize::from(fext.is_some());
        let fx = fext.as_deref();
        let zeros = vec![0.0; model.dof()];
        let mut rnea = |q: &[f64], v: &[f64], a: &[f64]| -> Vec<f64> {
            match fx {
                Some(f) => algo::rnea_with_external_forces(&model, &mut scratch, q, v, a, f),
                None => algo::rnea(&model, &mut scratch, q, v, a),
            }
            .unwrap()
            .to_vec()
        };

        let r = match fx {
            Some(f) => algo::rnea_derivatives_with_external_forces(
                &model, &mut d, &mut deriv, &q, &v, &a, f,
            ),
            None => algo::rnea_derivatives(&model, &mut d, &mut deriv, &q, &v, &a),
        }
        .unwrap();
        compare(&what("dtau/dq"), r.dtau_dq, &s["drnea_dq"], TOL);
        compare(&what("dtau/dv"), r.dtau_dv, &s["drnea_dv"], TOL);
        compare(&what("M"), r.mass_matrix, &s["mass_matrix"], TOL);
        compare_fd::<true>(&what("dtau/dq vs FD"), &model, r.dtau_dq, &q, |x| {
            rnea(x, &v, &a)
        });
        compare_fd::<false>(&what("dtau/dv vs FD"), &model, r.dtau_dv, &v, |x| {
            rnea(&q, x, &a)
        });
        assert_close(&what("tau"), &rnea(&q, &v, &a), &f64s(&s["tau"]), TOL);

        let g = match fx {
            Some(f) => algo::static_torque_derivatives_with_external_forces(
                &model, &mut d, &mut deriv, &q, f,
            ),
            None => algo::static_torque_derivatives(&model, &mut d, &mut deriv, &q),
        }
        .unwrap();
        compare(&what("dg/dq"), g, &s["dstatic_dq"], TOL);
        compare_fd::<true>(&what("dg/dq vs FD"), &model, g, &q, |x| {
            rnea(x, &zeros, &zeros)
        });

        let r = match fx {
            Some(f) => algo::aba_derivatives_with_external_forces(
                &model, &mut d, &mut deriv, &q, &v, &tau_in, f,
            ),
            None => algo::aba_derivatives(&model, &mut d, &mut deriv, &q, &v, &tau_in),
        }
        .unwrap();
        assert_close(&what("qdd"), r.qdd, &f64s(&s["qdd"]), TOL);
        compare(&what("dqdd/dq"), r.ddq_dq, &s["daba_dq"], TOL);
        compare(&what("dqdd/dv"), r.ddq_dv, &s["daba_dv"], TOL);
        compare(&what("Minv"), r.minv, &s["minv"], TOL);
        let mut aba = |q: &[f64], v: &[f64]| -> Vec<f64> {
            match fx {
                Some(f) => algo::aba_with_external_forces(&model, &mut scratch, q, v, &tau_in, f),
                None => algo::aba(&model, &mut scratch, q, v, &tau_in),
            }
            .unwrap()
            .to_vec()
        };
        compare_fd::<true>(&what("dqdd/dq vs FD"), &model, r.ddq_dq, &q, |x| aba(x, &v));
        compare_fd::<false>(&what("dqdd/dv vs FD"), &model, r.ddq_dv, &v, |x| aba(&q, x));
    }
    assert!(with_forces >= 1, "{robot}: no state with external forces");
}

#[test]
fn ur5() {
    check("ur5");
}

#[test]
fn iiwa() {
    check("iiwa");
}

#[test]
fn panda() {
    check("panda");
}

#[test]
fn talos_floating_base() {
    check("talos_reduced");
}

#[test]
fn g1_humanoid_floating_base() {
    check("g1");
}

/// The FR3's armature on the Panda arm: `M` (and `M⁻¹`) carry it, `∂τ/∂q` and `∂τ/∂q̇` do
/// not.
#[test]
fn panda_arm_with_armature() {
    check("panda_arm_armature");
}

/// Armature on a floating base, its six-DOF joint included.
#[test]
fn solo12_with_armature() {
    check("solo12_armature");
}
