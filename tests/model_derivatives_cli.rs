//! `rl model eval --derivatives` end to end: on the KUKA iiwa URDF (in the repository) at the
//! states of rl-core's derivative fixture, `drnea_dq`, `drnea_dv`, `daba_dq`, `daba_dv` and
//! `mass_matrix` equal Pinocchio 4.1's computeRNEADerivatives / computeABADerivatives to 1e-9
//! (row-major nested lists); without the flag the keys are absent.

mod cli;

use cli::rl_json;
use serde_json::Value;

const IIWA: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/rl-core/tests/data/urdf/kuka_lbr_iiwa.urdf"
);

fn fixture() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/rl-core/tests/data/pinocchio/derivatives/iiwa.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn list(v: &Value) -> String {
    let x: Vec<String> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| format!("{}", x.as_f64().unwrap()))
        .collect();
    x.join(",")
}

fn same_matrix(what: &str, ours: &Value, theirs: &Value) {
    let (a, b) = (ours.as_array().unwrap(), theirs.as_array().unwrap());
    assert_eq!(a.len(), b.len(), "{what}: rows");
    for (r, (ra, rb)) in a.iter().zip(b).enumerate() {
        let (ra, rb) = (ra.as_array().unwrap(), rb.as_array().unwrap());
        assert_eq!(ra.len(), rb.len(), "{what}: columns");
        for (c, (x, y)) in ra.iter().zip(rb).enumerate() {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!(
                (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0),
                "{what}[{r}][{c}]: {x} vs {y}"
            );
        }
    }
}

#[test]
fn eval_derivatives_match_pinocchio_on_the_iiwa() {
    let fx = fixture();
    let mut checked = 0;
    for s in fx["states"].as_array().unwrap() {
        if !s["fext"].is_null() {
            continue; // the command has no external forces
        }
        let (q, v, a, tau) = (
            list(&s["q"]),
            list(&s["v"]),
            list(&s["a"]),
            list(&s["tau_in"]),
        );
        let args = [
            "model",
            "eval",
            IIWA,
            "--joint-order",
            "pinocchio",
            "--q",
            &q,
            "--qd",
            &v,
            "--qdd",
            &a,
            "--tau",
            &tau,
        ];
        let plain = rl_json(&args);
        assert!(
            plain.get("drnea_dq").is_none(),
            "derivatives without the flag"
        );
        let mut with = args.to_vec();
        with.push("--derivatives");
        let out = rl_json(&with);
        same_matrix("drnea_dq", &out["drnea_dq"], &s["drnea_dq"]);
        same_matrix("drnea_dv", &out["drnea_dv"], &s["drnea_dv"]);
        same_matrix("mass_matrix", &out["mass_matrix"], &s["mass_matrix"]);
        same_matrix("daba_dq", &out["daba_dq"], &s["daba_dq"]);
        same_matrix("daba_dv", &out["daba_dv"], &s["daba_dv"]);
        checked += 1;
    }
    assert!(checked >= 2, "states without external forces: {checked}");
}
