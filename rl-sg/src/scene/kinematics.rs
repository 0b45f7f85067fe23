//! Bodies that follow a kinematic model: the link between rl-core's forward kinematics and the
//! scene (what RL's users wrote by hand, its issue #23).

use core::fmt;

use rl_core::loader::LoadedModel;
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;

use super::Model;
use crate::error::{SgError, SgErrorKind};

/// For each body of a scene model, the rl-core body it moves with (or the world) and its pose
/// in that body's frame; and where the kinematic model's world frame is in the scene (its
/// base placement: RL's rlplan `<kinematics><world>`, `rl view --place`), identity unless set.
#[derive(Clone, Debug, PartialEq)]
pub struct KinematicLink {
    /// Per scene body: `(rl-core body or ROOT, pose in it)`; `None` leaves the body where it is.
    frames: Vec<Option<(usize, PlueckerTransform)>>,
    /// The number of rl-core bodies (`Data` must hold them).
    bodies: usize,
    /// The kinematic model's world frame in the scene's.
    base: PlueckerTransform,
}

impl KinematicLink {
    /// A link from explicit frames (one per scene body) for a kinematic model of `bodies`
    /// bodies; a body index at or beyond `bodies` (other than [`ROOT`]) is an error.
    pub fn new(
        frames: Vec<Option<(usize, PlueckerTransform)>>,
        bodies: usize,
    ) -> Result<Self, SgError> {
        for (i, f) in frames.iter().enumerate() {
            if let Some((b, x)) = f {
                if *b != ROOT && *b >= bodies {
                    return Err(SgError::invalid(
                        format!("kinematic body of scene body {i}"),
                        b,
                        "beyond the model's bodies",
                    ));
                }
                crate::pose::check(&format!("placement of scene body {i}"), x)?;
            }
        }
        Ok(Self {
            frames,
            bodies,
            base: PlueckerTransform::IDENTITY,
        })
    }

    /// The same link with the kinematic model's world frame placed at `base` in the scene: a
    /// body at `x` in the model's world is at `base · x` in the scene. A pose that is not a
    /// finite rigid transform is an error.
    pub fn with_base(mut self, base: PlueckerTransform) -> Result<Self, SgError> {
        crate::pose::check("base placement", &base)?;
        self.base = base;
        Ok(self)
    }

    /// Where the kinematic model's world frame is in the scene (identity unless set by
    /// [`KinematicLink::with_base`]).
    pub fn base(&self) -> PlueckerTransform {
        self.base
    }

    /// Links every body of `model` to the frame of `loaded` with the same name (URDF links,
    /// RL frames and bodies). A scene body without such a frame is an
    /// [`SgErrorKind::UnknownName`].
    pub fn by_name<const N: usize>(
        model: &Model,
        loaded: &LoadedModel<N>,
    ) -> Result<Self, SgError> {
        let frames = model
            .bodies()
            .iter()
            .map(|b| {
                loaded
                    .frame(b.name())
                    .map(|f| Some((f.body, f.placement)))
                    .ok_or_else(|| {
                        SgError::new(SgErrorKind::UnknownName {
                            what: "frame or link in the kinematic model",
                            name: b.name().to_string(),
                        })
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(frames, loaded.model.body_count())
    }

    /// Links the scene bodies, in order, to the named frames of `loaded` (RL's scenes name their
    /// bodies `link0`, `link1`, … and pair them by position with the model's `<body>` elements).
    pub fn by_order<const N: usize>(
        model: &Model,
        loaded: &LoadedModel<N>,
        frame_names: &[String],
    ) -> Result<Self, SgError> {
        if frame_names.len() < model.bodies().len() {
            return Err(SgError::invalid(
                "number of scene bodies",
                model.bodies().len(),
                "more than the kinematic model's bodies",
            ));
        }
        let frames = frame_names
            .iter()
            .take(model.bodies().len())
            .map(|n| {
                loaded
                    .frame(n)
                    .map(|f| Some((f.body, f.placement)))
                    .ok_or_else(|| {
                        SgError::new(SgErrorKind::UnknownName {
                            what: "frame in the kinematic model",
                            name: n.clone(),
                        })
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Self::new(frames, loaded.model.body_count())
    }

    /// The frame of scene body `i`.
    pub fn frame(&self, i: usize) -> Option<(usize, PlueckerTransform)> {
        self.frames.get(i).copied().flatten()
    }

    /// The number of rl-core bodies the link expects.
    pub fn kinematic_bodies(&self) -> usize {
        self.bodies
    }

    pub(crate) fn frames(&self) -> &[Option<(usize, PlueckerTransform)>] {
        &self.frames
    }
}

/// Why a kinematic update was refused (a small `Copy` value: building it allocates nothing).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UpdateError {
    /// No model with this id.
    UnknownModel,
    /// The model has no [`KinematicLink`].
    NotKinematic,
    /// The kinematic data holds fewer bodies than the link needs.
    TooFewBodies {
        /// Bodies needed.
        needed: usize,
        /// Bodies the data has room for.
        capacity: usize,
    },
    /// A body's pose is not finite (NaN joint values?).
    NotFinite {
        /// The scene body.
        body: usize,
    },
    /// Forward kinematics refused the configuration.
    Kinematics(rl_core::Error),
}

impl fmt::Display for UpdateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnknownModel => f.write_str("no such model in the scene"),
            Self::NotKinematic => f.write_str("the model is not linked to a kinematic model"),
            Self::TooFewBodies { needed, capacity } => write!(
                f,
                "the kinematic data has room for {capacity} bodies, the link needs {needed}"
            ),
            Self::NotFinite { body } => write!(f, "the pose of scene body {body} is not finite"),
            Self::Kinematics(e) => write!(f, "forward kinematics: {e}"),
        }
    }
}

impl std::error::Error for UpdateError {}
