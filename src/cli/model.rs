//! `rl model info | eval | bench`: see what a model file describes, evaluate its kinematics
//! and dynamics at one state, and time the algorithms on this machine.

use std::hint::black_box;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Subcommand, ValueEnum};
use rl_core::algo;
use rl_core::joint::Joint;
use rl_core::loader::{self, JointOrder, LoadedModel, UrdfOptions};
use rl_core::model::ROOT;
use rl_core::{Data, Model};
use serde_json::json;

use super::{CliError, CliResult};

/// Capacity of models loaded at run time: bodies and degrees of freedom.
pub const CAPACITY: usize = 64;

/// `rl model` subcommands.
#[derive(Subcommand, Debug)]
pub enum ModelCommand {
    /// Joints (name, type, parent, limits), DOF, total mass and tools of a model file.
    Info(InfoArgs),
    /// Evaluate kinematics and dynamics at one state; prints JSON.
    Eval(EvalArgs),
    /// Median nanoseconds per call of each algorithm over random states.
    Bench(BenchArgs),
}

/// How to read a model file.
#[derive(Args, Debug, Clone)]
pub struct ModelFile {
    /// A URDF or RL XML (rlmdl) model file.
    pub file: PathBuf,
    /// URDF only: add a six-DOF root joint (a floating base, as Pinocchio's free-flyer).
    #[arg(long)]
    pub floating_base: bool,
    /// URDF only: number sibling joints in file order (RL) or by name (Pinocchio).
    #[arg(long, value_enum, default_value_t = Order::File)]
    pub joint_order: Order,
}

/// Sibling joint order for URDF files.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    /// Depth-first, children in file order (RL's order).
    File,
    /// Depth-first, children by joint name (Pinocchio's order, from urdfdom's sorted map).
    Pinocchio,
}

/// Arguments of `rl model info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    #[command(flatten)]
    model: ModelFile,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// Arguments of `rl model eval`.
#[derive(Args, Debug)]
pub struct EvalArgs {
    #[command(flatten)]
    model: ModelFile,
    /// Joint positions, comma-separated (nq values; quaternions as x,y,z,w).
    #[arg(long, allow_hyphen_values = true)]
    q: String,
    /// Joint velocities (dof values; default zeros).
    #[arg(long, allow_hyphen_values = true)]
    qd: Option<String>,
    /// Joint accelerations (dof values; default zeros).
    #[arg(long, allow_hyphen_values = true)]
    qdd: Option<String>,
    /// Joint torques for forward dynamics (dof values; default zeros).
    #[arg(long, allow_hyphen_values = true)]
    tau: Option<String>,
    /// Physical gravitational acceleration gx,gy,gz in m/s² (default: the file's own).
    #[arg(long, allow_hyphen_values = true)]
    gravity: Option<String>,
}

/// Arguments of `rl model bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    model: ModelFile,
    /// Print JSON (keys fk_ns, jacobian_ns, rnea_ns, nle_ns, gravity_ns, crba_ns, aba_ns).
    #[arg(long)]
    json: bool,
    /// Number of random states.
    #[arg(long, default_value_t = 64)]
    states: usize,
    /// Number of timed rounds (the median is reported).
    #[arg(long, default_value_t = 15)]
    rounds: usize,
}

/// Runs `rl model`.
pub fn run(cmd: ModelCommand) -> CliResult {
    match cmd {
        ModelCommand::Info(a) => info(a),
        ModelCommand::Eval(a) => eval(a),
        ModelCommand::Bench(a) => bench(a),
    }
}

/// Loads a model file into a boxed model of [`CAPACITY`].
pub fn load(m: &ModelFile) -> Result<Box<LoadedModel<CAPACITY>>, CliError> {
    let options = UrdfOptions {
        floating_base: m.floating_base,
        joint_order: match m.joint_order {
            Order::File => JointOrder::File,
            Order::Pinocchio => JointOrder::Pinocchio,
        },
        ..UrdfOptions::default()
    };
    loader::load_file_with::<CAPACITY>(&m.file, &options)
        .map(Box::new)
        .map_err(|e| CliError::usage(e.to_string()))
}

