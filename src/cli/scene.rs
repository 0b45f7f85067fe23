//! `rl scene info | check | bench | dump`: what a scene file holds, whether a robot at a
//! configuration collides (with itself, with obstacles) and how close it comes, how long the
//! queries take on this machine, and every shape in the world frame (for other tools).

use std::hint::black_box;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Subcommand, ValueEnum};
use glam::DVec3;
use rl_core::Data;
use rl_core::algo::ik::SplitMix64;
use rl_core::loader::{LoadedModel, MimicJoints, UrdfOptions};
use rl_sg::capsule::Capsule;
use rl_sg::fit::{FitOptions, fit_capsule_model};
use rl_sg::load::{self, GeometryKind, MeshCache, MeshMode, RobotScene, UrdfGeometryOptions};
use rl_sg::report::{self, NamedDistance};
use rl_sg::{CollisionFilter, Geometry, ModelId, Scene};
use serde_json::{Value, json};

use super::output::outln;
use super::placement::{ScenarioRobot, is_scenario, parse_place};
use super::progress::{ProgressLine, fraction};
use super::{CliError, CliResult, refuse_given};

/// Capacity of the robots `rl scene` loads (bodies and degrees of freedom), as the tool had
/// before its capacities ([`super::capacity::CAPACITIES`]); fixed here because rl-sg's robot setup
/// loads the kinematics itself rather than through [`super::capacity::load`].
const CAPACITY: usize = 64;

/// `rl scene` subcommands.
#[derive(Subcommand, Debug)]
pub enum SceneCommand {
    /// Models, bodies, shapes and meshes of a scene file (URDF, rlsg XML, VRML, MoveIt YAML).
    Info(InfoArgs),
    /// Whether a robot at a configuration collides, with which bodies, how close it comes (JSON).
    Check(CheckArgs),
    /// Nanoseconds per query over random configurations: collision, distance, capsule path.
    Bench(BenchArgs),
    /// Every shape of the robot and the environment, their world poses at configurations, and
    /// the pairs checked (JSON, for other collision libraries).
    Dump(DumpArgs),
}

/// Geometry options shared by the subcommands.
#[derive(Args, Debug, Clone)]
pub struct GeometryArgs {
    /// Where `package://` URIs are looked up (repeatable; `$ROS_PACKAGE_PATH` and the file's
    /// parent directories are searched too).
    #[arg(long = "package-dir", value_name = "DIR")]
    pub package_dirs: Vec<PathBuf>,
    /// Meshes as triangle meshes or as their convex hulls.
    #[arg(long, value_enum, default_value_t = Meshes::Mesh)]
    pub meshes: Meshes,
    /// Refuse meshes with degenerate triangles or non-manifold edges instead of noting them.
    #[arg(long)]
    pub strict_meshes: bool,
}

/// What meshes become.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Meshes {
    /// The triangle mesh.
    Mesh,
    /// Its convex hull.
    ConvexHull,
}

/// Which URDF geometry.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `<collision>` elements.
    Collision,
    /// `<visual>` elements.
    Visual,
}

/// Arguments of `rl scene info`.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// A scene file: URDF, RL's rlsg XML, VRML (.wrl) or a MoveIt planning scene (.yaml).
    file: PathBuf,
    /// URDF: collision or visual geometry.
    #[arg(long, value_enum, default_value_t = Kind::Collision)]
    kind: Kind,
    #[command(flatten)]
    geometry: GeometryArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// The robot and its surroundings.
