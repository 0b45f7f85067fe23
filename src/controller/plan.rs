//! What to move through, how fast, and the check against the model's limits before moving.
//!
//! A [`Plan`] goes from the measured start through the waypoints and back to the start, as
//! jerk-limited rest-to-rest moves synchronised over the joints (Biagiotti & Melchiorri's
//! 7-segment profile), or follows a trajectory made elsewhere ([`Plan::from_trajectory`],
//! [`Motion::Trajectory`]: e.g. a planned collision-free path). Each move is monotonic per joint, so the path stays between its two
//! waypoints: waypoints inside the position limits keep the whole path inside. The plan is
//! also sampled (every millisecond, or more coarsely for very long plans so the check stays
//! bounded) and checked against position, speed and (where the model has them) effort limits
//! with inverse dynamics, so nothing moves before all of that holds. The check is bounded in
//! time by a [`PlanBudget`] (the longest trajectory accepted, a cancelling [`StopFlag`]) and
//! runs before the device is started.
//!
//! Joint vectors are `[f64; J]` for the controller's joint capacity `J`.

use core::fmt;

use std::time::Duration;

use rl_core::algo::rnea;
use rl_core::traj::{JerkLimited, Limits, Piecewise, Sample, Segment, Trajectory, TrajectoryError};
use rl_core::{Data, Model};
use rl_rt::StopFlag;

use super::{DEFAULT_JOINTS, MAX_WAYPOINTS};

/// Speed assumed for a joint whose model has no speed limit (rad/s or m/s).
pub const UNKNOWN_SPEED: f64 = 0.5;
/// Time to reach the planned speed at the planned acceleration: `amax = vmax / ACCEL_TIME_S`.
pub const ACCEL_TIME_S: f64 = 0.5;
/// Time to reach the planned acceleration at the planned jerk: `jmax = amax / JERK_TIME_S`.
pub const JERK_TIME_S: f64 = 0.15;
/// Sampling step of the pre-motion limit check.
pub const CHECK_STEP_S: f64 = 1e-3;
/// Most samples the pre-motion check takes (longer plans are sampled more coarsely).
pub const MAX_CHECK_SAMPLES: usize = 200_000;
/// The longest trajectory a plan accepts by default.
pub const DEFAULT_MAX_PLAN_DURATION: Duration = Duration::from_secs(3600);

/// Segments a tour holds: start → waypoints → start (and a path stopping at each of its
/// waypoints: one jerk-limited move per path segment).
pub const MOVE_SEGMENTS: usize = MAX_WAYPOINTS + 1;

/// Segments a blended trajectory holds: a path of up to [`MOVE_SEGMENTS`] segments blended
/// through its waypoints needs at most five per path segment (a line and a blend each, plus
/// the start and end ramps of every stretch between two stops, up to three pieces each;
/// rl-plan's `execute::blend` module docs count them). Beyond, building the trajectory is an
/// error.
pub const BLENDED_SEGMENTS: usize = 5 * MOVE_SEGMENTS;

/// The trajectory of a plan for `J` joints: jerk-limited moves from rest to rest (a tour, or a
/// path that stops at every waypoint), or lines and blends mixed with such moves (a path
/// blended through its waypoints). Each is boxed, and evaluation is one `match` and the
/// segment's closed form: no allocation in the control loop.
#[derive(Clone, Debug)]
pub enum PlanTrajectory<const J: usize = DEFAULT_JOINTS> {
    /// Rest-to-rest jerk-limited moves.
    Moves(Box<Piecewise<JerkLimited<J>, MOVE_SEGMENTS>>),
    /// Lines, blends and moves ([`Segment`]).
    Blended(Box<Piecewise<Segment<J>, BLENDED_SEGMENTS>>),
    /// Lines, blends and moves retimed with bounded jerk along their own configurations.
    #[cfg(feature = "plan")]
    Retimed(Box<RetimedPath<J>>),
}

/// A blended path retimed near time-optimally with bounded jerk along its own configurations
/// (rl-plan's [`jerk_limited`](rl_plan::execute::jerk_limited)); evaluated without allocating.
#[cfg(feature = "plan")]
pub type RetimedPath<const J: usize> =
    rl_plan::execute::JerkRetimed<Box<Piecewise<Segment<J>, BLENDED_SEGMENTS>>>;

