//! What to move through, how fast, and the check against the model's limits before moving.
//!
//! A [`Plan`] goes from the measured start through the waypoints and back to the start, as
//! jerk-limited rest-to-rest moves synchronised over the joints (Biagiotti & Melchiorri's
//! 7-segment profile). Each move is monotonic per joint, so the path stays between its two
//! waypoints: waypoints inside the position limits keep the whole path inside. The plan is
//! also sampled every millisecond and checked against position, speed and (where the model has
//! them) effort limits with inverse dynamics, so nothing moves before all of that holds.

use core::fmt;

use rl_core::algo::rnea;
use rl_core::traj::{JerkLimited, Limits, Piecewise, Trajectory, TrajectoryError};
use rl_core::{Data, Model};

use super::{MAX_JOINTS, MAX_WAYPOINTS};

/// Speed assumed for a joint whose model has no speed limit (rad/s or m/s).
pub const UNKNOWN_SPEED: f64 = 0.5;
/// Time to reach the planned speed at the planned acceleration: `amax = vmax / ACCEL_TIME_S`.
pub const ACCEL_TIME_S: f64 = 0.5;
/// Time to reach the planned acceleration at the planned jerk: `jmax = amax / JERK_TIME_S`.
pub const JERK_TIME_S: f64 = 0.15;
/// Sampling step of the pre-motion limit check.
pub const CHECK_STEP_S: f64 = 1e-3;

/// Segments a plan holds: start → waypoints → start.
const SEGMENTS: usize = MAX_WAYPOINTS + 1;

/// The jerk-limited trajectory type of a plan.
pub type PlanTrajectory = Piecewise<JerkLimited<MAX_JOINTS>, SEGMENTS>;

/// Why a plan was refused; joints are named as in the model.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanError {
    /// The model has more joints than the controller drives.
    TooManyJoints {
        /// Joints of the model.
        dof: usize,
    },
    /// The model has joints whose configuration is not a plain vector (spherical, free-flyer).
    NotJointSpace {
        /// Position coordinates.
        nq: usize,
        /// Degrees of freedom.
        dof: usize,
    },
    /// A joint vector has the wrong length.
    Length {
        /// `"start"` or `"waypoint N"`.
        what: String,
        /// Expected length (the model's joints).
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// Too many waypoints.
    TooManyWaypoints {
        /// Given.
        given: usize,
    },
    /// The speed fraction is not in `(0, 1]`.
    SpeedFraction(f64),
    /// A position (start or waypoint) outside the joint's limits, or not finite.
    OutsideLimits {
        /// `"start"` or `"waypoint N"` (1-based, as in the file).
        what: String,
        /// The joint's name.
        joint: String,
        /// The value.
        value: f64,
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
    /// The sampled trajectory exceeds a limit (should not happen for a valid plan; reported).
    Exceeds {
        /// `"position"`, `"speed"` or `"effort"`.
        quantity: &'static str,
        /// The joint's name.
        joint: String,
        /// Trajectory time in s.
        time_s: f64,
        /// The value.
        value: f64,
        /// The limit.
        limit: f64,
    },
    /// The trajectory could not be built.
    Trajectory(TrajectoryError),
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooManyJoints { dof } => write!(
                f,
                "the model has {dof} joints; the controller drives at most {MAX_JOINTS}"
            ),
            Self::NotJointSpace { nq, dof } => write!(
                f,
                "the model has {nq} position coordinates for {dof} joints (spherical or \
                 free-flying joints); the controller needs one coordinate per joint"
            ),
            Self::Length {
                what,
                expected,
                got,
            } => write!(
                f,
                "{what} has {got} joint values, the model has {expected} joints"
            ),
            Self::TooManyWaypoints { given } => {
                write!(
                    f,
                    "{given} waypoints; at most {MAX_WAYPOINTS} are supported"
                )
            }
            Self::SpeedFraction(s) => write!(
                f,
                "speed fraction {s} must be above 0 and at most 1 (of the model's speed limits)"
            ),
            Self::OutsideLimits {
                what,
                joint,
                value,
                lower,
                upper,
            } => write!(
                f,
                "{what}: joint {joint} at {value} is outside its limits [{lower}, {upper}]"
            ),
            Self::Exceeds {
                quantity,
                joint,
                time_s,
                value,
                limit,
            } => write!(
                f,
                "the trajectory exceeds the {quantity} limit of joint {joint} at t = {time_s:.3} s: \
                 {value} (limit {limit})"
            ),
            Self::Trajectory(e) => write!(f, "cannot plan the trajectory: {e}"),
        }
    }
}

