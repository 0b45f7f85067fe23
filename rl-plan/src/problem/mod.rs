//! Planning problems from files, and the robots they are posed for.
//!
//! - [`Robot`]: a URDF robot — kinematics (rl-core), collision geometry (rl-sg, meshes as
//!   meshes), an SRDF's allowed pairs, its configuration space, and the spheres of the fast
//!   checker (a `*_spherized.urdf` beside the URDF when there is one, else fitted around the
//!   meshes);
//! - [`moveit`]: MoveIt motion plan requests (start state, joint goal) — with rl-sg's MoveIt
//!   planning-scene reader, the MotionBenchMaker problems;
//! - [`mbm`]: a directory of MotionBenchMaker problems;
//! - [`rlplan`]: RL's rlplan XML scenarios (planner, sampler, verifier, optimiser, model,
//!   scene, start, goal).

pub mod mbm;
pub mod moveit;
pub mod rlplan;

use std::path::{Path, PathBuf};

use rl_core::loader::{LoadedModel, UrdfOptions};
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_sg::load::{MeshCache, UrdfGeometryOptions, load_robot};
use rl_sg::{ModelId, Scene};

use crate::error::PlanError;
use crate::fast::{Environment, HybridChecker, PADDING, SphereChecker, SphereRobot, SphereSet};
use crate::scene::{MAX_BODIES, SceneValidity};
use crate::space::JointSpace;

/// Where the fast checker's spheres came from.
#[derive(Clone, Debug, PartialEq)]
pub enum SphereSource {
    /// A spherized URDF.
    File(PathBuf),
    /// Fitted around the collision geometry, `k` per link.
    Fitted(usize),
}

/// Spheres per link when they are fitted.
pub const FITTED_PER_LINK: usize = 8;

/// Random configurations that decide which self pairs always touch in the sphere model.
pub const ALWAYS_SAMPLES: usize = 256;

/// Sample spacing (and margin) when spheres from a file are grown to cover the meshes, m.
pub const COVER_SPACING: f64 = 0.004;

/// A robot ready to plan for.
#[derive(Clone, Debug)]
pub struct Robot {
    /// The URDF it came from.
    pub urdf: PathBuf,
    /// Kinematics.
    pub kinematics: LoadedModel<MAX_BODIES>,
    /// Collision geometry, one body per link, the SRDF (if any) applied.
    pub geometry: rl_sg::Model,
    /// The configuration space (limits from the URDF).
    pub space: JointSpace,
    /// The fast checker's spheres.
    pub spheres: SphereSet,
    /// Where they came from.
    pub sphere_source: SphereSource,
    /// How spheres from a file were grown to cover the collision geometry (`None` when
    /// fitted, which covers by construction, or when covering was switched off).
    pub cover: Option<crate::fast::CoverReport>,
    /// The spheres of the file before covering (the hybrid checker's inner model).
    pub inner_spheres: Option<SphereSet>,
    /// The fast checker's robot, built once (or why it cannot be built).
    fast: Result<SphereRobot, PlanError>,
    /// The same for the inner spheres.
    fast_inner: Option<SphereRobot>,
}

/// `NAME_spherized.urdf` beside `NAME.urdf`, if it exists.
pub fn spherized_beside(urdf: &Path) -> Option<PathBuf> {
    let stem = urdf.file_stem()?.to_str()?;
    let p = urdf.with_file_name(format!("{stem}_spherized.urdf"));
    p.exists().then_some(p)
}

/// `NAME.srdf` beside `NAME.urdf`, if it exists (rl-sg's one rule,
/// [`rl_sg::load::srdf::beside`]).
pub fn srdf_beside(urdf: &Path) -> Option<PathBuf> {
    rl_sg::load::srdf::beside(urdf)
}

impl Robot {
    /// Loads a URDF robot. `srdf`: an SRDF to apply (`None`: the `.srdf` beside the URDF, if
    /// any: [`rl_sg::load::srdf::for_robot`]). Spheres: `spheres` if given, else the `_spherized.urdf` beside it, else fitted;
    /// spheres from a file are grown to cover the collision meshes ([`COVER_SPACING`]).
    /// Mimic joints are loaded as independent joints.
    pub fn load_urdf(
        urdf: &Path,
        srdf: Option<&Path>,
        spheres: Option<&Path>,
    ) -> Result<Self, PlanError> {
        Self::load_urdf_with(urdf, srdf, spheres, Some(COVER_SPACING))
    }

