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
    /// URDF only: load joints that have a `<mimic>` tag as independent joints (as Pinocchio
    /// does) instead of refusing the file.
    #[arg(long)]
    pub mimic_independent: bool,
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
    /// Time these states instead of random ones: a file in the `rl-bench-states 1` format of
    /// scripts/bench-pinocchio (joints named, so any joint order maps by name).
    #[arg(long, value_name = "FILE")]
    states_file: Option<PathBuf>,
    /// Time the Jacobian of this tool (URDF: any link, added as a tool when it is not a
    /// leaf) instead of the first tool.
    #[arg(long, value_name = "NAME")]
    tool: Option<String>,
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
    load_with_tools(m, Vec::new())
}

/// Loads a model file with `extra_tools` (URDF link names) made tools after the leaves.
fn load_with_tools(
    m: &ModelFile,
    extra_tools: Vec<String>,
) -> Result<Box<LoadedModel<CAPACITY>>, CliError> {
    let options = UrdfOptions {
        floating_base: m.floating_base,
        joint_order: match m.joint_order {
            Order::File => JointOrder::File,
            Order::Pinocchio => JointOrder::Pinocchio,
        },
        extra_tools,
        mimic: if m.mimic_independent {
            loader::MimicJoints::Independent
        } else {
            loader::MimicJoints::Reject
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

/// Benchmark states in the model's own layout: `n` states of `q` (nq), `q̇` and `q̈` (dof).
#[derive(Debug, Clone, PartialEq)]
pub struct BenchStates {
    /// Number of states.
    pub n: usize,
    /// Positions, state after state.
    pub q: Vec<f64>,
    /// Velocities, state after state.
    pub qd: Vec<f64>,
    /// Accelerations, state after state.
    pub qdd: Vec<f64>,
}

impl BenchStates {
    /// `n` reproducible random states (SplitMix64 seed 0x5EED; positions within limits).
    pub fn random(model: &Model<CAPACITY>, n: usize) -> Self {
        let n = n.max(1);
        let mut rng = SplitMix(0x5EED);
        let (nq, nv) = (model.nq(), model.dof());
        let mut q = vec![0.0; nq * n];
        for s in 0..n {
            model.random_configuration(&mut q[s * nq..(s + 1) * nq], || rng.uniform());
        }
        let mut r = || rng.uniform() * 2.0 - 1.0;
        let qd = (0..nv * n).map(|_| r()).collect();
        let qdd = (0..nv * n).map(|_| r()).collect();
        Self { n, q, qd, qdd }
    }

    /// Parses a states file (`rl-bench-states 1`, written by scripts/bench-pinocchio) and maps
    /// its joints onto `model`'s by name: every moving joint of the model must appear once,
    /// with the same nq and nv.
    pub fn parse(model: &Model<CAPACITY>, text: &str) -> Result<Self, String> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty());
        let mut next = |what: &str| lines.next().ok_or(format!("file ends before the {what}"));
        let (_, magic) = next("header")?;
        if magic != "rl-bench-states 1" {
            return Err(format!(
                "line 1: expected \"rl-bench-states 1\", found {magic:?}"
            ));
        }
        let (ln, sizes) = next("sizes line")?;
        let f: Vec<&str> = sizes.split_whitespace().collect();
        let num = |i: usize| -> Result<usize, String> {
            f.get(i).and_then(|x| x.parse().ok()).ok_or(format!(
                "line {ln}: expected \"nq N nv N joints N states N\""
            ))
        };
        if f.len() != 8 || f[0] != "nq" || f[2] != "nv" || f[4] != "joints" || f[6] != "states" {
            return Err(format!(
                "line {ln}: expected \"nq N nv N joints N states N\""
            ));
        }
        let (fnq, fnv, nj, n) = (num(1)?, num(3)?, num(5)?, num(7)?);
        if n == 0 {
            return Err(format!("line {ln}: no states"));
        }
        // (our body index, offset in the file's q, offset in the file's v) per file joint.
        let mut map = Vec::with_capacity(nj);
        let (mut oq, mut ov) = (0, 0);
        for _ in 0..nj {
            let (ln, l) = next("joint lines")?;
            let f: Vec<&str> = l.split_whitespace().collect();
            let (Some(&"joint"), Some(name), Some(jq), Some(jv), 4) = (
                f.first(),
                f.get(1),
                f.get(2).and_then(|x| x.parse::<usize>().ok()),
                f.get(3).and_then(|x| x.parse::<usize>().ok()),
                f.len(),
            ) else {
                return Err(format!("line {ln}: expected \"joint NAME NQ NV\""));
            };
            let body = (0..model.body_count())
                .find(|&i| model.joint_name(i) == *name)
                .ok_or(format!("line {ln}: the model has no joint named {name}"))?;
            let j = model.joint(body);
            if (j.nq(), j.nv()) != (jq, jv) {
                return Err(format!(
                    "line {ln}: joint {name} has nq {jq}, nv {jv} in the file but {}, {} in the model",
                    j.nq(),
                    j.nv()
                ));
            }
            map.push((body, oq, ov));
            oq += jq;
            ov += jv;
        }
        let (nq, nv) = (model.nq(), model.dof());
        if (oq, ov) != (fnq, fnv) || (fnq, fnv) != (nq, nv) {
            return Err(format!(
                "the file's joints give nq {oq}, nv {ov} (header: {fnq}, {fnv}); the model has nq {nq}, nv {nv}"
            ));
        }
        let mut out = Self {
            n,
            q: vec![0.0; nq * n],
            qd: vec![0.0; nv * n],
            qdd: vec![0.0; nv * n],
        };
        for s in 0..n {
            let (ln, l) = next("state lines")?;
            let mut it = l.split_whitespace();
            if it.next() != Some("state") {
                return Err(format!(
                    "line {ln}: expected \"state\" and {} numbers",
                    nq + 2 * nv
                ));
            }
            let x: Vec<f64> = it
                .map(|t| t.parse::<f64>().ok().filter(|v| v.is_finite()))
                .collect::<Option<_>>()
                .ok_or(format!("line {ln}: a value is not a finite number"))?;
            if x.len() != nq + 2 * nv {
                return Err(format!(
                    "line {ln}: {} numbers, expected {}",
                    x.len(),
                    nq + 2 * nv
                ));
            }
            let (fq, rest) = x.split_at(nq);
            let (fv, fa) = rest.split_at(nv);
            for &(body, oq, ov) in &map {
                let j = model.joint(body);
                let (mq, mv) = (model.q_index(body), model.v_index(body));
                out.q[s * nq + mq..][..j.nq()].copy_from_slice(&fq[oq..oq + j.nq()]);
                out.qd[s * nv + mv..][..j.nv()].copy_from_slice(&fv[ov..ov + j.nv()]);
                out.qdd[s * nv + mv..][..j.nv()].copy_from_slice(&fa[ov..ov + j.nv()]);
            }
        }
        Ok(out)
    }
}

/// The sum of RNEA's τ over all states and all one-DOF joints: programs that time the same
/// states with other libraries print the same number (to ~1e-9 relative), which checks that the
/// states were mapped onto each library's joint order correctly. Multi-DOF joints (a floating
/// base) are left out because libraries express their forces in different frames.
pub fn rnea_check(model: &Model<CAPACITY>, states: &BenchStates) -> Result<f64, CliError> {
    let (nq, nv) = (model.nq(), model.dof());
    let mut d = Box::new(Data::<CAPACITY>::new());
    let mut sum = 0.0;
    for s in 0..states.n {
        let tau = algo::rnea(
            model,
            &mut d,
            &states.q[s * nq..(s + 1) * nq],
            &states.qd[s * nv..(s + 1) * nv],
            &states.qdd[s * nv..(s + 1) * nv],
        )
        .map_err(|e| CliError::failed(e.to_string()))?;
        sum += (0..model.body_count())
            .filter(|&i| model.joint(i).nv() == 1)
            .map(|i| tau[model.v_index(i)])
            .sum::<f64>();
    }
    Ok(sum)
}

/// Median ns per call for each of [`BENCH_KEYS`] on `model` over `states`, with the
/// Jacobian of tool index `tool`.
pub fn bench_states(
    model: &Model<CAPACITY>,
    states: &BenchStates,
    rounds: usize,
    tool: usize,
) -> Result<[f64; 7], CliError> {
    let nstates = states.n;
    let rounds = rounds.max(1);
    let (nq, nv) = (model.nq(), model.dof());
    if states.q.len() != nq * nstates
        || states.qd.len() != nv * nstates
        || states.qdd.len() != nv * nstates
    {
        return Err(CliError::usage(
            "the states do not fit the model's nq and dof",
        ));
    }
    if tool >= model.tools().len() {
        return Err(CliError::usage(
            "the model has no tool to compute a Jacobian for",
        ));
    }
    let mut d = Box::new(Data::<CAPACITY>::new());
    let mut jac = Box::new([[0.0; CAPACITY]; 6]);
    let q = |s: usize| &states.q[s * nq..(s + 1) * nq];
    let qd = |s: usize| &states.qd[s * nv..(s + 1) * nv];
    let qdd = |s: usize| &states.qdd[s * nv..(s + 1) * nv];
    // τ for ABA: RNEA of the states' accelerations, so ABA sees realistic torques.
    let mut taus = vec![0.0; nv * nstates];
    for s in 0..nstates {
        let t = algo::rnea(model, &mut d, q(s), qd(s), qdd(s))
            .map_err(|e| CliError::failed(e.to_string()))?;
        taus[s * nv..(s + 1) * nv].copy_from_slice(t);
    }
    let tau = |s: usize| &taus[s * nv..(s + 1) * nv];
    let mut out = [0.0; 7];
    out[0] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::forward_position(model, &mut d, black_box(q(s))));
    });
    out[1] = time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::jacobian(
            model,
            &mut d,
            black_box(q(s)),
            tool,
            &mut jac,
        ));
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
    let first = load(&a.model)?;
    let loaded = match a.tool.as_deref() {
        Some(t) if first.model.tool_index(t).is_none() => {
            load_with_tools(&a.model, vec![t.to_string()])?
        }
        _ => first,
    };
    let m = &loaded.model;
    let tool = match a.tool.as_deref() {
        None => 0,
        Some(t) => m.tool_index(t).ok_or_else(|| {
            let names: Vec<_> = m.tools().iter().map(|x| x.name.as_str()).collect();
            CliError::usage(format!(
                "--tool: the model has no tool or link named {t:?} (tools: {})",
                names.join(", ")
            ))
        })?,
    };
    let states = match &a.states_file {
        None => BenchStates::random(m, a.states),
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| CliError::usage(format!("--states-file {}: {e}", path.display())))?;
            BenchStates::parse(m, &text)
                .map_err(|e| CliError::usage(format!("--states-file {}: {e}", path.display())))?
        }
    };
    let ns = bench_states(m, &states, a.rounds, tool)?;
    if a.json {
        let mut obj = serde_json::Map::new();
        for (k, v) in BENCH_KEYS.iter().zip(ns) {
            obj.insert(format!("{k}_ns"), json!((v * 10.0).round() / 10.0));
        }
        obj.insert("dof".into(), json!(m.dof()));
        obj.insert("tool".into(), json!(m.tools()[tool].name.as_str()));
        obj.insert("states".into(), json!(states.n));
        if a.states_file.is_some() {
            obj.insert("rnea_check".into(), json!(rnea_check(m, &states)?));
        }
        println!("{}", serde_json::Value::Object(obj));
    } else {
        println!(
            "{} ({} DOF), median of {} rounds over {} random states, Jacobian of tool {:?}",
            m.name(),
            m.dof(),
            a.rounds,
            states.n,
            m.tools()[tool].name.as_str()
        );
        for (k, v) in BENCH_KEYS.iter().zip(ns) {
            println!("  {k:<10} {v:>10.1} ns");
        }
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two branches under the base: file order `j_b`, `j_a`; Pinocchio's order `j_a`, `j_b`.
    const URDF: &str = r#"<robot name="fork">
      <link name="base"/>
      <link name="b"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j_b" type="revolute"><parent link="base"/><child link="b"/><axis xyz="0 0 1"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
      <joint name="j_a" type="prismatic"><parent link="base"/><child link="a"/><axis xyz="1 0 0"/>
        <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    </robot>"#;

    fn model(order: JointOrder) -> Box<Model<CAPACITY>> {
        let options = UrdfOptions {
            joint_order: order,
            ..UrdfOptions::default()
        };
        Box::new(
            loader::load_urdf_str::<CAPACITY>(URDF, &options)
                .expect("test URDF loads")
                .model,
        )
    }

    const STATES: &str = "rl-bench-states 1\nnq 2 nv 2 joints 2 states 2\n\
        joint j_a 1 1\njoint j_b 1 1\n\
        state 0.1 0.2 1.1 1.2 2.1 2.2\nstate 0.3 0.4 1.3 1.4 2.3 2.4\n";

    #[test]
    fn states_map_by_joint_name() {
        let pin = BenchStates::parse(&model(JointOrder::Pinocchio), STATES).unwrap();
        assert_eq!(pin.n, 2);
        assert_eq!(pin.q, [0.1, 0.2, 0.3, 0.4]);
        assert_eq!(pin.qd, [1.1, 1.2, 1.3, 1.4]);
        assert_eq!(pin.qdd, [2.1, 2.2, 2.3, 2.4]);
        let file = model(JointOrder::File);
        assert_eq!(file.joint_name(0), "j_b");
        let s = BenchStates::parse(&file, STATES).unwrap();
        assert_eq!(s.q, [0.2, 0.1, 0.4, 0.3]);
        assert_eq!(s.qd, [1.2, 1.1, 1.4, 1.3]);
        assert_eq!(s.qdd, [2.2, 2.1, 2.4, 2.3]);
    }

    #[test]
    fn bad_states_files_name_the_problem() {
        let m = model(JointOrder::Pinocchio);
        let err = |text: &str| BenchStates::parse(&m, text).unwrap_err();
        assert!(err("hello").contains("rl-bench-states 1"));
        assert!(err(&STATES.replace("j_b 1 1", "j_c 1 1")).contains("no joint named j_c"));
        assert!(err(&STATES.replace("j_b 1 1", "j_b 2 1")).contains("nq 2, nv 1"));
        assert!(err(&STATES.replace("0.4 1.3", "0.4")).contains("line 6: 5 numbers, expected 6"));
        assert!(err(&STATES.replace("2.4", "nan")).contains("not a finite number"));
        assert!(err(&STATES.replace("states 2", "states 3")).contains("ends before"));
    }

    #[test]
    fn bench_states_times_every_algorithm() {
        let m = model(JointOrder::Pinocchio);
        let s = BenchStates::parse(&m, STATES).unwrap();
        let ns = bench_states(&m, &s, 1, 0).unwrap();
        // The same states seen through the other joint order give the same check.
        let check = rnea_check(&m, &s).unwrap();
        let file = model(JointOrder::File);
        let other = rnea_check(&file, &BenchStates::parse(&file, STATES).unwrap()).unwrap();
        assert!(check.abs() > 1e-3 && (check - other).abs() <= 1e-12 * check.abs());
        assert!(ns.iter().all(|&t| t.is_finite() && t > 0.0), "{ns:?}");
        assert!(bench_states(&m, &s, 1, m.tools().len()).is_err());
    }
}
