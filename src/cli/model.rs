//! `rl model info | eval | bench`: see what a model file describes, evaluate its kinematics
//! and dynamics at one state, and time the algorithms on this machine.
//!
//! Every file loads into the smallest capacity that holds it ([`super::capacity`]); each
//! subcommand is a [`WithModel`] job, monomorphised per capacity.

use std::hint::black_box;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Subcommand, ValueEnum};
use rl_core::algo;
use rl_core::loader::{self, InertiaCheck, JointOrder, LoadOptions, LoadedModel, UrdfOptions};
use rl_core::model::DerivativeData;
use rl_core::model::ROOT;
use rl_core::{Data, Model};
use serde_json::json;

use super::capacity::{self, WithModel};
use super::output::{errln, outln};
use super::{CliError, CliResult, refuse_given};

/// Most benchmark states (`--states`): 100 000 states of a 256-DOF model take about 600 MB.
pub const MAX_STATES: usize = 100_000;
/// Most timed rounds (`--rounds`).
pub const MAX_ROUNDS: usize = 10_000;

/// `rl model` subcommands.
#[derive(Subcommand, Debug)]
pub enum ModelCommand {
    /// Joints (name, type, parent, limits, mimic relations), DOF, total mass and tools of a
    /// model file.
    Info(InfoArgs),
    /// Evaluate kinematics and dynamics at one state; prints JSON.
    Eval(EvalArgs),
    /// Median nanoseconds per call of each algorithm over random states.
    Bench(BenchArgs),
}

/// How to read a model file.
#[derive(Args, Debug, Clone)]
pub struct ModelFile {
    /// A URDF or RL XML model file (rlmdl, or rlkin: RL's Denavit–Hartenberg kinematics).
    pub file: PathBuf,
    /// URDF only: add a six-DOF root joint (a floating base, as Pinocchio's free-flyer).
    #[arg(long)]
    pub floating_base: bool,
    /// URDF only: number sibling joints in file order (RL) or by name (Pinocchio).
    #[arg(long, value_enum, default_value_t = Order::File)]
    pub joint_order: Order,
    /// URDF only: load joints that have a `<mimic>` tag as independent joints (Pinocchio's
    /// default) instead of following their leaders (`q = multiplier · q_leader + offset`, no
    /// degree of freedom of their own).
    #[arg(long)]
    pub mimic_independent: bool,
    /// What an inertia no rigid body can have is: strict refuses one that is not positive
    /// semi-definite or breaks the triangle inequality I₁ + I₂ ≥ I₃; definite refuses the
    /// first and warns about the second; lenient warns about both.
    #[arg(long, value_enum, default_value_t = InertiaArg::Definite)]
    pub inertia_check: InertiaArg,
}

/// `--inertia-check`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum InertiaArg {
    /// Refuse inertias that are not positive semi-definite or break the triangle inequality.
    Strict,
    /// Refuse inertias that are not positive semi-definite; warn about the triangle inequality.
    Definite,
    /// Warn about both.
    Lenient,
}

/// Sibling joint order for URDF files.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Order {
    /// Depth-first, children in file order (RL's order).
    File,
    /// Depth-first, children by joint name (Pinocchio's order, from urdfdom's sorted map).
    Pinocchio,
}

impl ModelFile {
    /// A file read with the defaults.
    pub fn with_defaults(file: PathBuf) -> Self {
        Self {
            file,
            floating_base: false,
            joint_order: Order::File,
            mimic_independent: false,
            inertia_check: InertiaArg::Definite,
        }
    }

    /// The loader options these flags ask for, with `extra_tools` made tools after the leaves.
    pub fn options(&self, extra_tools: Vec<String>) -> LoadOptions {
        LoadOptions {
            urdf: UrdfOptions {
                floating_base: self.floating_base,
                joint_order: match self.joint_order {
                    Order::File => JointOrder::File,
                    Order::Pinocchio => JointOrder::Pinocchio,
                },
                extra_tools,
                mimic: if self.mimic_independent {
                    loader::MimicJoints::Independent
                } else {
                    loader::MimicJoints::Follow
                },
                ..UrdfOptions::default()
            },
            inertia: match self.inertia_check {
                InertiaArg::Strict => InertiaCheck::Strict,
                InertiaArg::Definite => InertiaCheck::Definite,
                InertiaArg::Lenient => InertiaCheck::Lenient,
            },
            ..LoadOptions::default()
        }
    }

