//! `rl plan`: plan a collision-free path for a robot among obstacles (rl-plan), print what it
//! found as JSON, and write the path and its trajectory as CSV; `rl plan bench` runs a
//! MotionBenchMaker problem set and writes OMPL's benchmark logs and RL's CSV.
//!
//! - `rl plan ROBOT.urdf --scene SCENE.yaml --request REQUEST.yaml`: a MoveIt planning scene
//!   and motion plan request (MotionBenchMaker's format); the SRDF beside the URDF and the
//!   `_spherized.urdf` beside it are used when present.
//! - `rl plan SCENARIO.xml`: one of RL's rlplan scenarios (planner, model, scene, start, goal).
//!
//! All the logic lives in rl-plan; this file parses arguments and prints.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Subcommand, ValueEnum};
use rl::controller::runtime::DEFAULT_SPEED;
use rl_core::traj::Trajectory;
use rl_plan::bench::{self, BenchOptions, CheckerKind, Run};
use rl_plan::execute::{Execution, ExecutionLimits};
use rl_plan::optimizer::OptimizerKind;
use rl_plan::planner::{DynamicDomain, PlannerKind};
use rl_plan::problem::moveit::MotionRequest;
use rl_plan::problem::rlplan::Scenario;
use rl_plan::problem::{COVER_SPACING, Robot, mbm};
use rl_plan::sampler::SamplerKind;
use rl_plan::scene::{CertifyOptions, CertifyProgress};
use rl_plan::space::parse_bounds;
use rl_plan::verifier::Verifier;
use rl_plan::{JointSpace, Path as PlanPath, PlanError, PlanOptions, PlanResult, Validity, plan};
use serde_json::json;

use super::output::{Replacement, outln};
use super::progress::{ProgressLine, fraction};
use super::{CliError, CliResult, given, parse_duration, refuse_given};

/// Arguments of `rl plan`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub struct PlanArgs {
    /// Run a problem set instead of one problem.
    #[command(subcommand)]
    pub command: Option<PlanCommand>,
    /// The robot (URDF) or one of RL's planning scenarios (rlplan XML).
    pub model: Option<PathBuf>,
    /// MoveIt planning scene (YAML) with the obstacles.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// MoveIt motion plan request (YAML) with start state and joint goal.
    #[arg(long)]
    pub request: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
    /// Write the path as CSV: a header of joint names, one row per waypoint (rad or m).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write a jerk-limited trajectory along the path as CSV (`t`, positions, velocities,
    /// accelerations), sampled every --dt.
    #[arg(long)]
    pub trajectory: Option<PathBuf>,
    /// Sampling period of --trajectory: a duration (e.g. 10ms) or a bare number of seconds, as
    /// `rl traj --dt` takes it.
    #[arg(long, value_name = "DURATION", value_parser = parse_duration, default_value = "10ms")]
    pub dt: Duration,
    /// Fraction of the model's speed limits for --trajectory, in (0, 1] (the same default as
    /// `rl run --speed`).
    #[arg(long, default_value_t = DEFAULT_SPEED)]
    pub speed: f64,
    /// Clearance below which a path's edge is not certified, m: every edge of the returned path
    /// is checked by conservative advancement on the exact geometry (nothing passes between
    /// samples); the JSON's "certified" says what came out.
    #[arg(long, default_value_t = CertifyOptions::default().margin)]
    pub certify_margin: f64,
    /// Do not certify the returned path.
    #[arg(long)]
    pub no_certify: bool,
}

