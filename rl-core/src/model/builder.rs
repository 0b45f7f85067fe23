//! Building a model body by body, merging fixed joints as it goes.

use super::{JointLimits, Mimic, Model, ModelError, Name, ROOT, Tool};
use crate::joint::{Joint, MAX_JOINT_NV};
use crate::spatial::{MotionVector, PlueckerTransform, RigidBodyInertia};

/// Builds a [`Model`]: bodies must be added parents first (loaders add them depth-first, in
/// file order, which fixes the joint order as RL and Pinocchio have it).
#[derive(Clone, Debug)]
pub struct ModelBuilder<const N: usize> {
    model: Model<N>,
}

impl<const N: usize> Default for ModelBuilder<N> {
    fn default() -> Self {
        Self::new()
    }
}

fn name(s: &str) -> Result<Name, ModelError> {
    Name::try_new(s).ok_or(ModelError::NameTooLong { len: s.len() })
}

fn check_inertia(i: &RigidBodyInertia, body: usize) -> Result<(), ModelError> {
    let finite = i.mass.is_finite()
        && i.first_moment.is_finite()
        && i.rotational.to_cols_array().iter().all(|x| x.is_finite());
    let ic = i.inertia_com();
    let (a, b, c) = (ic.col(0).x, ic.col(1).y, ic.col(2).z);
    let tol = (1e-9 * (a.abs() + b.abs() + c.abs())).max(1e-12);
    // Moments about the COM are non-negative. (The triangle inequality of physical bodies is not
    // required: RL's own Puma 560 model has I = diag(0, 0.35, 0), a rotor-only inertia.)
    let physical = i.mass >= 0.0 && a >= -tol && b >= -tol && c >= -tol;
    if finite && physical {
        Ok(())
    } else {
        Err(ModelError::InvalidInertia { body })
    }
}

impl<const N: usize> ModelBuilder<N> {
    /// An empty model.
    pub fn new() -> Self {
        Self {
            model: Model::new(),
        }
    }

    /// Sets the model's name.
    pub fn name(&mut self, s: &str) -> Result<&mut Self, ModelError> {
        self.model.name = name(s)?;
        Ok(self)
    }

    /// Sets the physical gravitational acceleration (world coordinates, m/s²).
    pub fn gravity(&mut self, g: glam::DVec3) -> &mut Self {
        self.model.gravity = g;
        self
    }

    /// Number of bodies so far.
    pub fn body_count(&self) -> usize {
        self.model.nbodies
    }

    /// Body `body`'s inertia so far (its own and what was merged into it), in its frame.
    pub fn inertia(&self, body: usize) -> Option<&RigidBodyInertia> {
        self.model.inertias[..self.model.nbodies].get(body)
    }

    /// Adds a moving body hanging from `parent` (a body index or [`ROOT`]) through `joint`,
    /// whose frame sits at `placement` in the parent's frame. Returns the new body's index.
    pub fn add_body(
        &mut self,
        parent: usize,
        joint_name: &str,
        joint: Joint,
        placement: PlueckerTransform,
        body_name: &str,
        inertia: RigidBodyInertia,
    ) -> Result<usize, ModelError> {
        let m = &mut self.model;
        let i = m.nbodies;
        if i >= N {
            return Err(ModelError::TooManyBodies { capacity: N });
        }
        if parent != ROOT && parent >= i {
            return Err(ModelError::UnknownParent { parent });
        }
        if m.nv_ext + joint.nv() > N {
            return Err(ModelError::TooManyDofs {
                capacity: N,
                needed: m.nv_ext + joint.nv(),
            });
        }
        if !placement.translation.is_finite()
            || !placement
                .rotation
                .to_cols_array()
                .iter()
                .all(|x| x.is_finite())
        {
            return Err(ModelError::NotFinite {
                what: "joint placement",
            });
        }
        let axis_ok = match &joint {
            Joint::Revolute(j) => j.axis.is_finite() && j.axis.length() > 0.5,
            Joint::Prismatic(j) => j.axis.is_finite() && j.axis.length() > 0.5,
            Joint::Helical(j) => j.axis.is_finite() && j.axis.length() > 0.5 && j.pitch.is_finite(),
            Joint::Cylindrical(j) => j.axis.is_finite() && j.axis.length() > 0.5,
            _ => true,
        };
        if !axis_ok {
            return Err(ModelError::InvalidAxis { body: i });
        }
        check_inertia(&inertia, i)?;
        m.joint_names[i] = name(joint_name)?;
        m.body_names[i] = name(body_name)?;
        m.parents[i] = parent;
        m.joints[i] = joint;
        m.placements[i] = placement;
        m.inertias[i] = inertia;
        // Until `build`, every joint has coordinates of its own (internal indices).
        m.idx_v[i] = m.nv_ext;
        let mut s = [MotionVector::ZERO; MAX_JOINT_NV];
        joint.motion_subspace(&mut s);
        for (k, col) in s.iter().enumerate().take(joint.nv()) {
            m.subspace[m.nv_ext + k] = *col;
            m.dof_body[m.nv_ext + k] = i;
            m.limits[m.nv_ext + k] = JointLimits::UNLIMITED;
        }
        m.nv_ext += joint.nv();
        m.nbodies += 1;
        Ok(i)
    }