    /// Loads the file and runs `job` on it.
    pub fn load<J: WithModel>(&self, job: J) -> Result<J::Output, CliError> {
        capacity::load(&self.file, &self.options(Vec::new()), job)
    }
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
    /// Joint positions, comma-separated (nq values; quaternions as x,y,z,w, of unit norm)
    /// [default: RL's home position, or the neutral one].
    #[arg(long, allow_hyphen_values = true)]
    q: Option<String>,
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
    /// Normalise the quaternions in --q instead of refusing ones that are not of unit norm.
    #[arg(long)]
    normalize: bool,
    /// Add the analytical derivatives (row-major nested lists, dof × dof, Pinocchio's
    /// tangent-space convention): drnea_dq, drnea_dv of RNEA at (q, qd, qdd) and daba_dq,
    /// daba_dv of ABA at (q, qd, tau).
    #[arg(long)]
    derivatives: bool,
}

/// Arguments of `rl model bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    model: ModelFile,
    /// Print JSON (keys fk_ns, jacobian_ns, rnea_ns, nle_ns, gravity_ns, crba_ns, aba_ns,
    /// drnea_ns, daba_ns).
    #[arg(long)]
    json: bool,
    /// Number of random states (1 to 100 000).
    #[arg(long, default_value_t = 64)]
    states: usize,
    /// Number of timed rounds, the median is reported (1 to 10 000).
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
        ModelCommand::Info(a) => {
            let m = a.model.clone();
            m.load(Info(a))
        }
        ModelCommand::Eval(a) => {
            let m = a.model.clone();
            m.load(Eval(a))
        }
        ModelCommand::Bench(a) => bench(a),
    }
}

fn joint_type<const N: usize>(m: &Model<N>, i: usize) -> String {
    let kind = m.joint(i).kind().name();
    if m.mimic(i).is_some() {
        format!("{kind} (mimic)")
    } else {
        kind.to_string()
    }
}

/// The warnings of a load, on standard error (for the commands whose output is data).
fn warn<const N: usize>(loaded: &LoadedModel<N>) {
    for w in &loaded.warnings {
        errln!("rl: warning: {w}");
    }
}

/// An algorithm's error, naming the joint where the error has one.
fn algo_error<const N: usize>(m: &Model<N>, e: rl_core::Error) -> CliError {
    match e {
        rl_core::Error::NotPositiveDefinite { dof } if dof < m.dof() => CliError::failed(format!(
            "the mass matrix cannot be factorised: joint \"{}\" (DOF {dof}) moves no mass \
                 or inertia along its axis here (its subtree is massless), so forward dynamics \
                 are undefined; give the links it moves an inertia",
            m.joint_name(m.dof_body(dof))
        )),
        e => CliError::failed(e.to_string()),
    }
}

struct Info(InfoArgs);

impl WithModel for Info {
    type Output = ExitCode;

    fn run<const N: usize>(self, loaded: Box<LoadedModel<N>>) -> CliResult {
        info(&self.0, &loaded)
    }
}

