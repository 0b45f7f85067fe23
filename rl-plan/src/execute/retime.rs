//! A trajectory retimed along its own path by TOPP-RA: `q(t) = p(s(t))`, where `p` is the
//! trajectory's position as a function of its own time and `s(t)` the time-optimal timing of
//! that path under joint velocity and acceleration limits ([`topp_ra`]).
//!
//! The retimed motion visits exactly the configurations of the original (the same geometric
//! path, another timing), so whatever was certified about them (collision-free at a checked
//! resolution) holds for it. Its duration is the least any timing of that path can have within
//! the velocity and acceleration limits, to the grid's second-order error: a lower bound for a
//! jerk-limited execution of the same geometry. Its jerk is not bounded (`s̈` is constant per
//! stage and steps between stages), so it is a measure, not yet a trajectory for the loop.
//!
//! With `p' = dp/dτ` and `p''` from the trajectory's exact derivatives on a grid uniform in its
//! own time `τ`: `q̇ = p'·ṡ`, `q̈ = p'·s̈ + p''·ṡ²`. Cost: one TOPP-RA of `stages` stages.

use rl_core::traj::Trajectory;

use super::ExecutionLimits;
use super::topp::{Parameterization, ToppProblem, topp_ra};
use crate::error::PlanError;

/// `path` retimed: its timing and the path itself.
#[derive(Clone, Debug)]
pub struct Retimed<'a, T> {
    path: &'a T,
    nq: usize,
    timing: Parameterization,
}

/// Retimes `path` (its first `limits.velocity.len()` axes are joints) on `stages` stages of
/// equal path time.
pub fn time_optimal<'a, const D: usize, T: Trajectory<D>>(
    path: &'a T,
    limits: &ExecutionLimits,
    stages: usize,
) -> Result<Retimed<'a, T>, PlanError> {
    let nq = limits.velocity.len();
    if nq > D || stages == 0 {
        return Err(PlanError::setting(
            "retiming",
            format!("{nq} joints of {D} axes, {stages} stages"),
        ));
    }
    let duration = path.duration();
    let grid: Vec<f64> = (0..=stages)
        .map(|i| duration * i as f64 / stages as f64)
        .collect();
    let mut dq = Vec::with_capacity(grid.len() * nq);
    let mut ddq = Vec::with_capacity(grid.len() * nq);
    for &tau in &grid {
        dq.extend_from_slice(&path.derivative(tau, 1)[..nq]);
        ddq.extend_from_slice(&path.derivative(tau, 2)[..nq]);
    }
    let timing = topp_ra(&ToppProblem::rest_to_rest(&grid, &dq, &ddq, limits, &[]))?;
    Ok(Retimed { path, nq, timing })
}

impl<T> Retimed<'_, T> {
    /// The time-optimal duration.
    pub fn duration(&self) -> f64 {
        self.timing.duration()
    }

    /// The timing of the path's own time.
    pub fn timing(&self) -> &Parameterization {
        &self.timing
    }
}

impl<T> Retimed<'_, T> {
    /// Position, velocity and acceleration of the joints at `t`.
    pub fn sample<const D: usize>(&self, t: f64) -> ([f64; D], [f64; D], [f64; D])
    where
        T: Trajectory<D>,
    {
        let (s, sd, sdd) = self.timing.eval(t);
        let q = self.path.derivative(s, 0);
        let d1 = self.path.derivative(s, 1);
        let d2 = self.path.derivative(s, 2);
        let mut v = [0.0; D];
        let mut a = [0.0; D];
        for k in 0..self.nq {
            v[k] = d1[k] * sd;
            a[k] = d1[k] * sdd + d2[k] * sd * sd;
        }
        (q, v, a)
    }
}
