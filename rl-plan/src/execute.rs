//! From a planned path to motion: a time-parameterised trajectory that follows the path's
//! straight segments exactly, within per-joint velocity, acceleration and jerk limits, built
//! from rl-core's jerk-limited profile ([`rl_core::traj::JerkLimited`], Biagiotti & Melchiorri
//! §3.4).
//!
//! The path was checked along its straight segments, so the robot must stay on them: a
//! trajectory that synchronises independently optimal joint profiles leaves the segment
//! between the waypoints. Here each segment `a → b` (difference `d = b ⊖ a`, circles the short
//! way) is one rest-to-rest move in which every joint `k` gets the limits `|d_k| · (v_s, a_s,
//! j_s)` with `v_s = min_k v_k / |d_k|` (and alike for acceleration and jerk): every joint then
//! has the same normalised profile `s(t) ∈ [0, 1]`, so `q(t) = a + s(t)·d` lies on the segment at
//! every instant, and no joint exceeds its own limits. The robot stops at every waypoint
//! (optimised paths have few). [`blend`] is the execution that does not stop at interior
//! waypoints (lines and jerk-continuous blends, checked for collisions where they leave the
//! path).
//!
//! Circle coordinates are unwrapped along the path (the trajectory is continuous; positions
//! may leave `[−π, π)`), which is what a joint controller wants.
//!
//! For `rl run --plan`: [`Execution::trajectory`] returns the `Piecewise<JerkLimited<8>, 33>`
//! that the controller's plan type holds (`MAX_JOINTS = 8`, `MAX_WAYPOINTS + 1 = 33`
//! segments) and [`Execution::waypoints`] the unwrapped waypoints.

use rl_core::Model;
use rl_core::traj::{JerkLimited, Limits, Piecewise, Segment};

use crate::error::PlanError;
use crate::path::Path;
use crate::space::JointSpace;

pub mod blend;
pub mod jerk;
pub mod retime;
pub mod topp;

pub use blend::{BlendOptions, BlendReport, Blended, StopReason, WaypointOutcome};
pub use jerk::{JerkRetimed, jerk_limited, rests_of};
pub use retime::{Retimed, time_optimal};
pub use topp::{Discretization, Parameterization, ToppProblem, topp_ra};

/// Time to reach the speed limit at the acceleration limit, s (the controller's convention:
/// `a = v / 0.5 s`, `j = a / 0.15 s`).
pub const ACCEL_TIME_S: f64 = 0.5;
/// Time to reach the acceleration limit at the jerk limit, s.
pub const JERK_TIME_S: f64 = 0.15;
/// Speed assumed for a joint the model gives no speed limit, rad/s or m/s.
pub const UNKNOWN_SPEED: f64 = 0.5;

/// Per-joint limits of the trajectory.
#[derive(Clone, Debug, PartialEq)]
pub struct ExecutionLimits {
    /// Speed limit per coordinate.
    pub velocity: Vec<f64>,
    /// Acceleration limit per coordinate.
    pub acceleration: Vec<f64>,
    /// Jerk limit per coordinate.
    pub jerk: Vec<f64>,
}

impl ExecutionLimits {
    /// From the model's speed limits scaled by `fraction ∈ (0, 1]`; acceleration and jerk
    /// follow [`ACCEL_TIME_S`] and [`JERK_TIME_S`] (rl-core models carry speed limits only).
    pub fn from_model<const N: usize>(model: &Model<N>, fraction: f64) -> Result<Self, PlanError> {
        if !(fraction > 0.0 && fraction <= 1.0) {
            return Err(PlanError::setting(
                "speed fraction",
                format!("{fraction} is not in (0, 1]"),
            ));
        }
        if model.nq() != model.dof() {
            return Err(PlanError::Unsupported(
                "trajectories for joints of several coordinates (spherical, free)".into(),
            ));
        }
        let velocity: Vec<f64> = (0..model.dof())
            .map(|k| {
                let v = model.limits(k).velocity;
                fraction
                    * if v.is_finite() && v > 0.0 {
                        v
                    } else {
                        UNKNOWN_SPEED
                    }
            })
            .collect();
        let acceleration: Vec<f64> = velocity.iter().map(|v| v / ACCEL_TIME_S).collect();
        let jerk = acceleration.iter().map(|a| a / JERK_TIME_S).collect();
        Ok(Self {
            velocity,
            acceleration,
            jerk,
        })
    }
}

/// A path prepared for execution.
#[derive(Clone, Debug, PartialEq)]
pub struct Execution {
    /// The waypoints, circles unwrapped along the path.
    waypoints: Vec<Vec<f64>>,
    limits: ExecutionLimits,
}

