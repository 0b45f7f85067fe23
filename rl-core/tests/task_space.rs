//! Operational-space impedance (`rl_core::task`) checked by what it promises, with algorithms
//! it does not use: the arm's forward dynamics (ABA) under the law's torques gives the tool
//! exactly the commanded task acceleration (undamped, away from singularities), whatever the
//! posture asks of the nullspace, on a redundant arm (KUKA iiwa, 7 DoF) and on random chains;
//! at rest on target the law holds the arm against gravity and nothing more; a device that
//! adds gravity gets the same torques less gravity; through a singularity the damped law's
//! torques stay bounded as its damping says, where the undamped one fails.
#![cfg(feature = "std")]

mod support;

use glam::{DQuat, DVec3};
use rl_core::algo;
use rl_core::spatial::PlueckerTransform;
use rl_core::task::{
    self, ImpedanceGains, Orientation, Priority, Proximity, Repulsion, Singularity, TaskData,
    TaskError, TaskTarget, operational_impedance,
};
use rl_core::{Data, Model};
use support::{Rng, assert_close, random_chain};

fn iiwa() -> Model<16> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/urdf/kuka_lbr_iiwa.urdf"
    );
    rl_core::loader::load_file::<16>(path)
        .unwrap_or_else(|e| panic!("{e}"))
        .model
}

/// The undamped law with random gains.
fn gains(r: &mut Rng, orientation: Orientation) -> ImpedanceGains {
    let mut stiffness = [0.0; 6];
    for k in &mut stiffness {
        *k = r.range(10.0, 500.0);
    }
    ImpedanceGains {
        stiffness,
        damping_ratio: r.range(0.3, 1.5),
        orientation,
        max_position_error: 0.05,
        max_orientation_error: 0.3,
        posture_stiffness: r.range(1.0, 50.0),
        posture_damping_ratio: 1.0,
        limit_band: 0.3,
        limit_stiffness: 100.0,
        singularity: Singularity::Exact,
        ..ImpedanceGains::default()
    }
}

/// A state, a target a few cm and degrees away (sometimes beyond the saturation), and a
/// posture elsewhere.
fn scene<const N: usize>(
    m: &Model<N>,
    d: &mut Data<N>,
    r: &mut Rng,
) -> (Vec<f64>, Vec<f64>, TaskTarget, Vec<f64>) {
    let n = m.dof();
    let q: Vec<f64> = (0..n).map(|_| r.range(-1.5, 1.5)).collect();
    let qd: Vec<f64> = (0..n).map(|_| r.range(-1.0, 1.0)).collect();
    let posture: Vec<f64> = (0..n).map(|_| r.range(-1.0, 1.0)).collect();
    algo::forward_position(m, d, &q).unwrap();
    let x = algo::tool_pose(m, d, 0).unwrap();
    let turn = DQuat::from_scaled_axis(r.vec3(0.4));
    let pose = PlueckerTransform::new(
        glam::DMat3::from_quat(turn) * x.rotation,
        x.translation + r.vec3(0.08),
    );
    let mut velocity = [0.0; 6];
    let mut acceleration = [0.0; 6];
    for k in 0..6 {
        velocity[k] = r.range(-0.3, 0.3);
        acceleration[k] = r.range(-2.0, 2.0);
    }
    (
        q,
        qd,
        TaskTarget {
            pose,
            velocity,
            acceleration,
        },
        posture,
    )
}

/// The commanded task acceleration, worked out here from the tool's pose and velocity
/// (forward position and velocity, glam's axis–angle), saturated as the gains say.
fn commanded<const N: usize>(
    m: &Model<N>,
    d: &mut Data<N>,
    g: &ImpedanceGains,
    t: &TaskTarget,
    q: &[f64],
    qd: &[f64],
) -> [f64; 6] {
    algo::forward_position(m, d, q).unwrap();
    let x = algo::tool_pose(m, d, 0).unwrap();
    algo::forward_velocity(m, d, q, qd).unwrap();
    let v = algo::tool_velocity(m, d, 0).unwrap();
    let sat = |e: DVec3, max: f64| {
        if e.length() > max {
            e * (max / e.length())
        } else {
            e
        }
    };
    let ep = sat(t.pose.translation - x.translation, g.max_position_error);
    let (axis, angle) = rotation_error(&t.pose, &x);
    let eo = sat(axis * angle, g.max_orientation_error);
    let e = [ep.x, ep.y, ep.z, eo.x, eo.y, eo.z];
    let mut a = [0.0; 6];
    for k in 0..6 {
        let kd = 2.0 * g.damping_ratio * g.stiffness[k].sqrt();
        a[k] = t.acceleration[k] + kd * (t.velocity[k] - v[k]) + g.stiffness[k] * e[k];
    }
    a
}

