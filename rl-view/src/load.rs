//! Loading what the viewer shows: the robots (rl-core's loaders, URDF or RL XML), their
//! geometry as an rl-sg scene built from the same files, the obstacles (`--env`: a MoveIt
//! planning scene, an RL scene, VRML or a URDF, through [`rl_sg::load::load_scene_file`]), the
//! SRDF (`--srdf`, for the first model), and the fixed table of files the page may fetch.
//!
//! Scene model `i` of [`World::scene`] is robot `i` (the Coach model index, the order on the
//! command line); the obstacles' models follow.
//!
//! An RL scene (rlsg XML) with the rlmdl files of its first models (RL's `rlCoachMdl scene.xml
//! model.xml …`) gives robots drawn and checked with the scene's own geometry; its other models
//! are obstacles.
//!
//! An RL scene held in memory ([`ModelSource::Embedded`], e.g. the `rl` tool's default robot
//! with RL's visual meshes) is read the same way from an [`EmbeddedFiles`] table.
//!
//! URDF robots collide with their `<collision>` geometry; the page draws their `<visual>`
//! geometry (or the collision geometry where visual meshes are missing). RL XML models without
//! a scene carry no geometry: they get a skeleton (a sphere at every body origin, a capsule
//! from it to each child joint) which is drawn, and checked against the obstacles but not
//! against itself.
//!
//! Per robot ([`RobotOptions`]): where its kinematic world frame is placed (`rl view --place`,
//! RL's rlplan `<world>`), its SRDF (allowed pairs, and the named state it starts at: `home`,
//! else `ready`, else the first `<group_state>`), a start configuration. A planned path or a
//! planning problem's start and goal (for robot 0) are shown as ghosts and a trail of the
//! tool ([`PlanView`]).

use std::path::PathBuf;
use std::sync::Arc;

use glam::{DQuat, DVec3};
use rl_core::algo::tool_pose;
use rl_core::loader::{self as core_loader, LoadedModel, UrdfOptions};
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_sg::load::{
    self, EmbeddedFiles, GeometryKind, MeshCache, MeshMode, SceneLimits, UrdfGeometryOptions,
};
use rl_sg::{Geometry, KinematicLink, Model, Scene, Shape};

use crate::error::ViewError;
use crate::files::FileTable;
use crate::path::PathData;

/// Capacity of the viewer's kinematic models (bodies and degrees of freedom).
pub const CAPACITY: usize = 64;

/// Radius of the skeleton drawn for RL XML models, m.
const SKELETON_RADIUS: f64 = 0.03;

/// Where a robot comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelSource {
    /// A URDF or RL XML (rlmdl) file.
    File(PathBuf),
    /// An RL scene (rlsg XML with its VRML) whose first models are the robots of RL kinematic
    /// models (rlmdl), in order, as RL's `rlCoachMdl scene.xml model1.xml …` takes them; the
    /// scene's other models are obstacles.
    RlScene {
        /// The rlsg file.
        scene: PathBuf,
        /// One rlmdl file per robot, paired with the scene's models in order.
        kinematics: Vec<PathBuf>,
    },
    /// URDF or RL XML text (e.g. the embedded default robot), with a name for messages.
    Text {
        /// What to call it in messages (`"the embedded RV-6SL"`).
        name: String,
        /// The XML.
        text: String,
    },
    /// An RL scene held in memory whose first model is the robot of the RL kinematic model
    /// `kinematics` (rlmdl or rlkin text), drawn and checked with the scene's geometry; the
    /// scene's other models are obstacles.
    Embedded {
        /// What to call it in messages.
        name: String,
        /// The rlmdl or rlkin XML.
        kinematics: String,
        /// The rlsg file in `files`.
        scene: PathBuf,
        /// The scene's files (rlsg XML, VRML and what it inlines).
        files: Arc<EmbeddedFiles>,
    },
}

impl ModelSource {
    fn describe(&self) -> String {
        match self {
            ModelSource::File(p) | ModelSource::RlScene { scene: p, .. } => p.display().to_string(),
            ModelSource::Text { name, .. } | ModelSource::Embedded { name, .. } => name.clone(),
        }
    }
}