fn info<const N: usize>(a: &InfoArgs, loaded: &LoadedModel<N>) -> CliResult {
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
                let limits: Vec<_> = (sv..sv + m.joint_nv(i))
                    .map(|k| {
                        let l = m.limits(k);
                        json!({"lower": finite(l.lower), "upper": finite(l.upper),
                               "velocity": finite(l.velocity), "effort": finite(l.effort),
                               "wraparound": l.wraparound})
                    })
                    .collect();
                let mimic = m.mimic(i).map(|x| {
                    json!({"leader": m.joint_name(x.leader), "multiplier": x.multiplier,
                           "offset": x.offset})
                });
                json!({"name": m.joint_name(i), "type": m.joint(i).kind().name(),
                       "body": m.body_name(i), "parent": parent_name(i),
                       "nq": m.joint_nq(i), "nv": m.joint_nv(i), "limits": limits,
                       "mimic": mimic})
            })
            .collect();
        let out = rl::json::versioned(
            "model.info",
            1,
            json!({"name": m.name(),
            "format": format!("{:?}", loaded.format),
            "dof": m.dof(), "nq": m.nq(), "bodies": m.body_count(),
            "mass_kg": total_mass, "moving_mass_kg": m.moving_mass(),
            "gravity_m_s2": m.gravity().to_array(), "joints": joints,
            "tools": tools.iter().map(|(n, b)| json!({"name": n, "body": b})).collect::<Vec<_>>(),
            "warnings": loaded.warnings}),
        );
        outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default())?;
        return Ok(ExitCode::SUCCESS);
    }
    outln!(
        "model      {} ({:?}, {})",
        m.name(),
        loaded.format,
        a.model.file.display()
    )?;
    let mimics = (0..m.body_count())
        .filter(|&i| m.mimic(i).is_some())
        .count();
    outln!(
        "dof        {} (nq {}), {} moving bodies{}",
        m.dof(),
        m.nq(),
        m.body_count(),
        if mimics > 0 {
            format!(", {mimics} of them on mimic joints")
        } else {
            String::new()
        }
    )?;
    outln!(
        "mass       {:.6} kg ({:.6} kg moving)",
        total_mass,
        m.moving_mass()
    )?;
    let g = m.gravity();
    outln!("gravity    ({}, {}, {}) m/s²", g.x, g.y, g.z)?;
    outln!()?;
    outln!(
        "{:<4} {:<24} {:<18} {:<24} {:>12} {:>12} {:>10} {:>10}",
        "#",
        "joint",
        "type",
        "parent",
        "lower",
        "upper",
        "speed",
        "effort"
    )?;
    for i in 0..m.body_count() {
        if let Some(x) = m.mimic(i) {
            outln!(
                "{:<4} {:<24} {:<18} {:<24} q = {} · q({}) {} {}",
                "-",
                m.joint_name(i),
                joint_type(m, i),
                parent_name(i),
                x.multiplier,
                m.joint_name(x.leader),
                if x.offset < 0.0 { '-' } else { '+' },
                x.offset.abs()
            )?;
            continue;
        }
        let sv = m.v_index(i);
        for k in sv..sv + m.joint_nv(i) {
            let l = m.limits(k);
            let first = k == sv;
            outln!(
                "{:<4} {:<24} {:<18} {:<24} {:>12} {:>12} {:>10} {:>10}",
                k,
                if first { m.joint_name(i) } else { "" },
                if first {
                    joint_type(m, i)
                } else {
                    String::new()
                },
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
            )?;
        }
    }
    outln!()?;
    outln!("tools      {}", tools.len())?;
    for (i, (n, b)) in tools.iter().enumerate() {
        outln!("  {i}: {n} (on {b})")?;
    }
    for w in &loaded.warnings {
        outln!("warning: {w}")?;
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

/// Parses a comma-separated vector argument of exactly `n` numbers (`None`: `n` zeros; an
/// empty string: no numbers).
fn parse_vec(name: &str, s: Option<&str>, n: usize) -> Result<Vec<f64>, CliError> {
    let Some(s) = s else { return Ok(vec![0.0; n]) };
    let v: Vec<f64> = if s.trim().is_empty() {
        Vec::new()
    } else {
        s.split(',')
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
            .collect::<Result<_, _>>()?
    };
    if v.len() != n {
        return Err(CliError::usage(format!(
            "--{name}: {} values given, the model needs {n}",
            v.len()
        )));
    }
    Ok(v)
}

struct Eval(EvalArgs);

impl WithModel for Eval {
    type Output = ExitCode;

    fn run<const N: usize>(self, loaded: Box<LoadedModel<N>>) -> CliResult {
        eval(&self.0, loaded)
    }
}

fn eval<const N: usize>(a: &EvalArgs, mut loaded: Box<LoadedModel<N>>) -> CliResult {
    if a.q.is_none() {
        refuse_given(
            &["normalize"],
            "without --q: the home and neutral positions have unit quaternions",
        )?;
    }
    warn(&loaded);
    if let Some(g) = a.gravity.as_deref() {
        let g = parse_vec("gravity", Some(g), 3)?;
        loaded.model.set_gravity(glam::DVec3::new(g[0], g[1], g[2]));
    }
    let m = &loaded.model;
    let n = m.dof();
    let mut q = match a.q.as_deref() {
        Some(text) => parse_vec("q", Some(text), m.nq())?,
        None => loaded.home_or_neutral(),
    };
    check_quaternions(m, &mut q, a.normalize)?;
    let qd = parse_vec("qd", a.qd.as_deref(), n)?;
    let qdd = parse_vec("qdd", a.qdd.as_deref(), n)?;
    let tau_in = parse_vec("tau", a.tau.as_deref(), n)?;
    let fail = |e: rl_core::Error| algo_error(m, e);
    let mut d = Box::new(Data::<N>::new());
    let tau = algo::rnea(m, &mut d, &q, &qd, &qdd).map_err(fail)?.to_vec();
    let gravity = algo::gravity(m, &mut d, &q).map_err(fail)?.to_vec();
    let coriolis = algo::coriolis(m, &mut d, &q, &qd).map_err(fail)?.to_vec();
    algo::crba(m, &mut d, &q).map_err(fail)?;
    let mass: Vec<Vec<f64>> = (0..n)
        .map(|r| (0..n).map(|c| d.mass_matrix(r, c)).collect())
        .collect();
    // Forward dynamics needs an invertible mass matrix; without one the rest is still useful.
    let (qdd_out, forward_error) = match algo::aba(m, &mut d, &q, &qd, &tau_in) {
        Ok(x) => (Some(x.to_vec()), None),
        Err(e) => {
            let e = fail(e).to_string();
            errln!("rl: warning: no forward dynamics (\"qdd\": null): {e}");
            (None, Some(e))
        }
    };
    let mut jac = Box::new([[0.0; N]; 6]);
    let mut tools = Vec::new();
    for (t, tool) in m.tools().iter().enumerate() {
        algo::jacobian(m, &mut d, &q, t, &mut jac).map_err(fail)?;
        let x = algo::tool_pose(m, &d, t).map_err(fail)?;
        let quat = x.quaternion();
        tools.push(json!({
            "name": tool.name.as_str(),
            "position": x.translation.to_array(),
            // x, y, z, w: the order of every quaternion the tool prints or reads.
            "quat_xyzw": [quat.x, quat.y, quat.z, quat.w],
            "jacobian": jac.iter().map(|row| row[..n].to_vec()).collect::<Vec<_>>(),
        }));
    }
    let mut out = json!({
        "dof": n, "nq": m.nq(), "q": q, "tau": tau, "gravity": gravity, "coriolis": coriolis,
        "qdd": qdd_out, "mass_matrix": mass, "tools": tools,
    });
    if a.derivatives {
        let rows = |m: rl_core::model::MatrixView<'_, N>| -> Vec<Vec<f64>> {
            m.rows().map(<[f64]>::to_vec).collect()
        };
        let mut deriv = Box::new(DerivativeData::<N>::new());
        let r = algo::rnea_derivatives(m, &mut d, &mut deriv, &q, &qd, &qdd).map_err(fail)?;
        out["drnea_dq"] = json!(rows(r.dtau_dq));
        out["drnea_dv"] = json!(rows(r.dtau_dv));
        // Like "qdd": null when forward dynamics are undefined (the error is in "qdd_error").
        match algo::aba_derivatives(m, &mut d, &mut deriv, &q, &qd, &tau_in) {
            Ok(r) => {
                out["daba_dq"] = json!(rows(r.ddq_dq));
                out["daba_dv"] = json!(rows(r.ddq_dv));
            }
            Err(_) => {
                out["daba_dq"] = json!(null);
                out["daba_dv"] = json!(null);
            }
        }
    }
    if let Some(e) = forward_error {
        out["qdd_error"] = json!(e);
    }
    rl::json::tag("model.eval", 1, &mut out);
    outln!("{}", serde_json::to_string(&out).unwrap_or_default())?;
    Ok(ExitCode::SUCCESS)
}