impl std::error::Error for PlanError {}

impl From<TrajectoryError> for PlanError {
    fn from(e: TrajectoryError) -> Self {
        Self::Trajectory(e)
    }
}

/// The name of joint (degree of freedom) `k` of `model`.
pub fn joint_name<const N: usize>(model: &Model<N>, k: usize) -> String {
    model.joint_name(model.dof_body(k)).to_owned()
}

/// Checks that the controller can drive `model`: at most [`MAX_JOINTS`] joints of one
/// coordinate each.
pub fn check_model<const N: usize>(model: &Model<N>) -> Result<(), PlanError> {
    if model.dof() > MAX_JOINTS {
        return Err(PlanError::TooManyJoints { dof: model.dof() });
    }
    if model.nq() != model.dof() {
        return Err(PlanError::NotJointSpace {
            nq: model.nq(),
            dof: model.dof(),
        });
    }
    Ok(())
}

/// Per-joint speed, acceleration and jerk limits of a plan, derived from the model's speed
/// limits: `vmax = fraction × speed limit`, `amax = vmax / 0.5 s`, `jmax = amax / 0.15 s`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionLimits {
    /// Joints used.
    pub dof: usize,
    /// Planned speed limit per joint.
    pub velocity: [f64; MAX_JOINTS],
    /// Planned acceleration limit per joint.
    pub acceleration: [f64; MAX_JOINTS],
    /// Planned jerk limit per joint.
    pub jerk: [f64; MAX_JOINTS],
    /// Joints whose model has no speed limit ([`UNKNOWN_SPEED`] was assumed).
    pub assumed_speed: [bool; MAX_JOINTS],
}

impl MotionLimits {
    /// Limits at `fraction` (0, 1] of the model's speed limits.
    pub fn from_model<const N: usize>(model: &Model<N>, fraction: f64) -> Result<Self, PlanError> {
        check_model(model)?;
        if !(fraction > 0.0 && fraction <= 1.0) {
            return Err(PlanError::SpeedFraction(fraction));
        }
        let mut limits = Self {
            dof: model.dof(),
            velocity: [1.0; MAX_JOINTS],
            acceleration: [1.0; MAX_JOINTS],
            jerk: [1.0; MAX_JOINTS],
            assumed_speed: [false; MAX_JOINTS],
        };
        for k in 0..model.dof() {
            let speed = model.limits(k).velocity;
            let known = speed.is_finite() && speed > 0.0;
            limits.assumed_speed[k] = !known;
            let v = fraction * if known { speed } else { UNKNOWN_SPEED };
            limits.velocity[k] = v;
            limits.acceleration[k] = v / ACCEL_TIME_S;
            limits.jerk[k] = v / ACCEL_TIME_S / JERK_TIME_S;
        }
        Ok(limits)
    }

    fn trajectory_limits(&self) -> Limits<MAX_JOINTS> {
        // Unused axes do not move; their limits only need to be valid.
        Limits {
            velocity: self.velocity,
            acceleration: self.acceleration,
            jerk: self.jerk,
        }
    }
}