/// What to load.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// The robots, in Coach model order.
    pub models: Vec<ModelSource>,
    /// Obstacles (MoveIt planning-scene YAML, rlsg XML, VRML, URDF).
    pub env: Option<PathBuf>,
    /// Allowed collision pairs (and named states) of the first model (SRDF), unless
    /// [`RobotOptions::srdf`] of robot 0 names one.
    pub srdf: Option<PathBuf>,
    /// A path to play back (`rl plan --out` or `--trajectory` CSV), for model 0.
    pub path: Option<PathBuf>,
    /// A path to show for model 0 given as data (e.g. the one `rl run --plan` follows), in
    /// place of [`LoadOptions::path`].
    pub path_data: Option<PathData>,
    /// Where `package://` URIs are looked up (besides `$ROS_PACKAGE_PATH` and the files'
    /// ancestors).
    pub package_dirs: Vec<PathBuf>,
    /// Per robot, in Coach model order (missing entries: the defaults).
    pub robots: Vec<RobotOptions>,
    /// URDF robots get a six-DOF root joint (q starts with x, y, z, qx, qy, qz, qw).
    pub floating_base: bool,
    /// The goal of a planning problem for robot 0 (shown as a ghost with its start, the
    /// robot's start configuration).
    pub goal: Option<Vec<f64>>,
}

/// Options of one robot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotOptions {
    /// Where its kinematic world frame is placed in the scene (`None`: where its files put it).
    pub place: Option<PlueckerTransform>,
    /// Its SRDF: allowed collision pairs, and the named state it starts at.
    pub srdf: Option<PathBuf>,
    /// Where it starts (before the SRDF's named state and the model's home).
    pub start: Option<Vec<f64>>,
}

/// What the page shows of a plan for one robot: ghosts at its start and goal, and the trail
/// of its tool between them.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanView {
    /// The robot.
    pub model: usize,
    /// Start configuration.
    pub start: Vec<f64>,
    /// Goal configuration.
    pub goal: Vec<f64>,
    /// World poses of the robot's scene bodies at the start (as the state's `bodies`).
    pub start_bodies: Vec<PlueckerTransform>,
    /// ... at the goal.
    pub goal_bodies: Vec<PlueckerTransform>,
    /// Tool positions along the path, world frame (empty without a path).
    pub trail: Vec<DVec3>,
}

/// One coordinate of a robot's `q`.
#[derive(Clone, Debug, PartialEq)]
pub struct JointInfo {
    /// Joint name (`name[k]` for joints with several coordinates).
    pub name: String,
    /// `revolute`, `continuous`, `prismatic` or `other`.
    pub kind: &'static str,
    /// Lower limit (rad or m; `-inf` when none).
    pub min: f64,
    /// Upper limit.
    pub max: f64,
    /// `rad`, `m` or `""`.
    pub unit: &'static str,
    /// Speed limit (rad/s or m/s; infinite when the model gives none).
    pub max_speed: f64,
}

/// A loaded robot.
#[derive(Clone, Debug)]
pub struct Robot {
    /// Its name (the model's).
    pub name: String,
    /// The kinematic model.
    pub kinematics: Box<LoadedModel<CAPACITY>>,
    /// `/files/<i>/robot.urdf` for URDF robots.
    pub urdf: Option<String>,
    /// The geometry the page draws (same bodies, same order, as the collision model).
    pub visual: Model,
    /// The tool the IK target drags (index into the model's tools).
    pub tool: usize,
    /// The coordinates of `q`.
    pub joints: Vec<JointInfo>,
    /// The configuration it starts at: the one given, the SRDF's named state, RL's home, or
    /// neutral.
    pub initial_q: Vec<f64>,
    /// Where `initial_q` came from (`"start"`, `"srdf:NAME"`, `"home"`, `"neutral"`).
    pub initial_source: String,
    /// Where its kinematic world frame is in the scene.
    pub base: PlueckerTransform,
    /// Notes made while loading (missing meshes, ignored elements).
    pub warnings: Vec<String>,
}

