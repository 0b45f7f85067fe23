//! Operational-space impedance with a dynamically consistent nullspace.
//!
//! The tool's task acceleration is commanded as a mass–spring–damper of unit mass per task
//! direction, and the joint torques that produce it are found through the operational-space
//! inertia (Khatib, *A unified approach for motion and force control of robot manipulators:
//! the operational space formulation*, IEEE J. Robotics and Automation 3(1), 1987):
//!
//! ```text
//! a   = ẍ_d + K_d (ẋ_d − ẋ) + K_p e                 e = [p_d − p; log(R_d Rᵀ)]   (world)
//! Λ   = (J M⁻¹ Jᵀ)⁻¹, clamped or damped near singularities (below)
//! τ   = Jᵀ Λ (a − J̇ q̇) + Nᵀ M a₀ + C(q, q̇) + G(q)     Nᵀ = I − Jᵀ Λ J M⁻¹
//! a₀  = K_q (q_r − q) − D_q q̇ + a_lim                (posture and joint-limit avoidance)
//! ```
//!
//! plus the joints' own friction where the model has it ([`Model::joint_friction`]:
//! `d q̇ + f tanh(q̇ / v_s)`, compensated at the measured `q̇`).
//!
//! Away from singularities, with the errors under their saturation, the closed loop is
//! `ë + K_d ė + K_p e = 0` in every task direction (exactly for the position; for the
//! orientation to first order in the error, as `ė_o` is the angular velocity error only for
//! small errors), decoupled, whatever the arm's inertia (`J M⁻¹ Nᵀ = 0`: the nullspace torque
//! moves no task coordinate), and `K_d = 2ζ√K_p` makes it critically damped for `ζ = 1`. Near
//! a singularity `J M⁻¹ Jᵀ` loses rank and `Λ` grows without bound; [`Singularity`] chooses
//! what bounds it by `ε⁻¹` (`ε = diag(ε_lin I₃, ε_ang I₃)`), so that the torques stay bounded at
//! the price of a task error in the singular direction:
//!
//! - [`Singularity::Clamped`] (the default): the eigenvalues of `ε^{-1/2} J M⁻¹ Jᵀ ε^{-1/2}`
//!   are clamped from below at 1 (a symmetric eigen-decomposition,
//!   [`crate::math::symmetric_eigen`], made only when a Cholesky factorisation of the weighted
//!   matrix less the identity finds an eigenvalue under 1): directions farther than that from
//!   singular are inverted exactly, so the task is exact wherever no clamp acts.
//! - [`Singularity::Damped`]: `Λ = (J M⁻¹ Jᵀ + ε)⁻¹` (damped least squares in the operational
//!   space, Nakamura & Hanafusa 1986): cheaper, but every direction is softened a little.
//! - [`Singularity::Exact`]: no bound; a singular task is an error.
//!
//! `J`: the
//! tool's world Jacobian at its origin, rows `[linear; angular]` (RL's convention,
//! [`crate::algo::jacobian`]); only the rows [`ImpedanceGains::orientation`] selects form the task
//! (e.g. position only, leaving the tool's orientation to the nullspace). The orientation
//! error is the rotation vector of `R_d Rᵀ` (the shortest way, `|e_o| ≤ π`); its derivative is
//! the angular velocity error for small errors, as is usual.
//!
//! **Priorities** ([`Priority`]). With `OrientationFirst` the orientation rows (`a`) come
//! first and the position rows (`l`) act in their dynamically consistent nullspace
//! (Khatib's prioritised operational space; Sentis & Khatib 2005), with `Ψ = J M⁻¹ Jᵀ`:
//!
//! ```text
//! τ₁ = J_aᵀ Λ₁ a_a                          Λ₁ = Ψ_aa⁻¹
//! τ₂ = N₁ᵀ J_lᵀ Λ₂ (a_l − Ψ_la Λ₁ a_a)      Λ₂ = (Ψ_ll − Ψ_la Λ₁ Ψ_al)⁻¹,  N₁ᵀ = I − J_aᵀ Λ₁ J_a M⁻¹
//! τ  = τ₁ + τ₂ + N₁ᵀ τ_rep + Nᵀ M a₀ + C + G
//! ```
//!
//! (both inverses bounded as [`Singularity`] says): the orientation's acceleration is exact
//! whatever the lower levels and the repulsion ([`super::repulsion`], at the robot's points
//! near obstacles, [`TaskData::set_proximities`]) ask; the position's is exact without
//! obstacles and yields to them — its commanded acceleration fades with the nearest
//! obstacle's activation, to none at the margin; away from singularities the two levels give
//! the same torques as the one 6-D task. With `Together` the repulsion acts in the whole
//! task's nullspace, as the posture does.
//!
//! `q`, `q_r`: `nq` (= `nv`: fixed-base models without quaternion joints); `q̇`, `τ`: `nv`.
//! Cost: one CRBA, its sparse factorisation and `m ≤ 6` solves, one Jacobian, one forward
//! acceleration sweep (`J̇ q̇`), one RNEA (without gravity when the device adds it),
//! two `m × m` Cholesky factorisations, and a Jacobi eigen-decomposition when the clamp acts;
//! with two levels two more `3 × 3` inversions; per proximity one forward sweep (once), one
//! point Jacobian and one solve.
//! The gains are checked at every call ([`ImpedanceGains::check`]). Does not allocate.

