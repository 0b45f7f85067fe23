//! dynibo's side of scripts/bench-pinocchio: times fk, jacobian, rnea, nle, gravity, crba and
//! aba of dynibo 0.5.3 on the states of a states file, exactly as `rl model bench` times
//! rl-core (per algorithm, enough repetitions over all states for ~2 ms per round, the median
//! of `rounds` rounds, ns per call), and prints one JSON line with the same keys.
//!
//! Usage: dynibo-bench URDF STATES LINK [--floating-base] [--rounds N]
//!
//! The states file is in Pinocchio's order and layout; dynibo orders joints breadth-first, so
//! joint values are mapped by name. A floating base (Pinocchio: q = [x y z qx qy qz qw],
//! v = [linear; angular] in the base frame) becomes dynibo's `BaseState` (pose, classical
//! velocity and acceleration in world axes, angular first). dynibo's gravity is fixed at
//! 9.80665 m/s² along -z, which the script sets for the other two as well.
//!
//! Definitions, as close to `rl model bench` as dynibo's API allows:
//! fk = `forward_kinematics_all` (every link, fixed ones included), jacobian = `jacobian`
//! (world, target-link origin, its FK included), rnea = `inverse_dynamics`, nle =
//! `inverse_dynamics` with q̈ = 0 (dynibo has no C + G call), gravity = `gravity`, crba =
//! `mass_matrix` (full symmetric), aba = `forward_dynamics` with τ = its own RNEA of the state.

use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

use dynibo::{BaseState, FloatingRobot, Frame, IndexedLoad, LinkId, Robot, Twist};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};

const NO_LOADS: &[IndexedLoad] = &[];

/// A Pinocchio free-flyer state: q (x y z qx qy qz qw), v and a ([linear; angular], local).
type FreeFlyerState = ([f64; 7], [f64; 6], [f64; 6]);

/// States as read from the file, already in dynibo's joint order.
struct States {
    n: usize,
    /// Joint positions, velocities, accelerations (J each per state).
    q: Vec<Vec<f64>>,
    qd: Vec<Vec<f64>>,
    qdd: Vec<Vec<f64>>,
    /// The floating base: (q[7], v[6], a[6]) in Pinocchio's layout, when the file has one.
    base: Vec<Option<FreeFlyerState>>,
}

fn parse_states(text: &str, dynibo_names: &[String], floating: bool) -> Result<States, String> {
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut next = || lines.next().ok_or("the states file ends early".to_string());
    if next()? != "rl-bench-states 1" {
        return Err("not an rl-bench-states 1 file".into());
    }
    let h: Vec<usize> = next()?
        .split_whitespace()
        .skip(1)
        .step_by(2)
        .map(|x| x.parse().map_err(|_| "bad header line".to_string()))
        .collect::<Result<_, _>>()?;
    let [nq, nv, nj, n] = h[..] else {
        return Err("bad header line".into());
    };
    // File joints: name, nq, nv, offsets.
    let mut joints = Vec::new();
    let (mut oq, mut ov) = (0, 0);
    for _ in 0..nj {
        let f: Vec<String> = next()?.split_whitespace().map(String::from).collect();
        if f.len() != 4 || f[0] != "joint" {
            return Err("bad joint line".into());
        }
        let jq: usize = f[2].parse().map_err(|_| "bad joint nq")?;
        let jv: usize = f[3].parse().map_err(|_| "bad joint nv")?;
        joints.push((f[1].clone(), jq, jv, oq, ov));
        oq += jq;
        ov += jv;
    }
    if (oq, ov) != (nq, nv) {
        return Err("joint sizes do not add up to nq, nv".into());
    }
    // For each dynibo joint, its (q offset, v offset) in the file.
    let map: Vec<(usize, usize)> = dynibo_names
        .iter()
        .map(|name| {
            joints
                .iter()
                .find(|j| &j.0 == name)
                .filter(|j| j.1 == 1 && j.2 == 1)
                .map(|j| (j.3, j.4))
                .ok_or(format!(
                    "joint {name} of dynibo's model is not a 1-DoF joint of the file"
                ))
        })
        .collect::<Result<_, _>>()?;
    let root = joints.iter().find(|j| j.1 == 7 && j.2 == 6);
    if floating != root.is_some() || nj != dynibo_names.len() + usize::from(floating) {
        return Err("the file's joints do not match dynibo's model".into());
    }
    let mut s = States {
        n,
        q: vec![],
        qd: vec![],
        qdd: vec![],
        base: vec![],
    };
    for _ in 0..n {
        let x: Vec<f64> = next()?
            .split_whitespace()
            .skip(1)
            .map(|t| t.parse::<f64>().map_err(|_| "bad number".to_string()))
            .collect::<Result<_, _>>()?;
        if x.len() != nq + 2 * nv {
            return Err("short state line".into());
        }
        let (fq, rest) = x.split_at(nq);
        let (fv, fa) = rest.split_at(nv);
        s.q.push(map.iter().map(|&(q, _)| fq[q]).collect());
        s.qd.push(map.iter().map(|&(_, v)| fv[v]).collect());
        s.qdd.push(map.iter().map(|&(_, v)| fa[v]).collect());
        s.base.push(root.map(|r| {
            let mut q = [0.0; 7];
            let (mut v, mut a) = ([0.0; 6], [0.0; 6]);
            q.copy_from_slice(&fq[r.3..r.3 + 7]);
            v.copy_from_slice(&fv[r.4..r.4 + 6]);
            a.copy_from_slice(&fa[r.4..r.4 + 6]);
            (q, v, a)
        }));
    }
    Ok(s)
}