/// The rotation from the tool's orientation `x` to the target's, as axis and angle in
/// `[0, π]` (glam's quaternion axis–angle).
fn rotation_error(target: &PlueckerTransform, x: &PlueckerTransform) -> (DVec3, f64) {
    let (axis, angle) = (DQuat::from_mat3(&target.rotation)
        * DQuat::from_mat3(&x.rotation).conjugate())
    .to_axis_angle();
    if angle > std::f64::consts::PI {
        (-axis, 2.0 * std::f64::consts::PI - angle)
    } else {
        (axis, angle)
    }
}

/// The tool's distance to the target and the angle between their orientations at `q`.
fn errors<const N: usize>(m: &Model<N>, d: &mut Data<N>, t: &TaskTarget, q: &[f64]) -> (f64, f64) {
    algo::forward_position(m, d, q).unwrap();
    let x = algo::tool_pose(m, d, 0).unwrap();
    (
        (t.pose.translation - x.translation).length(),
        rotation_error(&t.pose, &x).1,
    )
}

/// The tool's acceleration under torques `tau` (ABA, then forward acceleration), and `q̈`.
fn tool_acceleration<const N: usize>(
    m: &Model<N>,
    d: &mut Data<N>,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
) -> ([f64; 6], Vec<f64>) {
    let qdd = algo::aba(m, d, q, qd, tau).unwrap().to_vec();
    algo::forward_acceleration(m, d, q, qd, &qdd).unwrap();
    (algo::tool_acceleration(m, d, 0).unwrap(), qdd)
}

fn check_task_acceleration<const N: usize>(m: &Model<N>, seed: u64, states: usize) {
    let mut r = Rng(seed);
    let mut d = Box::new(Data::<N>::new());
    let mut task = Box::new(TaskData::<N>::new());
    let n = m.dof();
    let mut checked = 0;
    while checked < states {
        let (q, qd, target, posture) = scene(m, &mut d, &mut r);
        for orientation in [Orientation::Held, Orientation::Free] {
            let g = gains(&mut r, orientation);
            let rows = if orientation == Orientation::Held {
                6
            } else {
                3
            };
            let mut tau = vec![0.0; n];
            let report = operational_impedance(
                m, &mut d, &mut task, 0, &g, &target, &q, &qd, &posture, &mut tau,
            )
            .unwrap();
            // The errors as the law reports them (before saturation).
            let (dp, angle) = errors(m, &mut d, &target, &q);
            assert!((report.position_error - dp).abs() < 1e-12, "{report:?}");
            let angle = if rows == 6 { angle } else { 0.0 };
            assert!(
                (report.orientation_error - angle).abs() < 1e-9,
                "{report:?} {angle}"
            );
            let want = commanded(m, &mut d, &g, &target, &q, &qd);
            let (got, qdd) = tool_acceleration(m, &mut d, &q, &qd, &tau);
            // Relative to the size of the terms that cancel in it.
            let scale = 1.0 + want.iter().map(|a| a.abs()).fold(0.0, f64::max);
            assert_close(
                "tool acceleration",
                &got[..rows],
                &want[..rows],
                1e-7 * scale,
            );

            // Another posture: other joint accelerations, the same task acceleration.
            let other: Vec<f64> = posture.iter().map(|p| -p).collect();
            let mut tau2 = vec![0.0; n];
            operational_impedance(
                m, &mut d, &mut task, 0, &g, &target, &q, &qd, &other, &mut tau2,
            )
            .unwrap();
            let (got2, qdd2) = tool_acceleration(m, &mut d, &q, &qd, &tau2);
            assert_close(
                "task under another posture",
                &got2[..rows],
                &got[..rows],
                1e-7 * scale,
            );
            let moved = qdd
                .iter()
                .zip(&qdd2)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            if n > rows {
                assert!(
                    moved > 1e-3,
                    "the posture changed no joint acceleration ({moved})"
                );
            }
        }
        checked += 1;
    }
}

#[test]
fn the_tool_accelerates_as_commanded_whatever_the_posture_asks_iiwa() {
    check_task_acceleration(&iiwa(), 1, 50);
}

#[test]
fn the_tool_accelerates_as_commanded_whatever_the_posture_asks_random_chains() {
    for (n, seed) in [(6, 11), (7, 12), (9, 13)] {
        check_task_acceleration(&random_chain::<16>(n, seed), seed, 20);
    }
}