use core::fmt;

use glam::{DQuat, DVec3};

use crate::algo::{
    Jacobian, coriolis, crba, factor_mass_matrix, jacobian, jacobian_derivative_times_qd,
    nonlinear_effects, solve_mass_matrix, tool_pose,
};
use crate::error::{Error, check_len};
use crate::math::{invert_spd, symmetric_eigen};
use crate::model::{Data, Model};
use crate::rotation::quaternion;
use crate::spatial::PlueckerTransform;

use super::repulsion::{MAX_PROXIMITIES, Proximity, Repulsion, add_repulsion};

/// What the task controls of the tool's orientation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Orientation {
    /// Position and orientation (a 6-D task).
    #[default]
    Held,
    /// Position only (a 3-D task); the orientation is left to the nullspace.
    Free,
}

/// The gains of [`operational_impedance`]. Stiffnesses are per unit of operational inertia
/// (accelerations per unit error, 1/s²): the task behaves the same whatever the arm carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpedanceGains {
    /// Task stiffness `K_p`, 1/s², per world direction `[x y z; rx ry rz]`.
    pub stiffness: [f64; 6],
    /// Damping ratio `ζ` of the task directions (`K_d = 2ζ√K_p`; 1: critical).
    pub damping_ratio: f64,
    /// Which task rows are controlled.
    pub orientation: Orientation,
    /// The task error is saturated to this length (m) before the spring acts, so that a far
    /// target pulls with a bounded acceleration; `f64::INFINITY`: not saturated.
    pub max_position_error: f64,
    /// The orientation error is saturated to this angle (rad).
    pub max_orientation_error: f64,
    /// Posture stiffness `K_q` in the nullspace, 1/s².
    pub posture_stiffness: f64,
    /// Damping ratio of the posture (`D_q = 2ζ_q√K_q`); it also damps the nullspace motion.
    pub posture_damping_ratio: f64,
    /// Joint-limit avoidance: within this distance of a joint's limit (rad or m) the nullspace
    /// pushes it away, `a_lim = limit_stiffness · (band − distance)`; 0: off.
    pub limit_band: f64,
    /// The joint-limit push per unit of intrusion into the band, 1/s².
    pub limit_stiffness: f64,
    /// How `Λ` is kept bounded near singularities.
    pub singularity: Singularity,
    /// The device adds the gravity torque itself (a Franka arm): `G(q)` is left out of `τ`.
    pub gravity_by_device: bool,
    /// Which task rows yield to which ([`Priority`]).
    pub priority: Priority,
    /// The repulsion from the proximities in [`TaskData::set_proximities`].
    pub repulsion: Repulsion,
    /// The joints' friction in the model ([`Model::joint_friction`]) is compensated at the
    /// measured `q̇`, its dry part smoothed over this speed (rad/s or m/s, > 0;
    /// [`Model::friction_torque`]).
    pub friction_smoothing: f64,
}

/// The order of the task's parts when they cannot all be met (module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Priority {
    /// Position and orientation as one task; the repulsion and the posture act in its
    /// nullspace (on a 7-DoF arm with a 6-D task: the elbow only).
    #[default]
    Together,
    /// The orientation first; the position in its nullspace, where the repulsion acts beside
    /// it: the position yields to obstacles — its command fades with the nearest obstacle's
    /// activation `s` ([`Repulsion::activation`]: 0 at the influence distance, 1 at the
    /// margin), `ẍ_l ← (1 − s) ẍ_l` of the commanded tool acceleration — the orientation does not; the posture in the nullspace
    /// of both. With [`Orientation::Free`] the same as `Together`.
    OrientationFirst,
}

