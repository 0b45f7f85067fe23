//! RL's planning scenarios (`rlplan` XML, as rlPlanDemo reads them): the planner element
//! (`prm`, `rrt`, `rrtGoalBias`, `rrtDual`, `rrtConCon`, `rrtExtCon`, `rrtExtExt`) with its
//! settings, the model (a kinematic model, RL's `rlmdl` or its older Denavit–Hartenberg
//! `rlkin`, optionally placed by `<world>`, and a `rlsg` scene with the robot's index in it,
//! whose bodies are linked to the rlmdl bodies or rlkin links in order), start and goal, the
//! nearest-neighbour structure,
//! the sampler, the verifier, and an optional optimiser after the planner element.
//!
//! Units as RL reads them: `<q unit="deg">` and `<delta unit="deg">` are degrees, else radians
//! or metres; `<world>` rotations are degrees about x, y, z applied as `Rz·Ry·Rx`. The viewer
//! element is ignored. RL's RRTs have no verifier element — they check each new vertex and
//! rely on a small `delta` — so for them the verifier is sequential at the planner's `delta`,
//! which checks exactly the new vertex of each step. The kinematics file is read by its root
//! element; RL reads it by `<kinematics type>` (`kin` when absent), so a type that contradicts
//! the file is an error. Not supported (an error says so): the planners `eet`,
//! `prmUtilityGuided`, `addRrtConCon` and `rrtCon`.
//!
//! An `href` that does not exist is also looked up case-insensitively in its directory: RL's
//! own `box-6d-300505_maze` scenarios name `box-6d-300505.sixdof.xml` for the file
//! `box-6d-300505.sixDof.xml`, which works only on case-insensitive file systems.

use std::path::{Path, PathBuf};
use std::time::Duration;

use glam::{DMat3, DVec3};
use rl_core::loader::Format;
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_sg::ModelId;
use roxmltree::Node;

use crate::error::PlanError;
use crate::nn::NnKind;
use crate::optimizer::OptimizerKind;
use crate::planner::{PlannerKind, PrmSettings, RrtSettings};
use crate::sampler::SamplerKind;
use crate::scene::{MAX_BODIES, SceneValidity};
use crate::solve::PlanOptions;
use crate::space::JointSpace;
use crate::verifier::Verifier;

/// RL's two kinematics formats, as `<kinematics type>` names them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KinematicsType {
    /// `kin`: RL's Denavit–Hartenberg format (`rlkin`).
    Kin,
    /// `mdl`: RL's XML model format (`rlmdl`).
    Mdl,
}

/// A scenario read from an rlplan file.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// The file.
    pub path: PathBuf,
    /// RL's element name of the planner.
    pub planner_element: String,
    /// The planner and its settings.
    pub planner: PlannerKind,
    /// The sampler.
    pub sampler: SamplerKind,
    /// The planner's verifier.
    pub verifier: Verifier,
    /// The optimiser (none when the file has none).
    pub optimizer: OptimizerKind,
    /// The optimiser's own verifier, if the file gives one.
    pub optimizer_verifier: Option<Verifier>,
    /// RL's `duration`.
    pub duration: Duration,
    /// A seed from the file (planner or sampler `seed`), if any.
    pub seed: Option<u64>,
    /// Start configuration (rad, m).
    pub start: Vec<f64>,
    /// Goal configuration.
    pub goal: Vec<f64>,
    /// The kinematic model file.
    pub kinematics: PathBuf,
    /// `<kinematics type>` as written: RL's `kin` (rlkin, RL's default when there is none) or
    /// `mdl` (rlmdl). The file is read by its root element; a type that contradicts it is an
    /// error when the scenario is built.
    pub kinematics_type: Option<KinematicsType>,
    /// `<kinematics><world>`: where the model's world frame is placed.
    pub world: Option<PlueckerTransform>,
    /// The robot's model index in the scene.
    pub model_index: usize,
    /// The scene file.
    pub scene: PathBuf,
}

fn err(path: &Path, doc: &roxmltree::Document, n: Node, message: impl Into<String>) -> PlanError {
    let p = doc.text_pos_at(n.range().start);
    PlanError::file(path, format!("<{}>", n.tag_name().name()), message).at_position(p.row, p.col)
}