/// Everything the viewer shows.
#[derive(Clone, Debug)]
pub struct World {
    /// The robots, in Coach model order.
    pub robots: Vec<Robot>,
    /// Collision geometry: robot `i` is scene model `i`, the obstacles follow.
    pub scene: Scene,
    /// The files the page may fetch.
    pub files: FileTable,
    /// The path to play back.
    pub path: Option<PathData>,
    /// Ghosts and trail of a plan, if there is one.
    pub plan: Option<PlanView>,
}

fn load_err(what: impl Into<String>, e: impl std::fmt::Display) -> ViewError {
    ViewError::Load {
        what: what.into(),
        reason: e.to_string(),
    }
}

fn geometry_options(kind: GeometryKind, package_dirs: &[PathBuf]) -> UrdfGeometryOptions {
    UrdfGeometryOptions {
        kind,
        package_dirs: package_dirs.to_vec(),
        mesh: MeshMode::Mesh,
        strict_meshes: false,
    }
}

/// Whether `path` is an RL scene (an XML file whose root element is `<rlsg>`).
pub fn is_rl_scene(path: &std::path::Path) -> bool {
    let limits = rl_core::loader::InputLimits::DEFAULT;
    rl_core::loader::read_text(path, limits.max_bytes).is_ok_and(|t| {
        rl_core::loader::check_xml(&t, &limits).is_ok()
            && roxmltree::Document::parse(&t).is_ok_and(|d| d.root_element().has_tag_name("rlsg"))
    })
}

/// The coordinates of `q` of a kinematic model.
pub fn joint_infos(k: &LoadedModel<CAPACITY>) -> Vec<JointInfo> {
    use rl_core::joint::JointKind;
    let m = &k.model;
    let mut out = Vec::with_capacity(m.nq());
    for b in 0..m.body_count() {
        let nq = m.joint_nq(b);
        if nq == 0 {
            continue;
        }
        let name = m.joint_name(b).to_string();
        let kind = m.joint(b).kind();
        if nq == 1 && matches!(kind, JointKind::Revolute | JointKind::Prismatic) {
            let lim = m.limits(m.v_index(b));
            let prismatic = kind == JointKind::Prismatic;
            let max_speed = if lim.velocity > 0.0 {
                lim.velocity
            } else {
                f64::INFINITY
            };
            out.push(JointInfo {
                name,
                kind: if prismatic {
                    "prismatic"
                } else if lim.wraparound || k.joint_source_type(b) == Some("continuous") {
                    "continuous"
                } else {
                    "revolute"
                },
                min: if lim.wraparound {
                    -std::f64::consts::PI
                } else {
                    lim.lower
                },
                max: if lim.wraparound {
                    std::f64::consts::PI
                } else {
                    lim.upper
                },
                unit: if prismatic { "m" } else { "rad" },
                max_speed,
            });
        } else if kind == JointKind::SixDof {
            // x, y, z (m) and the unit quaternion qx, qy, qz, qw: the page turns the four
            // into roll, pitch and yaw sliders.
            for (c, axis) in ["x", "y", "z", "qx", "qy", "qz", "qw"].iter().enumerate() {
                out.push(JointInfo {
                    name: format!("{name}[{axis}]"),
                    kind: if c < 3 { "position" } else { "quaternion" },
                    min: f64::NEG_INFINITY,
                    max: f64::INFINITY,
                    unit: if c < 3 { "m" } else { "" },
                    max_speed: f64::INFINITY,
                });
            }
        } else {
            for c in 0..nq {
                out.push(JointInfo {
                    name: format!("{name}[{c}]"),
                    kind: "other",
                    min: f64::NEG_INFINITY,
                    max: f64::INFINITY,
                    unit: "",
                    max_speed: f64::INFINITY,
                });
            }
        }
    }
    out
}