#[derive(Args, Debug, Clone)]
pub struct RobotArgs {
    /// The robot: a URDF, an RL scene (rlsg XML) whose first model is the robot (then give
    /// its kinematic model with --kinematics), or an RL planning scenario (rlplan XML: the
    /// scene, kinematics and <world> placement its planner checks; --q start and --q goal
    /// take its start and goal).
    model: PathBuf,
    /// RL scenes: the robot's kinematic model (rlmdl or rlkin XML); its bodies (rlkin: links)
    /// pair with the scene's first model's in order, its <ignore> elements apply.
    #[arg(long, value_name = "FILE")]
    kinematics: Option<PathBuf>,
    /// The SRDF with the robot's allowed collision pairs [default: the .srdf beside the URDF
    /// (same stem); without one, adjacent links and links rigidly joined are not checked
    /// against each other].
    #[arg(long, value_name = "FILE")]
    srdf: Option<PathBuf>,
    /// Obstacles: a MoveIt planning scene (.yaml), an RL scene (rlsg XML or .wrl) or a URDF.
    #[arg(long, value_name = "SCENE")]
    env: Option<PathBuf>,
    /// Where the robot's kinematic world frame stands in the scene: x,y,z (m) or
    /// x,y,z,rx,ry,rz (m, degrees about x, y, z applied as Rz·Ry·Rx, as RL's rlplan <world>).
    #[arg(long, value_name = "POSE", allow_hyphen_values = true)]
    place: Option<String>,
    /// URDF: add a six-DOF root joint (q starts with x,y,z,qx,qy,qz,qw).
    #[arg(long)]
    floating_base: bool,
    /// URDF: load joints with a <mimic> tag as independent joints.
    #[arg(long)]
    mimic_independent: bool,
    #[command(flatten)]
    geometry: GeometryArgs,
}

/// Arguments of `rl scene check` and `rl scene dump`.
#[derive(Args, Debug)]
pub struct CheckArgs {
    #[command(flatten)]
    robot: RobotArgs,
    /// Joint positions, comma-separated (nq values, the model's joint order); with an RL
    /// scenario also `start` or `goal`.
    #[arg(long, allow_hyphen_values = true)]
    q: String,
}

/// Arguments of `rl scene dump`.
#[derive(Args, Debug)]
pub struct DumpArgs {
    #[command(flatten)]
    robot: RobotArgs,
    /// A configuration, comma-separated (nq values).
    #[arg(long, allow_hyphen_values = true)]
    q: Option<String>,
    /// This many random configurations as well: those `rl scene bench --configs N` times.
    #[arg(long, default_value_t = 0)]
    random: usize,
}

/// Arguments of `rl scene bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    robot: RobotArgs,
    /// Random configurations (within the joint limits).
    #[arg(long, default_value_t = 100)]
    configs: usize,
    /// Timed rounds (the median is reported).
    #[arg(long, default_value_t = 7)]
    rounds: usize,
    /// Capsules per link for the control-rate path.
    #[arg(long, default_value_t = 2)]
    capsules_per_link: usize,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Runs `rl scene`.
pub fn run(cmd: SceneCommand) -> CliResult {
    match cmd {
        SceneCommand::Info(a) => info(a),
        SceneCommand::Check(a) => check(a),
        SceneCommand::Bench(a) => bench(a),
        SceneCommand::Dump(a) => dump(a),
    }
}

fn geometry_options(g: &GeometryArgs, kind: Kind) -> UrdfGeometryOptions {
    UrdfGeometryOptions {
        kind: match kind {
            Kind::Collision => GeometryKind::Collision,
            Kind::Visual => GeometryKind::Visual,
        },
        package_dirs: g.package_dirs.clone(),
        mesh: match g.meshes {
            Meshes::Mesh => MeshMode::Mesh,
            Meshes::ConvexHull => MeshMode::ConvexHull,
        },
        strict_meshes: g.strict_meshes,
    }
}

fn usage(e: impl std::fmt::Display) -> CliError {
    CliError::usage(e.to_string())
}

/// A robot in a scene, with its kinematics.
struct Setup {
    scene: Scene,
    robot: ModelId,
    kinematics: Box<LoadedModel<CAPACITY>>,
    env: bool,
    /// The RL scenario the robot came from, if it did.
    scenario: Option<ScenarioRobot>,
}

