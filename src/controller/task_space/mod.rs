//! Task-space control in the supervised runtime: [`CartesianImpedance`], a torque law that
//! makes the tool follow a pose (held, streamed, or a figure-eight) with rl-core's
//! operational-space impedance ([`rl_core::task`]), a posture and joint-limit avoidance in
//! the nullspace, and a torque-rate limit (by default half Franka's 1 N·m per ms).
//!
//! ```no_run
//! # use rl::controller::task_space::{CartesianImpedance, TaskMotion};
//! # use rl::controller::{ControlRun, RunOptions};
//! # fn run<D: rl::controller::JointRobot + Send + 'static>(robot: D, model: rl::core::loader::LoadedModel<16>)
//! # -> Result<(), Box<dyn std::error::Error>> {
//! let law = CartesianImpedance::<16, 8>::new(0, TaskMotion::FigureEight {
//!     size_m: 0.1,
//!     period_s: 8.0,
//! });
//! let run = ControlRun::start_law(robot, model, RunOptions::default(), law)?;
//! let report = run.join();
//! # Ok(()) }
//! ```
//!
//! Streamed targets: with [`TaskMotion::Streamed`], each [`TaskInput::Pose`] sent through the
//! run's input sender becomes the tool's goal (world coordinates); the tool's target follows
//! it through a critically damped second-order filter (time constant [`STREAM_FILTER_S`];
//! Franka's own Cartesian impedance example uses a first-order one), whose velocity and
//! acceleration are the task's feed-forward: the target moves without a step in velocity when
//! a goal jumps, and the filter's error is saturated as the impedance's is
//! ([`ImpedanceGains::max_position_error`], [`ImpedanceGains::max_orientation_error`]), so a
//! far goal is approached at a bounded speed and acceleration. A figure-eight faster than
//! [`MAX_FIGURE_SPEED`] or [`MAX_FIGURE_ACCELERATION`] is refused at the start.
//!
//! A cycle the law cannot compute (counted in its report) moves the torque toward the one that
//! holds the arm; [`FAILURES_TO_BRAKE`] in a row bring it to rest.
//!
//! The torque-rate limit grows from 0 over the run's first [`SOFT_START_S`].
//!
//! Braking (a stop request, the run's duration, a fault that leaves the link working): the
//! tool's target freezes where the tool is and the arm is damped to rest; the law reports
//! [`LawStatus::AtRest`] once every joint is slower than [`REST_SPEED`] for [`REST_CYCLES`]
//! cycles.
//!
//! The device's velocities are used where it measures them; otherwise they are the measured
//! positions' differences over the period.

mod compute;
pub mod lines;
mod obstacles;

use std::f64::consts::PI;
use std::time::Instant;

use glam::{DMat3, DQuat, DVec3};
use rl_core::spatial::PlueckerTransform;
use rl_core::task::{
    ImpedanceGains, TaskData, TaskError, TaskTarget, limit_rate, operational_impedance,
};
use rl_core::{Model, algo};
use serde_json::json;

pub use compute::ComputeTimes;
use obstacles::Obstacles;
pub use obstacles::{
    MAX_ARM_CAPSULES, MAX_OBSTACLE_SPEED, MAX_OBSTACLES, MovingSphere, Obstacle,
    PREDICTION_HORIZON_S, SKELETON_RADIUS, TowardTool,
};
use rl_sg::capsule::CapsuleModel;

use super::input::Input;
use super::law::{
    BrakeReason, Command, CommandMode, Context, ControlLaw, LawError, LawStatus, LawSummary,
    Refused, Start,
};

