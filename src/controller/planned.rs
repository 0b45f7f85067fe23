//! A planned motion for a run (feature `plan`): a collision-free path from rl-plan, made a
//! time-parameterised trajectory through its waypoints within the model's speed, acceleration
//! and jerk limits (rl-core's jerk-limited profile, rl-plan's [`Execution`]), as the
//! [`Motion`] a [`ControlRun`](super::ControlRun) follows.
//!
//! Planning runs before anything is opened or started, bounded by the planner's time budget
//! (planning, then as much again for optimising) and cancelled within one planner iteration
//! when the run's [`StopFlag`] is raised (Ctrl-C). A start or goal in collision, or no path
//! within the budget, is an error and nothing moves.
//!
//! By default ([`PathExecution::Retimed`]) the trajectory does not stop at the optimised
//! path's interior waypoints: rl-plan's blended execution ([`rl_plan::execute::blend`]) runs
//! straight lines joined by jerk-continuous blends (and jerk-limited ramps from and to rest)
//! within every joint's velocity,
//! acceleration and jerk limits, samples the whole trajectory a tenth of the planner's
//! collision resolution apart and checks every sample with the run's validity checker, and
//! shrinks a blend that collides, or stops at that waypoint. [`PathExecution::StopAtWaypoints`]
//! keeps the older execution: it stops at every waypoint and follows the straight segments
//! between them exactly (every joint on the same normalised profile), so the arm passes only
//! through configurations the planner checked. The certified blended trajectory is then retimed
//! near time-optimally with bounded jerk along its own configurations
//! ([`rl_plan::execute::jerk_limited`]) and the faster of the two is followed
//! ([`PathExecution::Blended`] keeps the blends' timing). The description (the run's report)
//! says which, how many waypoints were blended and the durations.
//!
//! Sampling, however fine, can step over an obstacle. So before it is handed to the controller
//! the motion is certified on the checker's exact geometry by conservative advancement
//! ([`rl_plan::scene`]'s `certify_*`: nothing comes within the margin anywhere along it, not
//! only at samples): the blended trajectory over time within its speed limits, the
//! stop-at-waypoints one along its straight edges. A blended trajectory that is not certified
//! is replaced by the stop-at-waypoints one if that is; a path that is not certified is planned
//! again with the next seed, up to [`CERTIFY_ATTEMPTS`] times, then refused
//! ([`PlannedMotionError::Uncertified`]). A checker without exact geometry (the sphere checker)
//! certifies nothing, and the description says so.
//!
//! ```no_run
//! use std::path::Path;
//! use rl::controller::{ControlRun, RunOptions, planned};
//! use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
//! use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
//! use rl_plan::problem::{Robot, moveit::MotionRequest};
//!
//! let urdf = Path::new("tests/data/mbm/panda/panda.urdf");
//! let problem = Path::new("tests/data/mbm/panda/problems/table_pick_panda");
//! let robot = Robot::load_urdf(urdf, None, None)?; // the SRDF and spheres beside the URDF
//! let scene = rl::sg::load::moveit::load_environment(&problem.join("scene0001.yaml"))?;
//! let request = MotionRequest::load(&problem.join("request0001.yaml"))?;
//! let (start, goal) = request.configurations(&robot.space)?;
//!
//! let loaded = rl::core::loader::load_file::<16>(urdf)?;
//! let options = RunOptions::default().speed(0.5);
//! let mut checker = robot.hybrid_checker(&scene)?;
//! let planned = planned::plan_motion::<16, 16>(
//!     &loaded.model, &robot.space, &mut checker, &start, &goal,
//!     &rl_plan::PlanOptions::default(), options.speed, Some(&options.stop),
//! )?;
//! // The robot must stand at the start: here a fake H7 whose arm rests there.
//! let fake = FakeH7::spawn(FakeH7Config::for_model(&loaded.model, &start)?)?;
//! let h7 = MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr()))?;
//! let run = ControlRun::<_, 16, 16>::start_with(h7, loaded, options, planned.motion)?;
//! println!("{}", run.join());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use core::fmt;

use rl_core::Model;
use rl_plan::budget::Cancel;
use rl_plan::execute::{
    BlendOptions, BlendReport, Execution, ExecutionLimits, jerk_limited, rests_of,
};
use rl_plan::scene::{Certificate, CertifyOptions, Uncertified};
use rl_plan::solve::plan_cancellable;
use rl_plan::{JointSpace, PlanOptions, PlanResult, Validity};
use rl_rt::StopFlag;