fn setup(r: &RobotArgs) -> Result<Setup, CliError> {
    let scenario = if is_scenario(&r.model) {
        if r.kinematics.is_some() {
            return Err(CliError::usage(
                "--kinematics: an RL scenario names its kinematic model itself",
            ));
        }
        if r.place.is_some() {
            return Err(CliError::usage(
                "--place: an RL scenario places its robot itself (<kinematics><world>)",
            ));
        }
        Some(ScenarioRobot::load(&r.model, false)?)
    } else {
        None
    };
    let (model, kinematics) = match &scenario {
        Some(s) => (s.scene.clone(), Some(s.kinematics.clone())),
        None => (r.model.clone(), r.kinematics.clone()),
    };
    if load::is_urdf(&model) {
        refuse_given(
            &["kinematics"],
            "to a URDF robot: the URDF is its kinematic model",
        )?;
    } else {
        refuse_given(
            &["floating-base", "mimic-independent"],
            "to an RL scene's robot: they set how URDF joints load",
        )?;
    }
    let place = match (&scenario, &r.place) {
        (Some(s), _) => Some(s.place),
        (None, Some(p)) => Some(parse_place(p, "--place")?),
        (None, None) => None,
    };
    let srdf = rl_sg::load::srdf::for_robot(&model, r.srdf.as_deref());
    let setup = load::RobotSetup {
        model,
        kinematics,
        srdf,
        environment: r.env.clone(),
        urdf: UrdfOptions {
            floating_base: r.floating_base,
            mimic: if r.mimic_independent {
                MimicJoints::Independent
            } else {
                MimicJoints::Reject
            },
            ..UrdfOptions::default()
        },
        geometry: geometry_options(&r.geometry, Kind::Collision),
    };
    let loaded = Box::new(setup.load::<CAPACITY>().map_err(usage)?);
    let RobotScene {
        mut scene,
        robot,
        kinematics,
    } = *loaded;
    if let Some(x) = place {
        scene
            .model_mut(robot)
            .ok_or_else(|| CliError::usage("no robot model to place"))?
            .set_base(x)
            .map_err(|e| CliError::usage(format!("--place: {e}")))?;
    }
    // Obstacles from --env, or the other models of an RL scene.
    let env = scene.models().len() > 1;
    Ok(Setup {
        scene,
        robot,
        kinematics: Box::new(kinematics),
        env,
        scenario,
    })
}

/// Parses `--q` for `s`: `start` or `goal` of its scenario, or exactly nq finite numbers.
fn scenario_q(text: &str, s: &Setup) -> Result<Vec<f64>, CliError> {
    let n = s.kinematics.model.nq();
    match (text.trim(), &s.scenario) {
        ("start", Some(sc)) => Ok(sc.start.clone()),
        ("goal", Some(sc)) => Ok(sc.goal.clone()),
        ("start" | "goal", None) => Err(CliError::usage(format!(
            "--q {}: start and goal come from an RL scenario (rlplan XML) given as the model",
            text.trim()
        ))),
        _ => parse_q(text, n),
    }
}

/// Parses `--q`: exactly `n` finite numbers.
fn parse_q(text: &str, n: usize) -> Result<Vec<f64>, CliError> {
    let mut q = Vec::with_capacity(n);
    for (i, part) in text.split(',').enumerate() {
        match part.trim().parse::<f64>() {
            Ok(x) if x.is_finite() => q.push(x),
            _ => {
                return Err(CliError::usage(format!(
                    "--q: value {i} ({part:?}) is not a finite number"
                )));
            }
        }
    }
    if q.len() != n {
        return Err(CliError::usage(format!(
            "--q: {} values given, the model needs {n}",
            q.len()
        )));
    }
    Ok(q)
}

fn place(s: &mut Setup, q: &[f64]) -> Result<(), CliError> {
    let mut data = Box::new(Data::<CAPACITY>::new());
    s.scene
        .set_configuration(s.robot, &s.kinematics.model, &mut data, q)
        .map_err(|e| CliError::usage(format!("--q: {e}")))
}

fn distance_json(d: &Option<NamedDistance>) -> Value {
    match d {
        Some(d) => {
            json!({"a": d.a, "b": d.b, "distance": d.distance, "point_a": d.point_a, "point_b": d.point_b})
        }
        None => Value::Null,
    }
}