#[test]
fn at_rest_on_target_the_law_holds_the_arm_against_gravity_and_a_device_that_adds_gravity_gets_none()
 {
    let m = iiwa();
    let mut d = Box::new(Data::<16>::new());
    let mut task = Box::new(TaskData::<16>::new());
    let mut r = Rng(3);
    for _ in 0..20 {
        let q: Vec<f64> = (0..7).map(|_| r.range(-1.5, 1.5)).collect();
        let zero = vec![0.0; 7];
        algo::forward_position(&m, &mut d, &q).unwrap();
        let target = TaskTarget::at(algo::tool_pose(&m, &d, 0).unwrap());
        let g = ImpedanceGains {
            limit_band: 0.0,
            ..ImpedanceGains::default()
        };
        let mut tau = vec![0.0; 7];
        let report = operational_impedance(
            &m, &mut d, &mut task, 0, &g, &target, &q, &zero, &q, &mut tau,
        )
        .unwrap();
        assert!(report.position_error < 1e-12 && report.orientation_error < 1e-7);
        let gravity = algo::gravity(&m, &mut d, &q).unwrap().to_vec();
        assert_close("holding torque", &tau, &gravity, 1e-9);
        // The same moving toward a target, gravity left to the device.
        let (q, qd, target, posture) = scene(&m, &mut d, &mut r);
        let mut full = vec![0.0; 7];
        operational_impedance(
            &m, &mut d, &mut task, 0, &g, &target, &q, &qd, &posture, &mut full,
        )
        .unwrap();
        let mut less = vec![0.0; 7];
        let by_device = ImpedanceGains {
            gravity_by_device: true,
            ..g
        };
        operational_impedance(
            &m, &mut d, &mut task, 0, &by_device, &target, &q, &qd, &posture, &mut less,
        )
        .unwrap();
        let gravity = algo::gravity(&m, &mut d, &q).unwrap().to_vec();
        let sum: Vec<f64> = less.iter().zip(&gravity).map(|(a, b)| a + b).collect();
        assert_close("torques less gravity", &sum, &full, 1e-9);
    }
}

/// The iiwa straightened through its stretched singularity (every joint 0: the tool cannot
/// move along the arm's axis), pulled toward a target beyond reach at rest: with `Λ` clamped
/// or damped at `ε` the task torques stay under `‖J‖ ‖a‖ / ε` (the bound `Λ ≤ ε⁻¹` gives) all
/// the way, and under the effort limits; without a bound the law reports the singularity or its
/// torques grow far past that bound.
#[test]
fn through_a_singularity_the_bounded_law_keeps_its_torques_bounded() {
    let m = iiwa();
    let mut d = Box::new(Data::<16>::new());
    let mut task = Box::new(TaskData::<16>::new());
    let zero = [0.0; 7];
    algo::forward_position(&m, &mut d, &zero).unwrap();
    let stretched = algo::tool_pose(&m, &d, 0).unwrap();
    // 5 cm beyond reach, along the arm.
    let target = TaskTarget::at(PlueckerTransform::new(
        stretched.rotation,
        stretched.translation + DVec3::new(0.0, 0.0, 0.05),
    ));
    let eps = [0.01, 0.1];
    let base = ImpedanceGains {
        gravity_by_device: true,
        limit_band: 0.0,
        posture_stiffness: 0.0,
        ..ImpedanceGains::default()
    };
    let a_max = (3.0f64.sqrt() * 400.0 * 0.05).hypot(300.0 * 0.3);
    let mut worst_bounded: f64 = 0.0;
    let mut worst_exact: f64 = 0.0;
    let mut refused = 0;
    let mut clamped_at = 0;
    for k in -200..=200 {
        // Joints 2, 4 and 6 bend through 0, down to 1e-6 rad from it.
        let s = k as f64 / 200.0;
        let bend = 0.3 * s.signum() * s.abs().powi(3).max(1e-6 / 0.3);
        let q = [0.0, bend, 0.0, -2.0 * bend, 0.0, bend, 0.0];
        let mut tau = [0.0; 7];
        for singularity in [Singularity::Clamped(eps), Singularity::Damped(eps)] {
            let g = ImpedanceGains {
                singularity,
                ..base
            };
            let report = operational_impedance(
                &m, &mut d, &mut task, 0, &g, &target, &q, &zero, &q, &mut tau,
            )
            .unwrap();
            if matches!(singularity, Singularity::Clamped(_)) && report.bounded_directions > 0 {
                clamped_at += 1;
            }
            assert!(tau.iter().all(|t| t.is_finite()), "{q:?}: {tau:?}");
            let jn = frobenius(&task.jacobian, 7);
            let norm = tau.iter().map(|t| t * t).sum::<f64>().sqrt();
            let bound = jn * a_max / eps[0].min(eps[1]);
            assert!(
                norm <= bound,
                "{singularity:?} {q:?}: |τ| {norm} over the bound {bound}"
            );
            for (j, t) in tau.iter().enumerate() {
                assert!(
                    t.abs() <= m.limits(j).effort,
                    "{singularity:?} joint {j}: {t} N·m at {q:?}"
                );
            }
            worst_bounded = worst_bounded.max(norm);
        }
        let exact = ImpedanceGains {
            singularity: Singularity::Exact,
            ..base
        };
        match operational_impedance(
            &m, &mut d, &mut task, 0, &exact, &target, &q, &zero, &q, &mut tau,
        ) {
            Ok(_) => worst_exact = worst_exact.max(tau.iter().map(|t| t * t).sum::<f64>().sqrt()),
            Err(TaskError::Singular) => refused += 1,
            Err(e) => panic!("{e}"),
        }
    }
    println!(
        "through the singularity: bounded |τ| ≤ {worst_bounded:.1} N·m (the clamp acted at \
         {clamped_at} of 401 configurations); unbounded up to {worst_exact:.3e} N·m, refused at \
         {refused}"
    );
    assert!(clamped_at > 0 && clamped_at < 401, "{clamped_at}");
    assert!(
        refused > 0 || worst_exact > 100.0 * worst_bounded,
        "the unbounded law met no singularity: {worst_exact} vs {worst_bounded}"
    );
}