use super::MAX_WAYPOINTS;
use super::plan::{BLENDED_SEGMENTS, Motion, MotionLimits, PlanError, PlanTrajectory, joint_name};

/// Why no motion was planned. Nothing was opened or moved.
#[derive(Clone, Debug, PartialEq)]
pub enum PlannedMotionError {
    /// The planning space's joints are not the controller model's (names, in order).
    Joints {
        /// The space's coordinates.
        space: Vec<String>,
        /// The model's joints.
        model: Vec<String>,
    },
    /// The planner refused the problem (e.g. the start or goal in collision) or the path
    /// could not be made a trajectory.
    Planner(rl_plan::PlanError),
    /// No path was found within the time budget.
    NotSolved {
        /// The planner's name.
        planner: String,
        /// The budget.
        time: std::time::Duration,
        /// Iterations it ran.
        iterations: u64,
    },
    /// The model's limits or the controller's capacity refuse the motion.
    Limits(PlanError),
    /// A stop was requested while planning.
    Cancelled,
    /// No planned path could be certified collision-free on the exact geometry (seeds tried,
    /// and why each was refused).
    Uncertified {
        /// `(seed, the first edge or time not certified and why)` per attempt.
        attempts: Vec<(u64, String)>,
    },
}

impl fmt::Display for PlannedMotionError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Joints { space, model } => write!(
                f,
                "the planning model's joints {space:?} are not the controller model's {model:?}"
            ),
            Self::Planner(e) => write!(f, "planning failed: {e}"),
            Self::NotSolved {
                planner,
                time,
                iterations,
            } => write!(
                f,
                "no collision-free path found: {planner} ran {iterations} iterations within its \
                 {time:?} budget (give more time, another seed or planner, or check the problem)"
            ),
            Self::Limits(e) => write!(f, "{e}"),
            Self::Cancelled => f.write_str("planning was cancelled by a stop request"),
            Self::Uncertified { attempts } => {
                write!(
                    f,
                    "no planned path could be certified collision-free on the exact geometry in \
                     {} attempts (",
                    attempts.len()
                )?;
                for (k, (seed, why)) in attempts.iter().enumerate() {
                    let sep = if k == 0 { "" } else { "; " };
                    write!(f, "{sep}seed {seed}: {why}")?;
                }
                f.write_str("): give the robot more room, or another seed or planner")
            }
        }
    }
}

impl std::error::Error for PlannedMotionError {}

impl From<rl_plan::PlanError> for PlannedMotionError {
    fn from(e: rl_plan::PlanError) -> Self {
        match e {
            rl_plan::PlanError::Cancelled => Self::Cancelled,
            e => Self::Planner(e),
        }
    }
}

/// How a planned path is executed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathExecution {
    /// Blended ([`Blended`](Self::Blended)), then retimed near time-optimally with bounded
    /// jerk along the blended configurations (rl-plan's [`jerk_limited`]: TOPP-RA, its path
    /// acceleration averaged, slowed where a sample would exceed a limit) when that is faster;
    /// the default. The configurations are the blended trajectory's, so its certificate holds.
    #[default]
    Retimed,
    /// Through the interior waypoints without stopping where blends are valid and faster
    /// (rl-plan's [`blend`](rl_plan::execute::blend)), at the blends' own timing: one speed
    /// along each line and through each blend.
    Blended,
    /// Stopping at every waypoint, on the path's straight segments exactly.
    StopAtWaypoints,
}

impl fmt::Display for PathExecution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Retimed => "blended through the waypoints and retimed with bounded jerk",
            Self::Blended => "blended through the waypoints",
            Self::StopAtWaypoints => "stopping at every waypoint",
        })
    }
}