fn check(a: CheckArgs) -> CliResult {
    let mut s = setup(&a.robot)?;
    let q = scenario_q(&a.q, &s)?;
    place(&mut s, &q)?;
    let r = report::check(&s.scene, s.robot);
    let robot = &s.scene.models()[s.robot.0];
    let pair = |v: &[(String, String)]| v.iter().map(|(a, b)| json!([a, b])).collect::<Vec<_>>();
    let mut out = json!({
        "model": robot.name(),
        "q": q,
        "colliding": r.colliding,
        "collisions": pair(&r.collisions),
        "self_collisions": pair(&r.self_collisions),
        "min_distance": distance_json(&r.min_distance),
        "self_min_distance": distance_json(&r.self_min_distance),
        "self_pairs_checked": r.self_pairs_checked,
        "warnings": robot.warnings(),
    });
    if s.env {
        out["environment_collisions"] = json!(pair(&r.environment_collisions));
        out["environment_min_distance"] = distance_json(&r.environment_min_distance);
        out["environment_bodies"] = json!(r.environment_bodies);
    }
    rl::json::tag("scene.check", 1, &mut out);
    outln!("{}", serde_json::to_string_pretty(&out).unwrap_or_default())?;
    Ok(ExitCode::SUCCESS)
}

fn geometry_json(g: &Geometry) -> Value {
    let mesh = |m: &rl_sg::TriangleMesh| {
        json!({
            "vertices": m.vertices().iter().map(|v| v.to_array()).collect::<Vec<_>>(),
            "triangles": m.triangles(),
        })
    };
    match g {
        Geometry::Box { size } => json!({"kind": "box", "size": size.to_array()}),
        Geometry::Sphere { radius } => json!({"kind": "sphere", "radius": radius}),
        Geometry::Cylinder { radius, length } => {
            json!({"kind": "cylinder", "radius": radius, "length": length})
        }
        Geometry::Capsule { radius, length } => {
            json!({"kind": "capsule", "radius": radius, "length": length})
        }
        Geometry::Cone { radius, length } => {
            json!({"kind": "cone", "radius": radius, "length": length})
        }
        Geometry::Convex(m) => {
            let mut v = mesh(m);
            v["kind"] = json!("convex");
            v
        }
        Geometry::Mesh(m) => {
            let mut v = mesh(m);
            v["kind"] = json!("mesh");
            v
        }
        Geometry::HalfSpace { normal, offset } => {
            json!({"kind": "halfspace", "normal": normal.to_array(), "offset": offset})
        }
    }
}

fn dump(a: DumpArgs) -> CliResult {
    let mut s = setup(&a.robot)?;
    let nq = s.kinematics.model.nq();
    let mut qs = Vec::new();
    if let Some(q) = &a.q {
        qs.push(scenario_q(q, &s)?);
    }
    let random = random_configs(&s.kinematics.model, a.random);
    qs.extend(random.chunks(nq.max(1)).take(a.random).map(<[f64]>::to_vec));
    if qs.is_empty() {
        return Err(CliError::usage("give --q or --random N"));
    }
    // Shapes once (their own frames), then their world poses per configuration.
    let mut ids = Vec::new();
    let mut shapes = Vec::new();
    for (mi, m) in s.scene.models().iter().enumerate() {
        for (bi, b) in m.bodies().iter().enumerate() {
            for (si, sh) in b.shapes().iter().enumerate() {
                let mut v = geometry_json(sh.geometry());
                v["model"] = json!(m.name());
                v["body"] = json!(report::body_label(
                    &s.scene,
                    rl_sg::BodyId {
                        model: mi,
                        body: bi
                    }
                ));
                if let Some(p) = sh.source() {
                    v["source"] = json!(p.display().to_string());
                    v["scale"] = json!(sh.source_scale().to_array());
                }
                shapes.push(v);
                ids.push(rl_sg::ShapeId {
                    model: mi,
                    body: bi,
                    shape: si,
                });
            }
        }
    }
    let index = |id: &rl_sg::ShapeId| ids.iter().position(|x| x == id).unwrap_or(usize::MAX);
    let pairs = |f: CollisionFilter| -> Vec<[usize; 2]> {
        s.scene
            .pairs_checked(&f)
            .iter()
            .map(|(a, b)| [index(a), index(b)])
            .collect()
    };
    let self_pairs = pairs(CollisionFilter::SelfCollision(s.robot));
    let env_pairs = pairs(CollisionFilter::Against(s.robot));
    let mut configs = Vec::new();
    for q in &qs {
        place(&mut s, q)?;
        let poses: Vec<_> = ids
            .iter()
            .map(|id| {
                let x = s
                    .scene
                    .shape(*id)
                    .map(|sh| sh.world_pose())
                    .unwrap_or_default();
                let r = x.quaternion();
                [
                    x.translation.x,
                    x.translation.y,
                    x.translation.z,
                    r.x,
                    r.y,
                    r.z,
                    r.w,
                ]
            })
            .collect();
        configs.push(json!({"q": q, "poses": poses}));
    }
    let out = rl::json::versioned(
        "scene.dump",
        1,
        json!({
            "robot_model": s.scene.models()[s.robot.0].name(),
            "shapes": shapes,
            "self_pairs": self_pairs,
            "environment_pairs": env_pairs,
            "configs": configs,
        }),
    );
    outln!("{}", serde_json::to_string(&out).unwrap_or_default())?;
    Ok(ExitCode::SUCCESS)
}