/// The tool the IK target drags: `tool0` if the model has one, else its first tool.
fn pick_tool(k: &LoadedModel<CAPACITY>) -> usize {
    let tools = k.model.tools();
    ["tool0", "tool", "ee_link"]
        .iter()
        .find_map(|n| tools.iter().position(|t| t.name.as_str() == *n))
        .unwrap_or(0)
}

/// A pose placing a z-aligned shape of length `|d|` between `a` and `a + d`.
fn segment_pose(a: DVec3, d: DVec3) -> PlueckerTransform {
    let len = d.length();
    let rot = if len > 0.0 {
        DQuat::from_rotation_arc(DVec3::Z, d / len)
    } else {
        DQuat::IDENTITY
    };
    PlueckerTransform::from_quat_translation(rot, a + d * 0.5)
}

/// The skeleton of an RL XML model: one scene body per rl-core body (named after it), and a base
/// body fixed to the world.
pub fn skeleton(k: &LoadedModel<CAPACITY>) -> Result<Model, ViewError> {
    let m = &k.model;
    let err = |e: rl_sg::SgError| load_err(format!("skeleton of \"{}\"", m.name()), e);
    let mut model = Model::new(m.name());
    let mut frames = Vec::with_capacity(m.body_count() + 1);
    let add = |model: &mut Model, name: &str, parent: usize| -> Result<(), ViewError> {
        let body = model.add_body(name);
        body.push_shape(
            Shape::new(
                format!("{name}/joint"),
                Geometry::sphere(SKELETON_RADIUS * 1.4).map_err(err)?,
                PlueckerTransform::IDENTITY,
            )
            .map_err(err)?,
        );
        for c in (0..m.body_count()).filter(|&c| m.parent(c) == parent) {
            let d = m.placement(c).translation;
            if d.length() > 1e-6 {
                body.push_shape(
                    Shape::new(
                        format!("{name}/link/{c}"),
                        Geometry::capsule(SKELETON_RADIUS, d.length()).map_err(err)?,
                        segment_pose(DVec3::ZERO, d),
                    )
                    .map_err(err)?,
                );
            }
        }
        Ok(())
    };
    add(&mut model, "base", ROOT)?;
    frames.push(Some((ROOT, PlueckerTransform::IDENTITY)));
    for b in 0..m.body_count() {
        let name = m.body_name(b).to_string();
        add(&mut model, &name, b)?;
        frames.push(Some((b, PlueckerTransform::IDENTITY)));
    }
    let link = KinematicLink::new(frames, m.body_count()).map_err(err)?;
    model.set_kinematics(link);
    model.set_self_collision(false);
    Ok(model)
}

/// Loads robot `index` from `source`: its kinematics, collision model (returned) and drawn
/// geometry; URDF files are added to `files`.
fn load_robot(
    index: usize,
    source: &ModelSource,
    options: &LoadOptions,
    files: &mut FileTable,
    cache: &mut MeshCache,
) -> Result<(Robot, Model), ViewError> {
    let what = source.describe();
    let package_dirs = &options.package_dirs;
    let urdf_options = UrdfOptions {
        floating_base: options.floating_base,
        ..UrdfOptions::default()
    };
    let mut warnings = Vec::new();
    let (kinematics, collision, visual, urdf) = match source {
        ModelSource::File(path) if load::is_urdf(path) => {
            let opts = geometry_options(GeometryKind::Collision, package_dirs);
            let r = load::load_robot::<CAPACITY>(path, &opts, &urdf_options, cache)
                .map_err(|e| load_err(&what, e))?;
            let served = files.add_urdf(index, path, package_dirs)?;
            warnings.extend(served.warnings);
            let vopts = geometry_options(GeometryKind::Visual, package_dirs);
            let visual = match load::urdf::load_geometry(path, &vopts, cache) {
                Ok(v) => v,
                Err(e) => {
                    // Missing visual meshes are noted one by one already.
                    if !warnings.iter().any(|w| w.contains("visual mesh")) {
                        warnings.push(format!(
                            "visual geometry not loaded ({e}): the collision geometry is drawn"
                        ));
                    }
                    r.model.clone()
                }
            };
            (r.kinematics, r.model, visual, Some(served.url))
        }
        ModelSource::File(path) if is_rl_scene(path) => {
            return Err(load_err(
                &what,
                "an RL scene: give the kinematic models of its robots (rl view SCENE \
                 --kinematics MODEL.xml …)",
            ));
        }
        ModelSource::RlScene { .. } | ModelSource::Embedded { .. } => {
            return Err(load_err(&what, "an RL scene is loaded by rl_scene_robots"));
        }
        ModelSource::File(path) => {
            let k = core_loader::load_file::<CAPACITY>(path).map_err(|e| load_err(&what, e))?;
            let sk = skeleton(&k)?;
            (k, sk.clone(), sk, None)
        }
        ModelSource::Text { text, .. } => {
            let k = core_loader::load_str::<CAPACITY>(text, &UrdfOptions::default())
                .map_err(|e| load_err(&what, e))?;
            let sk = skeleton(&k)?;
            (k, sk.clone(), sk, None)
        }
    };
    Ok(finish_robot(
        index, kinematics, urdf, visual, collision, warnings, files,
    ))
}