impl Default for ImpedanceGains {
    /// `K_p` 400 1/s² for position (20 rad/s, 3.2 Hz) and 300 1/s² for orientation
    /// (17 rad/s), critically damped; errors saturated at 5 cm and 0.3 rad; a 10 1/s² posture;
    /// a 0.1 rad joint-limit band pushing at 200 1/s²; singularity damping `1e-3`.
    fn default() -> Self {
        Self {
            stiffness: [400.0, 400.0, 400.0, 300.0, 300.0, 300.0],
            damping_ratio: 1.0,
            orientation: Orientation::Held,
            max_position_error: 0.05,
            max_orientation_error: 0.3,
            posture_stiffness: 10.0,
            posture_damping_ratio: 1.0,
            limit_band: 0.1,
            limit_stiffness: 200.0,
            singularity: Singularity::Clamped([0.01, 0.1]),
            gravity_by_device: false,
            priority: Priority::Together,
            repulsion: Repulsion::default(),
            friction_smoothing: 0.05,
        }
    }
}

/// How [`operational_impedance`] bounds the operational inertia `Λ` near singularities (module
/// doc); `ε = [linear (1/kg), angular (1/(kg·m²))]`, each > 0, and `Λ ≤ ε⁻¹`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Singularity {
    /// `Λ = (J M⁻¹ Jᵀ)⁻¹`; a singular task is [`TaskError::Singular`].
    Exact,
    /// `Λ = (J M⁻¹ Jᵀ + ε)⁻¹`.
    Damped([f64; 2]),
    /// The eigenvalues of `ε^{-1/2} J M⁻¹ Jᵀ ε^{-1/2}` clamped from below at 1.
    Clamped([f64; 2]),
}

impl ImpedanceGains {
    /// Checks that every gain is finite and ≥ 0 (the saturations may be infinite) and the
    /// singularity bound, if any, positive.
    pub fn check(&self) -> Result<(), TaskError> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        let checks = [
            ("stiffness", self.stiffness.iter().all(|k| ok(*k))),
            ("damping_ratio", ok(self.damping_ratio)),
            ("max_position_error", self.max_position_error >= 0.0),
            ("max_orientation_error", self.max_orientation_error >= 0.0),
            ("posture_stiffness", ok(self.posture_stiffness)),
            ("posture_damping_ratio", ok(self.posture_damping_ratio)),
            ("limit_band", ok(self.limit_band)),
            ("limit_stiffness", ok(self.limit_stiffness)),
            (
                "friction_smoothing",
                ok(self.friction_smoothing) && self.friction_smoothing > 0.0,
            ),
        ];
        if let Some((gain, _)) = checks.iter().find(|(_, good)| !good) {
            return Err(TaskError::Gain { gain });
        }
        self.repulsion.check()?;
        match self.singularity {
            Singularity::Exact => Ok(()),
            Singularity::Damped(e) | Singularity::Clamped(e) => {
                if e.iter().all(|x| x.is_finite() && *x > 0.0) {
                    Ok(())
                } else {
                    Err(TaskError::Bound)
                }
            }
        }
    }
}

/// Where the tool should be: its pose in the world, and the velocity and acceleration along
/// the way (`[linear; angular]`, world; zero for a set point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaskTarget {
    /// The tool's pose.
    pub pose: PlueckerTransform,
    /// The tool's velocity, m/s and rad/s.
    pub velocity: [f64; 6],
    /// The tool's acceleration, m/s² and rad/s².
    pub acceleration: [f64; 6],
}

impl TaskTarget {
    /// A pose to hold still.
    pub const fn at(pose: PlueckerTransform) -> Self {
        Self {
            pose,
            velocity: [0.0; 6],
            acceleration: [0.0; 6],
        }
    }
}

/// The task's workspace: the Jacobian and the operational quantities of the last call, kept
/// for the caller (e.g. to add forces of its own through `Jᵀ` or to report the task's
/// conditioning). Large for large `N`: box it or keep it in a static.
#[derive(Clone, Debug)]
pub struct TaskData<const N: usize> {
    /// The tool's world Jacobian, rows `[linear; angular]`.
    pub jacobian: Jacobian<N>,
    /// `M⁻¹ Jᵀ` of the task rows (column `r` of the `m` task rows).
    minv_jt: [[f64; N]; 6],
    /// `Λ`, the damped operational inertia of the task rows (leading `m × m` block).
    lambda: [[f64; 6]; 6],
    /// The points near obstacles the next calls repel ([`Self::set_proximities`]).
    proximities: [Proximity; MAX_PROXIMITIES],
    nproximities: usize,
    /// Scratch: a proximity's point Jacobian.
    point_jacobian: Jacobian<N>,
}