impl<const J: usize> PlanTrajectory<J> {
    /// Number of segments.
    pub fn len(&self) -> usize {
        match self {
            Self::Moves(p) => p.len(),
            Self::Blended(p) => p.len(),
            #[cfg(feature = "plan")]
            Self::Retimed(p) => p.path().len(),
        }
    }

    /// `true` without segments.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Where segment `i` starts (zeros beyond the last; a retimed path's are its path's).
    pub fn segment_start(&self, i: usize) -> [f64; J] {
        match self {
            Self::Moves(p) => p.segments().get(i).map(|s| s.position(0.0)),
            Self::Blended(p) => p.segments().get(i).map(|s| s.position(0.0)),
            #[cfg(feature = "plan")]
            Self::Retimed(p) => p.path().segments().get(i).map(|s| s.position(0.0)),
        }
        .unwrap_or([0.0; J])
    }
}

impl<const J: usize> Trajectory<J> for PlanTrajectory<J> {
    fn duration(&self) -> f64 {
        match self {
            Self::Moves(p) => p.duration(),
            Self::Blended(p) => p.duration(),
            #[cfg(feature = "plan")]
            Self::Retimed(p) => Trajectory::<J>::duration(&**p),
        }
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; J] {
        match self {
            Self::Moves(p) => p.derivative(t, order),
            Self::Blended(p) => p.derivative(t, order),
            #[cfg(feature = "plan")]
            Self::Retimed(p) => p.derivative(t, order),
        }
    }

    #[inline]
    fn sample(&self, t: f64) -> Sample<J> {
        match self {
            Self::Moves(p) => p.sample(t),
            Self::Blended(p) => p.sample(t),
            #[cfg(feature = "plan")]
            Self::Retimed(p) => Trajectory::<J>::sample(&**p, t),
        }
    }
}

/// What planning may spend: the longest trajectory accepted and a flag that cancels it (Ctrl-C
/// during planning).
#[derive(Clone, Debug)]
pub struct PlanBudget {
    /// The longest trajectory accepted.
    pub max_duration: Duration,
    /// Raised: planning ends with [`PlanError::Cancelled`].
    pub stop: Option<StopFlag>,
}

impl Default for PlanBudget {
    fn default() -> Self {
        Self {
            max_duration: DEFAULT_MAX_PLAN_DURATION,
            stop: None,
        }
    }
}