/// A small tour for the model: every joint 40 % of the way from `start` towards its upper
/// limit, then towards its lower limit, then alternating joints 25 % up and down (limits
/// shrunk by 5 % of the range; ±1 rad for unbounded joints). The plan adds the return to
/// `start`.
pub fn default_waypoints<const N: usize>(model: &Model<N>, start: &[f64]) -> Vec<Vec<f64>> {
    let toward = |k: usize, fraction: f64, up: bool| -> f64 {
        let l = model.limits(k);
        let s = start[k];
        if l.is_bounded() {
            let margin = 0.05 * (l.upper - l.lower);
            let target = if up {
                l.upper - margin
            } else {
                l.lower + margin
            };
            s + fraction * (target - s)
        } else {
            s + if up { fraction } else { -fraction }
        }
    };
    let dof = model.dof().min(start.len());
    vec![
        (0..dof).map(|k| toward(k, 0.4, true)).collect(),
        (0..dof).map(|k| toward(k, 0.4, false)).collect(),
        (0..dof).map(|k| toward(k, 0.25, k % 2 == 0)).collect(),
    ]
}

/// A checked jerk-limited trajectory from `start` through waypoints and back to `start`.
#[derive(Clone, Debug)]
pub struct Plan {
    dof: usize,
    trajectory: PlanTrajectory,
    points: Vec<[f64; MAX_JOINTS]>,
    limits: MotionLimits,
    peak_velocity: [f64; MAX_JOINTS],
    peak_effort: [f64; MAX_JOINTS],
}

impl Plan {
    /// Plans and checks against `model`'s limits; `start` is where the robot is.
    pub fn new<const N: usize>(
        model: &Model<N>,
        start: &[f64],
        waypoints: &[Vec<f64>],
        limits: &MotionLimits,
    ) -> Result<Self, PlanError> {
        check_model(model)?;
        let dof = model.dof();
        if waypoints.len() > MAX_WAYPOINTS {
            return Err(PlanError::TooManyWaypoints {
                given: waypoints.len(),
            });
        }
        let mut points = Vec::with_capacity(waypoints.len() + 2);
        points.push(to_point(model, "start".into(), start)?);
        for (i, w) in waypoints.iter().enumerate() {
            points.push(to_point(model, format!("waypoint {}", i + 1), w)?);
        }
        points.push(points[0]);
        let mut trajectory = PlanTrajectory::new();
        let tl = limits.trajectory_limits();
        for pair in points.windows(2) {
            trajectory.push(JerkLimited::new(pair[0], pair[1], &tl)?)?;
        }
        let mut plan = Self {
            dof,
            trajectory,
            points,
            limits: *limits,
            peak_velocity: [0.0; MAX_JOINTS],
            peak_effort: [0.0; MAX_JOINTS],
        };
        plan.check(model)?;
        Ok(plan)
    }

    /// Samples the trajectory every [`CHECK_STEP_S`] (and at its end) and checks positions,
    /// speeds, and inverse-dynamics efforts against the model's limits; records the peaks.
    fn check<const N: usize>(&mut self, model: &Model<N>) -> Result<(), PlanError> {
        let dof = self.dof;
        let mut data = Box::new(Data::<N>::new());
        let duration = self.trajectory.duration();
        let steps = (duration / CHECK_STEP_S).ceil() as usize;
        for i in 0..=steps {
            let t = (i as f64 * CHECK_STEP_S).min(duration);
            let s = self.trajectory.sample(t);
            let tau = rnea(
                model,
                &mut data,
                &s.position[..dof],
                &s.velocity[..dof],
                &s.acceleration[..dof],
            )
            .map_err(|_| PlanError::NotJointSpace {
                nq: model.nq(),
                dof,
            })?;
            for (k, tau_k) in tau.iter().enumerate().take(dof) {
                let l = model.limits(k);
                let exceeds = |quantity, value: f64, limit: f64| PlanError::Exceeds {
                    quantity,
                    joint: joint_name(model, k),
                    time_s: t,
                    value,
                    limit,
                };
                let q = s.position[k];
                if !l.contains(q) {
                    let limit = if q < l.lower { l.lower } else { l.upper };
                    return Err(exceeds("position", q, limit));
                }
                let v = s.velocity[k].abs();
                if v > l.velocity * (1.0 + 1e-9) {
                    return Err(exceeds("speed", v, l.velocity));
                }
                let e = tau_k.abs();
                if e > l.effort {
                    return Err(exceeds("effort", e, l.effort));
                }
                self.peak_velocity[k] = self.peak_velocity[k].max(v);
                self.peak_effort[k] = self.peak_effort[k].max(e);
            }
        }
        Ok(())
    }