/// A robot from its parts; its drawn meshes are added to `files`.
fn finish_robot(
    index: usize,
    kinematics: LoadedModel<CAPACITY>,
    urdf: Option<String>,
    visual: Model,
    collision: Model,
    mut warnings: Vec<String>,
    files: &mut FileTable,
) -> (Robot, Model) {
    if kinematics.model.tools().is_empty() {
        warnings.push("the model has no tool: inverse kinematics is off".into());
    }
    warnings.extend(collision.warnings().iter().cloned());
    // Every mesh drawn must be in the file table (the collision stand-ins may not be yet).
    for b in visual.bodies() {
        for s in b.shapes() {
            if let Some(p) = s.source() {
                files.add_mesh_file(index, p);
            }
        }
    }
    let robot = Robot {
        name: kinematics.model.name().to_string(),
        tool: pick_tool(&kinematics),
        joints: joint_infos(&kinematics),
        initial_q: kinematics.home_or_neutral(),
        initial_source: if kinematics.home.is_some() {
            "home"
        } else {
            "neutral"
        }
        .into(),
        base: PlueckerTransform::IDENTITY,
        kinematics: Box::new(kinematics),
        urdf,
        visual,
        warnings,
    };
    (robot, collision)
}

/// A robot and its collision model.
type RobotAndGeometry = (Robot, Model);

/// The robots of an RL scene (its first `kinematics.len()` models, linked to their rlmdl
/// or rlkin files as rl-sg's [`load::rlsg::link_kinematics`] does) and the scene's other models
/// (obstacles).
fn rl_scene_robots(
    first_index: usize,
    scene: &std::path::Path,
    kinematics: &[PathBuf],
    files: &mut FileTable,
) -> Result<(Vec<RobotAndGeometry>, Vec<Model>), ViewError> {
    let what = scene.display().to_string();
    let s = load::rlsg::load_scene(scene).map_err(|e| load_err(&what, e))?;
    if kinematics.is_empty() {
        return Err(load_err(
            &what,
            "an RL scene: give the kinematic models of its robots, in the scene's order \
             (--kinematics MODEL.xml …)",
        ));
    }
    if kinematics.len() > s.models().len() {
        return Err(load_err(
            &what,
            format!(
                "{} kinematic models given for a scene of {} models",
                kinematics.len(),
                s.models().len()
            ),
        ));
    }
    let mut robots = Vec::with_capacity(kinematics.len());
    for (j, kpath) in kinematics.iter().enumerate() {
        let kwhat = kpath.display().to_string();
        let k = core_loader::load_file::<CAPACITY>(kpath).map_err(|e| load_err(&kwhat, e))?;
        let mut model = s.models()[j].clone();
        load::rlsg::link_kinematics(&mut model, kpath, &k).map_err(|e| load_err(&kwhat, e))?;
        let warnings = Vec::new();
        robots.push(finish_robot(
            first_index + j,
            k,
            None,
            model.clone(),
            model,
            warnings,
            files,
        ));
    }
    let rest = s.models()[kinematics.len()..].to_vec();
    Ok((robots, rest))
}

