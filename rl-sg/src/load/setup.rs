//! A robot among obstacles from files, in one call: what `rl scene check` and the tests build.

use std::path::PathBuf;

use rl_core::loader::{self as core_loader, LoadedModel, UrdfOptions};

use super::{MeshCache, UrdfGeometryOptions, load_scene_file, rlsg, srdf, urdf};
use crate::error::{SgError, SgErrorKind};
use crate::scene::{ModelId, Scene};

/// Where a robot and its surroundings come from.
#[derive(Clone, Debug, Default)]
pub struct RobotSetup {
    /// The robot: a URDF, or an RL scene (rlsg XML) whose first model is the robot.
    pub model: PathBuf,
    /// RL scenes: the robot's kinematic model (rlmdl XML).
    pub kinematics: Option<PathBuf>,
    /// The SRDF with the robot's allowed collision pairs.
    pub srdf: Option<PathBuf>,
    /// Obstacles: a MoveIt planning scene, an RL scene, a VRML file or a URDF
    /// ([`load_scene_file`]); their models are renamed with a `'` where a name is taken.
    pub environment: Option<PathBuf>,
    /// How rl-core reads a URDF robot.
    pub urdf: UrdfOptions,
    /// How its geometry (and a URDF environment's) is read.
    pub geometry: UrdfGeometryOptions,
}

/// A robot in a scene (model [`ModelId`] 0) with its kinematics, the other models obstacles.
#[derive(Clone, Debug)]
pub struct RobotScene<const N: usize> {
    /// The scene.
    pub scene: Scene,
    /// The robot's model in it.
    pub robot: ModelId,
    /// Its kinematic model.
    pub kinematics: LoadedModel<N>,
}

/// Whether `path` is a URDF: its extension, or an XML file whose root element is `<robot>`.
pub fn is_urdf(path: &std::path::Path) -> bool {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext.eq_ignore_ascii_case("urdf") {
        return true;
    }
    ext.eq_ignore_ascii_case("xml")
        && super::read_text(path)
            .ok()
            .and_then(|t| {
                super::xml::parse(&t)
                    .ok()
                    .map(|d| d.root_element().tag_name().name() == "robot")
            })
            .unwrap_or(false)
}

impl RobotSetup {
    /// Loads it all.
    pub fn load<const N: usize>(&self) -> Result<RobotScene<N>, SgError> {
        let mut cache = MeshCache::new();
        let (mut scene, kinematics) = if is_urdf(&self.model) {
            let r = urdf::load_robot::<N>(&self.model, &self.geometry, &self.urdf, &mut cache)?;
            let mut scene = Scene::new();
            scene.add_model(r.model)?;
            (scene, r.kinematics)
        } else {
            let k = self.kinematics.as_ref().ok_or_else(|| {
                SgError::missing("the kinematic model (rlmdl or rlkin) of the scene's first model")
                    .in_file(&self.model)
            })?;
            let kin = core_loader::load_file::<N>(k)
                .map_err(|e| SgError::new(SgErrorKind::Model(e.to_string())).in_file(k))?;
            (rlsg::load_robot_scene(&self.model, k, &kin)?, kin)
        };
        let robot = ModelId(0);
        if let Some(path) = &self.srdf {
            let m = scene
                .model_mut(robot)
                .ok_or_else(|| SgError::missing("a robot model"))?;
            srdf::apply_file(path, m)?;
        }
        if let Some(e) = &self.environment {
            let env = load_scene_file(e, &self.geometry, &mut cache)?;
            for mut m in env.models().iter().cloned() {
                while scene.model_id(m.name()).is_some() {
                    m.set_name(format!("{}'", m.name()));
                }
                scene.add_model(m)?;
            }
        }
        Ok(RobotScene {
            scene,
            robot,
            kinematics,
        })
    }
}