impl Execution {
    /// Prepares `path` (configurations of `space`, one number per joint) for execution within
    /// `limits`.
    pub fn new(
        space: &JointSpace,
        path: &Path,
        limits: ExecutionLimits,
    ) -> Result<Self, PlanError> {
        if !space.is_vector() {
            return Err(PlanError::Unsupported(
                "trajectories for joints of several coordinates (spherical, free)".into(),
            ));
        }
        let n = space.nq();
        for (what, v) in [
            ("velocity", &limits.velocity),
            ("acceleration", &limits.acceleration),
            ("jerk", &limits.jerk),
        ] {
            if v.len() != n || !v.iter().all(|x| x.is_finite() && *x > 0.0) {
                return Err(PlanError::setting(
                    format!("{what} limits"),
                    format!("need {n} positive finite values, got {v:?}"),
                ));
            }
        }
        if path.len() < 2 {
            return Err(PlanError::setting("path", "needs at least two waypoints"));
        }
        let mut waypoints = vec![path.point(0).to_vec()];
        let mut d = vec![0.0; n];
        for i in 1..path.len() {
            space.difference(path.point(i - 1), path.point(i), &mut d);
            let prev = waypoints.last().expect("non-empty");
            let next: Vec<f64> = prev.iter().zip(&d).map(|(a, d)| a + d).collect();
            waypoints.push(next);
        }
        Ok(Self { waypoints, limits })
    }

    /// The waypoints (unwrapped).
    pub fn waypoints(&self) -> &[Vec<f64>] {
        &self.waypoints
    }

    /// The limits it is timed within.
    pub fn limits(&self) -> &ExecutionLimits {
        &self.limits
    }

    /// [`Execution::trajectory`] as [`Segment`]s, the type the blended execution
    /// ([`Execution::blended`]) returns, so a controller can hold either.
    pub fn stop_at_waypoints<const D: usize, const MAX: usize>(
        &self,
    ) -> Result<Piecewise<Segment<D>, MAX>, PlanError> {
        let moves = self.trajectory::<D, MAX>()?;
        let mut out = Piecewise::new();
        for m in moves.segments() {
            out.push(Segment::JerkLimited(*m))
                .map_err(|e| PlanError::setting("trajectory", e.to_string()))?;
        }
        Ok(out)
    }

    /// The trajectory of `D ≥ nq` axes (unused axes stay at 0) and at most `MAX` segments: one
    /// synchronised jerk-limited move per path segment (see the module docs). Segments of zero
    /// length are skipped.
    pub fn trajectory<const D: usize, const MAX: usize>(
        &self,
    ) -> Result<Piecewise<JerkLimited<D>, MAX>, PlanError> {
        let n = self.limits.velocity.len();
        if n > D {
            return Err(PlanError::Unsupported(format!(
                "{n} joints in a trajectory of {D} axes"
            )));
        }
        let mut out = Piecewise::new();
        for w in self.waypoints.windows(2) {
            let Some(segment) = synchronized_move::<D>(&w[0], &w[1], &self.limits)? else {
                continue;
            };
            out.push(segment).map_err(|_| {
                PlanError::Unsupported(format!(
                    "a path of more than {MAX} segments in this trajectory (simplify it first)"
                ))
            })?;
        }
        Ok(out)
    }
}

/// The synchronised rest-to-rest move from `a` to `b` (every joint on the same normalised
/// profile, see the module docs), `None` when they are equal.
pub(crate) fn synchronized_move<const D: usize>(
    a: &[f64],
    b: &[f64],
    limits: &ExecutionLimits,
) -> Result<Option<JerkLimited<D>>, PlanError> {
    let n = limits.velocity.len();
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| y - x).collect();
    if d.iter().all(|x| *x == 0.0) {
        return Ok(None);
    }
    let scale = |lim: &[f64]| {
        d.iter()
            .zip(lim)
            .filter(|(d, _)| **d != 0.0)
            .map(|(d, l)| l / d.abs())
            .fold(f64::INFINITY, f64::min)
    };
    let (vs, as_, js) = (
        scale(&limits.velocity),
        scale(&limits.acceleration),
        scale(&limits.jerk),
    );
    let mut segment_limits = Limits::<D>::uniform(vs, as_, js);
    let (mut start, mut goal) = ([0.0; D], [0.0; D]);
    for k in 0..n {
        start[k] = a[k];
        goal[k] = b[k];
        if d[k] != 0.0 {
            segment_limits.velocity[k] = vs * d[k].abs();
            segment_limits.acceleration[k] = as_ * d[k].abs();
            segment_limits.jerk[k] = js * d[k].abs();
        }
    }
    JerkLimited::new(start, goal, &segment_limits)
        .map(Some)
        .map_err(|e| PlanError::setting("trajectory", e.to_string()))
}

