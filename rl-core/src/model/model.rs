//! The immutable description of a tree of rigid bodies.

use glam::{DMat3, DVec3};

use super::{JointLimits, Mimic, Name};
use crate::joint::{Joint, Revolute};
use crate::spatial::{
    ForceVector, MotionVector, PlueckerTransform, RigidBodyInertia, rotate_symmetric_upper,
    shift_upper, symmetric_from_upper,
};

/// The parent index of a body attached to the world (the fixed base).
pub const ROOT: usize = usize::MAX;

/// How far from 1 the norm of a configuration's quaternion may be
/// ([`Model::unit_quaternion_errors`]): far above the rounding of computed quaternions, far
/// below the error of one typed with four decimals.
pub const UNIT_QUATERNION_TOLERANCE: f64 = 1e-6;

/// A quaternion of a configuration that is not of unit norm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuaternionNorm {
    /// The body whose joint it belongs to.
    pub body: usize,
    /// The index of its `x` in `q` (`x, y, z, w` follow).
    pub q_index: usize,
    /// Its norm.
    pub norm: f64,
}

/// A tool (operational frame, RL's end-effector): a frame rigidly attached to a body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tool {
    /// The tool's name.
    pub name: Name,
    /// The body it is attached to, or [`ROOT`] for the world.
    pub body: usize,
    /// Its pose in the body's frame.
    pub placement: PlueckerTransform,
}

/// A tree of up to `N` moving bodies with up to `N` degrees of freedom in total (mimic joints
/// count here too: `N` bounds the internal coordinates, see [`super::mimic`]).
///
/// Body `i` hangs from `parent(i)` (an earlier body, or [`ROOT`]) through its joint: the
/// joint frame sits at `placement(i)` in the parent's frame, and the body frame is the joint's
/// child frame. Build one with [`super::ModelBuilder`] or a loader; it never changes after.
///
/// A joint may follow another ([`Model::mimic`]): it then has no coordinates of its own in
/// `q`, `q̇`, `q̈` and `τ`, which hold the independent joints only ([`Model::nq`],
/// [`Model::dof`]).
#[derive(Clone, Debug)]
pub struct Model<const N: usize> {
    pub(crate) name: Name,
    pub(crate) nbodies: usize,
    pub(crate) nq: usize,
    pub(crate) nv: usize,
    pub(crate) parents: [usize; N],
    pub(crate) joints: [Joint; N],
    pub(crate) placements: [PlueckerTransform; N],
    pub(crate) inertias: [RigidBodyInertia; N],
    /// Each body's centre of mass and rotational inertia about it (body axes), kept beside
    /// `inertias` because rotating an inertia about its centre of mass is the cheap way.
    pub(crate) coms: [DVec3; N],
    pub(crate) inertias_com: [DMat3; N],
    /// Index of each body's first coordinate in the public `q` (its leader's for a mimic joint).
    pub(crate) idx_q: [usize; N],
    /// Index of each body's first internal velocity coordinate (the sweeps' indexing: every
    /// joint, mimic or not, has its own).
    pub(crate) idx_v: [usize; N],
    pub(crate) joint_names: [Name; N],
    pub(crate) body_names: [Name; N],
    /// Motion subspace columns, one per internal coordinate, in the owning body's coordinates.
    pub(crate) subspace: [MotionVector; N],
    /// The body that owns each internal coordinate.
    pub(crate) dof_body: [usize; N],
    /// The public DOF before each public DOF on the path of the sparse factorisation of `M`
    /// (Featherstone's λ; the elimination tree when mimic joints couple branches), or [`ROOT`].
    pub(crate) dof_parent: [usize; N],
    /// Limits per public DOF.
    pub(crate) limits: [JointLimits; N],
    /// Number of internal velocity coordinates (`nv` plus one per mimic joint).
    pub(crate) nv_ext: usize,
    /// How each body's joint follows another, if it does.
    pub(crate) mimic: [Option<Mimic>; N],
    /// Per internal coordinate: the public DOF it follows (its own, or its leader's) …
    pub(crate) ext_v: [usize; N],
    /// … and the factor (1, or the mimic multiplier): `q̇_int[k] = ext_scale[k] q̇[ext_v[k]]`.
    pub(crate) ext_scale: [f64; N],
    /// Per public DOF: its internal coordinate.
    pub(crate) v_ext: [usize; N],
    /// Whether any joint is a mimic joint.
    pub(crate) has_mimic: bool,
    pub(crate) tools: [Tool; N],
    pub(crate) ntools: usize,
    /// Physical gravitational acceleration in world coordinates, m/s².
    pub(crate) gravity: DVec3,
    /// Mass rigidly attached to the world (does not move; reported, never simulated).
    pub(crate) base_mass: f64,
    /// Rotor inertia reflected to each public DOF (kg·m² or kg), on the mass matrix's diagonal.
    pub(crate) armature: [f64; N],
    /// Whether any armature is non-zero (the dynamics skip it otherwise).
    pub(crate) has_armature: bool,
    /// Viscous friction per public DOF (N·m·s/rad or N·s/m).
    pub(crate) damping: [f64; N],
    /// Dry (Coulomb) friction per public DOF (N·m or N).
    pub(crate) friction: [f64; N],
    /// Whether any damping or friction is non-zero (the compensation skips it otherwise).
    pub(crate) has_friction: bool,
}

