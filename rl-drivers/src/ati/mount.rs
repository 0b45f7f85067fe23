//! Where a force/torque sensor sits on the arm: a frame of the model (a URDF link fixed to the
//! flange, an RL frame), so the wrench it measures can be expressed in the frame of the body
//! it is fixed to (the flange), of another fixed frame (the tool), or of the world through
//! forward kinematics — the frame a task-space controller works in.
//!
//! A wrench `f_S` measured in the sensor frame S is `f_A = A_X_S* f_S` in frame A
//! (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, eq. 2.23): forces rotated into A,
//! moments taken about A's origin. Does not allocate.

use core::fmt;

use rl_core::loader::LoadedModel;
use rl_core::model::{Data, ROOT};
use rl_core::spatial::{ForceVector, PlueckerTransform};

/// Why a mount cannot be made from a model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MountError {
    /// The model has no frame of this name.
    UnknownFrame(String),
}

impl fmt::Display for MountError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnknownFrame(name) => write!(f, "the model has no frame `{name}`"),
        }
    }
}

impl std::error::Error for MountError {}

/// The sensor frame's place in a model: the body it is fixed to and its pose in that body's
/// frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorMount {
    /// The body ([`ROOT`] for a sensor fixed to the world).
    pub body: usize,
    /// The sensor frame's pose in the body's frame.
    pub placement: PlueckerTransform,
}

impl SensorMount {
    /// The sensor at frame `name` of a loaded model (URDF link, RL frame).
    pub fn from_model<const N: usize>(
        loaded: &LoadedModel<N>,
        name: &str,
    ) -> Result<Self, MountError> {
        let (body, placement) = loaded
            .frame_placement(name)
            .ok_or_else(|| MountError::UnknownFrame(name.into()))?;
        Ok(Self { body, placement })
    }

    /// The pose of the sensor frame in frame `name` of the same model, when both are fixed to
    /// the same body (the flange's or a tool's frame): constant, no kinematics needed. `None`
    /// if there is no such frame or it is on another body.
    pub fn pose_in<const N: usize>(
        &self,
        loaded: &LoadedModel<N>,
        name: &str,
    ) -> Option<PlueckerTransform> {
        let (body, x_body_frame) = loaded.frame_placement(name)?;
        (body == self.body).then(|| x_body_frame.inverse() * self.placement)
    }

    /// The sensor frame's pose in the world after a forward position sweep of `data`
    /// ([`rl_core::algo::forward_position`]).
    pub fn world_pose<const N: usize>(&self, data: &Data<N>) -> PlueckerTransform {
        if self.body == ROOT {
            self.placement
        } else {
            *data.world_pose(self.body) * self.placement
        }
    }

    /// A wrench measured in the sensor frame, in world coordinates (moments about the world's
    /// origin), after a forward position sweep of `data`.
    pub fn wrench_in_world<const N: usize>(
        &self,
        data: &Data<N>,
        wrench_sensor: &ForceVector,
    ) -> ForceVector {
        self.world_pose(data).act_force(wrench_sensor)
    }
}