/// Why a plan was refused; joints are named as in the model.
#[derive(Clone, Debug, PartialEq)]
pub enum PlanError {
    /// The model has more joints than the controller's capacity.
    TooManyJoints {
        /// Joints of the model.
        dof: usize,
        /// The controller's joint capacity.
        capacity: usize,
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
    /// The trajectory would last longer than the budget allows (e.g. a model with a tiny speed
    /// limit).
    TooLong {
        /// Its duration, s.
        duration_s: f64,
        /// The longest accepted, s.
        max_s: f64,
        /// The slowest joint (its speed limit sets the pace).
        joint: String,
        /// That joint's planned speed.
        speed: f64,
    },
    /// A stop was requested while planning.
    Cancelled,
    /// The model and the device have different numbers of joints.
    DeviceJoints {
        /// Joints of the model.
        model: usize,
        /// Axes of the device.
        device: usize,
    },
    /// The device takes no command of the law's kind (in its configured mode).
    CommandMode {
        /// What the law commands.
        mode: super::law::CommandMode,
    },
    /// One control period's step exceeds what the joint may move in one cycle of the device:
    /// the control period is longer than the device's and the device would execute each step
    /// within its own, shorter cycle.
    StepTooLarge {
        /// The joint's name.
        joint: String,
        /// The planned step per control period.
        step: f64,
        /// What the speed limit allows in one device cycle.
        allowed: f64,
        /// Control period, s.
        period_s: f64,
        /// Device cycle, s.
        device_period_s: f64,
    },
}

impl fmt::Display for PlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooManyJoints { dof, capacity } => write!(
                f,
                "the model has {dof} joints; this controller was built for at most {capacity} \
                 (choose a larger joint capacity)"
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
            Self::TooLong {
                duration_s,
                max_s,
                joint,
                speed,
            } => write!(
                f,
                "the trajectory would take {duration_s:.3e} s, more than the {max_s} s allowed \
                 (joint {joint} is planned at {speed:e}: check the model's speed limits or the \
                 speed fraction)"
            ),
            Self::Cancelled => f.write_str("planning was cancelled by a stop request"),
            Self::DeviceJoints { model, device } => write!(
                f,
                "the model has {model} joints but the device has {device} axes: refusing to \
                 drive it (an axis the model does not describe would be commanded blindly)"
            ),
            Self::CommandMode { mode } => write!(
                f,
                "the law commands joint {mode}s, which this device does not take (in its \
                 configured mode)"
            ),
            Self::StepTooLarge {
                joint,
                step,
                allowed,
                period_s,
                device_period_s,
            } => write!(
                f,
                "joint {joint} would be commanded steps of up to {step:.4} per control period \
                 ({:.2} ms), but the device executes each within its {:.2} ms cycle, where its \
                 speed limit allows {allowed:.4}: use a control period of at most {:.2} ms or a \
                 lower speed",
                period_s * 1e3,
                device_period_s * 1e3,
                period_s * 1e3 * allowed / step
            ),
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

/// Checks that a controller of joint capacity `J` can drive `model`: at most `J` joints of one
/// coordinate each.
pub fn check_model<const N: usize, const J: usize>(model: &Model<N>) -> Result<(), PlanError> {
    if model.dof() > J {
        return Err(PlanError::TooManyJoints {
            dof: model.dof(),
            capacity: J,
        });
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
pub struct MotionLimits<const J: usize = DEFAULT_JOINTS> {
    /// Joints used.
    pub dof: usize,
    /// The fraction of the speed limits planned with.
    pub fraction: f64,
    /// The speed limit per joint: the model's, or [`UNKNOWN_SPEED`] where it gives none.
    pub speed_limit: [f64; J],
    /// Planned speed limit per joint.
    pub velocity: [f64; J],
    /// Planned acceleration limit per joint.
    pub acceleration: [f64; J],
    /// Planned jerk limit per joint.
    pub jerk: [f64; J],
    /// Joints whose model has no speed limit ([`UNKNOWN_SPEED`] was assumed).
    pub assumed_speed: [bool; J],
}

impl<const J: usize> MotionLimits<J> {
    /// Limits at `fraction` (0, 1] of the model's speed limits.
    pub fn from_model<const N: usize>(model: &Model<N>, fraction: f64) -> Result<Self, PlanError> {
        check_model::<N, J>(model)?;
        if !(fraction > 0.0 && fraction <= 1.0) {
            return Err(PlanError::SpeedFraction(fraction));
        }
        let mut limits = Self {
            dof: model.dof(),
            fraction,
            speed_limit: [1.0; J],
            velocity: [1.0; J],
            acceleration: [1.0; J],
            jerk: [1.0; J],
            assumed_speed: [false; J],
        };
        for k in 0..model.dof() {
            let speed = model.limits(k).velocity;
            let known = speed.is_finite() && speed > 0.0;
            limits.assumed_speed[k] = !known;
            limits.speed_limit[k] = if known { speed } else { UNKNOWN_SPEED };
            let v = fraction * limits.speed_limit[k];
            limits.velocity[k] = v;
            limits.acceleration[k] = v / ACCEL_TIME_S;
            limits.jerk[k] = v / ACCEL_TIME_S / JERK_TIME_S;
        }
        Ok(limits)
    }

    /// Whether any joint's speed was assumed ([`UNKNOWN_SPEED`]).
    pub fn any_assumed(&self) -> bool {
        self.assumed_speed[..self.dof].iter().any(|&a| a)
    }

    fn trajectory_limits(&self) -> Limits<J> {
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

/// What a run moves along.
#[derive(Clone, Debug, Default)]
pub enum Motion<const J: usize = DEFAULT_JOINTS> {
    /// A tour from where the arm stands through the run's waypoints (or
    /// [`default_waypoints`]) and back.
    #[default]
    Tour,
    /// A given trajectory, followed from its start (where the arm must stand) to its end.
    Trajectory(FollowTrajectory<J>),
}

/// A trajectory for a run to follow, and where it came from (for the report).
#[derive(Clone, Debug)]
pub struct FollowTrajectory<const J: usize = DEFAULT_JOINTS> {
    /// The trajectory (rl-core's jerk-limited moves, or lines and blends; axes beyond the
    /// model's joints unused).
    pub trajectory: PlanTrajectory<J>,
    /// A short tag for scripts, e.g. `"plan"` (the report's `trajectory_source`).
    pub source: String,
    /// One line for people, e.g. which planner found the path.
    pub description: String,
}

impl<const J: usize> Motion<J> {
    /// Follow `trajectory`; `source` and `description` go into the report.
    pub fn trajectory(
        trajectory: PlanTrajectory<J>,
        source: impl Into<String>,
        description: impl Into<String>,
    ) -> Self {
        Self::Trajectory(FollowTrajectory {
            trajectory,
            source: source.into(),
            description: description.into(),
        })
    }
}

/// A checked jerk-limited trajectory from `start` through waypoints and back to `start`.
#[derive(Clone, Debug)]
pub struct Plan<const J: usize = DEFAULT_JOINTS> {
    dof: usize,
    /// Its segments are boxed: a segment per waypoint for every joint (about 1 MB at 256
    /// joints) is no stack value.
    trajectory: PlanTrajectory<J>,
    points: Vec<[f64; J]>,
    limits: MotionLimits<J>,
    peak_velocity: [f64; J],
    peak_effort: [f64; J],
}

impl<const J: usize> Plan<J> {
    /// Plans and checks against `model`'s limits within the default [`PlanBudget`]; `start`
    /// is where the robot is.
    pub fn new<const N: usize>(
        model: &Model<N>,
        start: &[f64],
        waypoints: &[Vec<f64>],
        limits: &MotionLimits<J>,
    ) -> Result<Self, PlanError> {
        Self::with_budget(model, start, waypoints, limits, &PlanBudget::default())
    }

    /// Plans and checks against `model`'s limits within `budget`.
    pub fn with_budget<const N: usize>(
        model: &Model<N>,
        start: &[f64],
        waypoints: &[Vec<f64>],
        limits: &MotionLimits<J>,
        budget: &PlanBudget,
    ) -> Result<Self, PlanError> {
        check_model::<N, J>(model)?;
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
        let mut moves = Box::new(Piecewise::<JerkLimited<J>, MOVE_SEGMENTS>::new());
        let tl = limits.trajectory_limits();
        let max_s = budget.max_duration.as_secs_f64();
        for pair in points.windows(2) {
            let segment = JerkLimited::new(pair[0], pair[1], &tl)?;
            let total = moves.duration() + segment.duration();
            if total.is_nan() || total > max_s {
                // The slowest joint sets the pace.
                let k = (0..dof)
                    .min_by(|&a, &b| limits.velocity[a].total_cmp(&limits.velocity[b]))
                    .unwrap_or(0);
                return Err(PlanError::TooLong {
                    duration_s: total,
                    max_s,
                    joint: joint_name(model, k),
                    speed: limits.velocity[k],
                });
            }
            moves.push(segment)?;
        }
        let trajectory = PlanTrajectory::Moves(moves);
        let mut plan = Self {
            dof,
            trajectory,
            points,
            limits: *limits,
            peak_velocity: [0.0; J],
            peak_effort: [0.0; J],
        };
        plan.check(model, budget)?;
        Ok(plan)
    }

    /// A checked plan that follows `trajectory` from its start to its end (no return): a
    /// trajectory from elsewhere, e.g. rl-plan's time-parameterised collision-free path
    /// (`rl_plan::execute`), built within `limits`. Its segments' end points must lie within
    /// the model's position limits, and it is sampled and checked against position, speed and
    /// effort limits exactly as a tour is, within `budget`. The robot must stand at its start
    /// ([`Plan::start`]) when the device starts.
    pub fn from_trajectory<const N: usize>(
        model: &Model<N>,
        trajectory: PlanTrajectory<J>,
        limits: &MotionLimits<J>,
        budget: &PlanBudget,
    ) -> Result<Self, PlanError> {
        check_model::<N, J>(model)?;
        let dof = model.dof();
        if trajectory.is_empty() {
            return Err(PlanError::Trajectory(TrajectoryError::TooFewWaypoints {
                required: 2,
                given: 1,
            }));
        }
        let duration = trajectory.duration();
        let max_s = budget.max_duration.as_secs_f64();
        if !duration.is_finite() || duration > max_s {
            let k = (0..dof)
                .min_by(|&a, &b| limits.velocity[a].total_cmp(&limits.velocity[b]))
                .unwrap_or(0);
            return Err(PlanError::TooLong {
                duration_s: duration,
                max_s,
                joint: joint_name(model, k),
                speed: limits.velocity[k],
            });
        }
        let mut points = Vec::with_capacity(trajectory.len() + 1);
        for i in 0..trajectory.len() {
            let what = if i == 0 {
                "trajectory start".to_owned()
            } else {
                format!("trajectory waypoint {i}")
            };
            points.push(to_point(model, what, &trajectory.segment_start(i)[..dof])?);
        }
        points.push(to_point(
            model,
            "trajectory end".into(),
            &trajectory.position(duration)[..dof],
        )?);
        let mut plan = Self {
            dof,
            trajectory,
            points,
            limits: *limits,
            peak_velocity: [0.0; J],
            peak_effort: [0.0; J],
        };
        plan.check(model, budget)?;
        Ok(plan)
    }

    /// Samples the trajectory every [`CHECK_STEP_S`] (at most [`MAX_CHECK_SAMPLES`] samples,
    /// and at its end) and checks positions, speeds, and inverse-dynamics efforts against the
    /// model's limits; records the peaks. Ends early with [`PlanError::Cancelled`] when the
    /// budget's stop flag is raised.
    fn check<const N: usize>(
        &mut self,
        model: &Model<N>,
        budget: &PlanBudget,
    ) -> Result<(), PlanError> {
        let dof = self.dof;
        let mut data = Box::new(Data::<N>::new());
        let duration = self.trajectory.duration();
        let step = CHECK_STEP_S.max(duration / MAX_CHECK_SAMPLES as f64);
        let steps = (duration / step).ceil() as usize;
        for i in 0..=steps {
            if i % 1024 == 0
                && budget
                    .stop
                    .as_ref()
                    .is_some_and(StopFlag::is_stop_requested)
            {
                return Err(PlanError::Cancelled);
            }
            let t = (i as f64 * step).min(duration);
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
                let speed_limit = self.limits.speed_limit[k];
                if v > speed_limit * (1.0 + 1e-9) {
                    return Err(exceeds("speed", v, speed_limit));
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

    /// Refuses the plan if one control period's step would exceed what a joint may move in
    /// one cycle of the device (`period` longer than `device_period`: the device executes each
    /// command within its own cycle).
    pub fn check_step<const N: usize>(
        &self,
        model: &Model<N>,
        period: Duration,
        device_period: Duration,
    ) -> Result<(), PlanError> {
        let (p, d) = (period.as_secs_f64(), device_period.as_secs_f64());
        if p <= d {
            return Ok(());
        }
        for k in 0..self.dof {
            let step = self.peak_velocity[k] * p;
            let allowed = self.limits.speed_limit[k] * d;
            if step > allowed * (1.0 + 1e-9) {
                return Err(PlanError::StepTooLarge {
                    joint: joint_name(model, k),
                    step,
                    allowed,
                    period_s: p,
                    device_period_s: d,
                });
            }
        }
        Ok(())
    }

    /// The trajectory (axes beyond [`dof`](Self::dof) stay at zero).
    pub fn trajectory(&self) -> &PlanTrajectory<J> {
        &self.trajectory
    }

    /// Duration in s.
    pub fn duration_s(&self) -> f64 {
        self.trajectory.duration()
    }

    /// The start, the waypoints and the start again (for a tour), or the start and the end
    /// of every segment (for a trajectory given to [`Plan::from_trajectory`]).
    pub fn points(&self) -> &[[f64; J]] {
        &self.points
    }

    /// Where the plan starts (the robot must stand there).
    pub fn start(&self) -> &[f64] {
        &self.points[0][..self.dof]
    }

    /// The limits it was planned with.
    pub fn limits(&self) -> &MotionLimits<J> {
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

fn to_point<const N: usize, const J: usize>(
    model: &Model<N>,
    what: String,
    q: &[f64],
) -> Result<[f64; J], PlanError> {
    let dof = model.dof();
    if q.len() != dof {
        return Err(PlanError::Length {
            what,
            expected: dof,
            got: q.len(),
        });
    }
    let mut p = [0.0; J];
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

    fn model() -> rl_core::Model<16> {
        super::super::rv6sl().expect("embedded model loads").model
    }

    #[test]
    fn default_plan_of_the_rv6sl_is_within_limits_and_a_few_seconds_long() {
        let m = model();
        let start = [0.0; 6];
        let limits = MotionLimits::<8>::from_model(&m, 0.25).expect("limits");
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
        let limits = MotionLimits::<8>::from_model(&m, 0.25).expect("limits");
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
        assert!(MotionLimits::<8>::from_model(&m, 1.5).is_err());
    }
}