/// Settings shared by `rl plan` and `rl plan bench`.
#[derive(Args, Debug, Clone)]
pub struct CommonArgs {
    /// SRDF with the allowed collision pairs (default: the .srdf beside the URDF).
    #[arg(long)]
    pub srdf: Option<PathBuf>,
    /// Planner: rrt-connect (Kuffner & LaValle's extend-connect, RL's rrtExtCon), rrt-con-con,
    /// rrt-ext-ext, rrt-dual, rrt-goal-bias, rrt, prm.
    #[arg(long, default_value = "rrt-connect")]
    pub planner: String,
    /// Random seed (the same seed gives the same path).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Time budget for planning, and as much again for shortening the path (an RL scenario:
    /// its file's budget unless given).
    #[arg(
        long,
        alias = "time",
        value_parser = parse_duration,
        value_name = "DURATION",
        default_value = "1s"
    )]
    pub plan_time: Duration,
    /// Collision checker: hybrid (spheres that cover the meshes, the file's spheres, then the
    /// exact meshes where they disagree: exact results at sphere speed), spheres (SIMD only;
    /// conservative unless --raw-spheres), or exact (meshes only).
    #[arg(long, value_enum, default_value = "hybrid")]
    pub checker: Checker,
    /// Spherized URDF with the robot's spheres (default: NAME_spherized.urdf beside the URDF,
    /// else spheres fitted around the meshes).
    #[arg(long)]
    pub spheres: Option<PathBuf>,
    /// Use the spherized URDF's spheres as they are, without adding spheres where the meshes
    /// stick out of them (VAMP's model: faster, not conservative).
    #[arg(long)]
    pub raw_spheres: bool,
    /// Sampler: halton (VAMP's), uniform, gaussian, bridge.
    #[arg(long, default_value = "halton")]
    pub sampler: String,
    /// Optimiser: simple (RL's shortcutting), shortcut (VAMP's greedy shortcutting), advanced
    /// (RL's), none.
    #[arg(long, default_value = "simple")]
    pub optimizer: String,
    /// Edge check resolution, rad (largest step between checked configurations).
    #[arg(long, default_value_t = 1.0 / 32.0)]
    pub resolution: f64,
    /// RRT step (RL's delta, VAMP's range), rad.
    #[arg(long)]
    pub range: Option<f64>,
    /// Plain RRT extensions instead of dynamic-domain ones (VAMP's default, on here too; used
    /// by rrt-connect / rrt-ext-con only).
    #[arg(long)]
    pub no_dynamic_domain: bool,
    /// Joint limits to plan within, replacing the model's for the joints named:
    /// JOINT=MIN:MAX[,JOINT=MIN:MAX…] in rad (m for prismatic joints), e.g.
    /// panda_joint1=-1:1. Start and goal must lie within them.
    #[arg(long, value_name = "JOINT=MIN:MAX[,…]")]
    pub limits: Option<String>,
}

impl Default for CommonArgs {
    /// The same defaults as the flags (for `rl run --plan`, which takes a few of them).
    fn default() -> Self {
        Self {
            srdf: None,
            planner: "rrt-connect".into(),
            seed: 0,
            plan_time: Duration::from_secs(1),
            checker: Checker::Hybrid,
            spheres: None,
            raw_spheres: false,
            sampler: "halton".into(),
            optimizer: "simple".into(),
            resolution: 1.0 / 32.0,
            range: None,
            no_dynamic_domain: false,
            limits: None,
        }
    }
}

/// The collision checker.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Checker {
    /// Covering spheres, the file's spheres, then the exact meshes.
    Hybrid,
    /// Spheres in SIMD lanes.
    Spheres,
    /// rl-sg's exact geometry.
    Exact,
}

/// Subcommands of `rl plan`.
#[derive(Subcommand, Debug)]
pub enum PlanCommand {
    /// Run every problem of a MotionBenchMaker set and print VAMP's summary table.
    Bench(BenchArgs),
}