impl<const N: usize> Default for TaskData<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> TaskData<N> {
    /// A zeroed workspace.
    pub const fn new() -> Self {
        Self {
            jacobian: [[0.0; N]; 6],
            minv_jt: [[0.0; N]; 6],
            lambda: [[0.0; 6]; 6],
            proximities: [Proximity::at_rest(0, DVec3::ZERO, DVec3::X, f64::INFINITY);
                MAX_PROXIMITIES],
            nproximities: 0,
            point_jacobian: [[0.0; N]; 6],
        }
    }

    /// The robot's points near obstacles that the next calls of [`operational_impedance`]
    /// repel (replacing the last ones; at most [`MAX_PROXIMITIES`], the rest ignored): e.g.
    /// rl-sg's nearest capsule contacts of this cycle. Their bodies' world poses in the `Data`
    /// of the call must be those at its `q` — as the caller's [`crate::algo::forward_position`]
    /// that placed the capsules left them (the law's sweeps move no other body). Refuses
    /// (keeping none) a proximity that is not finite or whose normal is not a unit vector.
    /// Returns how many were kept.
    pub fn set_proximities(&mut self, proximities: &[Proximity]) -> Result<usize, TaskError> {
        self.nproximities = 0;
        let n = proximities.len().min(MAX_PROXIMITIES);
        for p in &proximities[..n] {
            let finite = p.point.is_finite()
                && p.normal.is_finite()
                && p.obstacle_velocity.is_finite()
                && !p.distance.is_nan();
            if !finite || (p.normal.length_squared() - 1.0).abs() > 1e-6 {
                return Err(TaskError::NotFinite {
                    argument: "proximity",
                });
            }
        }
        self.proximities[..n].copy_from_slice(&proximities[..n]);
        self.nproximities = n;
        Ok(n)
    }

    /// The proximities of the next calls.
    pub fn proximities(&self) -> &[Proximity] {
        &self.proximities[..self.nproximities]
    }

    /// The damped operational inertia `Λ` of the last call, `m × m` over the task rows (the
    /// first `m` rows and columns of the result); zeros after a call with two levels
    /// ([`Priority::OrientationFirst`], which bounds each level's instead).
    pub fn operational_inertia(&self) -> &[[f64; 6]; 6] {
        &self.lambda
    }
}

/// How the task stood at the call.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaskReport {
    /// `|p_d − p|`, m (before saturation).
    pub position_error: f64,
    /// The angle of `R_d Rᵀ`, rad (before saturation; 0 when the orientation is free).
    pub orientation_error: f64,
    /// The tool's velocity `J q̇`, `[linear; angular]`, world.
    pub tool_velocity: [f64; 6],
    /// The tool's pose.
    pub tool_pose: PlueckerTransform,
    /// Joints inside their limit band (pushed away by the nullspace).
    pub joints_near_limits: usize,
    /// Task directions whose operational inertia was bounded ([`Singularity::Clamped`]: the
    /// clamped eigenvalues; [`Singularity::Damped`]: all of them).
    pub bounded_directions: usize,
    /// Proximities inside the repulsion's influence distance.
    pub repelling: usize,
    /// The smallest distance among the proximities, m (∞ without).
    pub min_distance: f64,
    /// How much the position's command was faded for the nearest obstacle
    /// ([`Priority::OrientationFirst`]): 0 (none inside the influence distance) to 1 (at the
    /// margin).
    pub yielding: f64,
}

/// Why [`operational_impedance`] gave no torques.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TaskError {
    /// A dynamics algorithm failed (a length, the tool, a singular mass matrix).
    Dynamics(Error),
    /// The model has joints whose position is not their velocity's integral coordinate
    /// (`nq ≠ nv`: a floating base or a spherical joint): the posture error is not defined.
    NotFixedBase {
        /// Position coordinates.
        nq: usize,
        /// Velocity coordinates.
        nv: usize,
    },
    /// `J M⁻¹ Jᵀ + Λ_ε` is not positive definite: the arm is at a singularity of the task and
    /// no damping was given.
    Singular,
    /// A singularity bound `ε` that is not positive.
    Bound,
    /// A gain that is negative or not finite (the saturations may be `f64::INFINITY`).
    Gain {
        /// Which gain.
        gain: &'static str,
    },
    /// A target or state that is not finite.
    NotFinite {
        /// Which argument.
        argument: &'static str,
    },
}