    /// Makes `body`'s joint follow `leader`'s: `q_body = multiplier · q_leader + offset` (a mimic
    /// joint, see [`super::mimic`]). Both joints have one coordinate; the leader is no mimic
    /// joint itself and `body` leads no other (resolve chains first: a mimic of a mimic follows
    /// the first leader with the multipliers multiplied). The leader may be added before or
    /// after `body`. Limits set on `body` are dropped (it has no coordinate of its own).
    pub fn set_mimic(
        &mut self,
        body: usize,
        leader: usize,
        multiplier: f64,
        offset: f64,
    ) -> Result<&mut Self, ModelError> {
        let m = &mut self.model;
        let bad = |reason| Err(ModelError::InvalidMimic { body, reason });
        if body >= m.nbodies {
            return Err(ModelError::UnknownBody { body });
        }
        if leader >= m.nbodies {
            return Err(ModelError::UnknownBody { body: leader });
        }
        if !(multiplier.is_finite() && offset.is_finite()) {
            return bad("the multiplier or offset is not finite");
        }
        if body == leader {
            return bad("it follows itself");
        }
        if m.joints[body].nq() != 1 || m.joints[body].nv() != 1 {
            return bad("only a joint with one coordinate can follow another");
        }
        if m.joints[leader].nq() != 1 || m.joints[leader].nv() != 1 {
            return bad("the joint it follows does not have exactly one coordinate");
        }
        if m.mimic[leader].is_some() {
            return bad("the joint it follows is a mimic joint itself");
        }
        if m.mimic[..m.nbodies]
            .iter()
            .any(|x| x.is_some_and(|x| x.leader == body))
        {
            return bad("another mimic joint follows it");
        }
        m.mimic[body] = Some(Mimic {
            leader,
            multiplier,
            offset,
        });
        Ok(self)
    }

    /// Rigidly attaches more mass to `body` (or to the world with [`ROOT`]): `inertia` is given
    /// in a frame whose pose in the body's frame is `placement`. This is how fixed joints are
    /// merged.
    pub fn add_fixed_inertia(
        &mut self,
        body: usize,
        placement: PlueckerTransform,
        inertia: RigidBodyInertia,
    ) -> Result<&mut Self, ModelError> {
        let m = &mut self.model;
        check_inertia(&inertia, body)?;
        if body == ROOT {
            m.base_mass += inertia.mass;
            return Ok(self);
        }
        if body >= m.nbodies {
            return Err(ModelError::UnknownBody { body });
        }
        m.inertias[body] += inertia.transform_to_parent(&placement);
        Ok(self)
    }

    /// Sets the limits of DOF `dof` of `body`'s joint.
    pub fn set_limits(
        &mut self,
        body: usize,
        dof: usize,
        limits: JointLimits,
    ) -> Result<&mut Self, ModelError> {
        let m = &mut self.model;
        if body >= m.nbodies {
            return Err(ModelError::UnknownBody { body });
        }
        if dof >= m.joints[body].nv() {
            return Err(ModelError::UnknownDof { body, dof });
        }
        m.limits[m.idx_v[body] + dof] = limits;
        Ok(self)
    }

    /// Adds a tool (operational frame) at `placement` in `body`'s frame (or the world's).
    pub fn add_tool(
        &mut self,
        tool_name: &str,
        body: usize,
        placement: PlueckerTransform,
    ) -> Result<usize, ModelError> {
        let m = &mut self.model;
        if m.ntools >= N {
            return Err(ModelError::TooManyTools { capacity: N });
        }
        if body != ROOT && body >= m.nbodies {
            return Err(ModelError::UnknownBody { body });
        }
        m.tools[m.ntools] = Tool {
            name: name(tool_name)?,
            body,
            placement,
        };
        m.ntools += 1;
        Ok(m.ntools - 1)
    }

    /// The finished model.
    pub fn build(mut self) -> Model<N> {
        let m = &mut self.model;
        for i in 0..m.nbodies {
            m.coms[i] = m.inertias[i].com();
            m.inertias_com[i] = m.inertias[i].inertia_com();
        }
        m.finish_coordinates();
        self.model
    }
}