/// Joint speed under which the arm counts as at rest, rad/s or m/s.
pub const REST_SPEED: f64 = 0.01;
/// Cycles in a row every joint must stay under [`REST_SPEED`] to be at rest.
pub const REST_CYCLES: u32 = 50;
/// Cycles in a row the law may fail to compute (e.g. a mass matrix that is not positive
/// definite) before it brakes on its own; meanwhile it moves toward the torque that holds the
/// arm.
pub const FAILURES_TO_BRAKE: u32 = 10;
/// The fastest figure-eight the law takes: peak tool speed, m/s.
pub const MAX_FIGURE_SPEED: f64 = 1.0;
/// The fastest figure-eight the law takes: peak tool acceleration, m/s² (Franka's Cartesian
/// limits are 1.7 m/s and 13 m/s²).
pub const MAX_FIGURE_ACCELERATION: f64 = 10.0;
/// Time constant of the filter between a streamed pose and the tool's target, s.
pub const STREAM_FILTER_S: f64 = 0.2;
/// Over the run's first `SOFT_START_S` the torque-rate limit grows from 0 to its value: the
/// first exchanges of a link (Franka's: before the client's cycle locks onto the robot's) may
/// lose commands, and a robot that compares each command with the last one it got would see
/// their steps add up.
pub const SOFT_START_S: f64 = 0.1;
/// Franka's torque-rate limit, N·m/s (1 N·m per ms): a larger step between two commands the
/// robot receives is a `controller_torque_discontinuity` reflex.
pub const FRANKA_TORQUE_RATE: f64 = 1000.0;
/// The law's torque-rate limit by default, N·m/s: half [`FRANKA_TORQUE_RATE`], so that after a
/// command lost on the way the next one is still within the robot's limit of the last it got.
pub const DEFAULT_TORQUE_RATE: f64 = 0.5 * FRANKA_TORQUE_RATE;

/// Where the tool goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TaskMotion {
    /// It holds the pose it had at the start.
    Hold,
    /// A figure-eight (Gerono's lemniscate) in the world's y–z plane through the start pose,
    /// `size_m` wide and `size_m / 2` high, once every `period_s`, at the start orientation;
    /// its speed ramps up smoothly over the first period (no step in velocity or
    /// acceleration).
    FigureEight {
        /// Width of the figure, m.
        size_m: f64,
        /// Time for one figure, s.
        period_s: f64,
    },
    /// It goes where [`TaskInput::Pose`] inputs say (it holds the start pose until the first).
    Streamed,
}

/// What the task-space law takes while it runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TaskInput {
    /// A new pose for the tool (with [`TaskMotion::Streamed`]), world coordinates.
    Pose(PlueckerTransform),
    /// An obstacle into slot `slot` (< [`MAX_OBSTACLES`]), or the slot cleared (`None`), for a
    /// law that avoids obstacles ([`CartesianImpedance::avoid`]).
    Obstacle {
        /// The slot.
        slot: usize,
        /// The obstacle, world coordinates.
        obstacle: Option<Obstacle>,
    },
}

/// Operational-space impedance as a [`ControlLaw`] in torque mode (module doc).
pub struct CartesianImpedance<const B: usize, const J: usize> {
    tool: usize,
    /// The tool asked for by name (resolved at the start).
    tool_name: Option<String>,
    motion: TaskMotion,
    gains: ImpedanceGains,
    torque_rate: f64,
    gravity_by_device: Option<bool>,
    task: Box<TaskData<B>>,
    dof: usize,
    period_s: f64,
    start_pose: PlueckerTransform,
    tool_pose: PlueckerTransform,
    streamed: Option<PlueckerTransform>,
    filtered: PlueckerTransform,
    filtered_velocity: [f64; 6],
    filtered_acceleration: [f64; 6],
    posture: [f64; J],
    last_position: [f64; J],
    last_torque: [f64; J],
    braking: Option<(BrakeReason, PlueckerTransform)>,
    still_cycles: u32,
    failures_in_a_row: u32,
    stats: TaskStats,
    obstacles: Box<Obstacles>,
    compute: Box<ComputeTimes>,
}

/// What the task-space law measured over a run (its report's `law` object).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TaskStats {
    /// Cycles computed.
    pub cycles: u64,
    /// The largest distance between the tool and its target, m (while not braking).
    pub task_error_max_m: f64,
    /// Sum of squared distances, for the RMS.
    task_error_sq_sum: f64,
    /// Cycles in the RMS (computed, not braking).
    task_error_cycles: u64,
    /// The largest angle between the tool's orientation and its target's, rad (not braking).
    pub orientation_error_max_rad: f64,
    /// The largest torque change per period from the torque the device applied (where it
    /// reports it, else from the last command), N·m/s.
    pub torque_rate_max: f64,
    /// Cycles in which the torque-rate limit cut a joint's torque.
    pub rate_limited_cycles: u64,
    /// Cycles with a joint inside its limit band.
    pub near_limit_cycles: u64,
    /// Cycles the law could not compute (a singular mass matrix, a non-finite state): the arm
    /// was held with the last torques less their rate.
    pub failed_cycles: u64,
    /// The first such failure.
    pub first_failure: Option<TaskError>,
    /// Pose inputs taken.
    pub poses: u64,
    /// Obstacle inputs taken.
    pub obstacle_inputs: u64,
    /// The smallest distance between the arm's capsules and an obstacle, m (∞ without any).
    pub min_obstacle_distance_m: f64,
    /// Cycles with an obstacle inside the repulsion's influence distance.
    pub repelling_cycles: u64,
    /// Cycles with an obstacle nearer than the repulsion's margin.
    pub margin_violations: u64,
}