/// Refuses (or with `normalize`, normalises) quaternions in `q` that are not of unit norm,
/// naming the joint, the elements and the norm.
fn check_quaternions<const N: usize>(
    m: &Model<N>,
    q: &mut [f64],
    normalize: bool,
) -> Result<(), CliError> {
    let found: Vec<_> = m.unit_quaternion_errors(q).collect();
    for bad in found {
        let at = bad.q_index;
        let joint = m.joint_name(bad.body);
        if normalize && bad.norm > 0.0 {
            for x in &mut q[at..at + 4] {
                *x /= bad.norm;
            }
            continue;
        }
        return Err(CliError::usage(format!(
            "--q: elements {at}..{} (x, y, z, w of joint \"{joint}\"'s quaternion) have norm {}; \
             a rotation needs a unit quaternion{}",
            at + 3,
            bad.norm,
            if bad.norm > 0.0 {
                " (--normalize divides it by its norm)"
            } else {
                ""
            }
        )));
    }
    Ok(())
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
pub const BENCH_KEYS: [&str; 9] = [
    "fk", "jacobian", "rnea", "nle", "gravity", "crba", "aba", "drnea", "daba",
];

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
    pub fn random<const N: usize>(model: &Model<N>, n: usize) -> Self {
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
    pub fn parse<const N: usize>(model: &Model<N>, text: &str) -> Result<Self, String> {
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
            let (mq, mv) = (model.joint_nq(body), model.joint_nv(body));
            if (mq, mv) != (jq, jv) {
                return Err(format!(
                    "line {ln}: joint {name} has nq {jq}, nv {jv} in the file but {mq}, {mv} in the model"
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
                let (jq, jv) = (model.joint_nq(body), model.joint_nv(body));
                let (mq, mv) = (model.q_index(body), model.v_index(body));
                out.q[s * nq + mq..][..jq].copy_from_slice(&fq[oq..oq + jq]);
                out.qd[s * nv + mv..][..jv].copy_from_slice(&fv[ov..ov + jv]);
                out.qdd[s * nv + mv..][..jv].copy_from_slice(&fa[ov..ov + jv]);
            }
        }
        Ok(out)
    }
}

/// The sum of RNEA's τ over all states and all one-DOF joints: programs that time the same
/// states with other libraries print the same number (to ~1e-9 relative), which checks that the
/// states were mapped onto each library's joint order correctly. Multi-DOF joints (a floating
/// base) are left out because libraries express their forces in different frames.
pub fn rnea_check<const N: usize>(model: &Model<N>, states: &BenchStates) -> Result<f64, CliError> {
    let (nq, nv) = (model.nq(), model.dof());
    let mut d = Box::new(Data::<N>::new());
    let mut sum = 0.0;
    for s in 0..states.n {
        let tau = algo::rnea(
            model,
            &mut d,
            &states.q[s * nq..(s + 1) * nq],
            &states.qd[s * nv..(s + 1) * nv],
            &states.qdd[s * nv..(s + 1) * nv],
        )
        .map_err(|e| algo_error(model, e))?;
        sum += (0..model.body_count())
            .filter(|&i| model.joint_nv(i) == 1)
            .map(|i| tau[model.v_index(i)])
            .sum::<f64>();
    }
    Ok(sum)
}

/// Median ns per call for each of [`BENCH_KEYS`] on `model` over `states`, with the
/// Jacobian of tool index `tool` (`None`: a model without tools, no Jacobian timed). ABA and
/// its derivatives are not timed (`None`) when the mass matrix is singular. `drnea` is
/// [`algo::rnea_derivatives`] (∂τ/∂q, ∂τ/∂q̇, M), `daba` [`algo::aba_derivatives`] (∂q̈/∂q,
/// ∂q̈/∂q̇, M⁻¹) at the same τ as ABA.
pub fn bench_states<const N: usize>(
    model: &Model<N>,
    states: &BenchStates,
    rounds: usize,
    tool: Option<usize>,
) -> Result<[Option<f64>; 9], CliError> {
    let nstates = states.n;
    let rounds = rounds.max(1);
    let (nq, nv) = (model.nq(), model.dof());
    if nstates == 0
        || states.q.len() != nq * nstates
        || states.qd.len() != nv * nstates
        || states.qdd.len() != nv * nstates
    {
        return Err(CliError::usage(
            "the states do not fit the model's nq and dof",
        ));
    }
    if tool.is_some_and(|t| t >= model.tools().len()) {
        return Err(CliError::usage(
            "the model has no such tool to compute a Jacobian for",
        ));
    }
    let mut d = Box::new(Data::<N>::new());
    let mut jac = Box::new([[0.0; N]; 6]);
    let q = |s: usize| &states.q[s * nq..(s + 1) * nq];
    let qd = |s: usize| &states.qd[s * nv..(s + 1) * nv];
    let qdd = |s: usize| &states.qdd[s * nv..(s + 1) * nv];
    // τ for ABA: RNEA of the states' accelerations, so ABA sees realistic torques.
    let mut taus = vec![0.0; nv * nstates];
    for s in 0..nstates {
        let t = algo::rnea(model, &mut d, q(s), qd(s), qdd(s)).map_err(|e| algo_error(model, e))?;
        taus[s * nv..(s + 1) * nv].copy_from_slice(t);
    }
    let tau = |s: usize| &taus[s * nv..(s + 1) * nv];
    let first = |t: &[f64]| t.first().copied().unwrap_or(0.0);
    let mut deriv = Box::new(DerivativeData::<N>::new());
    let mut out = [None; 9];
    out[0] = Some(time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::forward_position(model, &mut d, black_box(q(s))));
    }));
    if let Some(tool) = tool {
        out[1] = Some(time_per_call(nstates, rounds, |s| {
            let _ = black_box(algo::jacobian(
                model,
                &mut d,
                black_box(q(s)),
                tool,
                &mut jac,
            ));
        }));
    }
    out[2] = Some(time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::rnea(model, &mut d, black_box(q(s)), qd(s), qdd(s)).map(first));
    }));
    out[3] = Some(time_per_call(nstates, rounds, |s| {
        let _ =
            black_box(algo::nonlinear_effects(model, &mut d, black_box(q(s)), qd(s)).map(first));
    }));
    out[4] = Some(time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::gravity(model, &mut d, black_box(q(s))).map(first));
    }));
    out[5] = Some(time_per_call(nstates, rounds, |s| {
        let _ = black_box(algo::crba(model, &mut d, black_box(q(s))));
    }));
    out[7] = Some(time_per_call(nstates, rounds, |s| {
        let _ = black_box(
            algo::rnea_derivatives(model, &mut d, &mut deriv, black_box(q(s)), qd(s), qdd(s))
                .map(|r| r.dtau_dq.dim()),
        );
    }));
    match algo::aba(model, &mut d, q(0), qd(0), tau(0)) {
        Ok(_) => {
            out[6] = Some(time_per_call(nstates, rounds, |s| {
                let _ =
                    black_box(algo::aba(model, &mut d, black_box(q(s)), qd(s), tau(s)).map(first));
            }));
            out[8] = Some(time_per_call(nstates, rounds, |s| {
                let _ = black_box(
                    algo::aba_derivatives(
                        model,
                        &mut d,
                        &mut deriv,
                        black_box(q(s)),
                        qd(s),
                        tau(s),
                    )
                    .map(|r| r.ddq_dq.dim()),
                );
            }));
        }
        Err(e) => errln!(
            "rl: warning: ABA not timed, nor its derivatives: {}",
            algo_error(model, e)
        ),
    }
    Ok(out)
}