/// A planned motion: what the planner found and the trajectory along its path.
#[derive(Clone, Debug)]
pub struct PlannedMotion<const J: usize> {
    /// The trajectory for [`ControlRun::start_with`](super::ControlRun::start_with) (source
    /// `"plan"`).
    pub motion: Motion<J>,
    /// The planner's report (times, iterations, collision checks, lengths, paths).
    pub result: PlanResult,
    /// The optimised path's waypoints (start first, goal last; circle joints unwrapped).
    pub waypoints: Vec<Vec<f64>>,
    /// The trajectory's duration, s.
    pub duration_s: f64,
    /// How the path is executed.
    pub execution: PathExecution,
    /// The duration when stopping at every waypoint, s (equal to `duration_s` for
    /// [`PathExecution::StopAtWaypoints`]).
    pub stop_duration_s: f64,
    /// For [`PathExecution::Blended`] and [`PathExecution::Retimed`]: waypoints blended and
    /// stopped at, the collision check.
    pub blend: Option<BlendReport>,
    /// The blended trajectory's duration at the blends' own timing, s (`None`: not blended).
    pub blended_duration_s: Option<f64>,
    /// The retiming of the blended trajectory (asked for with [`PathExecution::Retimed`]):
    /// its duration in s, or why there is none. Followed when shorter than the blended one.
    pub retimed: Option<Result<f64, String>>,
    /// The certificate of the motion followed (`None`: the checker has no exact geometry).
    pub certificate: Option<Certificate>,
    /// Earlier attempts refused as not certified: `(seed, why)`.
    pub refused: Vec<(u64, String)>,
}

/// Seeds tried before a path that cannot be certified is refused.
pub const CERTIFY_ATTEMPTS: u64 = 3;

/// What one planning attempt gave.
enum Attempt<const J: usize> {
    Done(Box<PlannedMotion<J>>),
    Uncertified(String),
}

/// Plans from `start` to `goal` in `space` with `validity` and `options`, and makes the
/// optimised path a trajectory blended through its waypoints and retimed with bounded jerk
/// ([`PathExecution::Retimed`], checked with `validity`) within `speed` (a fraction, (0, 1])
/// of `model`'s speed limits, with the controller's acceleration and jerk ([`MotionLimits`]).
/// `model` is the controller's model: its joints must be the space's, in the same order.
/// `stop` cancels planning.
#[allow(clippy::too_many_arguments)]
pub fn plan_motion<const B: usize, const J: usize>(
    model: &Model<B>,
    space: &JointSpace,
    validity: &mut dyn Validity,
    start: &[f64],
    goal: &[f64],
    options: &PlanOptions,
    speed: f64,
    stop: Option<&StopFlag>,
) -> Result<PlannedMotion<J>, PlannedMotionError> {
    plan_motion_with(
        model,
        space,
        validity,
        start,
        goal,
        options,
        speed,
        stop,
        PathExecution::Retimed,
    )
}

/// [`plan_motion`] with the choice of execution.
#[allow(clippy::too_many_arguments)]
pub fn plan_motion_with<const B: usize, const J: usize>(
    model: &Model<B>,
    space: &JointSpace,
    validity: &mut dyn Validity,
    start: &[f64],
    goal: &[f64],
    options: &PlanOptions,
    speed: f64,
    stop: Option<&StopFlag>,
    execution: PathExecution,
) -> Result<PlannedMotion<J>, PlannedMotionError> {
    let limits = MotionLimits::<J>::from_model(model, speed).map_err(PlannedMotionError::Limits)?;
    let names: Vec<String> = (0..model.dof()).map(|k| joint_name(model, k)).collect();
    let coordinates: Vec<String> = space.coordinates().iter().map(|c| c.name.clone()).collect();
    if !space.is_vector() || names != coordinates {
        return Err(PlannedMotionError::Joints {
            space: coordinates,
            model: names,
        });
    }
    let cancel = stop
        .cloned()
        .map(|s| Cancel::when(move || s.is_stop_requested()));
    let mut opts = options.clone();
    let mut refused = Vec::new();
    for _ in 0..CERTIFY_ATTEMPTS {
        let attempt = plan_once(
            model,
            space,
            validity,
            (start, goal),
            &opts,
            speed,
            cancel.as_ref(),
            execution,
            &limits,
        )?;
        match attempt {
            Attempt::Done(mut m) => {
                m.refused = refused;
                return Ok(*m);
            }
            Attempt::Uncertified(why) => {
                refused.push((opts.seed, why));
                opts.seed = opts.seed.wrapping_add(1);
            }
        }
    }
    Err(PlannedMotionError::Uncertified { attempts: refused })
}