impl TaskStats {
    /// The RMS distance between the tool and its target, m.
    pub fn task_error_rms_m(&self) -> f64 {
        if self.task_error_cycles == 0 {
            0.0
        } else {
            (self.task_error_sq_sum / self.task_error_cycles as f64).sqrt()
        }
    }
}

impl<const B: usize, const J: usize> CartesianImpedance<B, J> {
    /// The law for tool `tool` of the run's model, with the default gains
    /// ([`ImpedanceGains::default`]) and half Franka's torque-rate limit
    /// ([`DEFAULT_TORQUE_RATE`]).
    pub fn new(tool: usize, motion: TaskMotion) -> Self {
        Self {
            tool,
            tool_name: None,
            motion,
            gains: ImpedanceGains::default(),
            torque_rate: DEFAULT_TORQUE_RATE,
            gravity_by_device: None,
            task: Box::new(TaskData::new()),
            dof: 0,
            period_s: 0.001,
            start_pose: PlueckerTransform::IDENTITY,
            tool_pose: PlueckerTransform::IDENTITY,
            streamed: None,
            filtered: PlueckerTransform::IDENTITY,
            filtered_velocity: [0.0; 6],
            filtered_acceleration: [0.0; 6],
            posture: [0.0; J],
            last_position: [0.0; J],
            last_torque: [0.0; J],
            braking: None,
            still_cycles: 0,
            failures_in_a_row: 0,
            stats: TaskStats::default(),
            obstacles: Box::new(Obstacles::new()),
            compute: Box::new(ComputeTimes::new()),
        }
    }

    /// Avoids obstacles: the arm's capsules (the skeleton at [`SKELETON_RADIUS`] unless
    /// [`Self::arm_capsules`] gives them) are kept away from the obstacles streamed in
    /// ([`TaskInput::Obstacle`]), given ([`Self::obstacle`]) or scripted
    /// ([`Self::moving_sphere`]) by the repulsion of the gains ([`ImpedanceGains::repulsion`]),
    /// in the nullspace of what the priority keeps ([`ImpedanceGains::priority`]: with
    /// `OrientationFirst` the position yields, the orientation does not; with `Together` only
    /// the nullspace of the whole pose avoids).
    pub fn avoid(mut self) -> Self {
        self.obstacles.enabled = true;
        self
    }

    /// The arm's capsules, fixed to the model's bodies (e.g. [`rl_sg::fit`] fitted to its
    /// meshes); avoidance on.
    pub fn arm_capsules(mut self, capsules: CapsuleModel<MAX_ARM_CAPSULES>) -> Self {
        self.obstacles.capsules = Some(Box::new(capsules));
        self.avoid()
    }

    /// An obstacle from the start, in the first free slot (ignored when all are taken);
    /// avoidance on.
    pub fn obstacle(mut self, obstacle: Obstacle) -> Self {
        if let Some(slot) = self.obstacles.slots.iter().position(Option::is_none) {
            self.obstacles.set(slot, Some(obstacle));
        }
        self.avoid()
    }

    /// A scripted sphere coming at the tool's start position and going back; avoidance on.
    pub fn moving_sphere(mut self, sphere: TowardTool) -> Self {
        self.obstacles.script = Some(sphere);
        self.avoid()
    }

    /// The law's compute time per cycle so far (the whole of [`ControlLaw::cycle`]).
    pub fn compute_times(&self) -> &ComputeTimes {
        &self.compute
    }

    /// The law for the model's tool named `name` (resolved at the start: an error there if the
    /// model has none of that name).
    pub fn for_tool(name: &str, motion: TaskMotion) -> Self {
        let mut law = Self::new(0, motion);
        law.tool_name = Some(name.to_owned());
        law
    }

    /// The law for the model's flange ([`flange`]: the tool farthest down the chain).
    pub fn for_flange(motion: TaskMotion) -> Self {
        let mut law = Self::new(usize::MAX, motion);
        law.tool_name = None;
        law
    }