impl<const N: usize> Default for Model<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Model<N> {
    /// An empty model (no bodies), gravity `(0, 0, -9.80665)`.
    pub fn new() -> Self {
        let filler = Tool {
            name: Name::EMPTY,
            body: ROOT,
            placement: PlueckerTransform::IDENTITY,
        };
        Self {
            name: Name::EMPTY,
            nbodies: 0,
            nq: 0,
            nv: 0,
            parents: [ROOT; N],
            joints: [Joint::Revolute(Revolute { axis: DVec3::Z }); N],
            placements: [PlueckerTransform::IDENTITY; N],
            inertias: [RigidBodyInertia::ZERO; N],
            coms: [DVec3::ZERO; N],
            inertias_com: [DMat3::ZERO; N],
            idx_q: [0; N],
            idx_v: [0; N],
            joint_names: [Name::EMPTY; N],
            body_names: [Name::EMPTY; N],
            subspace: [MotionVector::ZERO; N],
            dof_body: [0; N],
            dof_parent: [ROOT; N],
            limits: [JointLimits::UNLIMITED; N],
            nv_ext: 0,
            mimic: [None; N],
            ext_v: [0; N],
            ext_scale: [1.0; N],
            v_ext: [0; N],
            has_mimic: false,
            tools: [filler; N],
            ntools: 0,
            gravity: DVec3::new(0.0, 0.0, -9.80665),
            base_mass: 0.0,
            armature: [0.0; N],
            has_armature: false,
            damping: [0.0; N],
            friction: [0.0; N],
            has_friction: false,
        }
    }

    /// The model's name.
    pub fn name(&self) -> &str {
        self.name.as_str()
    }

    /// Number of moving bodies (= number of joints, mimic joints included).
    #[inline]
    pub fn body_count(&self) -> usize {
        self.nbodies
    }

    /// Number of position coordinates (length of `q`).
    #[inline]
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// Number of velocity coordinates, the degrees of freedom (length of `q̇`, `q̈`, `τ`).
    #[inline]
    pub fn dof(&self) -> usize {
        self.nv
    }

    /// The parent of body `i`, or [`ROOT`].
    pub fn parent(&self, i: usize) -> usize {
        self.parents[i]
    }

    /// The joint of body `i`.
    pub fn joint(&self, i: usize) -> &Joint {
        &self.joints[i]
    }

    /// The joint frame's pose in the parent body's frame.
    pub fn placement(&self, i: usize) -> &PlueckerTransform {
        &self.placements[i]
    }