impl From<Error> for TaskError {
    fn from(e: Error) -> Self {
        Self::Dynamics(e)
    }
}

impl fmt::Display for TaskError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Dynamics(e) => e.fmt(f),
            Self::NotFixedBase { nq, nv } => write!(
                f,
                "task-space control needs nq = nv (a fixed base, no quaternion joints); the \
                 model has nq = {nq}, nv = {nv}"
            ),
            Self::Singular => f.write_str(
                "the task's operational inverse inertia J M⁻¹ Jᵀ (bounded as asked) is not \
                 positive definite: the arm is at a singularity and Singularity::Exact was \
                 asked for, or the model's inertias are not physical",
            ),
            Self::Bound => f.write_str("the singularity bound ε must be positive"),
            Self::Gain { gain } => write!(f, "the gain `{gain}` must be finite and ≥ 0"),
            Self::NotFinite { argument } => write!(f, "`{argument}` is not finite"),
        }
    }
}

impl core::error::Error for TaskError {}

/// The operational-space impedance torques (module doc) for tool `tool` at state `(q, q̇)`,
/// toward `target`, with the posture `posture` in the nullspace, into `tau` (`nv`).
#[allow(clippy::too_many_arguments)]
pub fn operational_impedance<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    task: &mut TaskData<N>,
    tool: usize,
    gains: &ImpedanceGains,
    target: &TaskTarget,
    q: &[f64],
    qd: &[f64],
    posture: &[f64],
    tau: &mut [f64],
) -> Result<TaskReport, TaskError> {
    gains.check()?;
    let n = model.nv;
    if model.nq != n {
        return Err(TaskError::NotFixedBase {
            nq: model.nq,
            nv: n,
        });
    }
    check_len("q", q, n)?;
    check_len("qd", qd, n)?;
    check_len("posture", posture, n)?;
    check_len("tau", tau, n)?;
    finite("q", q)?;
    finite("qd", qd)?;
    finite("posture", posture)?;
    finite("target velocity", &target.velocity)?;
    finite("target acceleration", &target.acceleration)?;
    let t = &target.pose;
    if !(t.translation.is_finite() && t.rotation.is_finite()) {
        return Err(TaskError::NotFinite {
            argument: "target pose",
        });
    }

    // The task rows: all six, or the three linear ones.
    let m = match gains.orientation {
        Orientation::Held => 6,
        Orientation::Free => 3,
    };

    // J, the tool's pose and velocity (the proximities' bodies are where the caller's forward
    // sweep at `q` put them: `jacobian` moves only the tool's chain, to the same poses).
    let nprox = task.nproximities;
    jacobian(model, data, q, tool, &mut task.jacobian)?;
    let pose = tool_pose(model, data, tool)?;
    let jac = &task.jacobian;
    let mut xd = [0.0; 6];
    for (r, x) in xd.iter_mut().enumerate() {
        *x = dot(&jac[r][..n], qd);
    }

    // The error, saturated, and the commanded task acceleration a − J̇ q̇.
    let dp = t.translation - pose.translation;
    let mut dq = DQuat::from_mat3(&t.rotation) * DQuat::from_mat3(&pose.rotation).inverse();
    if dq.w < 0.0 {
        dq = -dq;
    }
    let dr = 2.0 * quaternion::log(dq.normalize());
    let position_error = dp.length();
    let orientation_error = if m == 6 { dr.length() } else { 0.0 };
    let e_p = saturate(dp, gains.max_position_error);
    let e_o = saturate(dr, gains.max_orientation_error);
    let e = [e_p.x, e_p.y, e_p.z, e_o.x, e_o.y, e_o.z];
    let jdqd = jacobian_derivative_times_qd(model, data, q, qd, tool)?;
    let mut a = [0.0; 6];
    for r in 0..m {
        let kp = gains.stiffness[r];
        let kd = 2.0 * gains.damping_ratio * libm::sqrt(kp.max(0.0));
        a[r] = target.acceleration[r] + kd * (target.velocity[r] - xd[r]) + kp * e[r] - jdqd[r];
    }

    // C(q, q̇) + G(q) (less G for a device that adds it), before the sweeps below reuse `data`.
    let mut bias = [0.0; N];
    if gains.gravity_by_device {
        bias[..n].copy_from_slice(coriolis(model, data, q, qd)?);
    } else {
        bias[..n].copy_from_slice(nonlinear_effects(model, data, q, qd)?);
    }

    // M, its factors, M⁻¹ Jᵀ (m solves) and Ψ = J M⁻¹ Jᵀ.
    crba(model, data, q)?;
    factor_mass_matrix(model, data)?;
    let mut psi = [[0.0; 6]; 6];
    for r in 0..m {
        let x = &mut task.minv_jt[r];
        x[..n].copy_from_slice(&jac[r][..n]);
        solve_mass_matrix(model, data, &mut x[..n])?;
    }
    for r in 0..m {
        for c in 0..=r {
            let v = dot(&jac[r][..n], &task.minv_jt[c][..n]);
            psi[r][c] = v;
            psi[c][r] = v;
        }
    }
    let eps_lin = match gains.singularity {
        Singularity::Exact => 0.0,
        Singularity::Damped(e) | Singularity::Clamped(e) => e[0],
    };
    let levels = gains.priority == Priority::OrientationFirst && m == 6;
    // One level: Λ of the whole task (its nullspace is the posture's and the repulsion's). Two
    // levels: Λ₁ and Λ₂ below, whose nullspaces chained are the posture's.
    let mut bounded_directions = 0;
    if levels {
        task.lambda = [[0.0; 6]; 6];
    } else {
        bounded_directions = operational_inertia(&psi, m, 0, gains.singularity, &mut task.lambda)?;
    }
    let minv_jt = &task.minv_jt;
    let lambda = &task.lambda;
    // How far the position yields to the nearest obstacle (two levels only): its command fades
    // from whole at the repulsion's influence distance to none at the margin.
    let yielding = if levels {
        task.proximities[..nprox]
            .iter()
            .map(|p| gains.repulsion.activation(p.distance))
            .fold(0.0, f64::max)
    } else {
        0.0
    };

    // The task torque, and the operational inertias of the two levels.
    let mut first = [[0.0; 6]; 6];
    let mut second = [[0.0; 6]; 6];
    if levels {
        // Level 1, the orientation (rows 3..6): τ₁ = J_aᵀ Λ₁ a_a.
        let block = |r0: usize, c0: usize| {
            let mut b = [[0.0; 6]; 6];
            for r in 0..3 {
                for c in 0..3 {
                    b[r][c] = psi[r0 + r][c0 + c];
                }
            }
            b
        };
        bounded_directions =
            operational_inertia(&block(3, 3), 3, 3, gains.singularity, &mut first)?;
        let y = mat_vec(&first, 3, &a[3..6]);
        for (k, t) in tau[..n].iter_mut().enumerate() {
            *t = (0..3).map(|r| jac[3 + r][k] * y[r]).sum();
        }
        // Level 2, the position in level 1's nullspace: F₂ = Λ₂ (a_l − Ψ_la Λ₁ a_a) with
        // Λ₂⁻¹ = Ψ_ll − Ψ_la Λ₁ Ψ_al, τ₂ = N₁ᵀ J_lᵀ F₂.
        let psi_la = block(0, 3);
        let mut s = block(0, 0);
        let mut want = [0.0; 3];
        for r in 0..3 {
            let row_l1: [f64; 3] =
                core::array::from_fn(|c| (0..3).map(|k| psi_la[r][k] * first[k][c]).sum());
            for c in 0..3 {
                s[r][c] -= (0..3).map(|k| row_l1[k] * psi_la[c][k]).sum::<f64>();
            }
            // The command (`a + J̇ q̇`) fades; the J̇ q̇ compensation stays.
            want[r] = a[r]
                - yielding * (a[r] + jdqd[r])
                - (0..3).map(|k| psi_la[r][k] * y[k]).sum::<f64>();
        }
        bounded_directions += operational_inertia(&s, 3, 0, gains.singularity, &mut second)?;
        let f2 = mat_vec(&second, 3, &want);
        let mut v = [0.0; N];
        for (k, x) in v[..n].iter_mut().enumerate() {
            *x = (0..3).map(|r| jac[r][k] * f2[r]).sum();
        }
        project_rows(&mut v[..n], jac, minv_jt, &first, 3, 3);
        for (t, x) in tau[..n].iter_mut().zip(&v[..n]) {
            *t += x;
        }
    } else {
        // One level: τ = Jᵀ Λ (a − J̇ q̇).
        let f = mat_vec(lambda, m, &a[..m]);
        for (k, t) in tau[..n].iter_mut().enumerate() {
            *t = (0..m).map(|r| jac[r][k] * f[r]).sum();
        }
    }

    // The repulsion, in the nullspace of what must not yield: the orientation (two levels) or
    // the whole task (one).
    let mut repelling = 0;
    let mut min_distance = f64::INFINITY;
    if nprox > 0 {
        let mut rep = [0.0; N];
        repelling = add_repulsion(
            model,
            data,
            &gains.repulsion,
            eps_lin,
            &task.proximities[..nprox],
            qd,
            &mut task.point_jacobian,
            &mut rep[..n],
        )?;
        min_distance = task.proximities[..nprox]
            .iter()
            .map(|p| p.distance)
            .fold(f64::INFINITY, f64::min);
        let jac = &task.jacobian;
        if levels {
            project_rows(&mut rep[..n], jac, &task.minv_jt, &first, 3, 3);
        } else {
            project(&mut rep[..n], jac, &task.minv_jt, &task.lambda, m);
        }
        for (t, x) in tau[..n].iter_mut().zip(&rep[..n]) {
            *t += x;
        }
    }
    let jac = &task.jacobian;
    let lambda = &task.lambda;

    // The posture in the nullspace of the whole task: τ₀ = M a₀, Nᵀ τ₀ = τ₀ − Jᵀ Λ (M⁻¹ Jᵀ)ᵀ τ₀.
    let kq = gains.posture_stiffness.max(0.0);
    let dq_gain = 2.0 * gains.posture_damping_ratio * libm::sqrt(kq);
    let mut a0 = [0.0; N];
    let mut near = 0;
    for k in 0..n {
        a0[k] = kq * (posture[k] - q[k]) - dq_gain * qd[k];
        let l = model.limits(k);
        if gains.limit_band > 0.0 && l.is_bounded() && !l.wraparound {
            let below = gains.limit_band - (q[k] - l.lower);
            let above = gains.limit_band - (l.upper - q[k]);
            if below > 0.0 {
                a0[k] += gains.limit_stiffness * below;
                near += 1;
            } else if above > 0.0 {
                a0[k] -= gains.limit_stiffness * above;
                near += 1;
            }
        }
    }
    let mut tau0 = [0.0; N];
    for r in 0..n {
        tau0[r] = (0..n).map(|c| data.mass_matrix(r, c) * a0[c]).sum();
    }
    if levels {
        // N₁ᵀ then level 2's: z = N₁ᵀ τ₀, z − N₁ᵀ J_lᵀ Λ₂ (M⁻¹ J_lᵀ)ᵀ z (J_l N₁ M⁻¹ = J_l M⁻¹ N₁ᵀ).
        project_rows(&mut tau0[..n], jac, &task.minv_jt, &first, 3, 3);
        let mut y = [0.0; 3];
        for (r, x) in y.iter_mut().enumerate() {
            *x = dot(&task.minv_jt[r][..n], &tau0[..n]);
        }
        let z = mat_vec(&second, 3, &y);
        let mut v = [0.0; N];
        for (k, x) in v[..n].iter_mut().enumerate() {
            *x = (0..3).map(|r| jac[r][k] * z[r]).sum();
        }
        project_rows(&mut v[..n], jac, &task.minv_jt, &first, 3, 3);
        for (t, x) in tau0[..n].iter_mut().zip(&v[..n]) {
            *t -= x;
        }
    } else {
        project(&mut tau0[..n], jac, &task.minv_jt, lambda, m);
    }
    for k in 0..n {
        tau[k] += tau0[k] + bias[k];
    }
    model.friction_torque(qd, gains.friction_smoothing, &mut tau[..n]);

    let mut tool_velocity = [0.0; 6];
    tool_velocity.copy_from_slice(&xd);
    Ok(TaskReport {
        position_error,
        orientation_error,
        tool_velocity,
        tool_pose: pose,
        joints_near_limits: near,
        bounded_directions,
        repelling,
        min_distance,
        yielding,
    })
}