fn joint_type(j: &Joint) -> &'static str {
    j.kind().name()
}

fn info(a: InfoArgs) -> CliResult {
    let loaded = load(&a.model)?;
    let m = &loaded.model;
    let parent_name = |i: usize| match m.parent(i) {
        ROOT => "world".to_string(),
        p => m.body_name(p).to_string(),
    };
    let tools: Vec<_> = m
        .tools()
        .iter()
        .map(|t| {
            let body = if t.body == ROOT {
                "world"
            } else {
                m.body_name(t.body)
            };
            (t.name.as_str().to_string(), body.to_string())
        })
        .collect();
    let total_mass = m.moving_mass() + m.base_mass();
    if a.json {
        let joints: Vec<_> = (0..m.body_count())
            .map(|i| {
                let sv = m.v_index(i);
                let limits: Vec<_> = (sv..sv + m.joint(i).nv())
                    .map(|k| {
                        let l = m.limits(k);
                        json!({"lower": finite(l.lower), "upper": finite(l.upper),
                               "velocity": finite(l.velocity), "effort": finite(l.effort),
                               "wraparound": l.wraparound})
                    })
                    .collect();
                json!({"name": m.joint_name(i), "type": joint_type(m.joint(i)),
                       "body": m.body_name(i), "parent": parent_name(i),
                       "nq": m.joint(i).nq(), "nv": m.joint(i).nv(), "limits": limits})
            })
            .collect();
        let out = json!({"name": m.name(), "format": format!("{:?}", loaded.format),
            "dof": m.dof(), "nq": m.nq(), "bodies": m.body_count(),
            "mass": total_mass, "moving_mass": m.moving_mass(),
            "gravity": m.gravity().to_array(), "joints": joints,
            "tools": tools.iter().map(|(n, b)| json!({"name": n, "body": b})).collect::<Vec<_>>()});
        println!("{}", serde_json::to_string_pretty(&out).unwrap_or_default());
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "model      {} ({:?}, {})",
        m.name(),
        loaded.format,
        a.model.file.display()
    );
    println!(
        "dof        {} (nq {}), {} moving bodies",
        m.dof(),
        m.nq(),
        m.body_count()
    );
    println!(
        "mass       {:.6} kg ({:.6} kg moving)",
        total_mass,
        m.moving_mass()
    );
    let g = m.gravity();
    println!("gravity    ({}, {}, {}) m/s²", g.x, g.y, g.z);
    println!();
    println!(
        "{:<4} {:<24} {:<12} {:<24} {:>12} {:>12} {:>10} {:>10}",
        "#", "joint", "type", "parent", "lower", "upper", "speed", "effort"
    );
    for i in 0..m.body_count() {
        let sv = m.v_index(i);
        for k in sv..sv + m.joint(i).nv() {
            let l = m.limits(k);
            let first = k == sv;
            println!(
                "{:<4} {:<24} {:<12} {:<24} {:>12} {:>12} {:>10} {:>10}",
                k,
                if first { m.joint_name(i) } else { "" },
                if first { joint_type(m.joint(i)) } else { "" },
                if first { parent_name(i) } else { String::new() },
                if l.wraparound {
                    "wrap".into()
                } else {
                    num(l.lower)
                },
                if l.wraparound {
                    "wrap".into()
                } else {
                    num(l.upper)
                },
                num(l.velocity),
                num(l.effort),
            );
        }
    }
    println!();
    println!("tools      {}", tools.len());
    for (i, (n, b)) in tools.iter().enumerate() {
        println!("  {i}: {n} (on {b})");
    }
    for w in &loaded.warnings {
        println!("warning: {w}");
    }
    Ok(ExitCode::SUCCESS)
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.4}")
    } else {
        "-".into()
    }
}