    /// Other gains.
    pub fn gains(mut self, gains: ImpedanceGains) -> Self {
        self.gains = gains;
        self
    }

    /// Whether the device adds the gravity torque itself, whatever the device says
    /// ([`Start::device_adds_gravity`], which the law follows otherwise).
    pub fn gravity_by_device(mut self, yes: bool) -> Self {
        self.gravity_by_device = Some(yes);
        self
    }

    /// Another torque-rate limit, N·m/s (`f64::INFINITY`: none).
    pub fn torque_rate(mut self, rate: f64) -> Self {
        self.torque_rate = rate;
        self
    }

    /// One step of the streamed pose's filter toward `goal`: `ẍ = ω² e − 2ω ẋ` per world
    /// direction (`e`: the position difference and the rotation vector from the target's
    /// orientation to the goal's; `ω = 1/STREAM_FILTER_S`), integrated semi-implicitly.
    fn approach(&mut self, goal: &PlueckerTransform, dt: f64) {
        let w = 1.0 / STREAM_FILTER_S;
        let f = &mut self.filtered;
        let dp = goal.translation - f.translation;
        let mut turn = DQuat::from_mat3(&goal.rotation) * DQuat::from_mat3(&f.rotation).inverse();
        if turn.w < 0.0 {
            turn = -turn;
        }
        let dr = turn.normalize().to_scaled_axis();
        // The errors saturated as the impedance's are: a far goal is approached at a bounded
        // speed and acceleration (ω·e_max/e and ω²·e_max).
        let sat = |v: DVec3, max: f64| {
            let l = v.length();
            if l > max { v * (max / l) } else { v }
        };
        let dp = sat(dp, self.gains.max_position_error);
        let dr = sat(dr, self.gains.max_orientation_error);
        let e = [dp.x, dp.y, dp.z, dr.x, dr.y, dr.z];
        let (v, a) = (&mut self.filtered_velocity, &mut self.filtered_acceleration);
        for k in 0..6 {
            a[k] = w * w * e[k] - 2.0 * w * v[k];
            v[k] += a[k] * dt;
        }
        f.translation += DVec3::new(v[0], v[1], v[2]) * dt;
        let spin = DQuat::from_scaled_axis(DVec3::new(v[3], v[4], v[5]) * dt);
        f.rotation = DMat3::from_quat((spin * DQuat::from_mat3(&f.rotation)).normalize());
    }

    /// What the law measured so far.
    pub fn stats(&self) -> &TaskStats {
        &self.stats
    }

    /// The tool's target at time `t` (s since the start).
    pub fn target_at(&self, t: f64) -> TaskTarget {
        if let Some((_, pose)) = self.braking {
            return TaskTarget::at(pose);
        }
        match self.motion {
            TaskMotion::Hold => TaskTarget::at(self.start_pose),
            TaskMotion::Streamed => TaskTarget {
                pose: self.filtered,
                velocity: self.filtered_velocity,
                acceleration: self.filtered_acceleration,
            },
            TaskMotion::FigureEight { size_m, period_s } => {
                figure_eight(&self.start_pose, size_m, period_s, t)
            }
        }
    }
}

/// The tool farthest down the kinematic chain (the most moving bodies between it and the
/// world; of those, the last): a URDF's flange or end effector rather than a sensor frame on
/// the base, which a URDF may list first.
pub fn flange<const B: usize>(model: &Model<B>) -> Option<usize> {
    let depth = |mut b: usize| {
        let mut d = 0;
        while b != rl_core::model::ROOT && d <= model.body_count() {
            d += 1;
            b = model.parent(b);
        }
        d
    };
    let tools = model.tools();
    (0..tools.len()).max_by_key(|&t| (depth(tools[t].body), t))
}