/// The robot of an RL scene held in memory (its first model, linked to the kinematics text)
/// and the scene's other models (obstacles).
fn embedded_scene_robot(
    index: usize,
    name: &str,
    kinematics: &str,
    scene: &std::path::Path,
    embedded: &Arc<EmbeddedFiles>,
    files: &mut FileTable,
) -> Result<(RobotAndGeometry, Vec<Model>), ViewError> {
    let s = load::rlsg::load_scene_embedded(scene, embedded, &SceneLimits::DEFAULT)
        .map_err(|e| load_err(name, e))?;
    let k = core_loader::load_str::<CAPACITY>(kinematics, &UrdfOptions::default())
        .map_err(|e| load_err(name, e))?;
    let mut model = s
        .models()
        .first()
        .cloned()
        .ok_or_else(|| load_err(name, "the scene has no model"))?;
    let linked = match k.format {
        rl_core::loader::Format::Rlkin => load::rlsg::link_rlkin_str(&mut model, kinematics, &k),
        _ => load::rlsg::link_rlmdl_str(&mut model, kinematics, &k),
    };
    linked.map_err(|e| load_err(name, e))?;
    let robot = finish_robot(index, k, None, model.clone(), model, Vec::new(), files);
    Ok((robot, s.models()[1..].to_vec()))
}

/// The named state a robot starts at: `home`, else `ready`, else the SRDF's first.
fn pick_named_state(states: &[load::srdf::NamedState]) -> Option<&load::srdf::NamedState> {
    ["home", "ready"]
        .iter()
        .find_map(|n| states.iter().find(|s| s.name == *n))
        .or(states.first())
}

/// `robot`'s start from the named state of its SRDF (joints the state does not name keep
/// their value); notes for joints the model lacks.
fn apply_named_state(robot: &mut Robot, srdf: &std::path::Path) -> Result<(), ViewError> {
    let states =
        load::srdf::named_states_file(srdf).map_err(|e| load_err(srdf.display().to_string(), e))?;
    let Some(state) = pick_named_state(&states) else {
        return Ok(());
    };
    let m = &robot.kinematics.model;
    let mut q = robot.initial_q.clone();
    let mut unknown = Vec::new();
    for (joint, values) in &state.joints {
        let body = (0..m.body_count()).find(|&b| m.joint_name(b) == joint.as_str());
        match body {
            Some(b) if m.joint_nq(b) == values.len() => {
                let at = m.q_index(b);
                q[at..at + values.len()].copy_from_slice(values);
            }
            Some(b) => {
                return Err(load_err(
                    srdf.display().to_string(),
                    format!(
                        "group_state \"{}\": joint \"{joint}\" has {} coordinates, {} values given",
                        state.name,
                        m.joint_nq(b),
                        values.len()
                    ),
                ));
            }
            None => unknown.push(joint.as_str()),
        }
    }
    if !unknown.is_empty() {
        robot.warnings.push(format!(
            "the SRDF's state \"{}\" names joints this model does not have: {}",
            state.name,
            unknown.join(", ")
        ));
    }
    robot.initial_q = q;
    robot.initial_source = format!("srdf:{}", state.name);
    Ok(())
}

/// World poses of `model`'s scene bodies with its kinematics at `q` (through the model's
/// kinematic link and base, as [`rl_sg::Scene::update`] places them); bodies without a
/// kinematic frame at their current pose.
pub fn body_poses_at(
    model: &Model,
    kin: &rl_core::Model<CAPACITY>,
    data: &mut rl_core::Data<CAPACITY>,
    q: &[f64],
) -> Option<Vec<PlueckerTransform>> {
    rl_core::algo::forward_position(kin, data, q).ok()?;
    let link = model.kinematics()?;
    let base = link.base();
    Some(
        model
            .bodies()
            .iter()
            .enumerate()
            .map(|(i, b)| match link.frame(i) {
                Some((k, placement)) if k == ROOT => base * placement,
                Some((k, placement)) => base * *data.world_pose(k) * placement,
                None => *b.pose(),
            })
            .collect(),
    )
}