/// dynibo's `BaseState` for a Pinocchio free-flyer state; `with_acceleration = false` gives
/// zero base acceleration (for nle).
fn base_state((q, v, a): &FreeFlyerState, with_acceleration: bool) -> Result<BaseState, String> {
    let rot = UnitQuaternion::from_quaternion(Quaternion::new(q[6], q[3], q[4], q[5]));
    let frame: Frame = Isometry3::from_parts(Translation3::new(q[0], q[1], q[2]), rot);
    let (vl, wl) = (
        Vector3::new(v[0], v[1], v[2]),
        Vector3::new(v[3], v[4], v[5]),
    );
    let (al, dwl) = (
        Vector3::new(a[0], a[1], a[2]),
        Vector3::new(a[3], a[4], a[5]),
    );
    let velocity = Twist::new(rot * wl, rot * vl);
    let acceleration = if with_acceleration {
        Twist::new(rot * dwl, rot * (al + wl.cross(&vl)))
    } else {
        Twist::zeros()
    };
    BaseState::new(frame, velocity, acceleration).map_err(|e| e.to_string())
}

/// Median ns per call of `f` over all states, over `rounds` rounds (as `rl model bench`).
fn time_per_call(states: usize, rounds: usize, mut f: impl FnMut(usize)) -> f64 {
    let start = Instant::now();
    for s in 0..states {
        f(s);
    }
    let once = start.elapsed().as_secs_f64().max(1e-9);
    let reps = ((2e-3 / once).ceil() as usize).clamp(1, 10_000);
    let mut samples: Vec<f64> = (0..rounds)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..reps {
                for s in 0..states {
                    f(s);
                }
            }
            t.elapsed().as_secs_f64() * 1e9 / (reps * states) as f64
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

/// Median ns per algorithm and the RNEA check (Σ τ of the joints over all states).
type Timings = ([f64; 7], f64);

fn bench_fixed(
    robot: &mut Robot,
    link: LinkId,
    s: &States,
    rounds: usize,
) -> Result<Timings, String> {
    let g = robot.generalized_count();
    let e = |e: dynibo::Error| e.to_string();
    let mut frames = vec![Frame::identity(); robot.link_count()];
    let mut jac = vec![0.0; 6 * g];
    let mut out = vec![0.0; g];
    let mut mass = vec![0.0; g * g];
    let zeros = vec![0.0; g];
    let mut taus = Vec::with_capacity(s.n);
    for i in 0..s.n {
        robot
            .inverse_dynamics(&s.q[i], &s.qd[i], &s.qdd[i], NO_LOADS, &mut out)
            .map_err(e)?;
        taus.push(out.clone());
    }
    let check = taus.iter().flatten().sum();
    let r = rounds;
    let ns = [
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.forward_kinematics_all(black_box(&s.q[i]), &mut frames));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.jacobian(black_box(&s.q[i]), link, &mut jac));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.inverse_dynamics(
                black_box(&s.q[i]),
                &s.qd[i],
                &s.qdd[i],
                NO_LOADS,
                &mut out,
            ));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.inverse_dynamics(
                black_box(&s.q[i]),
                &s.qd[i],
                &zeros,
                NO_LOADS,
                &mut out,
            ));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.gravity(black_box(&s.q[i]), NO_LOADS, &mut out));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.mass_matrix(black_box(&s.q[i]), &mut mass));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.forward_dynamics(
                black_box(&s.q[i]),
                &s.qd[i],
                &taus[i],
                NO_LOADS,
                &mut out,
            ));
        }),
    ];
    Ok((ns, check))
}