/// Gerono's lemniscate `y = a sin φ, z = (a/2) sin 2φ` (a: half the width) through `start`,
/// with `φ̇` ramping from 0 to `2π/T` over the first period along a quintic smoothstep.
fn figure_eight(start: &PlueckerTransform, size_m: f64, period_s: f64, t: f64) -> TaskTarget {
    let a = 0.5 * size_m;
    let w = 2.0 * PI / period_s;
    let ramp = period_s;
    let (phi, dphi, ddphi) = if t < ramp {
        let x = t / ramp;
        let h = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
        let dh = 30.0 * x * x * (1.0 - x) * (1.0 - x) / ramp;
        let integral = x.powi(4) * (2.5 - 3.0 * x + x * x);
        (w * ramp * integral, w * h, w * dh)
    } else {
        (w * ramp * 0.5 + w * (t - ramp), w, 0.0)
    };
    let (s1, c1) = phi.sin_cos();
    let (s2, c2) = (2.0 * phi).sin_cos();
    let p = DVec3::new(0.0, a * s1, 0.5 * a * s2);
    let v = DVec3::new(0.0, a * c1 * dphi, a * c2 * dphi);
    let acc = DVec3::new(
        0.0,
        a * (-s1 * dphi * dphi + c1 * ddphi),
        a * (-2.0 * s2 * dphi * dphi + c2 * ddphi),
    );
    TaskTarget {
        pose: PlueckerTransform::new(start.rotation, start.translation + p),
        velocity: [v.x, v.y, v.z, 0.0, 0.0, 0.0],
        acceleration: [acc.x, acc.y, acc.z, 0.0, 0.0, 0.0],
    }
}

impl<const B: usize, const J: usize> CartesianImpedance<B, J> {
    /// One cycle of the law ([`ControlLaw::cycle`] times it).
    fn compute_cycle(
        &mut self,
        cx: &mut Context<'_, B, J, TaskInput>,
        out: &mut Command<J>,
    ) -> LawStatus {
        let dof = self.dof.min(cx.dof);
        let q = cx.measured.position;
        let mut qd = [0.0; J];
        match cx.measured.velocity {
            Some(v) => qd[..dof].copy_from_slice(&v[..dof]),
            None => {
                for k in 0..dof {
                    qd[k] = (q[k] - self.last_position[k]) / cx.period_s;
                }
            }
        }
        self.last_position[..dof].copy_from_slice(&q[..dof]);
        if let Some(goal) = self.streamed {
            self.approach(&goal, cx.period_s);
        }
        let target = self.target_at(cx.time_s);
        // The arm's points nearest to the obstacles, from the world poses at `q`.
        let (near, nearest) =
            if self.obstacles.enabled && algo::forward_position(cx.model, cx.data, q).is_ok() {
                let within = self.gains.repulsion.influence;
                self.obstacles.nearest(cx.data, cx.time_s, within)
            } else {
                (0, f64::INFINITY)
            };
        // Checked when they came in: a proximity of finite obstacles is finite.
        let _ = self
            .task
            .set_proximities(&self.obstacles.proximities[..near]);
        let mut tau = [0.0; J];
        let computed = operational_impedance(
            cx.model,
            cx.data,
            &mut self.task,
            self.tool,
            &self.gains,
            &target,
            q,
            &qd[..dof],
            &self.posture[..dof],
            &mut tau[..dof],
        );
        self.stats.cycles += 1;
        match computed {
            Ok(report) => {
                self.tool_pose = report.tool_pose;
                if self.braking.is_none() {
                    let s = &mut self.stats;
                    s.task_error_max_m = s.task_error_max_m.max(report.position_error);
                    s.task_error_sq_sum += report.position_error * report.position_error;
                    s.task_error_cycles += 1;
                    s.orientation_error_max_rad =
                        s.orientation_error_max_rad.max(report.orientation_error);
                }
                if report.joints_near_limits > 0 {
                    self.stats.near_limit_cycles += 1;
                }
                let s = &mut self.stats;
                s.min_obstacle_distance_m = s.min_obstacle_distance_m.min(nearest);
                if report.repelling > 0 {
                    s.repelling_cycles += 1;
                }
                if nearest < self.gains.repulsion.margin {
                    s.margin_violations += 1;
                }
            }
            Err(e) => {
                // Toward the torque that holds the arm (gravity, unless the device adds it; the
                // rate limit below makes the way there continuous), and after
                // `FAILURES_TO_BRAKE` in a row, brake: the target freezes where the tool was.
                self.stats.failed_cycles += 1;
                self.stats.first_failure.get_or_insert(e);
                self.failures_in_a_row += 1;
                if !self.gains.gravity_by_device
                    && let Ok(g) = algo::gravity(cx.model, cx.data, q)
                    && g.iter().all(|t| t.is_finite())
                {
                    tau[..dof].copy_from_slice(&g[..dof]);
                }
                if self.failures_in_a_row >= FAILURES_TO_BRAKE && self.braking.is_none() {
                    self.brake(BrakeReason::Fault);
                }
            }
        }
        if computed.is_ok() {
            self.failures_in_a_row = 0;
        }
        let ramp = ((cx.time_s + cx.period_s) / SOFT_START_S).min(1.0);
        let step = self.torque_rate * cx.period_s * ramp;
        // The step counts from what the device applies where it says (the last command it
        // received: after commands lost on the way the next is still within its limit), else
        // from the last command sent; the two agree while nothing is lost.
        let applied = cx.measured.applied_torque.filter(|a| a.len() >= dof);
        let reference = match applied {
            Some(a) => &a[..dof],
            None => &self.last_torque[..dof],
        };
        if limit_rate(reference, &mut tau[..dof], step) > 0 {
            self.stats.rate_limited_cycles += 1;
        }
        let rate = tau[..dof]
            .iter()
            .zip(reference)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / cx.period_s;
        self.stats.torque_rate_max = self.stats.torque_rate_max.max(rate);
        self.last_torque = tau;
        out.torque = tau;
        out.position[..dof].copy_from_slice(&q[..dof]);
        out.velocity[..dof].copy_from_slice(&qd[..dof]);
        if self.braking.is_none() {
            return LawStatus::Running;
        }
        if qd[..dof].iter().all(|v| v.abs() < REST_SPEED) {
            self.still_cycles += 1;
        } else {
            self.still_cycles = 0;
        }
        if self.still_cycles >= REST_CYCLES {
            LawStatus::AtRest
        } else {
            LawStatus::Braking
        }
    }
}