/// The ghosts and tool trail of robot `i` from `start` to `goal` along `path` (if any).
fn plan_view(
    i: usize,
    robot: &Robot,
    model: &Model,
    start: Vec<f64>,
    goal: Vec<f64>,
    path: Option<&PathData>,
) -> Option<PlanView> {
    let kin = &robot.kinematics.model;
    let mut data = Box::new(rl_core::Data::<CAPACITY>::new());
    let start_bodies = body_poses_at(model, kin, &mut data, &start)?;
    let goal_bodies = body_poses_at(model, kin, &mut data, &goal)?;
    let mut trail = Vec::new();
    if let Some(p) = path {
        // Joint-space steps of at most 1° (1 mm) between the samples: the tool's curve.
        const STEP: f64 = 0.0175;
        const MAX_POINTS: usize = 4000;
        let mut tool_at = |q: &[f64]| -> Option<DVec3> {
            rl_core::algo::forward_position(kin, &mut data, q).ok()?;
            let x = if kin.tools().is_empty() {
                *data.world_pose(kin.body_count().checked_sub(1)?)
            } else {
                tool_pose(kin, &data, robot.tool).ok()?
            };
            Some(robot.base.transform_point(x.translation))
        };
        let total: usize =
            p.q.windows(2)
                .map(|w| segment_steps(&w[0], &w[1], STEP))
                .sum();
        let thin = total.div_ceil(MAX_POINTS).max(1);
        let mut q = vec![0.0; kin.nq()];
        trail.extend(p.q.first().and_then(|q0| tool_at(q0)));
        for w in p.q.windows(2) {
            let n = segment_steps(&w[0], &w[1], STEP * thin as f64);
            for k in 1..=n {
                let s = k as f64 / n as f64;
                for (j, v) in q.iter_mut().enumerate() {
                    *v = w[0][j] + s * (w[1][j] - w[0][j]);
                }
                trail.extend(tool_at(&q));
            }
        }
    }
    Some(PlanView {
        model: i,
        start,
        goal,
        start_bodies,
        goal_bodies,
        trail,
    })
}

/// Steps of at most `step` in every coordinate from `a` to `b` (at least one).
fn segment_steps(a: &[f64], b: &[f64], step: f64) -> usize {
    let d = a
        .iter()
        .zip(b)
        .map(|(x, y)| (y - x).abs())
        .fold(0.0, f64::max);
    ((d / step).ceil() as usize).clamp(1, 100_000)
}