    /// Body `i`'s inertia in its own frame (fixed children merged in).
    pub fn inertia(&self, i: usize) -> &RigidBodyInertia {
        &self.inertias[i]
    }

    /// The name of body `i`'s joint.
    pub fn joint_name(&self, i: usize) -> &str {
        self.joint_names[i].as_str()
    }

    /// The name of body `i`.
    pub fn body_name(&self, i: usize) -> &str {
        self.body_names[i].as_str()
    }

    /// The first index of body `i`'s coordinates in `q` (for a mimic joint: its leader's).
    pub fn q_index(&self, i: usize) -> usize {
        self.idx_q[i]
    }

    /// The first index of body `i`'s coordinates in `q̇` (for a mimic joint: its leader's).
    pub fn v_index(&self, i: usize) -> usize {
        self.ext_v[self.idx_v[i]]
    }

    /// How many entries of `q` body `i`'s joint owns: its `nq`, or 0 for a mimic joint.
    pub fn joint_nq(&self, i: usize) -> usize {
        if self.mimic[i].is_some() {
            0
        } else {
            self.joints[i].nq()
        }
    }

    /// How many entries of `q̇` body `i`'s joint owns: its `nv`, or 0 for a mimic joint.
    pub fn joint_nv(&self, i: usize) -> usize {
        if self.mimic[i].is_some() {
            0
        } else {
            self.joints[i].nv()
        }
    }

    /// How body `i`'s joint follows another one, if it is a mimic joint.
    pub fn mimic(&self, i: usize) -> Option<&Mimic> {
        self.mimic[i].as_ref()
    }

    /// Whether any joint is a mimic joint.
    #[inline]
    pub fn has_mimic(&self) -> bool {
        self.has_mimic
    }

    /// Body `i`'s joint position when the model is at `q` (the mimic relation applied), for a
    /// joint with one coordinate; `None` for other joints.
    pub fn joint_position(&self, i: usize, q: &[f64]) -> Option<f64> {
        if self.joints[i].nq() != 1 {
            return None;
        }
        let x = *q.get(self.idx_q[i])?;
        Some(match &self.mimic[i] {
            Some(m) => m.multiplier * x + m.offset,
            None => x,
        })
    }

    /// Limits of DOF `k` (index into `q̇`).
    pub fn limits(&self, k: usize) -> &JointLimits {
        &self.limits[k]
    }

    /// The body that owns DOF `k` (index into `q̇`).
    pub fn dof_body(&self, k: usize) -> usize {
        self.dof_body[self.v_ext[k]]
    }

    /// The tools (operational frames).
    pub fn tools(&self) -> &[Tool] {
        &self.tools[..self.ntools]
    }

    /// The index of the tool called `name`.
    pub fn tool_index(&self, name: &str) -> Option<usize> {
        self.tools().iter().position(|t| t.name.as_str() == name)
    }