/// Arguments of `rl plan bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Directory of problems (sceneNNNN.yaml + requestNNNN.yaml, in scenario folders).
    pub dir: PathBuf,
    /// The robot's URDF (default: the only non-spherized .urdf in DIR or a parent of it).
    #[arg(long)]
    pub model: Option<PathBuf>,
    #[command(flatten)]
    pub common: CommonArgs,
    /// Runs per problem (seeds seed, seed+1, …).
    #[arg(long, default_value_t = 1)]
    pub runs: usize,
    /// Only the first N problems.
    #[arg(long)]
    pub limit: Option<usize>,
    /// Check every returned path with the exact meshes at a resolution 10× finer.
    #[arg(long)]
    pub fine_check: bool,
    /// Time the execution of every returned path at this fraction of the model's speed limits
    /// (0.5 if given bare): stopping at every waypoint, blended, retimed with bounded jerk,
    /// each over TOPP-RA's velocity-and-acceleration optimum on the same path.
    #[arg(long, value_name = "FRACTION", num_args = 0..=1, default_missing_value = "0.5")]
    pub retime: Option<f64>,
    /// Write OMPL benchmark logs (one per problem) and RL's benchmark.csv into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write every solved problem's returned (optimised) path of run 0 as CSV into this
    /// directory (SCENARIO_NNNN.csv, the format of `rl plan --out`), for an independent check.
    #[arg(long)]
    pub paths: Option<PathBuf>,
    /// Print one line per run.
    #[arg(long)]
    pub verbose: bool,
}

fn failed(e: impl std::fmt::Display) -> CliError {
    CliError::failed(e.to_string())
}

fn usage(e: impl std::fmt::Display) -> CliError {
    CliError::usage(e.to_string())
}

/// The planning options of the common arguments.
pub(crate) fn options(c: &CommonArgs) -> Result<PlanOptions, CliError> {
    let mut planner =
        PlannerKind::parse(&c.planner).map_err(|e| usage(format!("--planner: {e}")))?;
    if planner.rrt_settings_mut().is_none() {
        refuse_given(
            &["range", "no-dynamic-domain"],
            &format!("to --planner {} (they set RRT extensions)", c.planner),
        )?;
    }
    if c.checker == Checker::Exact {
        refuse_given(
            &["spheres", "raw-spheres"],
            "with --checker exact (it checks the meshes only)",
        )?;
    }
    if let Some(s) = planner.rrt_settings_mut() {
        // VAMP's settings: range 1 rad (its UR5: 1.5), trees balanced, dynamic domain; the
        // f32 k-d tree for nearest neighbours (where the space has circles or rotations, the
        // exact structures).
        s.delta = c.range.unwrap_or(1.0);
        s.balance = true;
        s.nn = rl_plan::nn::NnKind::Fast;
        if !c.no_dynamic_domain {
            s.dynamic_domain = Some(DynamicDomain::VAMP);
        }
    }
    let sampler = match c.sampler.as_str() {
        "halton" => SamplerKind::Halton,
        "uniform" => SamplerKind::Uniform,
        "gaussian" => SamplerKind::Gaussian(None),
        "bridge" => SamplerKind::Bridge(None, 5.0 / 6.0),
        other => {
            return Err(usage(format!(
                "--sampler {other}: use halton, uniform, gaussian or bridge"
            )));
        }
    };
    let optimizer = OptimizerKind::parse(&c.optimizer).ok_or_else(|| {
        usage(format!(
            "--optimizer {}: use simple, shortcut, advanced or none",
            c.optimizer
        ))
    })?;
    if !(c.resolution.is_finite() && c.resolution > 0.0) {
        return Err(usage("--resolution must be positive"));
    }
    Ok(PlanOptions {
        planner,
        sampler,
        verifier: Verifier::recursive(c.resolution),
        optimizer,
        optimizer_verifier: None,
        seed: c.seed,
        time: c.plan_time,
        optimize_time: c.plan_time,
        try_direct: true,
    })
}

/// Loads the robot with the common arguments' SRDF and spheres, and their `--limits`.
pub(crate) fn load_robot(urdf: &Path, c: &CommonArgs) -> Result<Robot, CliError> {
    let cover = (!c.raw_spheres).then_some(COVER_SPACING);
    let mut robot = Robot::load_urdf_with(urdf, c.srdf.as_deref(), c.spheres.as_deref(), cover)
        .map_err(usage)?;
    override_limits(&mut robot.space, c)?;
    Ok(robot)
}

