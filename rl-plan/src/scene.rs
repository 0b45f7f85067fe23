//! The exact validity check: rl-sg's geometry (meshes and primitives through parry3d) placed by
//! rl-core's forward kinematics — RL's `SimpleModel::isColliding`.
//!
//! A configuration is valid when it lies within the space's bounds, no pair of the robot's
//! bodies that the allowed set (SRDF, RL's `<ignore>`, adjacency) leaves checked touches, and
//! no robot body touches a body of another model (bodies whose collision is switched off
//! excepted). Touching counts as collision. Meshes are surfaces, as in coal and FCL: a mesh
//! wholly inside another shape does not collide with it.

use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_core::{Data, Model};
use rl_sg::{CollisionFilter, ModelId, Scene};

use crate::error::PlanError;
use crate::space::JointSpace;
use crate::validity::Validity;

pub mod certify;

pub use certify::{Certificate, CertifyOptions, CertifyProgress, PathCertificate, Uncertified};

/// Body capacity of the kinematic models the planners load.
pub const MAX_BODIES: usize = 32;

/// The exact checker.
#[derive(Clone)]
pub struct SceneValidity {
    scene: Scene,
    robot: ModelId,
    kinematics: Model<MAX_BODIES>,
    data: Box<Data<MAX_BODIES>>,
    /// Per scene body of the robot: (rl-core body or ROOT, placement).
    frames: Vec<Option<(usize, PlueckerTransform)>>,
    base: PlueckerTransform,
    space: JointSpace,
    checks: u64,
    free: u64,
    /// The motion bounds of certified edges, made on first use.
    bounds: Option<certify::MotionBounds>,
}

impl std::fmt::Debug for SceneValidity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneValidity")
            .field("robot", &self.robot)
            .field("checks", &self.checks)
            .finish_non_exhaustive()
    }
}

impl SceneValidity {
    /// A checker for model `robot` of `scene` (its bodies linked to `kinematics` through its
    /// [`rl_sg::KinematicLink`]), configurations from `space`.
    pub fn new(
        scene: Scene,
        robot: ModelId,
        kinematics: Model<MAX_BODIES>,
        space: JointSpace,
    ) -> Result<Self, PlanError> {
        let m = scene.model(robot).ok_or_else(|| PlanError::UnknownName {
            what: "scene model",
            name: robot.0.to_string(),
        })?;
        let link = m.kinematics().ok_or_else(|| {
            PlanError::Unsupported(format!(
                "scene model \"{}\" is not linked to a kinematic model",
                m.name()
            ))
        })?;
        let frames = (0..m.bodies().len()).map(|i| link.frame(i)).collect();
        if space.nq() != kinematics.nq() {
            return Err(PlanError::Length {
                what: "the space".into(),
                expected: kinematics.nq(),
                got: space.nq(),
            });
        }
        Ok(Self {
            scene,
            robot,
            kinematics,
            data: Box::new(Data::new()),
            frames,
            base: PlueckerTransform::IDENTITY,
            space,
            checks: 0,
            free: 0,
            bounds: None,
        })
    }

    /// The same checker with the robot's base placed at `base` in the world (RL's rlplan
    /// `<kinematics><world>`).
    pub fn with_base(mut self, base: PlueckerTransform) -> Self {
        self.base = base;
        self
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The robot's model in the scene.
    pub fn robot(&self) -> ModelId {
        self.robot
    }

    /// The configuration space.
    pub fn space(&self) -> &JointSpace {
        &self.space
    }

    /// Places the robot at `q`; `false` if the kinematics refused it.
    pub fn place(&mut self, q: &[f64]) -> bool {
        if rl_core::algo::forward_position(&self.kinematics, &mut self.data, q).is_err() {
            return false;
        }
        for (i, f) in self.frames.iter().enumerate() {
            let Some((k, placement)) = f else { continue };
            let x = if *k == ROOT {
                self.base * *placement
            } else {
                self.base * *self.data.world_pose(*k) * *placement
            };
            let id = rl_sg::BodyId {
                model: self.robot.0,
                body: i,
            };
            if self.scene.set_body_pose(id, &x).is_err() {
                return false;
            }
        }
        true
    }

    /// The colliding body pairs at `q` (`model/body` names), for messages; empty when valid.
    pub fn collisions(&mut self, q: &[f64]) -> Vec<(String, String)> {
        if !self.place(q) {
            return vec![("kinematics".into(), "refused the configuration".into())];
        }
        let mut v = Vec::new();
        for filter in [
            CollisionFilter::SelfCollision(self.robot),
            CollisionFilter::Against(self.robot),
        ] {
            for (a, b) in self.scene.colliding_bodies(&filter) {
                v.push((self.scene.body_name(a), self.scene.body_name(b)));
            }
        }
        v
    }
}

impl Validity for SceneValidity {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self.checks += 1;
        if !self.space.contains(q) || !self.place(q) {
            return false;
        }
        let ok = !self
            .scene
            .is_colliding(&CollisionFilter::SelfCollision(self.robot))
            && !self
                .scene
                .is_colliding(&CollisionFilter::Against(self.robot));
        self.free += u64::from(ok);
        ok
    }

    fn checks(&self) -> u64 {
        self.checks
    }

    fn free_checks(&self) -> u64 {
        self.free
    }

    fn exact_checker(&mut self) -> Option<&mut SceneValidity> {
        Some(self)
    }
}
