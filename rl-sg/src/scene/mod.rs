//! The scene: models, their bodies and shapes, placed in the world.

mod kinematics;
mod model;

pub use kinematics::{KinematicLink, UpdateError};
pub use model::{Body, Model, Shape};

use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_core::{Data, Model as KinematicModel};

use crate::error::{SgError, SgErrorKind};
use crate::pose;

/// A model of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ModelId(pub usize);

/// A body of a scene: its model and its index there.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId {
    /// The model.
    pub model: usize,
    /// The body's index in the model.
    pub body: usize,
}

/// A shape of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ShapeId {
    /// The model.
    pub model: usize,
    /// The body's index in the model.
    pub body: usize,
    /// The shape's index in the body.
    pub shape: usize,
}

impl ShapeId {
    /// Its body.
    pub fn body_id(&self) -> BodyId {
        BodyId {
            model: self.model,
            body: self.body,
        }
    }
}

/// Models in the world: RL's `rl::sg::Scene`.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub(crate) models: Vec<Model>,
}

impl Scene {
    /// An empty scene.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a model; two models may not share a name.
    pub fn add_model(&mut self, model: Model) -> Result<ModelId, SgError> {
        if self.models.iter().any(|m| m.name() == model.name()) {
            return Err(SgError::new(SgErrorKind::DuplicateName {
                name: model.name().to_string(),
            })
            .at("model"));
        }
        self.models.push(model);
        Ok(ModelId(self.models.len() - 1))
    }

    /// Adds every model of `other` (e.g. an environment loaded from a file).
    pub fn add_scene(&mut self, other: Scene) -> Result<Vec<ModelId>, SgError> {
        other
            .models
            .into_iter()
            .map(|m| self.add_model(m))
            .collect()
    }

    /// Its models.
    pub fn models(&self) -> &[Model] {
        &self.models
    }

    /// Model `id`.
    pub fn model(&self, id: ModelId) -> Option<&Model> {
        self.models.get(id.0)
    }

    /// Model `id`, mutable (bodies' shapes, allowed pairs, flags).
    pub fn model_mut(&mut self, id: ModelId) -> Option<&mut Model> {
        let m = self.models.get_mut(id.0)?;
        m.invalidate();
        Some(m)
    }

    /// The model called `name`.
    pub fn model_id(&self, name: &str) -> Option<ModelId> {
        self.models
            .iter()
            .position(|m| m.name() == name)
            .map(ModelId)
    }

    /// The body called `name` in model `model`.
    pub fn body_id(&self, model: ModelId, name: &str) -> Option<BodyId> {
        let m = self.model(model)?;
        m.body_index(name).map(|body| BodyId {
            model: model.0,
            body,
        })
    }

    /// Body `id`.
    pub fn body(&self, id: BodyId) -> Option<&Body> {
        self.models.get(id.model)?.bodies.get(id.body)
    }

    /// Shape `id`.
    pub fn shape(&self, id: ShapeId) -> Option<&Shape> {
        self.body(id.body_id())?.shapes().get(id.shape)
    }

    /// `model/body` names of a body, for messages.
    pub fn body_name(&self, id: BodyId) -> String {
        match (self.models.get(id.model), self.body(id)) {
            (Some(m), Some(b)) => format!("{}/{}", m.name(), b.name()),
            _ => format!("{}/{}", id.model, id.body),
        }
    }

    /// Places a body in the world (its pose must be a finite rigid transform).
    pub fn set_body_pose(&mut self, id: BodyId, x: &PlueckerTransform) -> Result<(), SgError> {
        pose::check("body pose", x)?;
        let m = self.models.get_mut(id.model).ok_or_else(|| {
            SgError::new(SgErrorKind::UnknownName {
                what: "model",
                name: id.model.to_string(),
            })
        })?;
        let b = m.bodies.get_mut(id.body).ok_or_else(|| {
            SgError::new(SgErrorKind::UnknownName {
                what: "body",
                name: id.body.to_string(),
            })
        })?;
        b.place(x);
        m.invalidate();
        Ok(())
    }

    /// Places every body of model `id` from rl-core's body poses in `data` (those of the last
    /// [`rl_core::algo::forward_position`]), through the model's [`KinematicLink`]: one call per
    /// cycle. Bodies with no kinematic frame stay where they are. Checks that every pose is
    /// finite (a NaN joint value is refused before it reaches the scene). Does not allocate.
    pub fn update<const N: usize>(
        &mut self,
        id: ModelId,
        data: &Data<N>,
    ) -> Result<(), UpdateError> {
        let m = self.models.get_mut(id.0).ok_or(UpdateError::UnknownModel)?;
        let link = m.kinematics.as_ref().ok_or(UpdateError::NotKinematic)?;
        if link.kinematic_bodies() > N {
            return Err(UpdateError::TooFewBodies {
                needed: link.kinematic_bodies(),
                capacity: N,
            });
        }
        let base = link.base();
        for (i, (body, frame)) in m.bodies.iter_mut().zip(link.frames()).enumerate() {
            let Some((k, placement)) = frame else {
                continue;
            };
            let x = if *k == ROOT {
                base * *placement
            } else {
                base * *data.world_pose(*k) * *placement
            };
            if !(x.translation.is_finite() && x.rotation.is_finite()) {
                return Err(UpdateError::NotFinite { body: i });
            }
            body.place(&x);
        }
        m.invalidate();
        Ok(())
    }

    /// Forward kinematics of `kin` at `q` into `data`, then [`Scene::update`]. Does not
    /// allocate.
    pub fn set_configuration<const N: usize>(
        &mut self,
        id: ModelId,
        kin: &KinematicModel<N>,
        data: &mut Data<N>,
        q: &[f64],
    ) -> Result<(), UpdateError> {
        rl_core::algo::forward_position(kin, data, q).map_err(UpdateError::Kinematics)?;
        self.update(id, data)
    }
}