/// `rl model bench` refuses to time a debug build: its numbers would describe the debug
/// assertions and the missing optimisation, not the algorithms (the most common cause of "why is
/// it so slow" with any dynamics library).
pub fn refuse_debug_build(debug_build: bool) -> Result<(), CliError> {
    if debug_build {
        return Err(CliError::failed(
            "rl model bench: this rl is a debug build (unoptimised, debug assertions on); its \
             timings would not describe the algorithms, so none are reported. Build it with \
             `cargo build --release` (or run `cargo run --release -- model bench …`)",
        ));
    }
    Ok(())
}

fn bench(a: BenchArgs) -> CliResult {
    if !(1..=MAX_STATES).contains(&a.states) {
        return Err(CliError::usage(format!(
            "--states {}: give 1 to {MAX_STATES} states",
            a.states
        )));
    }
    if !(1..=MAX_ROUNDS).contains(&a.rounds) {
        return Err(CliError::usage(format!(
            "--rounds {}: give 1 to {MAX_ROUNDS} rounds",
            a.rounds
        )));
    }
    if a.states_file.is_some() {
        refuse_given(&["states"], "with --states-file: its states are timed")?;
    }
    refuse_debug_build(cfg!(debug_assertions))?;
    // A states file is read before anything is timed, so a bad one fails at once.
    let states_text = match &a.states_file {
        None => None,
        Some(path) => Some(
            rl_core::loader::read_text(path, rl_core::loader::InputLimits::DEFAULT.max_bytes)
                .map_err(|e| CliError::usage(format!("--states-file {e}")))?,
        ),
    };
    let extra = a.tool.iter().cloned().collect();
    let options = a.model.options(extra);
    let file = a.model.file.clone();
    capacity::load(&file, &options, Bench { a, states_text })
}