/// Applies `--limits` to `space`; a bad entry or an unknown joint is a usage error naming it.
pub(crate) fn override_limits(space: &mut JointSpace, c: &CommonArgs) -> Result<(), CliError> {
    let Some(text) = &c.limits else {
        return Ok(());
    };
    let bounds = parse_bounds(text).map_err(|e| usage(format!("--limits: {e}")))?;
    space.override_bounds(&bounds).map_err(|e| match e {
        rl_plan::PlanError::UnknownName { name, .. } => usage(format!(
            "--limits: unknown joint \"{name}\" (the model's joints: {})",
            names_of(space).join(", ")
        )),
        e => usage(format!("--limits: {e}")),
    })
}

/// Runs `rl plan`.
pub fn run(args: PlanArgs) -> CliResult {
    if let Some(PlanCommand::Bench(b)) = args.command {
        return run_bench(b);
    }
    if args.no_certify {
        refuse_given(
            &["certify-margin"],
            "with --no-certify (nothing is certified)",
        )?;
    }
    let model = args.model.as_ref().ok_or_else(|| {
        usage("give a robot (URDF with --scene and --request) or an rlplan scenario")
    })?;
    let max = rl_core::loader::InputLimits::DEFAULT.max_bytes;
    let is_scenario = rl_core::loader::read_text(model, max)
        .map(|t| t.contains("<rlplan") || t.contains("<rl>"))
        .map_err(|e| usage(e.to_string()))?;
    if is_scenario {
        // A scenario names its own planner, optimiser, model and scene: the flags that choose
        // them (and the trajectory's, written for URDF robots only) are refused, not ignored.
        refuse_given(
            &[
                "scene",
                "request",
                "srdf",
                "planner",
                "checker",
                "spheres",
                "raw-spheres",
                "sampler",
                "optimizer",
                "resolution",
                "range",
                "no-dynamic-domain",
                "trajectory",
                "dt",
                "speed",
            ],
            "to an RL scenario (rlplan XML): the file names its planner, optimiser, model and \
             scene (a scenario's path: --out)",
        )?;
    } else if args.trajectory.is_none() {
        refuse_given(
            &["dt", "speed"],
            "without --trajectory (they time the trajectory)",
        )?;
    }
    // Output files before any work: one that cannot be created fails first, and each is moved
    // over an existing file only once written.
    let out_file = args.out.as_deref().map(create).transpose()?;
    let trajectory_file = args.trajectory.as_deref().map(create).transpose()?;
    let (space, result, checker_name, certified, budget) = if is_scenario {
        // A file that cannot be read or understood is a bad argument (exit 2), as in every
        // subcommand; a problem that cannot be solved is a failure (exit 1).
        let sc = Scenario::load(model).map_err(usage)?;
        let (mut space, mut checker) = sc.build().map_err(usage)?;
        override_limits(&mut space, &args.common)?;
        let mut opts = sc.options(args.common.seed);
        if given("plan-time") {
            opts.time = args.common.plan_time;
            opts.optimize_time = args.common.plan_time;
        }
        let r = plan(&space, &mut checker, &sc.start, &sc.goal, &opts).map_err(failed)?;
        let cert = certify(&args, &r, Some(&mut checker))?;
        (space, r, "exact", cert, opts.time)
    } else {
        let (scene, request) = match (&args.scene, &args.request) {
            (Some(s), Some(r)) => (s, r),
            _ => {
                return Err(usage(
                    "a URDF needs --scene SCENE.yaml and --request REQUEST.yaml",
                ));
            }
        };
        let robot = load_robot(model, &args.common)?;
        let env = rl_sg::load::moveit::load_environment(scene).map_err(usage)?;
        let req = MotionRequest::load(request).map_err(usage)?;
        let (start, goal) = req.configurations(&robot.space).map_err(usage)?;
        let opts = options(&args.common)?;
        // The path is certified on the exact geometry of the planner's checker (the sphere
        // checker has none: the exact checker of the same scene then).
        let (r, cert) = match args.common.checker {
            Checker::Hybrid => {
                let mut c = robot.hybrid_checker(&env).map_err(failed)?;
                let r = plan(&robot.space, &mut c, &start, &goal, &opts).map_err(failed)?;
                let cert = certify(&args, &r, Some(&mut c))?;
                (r, cert)
            }
            Checker::Spheres => {
                let mut c = robot.sphere_checker(&env).map_err(failed)?;
                let r = plan(&robot.space, &mut c, &start, &goal, &opts).map_err(failed)?;
                let mut exact = robot.exact_checker(env).map_err(failed)?;
                let cert = certify(&args, &r, Some(&mut exact))?;
                (r, cert)
            }
            Checker::Exact => {
                let mut c = robot.exact_checker(env).map_err(failed)?;
                let r = plan(&robot.space, &mut c, &start, &goal, &opts).map_err(failed)?;
                let cert = certify(&args, &r, Some(&mut c))?;
                (r, cert)
            }
        };
        let name = match args.common.checker {
            Checker::Hybrid => "hybrid",
            Checker::Spheres if args.common.raw_spheres => "spheres (raw)",
            Checker::Spheres => "spheres",
            Checker::Exact => "exact",
        };
        if let (Some(t), Some(file), Some(path)) = (&args.trajectory, trajectory_file, &r.optimized)
        {
            let names = robot.space.number_names();
            write_trajectory(t, file, &robot, path, args.speed, args.dt, &names)?;
        }
        (robot.space, r, name, cert, opts.time)
    };
    if let (Some(out), Some(file), Some(path)) = (&args.out, out_file, &result.optimized) {
        write_path_to(out, file, &space, path)?;
    }
    // What stdout's JSON says in numbers, one line on stderr for a reader who only looks at
    // the exit status: no path (exit 1), or a path the exact geometry did not certify (exit 0,
    // with a warning).
    if !result.solved {
        eprintln!(
            "rl plan: no path found by {} within {:?} ({} iterations)",
            result.planner, budget, result.iterations
        );
    } else if certified["certified"] == json!(false) {
        let why = match (&certified["failure"], &certified["unsupported"]) {
            (serde_json::Value::Object(f), _) => format!(
                "edge {}: {}",
                f.get("edge").unwrap_or(&json!(null)),
                f.get("reason").and_then(|r| r.as_str()).unwrap_or("")
            ),
            (_, serde_json::Value::String(u)) => u.clone(),
            _ => "see \"certified\" in the output".to_string(),
        };
        eprintln!(
            "rl plan: warning: the path is not certified on the exact geometry ({why}); \
             plan again with another --seed, or rl run --plan, which does"
        );
    }
    let mut json = result_json(&space, &result, checker_name, args.common.seed);
    json["certified"] = certified;
    rl::json::tag("plan", 1, &mut json);
    outln!(
        "{}",
        serde_json::to_string_pretty(&json).unwrap_or_default()
    )?;
    Ok(if result.solved {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// Certifies the returned path on `checker`'s exact geometry (unless --no-certify): the JSON
/// for "certified" (null when not asked, not solved, or the checker has no exact geometry).
fn certify(
    args: &PlanArgs,
    r: &PlanResult,
    checker: Option<&mut dyn Validity>,
) -> Result<serde_json::Value, CliError> {
    let (Some(path), Some(checker), false) = (&r.optimized, checker, args.no_certify) else {
        return Ok(serde_json::Value::Null);
    };
    let Some(exact) = checker.exact_checker() else {
        return Ok(serde_json::Value::Null);
    };
    if args.certify_margin.is_nan() || args.certify_margin < 0.0 {
        return Err(usage("--certify-margin must be a distance ≥ 0 (m)"));
    }
    let options = CertifyOptions {
        margin: args.certify_margin,
        ..Default::default()
    };
    let started = std::time::Instant::now();
    let mut line = ProgressLine::stderr("rl plan: ");
    let mut show = |p: &CertifyProgress| {
        line.update(|| {
            format!(
                "certifying edge {} of {}, {} steps, {:.1} s",
                (p.edges_done + 1).min(p.edges),
                p.edges,
                p.steps,
                started.elapsed().as_secs_f64()
            )
        })
    };
    let c = exact.certify_path_with_progress(path, &options, &mut show);
    line.clear();
    let c = match c {
        Ok(c) => c,
        // A model the motion bound does not cover (a helical joint, say): the plan stands,
        // uncertified, and the JSON says why.
        Err(PlanError::Unsupported(why)) => {
            return Ok(json!({ "certified": false, "margin": options.margin, "unsupported": why }));
        }
        Err(e) => return Err(failed(e)),
    };
    let finite = |x: f64| if x.is_finite() { json!(x) } else { json!(null) };
    Ok(json!({
        "certified": c.is_certified(),
        "margin": options.margin,
        "edges": c.edges,
        "edges_certified": c.certified,
        "steps": c.steps,
        "min_distance": finite(c.min_distance),
        "time_us": started.elapsed().as_secs_f64() * 1e6,
        "failure": c.failure.as_ref().map(|(edge, why)| json!({
            "edge": edge,
            "reason": why.to_string(),
        })),
    }))
}

fn names_of(space: &JointSpace) -> Vec<String> {
    space.coordinates().iter().map(|c| c.name.clone()).collect()
}

fn result_json(space: &JointSpace, r: &PlanResult, checker: &str, seed: u64) -> serde_json::Value {
    let finite = |x: f64| if x.is_finite() { json!(x) } else { json!(null) };
    json!({
        "solved": r.solved,
        "planner": r.planner,
        "checker": checker,
        "seed": seed,
        "planning_time_us": r.planning_time.as_secs_f64() * 1e6,
        "optimization_time_us": r.optimization_time.as_secs_f64() * 1e6,
        "iterations": r.iterations,
        "vertices": r.vertices,
        "collision_checks": r.planning_checks,
        "optimization_collision_checks": r.optimization_checks,
        "length_before": finite(r.length_before),
        "length_after": finite(r.length_after),
        "waypoints_before": r.path.as_ref().map_or(0, PlanPath::len),
        "waypoints_after": r.optimized.as_ref().map_or(0, PlanPath::len),
        "joints": names_of(space),
    })
}

/// An output file written beside `path` and moved over it by [`Replacement::commit`]; one that
/// cannot be created is a bad argument.
fn create(path: &Path) -> Result<Replacement, CliError> {
    Replacement::create(path).map_err(|e| usage(format!("cannot create {}: {e}", path.display())))
}

fn write_path(out: &Path, space: &JointSpace, path: &PlanPath) -> Result<(), CliError> {
    write_path_to(out, create(out)?, space, path)
}

fn write_path_to(
    out: &Path,
    mut f: Replacement,
    space: &JointSpace,
    path: &PlanPath,
) -> Result<(), CliError> {
    path.write_csv(space, &mut f)
        .map_err(|e| e.to_string())
        .and_then(|()| f.commit().map_err(|e| e.to_string()))
        .map_err(|e| failed(format!("{}: {e}", out.display())))
}

fn write_trajectory(
    out: &Path,
    mut f: Replacement,
    robot: &Robot,
    path: &PlanPath,
    speed: f64,
    dt: Duration,
    names: &[String],
) -> Result<(), CliError> {
    let limits = ExecutionLimits::from_model(&robot.kinematics.model, speed).map_err(usage)?;
    let ex = Execution::new(&robot.space, path, limits).map_err(failed)?;
    let tr = ex.trajectory::<16, 256>().map_err(failed)?;
    let io = |e: std::io::Error| failed(format!("{}: {e}", out.display()));
    let n = names.len();
    let mut header = vec!["t".to_string()];
    for suffix in ["", "/v", "/a"] {
        header.extend(names.iter().map(|nm| format!("{nm}{suffix}")));
    }
    writeln!(f, "{}", header.join(",")).map_err(io)?;
    let dt = dt.as_secs_f64().max(1e-6);
    let steps = (tr.duration() / dt).ceil() as usize;
    for i in 0..=steps {
        let t = (i as f64 * dt).min(tr.duration());
        let s = tr.sample(t);
        let mut row = vec![format!("{t}")];
        for v in [&s.position, &s.velocity, &s.acceleration] {
            row.extend(v[..n].iter().map(|x| format!("{x}")));
        }
        writeln!(f, "{}", row.join(",")).map_err(io)?;
    }
    f.commit().map_err(io)
}

/// The URDF for a problem directory: given, or the only plain `.urdf` in DIR or an ancestor.
fn find_urdf(dir: &Path, given: &Option<PathBuf>) -> Result<PathBuf, CliError> {
    if let Some(m) = given {
        return Ok(m.clone());
    }
    for d in dir.ancestors() {
        let Ok(rd) = std::fs::read_dir(d) else {
            continue;
        };
        let urdfs: Vec<PathBuf> = rd
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.extension().is_some_and(|e| e == "urdf")
                    && !p.to_string_lossy().ends_with("_spherized.urdf")
            })
            .collect();
        if urdfs.len() == 1 {
            return Ok(urdfs[0].clone());
        }
    }
    Err(usage(format!(
        "no robot URDF found in {} or above it; give --model",
        dir.display()
    )))
}

fn run_bench(b: BenchArgs) -> CliResult {
    let urdf = find_urdf(&b.dir, &b.model)?;
    let robot = load_robot(&urdf, &b.common)?;
    // A problem set that cannot be read is a bad argument (exit 2), and so is an output
    // directory that cannot be made: both are found before any run.
    let mut problems = mbm::find_problems(&b.dir).map_err(usage)?;
    for (flag, dir) in [("--paths", &b.paths), ("--out", &b.out)] {
        if let Some(dir) = dir {
            std::fs::create_dir_all(dir)
                .map_err(|e| usage(format!("{flag} {}: {e}", dir.display())))?;
        }
    }
    if let Some(n) = b.limit {
        problems.truncate(n);
    }
    if problems.is_empty() {
        return Err(usage(format!(
            "no problems (requestNNNN.yaml) under {}",
            b.dir.display()
        )));
    }
    let opts = BenchOptions {
        plan: options(&b.common)?,
        runs: b.runs,
        checker: match b.common.checker {
            Checker::Hybrid => CheckerKind::Hybrid,
            Checker::Spheres => CheckerKind::Spheres,
            Checker::Exact => CheckerKind::Exact,
        },
        fine_check: b.fine_check.then_some(10.0),
        retime: b
            .retime
            .map(|f| rl_plan::execute::ExecutionLimits::from_model(&robot.kinematics.model, f))
            .transpose()
            .map_err(|e| usage(format!("--retime: {e}")))?,
    };
    let spheres = match (&b.common.checker, b.common.raw_spheres) {
        (Checker::Exact, _) => "exact meshes".to_string(),
        (Checker::Hybrid, _) => format!(
            "hybrid: {} covering spheres, {} file spheres, exact meshes",
            robot.spheres.len(),
            robot.inner_spheres.as_ref().map_or(0, |s| s.len())
        ),
        (_, true) => format!("{} spheres as in the file (raw)", robot.spheres.len()),
        (_, false) => format!("{} spheres covering the meshes", robot.spheres.len()),
    };
    eprintln!(
        "rl plan bench: {} problems × {} runs, {} ({}), {} backend",
        problems.len(),
        b.runs,
        urdf.display(),
        spheres,
        rl_plan::fast::Backend::detect().name()
    );
    let verbose = b.verbose;
    let total = problems.len() * b.runs;
    let (mut done, mut solved) = (0, 0);
    let mut line = ProgressLine::stderr("rl plan bench: ");
    let started = std::time::Instant::now();
    let runs = bench::run_mbm(&robot, &problems, &opts, &mut |r: &Run| {
        done += 1;
        solved += usize::from(r.result.as_ref().is_some_and(|x| x.solved));
        if verbose {
            // The run's own line replaces the progress line, which comes back below it.
            line.clear();
        }
        print_run(verbose, r);
        line.update(|| {
            format!(
                "{} runs, {solved} solved, {:.0} s, last {} run {}",
                fraction(done, total),
                started.elapsed().as_secs_f64(),
                r.problem,
                r.run
            )
        });
    })
    .map_err(failed)?;
    line.clear();
    drop(line);
    outln!("{}", bench::vamp_table(&runs))?;
    if opts.retime.is_some() {
        outln!("{}", bench::retime_table(&runs))?;
    }
    if let Some(dir) = &b.paths {
        for r in runs.iter().filter(|r| r.run == 0) {
            if let Some(path) = r.result.as_ref().and_then(|x| x.optimized.as_ref()) {
                let file = dir.join(format!("{}.csv", r.problem.replace(['/', '.'], "_")));
                write_path(&file, &robot.space, path)?;
            }
        }
    }
    if let Some(out) = &b.out {
        let setup = format!(
            "robot {}\nchecker {spheres}\nplanner {} (range {:?}), sampler {}, resolution {} rad, optimiser {}, time {:?}",
            urdf.display(),
            b.common.planner,
            b.common.range.unwrap_or(1.0),
            b.common.sampler,
            b.common.resolution,
            b.common.optimizer,
            b.common.plan_time
        );
        for p in &problems {
            let mine: Vec<Run> = runs
                .iter()
                .filter(|r| r.problem == p.name)
                .cloned()
                .collect();
            let planner = mine
                .iter()
                .find_map(|r| r.result.as_ref().map(|x| x.planner))
                .filter(|n| !n.is_empty())
                .unwrap_or("RRT Extend Connect");
            let file = out.join(format!(
                "{}.log",
                p.name.replace(['/', '.'], "_").trim_start_matches('_')
            ));
            let mut f = create(&file)?;
            bench::write_ompl_log(&mut f, &p.name, planner, &setup, &mine)
                .and_then(|_| f.commit())
                .map_err(|e| failed(format!("{}: {e}", file.display())))?;
        }
        let csv = out.join("benchmark.csv");
        let mut f = create(&csv)?;
        let engine = match b.common.checker {
            Checker::Hybrid => "HYBRID",
            Checker::Spheres => "SPHERES",
            Checker::Exact => "PARRY",
        };
        bench::write_rl_csv(&mut f, &runs, engine)
            .and_then(|_| f.commit())
            .map_err(|e| failed(format!("{}: {e}", csv.display())))?;
        eprintln!(
            "rl plan bench: wrote {} OMPL logs and {}",
            problems.len(),
            csv.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `--verbose`: one line per run on standard error.
fn print_run(verbose: bool, r: &Run) {
    if !verbose {
        return;
    }
    match &r.result {
        Some(res) => eprintln!(
            "{} run {}: solved {} {:.1} µs, {} iterations, {} checks{}",
            r.problem,
            r.run,
            res.solved,
            res.planning_time.as_secs_f64() * 1e6,
            res.iterations,
            res.planning_checks,
            match r.fine_valid {
                Some(true) => ", fine check: valid",
                Some(false) => ", fine check: COLLISION",
                None => "",
            }
        ),
        None => eprintln!("{} run {}: invalid start or goal", r.problem, r.run),
    }
}