/// One planning attempt with `options`' seed: plan, make the trajectory, certify it.
#[allow(clippy::too_many_arguments)]
fn plan_once<const B: usize, const J: usize>(
    model: &Model<B>,
    space: &JointSpace,
    validity: &mut dyn Validity,
    (start, goal): (&[f64], &[f64]),
    options: &PlanOptions,
    speed: f64,
    cancel: Option<&Cancel>,
    execution: PathExecution,
    limits: &MotionLimits<J>,
) -> Result<Attempt<J>, PlannedMotionError> {
    let result = plan_cancellable(space, validity, start, goal, options, cancel)?;
    let Some(path) = result.optimized.as_ref() else {
        return Err(PlannedMotionError::NotSolved {
            planner: result.planner.to_owned(),
            time: options.time,
            iterations: result.iterations,
        });
    };
    let dof = model.dof();
    let execution_plan = Execution::new(
        space,
        path,
        ExecutionLimits {
            velocity: limits.velocity[..dof].to_vec(),
            acceleration: limits.acceleration[..dof].to_vec(),
            jerk: limits.jerk[..dof].to_vec(),
        },
    )?;
    let moves = Box::new(execution_plan.trajectory::<J, { MAX_WAYPOINTS + 1 }>()?);
    let stop_duration_s = rl_core::traj::Trajectory::duration(&*moves);
    let certify = CertifyOptions::default();
    let (trajectory, blend, certificate, fell_back) = match execution {
        PathExecution::StopAtWaypoints => match certify_edges(validity, path, &certify)? {
            Ok(c) => (PlanTrajectory::Moves(moves), None, c, None),
            Err(why) => return Ok(Attempt::Uncertified(why)),
        },
        PathExecution::Blended | PathExecution::Retimed => {
            // The planner's collision resolution (the finer of planning and optimising).
            let resolution = options
                .optimizer_verifier
                .map_or(options.verifier.delta, |v| {
                    v.delta.min(options.verifier.delta)
                });
            let blended = execution_plan.blended::<J, BLENDED_SEGMENTS>(
                space,
                validity,
                &BlendOptions::for_resolution(resolution),
            )?;
            let trajectory = PlanTrajectory::Blended(blended.trajectory);
            match certify_trajectory(validity, space, &trajectory, &limits.velocity[..dof])? {
                // Certified, or nothing to certify it with.
                Ok(c) => (trajectory, Some(blended.report), c, None),
                // The blends leave the straight edges somewhere they should not: stop at every
                // waypoint instead, if the edges themselves are certified (only then are they
                // measured: a certified blended trajectory needs nothing else).
                Err(why) => match certify_edges(validity, path, &certify)? {
                    Ok(c) => (
                        PlanTrajectory::Moves(moves),
                        Some(blended.report),
                        c,
                        Some(why.to_string()),
                    ),
                    Err(path_why) => return Ok(Attempt::Uncertified(path_why)),
                },
            }
        }
    };
    let blended_duration_s = match &trajectory {
        PlanTrajectory::Blended(b) => Some(rl_core::traj::Trajectory::duration(&**b)),
        _ => None,
    };
    // The certified blended trajectory retimed along its own configurations (so the
    // certificate holds), kept when faster.
    let (trajectory, retimed) = match (execution, trajectory) {
        (PathExecution::Retimed, PlanTrajectory::Blended(b)) => retime(b, execution_plan.limits()),
        (_, trajectory) => (trajectory, None),
    };
    let duration_s = rl_core::traj::Trajectory::duration(&trajectory);
    let how = match &blend {
        Some(r) => format!(
            "blended through {} of {} interior waypoints ({} shrunk, stopped at {}), {:.2} s \
             (stopping at every waypoint: {:.2} s), {} configurations checked{}",
            r.blended(),
            r.waypoints.len(),
            r.shrunk(),
            r.stopped(),
            r.duration_s,
            r.stop_duration_s,
            r.checks,
            match &retimed {
                Some(Ok(t)) if matches!(trajectory, PlanTrajectory::Retimed(_)) => {
                    format!(", retimed with bounded jerk to {t:.2} s")
                }
                Some(Ok(t)) => format!(" (retimed: {t:.2} s, not faster: kept)"),
                Some(Err(why)) => format!(" (not retimed: {why})"),
                None => String::new(),
            }
        ),
        None => format!("stopping at every waypoint, {duration_s:.2} s"),
    };
    let how = match &fell_back {
        Some(why) => format!(
            "stopping at every waypoint, {duration_s:.2} s (the blended trajectory was not \
             certified: {why})"
        ),
        None => how,
    };
    let certified = match &certificate {
        Some(c) => format!(
            "certified on the exact geometry ({} steps: clear by at least {:.0} µm everywhere)",
            c.steps,
            certify.margin * 0.5e6
        ),
        None => "not certified (the checker has no exact geometry)".to_owned(),
    };
    let description = format!(
        "planned path by {} (seed {}) in {:.1} ms: {} waypoints, {:.3} rad long, at {:.0} % of \
         the speed limits, {how}, {certified}",
        result.planner,
        options.seed,
        (result.planning_time + result.optimization_time).as_secs_f64() * 1e3,
        execution_plan.waypoints().len(),
        result.length_after,
        speed * 100.0
    );
    let execution = match &trajectory {
        PlanTrajectory::Moves(_) => PathExecution::StopAtWaypoints,
        PlanTrajectory::Blended(_) => PathExecution::Blended,
        PlanTrajectory::Retimed(_) => PathExecution::Retimed,
    };
    Ok(Attempt::Done(Box::new(PlannedMotion {
        motion: Motion::trajectory(trajectory, "plan", description),
        waypoints: execution_plan.waypoints().to_vec(),
        result,
        duration_s,
        execution,
        stop_duration_s,
        blend,
        blended_duration_s,
        retimed,
        certificate,
        refused: Vec::new(),
    })))
}