/// `v ← Nᵀ v = v − Jᵀ Λ (M⁻¹ Jᵀ)ᵀ v` over the task rows `0..m` (`Λ`: `m × m`).
fn project<const N: usize>(
    v: &mut [f64],
    jac: &Jacobian<N>,
    minv_jt: &[[f64; N]; 6],
    lambda: &[[f64; 6]; 6],
    m: usize,
) {
    project_rows(v, jac, minv_jt, lambda, 0, m);
}

/// [`project`] over the task rows `r0..r0 + m`.
fn project_rows<const N: usize>(
    v: &mut [f64],
    jac: &Jacobian<N>,
    minv_jt: &[[f64; N]; 6],
    lambda: &[[f64; 6]; 6],
    r0: usize,
    m: usize,
) {
    let n = v.len();
    let mut y = [0.0; 6];
    for r in 0..m {
        y[r] = dot(&minv_jt[r0 + r][..n], v);
    }
    let z = mat_vec(lambda, m, &y[..m]);
    for (k, x) in v.iter_mut().enumerate() {
        *x -= (0..m).map(|r| jac[r0 + r][k] * z[r]).sum::<f64>();
    }
}

/// The leading `m × m` block of `a` times `x` (`m` long).
fn mat_vec(a: &[[f64; 6]; 6], m: usize, x: &[f64]) -> [f64; 6] {
    let mut y = [0.0; 6];
    for r in 0..m {
        y[r] = (0..m).map(|c| a[r][c] * x[c]).sum();
    }
    y
}

