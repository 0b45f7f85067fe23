//! Distance-based repulsion from obstacles, as joint torques for a task-space law.
//!
//! Each [`Proximity`] is a point of the robot near an obstacle: the body it moves with, where it
//! is, the unit normal pointing from the obstacle to the robot, and the signed distance `d`
//! (from a distance kernel such as rl-sg's capsules). Along the normal the distance is a
//! one-dimensional task, `ḋ = J_n q̇ − n·v_obs` with `J_n = nᵀ J_p` (`J_p`: the point's linear
//! Jacobian, [`crate::algo::point_jacobian`]), and the repulsion commands it an acceleration
//! that grows without bound toward the margin and vanishes at the influence distance (Khatib's
//! potential field, *Real-time obstacle avoidance for manipulators and mobile robots*, IJRR
//! 5(1), 1986, with a damping of the approach only):
//!
//! ```text
//! s  = clamp((d_i − d) / (d_i − d_m), 0, 1)
//! a  = min(k_b (1 / max(d − d_m, 1 mm) − 1 / (d_i − d_m)) + s D max(−ḋ, 0), a_max)   (d < d_i)
//! τ  = Σ J_nᵀ Λ_n a,    Λ_n = 1 / max(J_n M⁻¹ J_nᵀ, ε_lin)
//! ```
//!
//! `Λ_n` makes `a` an acceleration whatever the arm's inertia at that point (bounded by the
//! task's linear singularity bound where the point cannot move along `n`). The repulsion is
//! continuous in the distance (zero, with a zero rate term, at `d_i`), so a passing obstacle
//! raises no torque step. [`super::operational_impedance`] projects the sum into the nullspace
//! of the tasks that must not yield ([`super::Priority`]).
//!
//! `d_i`: influence distance, m; `d_m`: margin, m; `k_b`: m³/s² ÷ m = m²/s²; `D`: 1/s;
//! `a_max`: m/s². Cost per proximity: one point Jacobian (O(depth)), one mass-matrix solve.

use glam::DVec3;

use crate::algo::{Jacobian, point_jacobian, solve_mass_matrix};
use crate::model::{Data, Model};

use super::TaskError;

/// The most proximities a [`super::TaskData`] holds.
pub const MAX_PROXIMITIES: usize = 8;

/// A point of the robot near an obstacle (world frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proximity {
    /// The rl-core body the point moves with.
    pub body: usize,
    /// The point of the robot closest to the obstacle, m.
    pub point: DVec3,
    /// Unit normal from the obstacle to the robot (the direction that increases the distance).
    pub normal: DVec3,
    /// Signed distance, m (negative: overlap).
    pub distance: f64,
    /// The obstacle's velocity at its closest point, m/s.
    pub obstacle_velocity: DVec3,
}

impl Proximity {
    /// A proximity to an obstacle at rest.
    pub const fn at_rest(body: usize, point: DVec3, normal: DVec3, distance: f64) -> Self {
        Self {
            body,
            point,
            normal,
            distance,
            obstacle_velocity: DVec3::ZERO,
        }
    }
}

/// The repulsion's gains (module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Repulsion {
    /// Influence distance `d_i`, m: no repulsion beyond it.
    pub influence: f64,
    /// Margin `d_m`, m: the distance the repulsion keeps (its acceleration is unbounded there
    /// but for `max_acceleration`).
    pub margin: f64,
    /// Barrier gain `k_b`, m²/s².
    pub stiffness: f64,
    /// Damping `D` of the approach, 1/s.
    pub damping: f64,
    /// The largest repulsive acceleration, m/s².
    pub max_acceleration: f64,
}

impl Default for Repulsion {
    /// Influence 0.2 m, margin 0.05 m, `k_b` 1 m²/s² (3.3 m/s² at 15 cm, 13 m/s² at 10 cm, the cap from 6.6 cm),
    /// `D` 20 1/s, at most 50 m/s².
    fn default() -> Self {
        Self {
            influence: 0.2,
            margin: 0.05,
            stiffness: 1.0,
            damping: 20.0,
            max_acceleration: 50.0,
        }
    }
}

impl Repulsion {
    /// Checks that every gain is finite and ≥ 0 and the influence beyond the margin.
    pub fn check(&self) -> Result<(), TaskError> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        let checks = [
            ("repulsion.margin", ok(self.margin)),
            (
                "repulsion.influence",
                ok(self.influence) && self.influence > self.margin,
            ),
            ("repulsion.stiffness", ok(self.stiffness)),
            ("repulsion.damping", ok(self.damping)),
            ("repulsion.max_acceleration", ok(self.max_acceleration)),
        ];
        match checks.iter().find(|(_, good)| !good) {
            Some((gain, _)) => Err(TaskError::Gain { gain }),
            None => Ok(()),
        }
    }

    /// How far inside the influence distance `d` is: `clamp((d_i − d)/(d_i − d_m), 0, 1)`.
    pub fn activation(&self, d: f64) -> f64 {
        let a = ((self.influence - d) / (self.influence - self.margin)).clamp(0.0, 1.0);
        if a.is_nan() { 1.0 } else { a }
    }

    /// The commanded acceleration along the normal at distance `d` (m) approached at `rate`
    /// (`ḋ`, m/s; negative when approaching); 0 beyond the influence distance.
    pub fn acceleration(&self, d: f64, rate: f64) -> f64 {
        if d >= self.influence {
            return 0.0;
        }
        let span = self.influence - self.margin;
        let s = self.activation(d);
        let barrier = self.stiffness * (1.0 / (d - self.margin).max(1e-3) - 1.0 / span);
        (barrier + s * self.damping * (-rate).max(0.0)).min(self.max_acceleration)
    }
}

/// Adds the repulsion torques of `proximities` to `tau` (`nv`), from the world poses and the
/// factored mass matrix in `data`; `jac` is scratch. Returns how many proximities repel (are
/// inside the influence distance).
#[allow(clippy::too_many_arguments)]
pub(crate) fn add_repulsion<const N: usize>(
    model: &Model<N>,
    data: &mut Data<N>,
    gains: &Repulsion,
    eps_lin: f64,
    proximities: &[Proximity],
    qd: &[f64],
    jac: &mut Jacobian<N>,
    tau: &mut [f64],
) -> Result<usize, TaskError> {
    let n = model.nv;
    let mut active = 0;
    for p in proximities {
        if p.distance >= gains.influence {
            continue;
        }
        point_jacobian(model, data, p.body, p.point, jac)?;
        let mut jn = [0.0; N];
        for (k, x) in jn[..n].iter_mut().enumerate() {
            *x = p.normal.x * jac[0][k] + p.normal.y * jac[1][k] + p.normal.z * jac[2][k];
        }
        let rate = dot(&jn[..n], qd) - p.normal.dot(p.obstacle_velocity);
        let a = gains.acceleration(p.distance, rate);
        let mut minv_jn = jn;
        solve_mass_matrix(model, data, &mut minv_jn[..n])?;
        let w = dot(&jn[..n], &minv_jn[..n]);
        let f = a / w.max(eps_lin);
        for (t, j) in tau[..n].iter_mut().zip(&jn[..n]) {
            *t += j * f;
        }
        active += 1;
    }
    Ok(active)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