    /// Joints.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// The trajectory (axes beyond [`dof`](Self::dof) stay at zero).
    pub fn trajectory(&self) -> &PlanTrajectory {
        &self.trajectory
    }

    /// Duration in s.
    pub fn duration_s(&self) -> f64 {
        self.trajectory.duration()
    }

    /// The start, the waypoints and the start again.
    pub fn points(&self) -> &[[f64; MAX_JOINTS]] {
        &self.points
    }

    /// The limits it was planned with.
    pub fn limits(&self) -> &MotionLimits {
        &self.limits
    }

    /// Largest speed per joint found by the check.
    pub fn peak_velocity(&self) -> &[f64] {
        &self.peak_velocity[..self.dof]
    }

    /// Largest inverse-dynamics effort per joint found by the check.
    pub fn peak_effort(&self) -> &[f64] {
        &self.peak_effort[..self.dof]
    }
}

fn to_point<const N: usize>(
    model: &Model<N>,
    what: String,
    q: &[f64],
) -> Result<[f64; MAX_JOINTS], PlanError> {
    let dof = model.dof();
    if q.len() != dof {
        return Err(PlanError::Length {
            what,
            expected: dof,
            got: q.len(),
        });
    }
    let mut p = [0.0; MAX_JOINTS];
    for (k, &v) in q.iter().enumerate() {
        let l = model.limits(k);
        if !v.is_finite() || !l.contains(v) {
            return Err(PlanError::OutsideLimits {
                what,
                joint: joint_name(model, k),
                value: v,
                lower: l.lower,
                upper: l.upper,
            });
        }
        p[k] = v;
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> super::super::RobotModel {
        super::super::rv6sl().expect("embedded model loads").model
    }

    #[test]
    fn default_plan_of_the_rv6sl_is_within_limits_and_a_few_seconds_long() {
        let m = model();
        let start = [0.0; 6];
        let limits = MotionLimits::from_model(&m, 0.25).expect("limits");
        let plan = Plan::new(&m, &start, &default_waypoints(&m, &start), &limits).expect("plan");
        assert!(
            (4.0..=9.0).contains(&plan.duration_s()),
            "{}",
            plan.duration_s()
        );
        for k in 0..6 {
            assert!(plan.peak_velocity()[k] <= limits.velocity[k] * (1.0 + 1e-9));
            assert!(plan.peak_velocity()[k] > 0.5 * limits.velocity[k]);
        }
        assert_eq!(plan.points().first(), plan.points().last());
    }

    #[test]
    fn waypoints_outside_limits_are_refused_with_the_joint_named() {
        let m = model();
        let limits = MotionLimits::from_model(&m, 0.25).expect("limits");
        let mut w = vec![0.0; 6];
        w[1] = 3.0; // joint1 is limited to [-92°, 135°]
        let e = Plan::new(&m, &[0.0; 6], &[w], &limits).expect_err("outside");
        assert!(
            matches!(&e, PlanError::OutsideLimits { what, joint, .. } if what == "waypoint 1" && joint == "joint1"),
            "{e}"
        );
        let e = Plan::new(&m, &[0.0; 6], &[vec![0.0; 5]], &limits).expect_err("length");
        assert!(matches!(
            e,
            PlanError::Length {
                expected: 6,
                got: 5,
                ..
            }
        ));
        assert!(MotionLimits::from_model(&m, 1.5).is_err());
    }
}