/// Parses a comma-separated vector argument of exactly `n` numbers.
fn parse_vec(name: &str, s: Option<&str>, n: usize) -> Result<Vec<f64>, CliError> {
    let Some(s) = s else { return Ok(vec![0.0; n]) };
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim())
        .enumerate()
        .map(|(i, x)| {
            x.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    CliError::usage(format!(
                        "--{name}: element {i} ({x:?}) is not a finite number"
                    ))
                })
        })
        .collect::<Result<_, _>>()?;
    if v.len() != n {
        return Err(CliError::usage(format!(
            "--{name}: {} values given, the model needs {n}",
            v.len()
        )));
    }
    Ok(v)
}

fn eval(a: EvalArgs) -> CliResult {
    let mut loaded = load(&a.model)?;
    if let Some(g) = a.gravity.as_deref() {
        let g = parse_vec("gravity", Some(g), 3)?;
        loaded.model.set_gravity(glam::DVec3::new(g[0], g[1], g[2]));
    }
    let m = &loaded.model;
    let n = m.dof();
    let q = parse_vec("q", Some(&a.q), m.nq())?;
    let qd = parse_vec("qd", a.qd.as_deref(), n)?;
    let qdd = parse_vec("qdd", a.qdd.as_deref(), n)?;
    let tau_in = parse_vec("tau", a.tau.as_deref(), n)?;
    let fail = |e: rl_core::Error| CliError::failed(e.to_string());
    let mut d = Box::new(Data::<CAPACITY>::new());
    let tau = algo::rnea(m, &mut d, &q, &qd, &qdd).map_err(fail)?.to_vec();
    let gravity = algo::gravity(m, &mut d, &q).map_err(fail)?.to_vec();
    let coriolis = algo::coriolis(m, &mut d, &q, &qd).map_err(fail)?.to_vec();
    let qdd_out = algo::aba(m, &mut d, &q, &qd, &tau_in)
        .map_err(fail)?
        .to_vec();
    algo::crba(m, &mut d, &q).map_err(fail)?;
    let mass: Vec<Vec<f64>> = (0..n)
        .map(|r| (0..n).map(|c| d.mass_matrix(r, c)).collect())
        .collect();
    let mut jac = Box::new([[0.0; CAPACITY]; 6]);
    let mut tools = Vec::new();
    for (t, tool) in m.tools().iter().enumerate() {
        algo::jacobian(m, &mut d, &q, t, &mut jac).map_err(fail)?;
        let x = algo::tool_pose(m, &d, t).map_err(fail)?;
        let quat = x.quaternion();
        tools.push(json!({
            "name": tool.name.as_str(),
            "position": x.translation.to_array(),
            "quaternion_wxyz": [quat.w, quat.x, quat.y, quat.z],
            "jacobian": jac.iter().map(|row| row[..n].to_vec()).collect::<Vec<_>>(),
        }));
    }
    let out = json!({
        "dof": n, "nq": m.nq(), "tau": tau, "gravity": gravity, "coriolis": coriolis,
        "qdd": qdd_out, "mass_matrix": mass, "tools": tools,
    });
    println!("{}", serde_json::to_string(&out).unwrap_or_default());
    Ok(ExitCode::SUCCESS)
}

/// A SplitMix64 stream of uniform numbers in [0, 1), for reproducible benchmark states.
struct SplitMix(u64);