fn bench_floating(
    robot: &mut FloatingRobot,
    link: LinkId,
    s: &States,
    rounds: usize,
) -> Result<Timings, String> {
    let g = robot.generalized_count();
    let e = |e: dynibo::Error| e.to_string();
    let mut frames = vec![Frame::identity(); robot.link_count()];
    let mut jac = vec![0.0; 6 * g];
    let mut out = vec![0.0; g];
    let mut mass = vec![0.0; g * g];
    let zeros = vec![0.0; robot.joint_count()];
    let mut bases = Vec::with_capacity(s.n);
    let mut bases0 = Vec::with_capacity(s.n);
    for b in &s.base {
        let b = b.as_ref().ok_or("a state has no floating-base values")?;
        bases.push(base_state(b, true)?);
        bases0.push(base_state(b, false)?);
    }
    let mut taus = Vec::with_capacity(s.n);
    for (i, base) in bases.iter().enumerate() {
        robot
            .inverse_dynamics(base, &s.q[i], &s.qd[i], &s.qdd[i], NO_LOADS, &mut out)
            .map_err(e)?;
        taus.push(out.clone());
    }
    // The six base entries are a world-frame wrench: left out of the check.
    let check = taus.iter().map(|t| t[6..].iter().sum::<f64>()).sum();
    let r = rounds;
    let ns = [
        time_per_call(s.n, r, |i| {
            let _ =
                black_box(robot.forward_kinematics_all(&bases[i], black_box(&s.q[i]), &mut frames));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.jacobian(&bases[i], black_box(&s.q[i]), link, &mut jac));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.inverse_dynamics(
                &bases[i],
                black_box(&s.q[i]),
                &s.qd[i],
                &s.qdd[i],
                NO_LOADS,
                &mut out,
            ));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.inverse_dynamics(
                &bases0[i],
                black_box(&s.q[i]),
                &s.qd[i],
                &zeros,
                NO_LOADS,
                &mut out,
            ));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.gravity(&bases0[i], black_box(&s.q[i]), NO_LOADS, &mut out));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.mass_matrix(&bases0[i], black_box(&s.q[i]), &mut mass));
        }),
        time_per_call(s.n, r, |i| {
            let _ = black_box(robot.forward_dynamics(
                &bases[i],
                black_box(&s.q[i]),
                &s.qd[i],
                &taus[i],
                NO_LOADS,
                &mut out,
            ));
        }),
    ];
    Ok((ns, check))
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 3 {
        return Err("usage: dynibo-bench URDF STATES LINK [--floating-base] [--rounds N]".into());
    }
    let (urdf, states_path, link_name) = (&args[0], &args[1], &args[2]);
    let (mut floating, mut rounds) = (false, 15usize);
    let mut rest = args[3..].iter();
    while let Some(a) = rest.next() {
        match a.as_str() {
            "--floating-base" => floating = true,
            "--rounds" => {
                rounds = rest
                    .next()
                    .and_then(|x| x.parse().ok())
                    .ok_or("--rounds needs a number")?;
            }
            other => return Err(format!("unknown argument {other}")),
        }
    }
    let rounds = rounds.max(1);
    let text = std::fs::read_to_string(states_path).map_err(|e| format!("{states_path}: {e}"))?;
    let e = |e: dynibo::Error| format!("{urdf}: {e}");
    let ((ns, check), dof) = if floating {
        let mut robot = FloatingRobot::from_urdf(urdf).map_err(e)?;
        let names = (0..robot.joint_count())
            .map(|k| robot.joint_name(k).map(String::from))
            .collect::<Result<Vec<_>, _>>()
            .map_err(e)?;
        let states = parse_states(&text, &names, true)?;
        let link = robot.link_id(link_name).map_err(e)?;
        (
            bench_floating(&mut robot, link, &states, rounds)?,
            robot.generalized_count(),
        )
    } else {
        let mut robot = Robot::from_urdf(urdf).map_err(e)?;
        let names = (0..robot.joint_count())
            .map(|k| robot.joint_name(k).map(String::from))
            .collect::<Result<Vec<_>, _>>()
            .map_err(e)?;
        let states = parse_states(&text, &names, false)?;
        let link = robot.link_id(link_name).map_err(e)?;
        (
            bench_fixed(&mut robot, link, &states, rounds)?,
            robot.generalized_count(),
        )
    };
    let keys = ["fk", "jacobian", "rnea", "nle", "gravity", "crba", "aba"];
    let fields: Vec<String> = keys
        .iter()
        .zip(ns)
        .map(|(k, v)| format!("\"{k}_ns\": {:.1}", v))
        .collect();
    // dynibo 0.5.3 has no analytical derivatives: those rows compare with Pinocchio alone.
    println!(
        "{{{}, \"drnea_ns\": null, \"daba_ns\": null, \"dof\": {dof}, \"tool\": \"{link_name}\", \"rnea_check\": {check:e}}}",
        fields.join(", ")
    );
    Ok(())
}

fn main() -> ExitCode {
    if cfg!(debug_assertions) {
        eprintln!("dynibo-bench: a debug build (debug assertions on): refusing to time");
        return ExitCode::FAILURE;
    }
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("dynibo-bench: {e}");
            ExitCode::FAILURE
        }
    }
}