/// Where the clamp does not act, the clamped law is the exact one; where it acts, it bounds.
#[test]
fn the_clamped_law_is_exact_wherever_its_clamp_does_not_act() {
    let m = iiwa();
    let mut d = Box::new(Data::<16>::new());
    let mut task = Box::new(TaskData::<16>::new());
    let mut r = Rng(21);
    let (mut exact_cases, mut clamped_cases) = (0, 0);
    for _ in 0..200 {
        let (q, qd, target, posture) = scene(&m, &mut d, &mut r);
        let g = gains(&mut r, Orientation::Held);
        let mut exact = [0.0; 7];
        operational_impedance(
            &m, &mut d, &mut task, 0, &g, &target, &q, &qd, &posture, &mut exact,
        )
        .unwrap();
        let clamped_gains = ImpedanceGains {
            singularity: Singularity::Clamped([0.01, 0.1]),
            ..g
        };
        let mut clamped = [0.0; 7];
        let report = operational_impedance(
            &m,
            &mut d,
            &mut task,
            0,
            &clamped_gains,
            &target,
            &q,
            &qd,
            &posture,
            &mut clamped,
        )
        .unwrap();
        if report.bounded_directions == 0 {
            exact_cases += 1;
            let scale = 1.0 + exact.iter().map(|t| t.abs()).fold(0.0, f64::max);
            assert_close("clamp not acting", &clamped, &exact, 1e-9 * scale);
        } else {
            clamped_cases += 1;
        }
    }
    println!("{exact_cases} states without a clamp, {clamped_cases} with");
    assert!(exact_cases > 20, "{exact_cases}");
}

#[test]
fn bad_arguments_are_refused_with_what_and_where() {
    let m = iiwa();
    let mut d = Box::new(Data::<16>::new());
    let mut task = Box::new(TaskData::<16>::new());
    let q = [0.1; 7];
    let target = TaskTarget::at(PlueckerTransform::IDENTITY);
    let g = ImpedanceGains::default();
    let mut tau = [0.0; 7];
    let e = operational_impedance(
        &m,
        &mut d,
        &mut task,
        0,
        &g,
        &target,
        &q[..6],
        &q,
        &q,
        &mut tau,
    )
    .unwrap_err();
    assert_eq!(e.to_string(), "`q` has 6 elements, the model needs 7");
    let e = operational_impedance(&m, &mut d, &mut task, 3, &g, &target, &q, &q, &q, &mut tau)
        .unwrap_err();
    assert_eq!(e.to_string(), "tool 3 does not exist");
    let mut nan = q;
    nan[2] = f64::NAN;
    let e = operational_impedance(
        &m, &mut d, &mut task, 0, &g, &target, &q, &nan, &q, &mut tau,
    )
    .unwrap_err();
    assert_eq!(e, TaskError::NotFinite { argument: "qd" });
}

#[test]
fn the_torque_rate_limit_moves_each_joint_at_most_its_step() {
    let mut r = Rng(9);
    for _ in 0..100 {
        let prev: Vec<f64> = (0..7).map(|_| r.range(-10.0, 10.0)).collect();
        let want: Vec<f64> = (0..7).map(|_| r.range(-12.0, 12.0)).collect();
        let mut tau = want.clone();
        let n = task::limit_rate(&prev, &mut tau, 1.0);
        let mut expect = 0;
        for k in 0..7 {
            assert!((tau[k] - prev[k]).abs() <= 1.0 + 1e-12);
            if (want[k] - prev[k]).abs() <= 1.0 {
                assert_eq!(tau[k], want[k]);
            } else {
                expect += 1;
            }
        }
        assert_eq!(n, expect);
    }
}

/// A bad step (negative, NaN) limits to no change, a NaN torque is the previous one: no panic.
#[test]
fn the_torque_rate_limit_takes_bad_steps_without_panicking() {
    let mut tau = [3.0, f64::NAN, -2.0];
    assert_eq!(task::limit_rate(&[1.0, 1.0, 1.0], &mut tau, -1.0), 3);
    assert_eq!(tau, [1.0, 1.0, 1.0]);
    let mut tau = [3.0, 0.5];
    assert_eq!(task::limit_rate(&[1.0, 0.5], &mut tau, f64::NAN), 1);
    assert_eq!(tau, [1.0, 0.5]);
}