struct Bench {
    a: BenchArgs,
    states_text: Option<String>,
}

impl WithModel for Bench {
    type Output = ExitCode;

    fn run<const N: usize>(self, loaded: Box<LoadedModel<N>>) -> CliResult {
        let a = &self.a;
        warn(&loaded);
        let m = &loaded.model;
        let tool = match a.tool.as_deref() {
            None if m.tools().is_empty() => None,
            None => Some(0),
            Some(t) => Some(m.tool_index(t).ok_or_else(|| {
                let names: Vec<_> = m.tools().iter().map(|x| x.name.as_str()).collect();
                CliError::usage(format!(
                    "--tool: the model has no tool or link named {t:?} (tools: {})",
                    names.join(", ")
                ))
            })?),
        };
        let states = match (&self.states_text, &a.states_file) {
            (Some(text), Some(path)) => BenchStates::parse(m, text)
                .map_err(|e| CliError::usage(format!("--states-file {}: {e}", path.display())))?,
            _ => BenchStates::random(m, a.states),
        };
        let ns = bench_states(m, &states, a.rounds, tool)?;
        let tool_name = tool.map(|t| m.tools()[t].name.as_str());
        if a.json {
            let mut obj = serde_json::Map::new();
            for (k, v) in BENCH_KEYS.iter().zip(ns) {
                obj.insert(
                    format!("{k}_ns"),
                    json!(v.map(|v| (v * 10.0).round() / 10.0)),
                );
            }
            obj.insert("dof".into(), json!(m.dof()));
            obj.insert("tool".into(), json!(tool_name));
            obj.insert("states".into(), json!(states.n));
            if a.states_file.is_some() {
                obj.insert("rnea_check".into(), json!(rnea_check(m, &states)?));
            }
            outln!(
                "{}",
                rl::json::versioned("model.bench", 1, serde_json::Value::Object(obj))
            )?;
        } else {
            outln!(
                "{} ({} DOF), median of {} rounds over {} {} states, Jacobian of tool {}",
                m.name(),
                m.dof(),
                a.rounds,
                states.n,
                if a.states_file.is_some() {
                    "given"
                } else {
                    "random"
                },
                tool_name.map_or("(none: no tools)".into(), |t| format!("{t:?}"))
            )?;
            for (k, v) in BENCH_KEYS.iter().zip(ns) {
                match v {
                    Some(v) => outln!("  {k:<10} {v:>10.1} ns")?,
                    None => outln!("  {k:<10} {:>10}", "-")?,
                }
            }
        }
        Ok(ExitCode::SUCCESS)
    }
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

    const CAPACITY: usize = 16;

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
        let ns = bench_states(&m, &s, 1, Some(0)).unwrap();
        // The same states seen through the other joint order give the same check.
        let check = rnea_check(&m, &s).unwrap();
        let file = model(JointOrder::File);
        let other = rnea_check(&file, &BenchStates::parse(&file, STATES).unwrap()).unwrap();
        assert!(check.abs() > 1e-3 && (check - other).abs() <= 1e-12 * check.abs());
        assert!(
            ns.iter()
                .all(|t| t.is_some_and(|t| t.is_finite() && t > 0.0)),
            "{ns:?}"
        );
        assert!(bench_states(&m, &s, 1, Some(m.tools().len())).is_err());
    }

    #[test]
    fn a_debug_build_refuses_to_bench() {
        let e = refuse_debug_build(true).unwrap_err().to_string();
        assert!(e.contains("debug build") && e.contains("--release"), "{e}");
        assert!(refuse_debug_build(false).is_ok());
    }
}