fn child<'a, 'i>(n: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    n.children().find(|c| c.has_tag_name(name))
}

/// The file at `href` relative to `dir`, or a case-insensitive match in its directory.
fn resolve(dir: &Path, href: &str) -> PathBuf {
    let p = dir.join(href);
    if p.exists() {
        return p;
    }
    if let (Some(parent), Some(name)) = (p.parent(), p.file_name().and_then(|n| n.to_str()))
        && let Ok(rd) = std::fs::read_dir(parent)
    {
        for e in rd.flatten() {
            if e.file_name()
                .to_str()
                .is_some_and(|f| f.eq_ignore_ascii_case(name))
            {
                return e.path();
            }
        }
    }
    p
}

impl Scenario {
    /// Reads the scenario at `path`.
    pub fn load(path: &Path) -> Result<Self, PlanError> {
        let text =
            rl_core::loader::read_text(path, rl_core::loader::InputLimits::DEFAULT.max_bytes)
                .map_err(|e| PlanError::Load(e.to_string()))?;
        Self::parse(&text, path)
    }

    /// Reads a scenario from `text` (the file `path`, for relative `href`s and messages).
    pub fn parse(text: &str, path: &Path) -> Result<Self, PlanError> {
        rl_core::loader::check_xml(text, &rl_core::loader::InputLimits::DEFAULT)
            .map_err(|e| PlanError::file(path, "XML", e.to_string()))?;
        let doc = roxmltree::Document::parse(text).map_err(|e| {
            let p = e.pos();
            PlanError::file(path, "XML", e.to_string()).at_position(p.row, p.col)
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let root = doc.root_element();
        let holder = match root.tag_name().name() {
            "rlplan" => root,
            "rl" => {
                child(root, "plan").ok_or_else(|| err(path, &doc, root, "no <plan> in <rl>"))?
            }
            other => {
                return Err(err(
                    path,
                    &doc,
                    root,
                    format!("<{other}> is not an RL planning scenario (<rlplan> or <rl><plan>)"),
                ));
            }
        };
        let mut elements = holder.children().filter(|n| n.is_element());
        let p = elements
            .next()
            .ok_or_else(|| err(path, &doc, holder, "no planner element"))?;
        let name = p.tag_name().name().to_string();
        // Numbers, with `unit="deg"` converted.
        let num = |n: Node| -> Result<f64, PlanError> {
            let t = n.text().unwrap_or("").trim();
            let v: f64 = t
                .parse()
                .map_err(|_| err(path, &doc, n, format!("\"{t}\" is not a number")))?;
            if !v.is_finite() {
                return Err(err(path, &doc, n, format!("{v} is not finite")));
            }
            Ok(if n.attribute("unit") == Some("deg") {
                v.to_radians()
            } else {
                v
            })
        };
        let opt = |n: Node, tag: &str| -> Result<Option<f64>, PlanError> {
            child(n, tag).map(num).transpose()
        };
        let qs = |tag: &str| -> Result<Vec<f64>, PlanError> {
            let c = child(p, tag).ok_or_else(|| err(path, &doc, p, format!("no <{tag}>")))?;
            c.children()
                .filter(|n| n.has_tag_name("q"))
                .map(num)
                .collect()
        };
        let start = qs("start")?;
        let goal = qs("goal")?;
        let duration = opt(p, "duration")?.unwrap_or(f64::INFINITY);
        let duration = Duration::try_from_secs_f64(duration).unwrap_or(Duration::from_secs(86_400));
        // Model.
        let model = child(p, "model").ok_or_else(|| err(path, &doc, p, "no <model>"))?;
        let kin =
            child(model, "kinematics").ok_or_else(|| err(path, &doc, model, "no <kinematics>"))?;
        let href = kin
            .attribute("href")
            .ok_or_else(|| err(path, &doc, kin, "no href"))?;
        let kinematics_type = match kin.attribute("type") {
            None => None,
            Some("kin") => Some(KinematicsType::Kin),
            Some("mdl") => Some(KinematicsType::Mdl),
            Some(other) => {
                return Err(err(
                    path,
                    &doc,
                    kin,
                    format!("type=\"{other}\": RL's kinematics types are \"kin\" and \"mdl\""),
                ));
            }
        };
        let world = match child(kin, "world") {
            Some(w) => {
                let v = |e: Option<Node>, k: &str| -> Result<f64, PlanError> {
                    Ok(match e.and_then(|e| child(e, k)) {
                        Some(n) => num(n)?,
                        None => 0.0,
                    })
                };
                let (r, t) = (child(w, "rotation"), child(w, "translation"));
                let (rx, ry, rz) = (v(r, "x")?, v(r, "y")?, v(r, "z")?);
                let rot = DMat3::from_rotation_z(rz.to_radians())
                    * DMat3::from_rotation_y(ry.to_radians())
                    * DMat3::from_rotation_x(rx.to_radians());
                Some(PlueckerTransform::new(
                    rot,
                    DVec3::new(v(t, "x")?, v(t, "y")?, v(t, "z")?),
                ))
            }
            None => None,
        };
        let index_node =
            child(model, "model").ok_or_else(|| err(path, &doc, model, "no <model> index"))?;
        let model_index = num(index_node)?;
        if model_index < 0.0 || model_index.fract() != 0.0 {
            return Err(err(path, &doc, index_node, "not a model index"));
        }
        let scene_node =
            child(model, "scene").ok_or_else(|| err(path, &doc, model, "no <scene>"))?;
        let scene_href = scene_node
            .attribute("href")
            .ok_or_else(|| err(path, &doc, scene_node, "no href"))?;
        // Nearest neighbours, sampler, verifier.
        let nn = p
            .children()
            .filter(|n| n.is_element())
            .find_map(|n| NnKind::parse(n.tag_name().name()))
            .unwrap_or_default();
        let mut seed = None;
        let seed_of = |n: Node| -> Result<Option<u64>, PlanError> {
            child(n, "seed")
                .map(|s| {
                    s.text()
                        .unwrap_or("")
                        .trim()
                        .parse::<u64>()
                        .map_err(|_| err(path, &doc, s, "not a seed (a non-negative integer)"))
                })
                .transpose()
        };
        let sigma = |n: Node| -> Result<Option<Vec<f64>>, PlanError> {
            child(n, "sigma")
                .map(|s| {
                    s.children()
                        .filter(|c| c.has_tag_name("q"))
                        .map(num)
                        .collect()
                })
                .transpose()
        };
        let sampler = if let Some(s) = child(p, "bridgeSampler") {
            seed = seed.or(seed_of(s)?);
            SamplerKind::Bridge(sigma(s)?, opt(s, "ratio")?.unwrap_or(5.0 / 6.0))
        } else if let Some(s) = child(p, "gaussianSampler") {
            seed = seed.or(seed_of(s)?);
            SamplerKind::Gaussian(sigma(s)?)
        } else {
            if let Some(s) = child(p, "uniformSampler") {
                seed = seed.or(seed_of(s)?);
            }
            SamplerKind::Uniform
        };
        seed = seed.or(seed_of(p)?);
        let verifier_of = |n: Node| -> Result<Option<Verifier>, PlanError> {
            if let Some(v) = child(n, "recursiveVerifier") {
                Ok(Some(Verifier::recursive(
                    opt(v, "delta")?.unwrap_or(1f64.to_radians()),
                )))
            } else if let Some(v) = child(n, "sequentialVerifier") {
                Ok(Some(Verifier::sequential(
                    opt(v, "delta")?.unwrap_or(1f64.to_radians()),
                )))
            } else {
                Ok(None)
            }
        };
        let rrt = RrtSettings {
            delta: opt(p, "delta")?.unwrap_or(1.0),
            epsilon: opt(p, "epsilon")?.unwrap_or(1e-3),
            nn,
            balance: false,
            dynamic_domain: None,
        };
        let planner = match name.as_str() {
            "prm" => PlannerKind::Prm(PrmSettings {
                k: opt(p, "k")?.map_or(30, |k| k as usize),
                radius: opt(p, "radius")?.unwrap_or(f64::INFINITY),
                degree: opt(p, "degree")?.map_or(usize::MAX, |d| d as usize),
                astar: child(p, "dijkstra").is_none(),
                nn,
            }),
            "rrt" => PlannerKind::Rrt(rrt),
            "rrtGoalBias" => PlannerKind::RrtGoalBias(rrt, opt(p, "probability")?.unwrap_or(0.05)),
            "rrtDual" => PlannerKind::RrtDual(rrt),
            "rrtConCon" => PlannerKind::RrtConCon(rrt),
            "rrtExtCon" => PlannerKind::RrtExtCon(rrt),
            "rrtExtExt" => PlannerKind::RrtExtExt(rrt),
            other => {
                return Err(PlanError::Unsupported(format!(
                    "{}: RL's planner <{other}> (supported: prm, rrt, rrtGoalBias, rrtDual, \
                     rrtConCon, rrtExtCon, rrtExtExt)",
                    path.display()
                )));
            }
        };
        let verifier = match verifier_of(p)? {
            Some(v) => v,
            None => Verifier::sequential(rrt.delta),
        };
        // An optimiser after the planner element.
        let (optimizer, optimizer_verifier) = match elements.next() {
            Some(o) if o.has_tag_name("simpleOptimizer") => {
                (OptimizerKind::Simple, verifier_of(o)?)
            }
            Some(o) if o.has_tag_name("advancedOptimizer") => (
                OptimizerKind::Advanced {
                    length: opt(o, "length")?.unwrap_or(1.0),
                    ratio: opt(o, "ratio")?.unwrap_or(0.1),
                },
                verifier_of(o)?,
            ),
            Some(o) => {
                return Err(err(
                    path,
                    &doc,
                    o,
                    "expected <simpleOptimizer> or <advancedOptimizer>",
                ));
            }
            None => (OptimizerKind::None, None),
        };
        Ok(Self {
            path: path.to_path_buf(),
            planner_element: name,
            planner,
            sampler,
            verifier,
            optimizer,
            optimizer_verifier,
            duration,
            seed,
            start,
            goal,
            kinematics: resolve(dir, href),
            kinematics_type,
            world,
            model_index: model_index as usize,
            scene: resolve(dir, scene_href),
        })
    }

    /// The space and the exact checker of the scenario: the kinematic model, the scene with
    /// the robot linked to it (RL's `<ignore>` applied), the base placed by `<world>`.
    pub fn build(&self) -> Result<(JointSpace, SceneValidity), PlanError> {
        let loaded = rl_core::loader::load_file::<MAX_BODIES>(&self.kinematics)?;
        let expected = match self.kinematics_type {
            Some(KinematicsType::Kin) => Some(Format::Rlkin),
            Some(KinematicsType::Mdl) => Some(Format::Rlmdl),
            None => None,
        };
        if let Some(f) = expected.filter(|f| *f != loaded.format) {
            return Err(PlanError::Load(format!(
                "{}: <kinematics type> says {f:?}, but {} is {:?}",
                self.path.display(),
                self.kinematics.display(),
                loaded.format
            )));
        }
        let mut scene = rl_sg::load::rlsg::load_scene(&self.scene)?;
        let id = ModelId(self.model_index);
        let robot = scene.model_mut(id).ok_or_else(|| PlanError::UnknownName {
            what: "scene model index",
            name: self.model_index.to_string(),
        })?;
        rl_sg::load::rlsg::link_kinematics(robot, &self.kinematics, &loaded)?;
        let space = JointSpace::from_model(&loaded.model)?;
        let mut checker = SceneValidity::new(scene, id, loaded.model.clone(), space.clone())?;
        if let Some(w) = self.world {
            // Replace the file's world frame by the scenario's.
            let file_world = loaded
                .frames
                .iter()
                .find(|f| f.body == ROOT)
                .map(|f| f.placement)
                .unwrap_or(PlueckerTransform::IDENTITY);
            checker = checker.with_base(w * file_world.inverse());
        }
        Ok((space, checker))
    }

    /// The planning options of the scenario, with `seed` when the file gives none.
    pub fn options(&self, seed: u64) -> PlanOptions {
        PlanOptions {
            planner: self.planner.clone(),
            sampler: self.sampler.clone(),
            verifier: self.verifier,
            optimizer: self.optimizer,
            optimizer_verifier: self.optimizer_verifier,
            seed: self.seed.unwrap_or(seed),
            time: self.duration,
            optimize_time: self.duration,
            try_direct: false,
        }
    }
}