/// A plan ready for a controller: what the planner found, the waypoints it will pass
/// (unwrapped), and the trajectory through them.
#[derive(Clone, Debug)]
pub struct Executable<const D: usize, const MAX: usize> {
    /// The planner's report (times, counts, lengths, paths).
    pub result: crate::solve::PlanResult,
    /// The optimised path's waypoints, circles unwrapped (start first).
    pub waypoints: Vec<Vec<f64>>,
    /// The jerk-limited trajectory along them.
    pub trajectory: Piecewise<JerkLimited<D>, MAX>,
}

/// Plans from `start` to `goal` with `validity` and turns the optimised path into a trajectory
/// within `limits`: what `rl run --plan` needs (`D = 8`, `MAX = 33` for the controller's
/// `PlanTrajectory`). Not solving within the budget is an error
/// ([`PlanError::Setting`] naming `plan`).
pub fn plan_executable<const D: usize, const MAX: usize>(
    space: &JointSpace,
    validity: &mut dyn crate::validity::Validity,
    start: &[f64],
    goal: &[f64],
    options: &crate::solve::PlanOptions,
    limits: ExecutionLimits,
) -> Result<Executable<D, MAX>, PlanError> {
    let result = crate::solve::plan(space, validity, start, goal, options)?;
    let Some(path) = result.optimized.as_ref() else {
        return Err(PlanError::setting(
            "plan",
            format!("no path found within {:?}", options.time),
        ));
    };
    let ex = Execution::new(space, path, limits)?;
    let trajectory = ex.trajectory::<D, MAX>()?;
    Ok(Executable {
        waypoints: ex.waypoints,
        trajectory,
        result,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::space::Topology;
    use rl_core::traj::Trajectory;

    #[test]
    fn follows_the_segments_within_the_limits() {
        let space = JointSpace::new(vec![
            (
                "a".into(),
                Topology::Interval {
                    lower: -3.0,
                    upper: 3.0,
                },
            ),
            ("b".into(), Topology::Circle),
            (
                "c".into(),
                Topology::Interval {
                    lower: -3.0,
                    upper: 3.0,
                },
            ),
        ])
        .unwrap();
        // The second segment crosses ±π on the circle (3.0 → −3.0 is 0.28 rad the short way).
        let path = Path::from_points(
            3,
            &[
                vec![0.0, 2.0, 0.0],
                vec![1.0, 3.0, -0.5],
                vec![1.2, -3.0, 0.5],
            ],
        );
        let limits = ExecutionLimits {
            velocity: vec![1.0, 2.0, 0.5],
            acceleration: vec![2.0, 4.0, 1.0],
            jerk: vec![10.0, 20.0, 5.0],
        };
        let ex = Execution::new(&space, &path, limits.clone()).unwrap();
        assert!((ex.waypoints()[2][1] - (3.0 + (2.0 * std::f64::consts::PI - 6.0))).abs() < 1e-12);
        let tr = ex.trajectory::<8, 4>().unwrap();
        assert_eq!(tr.len(), 2);
        let mut t = 0.0;
        let (mut peak_v, mut peak_a) = ([0.0f64; 3], [0.0f64; 3]);
        while t <= tr.duration() {
            let s = tr.sample(t);
            // On the segment: q − a is parallel to b − a.
            let seg = if t < tr.starts()[1] { 0 } else { 1 };
            let (a, b) = (&ex.waypoints()[seg], &ex.waypoints()[seg + 1]);
            let u: Vec<f64> = (0..3).map(|k| b[k] - a[k]).collect();
            let v: Vec<f64> = (0..3).map(|k| s.position[k] - a[k]).collect();
            let lam = v.iter().zip(&u).map(|(x, y)| x * y).sum::<f64>()
                / u.iter().map(|x| x * x).sum::<f64>();
            for k in 0..3 {
                assert!((v[k] - lam * u[k]).abs() < 1e-9, "off the segment at t={t}");
                peak_v[k] = peak_v[k].max(s.velocity[k].abs());
                peak_a[k] = peak_a[k].max(s.acceleration[k].abs());
            }
            assert_eq!(s.position[5], 0.0);
            t += 1e-3;
        }
        for k in 0..3 {
            assert!(
                peak_v[k] <= limits.velocity[k] * (1.0 + 1e-9),
                "{k}: {}",
                peak_v[k]
            );
            assert!(peak_a[k] <= limits.acceleration[k] * (1.0 + 1e-9));
        }
        // Some joint reaches its limit: the move is as fast as the limits allow.
        assert!(
            (0..3).any(|k| peak_v[k] > 0.99 * limits.velocity[k]
                || peak_a[k] > 0.99 * limits.acceleration[k])
        );
        let end = tr.sample(tr.duration()).position;
        assert!((end[0] - 1.2).abs() < 1e-12 && (end[2] - 0.5).abs() < 1e-12);
    }
}