impl SplitMix {
    fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Median nanoseconds per call of `f` over all states, over `rounds` rounds.
fn time_per_call(states: usize, rounds: usize, mut f: impl FnMut(usize)) -> f64 {
    // Enough repetitions per round for ~2 ms of work.
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

/// The algorithms `rl model bench` times, with their JSON keys.
pub const BENCH_KEYS: [&str; 7] = ["fk", "jacobian", "rnea", "nle", "gravity", "crba", "aba"];

/// Median ns per call for each of [`BENCH_KEYS`] on `model`.
pub fn bench_model(
    model: &Model<CAPACITY>,
    nstates: usize,
    rounds: usize,
) -> Result<[f64; 7], CliError> {
    let nstates = nstates.max(1);
    let rounds = rounds.max(1);
    let mut rng = SplitMix(0x5EED);
    let (nq, nv) = (model.nq(), model.dof());
    let mut qs = vec![0.0; nq * nstates];
    for s in 0..nstates {
        model.random_configuration(&mut qs[s * nq..(s + 1) * nq], || rng.uniform());
    }
    let mut r = || rng.uniform() * 2.0 - 1.0;
    let qds: Vec<f64> = (0..nv * nstates).map(|_| r()).collect();
    let qdds: Vec<f64> = (0..nv * nstates).map(|_| r()).collect();
    let mut d = Box::new(Data::<CAPACITY>::new());
    let mut jac = Box::new([[0.0; CAPACITY]; 6]);
    let q = |s: usize| &qs[s * nq..(s + 1) * nq];
    let qd = |s: usize| &qds[s * nv..(s + 1) * nv];
    let qdd = |s: usize| &qdds[s * nv..(s + 1) * nv];
    // τ for ABA: RNEA of the random accelerations, so ABA sees realistic torques.
    let mut taus = vec![0.0; nv * nstates];
    for s in 0..nstates {
        let t = algo::rnea(model, &mut d, q(s), qd(s), qdd(s))
            .map_err(|e| CliError::failed(e.to_string()))?;
        taus[s * nv..(s + 1) * nv].copy_from_slice(t);
    }
    let tau = |s: usize| &taus[s * nv..(s + 1) * nv];
    if model.tools().is_empty() {
        return Err(CliError::usage(
            "the model has no tool to compute a Jacobian for",
        ));
    }
    let mut out = [0.0; 7];
    out[0] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::forward_position(model, &mut d, black_box(q(s))));
    });
    out[1] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::jacobian(model, &mut d, black_box(q(s)), 0, &mut jac));
    });
    out[2] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::rnea(model, &mut d, black_box(q(s)), qd(s), qdd(s)).map(|t| t[0]));
    });
    out[3] = time_per_call(nstates, rounds, |s| {
        let _ =
            black_box(algo::nonlinear_effects(model, &mut d, black_box(q(s)), qd(s)).map(|t| t[0]));
    });
    out[4] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::gravity(model, &mut d, black_box(q(s))).map(|t| t[0]));
    });
    out[5] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::crba(model, &mut d, black_box(q(s))));
    });
    out[6] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::aba(model, &mut d, black_box(q(s)), qd(s), tau(s)).map(|t| t[0]));
    });
    Ok(out)
}

fn bench(a: BenchArgs) -> CliResult {
    let loaded = load(&a.model)?;
    let m = &loaded.model;
    let ns = bench_model(m, a.states, a.rounds)?;
    if a.json {
        let mut obj = serde_json::Map::new();
        for (k, v) in BENCH_KEYS.iter().zip(ns) {
            obj.insert(format!("{k}_ns"), json!((v * 10.0).round() / 10.0));
        }
        obj.insert("dof".into(), json!(m.dof()));
        obj.insert("tool".into(), json!(m.tools()[0].name.as_str()));
        println!("{}", serde_json::Value::Object(obj));
    } else {
        println!(
            "{} ({} DOF), median of {} rounds over {} random states, Jacobian of tool {:?}",
            m.name(),
            m.dof(),
            a.rounds,
            a.states,
            m.tools()[0].name.as_str()
        );
        for (k, v) in BENCH_KEYS.iter().zip(ns) {
            println!("  {k:<10} {v:>10.1} ns");
        }
    }
    Ok(ExitCode::SUCCESS)
}