impl<const B: usize, const J: usize> ControlLaw<B, J> for CartesianImpedance<B, J> {
    type Input = TaskInput;

    fn mode(&self) -> CommandMode {
        CommandMode::Torque
    }

    fn name(&self) -> &str {
        "cartesian-impedance"
    }

    fn describe(&self) -> String {
        let what = match self.motion {
            TaskMotion::Hold => "holding the tool's start pose".to_owned(),
            TaskMotion::FigureEight { size_m, period_s } => format!(
                "a figure-eight {size_m} m wide in the world's y-z plane every {period_s} s at \
                 constant orientation"
            ),
            TaskMotion::Streamed => "streamed tool poses".to_owned(),
        };
        format!(
            "operational-space impedance ({what}), posture and joint-limit avoidance in the \
             dynamically consistent nullspace, torques changing at most {} N·m/s",
            self.torque_rate
        )
    }

    fn start(&mut self, start: &Start<'_, B, J>) -> Result<(), LawError> {
        let model: &Model<B> = start.model;
        let dof = start.position.len().min(J);
        if model.nq() != model.dof() {
            return Err(TaskError::NotFixedBase {
                nq: model.nq(),
                nv: model.dof(),
            }
            .into());
        }
        if let Some(name) = &self.tool_name {
            self.tool = model.tool_index(name).ok_or_else(|| {
                let names: Vec<&str> = model.tools().iter().map(|t| t.name.as_str()).collect();
                format!("the model has no tool {name:?} (it has {names:?})")
            })?;
        } else if self.tool == usize::MAX {
            self.tool = flange(model).ok_or("the model has no tool")?;
        }
        if self.tool >= model.tools().len() {
            return Err(format!(
                "the model has {} tools: no tool {}",
                model.tools().len(),
                self.tool
            )
            .into());
        }
        if let TaskMotion::FigureEight { size_m, period_s } = self.motion {
            if !(size_m.is_finite() && size_m >= 0.0 && period_s.is_finite() && period_s > 0.0) {
                return Err(format!(
                    "a figure-eight needs a size ≥ 0 and a period > 0 (given {size_m} m, \
                     {period_s} s)"
                )
                .into());
            }
            // Half the width a, ω = 2π/T: peak speed aω (both axes), acceleration 2aω² (z).
            let (a, w) = (0.5 * size_m, 2.0 * PI / period_s);
            if a * w > MAX_FIGURE_SPEED || 2.0 * a * w * w > MAX_FIGURE_ACCELERATION {
                return Err(format!(
                    "a figure-eight {size_m} m wide every {period_s} s moves the tool at up to \
                     {:.2} m/s and {:.1} m/s²; the law takes at most {MAX_FIGURE_SPEED} m/s and \
                     {MAX_FIGURE_ACCELERATION} m/s² (a smaller figure or a longer period)",
                    a * w,
                    2.0 * a * w * w
                )
                .into());
            }
        }
        self.gains.check()?;
        if let Some(script) = &self.obstacles.script {
            script.check()?;
        }
        for o in self.obstacles.slots.iter().flatten() {
            if !o.is_valid() {
                return Err(format!(
                    "an obstacle that is not finite, has a negative radius or moves faster than \
                     {MAX_OBSTACLE_SPEED} m/s: {o:?}"
                )
                .into());
            }
        }
        if self.obstacles.enabled {
            self.obstacles.ensure_capsules(model).map_err(|e| {
                format!("the arm's skeleton needs more capsules than the law holds: {e}")
            })?;
        }
        if self.torque_rate.is_nan() || self.torque_rate <= 0.0 {
            return Err(format!(
                "the torque-rate limit must be above 0 N·m/s (given {})",
                self.torque_rate
            )
            .into());
        }
        let mut data = Box::new(rl_core::Data::<B>::new());
        algo::forward_position(model, &mut data, start.position)?;
        self.start_pose = algo::tool_pose(model, &data, self.tool)?;
        self.tool_pose = self.start_pose;
        self.gains.gravity_by_device = self.gravity_by_device.unwrap_or(start.device_adds_gravity);
        self.dof = dof;
        self.period_s = start.period_s;
        self.posture = [0.0; J];
        self.posture[..dof].copy_from_slice(&start.position[..dof]);
        self.last_position = self.posture;
        self.last_torque = [0.0; J];
        self.streamed = None;
        self.filtered = self.start_pose;
        self.filtered_velocity = [0.0; 6];
        self.filtered_acceleration = [0.0; 6];
        self.braking = None;
        self.still_cycles = 0;
        self.failures_in_a_row = 0;
        self.stats = TaskStats {
            min_obstacle_distance_m: f64::INFINITY,
            ..TaskStats::default()
        };
        self.obstacles.moving = self
            .obstacles
            .script
            .map(|s| s.sphere(self.start_pose.translation));
        self.obstacles.restart();
        self.compute.clear();
        Ok(())
    }