impl World {
    /// Loads everything `options` names.
    pub fn load(options: &LoadOptions) -> Result<World, ViewError> {
        if options.models.is_empty() {
            return Err(ViewError::Invalid("no model to show".into()));
        }
        let mut files = FileTable::new();
        let mut cache = MeshCache::new();
        let mut scene = Scene::new();
        let mut robots = Vec::with_capacity(options.models.len());
        let mut obstacles = Vec::new();
        let mut loaded = Vec::new();
        for src in &options.models {
            let i = loaded.len();
            match src {
                ModelSource::RlScene { scene, kinematics } => {
                    let (r, rest) = rl_scene_robots(i, scene, kinematics, &mut files)?;
                    loaded.extend(r.into_iter().map(|r| (r, src)));
                    obstacles.extend(rest);
                }
                ModelSource::Embedded {
                    name,
                    kinematics,
                    scene,
                    files: embedded,
                } => {
                    let (r, rest) =
                        embedded_scene_robot(i, name, kinematics, scene, embedded, &mut files)?;
                    loaded.push((r, src));
                    obstacles.extend(rest);
                }
                _ => loaded.push((load_robot(i, src, options, &mut files, &mut cache)?, src)),
            }
        }
        if options.robots.len() > loaded.len() {
            return Err(ViewError::Invalid(format!(
                "options for {} robots given, {} robots loaded",
                options.robots.len(),
                loaded.len()
            )));
        }
        let mut collisions = Vec::with_capacity(loaded.len());
        for (i, ((mut robot, mut collision), src)) in loaded.into_iter().enumerate() {
            let opts = options.robots.get(i).cloned().unwrap_or_default();
            let srdf = opts
                .srdf
                .as_ref()
                .or(if i == 0 { options.srdf.as_ref() } else { None });
            if let Some(srdf) = srdf {
                load::srdf::apply_file(srdf, &mut collision)
                    .map_err(|e| load_err(srdf.display().to_string(), e))?;
                apply_named_state(&mut robot, srdf)?;
            }
            if let Some(q) = opts.start {
                check_q(&robot, &q, "start")?;
                robot.initial_q = q;
                robot.initial_source = "start".into();
            }
            if let Some(x) = opts.place {
                collision
                    .set_base(x)
                    .map_err(|e| load_err(src.describe(), e))?;
                robot.base = x;
            }
            // Two robots of the same file: names must differ in the scene.
            while scene.model_id(collision.name()).is_some() {
                collision.set_name(format!("{}'", collision.name()));
            }
            collisions.push(collision.clone());
            scene
                .add_model(collision)
                .map_err(|e| load_err(src.describe(), e))?;
            robots.push(robot);
        }
        for mut m in obstacles {
            while scene.model_id(m.name()).is_some() {
                m.set_name(format!("{}'", m.name()));
            }
            scene
                .add_model(m)
                .map_err(|e| load_err("the RL scene's obstacles", e))?;
        }
        if let Some(env) = &options.env {
            let opts = geometry_options(GeometryKind::Collision, &options.package_dirs);
            let s = load::load_scene_file(env, &opts, &mut cache)
                .map_err(|e| load_err(env.display().to_string(), e))?;
            for mut m in s.models().iter().cloned() {
                while scene.model_id(m.name()).is_some() {
                    m.set_name(format!("{}'", m.name()));
                }
                scene
                    .add_model(m)
                    .map_err(|e| load_err(env.display().to_string(), e))?;
            }
        }
        let path = match (&options.path_data, &options.path) {
            (Some(p), _) => Some(p.clone()),
            (None, Some(p)) => Some(PathData::load(p, &robots[0].joints)?),
            (None, None) => None,
        };
        if let Some(p) = &path {
            if let Some(bad) = p.q.iter().find(|q| q.len() != robots[0].initial_q.len()) {
                return Err(ViewError::Invalid(format!(
                    "the path has {} values per sample, the model {}",
                    bad.len(),
                    robots[0].initial_q.len()
                )));
            }
        }
        if let Some(g) = &options.goal {
            check_q(&robots[0], g, "goal")?;
        }
        // Ghosts at the start and goal: the path's ends, or the problem's.
        let ends = match (&path, &options.goal) {
            (Some(p), _) => p.q.first().cloned().zip(p.q.last().cloned()),
            (None, Some(g)) => Some((robots[0].initial_q.clone(), g.clone())),
            (None, None) => None,
        };
        let plan = ends.and_then(|(start, goal)| {
            plan_view(0, &robots[0], &collisions[0], start, goal, path.as_ref())
        });
        Ok(World {
            robots,
            scene,
            files,
            path,
            plan,
        })
    }
}

/// Checks that `q` fits `robot` (its length, finite values).
fn check_q(robot: &Robot, q: &[f64], what: &str) -> Result<(), ViewError> {
    let n = robot.initial_q.len();
    if q.len() != n {
        return Err(ViewError::Invalid(format!(
            "{what}: {} values for {}, which has {n} joint coordinates",
            q.len(),
            robot.name
        )));
    }
    if let Some(k) = q.iter().position(|v| !v.is_finite()) {
        return Err(ViewError::Invalid(format!(
            "{what}: value {k} is not a finite number"
        )));
    }
    Ok(())
}