/// `Λ` from `Λ⁻¹` (`m × m`) as `singularity` says; returns the directions it bounded. Row `r`
/// of the block is task row `r0 + r` (rows 0..3 linear, 3..6 angular: their bound `ε`).
fn operational_inertia(
    lambda_inv: &[[f64; 6]; 6],
    m: usize,
    r0: usize,
    singularity: Singularity,
    lambda: &mut [[f64; 6]; 6],
) -> Result<usize, TaskError> {
    let eps = match singularity {
        Singularity::Exact => [0.0; 2],
        Singularity::Damped(e) | Singularity::Clamped(e) => {
            if !(e[0] > 0.0 && e[1] > 0.0 && e[0].is_finite() && e[1].is_finite()) {
                return Err(TaskError::Bound);
            }
            e
        }
    };
    match singularity {
        Singularity::Exact => {
            if !invert_spd(lambda_inv, m, lambda) {
                return Err(TaskError::Singular);
            }
            Ok(0)
        }
        Singularity::Damped(_) => {
            let mut a = *lambda_inv;
            for r in 0..m {
                a[r][r] += eps[(r0 + r) / 3];
            }
            if !invert_spd(&a, m, lambda) {
                return Err(TaskError::Singular);
            }
            Ok(m)
        }
        Singularity::Clamped(_) => {
            // W = ε^{-1/2}; A = W Λ⁻¹ W = V diag(σ) Vᵀ; Λ = W V diag(1/max(σ, 1)) Vᵀ W.
            let w = |r: usize| 1.0 / libm::sqrt(eps[(r0 + r) / 3]);
            let mut a = [[0.0; 6]; 6];
            for r in 0..m {
                for c in 0..m {
                    a[r][c] = w(r) * lambda_inv[r][c] * w(c);
                }
            }
            // Away from singularities every σ > 1: A − I is positive definite (one Cholesky
            // tells), and Λ = W A⁻¹ W without the eigen-decomposition.
            let mut shifted = a;
            for (k, row) in shifted.iter_mut().enumerate().take(m) {
                row[k] -= 1.0;
            }
            let mut inv_a = [[0.0; 6]; 6];
            if invert_spd(&shifted, m, &mut inv_a) && invert_spd(&a, m, &mut inv_a) {
                for r in 0..m {
                    for c in 0..m {
                        lambda[r][c] = w(r) * inv_a[r][c] * w(c);
                    }
                }
                return Ok(0);
            }
            let (mut sigma, mut v) = ([0.0; 6], [[0.0; 6]; 6]);
            symmetric_eigen(&a, m, &mut sigma, &mut v);
            let mut clamped = 0;
            let mut inv = [0.0; 6];
            for k in 0..m {
                if !sigma[k].is_finite() {
                    return Err(TaskError::Singular);
                }
                if sigma[k] < 1.0 {
                    clamped += 1;
                }
                inv[k] = 1.0 / sigma[k].max(1.0);
            }
            for r in 0..m {
                for c in 0..m {
                    let x: f64 = (0..m).map(|k| v[r][k] * inv[k] * v[c][k]).sum();
                    lambda[r][c] = w(r) * x * w(c);
                }
            }
            Ok(clamped)
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `v` shortened to at most `max` long (direction kept).
fn saturate(v: DVec3, max: f64) -> DVec3 {
    let l = v.length();
    if l > max && l > 0.0 { v * (max / l) } else { v }
}

fn finite(argument: &'static str, x: &[f64]) -> Result<(), TaskError> {
    if x.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(TaskError::NotFinite { argument })
    }
}