    /// The index of the body called `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.body_names[..self.nbodies]
            .iter()
            .position(|n| n.as_str() == name)
    }

    /// Physical gravitational acceleration in world coordinates, m/s² (e.g. `(0, 0, -9.81)`).
    pub fn gravity(&self) -> DVec3 {
        self.gravity
    }

    /// Sets the physical gravitational acceleration.
    pub fn set_gravity(&mut self, g: DVec3) {
        self.gravity = g;
    }

    /// The armature of each DOF ([`Model::dof`] elements, kg·m² for a rotation, kg for a
    /// translation): the inertia of the motor's rotor and gears reflected through the gear
    /// ratio (`I_rotor · n²`), which moves with the joint but belongs to no link. It adds to
    /// the mass matrix's diagonal, `M + diag(armature)`, so RNEA adds `armature · q̈`, CRBA its
    /// diagonal, ABA each joint's `D = Sᵀ Iᴬ S + armature`, and their derivatives follow
    /// (Pinocchio's `Model::armature`, MuJoCo's joint `armature`). URDF has no field for it:
    /// 0 unless set ([`Model::set_armature`]).
    pub fn armature(&self) -> &[f64] {
        &self.armature[..self.nv]
    }

    /// Sets the armature of every DOF ([`Model::armature`]): `armature` has [`Model::dof`]
    /// elements, each finite and not negative.
    pub fn set_armature(&mut self, armature: &[f64]) -> Result<(), crate::Error> {
        self.check_per_dof("armature", armature)?;
        self.armature[..self.nv].copy_from_slice(armature);
        self.has_armature = armature.iter().any(|a| *a != 0.0);
        Ok(())
    }

    /// The joints' friction, per DOF: viscous `damping` (N·m·s/rad, N·s/m) and dry `friction`
    /// (N·m, N) — Pinocchio's `Model::damping` and `Model::friction`, MuJoCo's joint `damping`
    /// and `frictionloss`. The rigid-body algorithms leave them out (they are not part of
    /// `M q̈ + C + G`); a controller compensates them with [`Model::friction_torque`]. 0 unless
    /// set ([`Model::set_joint_friction`]).
    pub fn joint_friction(&self) -> (&[f64], &[f64]) {
        (&self.damping[..self.nv], &self.friction[..self.nv])
    }

    /// Sets the joints' friction ([`Model::joint_friction`]): [`Model::dof`] elements each,
    /// finite and not negative.
    pub fn set_joint_friction(
        &mut self,
        damping: &[f64],
        friction: &[f64],
    ) -> Result<(), crate::Error> {
        self.check_per_dof("damping", damping)?;
        self.check_per_dof("friction", friction)?;
        self.damping[..self.nv].copy_from_slice(damping);
        self.friction[..self.nv].copy_from_slice(friction);
        self.has_friction = damping.iter().chain(friction).any(|x| *x != 0.0);
        Ok(())
    }

    /// Adds the joints' friction torque at `qd` to `tau`: `damping · q̇ + friction ·
    /// tanh(q̇ / smoothing)`, the dry friction smoothed over `smoothing` (rad/s or m/s, > 0)
    /// so that the torque is continuous through rest. `qd`, `tau`: [`Model::dof`] (shorter
    /// slices: their length).
    pub fn friction_torque(&self, qd: &[f64], smoothing: f64, tau: &mut [f64]) {
        if !self.has_friction {
            return;
        }
        for (k, (t, v)) in tau.iter_mut().zip(qd).take(self.nv).enumerate() {
            *t += self.damping[k] * v + self.friction[k] * libm::tanh(v / smoothing);
        }
    }

    /// `values` has one finite, non-negative element per DOF.
    fn check_per_dof(&self, argument: &'static str, values: &[f64]) -> Result<(), crate::Error> {
        crate::error::check_len(argument, values, self.nv)?;
        match values.iter().position(|a| !(a.is_finite() && *a >= 0.0)) {
            Some(index) => Err(crate::Error::NotPhysical { argument, index }),
            None => Ok(()),
        }
    }

    /// `m[k][k] += armature[k]` for every DOF (the upper triangle's diagonal of a public
    /// mass matrix).
    #[inline]
    pub(crate) fn add_armature_to_diagonal(&self, m: &mut [[f64; N]; N]) {
        if self.has_armature {
            for k in 0..self.nv {
                m[k][k] += self.armature[k];
            }
        }
    }

    /// `tau[k] += armature[k] · qdd[k]` for every DOF.
    #[inline]
    pub(crate) fn add_armature_torque(&self, tau: &mut [f64], qdd: &[f64]) {
        if self.has_armature {
            for k in 0..self.nv {
                tau[k] += self.armature[k] * qdd[k];
            }
        }
    }

    /// Total mass of the moving bodies, kg.
    pub fn moving_mass(&self) -> f64 {
        self.inertias[..self.nbodies]
            .iter()
            .fold(0.0, |m, i| m + i.mass)
    }

    /// Mass rigidly attached to the world (a fixed base), kg.
    pub fn base_mass(&self) -> f64 {
        self.base_mass
    }

    /// Whether body `a` is `b` or one of its ancestors.
    pub fn is_ancestor(&self, a: usize, mut b: usize) -> bool {
        while b != ROOT {
            if a == b {
                return true;
            }
            b = self.parents[b];
        }
        false
    }

    /// Body `i`'s inertia in the coordinates of a frame in which the body sits at `x` (e.g. the
    /// world): the centre of mass moves, the inertia about it rotates, and the parallel-axis
    /// term is added once (cheaper than transforming the inertia about the body's origin).
    #[inline]
    pub(crate) fn world_inertia(&self, i: usize, x: &PlueckerTransform) -> RigidBodyInertia {
        let m = self.inertias[i].mass;
        let c = x.transform_point(self.coms[i]);
        // Ī = R I_c Rᵀ + m (|c|² 1 − c cᵀ), on the upper triangle.
        let e = rotate_symmetric_upper(&x.rotation, &self.inertias_com[i]);
        let mc = c * m;
        RigidBodyInertia {
            mass: m,
            first_moment: mc,
            rotational: symmetric_from_upper(shift_upper(e, c, mc * 0.5, mc.dot(c))),
        }
    }

    /// `S q̇` of body `i`'s joint, with `x` a full velocity-sized vector.
    #[inline(always)]
    pub(crate) fn joint_motion(&self, i: usize, x: &[f64]) -> MotionVector {
        let sv = self.idx_v[i];
        match &self.joints[i] {
            Joint::Revolute(j) => MotionVector::new(j.axis * x[sv], DVec3::ZERO),
            Joint::Prismatic(j) => MotionVector::new(DVec3::ZERO, j.axis * x[sv]),
            j => {
                let mut m = MotionVector::ZERO;
                for k in sv..sv + j.nv() {
                    m += self.subspace[k] * x[k];
                }
                m
            }
        }
    }

    /// Motion subspace column `k` (a DOF of body `i`) in the coordinates of a frame in which
    /// body `i` sits at `x`; revolute and prismatic columns skip their zero half.
    #[inline(always)]
    pub(crate) fn act_subspace(&self, i: usize, k: usize, x: &PlueckerTransform) -> MotionVector {
        let s = &self.subspace[k];
        match &self.joints[i] {
            Joint::Revolute(_) => {
                let w = x.rotation * s.angular;
                MotionVector::new(w, x.translation.cross(w))
            }
            Joint::Prismatic(_) => MotionVector::new(DVec3::ZERO, x.rotation * s.linear),
            _ => x.act_motion(s),
        }
    }

    /// `Sᵀ f` of body `i`'s joint into its entries of `out` (a velocity-sized vector).
    #[inline(always)]
    pub(crate) fn joint_force(&self, i: usize, f: &ForceVector, out: &mut [f64]) {
        let sv = self.idx_v[i];
        match &self.joints[i] {
            Joint::Revolute(j) => out[sv] = j.axis.dot(f.moment),
            Joint::Prismatic(j) => out[sv] = j.axis.dot(f.force),
            j => {
                for k in sv..sv + j.nv() {
                    out[k] = self.subspace[k].dot(f);
                }
            }
        }
    }

    /// The neutral configuration (zeros, identity quaternions) into `q[..nq]`.
    pub fn neutral(&self, q: &mut [f64]) {
        for i in 0..self.nbodies {
            if self.mimic[i].is_some() {
                continue;
            }
            let j = &self.joints[i];
            let s = self.idx_q[i];
            j.neutral(&mut q[s..s + j.nq()]);
        }
    }

    /// `q ⊕ v dt` for the whole model (see [`Joint::integrate`]).
    pub fn integrate(&self, q: &[f64], v: &[f64], dt: f64, out: &mut [f64]) {
        for i in 0..self.nbodies {
            if self.mimic[i].is_some() {
                continue;
            }
            let j = &self.joints[i];
            let (sq, sv) = (self.idx_q[i], self.v_index(i));
            j.integrate(
                &q[sq..sq + j.nq()],
                &v[sv..sv + j.nv()],
                dt,
                &mut out[sq..sq + j.nq()],
            );
        }
    }

    /// The quaternions of `q` (spherical and six-DOF joints) that are not unit quaternions: a
    /// norm off 1 by more than [`UNIT_QUATERNION_TOLERANCE`], zero or not finite. The
    /// algorithms use a quaternion as given (a non-unit one shears the rotation), so inputs
    /// from outside should pass this check or go through [`Model::normalize`].
    pub fn unit_quaternion_errors<'a>(
        &'a self,
        q: &'a [f64],
    ) -> impl Iterator<Item = QuaternionNorm> + 'a {
        (0..self.nbodies).filter_map(move |i| {
            let at = match self.joints[i] {
                Joint::Spherical(_) if self.mimic[i].is_none() => self.idx_q[i],
                Joint::SixDof(_) if self.mimic[i].is_none() => self.idx_q[i] + 3,
                _ => return None,
            };
            let x = q.get(at..at + 4)?;
            let norm = libm::sqrt(x.iter().map(|v| v * v).sum::<f64>());
            let ok = norm.is_finite() && (norm - 1.0).abs() <= UNIT_QUATERNION_TOLERANCE;
            (!ok).then_some(QuaternionNorm {
                body: i,
                q_index: at,
                norm,
            })
        })
    }

    /// Renormalises every quaternion in `q`.
    pub fn normalize(&self, q: &mut [f64]) {
        for i in 0..self.nbodies {
            if self.mimic[i].is_some() {
                continue;
            }
            let j = &self.joints[i];
            let s = self.idx_q[i];
            j.normalize(&mut q[s..s + j.nq()]);
        }
    }

    /// A configuration drawn from `next_uniform` (uniform in `[0, 1)`): uniform within finite
    /// limits, in `[-π, π]` (angles) or `[-1, 1]` m (translations) where unlimited, and a
    /// uniformly random unit quaternion for ball and free joints.
    pub fn random_configuration(&self, q: &mut [f64], mut next_uniform: impl FnMut() -> f64) {
        for i in 0..self.nbodies {
            if self.mimic[i].is_some() {
                continue;
            }
            let j = &self.joints[i];
            let (sq, sv) = (self.idx_q[i], self.v_index(i));
            let mut draw = |k: usize, default_half_range: f64| {
                let l = &self.limits[sv + k];
                let u = next_uniform();
                if l.is_bounded() {
                    l.lower + (l.upper - l.lower) * u
                } else {
                    (2.0 * u - 1.0) * default_half_range
                }
            };
            let pi = core::f64::consts::PI;
            match j {
                Joint::Revolute(_) | Joint::Helical(_) => q[sq] = draw(0, pi),
                Joint::Prismatic(_) => q[sq] = draw(0, 1.0),
                Joint::Cylindrical(_) => {
                    q[sq] = draw(0, pi);
                    q[sq + 1] = draw(1, 1.0);
                }
                Joint::Planar(_) => {
                    q[sq] = draw(0, 1.0);
                    q[sq + 1] = draw(1, 1.0);
                    q[sq + 2] = draw(2, pi);
                }
                Joint::Spherical(_) | Joint::SixDof(_) => {
                    let o = if matches!(j, Joint::SixDof(_)) {
                        for k in 0..3 {
                            q[sq + k] = draw(k, 1.0);
                        }
                        3
                    } else {
                        0
                    };
                    // Shoemake's uniform random rotation.
                    let (u1, u2, u3) = (next_uniform(), next_uniform(), next_uniform());
                    let (a, b) = (libm::sqrt(1.0 - u1), libm::sqrt(u1));
                    let t = 2.0 * pi;
                    q[sq + o] = a * libm::sin(t * u2);
                    q[sq + o + 1] = a * libm::cos(t * u2);
                    q[sq + o + 2] = b * libm::sin(t * u3);
                    q[sq + o + 3] = b * libm::cos(t * u3);
                }
            }
        }
    }
}