/// TOPP-RA stages per run of the retiming (as rl-plan's benchmark).
const RETIME_STAGES: usize = 1000;
/// The retiming's margin on its slow-down.
const RETIME_MARGIN: f64 = 1e-3;

/// `blended` retimed with bounded jerk within `limits` (the same configurations), when that is
/// faster; otherwise `blended` as it was. Also the retiming's duration, or why there is none.
fn retime<const J: usize>(
    blended: Box<rl_core::traj::Piecewise<rl_core::traj::Segment<J>, BLENDED_SEGMENTS>>,
    limits: &ExecutionLimits,
) -> (PlanTrajectory<J>, Option<Result<f64, String>>) {
    let before = rl_core::traj::Trajectory::duration(&*blended);
    let rests = rests_of::<J, _, BLENDED_SEGMENTS>(&*blended, limits.velocity.len());
    let path = blended.clone();
    match jerk_limited(path, &rests, limits, RETIME_STAGES, RETIME_MARGIN) {
        Ok(r) if r.duration() < before => {
            let t = r.duration();
            (PlanTrajectory::Retimed(Box::new(r)), Some(Ok(t)))
        }
        Ok(r) => (PlanTrajectory::Blended(blended), Some(Ok(r.duration()))),
        Err(e) => (PlanTrajectory::Blended(blended), Some(Err(e.to_string()))),
    }
}

/// Certifies the straight edges of `path` (what the stop-at-waypoints execution follows) on
/// `validity`'s exact geometry: `Ok(Ok(None))` when there is none to certify with, `Ok(Err)`
/// with the first edge not certified and why.
fn certify_edges(
    validity: &mut dyn Validity,
    path: &rl_plan::Path,
    options: &CertifyOptions,
) -> Result<Result<Option<Certificate>, String>, PlannedMotionError> {
    let Some(exact) = validity.exact_checker() else {
        return Ok(Ok(None));
    };
    let c = exact.certify_path(path, options)?;
    Ok(match &c.failure {
        Some((edge, why)) => Err(format!("edge {edge}: {why}")),
        None => Ok(Some(Certificate {
            steps: c.steps,
            min_distance: c.min_distance,
        })),
    })
}

/// Certifies `trajectory` (within `speed`, rad/s or m/s per joint) on `validity`'s exact
/// geometry: `Ok(Ok(None))` when there is none to certify with.
fn certify_trajectory<const J: usize>(
    validity: &mut dyn Validity,
    space: &JointSpace,
    trajectory: &PlanTrajectory<J>,
    speed: &[f64],
) -> Result<Result<Option<Certificate>, Uncertified>, PlannedMotionError> {
    use rl_core::traj::Trajectory;
    let Some(exact) = validity.exact_checker() else {
        return Ok(Ok(None));
    };
    let n = space.nq();
    let duration = trajectory.duration();
    let c = exact.certify_motion(duration, speed, &CertifyOptions::default(), |t, q| {
        q.copy_from_slice(&trajectory.position(t)[..n]);
        // Circle joints are unwrapped along the trajectory.
        space.normalize(q);
    })?;
    Ok(c.map(Some))
}
