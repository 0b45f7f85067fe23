//! RL's own values for the Unimation Puma 560 (`unimation-puma560.xml`), from
//! `shared/reference/rl-models.md` ("Reference values: unimation-puma560 (RL's own output)"):
//! q_i = 0.1 i + 0.2, q̇_i = 0.05 i − 0.1, q̈_i = 0.3 − 0.02 i, RL's world gravity
//! (0, 0, +9.80665), i.e. physical gravity (0, 0, −9.80665).
//!
//! Tolerance: 1e-9 relative (1e-12 absolute near zero) to RL's exact value. The printout rounds
//! that value (M and J have only 9 significant digits), so the bound against the printed number
//! adds half a unit in its last digit, the most RL's exact value can differ from its printout.
#![cfg(feature = "std")]

use rl_core::Data;
use rl_core::algo;
use rl_core::loader;

/// A reference value with the number of significant digits it was printed with.
fn check(what: &str, ours: f64, printed: &str) {
    if printed == "~0" {
        assert!(ours.abs() <= 1e-12, "{what}: {ours} should be ~0");
        return;
    }
    let reference: f64 = printed.parse().unwrap();
    let mantissa = printed
        .trim_start_matches('-')
        .split(['e', 'E'])
        .next()
        .unwrap();
    let digits = mantissa
        .chars()
        .filter(|c| c.is_ascii_digit())
        .collect::<String>();
    let significant = digits.trim_start_matches('0').len() as i32;
    let half_unit = 0.5 * 10f64.powi(reference.abs().log10().floor() as i32 - significant + 1);
    // |ours − printed| ≤ |ours − RL's exact value| + |RL's exact value − printed|
    let tol = 1e-9 * reference.abs() + half_unit + 1e-12;
    assert!(
        (ours - reference).abs() <= tol,
        "{what}: ours {ours} vs RL {printed} (diff {:e}, tol {tol:e})",
        (ours - reference).abs()
    );
}

fn check_row(what: &str, ours: &[f64], printed: &str) {
    let refs: Vec<&str> = printed.split_whitespace().collect();
    assert_eq!(ours.len(), refs.len(), "{what}");
    for (i, (o, r)) in ours.iter().zip(refs).enumerate() {
        check(&format!("{what}[{i}]"), *o, r);
    }
}

const TAU: &str =
    "1.42472394576 -38.3359212354 -3.68244945768 0.0123398537079 -0.0550834260615 2.5415523965e-05";
const G: &str =
    "-2.39469485381e-15 -39.1083348355 -3.8513361781 0.0112745227341 -0.0580863489143 0";
const C: &str = "0.00149693788723 0.000354465997111 -0.00567153800117 1.0800395891e-05 -5.2267424037e-06 -9.92467923426e-08";
const QDD: &str =
    "-0.918422292327 20.0523198959 -12.5598405738 2.88121063273 -7.40773902886 -4.11715493739";
const P: &str = "0.671474225622 0.279233964449 0.889996320686";
const QUAT_WXYZ: &str = "0.587069090875 0.157051554336 0.565084560121 0.558000118039";
const M: [&str; 6] = [
    "4.68283594  0.152591007 -0.0989222243  0.00393964013  0.00192050641  1.24811399e-05",
    "0.152591007  2.21373255  0.406091391 -0.00120546888  0.00518228595  1.08281609e-05",
    "-0.0989222243  0.406091391  0.346564232 -0.000905384152  0.00289892102  1.08281609e-05",
    "0.00393964013 -0.00120546888 -0.000905384152  0.00182902924  ~0  3.30134246e-05",
    "0.00192050641  0.00518228595  0.00289892102  ~0  0.00103290062  ~0",
    "1.24811399e-05  1.08281609e-05  1.08281609e-05  3.30134246e-05  ~0  4e-05",
];
const J: [&str; 6] = [
    "-0.279233964  0.22501968  0.350081689 -0.0124312414  0.00444757432  0",
    "0.671474226  0.0456137474  0.0709650716  0.018336009  0.0175556279  0",
    "~0 -0.713564671 -0.301050375  0.00719368316 -0.0370618606  0",
    "0 -0.198669331 -0.198669331  0.631376224 -0.533724333  0.83875693",
    "~0  0.980066578  0.980066578  0.127986297  0.787240299  0.446234276",
    "1  ~0  ~0  0.764842187  0.308854412  0.312028498",
];

#[test]
fn puma560_matches_rl() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/rlmdl/unimation-puma560.xml"
    );
    let mut loaded = loader::load_file::<8>(path).unwrap();
    let model = &mut loaded.model;
    model.set_gravity(glam::DVec3::new(0.0, 0.0, -9.80665));
    assert_eq!(model.dof(), 6);
    let q: Vec<f64> = (0..6).map(|i| 0.1 * i as f64 + 0.2).collect();
    let qd: Vec<f64> = (0..6).map(|i| 0.05 * i as f64 - 0.1).collect();
    let qdd: Vec<f64> = (0..6).map(|i| 0.3 - 0.02 * i as f64).collect();
    let mut d = Data::<8>::new();

    check_row(
        "tau",
        algo::rnea(model, &mut d, &q, &qd, &qdd).unwrap(),
        TAU,
    );
    check_row("G", algo::gravity(model, &mut d, &q).unwrap(), G);
    check_row("C", algo::coriolis(model, &mut d, &q, &qd).unwrap(), C);
    check_row(
        "qdd",
        algo::aba(model, &mut d, &q, &qd, &[0.0; 6]).unwrap(),
        QDD,
    );

    algo::forward_position(model, &mut d, &q).unwrap();
    let x = algo::tool_pose(model, &d, 0).unwrap();
    check_row("tool position", &x.translation.to_array(), P);
    let mut quat = x.quaternion();
    if quat.w < 0.0 {
        quat = -quat;
    }
    check_row(
        "tool quaternion",
        &[quat.w, quat.x, quat.y, quat.z],
        QUAT_WXYZ,
    );

    algo::crba(model, &mut d, &q).unwrap();
    for (r, row) in M.iter().enumerate() {
        let ours: Vec<f64> = (0..6).map(|c| d.mass_matrix(r, c)).collect();
        check_row(&format!("M[{r}]"), &ours, row);
    }
    let mut jac = [[0.0; 8]; 6];
    algo::jacobian(model, &mut d, &q, 0, &mut jac).unwrap();
    for (r, row) in J.iter().enumerate() {
        check_row(&format!("J[{r}]"), &jac[r][..6], row);
    }
}

#[test]
fn tolerance_rule_rejects_a_wrong_digit() {
    // The printed-precision bound must still catch an error in the last printed digit.
    let r = std::panic::catch_unwind(|| check("x", 0.152591008, "0.152591007"));
    assert!(r.is_err());
    let r = std::panic::catch_unwind(|| check("x", 1.42472395576, "1.42472394576"));
    assert!(r.is_err());
}