    fn input(&mut self, input: &Input<J, TaskInput>) -> Result<(), Refused> {
        match input {
            Input::Other(TaskInput::Pose(_)) if self.motion != TaskMotion::Streamed => {
                Err(Refused("this task does not take streamed poses"))
            }
            Input::Other(TaskInput::Pose(_)) if self.braking.is_some() => {
                Err(Refused("the arm is being brought to rest"))
            }
            Input::Other(TaskInput::Pose(p)) => {
                if !(p.translation.is_finite() && p.rotation.is_finite()) {
                    return Err(Refused("a pose that is not finite"));
                }
                let r = p.rotation;
                if !(r.transpose() * r).abs_diff_eq(DMat3::IDENTITY, 1e-6) {
                    return Err(Refused("a rotation that is not orthonormal"));
                }
                self.streamed = Some(*p);
                self.stats.poses += 1;
                Ok(())
            }
            Input::Other(TaskInput::Obstacle { .. }) if !self.obstacles.enabled => {
                Err(Refused("this law does not avoid obstacles"))
            }
            Input::Other(TaskInput::Obstacle { slot, obstacle }) => {
                if *slot >= MAX_OBSTACLES {
                    return Err(Refused("an obstacle slot beyond the law's"));
                }
                if obstacle.is_some_and(|o| !o.is_valid()) {
                    return Err(Refused(
                        "an obstacle that is not finite, has a negative radius or moves faster \
                         than MAX_OBSTACLE_SPEED",
                    ));
                }
                self.obstacles.set(*slot, *obstacle);
                self.stats.obstacle_inputs += 1;
                Ok(())
            }
            Input::Target(_) => Err(Refused("this law takes tool poses, not joint targets")),
        }
    }

    fn hold(&mut self, cx: &mut Context<'_, B, J, TaskInput>, out: &mut Command<J>) {
        // The first exchange holds the arm: gravity, unless the device adds it.
        if !self.gains.gravity_by_device
            && let Ok(g) = algo::gravity(cx.model, cx.data, cx.measured.position)
            && g.iter().all(|t| t.is_finite())
        {
            out.torque[..g.len()].copy_from_slice(g);
        }
        self.last_torque = out.torque;
    }