fn frobenius(j: &[[f64; 16]; 6], n: usize) -> f64 {
    j.iter()
        .map(|row| row[..n].iter().map(|x| x * x).sum::<f64>())
        .sum::<f64>()
        .sqrt()
}

/// The law against the same law computed with Pinocchio 4.1 and numpy
/// (`scripts/gen-task-fixtures`: Pinocchio's frame Jacobian, classical acceleration, CRBA,
/// nonlinear effects and `log3`; numpy's inverses and `eigh`): 24 states of the iiwa with every
/// bound, position-only tasks and gravity left to the device, to 1e-9 relative.
#[test]
fn the_law_agrees_with_the_same_law_on_pinocchio() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/task/iiwa_impedance.json"
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).expect("fixture")).expect("JSON");
    assert_eq!(doc["format"], "rl-rs task impedance fixture 1");
    let mut m = iiwa();
    assert_eq!(m.tools()[0].name.as_str(), doc["tool"].as_str().unwrap());
    let g = f64s(&doc["gravity"]);
    m.set_gravity(DVec3::new(g[0], g[1], g[2]));
    let mut d = Box::new(Data::<16>::new());
    let mut task = Box::new(TaskData::<16>::new());
    let cases = doc["cases"].as_array().expect("cases");
    assert_eq!(cases.len(), 24);
    let mut clamped = 0;
    for (i, c) in cases.iter().enumerate() {
        let gj = &c["gains"];
        let eps = |s: &serde_json::Value| {
            let e = f64s(&s["eps"]);
            [e[0], e[1]]
        };
        let singularity = match gj["singularity"]["kind"].as_str().unwrap() {
            "exact" => Singularity::Exact,
            "damped" => Singularity::Damped(eps(&gj["singularity"])),
            "clamped" => Singularity::Clamped(eps(&gj["singularity"])),
            k => panic!("{k}"),
        };
        let mut stiffness = [0.0; 6];
        stiffness.copy_from_slice(&f64s(&gj["stiffness"]));
        let gains = ImpedanceGains {
            stiffness,
            damping_ratio: gj["damping_ratio"].as_f64().unwrap(),
            orientation: if gj["orientation"] == "held" {
                Orientation::Held
            } else {
                Orientation::Free
            },
            max_position_error: gj["max_position_error"].as_f64().unwrap(),
            max_orientation_error: gj["max_orientation_error"].as_f64().unwrap(),
            posture_stiffness: gj["posture_stiffness"].as_f64().unwrap(),
            posture_damping_ratio: gj["posture_damping_ratio"].as_f64().unwrap(),
            limit_band: gj["limit_band"].as_f64().unwrap(),
            limit_stiffness: gj["limit_stiffness"].as_f64().unwrap(),
            singularity,
            gravity_by_device: gj["gravity_by_device"].as_bool().unwrap(),
            ..ImpedanceGains::default()
        };
        let t = &c["target"];
        let r = f64s(&t["rotation"]);
        let tr = f64s(&t["translation"]);
        let mut velocity = [0.0; 6];
        velocity.copy_from_slice(&f64s(&t["velocity"]));
        let mut acceleration = [0.0; 6];
        acceleration.copy_from_slice(&f64s(&t["acceleration"]));
        let target = TaskTarget {
            pose: PlueckerTransform::new(
                glam::DMat3::from_cols_array(&<[f64; 9]>::try_from(r).unwrap()).transpose(),
                DVec3::new(tr[0], tr[1], tr[2]),
            ),
            velocity,
            acceleration,
        };
        let (q, qd, posture) = (f64s(&c["q"]), f64s(&c["qd"]), f64s(&c["posture"]));
        let mut tau = [0.0; 7];
        let report = operational_impedance(
            &m, &mut d, &mut task, 0, &gains, &target, &q, &qd, &posture, &mut tau,
        )
        .unwrap_or_else(|e| panic!("case {i}: {e}"));
        let want = f64s(&c["tau"]);
        let scale = 1.0 + want.iter().map(|x| x.abs()).fold(0.0, f64::max);
        assert_close(&format!("case {i}: τ"), &tau, &want, 1e-9 * scale);
        assert!((report.position_error - c["position_error"].as_f64().unwrap()).abs() < 1e-12);
        assert!(
            (report.orientation_error - c["orientation_error"].as_f64().unwrap()).abs() < 1e-9,
            "case {i}: {report:?}"
        );
        if let Some(n) = c.get("clamped").and_then(|n| n.as_u64()) {
            assert_eq!(report.bounded_directions as u64, n, "case {i}");
            clamped += usize::from(n > 0);
        }
    }
    assert!(clamped > 0, "no case has the clamp acting");
}

