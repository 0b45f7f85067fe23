//! Our TOPP-RA against PyPI `toppra` 0.6.10 (Pham & Pham's reference implementation) on the
//! problems of `rl-plan/tests/data/toppra.json` (made by `scripts/gen-topp-fixtures`): cubic
//! splines through random waypoints of 6 and 7 joints, random velocity and acceleration
//! limits, both discretization schemes, 100 grid intervals. On the same grid and path
//! derivatives both solve the same discrete problem: ours exactly (in closed form per stage),
//! toppra with Seidel's LP and its tolerances, which keep it a little inside the limits (in
//! case 0 its largest velocity is 0.99999957 of a limit, its largest acceleration 0.99999995).
//! Both take the greatest admissible `s̈` stage by stage; where `q''` couples the bound on `s̈`
//! to `ṡ²`, a slightly lower `ṡ` at one grid point allows a slightly higher one at the next,
//! so toppra's margins move its speeds both ways (case 0: ours above at most grid points,
//! 2e-7 below at one). The durations agree to 1e-5 relative and the path speeds to 1e-5 of
//! their peak. Every grid point keeps every limit.

use rl_plan::execute::{Discretization, ToppProblem, topp_ra};
use serde_json::Value;

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

#[test]
fn topp_ra_agrees_with_toppra() {
    let text = include_str!("data/toppra.json");
    let fixture: Value = serde_json::from_str(text).expect("fixture");
    let cases = fixture["cases"].as_array().expect("cases");
    assert!(cases.len() >= 10);
    let mut worst = 0.0f64;
    for (c, case) in cases.iter().enumerate() {
        let nq = case["dof"].as_u64().unwrap() as usize;
        let grid = floats(&case["grid"]);
        let dq = floats(&case["dq"]);
        let ddq = floats(&case["ddq"]);
        let velocity = floats(&case["velocity"]);
        let acceleration = floats(&case["acceleration"]);
        let discretization = match case["scheme"].as_str().unwrap() {
            "collocation" => Discretization::Collocation,
            _ => Discretization::Interpolation,
        };
        let r = topp_ra(&ToppProblem {
            grid: &grid,
            dq: &dq,
            ddq: &ddq,
            velocity: &velocity,
            acceleration: &acceleration,
            start_speed: 0.0,
            end_speed: 0.0,
            discretization,
            speed_cap: &[],
        })
        .unwrap_or_else(|e| panic!("case {c}: {e}"));
        let want = case["toppra_duration"].as_f64().unwrap();
        let rel = (want - r.duration()) / want;
        worst = worst.max(rel.abs());
        assert!(
            rel.abs() < 1e-5,
            "case {c} ({nq} joints, {discretization:?}): duration {} vs toppra's {want}",
            r.duration()
        );
        let theirs = floats(&case["toppra_sd"]);
        let sd_max = theirs.iter().fold(0.0f64, |m, v| m.max(*v));
        for (i, (ours, theirs)) in r.speeds().zip(theirs).enumerate() {
            assert!(
                (ours - theirs).abs() <= 1e-5 * sd_max,
                "case {c}, grid point {i}: sd {ours} vs toppra's {theirs}"
            );
        }
        // Every limit at every grid point: |q' ṡ| ≤ V, |q' s̈ + q'' ṡ²| ≤ A (s̈ of the stage
        // starting there; the last point with the last stage's).
        let s: Vec<f64> = r.speeds().collect();
        let n = grid.len();
        for i in 0..n {
            let j = i.min(n - 2);
            let u = (s[j + 1] * s[j + 1] - s[j] * s[j]) / (2.0 * (grid[j + 1] - grid[j]));
            for k in 0..nq {
                let v = dq[i * nq + k] * s[i];
                let a = dq[i * nq + k] * u + ddq[i * nq + k] * s[i] * s[i];
                assert!(
                    v.abs() <= velocity[k] * (1.0 + 1e-9),
                    "case {c}: v {v} at {i}"
                );
                if i == j || discretization == Discretization::Interpolation {
                    assert!(
                        a.abs() <= acceleration[k] * (1.0 + 1e-6),
                        "case {c}: joint {k} a {a} > {} at {i}",
                        acceleration[k]
                    );
                }
            }
        }
    }
    println!(
        "{} cases, worst relative duration difference to toppra {worst:.2e}",
        cases.len()
    );
}
