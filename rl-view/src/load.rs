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
//! URDF robots collide with their `<collision>` geometry; the page draws their `<visual>`
//! geometry (or the collision geometry where visual meshes are missing). RL XML models carry no
//! geometry: they get a skeleton (a sphere at every body origin, a capsule from it to each child
//! joint) which is drawn, and checked against the obstacles but not against itself.

use std::path::PathBuf;

use glam::{DQuat, DVec3};
use rl_core::loader::{self as core_loader, LoadedModel, UrdfOptions};
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_sg::load::{self, GeometryKind, MeshCache, MeshMode, UrdfGeometryOptions};
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
}

impl ModelSource {
    fn describe(&self) -> String {
        match self {
            ModelSource::File(p) | ModelSource::RlScene { scene: p, .. } => p.display().to_string(),
            ModelSource::Text { name, .. } => name.clone(),
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
    /// Allowed collision pairs of the first model (SRDF).
    pub srdf: Option<PathBuf>,
    /// A path to play back (`rl plan --out` or `--trajectory` CSV), for model 0.
    pub path: Option<PathBuf>,
    /// Where `package://` URIs are looked up (besides `$ROS_PACKAGE_PATH` and the files'
    /// ancestors).
    pub package_dirs: Vec<PathBuf>,
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
    /// The configuration it starts at (RL's home, or neutral).
    pub initial_q: Vec<f64>,
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
            });
        } else {
            for c in 0..nq {
                out.push(JointInfo {
                    name: format!("{name}[{c}]"),
                    kind: "other",
                    min: f64::NEG_INFINITY,
                    max: f64::INFINITY,
                    unit: "",
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
    package_dirs: &[PathBuf],
    files: &mut FileTable,
    cache: &mut MeshCache,
) -> Result<(Robot, Model), ViewError> {
    let what = source.describe();
    let mut warnings = Vec::new();
    let (kinematics, collision, visual, urdf) = match source {
        ModelSource::File(path) if load::is_urdf(path) => {
            let opts = geometry_options(GeometryKind::Collision, package_dirs);
            let r = load::load_robot::<CAPACITY>(path, &opts, &UrdfOptions::default(), cache)
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
        ModelSource::RlScene { .. } => {
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
                _ => loaded.push((
                    load_robot(i, src, &options.package_dirs, &mut files, &mut cache)?,
                    src,
                )),
            }
        }
        for (i, ((robot, mut collision), src)) in loaded.into_iter().enumerate() {
            if i == 0 {
                if let Some(srdf) = &options.srdf {
                    load::srdf::apply_file(srdf, &mut collision)
                        .map_err(|e| load_err(srdf.display().to_string(), e))?;
                }
            }
            // Two robots of the same file: names must differ in the scene.
            while scene.model_id(collision.name()).is_some() {
                collision.set_name(format!("{}'", collision.name()));
            }
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
        let path = match &options.path {
            Some(p) => Some(PathData::load(p, &robots[0].joints)?),
            None => None,
        };
        Ok(World {
            robots,
            scene,
            files,
            path,
        })
    }
}