/// `n` configurations of `model` within its limits, one after the other (SplitMix64 seed
/// 0x5CE7E): the same for `rl scene bench` and `rl scene dump --random`.
fn random_configs(model: &rl_core::Model<CAPACITY>, n: usize) -> Vec<f64> {
    let mut rng = SplitMix64::new(0x5CE7E);
    let nq = model.nq();
    let mut qs = vec![0.0; nq * n];
    for c in 0..n {
        model.random_configuration(&mut qs[c * nq..(c + 1) * nq], || rng.next_f64());
    }
    qs
}

fn info(a: InfoArgs) -> CliResult {
    let opts = geometry_options(&a.geometry, a.kind);
    let scene = load::load_scene_file(&a.file, &opts, &mut MeshCache::new()).map_err(usage)?;
    let shape_line = |sh: &rl_sg::Shape| -> (String, usize) {
        let (desc, tris) = match sh.geometry() {
            Geometry::Box { size } => (format!("box {} × {} × {}", size.x, size.y, size.z), 0),
            Geometry::Sphere { radius } => (format!("sphere r {radius}"), 0),
            Geometry::Cylinder { radius, length } => (format!("cylinder r {radius} l {length}"), 0),
            Geometry::Capsule { radius, length } => (format!("capsule r {radius} l {length}"), 0),
            Geometry::Cone { radius, length } => (format!("cone r {radius} l {length}"), 0),
            Geometry::Convex(m) => (
                format!("convex hull, {} vertices", m.vertices().len()),
                m.triangles().len(),
            ),
            Geometry::Mesh(m) => (
                format!(
                    "mesh, {} vertices, {} triangles",
                    m.vertices().len(),
                    m.triangles().len()
                ),
                m.triangles().len(),
            ),
            Geometry::HalfSpace { normal, offset } => {
                (format!("half-space n {normal:?} d {offset}"), 0)
            }
        };
        match sh.source() {
            Some(p) => (format!("{desc} ({})", p.display()), tris),
            None => (desc, tris),
        }
    };
    if a.json {
        let models: Vec<_> = scene
            .models()
            .iter()
            .map(|m| {
                let bodies: Vec<_> = m
                    .bodies()
                    .iter()
                    .map(|b| {
                        let shapes: Vec<_> = b
                            .shapes()
                            .iter()
                            .map(|sh| {
                                let mut v = geometry_json(sh.geometry());
                                if let Some(o) = v.as_object_mut() {
                                    o.remove("vertices");
                                    o.remove("triangles");
                                }
                                v["name"] = json!(sh.name());
                                v["source"] = json!(sh.source().map(|p| p.display().to_string()));
                                v["triangles"] = json!(shape_line(sh).1);
                                v
                            })
                            .collect();
                        json!({"name": b.name(), "shapes": shapes})
                    })
                    .collect();
                json!({"name": m.name(), "bodies": bodies, "self_collision": m.self_collision(),
                       "allowed_pairs": m.allowed_collisions().len(), "warnings": m.warnings()})
            })
            .collect();
        outln!(
            "{}",
            serde_json::to_string_pretty(&rl::json::versioned(
                "scene.info",
                1,
                json!({"file": a.file.display().to_string(), "models": models})
            ))
            .unwrap_or_default()
        )?;
        return Ok(ExitCode::SUCCESS);
    }
    outln!("scene      {}", a.file.display())?;
    let (mut shapes, mut meshes, mut triangles) = (0, 0, 0);
    for m in scene.models() {
        outln!(
            "model      \"{}\": {} bodies, {} shapes{}",
            m.name(),
            m.bodies().len(),
            m.shape_count(),
            if m.self_collision() {
                format!(
                    ", {} allowed pairs, {} self-collision pairs",
                    m.allowed_collisions().len(),
                    m.self_collision_pairs().len()
                )
            } else {
                String::new()
            }
        )?;
        for b in m.bodies() {
            outln!("  body     \"{}\"", b.name())?;
            for sh in b.shapes() {
                let (line, tris) = shape_line(sh);
                outln!("    shape  {line}")?;
                shapes += 1;
                if tris > 0 {
                    meshes += 1;
                    triangles += tris;
                }
            }
        }
        for w in m.warnings() {
            outln!("warning: {w}")?;
        }
    }
    outln!("total      {shapes} shapes, {meshes} meshes, {triangles} triangles")?;
    Ok(ExitCode::SUCCESS)
}