    fn cycle(&mut self, cx: &mut Context<'_, B, J, TaskInput>, out: &mut Command<J>) -> LawStatus {
        let began = Instant::now();
        let status = self.compute_cycle(cx, out);
        self.compute.record(began.elapsed().as_nanos() as u64);
        status
    }

    fn brake(&mut self, reason: BrakeReason) {
        // The target freezes where the tool is (at the last computed cycle).
        self.braking = Some((reason, self.tool_pose));
        self.still_cycles = 0;
    }

    fn summary(&self) -> Option<LawSummary> {
        let s = &self.stats;
        let mut lines = vec![format!(
            "cartesian impedance: tool within {:.2} mm of its target (RMS {:.2} mm), orientation \
             within {:.4} rad; torques changed at most {:.0} N·m/s, the rate limit cut {} cycles",
            s.task_error_max_m * 1e3,
            s.task_error_rms_m() * 1e3,
            s.orientation_error_max_rad,
            s.torque_rate_max,
            s.rate_limited_cycles
        )];
        let avoiding = self.obstacles.enabled;
        if avoiding {
            lines.push(format!(
                "cartesian impedance: obstacles at least {:.1} mm from the arm's capsules (margin \
                 {:.1} mm, nearer in {} cycles), repelled in {} cycles, {} obstacle inputs",
                s.min_obstacle_distance_m * 1e3,
                self.gains.repulsion.margin * 1e3,
                s.margin_violations,
                s.repelling_cycles,
                s.obstacle_inputs
            ));
        }
        let c = &self.compute;
        lines.push(format!(
            "cartesian impedance: computed in {:.1} µs per cycle (p50; p99 {:.1}, max {:.1})",
            c.quantile_us(0.5).unwrap_or(0.0),
            c.quantile_us(0.99).unwrap_or(0.0),
            c.max_us()
        ));
        if let Some(e) = s.first_failure {
            lines.push(format!(
                "cartesian impedance: {} cycles not computed, the first: {e}",
                s.failed_cycles
            ));
        }
        let min_distance = (avoiding && s.min_obstacle_distance_m.is_finite())
            .then_some(s.min_obstacle_distance_m);
        let compute_us = json!({
            "p50": c.quantile_us(0.5), "p99": c.quantile_us(0.99), "max": c.max_us(),
            "cycles": c.count(),
        });
        Some(LawSummary {
            lines,
            json: json!({
                    "law": "cartesian-impedance",
                    "cycles": s.cycles,
                    "task_error_max_m": s.task_error_max_m,
                    "task_error_rms_m": s.task_error_rms_m(),
                    "orientation_error_max_rad": s.orientation_error_max_rad,
                    "torque_rate_max": s.torque_rate_max,
                    "rate_limited_cycles": s.rate_limited_cycles,
                    "near_limit_cycles": s.near_limit_cycles,
                    "failed_cycles": s.failed_cycles,
                    "first_failure": s.first_failure.map(|e| e.to_string()),
                    "poses": s.poses,
                    "priority": format!("{:?}", self.gains.priority),
                    "obstacles": avoiding.then(|| json!({
                        "min_distance_m": min_distance,
                        "margin_m": self.gains.repulsion.margin,
                        "influence_m": self.gains.repulsion.influence,
                        "margin_violations": s.margin_violations,
                        "repelling_cycles": s.repelling_cycles,
                        "inputs": s.obstacle_inputs,
                        "arm_capsules": self.obstacles.capsules.as_ref().map(|c| c.len()),
                        "moving_sphere": self.obstacles.moving.map(|m| json!({
                            "radius_m": m.radius, "from": m.from.to_array(),
                            "to": m.to.to_array(), "period_s": m.period_s,
                        })),
                    })),
                    "compute_us": compute_us,
            }),
            headline: json!({
                "task_error_max_m": s.task_error_max_m,
                "task_error_rms_m": s.task_error_rms_m(),
                "orientation_error_max_rad": s.orientation_error_max_rad,
                "min_obstacle_distance_m": min_distance,
                "torque_rate_max": s.torque_rate_max,
                "compute_us": compute_us,
            }),
            failure: s.first_failure.map(|e| {
                format!(
                    "the task-space law could not compute {} cycles (the first: {e})",
                    s.failed_cycles
                )
            }),
        })
    }
}