fn f64s(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// A point of body `b` (world) from a point in its frame.
fn body_point<const N: usize>(d: &Data<N>, b: usize, local: DVec3) -> DVec3 {
    d.world_pose(b).transform_point(local)
}

#[test]
fn a_point_jacobian_is_the_derivative_of_the_point_and_the_tool_jacobian_at_the_tool() {
    let m = iiwa();
    let mut d = Box::new(Data::<16>::new());
    let mut r = Rng(21);
    let n = m.dof();
    let mut jac = [[0.0; 16]; 6];
    for _ in 0..20 {
        let q: Vec<f64> = (0..n).map(|_| r.range(-1.5, 1.5)).collect();
        let b = 1 + (r.range(0.0, 0.999) * (m.body_count() - 1) as f64) as usize;
        let local = r.vec3(0.2);
        algo::forward_position(&m, &mut d, &q).unwrap();
        let p = body_point(&d, b, local);
        algo::point_jacobian(&m, &d, b, p, &mut jac).unwrap();
        for k in 0..n {
            let h = 1e-6;
            let mut qp = q.clone();
            qp[k] += h;
            algo::forward_position(&m, &mut d, &qp).unwrap();
            let up = body_point(&d, b, local);
            qp[k] -= 2.0 * h;
            algo::forward_position(&m, &mut d, &qp).unwrap();
            let down = body_point(&d, b, local);
            let fd = (up - down) / (2.0 * h);
            let col = DVec3::new(jac[0][k], jac[1][k], jac[2][k]);
            assert!(
                (fd - col).length() < 1e-8,
                "body {b} column {k}: {fd} vs {col}"
            );
        }
        // At the tool's origin on the tool's body: the tool Jacobian.
        let mut tool = [[0.0; 16]; 6];
        algo::jacobian(&m, &mut d, &q, 0, &mut tool).unwrap();
        let x = algo::tool_pose(&m, &d, 0).unwrap();
        let body = m.tools()[0].body;
        algo::point_jacobian(&m, &d, body, x.translation, &mut jac).unwrap();
        for row in 0..6 {
            assert_close("tool columns", &jac[row][..n], &tool[row][..n], 1e-12);
        }
    }
    assert!(matches!(
        algo::point_jacobian(&m, &d, 99, DVec3::ZERO, &mut jac),
        Err(rl_core::Error::UnknownBody { body: 99 })
    ));
}

/// A proximity on a random body of `m` at `q`, 2–15 cm from its obstacle.
fn random_proximity<const N: usize>(
    m: &Model<N>,
    d: &mut Data<N>,
    q: &[f64],
    r: &mut Rng,
) -> Proximity {
    algo::forward_position(m, d, q).unwrap();
    let b = 2 + (r.range(0.0, 0.999) * (m.body_count() - 2) as f64) as usize;
    let point = body_point(d, b, r.vec3(0.05));
    Proximity::at_rest(b, point, r.vec3(1.0).normalize(), r.range(0.06, 0.15))
}

#[test]
fn orientation_first_holds_the_orientation_exactly_while_the_position_yields_to_obstacles() {
    let m = iiwa();
    let mut d = Box::new(Data::<16>::new());
    let mut task = Box::new(TaskData::<16>::new());
    let mut r = Rng(31);
    let n = m.dof();
    let mut jac = [[0.0; 16]; 6];
    for _ in 0..30 {
        let (q, qd, target, posture) = scene(&m, &mut d, &mut r);
        let g = ImpedanceGains {
            priority: Priority::OrientationFirst,
            ..gains(&mut r, Orientation::Held)
        };
        let want = commanded(&m, &mut d, &g, &target, &q, &qd);
        let scale = 1.0 + want.iter().map(|a| a.abs()).fold(0.0, f64::max);
        let call = |d: &mut Data<16>, task: &mut TaskData<16>, g: &ImpedanceGains| {
            let mut tau = vec![0.0; n];
            let report =
                operational_impedance(&m, d, task, 0, g, &target, &q, &qd, &posture, &mut tau)
                    .unwrap();
            (tau, report)
        };
        // Without obstacles, away from singularities: both levels exactly as commanded, and
        // the same torques as one 6-D task.
        task.set_proximities(&[]).unwrap();
        let (tau, _) = call(&mut d, &mut task, &g);
        let (got, _) = tool_acceleration(&m, &mut d, &q, &qd, &tau);
        assert_close("two levels, no obstacle", &got, &want, 1e-7 * scale);
        let together = ImpedanceGains {
            priority: Priority::Together,
            ..g
        };
        let (tau_one, _) = call(&mut d, &mut task, &together);
        let tscale = 1.0 + tau_one.iter().map(|t| t.abs()).fold(0.0, f64::max);
        assert_close("two levels = one task", &tau, &tau_one, 1e-7 * tscale);

        // An obstacle near a link: the orientation is untouched, the point is pushed away.
        let p = random_proximity(&m, &mut d, &q, &mut r);
        assert_eq!(task.set_proximities(&[p]).unwrap(), 1);
        let (tau, report) = call(&mut d, &mut task, &g);
        assert_eq!(report.repelling, 1);
        assert_eq!(report.min_distance, p.distance);
        let (got, qdd) = tool_acceleration(&m, &mut d, &q, &qd, &tau);
        assert_close(
            "orientation with an obstacle",
            &got[3..],
            &want[3..],
            1e-7 * scale,
        );
        // The same obstacle without its push (the position yields as much): the repulsion
        // alone accelerates the point away from the obstacle.
        let pushless = ImpedanceGains {
            repulsion: Repulsion {
                stiffness: 0.0,
                damping: 0.0,
                ..g.repulsion
            },
            ..g
        };
        let (tau_yield, report_yield) = call(&mut d, &mut task, &pushless);
        let (got_yield, qdd_yield) = tool_acceleration(&m, &mut d, &q, &qd, &tau_yield);
        // The position's command faded by the obstacle's activation, the orientation whole.
        let s = g.repulsion.activation(p.distance);
        assert_eq!(report_yield.yielding, s);
        let faded: Vec<f64> = (0..6)
            .map(|k| if k < 3 { (1.0 - s) * want[k] } else { want[k] })
            .collect();
        assert_close("the position yields", &got_yield, &faded, 1e-7 * scale);
        algo::forward_position(&m, &mut d, &q).unwrap();
        algo::point_jacobian(&m, &d, p.body, p.point, &mut jac).unwrap();
        let away: f64 = (0..n)
            .map(|k| {
                (p.normal.x * jac[0][k] + p.normal.y * jac[1][k] + p.normal.z * jac[2][k])
                    * (qdd[k] - qdd_yield[k])
            })
            .sum();
        assert!(
            away > 0.0,
            "the repulsion pulled the point toward the obstacle ({away})"
        );

        // One 6-D task: the repulsion acts in its nullspace only.
        let (tau, _) = call(&mut d, &mut task, &together);
        let (got, _) = tool_acceleration(&m, &mut d, &q, &qd, &tau);
        assert_close("one task with an obstacle", &got, &want, 1e-7 * scale);
        // Beyond the influence distance nothing changes.
        let far = Proximity {
            distance: g.repulsion.influence,
            ..p
        };
        task.set_proximities(&[far]).unwrap();
        let (tau_far, report) = call(&mut d, &mut task, &g);
        assert_eq!(report.repelling, 0);
        let (got, _) = tool_acceleration(&m, &mut d, &q, &qd, &tau_far);
        assert_close("an obstacle out of reach", &got, &want, 1e-7 * scale);
    }
}

#[test]
fn on_a_six_joint_arm_orientation_first_is_the_six_dimensional_task() {
    for seed in [41, 42, 43] {
        let m = random_chain::<16>(6, seed);
        let mut d = Box::new(Data::<16>::new());
        let mut task = Box::new(TaskData::<16>::new());
        let mut r = Rng(seed);
        let n = m.dof();
        for _ in 0..10 {
            let (q, qd, target, posture) = scene(&m, &mut d, &mut r);
            let g = gains(&mut r, Orientation::Held);
            let mut one = vec![0.0; n];
            let mut two = vec![0.0; n];
            let first = ImpedanceGains {
                priority: Priority::OrientationFirst,
                ..g
            };
            let a = operational_impedance(
                &m, &mut d, &mut task, 0, &g, &target, &q, &qd, &posture, &mut one,
            );
            let b = operational_impedance(
                &m, &mut d, &mut task, 0, &first, &target, &q, &qd, &posture, &mut two,
            );
            match (a, b) {
                (Ok(_), Ok(_)) => {
                    let scale = 1.0 + one.iter().map(|t| t.abs()).fold(0.0, f64::max);
                    assert_close("one level vs two", &two, &one, 1e-7 * scale);
                }
                // A singular random state is singular for both.
                (Err(TaskError::Singular), Err(TaskError::Singular)) => {}
                (a, b) => panic!("{a:?} vs {b:?}"),
            }
        }
    }
}

#[test]
fn the_repulsion_grows_toward_the_margin_and_vanishes_smoothly_at_its_reach() {
    let rep = Repulsion::default();
    assert_eq!(rep.acceleration(rep.influence, -5.0), 0.0);
    assert_eq!(rep.acceleration(1.0, -5.0), 0.0);
    // Continuous at the influence distance, the approach's damping included.
    assert!(rep.acceleration(rep.influence - 1e-9, -5.0) < 1e-6);
    // Growing toward the margin, capped.
    let mut last = 0.0;
    for k in 1..100 {
        let d = rep.influence - (rep.influence - rep.margin) * k as f64 / 100.0;
        let a = rep.acceleration(d, 0.0);
        assert!(
            a > last || a == rep.max_acceleration,
            "{d}: {a} after {last}"
        );
        last = a;
    }
    assert_eq!(rep.acceleration(rep.margin, 0.0), rep.max_acceleration);
    assert_eq!(rep.acceleration(-0.1, 0.0), rep.max_acceleration);
    // Damping only of an approach.
    let d = 0.15;
    assert!(rep.acceleration(d, -0.5) > rep.acceleration(d, 0.0));
    assert_eq!(rep.acceleration(d, 0.5), rep.acceleration(d, 0.0));
    // 1 m²/s² · (1/(0.1 − 0.05) − 1/(0.2 − 0.05)) at 10 cm.
    assert!((rep.acceleration(0.1, 0.0) - (20.0 - 1.0 / 0.15)).abs() < 1e-12);

    for (bad, what) in [
        (
            Repulsion {
                influence: 0.05,
                ..rep
            },
            "repulsion.influence",
        ),
        (
            Repulsion {
                damping: f64::NAN,
                ..rep
            },
            "repulsion.damping",
        ),
        (
            Repulsion {
                margin: -0.01,
                ..rep
            },
            "repulsion.margin",
        ),
    ] {
        let g = ImpedanceGains {
            repulsion: bad,
            ..ImpedanceGains::default()
        };
        assert_eq!(g.check(), Err(TaskError::Gain { gain: what }));
    }
    let mut task = Box::new(TaskData::<16>::new());
    let p = Proximity::at_rest(1, DVec3::ZERO, DVec3::X, 0.1);
    for bad in [
        Proximity {
            normal: DVec3::new(1.0, 1.0, 0.0),
            ..p
        },
        Proximity {
            distance: f64::NAN,
            ..p
        },
        Proximity {
            point: DVec3::new(f64::INFINITY, 0.0, 0.0),
            ..p
        },
    ] {
        assert_eq!(
            task.set_proximities(&[p, bad]),
            Err(TaskError::NotFinite {
                argument: "proximity"
            })
        );
        assert!(task.proximities().is_empty());
    }
    assert_eq!(
        task.set_proximities(&[p; 12]).unwrap(),
        task::MAX_PROXIMITIES
    );
}

/// The joints' friction in the model (viscous and dry) is what the law adds at the measured
/// speed, `d q̇ + f tanh(q̇ / v_s)`, and nothing else changes; the dry part is continuous
/// through rest (0 at q̇ = 0, half its value at q̇ = 0.55 v_s). Bad friction is refused by
/// argument and joint, and a smoothing that is not one by the law.
#[test]
fn the_law_compensates_the_joints_friction_in_the_model() {
    let mut m = iiwa();
    let n = m.dof();
    let mut d = Data::<16>::new();
    let mut task = TaskData::<16>::new();
    let mut r = Rng(41);
    let g = ImpedanceGains::default();
    let (q, qd, target, posture) = scene(&m, &mut d, &mut r);
    let mut plain = vec![0.0; n];
    operational_impedance(
        &m, &mut d, &mut task, 0, &g, &target, &q, &qd, &posture, &mut plain,
    )
    .unwrap();
    let damping: Vec<f64> = (0..n).map(|k| 0.1 + 0.05 * k as f64).collect();
    let friction: Vec<f64> = (0..n).map(|k| 1.2 - 0.1 * k as f64).collect();
    m.set_joint_friction(&damping, &friction).unwrap();
    assert_eq!(m.joint_friction(), (&damping[..], &friction[..]));
    let mut with = vec![0.0; n];
    operational_impedance(
        &m, &mut d, &mut task, 0, &g, &target, &q, &qd, &posture, &mut with,
    )
    .unwrap();
    let v_s = g.friction_smoothing;
    let expected: Vec<f64> = (0..n)
        .map(|k| plain[k] + damping[k] * qd[k] + friction[k] * (qd[k] / v_s).tanh())
        .collect();
    assert_close("τ with friction", &with, &expected, 1e-12);
    let mut tau = vec![0.0; n];
    m.friction_torque(&vec![0.0; n], v_s, &mut tau);
    assert!(tau.iter().all(|t| *t == 0.0), "{tau:?}");
    m.friction_torque(&vec![0.549_306_144_334_054_8 * v_s; n], v_s, &mut tau);
    let dry = tau[0] - damping[0] * 0.549_306_144_334_054_8 * v_s;
    assert!((dry - 0.5 * friction[0]).abs() < 1e-12, "{dry}");
    let mut bad = friction.clone();
    bad[3] = -1.0;
    assert_eq!(
        m.set_joint_friction(&damping, &bad),
        Err(rl_core::Error::NotPhysical {
            argument: "friction",
            index: 3
        })
    );
    assert!(matches!(
        m.set_joint_friction(&damping[..2], &friction),
        Err(rl_core::Error::Dimension {
            argument: "damping",
            ..
        })
    ));
    let zero_smoothing = ImpedanceGains {
        friction_smoothing: 0.0,
        ..ImpedanceGains::default()
    };
    assert_eq!(
        operational_impedance(
            &m,
            &mut d,
            &mut task,
            0,
            &zero_smoothing,
            &target,
            &q,
            &qd,
            &posture,
            &mut with,
        )
        .err(),
        Some(TaskError::Gain {
            gain: "friction_smoothing"
        })
    );
}