/// Median over `rounds` of the mean ns per call of `query` over all configurations, each
/// configuration set (untimed) by `set` before its calls; `tick` is called after each round
/// (untimed: the progress line).
fn per_query(
    tick: &dyn Fn(),
    configs: usize,
    rounds: usize,
    mut set: impl FnMut(usize),
    mut query: impl FnMut() -> bool,
) -> f64 {
    // Repetitions per configuration for ~20 µs of work each.
    set(0);
    let t = Instant::now();
    black_box(query());
    let once = t.elapsed().as_secs_f64().max(2e-8);
    let reps = ((2e-5 / once).ceil() as usize).clamp(1, 1000);
    let mut samples: Vec<f64> = (0..rounds.max(1))
        .map(|_| {
            let mut total = 0.0;
            for c in 0..configs {
                set(c);
                let t = Instant::now();
                for _ in 0..reps {
                    black_box(query());
                }
                total += t.elapsed().as_secs_f64();
            }
            tick();
            total * 1e9 / (configs * reps) as f64
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

fn bench(a: BenchArgs) -> CliResult {
    let mut s = setup(&a.robot)?;
    let configs = a.configs.max(1);
    let km = &s.kinematics.model;
    let nq = km.nq();
    let qs = random_configs(km, configs);
    let mut rng = SplitMix64::new(0x0B57AC1E);
    let q = |c: usize| &qs[c * nq..(c + 1) * nq];
    let mut data = Box::new(Data::<CAPACITY>::new());
    let robot = s.robot;
    let mut colliding = 0;
    for c in 0..configs {
        s.scene
            .set_configuration(robot, km, &mut data, q(c))
            .map_err(|e| CliError::failed(e.to_string()))?;
        colliding += usize::from(s.scene.is_colliding(&CollisionFilter::SelfCollision(robot)));
    }
    let scene = std::cell::RefCell::new(s.scene);
    let data = std::cell::RefCell::new(data);
    let set = |c: usize| {
        let mut d = data.borrow_mut();
        let _ = scene
            .borrow_mut()
            .set_configuration(robot, km, &mut d, q(c));
    };
    let mut out: Vec<(&str, f64)> = Vec::new();
    // Progress: rounds of every query timed so far, on a terminal only.
    let queries = if s.env { 8 } else { 6 };
    let total = queries * a.rounds.max(1);
    let rounds_done = std::cell::Cell::new(0);
    let line = std::cell::RefCell::new(ProgressLine::stderr("rl scene bench: "));
    let started = Instant::now();
    let tick = || {
        rounds_done.set(rounds_done.get() + 1);
        line.borrow_mut().update(|| {
            format!(
                "{} rounds of {queries} queries, {:.0} s",
                fraction(rounds_done.get(), total),
                started.elapsed().as_secs_f64()
            )
        });
    };
    let next = std::cell::Cell::new(0);
    let update = per_query(
        &tick,
        configs,
        a.rounds,
        |_| {},
        || {
            let c = (next.get() + 1) % configs;
            next.set(c);
            let mut d = data.borrow_mut();
            scene
                .borrow_mut()
                .set_configuration(robot, km, &mut d, q(c))
                .is_ok()
        },
    );
    out.push(("update", update));
    let own = CollisionFilter::SelfCollision(robot);
    out.push((
        "self_collision",
        per_query(&tick, configs, a.rounds, set, || {
            scene.borrow().is_colliding(&own)
        }),
    ));
    out.push((
        "self_distance",
        per_query(&tick, configs, a.rounds, set, || {
            scene.borrow().min_distance(&own).is_some()
        }),
    ));
    if s.env {
        let env = CollisionFilter::Against(robot);
        out.push((
            "environment",
            per_query(&tick, configs, a.rounds, set, || {
                scene.borrow().is_colliding(&env)
            }),
        ));
        out.push((
            "environment_distance",
            per_query(&tick, configs, a.rounds, set, || {
                scene.borrow().min_distance(&env).is_some()
            }),
        ));
    }
    // The control-rate path: capsules fitted to the links, ten obstacle spheres in reach.
    let options = FitOptions {
        per_body: a.capsules_per_link.max(1),
        ..FitOptions::default()
    };
    let fitted = fit_capsule_model::<256>(&scene.borrow().models()[robot.0], &options)
        .map_err(|e| CliError::failed(e.to_string()))?;
    let mut caps = Box::new(fitted.capsules.clone());
    let (lo, hi) = scene.borrow().models()[robot.0]
        .bodies()
        .iter()
        .filter_map(|b| b.world_aabb())
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), (a, b)| {
            (l.min(a), h.max(b))
        });
    let spheres: Vec<Capsule> = (0..10)
        .map(|_| {
            let p = lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            Capsule::sphere(p, 0.05 + 0.1 * rng.next_f64())
        })
        .collect();
    let fk = |c: usize| {
        let mut d = data.borrow_mut();
        let _ = rl_core::algo::forward_position(km, &mut d, q(c));
    };
    let sphere_path = per_query(&tick, configs, a.rounds, fk, || {
        let d = data.borrow();
        caps.update(&d);
        caps.min_distance(&spheres).is_some()
    });
    out.push(("sphere_path", sphere_path));
    let pairs = fitted.self_pairs.clone();
    out.push((
        "sphere_path_self",
        per_query(&tick, configs, a.rounds, fk, || {
            caps.update(&data.borrow());
            caps.min_self_distance(&pairs).is_some()
        }),
    ));
    line.borrow_mut().clear();
    let name = scene.borrow().models()[robot.0].name().to_string();
    if a.json {
        let mut v = json!({
            "model": name, "configs": configs, "self_colliding_configs": colliding,
            "capsules": fitted.capsules.len(), "obstacle_spheres": spheres.len(),
        });
        for (k, ns) in &out {
            v[format!("{k}_ns")] = json!(ns);
        }
        rl::json::tag("scene.bench", 1, &mut v);
        outln!("{}", serde_json::to_string(&v).unwrap_or_default())?;
    } else {
        outln!(
            "{name}: {configs} random configurations ({colliding} self-colliding), {} capsules, {} obstacle spheres",
            fitted.capsules.len(),
            spheres.len()
        )?;
        for (k, ns) in &out {
            outln!("  {k:<22} {ns:>12.0} ns per query")?;
        }
    }
    Ok(ExitCode::SUCCESS)
}