    /// As [`Robot::load_urdf`], covering file spheres with samples `cover` apart (`None`:
    /// take the file's spheres as they are — not conservative when the file's are not).
    pub fn load_urdf_with(
        urdf: &Path,
        srdf: Option<&Path>,
        spheres: Option<&Path>,
        cover: Option<f64>,
    ) -> Result<Self, PlanError> {
        let options = UrdfOptions {
            mimic: rl_core::loader::MimicJoints::Independent,
            ..Default::default()
        };
        let mut cache = MeshCache::new();
        let robot =
            load_robot::<MAX_BODIES>(urdf, &UrdfGeometryOptions::default(), &options, &mut cache)?;
        let mut geometry = robot.model;
        let srdf = rl_sg::load::srdf::for_robot(urdf, srdf);
        if let Some(s) = &srdf {
            rl_sg::load::srdf::apply_file(s, &mut geometry)?;
        }
        let space = JointSpace::from_model(&robot.kinematics.model)?;
        let file = spheres
            .map(Path::to_path_buf)
            .or_else(|| spherized_beside(urdf));
        let (spheres, sphere_source, cover, inner_spheres) = match file {
            Some(f) => {
                let mut s = SphereSet::from_spherized_urdf(&f, &robot.kinematics)?;
                let raw = s.clone();
                let report = cover.map(|h| s.cover(&geometry, h)).transpose()?;
                let inner = report.is_some().then_some(raw);
                (s, SphereSource::File(f), report, inner)
            }
            None => (
                SphereSet::fit(&geometry, FITTED_PER_LINK, 0.0)?,
                SphereSource::Fitted(FITTED_PER_LINK),
                None,
                None,
            ),
        };
        let mut out = Self {
            urdf: urdf.to_path_buf(),
            kinematics: robot.kinematics,
            geometry,
            space,
            spheres,
            sphere_source,
            cover,
            inner_spheres,
            fast: Err(PlanError::Unsupported("not built yet".into())),
            fast_inner: None,
        };
        out.fast = out.build_sphere_robot(&out.spheres);
        if let Some(inner) = &out.inner_spheres {
            out.fast_inner = out.build_sphere_robot(inner).ok();
        }
        Ok(out)
    }

    /// The names of the link pairs checked for self-collision (SRDF and adjacency applied).
    pub fn self_pairs(&self) -> Vec<(String, String)> {
        let b = self.geometry.bodies();
        self.geometry
            .self_collision_pairs()
            .iter()
            .map(|&(i, j)| {
                (
                    b[i as usize].name().to_string(),
                    b[j as usize].name().to_string(),
                )
            })
            .collect()
    }

    /// The scene of the robot and `environment`, and the robot's id in it.
    pub fn scene_with(&self, environment: rl_sg::Model) -> Result<(Scene, ModelId), PlanError> {
        let mut scene = Scene::new();
        let id = scene.add_model(self.geometry.clone())?;
        scene.add_model(environment)?;
        Ok((scene, id))
    }

    /// The exact checker for the robot among `environment`.
    pub fn exact_checker(&self, environment: rl_sg::Model) -> Result<SceneValidity, PlanError> {
        let (scene, id) = self.scene_with(environment)?;
        SceneValidity::new(scene, id, self.kinematics.model.clone(), self.space.clone())
    }

    /// The robot in the fast checker's form (spheres padded by [`PADDING`]; self pairs whose
    /// spheres always touch left out, see [`crate::fast::always_touching_pairs`]), or why
    /// the model cannot have one (joints other than revolute and prismatic).
    pub fn sphere_robot(&self) -> Result<SphereRobot, PlanError> {
        self.fast.clone()
    }

    fn build_sphere_robot(&self, spheres: &SphereSet) -> Result<SphereRobot, PlanError> {
        let spheres = spheres.clone().padded(PADDING);
        let all = SphereRobot::new(
            &self.kinematics.model,
            PlueckerTransform::IDENTITY,
            &spheres,
            &self.self_pairs(),
        )?;
        let always = crate::fast::always_touching_pairs(&all, &self.space, ALWAYS_SAMPLES, 0);
        if always.is_empty() {
            return Ok(all);
        }
        let pairs: Vec<(String, String)> = self
            .self_pairs()
            .into_iter()
            .filter(|p| !always.contains(p))
            .collect();
        Ok(SphereRobot::new(
            &self.kinematics.model,
            PlueckerTransform::IDENTITY,
            &spheres,
            &pairs,
        )?
        .with_unmodelled(always))
    }

    /// The fast checker's obstacles from `environment` (measured from the robot's base: the
    /// origin of the first moving joint's parent frame).
    pub fn sphere_environment(&self, environment: &rl_sg::Model) -> Result<Environment, PlanError> {
        let m = &self.kinematics.model;
        let origin = (0..m.body_count())
            .find(|&b| m.parent(b) == ROOT)
            .map(|b| m.placement(b).translation)
            .unwrap_or_default();
        let mut env = Environment::new(origin);
        let mut scene = Scene::new();
        scene.add_model(environment.clone())?;
        env.add_scene(&scene, None)?;
        Ok(env)
    }

    /// The fast checker for the robot among `environment`.
    pub fn sphere_checker(&self, environment: &rl_sg::Model) -> Result<SphereChecker, PlanError> {
        SphereChecker::new(
            self.sphere_robot()?,
            self.sphere_environment(environment)?,
            self.space.clone(),
        )
    }

    /// The hybrid checker (see [`HybridChecker`]): the covering spheres, the file's spheres
    /// as the inner model when there were any, and the exact geometry. Needs spheres that
    /// cover the meshes (loaded with covering, or fitted).
    pub fn hybrid_checker(&self, environment: &rl_sg::Model) -> Result<HybridChecker, PlanError> {
        if matches!(self.sphere_source, SphereSource::File(_)) && self.cover.is_none() {
            return Err(PlanError::setting(
                "hybrid checker",
                "needs spheres that cover the meshes: load without --raw-spheres",
            ));
        }
        let env = self.sphere_environment(environment)?;
        let cover = SphereChecker::new(self.sphere_robot()?, env.clone(), self.space.clone())?;
        let inner = match &self.fast_inner {
            Some(r) => Some(SphereChecker::new(r.clone(), env, self.space.clone())?),
            None => None,
        };
        Ok(HybridChecker::new(
            cover,
            inner,
            self.exact_checker(environment.clone())?,
        ))
    }
}
