//! `rl run` (the default command): a complete real-time controller.
//!
//! On the defaults it starts a fake Mitsubishi H7 controller in this process on loopback (its
//! own non-real-time threads, as a controller on the network), loads the embedded RV-6SL,
//! opens and starts the H7 device, plans a jerk-limited tour through a few waypoints and back
//! (checked against the model's position, speed and effort limits before anything moves), and
//! runs the control loop ([`rl::controller::Controller`]) at the device's 7.11 ms period in a
//! SCHED_FIFO thread. Progress goes to standard error (a live line on a terminal, plain lines
//! otherwise); the report goes to standard output (`--json` for a script). Ctrl-C brings the
//! arm to rest along its path and stops the device cleanly; a second Ctrl-C stops at once.
//!
//! With `--plan --scene SCENE.yaml --request REQUEST.yaml` (a MoveIt planning scene and motion
//! plan request, as `rl plan` takes them) the run follows a collision-free path instead of the
//! tour: rl-plan plans it before anything is opened (bounded by `--plan-time`, Ctrl-C cancels),
//! [`rl::controller::planned`] makes it a trajectory within the model's velocity, acceleration
//! and jerk limits (blended through the path's waypoints, every sample checked for collisions,
//! then retimed near time-optimally with bounded jerk along the same configurations when that is
//! faster; `--no-retime` keeps the blends' timing, `--stop-at-waypoints` stops at each waypoint
//! instead), the
//! in-process fake stands at the request's start state (a real robot must stand there, or the
//! run refuses to start), and the report says the trajectory came from the plan.
//!
//! Exit codes: 0 done, 1 failed (device fault, limits crossed, stop failed, no path found), 2
//! bad flags or files, 130 stopped by Ctrl-C before the end.

mod plot;
mod progress;
mod view;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Args;
use rl::controller::DEFAULT_INPUT_TIMEOUT;
use rl::controller::plan::joint_name;
use rl::controller::planned::{PathExecution, PlannedMotion, PlannedMotionError, plan_motion_with};
use rl::controller::runtime::DEFAULT_SPEED;
use rl::controller::stream::{self, StreamOptions, TargetSource};
use rl::controller::task_space::{CartesianImpedance, TaskMotion, TowardTool};
use rl::controller::{
    ControlLaw, ControlRun, CycleRecord, JointRobot, Motion, RV6SL_XML, RunError, RunOptions,
    Supervision, TargetFollower, TelemetryFile, ViewHook,
};
use rl::core::task::{ImpedanceGains, Priority};
use rl::drivers::safety::StopCategory;
use rl_core::Model;
use rl_core::loader::{LoadOptions, LoadedModel};
use rl_plan::PlanOptions;
use rl_plan::problem::moveit::MotionRequest;
use rl_rt::{StopFlag, StopLevel};

use self::progress::ProgressDisplay;
use super::capacity::{self, WithModel};
use super::output::{Replacement, out, outln};
use super::plan::{CommonArgs, load_robot, options as plan_options};
use super::{CliError, CliResult, refuse_given};
use rl::devices::{self as device, DeviceSpec};

/// A positive duration: the shared [`super::parse_duration`] units, zero refused.
fn parse_duration(text: &str) -> Result<Duration, String> {
    match super::parse_duration(text)? {
        d if d.is_zero() => Err(format!("`{text}`: the duration must be positive")),
        d => Ok(d),
    }
}

/// `--rate`'s help: what it takes, from the library's range and device table.
fn rate_help() -> String {
    let (low, high) = device::RATE_HZ;
    let fixed: Vec<&str> = device::DEVICE_FORMS
        .iter()
        .filter(|f| f.fixed_period)
        .map(|f| f.form)
        .collect();
    format!(
        "Control rate in Hz, a number from {low} to {high}, at most the device's own rate; {} \
         run at their fixed cycle and refuse it [default: the device's period, listed under \
         --device]",
        fixed.join(" and ")
    )
}

/// `--speed`'s help, with the library's default.
fn speed_help() -> String {
    format!(
        "Fraction of the model's speed limits to plan with, in (0, 1] [default: {DEFAULT_SPEED}]"
    )
}

/// Rows kept in memory for the plot (older ones are thinned out when it fills).
const PLOT_ROWS: usize = 50_000;

/// Arguments of `rl run`. Every field is optional so `RunArgs::default()` is the plain `rl`.
#[derive(Args, Debug, Default)]
pub struct RunArgs {
    /// Robot model (URDF or RL XML) [default: the embedded Mitsubishi RV-6SL].
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
    // The help is the library's device table (rl::devices::DEVICE_FORMS).
    #[arg(long, value_name = "DEVICE", help = device::device_help())]
    pub device: Option<String>,
    /// Waypoints in rad (m for prismatic joints): a header row, then one row per waypoint with a
    /// column per joint in the model's order. The tour starts where the robot is and returns
    /// there [default: a tour derived from the joint limits].
    #[arg(long, value_name = "FILE.csv")]
    pub waypoints: Option<PathBuf>,
    /// Stop (at rest, along the path) after this long: e.g. 3s, 500ms, 2m.
    #[arg(long, value_parser = parse_duration)]
    pub duration: Option<Duration>,
    // The range is the library's (rl::devices::RATE_HZ).
    #[arg(long, value_name = "HZ", help = rate_help())]
    pub rate: Option<f64>,
    /// SCHED_FIFO priority of the control thread [default: 80].
    #[arg(long)]
    pub priority: Option<i32>,
    /// Pin the control thread to this CPU.
    #[arg(long)]
    pub cpu: Option<usize>,
    // The default is the library's (rl::controller::runtime::DEFAULT_SPEED), as `rl plan`'s.
    #[arg(long, value_name = "FRACTION", help = speed_help())]
    pub speed: Option<f64>,
    /// Write per-cycle telemetry as CSV: time, commanded and measured joints, feed-forward
    /// torques, wake-up latency, step time, and the run's state (running, braking, fault,
    /// stopped).
    #[arg(long, value_name = "FILE.csv")]
    pub telemetry: Option<PathBuf>,
    /// Draw joint tracking and the latency histogram as SVG.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Do not lock memory (mlockall).
    #[arg(long)]
    pub no_mlock: bool,
    /// Tracking error bound in rad (or m), one value for every joint or one per joint
    /// [default: 4 cycles at each joint's speed limit].
    #[arg(long, value_name = "RAD[,RAD...]", value_delimiter = ',')]
    pub tracking_bound: Vec<f64>,
    /// Do not end the run on faults (tracking error, bad feedback, link loss); for bench set-ups
    /// only: a real arm needs supervision.
    #[arg(long)]
    pub no_supervision: bool,
    /// Lost replies in a row that are a short loss: the arm is brought to rest along its path
    /// and the run fails [default: 3].
    #[arg(long, value_name = "N")]
    pub rest_after_lost: Option<u32>,
    /// Lost replies in a row that mean the link is dead: the run stops at once (the device's
    /// own bound is set one above) [default: 10].
    #[arg(long, value_name = "N")]
    pub stop_after_lost: Option<u32>,
    /// Units of CiA 402 drives (CANopen, EtherCAT), replacing what they report in 0x608F,
    /// 0x6091, 0x6092, 0x6076 (read from each drive otherwise; a drive that cannot give them is
    /// refused before it is enabled): cpr:N,gear:G[,feed:F][,torque:NM][,lead:M], one value
    /// for every axis or one per axis joined by `/`. The same as the address's `units=`.
    #[arg(long, value_name = "cpr:N,gear:G,…")]
    pub units: Option<String>,
    /// Longest trajectory to accept: e.g. 10m, 1h [default: 1h].
    #[arg(long, value_parser = parse_duration, value_name = "DURATION")]
    pub max_plan_duration: Option<Duration>,
    /// Follow a collision-free path planned for --scene and --request (as `rl plan` takes
    /// them) instead of the tour. Planned before anything starts; the fake robot stands at the
    /// request's start state, a real one must stand there. Needs --model URDF.
    #[arg(long, help_heading = "Planned motion")]
    pub plan: bool,
    /// MoveIt planning scene (YAML) with the obstacles.
    #[arg(long, value_name = "SCENE.yaml", help_heading = "Planned motion")]
    pub scene: Option<PathBuf>,
    /// MoveIt motion plan request (YAML) with the start state and the joint goal.
    #[arg(long, value_name = "REQUEST.yaml", help_heading = "Planned motion")]
    pub request: Option<PathBuf>,
    /// SRDF with the allowed collision pairs, for the plan and the view [default: the .srdf
    /// beside the URDF (same stem)].
    #[arg(long, value_name = "FILE", help_heading = "Planned motion")]
    pub srdf: Option<PathBuf>,
    /// Planner: rrt-connect, rrt-con-con, rrt-ext-ext, rrt-dual, rrt-goal-bias, rrt, prm
    /// [default: rrt-connect].
    #[arg(long, value_name = "NAME", help_heading = "Planned motion")]
    pub planner: Option<String>,
    /// Random seed of the planner (the same seed gives the same path) [default: 0].
    #[arg(long, value_name = "N", help_heading = "Planned motion")]
    pub seed: Option<u64>,
    /// Joint limits to plan within, replacing the model's for the joints named:
    /// JOINT=MIN:MAX[,JOINT=MIN:MAX…] in rad (m), e.g. panda_joint1=-1:1 (as `rl plan --limits`;
    /// the controller still checks the model's own limits).
    #[arg(
        long,
        value_name = "JOINT=MIN:MAX[,…]",
        help_heading = "Planned motion"
    )]
    pub limits: Option<String>,
    /// Time budget for planning, and as much again for shortening the path [default: 1s].
    #[arg(long, value_parser = parse_duration, value_name = "DURATION", help_heading = "Planned motion")]
    pub plan_time: Option<Duration>,
    /// Stop at every waypoint of the planned path, on its straight segments exactly, instead
    /// of blending through them (the default: lines and jerk-continuous blends, every sample
    /// checked for collisions, a blend that collides shrunk or replaced by a stop, then
    /// retimed with bounded jerk along the same configurations when that is faster).
    #[arg(long, help_heading = "Planned motion", conflicts_with = "no_retime")]
    pub stop_at_waypoints: bool,
    /// Keep the blended path's own timing (one speed along each line and blend) instead of
    /// retiming it near time-optimally with bounded jerk.
    #[arg(long, help_heading = "Planned motion")]
    pub no_retime: bool,
    /// Show the run live in the robot viewer's page (as `rl view`), served by this process on
    /// ADDR while the run goes; the address is printed before the run starts. Port 0 picks a
    /// free port [default ADDR: 127.0.0.1:8080].
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    pub view: Option<std::net::SocketAddr>,
    /// With --view: keep serving the page after the report, until Ctrl-C.
    #[arg(long, requires = "view")]
    pub view_hold: bool,
    /// Follow streamed targets instead of a tour: `-` (standard input), `udp:PORT` (on
    /// loopback), `udp:HOST:PORT`, or `zenoh` (the cell's `joint_trajectory` topic; needs
    /// --zenoh or --zenoh-listen). One target per line: `position q1 … qn [velocity v1 … vn]`,
    /// `velocity v1 … vn` or `stop` (rl::controller::stream documents the format). Each target
    /// is reached along a time-optimal jerk-limited motion from where the arm is going; every
    /// stop brakes along the time-optimal jerk-limited profile. The end of standard input
    /// brings the arm to rest and ends the run.
    #[arg(long, value_name = "SOURCE", value_parser = parse_follow, help_heading = "Streamed targets")]
    pub follow: Option<Follow>,
    /// With --follow: when no target came for this long, bring the arm to rest and end the
    /// run (a failure) [default: 2s].
    #[arg(long, value_parser = parse_duration, value_name = "DURATION", requires = "follow", help_heading = "Streamed targets")]
    pub input_timeout: Option<Duration>,
    /// Run a task-space law instead of a tour: `cartesian-impedance` (operational-space
    /// impedance of the model's first tool, torque control; the device must take joint
    /// torques, e.g. franka://HOST). The tool does what --task says.
    #[arg(
        long,
        value_name = "LAW",
        value_enum,
        help_heading = "Task-space control"
    )]
    pub law: Option<LawArg>,
    /// With --law: `figure-eight` (a figure-eight in the world's y-z plane through the tool's
    /// start, --task-size wide, once every --task-period, at constant orientation) or `hold`
    /// (the start pose) [default: hold].
    #[arg(
        long,
        value_name = "TASK",
        value_enum,
        requires = "law",
        help_heading = "Task-space control"
    )]
    pub task: Option<TaskArg>,
    /// With --task figure-eight: its width, m [default: 0.2].
    #[arg(
        long,
        value_name = "M",
        requires = "law",
        help_heading = "Task-space control"
    )]
    pub task_size: Option<f64>,
    /// With --task figure-eight: the time for one figure [default: 4s].
    #[arg(long, value_parser = parse_duration, value_name = "DURATION", requires = "law", help_heading = "Task-space control")]
    pub task_period: Option<Duration>,
    /// With --law: obstacles to avoid: `moving-sphere` (a sphere of 8 cm radius that comes
    /// horizontally at the tool's start position from 55 cm beyond it to 15 cm of it and goes
    /// back, every --obstacle-period), `zenoh` (the cell's obstacle poses, spheres of
    /// --obstacle-radius; needs --zenoh or --zenoh-listen), or a stream of them: a FILE, `-`
    /// (standard input) or `udp:PORT` / `udp:HOST:PORT`, one per line: `sphere SLOT x y z r
    /// [velocity vx vy vz]`,
    /// `capsule SLOT ax ay az bx by bz r [velocity …]`, `clear SLOT`, each maybe after `at
    /// SECONDS` (from the stream's start: a recorded file replays in time); world coordinates,
    /// m (rl::controller::task_space documents the lines). The stream's end leaves the last
    /// obstacles in place. The arm's links are capsules around its skeleton; the repulsion
    /// keeps them --obstacle-margin away while the orientation holds (see --task-priority).
    #[arg(
        long,
        value_name = "OBSTACLE",
        value_parser = parse_obstacle,
        requires = "law",
        help_heading = "Task-space control"
    )]
    pub obstacle: Option<ObstacleArg>,
    /// With --obstacle zenoh: the radius of the sphere each obstacle pose stands for, m
    /// [default: 0.1].
    #[arg(
        long,
        value_name = "M",
        requires = "obstacle",
        help_heading = "Task-space control"
    )]
    pub obstacle_radius: Option<f64>,
    /// With --obstacle moving-sphere: the time it takes to come and go back [default: 8s].
    #[arg(long, value_parser = parse_duration, value_name = "DURATION", requires = "obstacle", help_heading = "Task-space control")]
    pub obstacle_period: Option<Duration>,
    /// With --obstacle: the distance the repulsion keeps between the arm and an obstacle, m
    /// [default: 0.05]; it acts from 0.15 m farther.
    #[arg(
        long,
        value_name = "M",
        requires = "obstacle",
        help_heading = "Task-space control"
    )]
    pub obstacle_margin: Option<f64>,
    /// With --law: which part of the task yields when not all can be met: `orientation-first`
    /// (the orientation first, the position in its nullspace beside the obstacles' repulsion,
    /// the posture last) or `together` (the whole pose as one task; obstacles and posture in its
    /// nullspace) [default: orientation-first with --obstacle, else together].
    #[arg(
        long,
        value_name = "PRIORITY",
        value_enum,
        requires = "law",
        help_heading = "Task-space control"
    )]
    pub task_priority: Option<PriorityArg>,
    /// With --law: the tool the task moves, by name [default: the model's tool farthest down
    /// the chain, e.g. the FR3's link8 flange].
    #[arg(
        long,
        value_name = "NAME",
        requires = "law",
        help_heading = "Task-space control"
    )]
    pub tool: Option<String>,
    /// The rotor inertia of each joint's drive reflected to the joint (kg·m², kg for a
    /// prismatic joint), which URDF has no field for: added to the model's mass matrix
    /// (rl-core's `Model::set_armature`) for every law that uses the dynamics. One value for
    /// all joints, or one per joint (franky-sim's FR3: 0.195,0.195,0.195,0.195,0.074,0.074,0.074).
    #[arg(long, value_name = "KG_M2[,…]", value_parser = crate::cli::parse_per_joint)]
    pub armature: Option<crate::cli::PerJointArg>,
    /// The joints' viscous friction (N·m·s/rad), which URDF's `<dynamics damping>` may give and
    /// rl-core does not read from it: the task-space law compensates it at the measured
    /// speed. One value for all joints, or one per joint (franky-sim's FR3: 0.21).
    #[arg(long, value_name = "NMS[,…]", value_parser = crate::cli::parse_per_joint)]
    pub joint_damping: Option<crate::cli::PerJointArg>,
    /// The joints' dry (Coulomb) friction (N·m), compensated by the task-space law as
    /// `f·tanh(q̇ / 0.05 rad/s)`. One value for all joints, or one per joint (franky-sim's FR3:
    /// 1.137,1.137,1.137,1.137,0.763,0.44,0.248).
    #[arg(long, value_name = "NM[,…]", value_parser = crate::cli::parse_per_joint)]
    pub joint_friction: Option<crate::cli::PerJointArg>,
    /// With --law: the task's stiffness in 1/s² (per unit of the arm's operational inertia,
    /// so the same whatever it carries), the position's and, after a comma, the
    /// orientation's [default: 400,300]; critically damped.
    #[arg(
        long,
        value_name = "K[,K_ROT]",
        requires = "law",
        value_parser = parse_stiffness,
        help_heading = "Task-space control"
    )]
    pub task_stiffness: Option<(f64, f64)>,
    /// The emergency-stop input, a GPIO line CHIP:OFFSET (e.g. gpiochip0:17), normally closed:
    /// it reads high while the chain is closed; low (pressed, or a broken wire) stops the arm.
    /// The run does not start with it open; a stop latches: closing it again restarts nothing.
    #[arg(long, value_name = "CHIP:OFFSET", help_heading = "Safety chain (GPIO)")]
    pub estop: Option<GpioLineArg>,
    /// The enable (dead-man) input: high while held; released stops the arm.
    #[arg(
        long,
        value_name = "CHIP:OFFSET",
        requires = "estop",
        help_heading = "Safety chain (GPIO)"
    )]
    pub enable: Option<GpioLineArg>,
    /// The watchdog output, toggled every cycle (a charge pump for an external relay that drops
    /// when the loop stops or stalls).
    #[arg(
        long,
        value_name = "CHIP:OFFSET",
        requires = "estop",
        help_heading = "Safety chain (GPIO)"
    )]
    pub watchdog: Option<GpioLineArg>,
    /// The brake or contactor output: high (energised) only while the chain allows motion.
    #[arg(
        long,
        value_name = "CHIP:OFFSET",
        requires = "estop",
        help_heading = "Safety chain (GPIO)"
    )]
    pub brake: Option<GpioLineArg>,
    /// Stop category on an open chain: 0 (remove power at once) or 1 (bring the arm to rest
    /// along its path, then remove power) [default: 0].
    #[arg(long, value_name = "0|1", value_parser = parse_category, requires = "estop", help_heading = "Safety chain (GPIO)")]
    pub stop_category: Option<StopCategory>,
    /// Join a cell over Zenoh (src/cli/cell.rs).
    #[command(flatten)]
    pub zenoh: super::cell::ZenohArgs,
}

/// A GPIO line flag's value.
#[cfg(feature = "gpio")]
pub type GpioLineArg = rl::controller::safety::gpio::GpioLine;
/// A GPIO line flag's value (this build has no GPIO support: refused when given).
#[cfg(not(feature = "gpio"))]
pub type GpioLineArg = String;

/// `--task-stiffness K[,K_ROT]`: finite, positive; one value sets both.
fn parse_stiffness(text: &str) -> Result<(f64, f64), String> {
    let mut values = text.split(',').map(|v| match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!(
            "`{}` is not a stiffness: expected a number > 0 in 1/s²",
            v.trim()
        )),
    });
    let k = values.next().unwrap_or(Ok(0.0))?;
    let k_rot = values.next().transpose()?.unwrap_or(k);
    if values.next().is_some() {
        return Err(format!("`{text}`: at most two stiffnesses (K,K_ROT)"));
    }
    Ok((k, k_rot))
}

/// `--stop-category`'s value.
fn parse_category(text: &str) -> Result<StopCategory, String> {
    match text {
        "0" => Ok(StopCategory::Zero),
        "1" => Ok(StopCategory::One),
        _ => Err(format!(
            "'{text}': give 0 (at once) or 1 (brought to rest first)"
        )),
    }
}

/// The safety chain the flags describe, its lines requested (before anything starts).
#[cfg(feature = "gpio")]
fn safety_chain(args: &RunArgs) -> Result<Option<rl::controller::safety::SafetyHandle>, CliError> {
    use rl::controller::safety::gpio::GpioChain;
    let Some(estop) = &args.estop else {
        return Ok(None);
    };
    let mut chain = GpioChain::new(estop.clone());
    chain.enable = args.enable.clone();
    chain.watchdog = args.watchdog.clone();
    chain.brake = args.brake.clone();
    chain.category = args.stop_category.unwrap_or_default();
    chain
        .open()
        .map(Some)
        .map_err(|e| CliError::failed(format!("--estop: {e} (nothing was started)")))
}

/// Without GPIO support: the flags are refused.
#[cfg(not(feature = "gpio"))]
fn safety_chain(args: &RunArgs) -> Result<Option<rl::controller::safety::SafetyHandle>, CliError> {
    match args.estop {
        Some(_) => Err(CliError::usage(
            "--estop: this build has no GPIO support (feature gpio)",
        )),
        None => Ok(None),
    }
}

/// Where `--follow` takes its targets from.
#[derive(Clone, Debug)]
pub enum Follow {
    /// Text lines from standard input or a UDP socket.
    Lines(TargetSource),
    /// The cell's streamed targets (Zenoh).
    Cell,
}

/// `--law`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LawArg {
    /// Operational-space impedance (rl::controller::task_space::CartesianImpedance).
    CartesianImpedance,
}

/// `--task`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TaskArg {
    /// A figure-eight through the start pose.
    FigureEight,
    /// The start pose, held.
    Hold,
}

/// `--obstacle zenoh`: the radius of the sphere an obstacle pose stands for, m (a hand or a
/// forearm with a tracker's error).
const DEFAULT_OBSTACLE_RADIUS: f64 = 0.1;

/// `--obstacle`'s values.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ObstacleArg {
    /// A sphere coming at the tool and going back.
    MovingSphere,
    /// Obstacle lines from standard input or a UDP socket.
    Lines(TargetSource),
    /// Obstacle lines from a file.
    File(PathBuf),
    /// The cell's obstacle poses (`--zenoh`), spheres of `--obstacle-radius`.
    Cell,
}

/// `--obstacle`'s value: `moving-sphere`, a stream source (`-`, `stdin`, `udp:…`) or a file.
fn parse_obstacle(text: &str) -> Result<ObstacleArg, String> {
    if text == "moving-sphere" {
        return Ok(ObstacleArg::MovingSphere);
    }
    if text == "zenoh" {
        return Ok(ObstacleArg::Cell);
    }
    let is_source = text == "-"
        || text.eq_ignore_ascii_case("stdin")
        || text
            .get(..4)
            .is_some_and(|p| p.eq_ignore_ascii_case("udp:"));
    if is_source {
        return text
            .parse()
            .map(ObstacleArg::Lines)
            .map_err(|e: stream::SourceError| e.to_string());
    }
    if text.is_empty() {
        return Err("give `moving-sphere`, a file, `-` or `udp:PORT`".into());
    }
    Ok(ObstacleArg::File(PathBuf::from(text)))
}

/// `--task-priority`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PriorityArg {
    /// The orientation, then the position, then the posture.
    OrientationFirst,
    /// The pose as one task, then the posture.
    Together,
}

/// The task-space law `--law` asks for.
fn task_law<const B: usize, const J: usize>(args: &RunArgs) -> CartesianImpedance<B, J> {
    let motion = match args.task.unwrap_or(TaskArg::Hold) {
        TaskArg::Hold => TaskMotion::Hold,
        TaskArg::FigureEight => TaskMotion::FigureEight {
            size_m: args.task_size.unwrap_or(0.2),
            period_s: args.task_period.map_or(4.0, |d| d.as_secs_f64()),
        },
    };
    let default = if args.obstacle.is_some() {
        PriorityArg::OrientationFirst
    } else {
        PriorityArg::Together
    };
    let mut gains = ImpedanceGains {
        priority: match args.task_priority.unwrap_or(default) {
            PriorityArg::OrientationFirst => Priority::OrientationFirst,
            PriorityArg::Together => Priority::Together,
        },
        ..ImpedanceGains::default()
    };
    if let Some((k, k_rot)) = args.task_stiffness {
        gains.stiffness = [k, k, k, k_rot, k_rot, k_rot];
    }
    if let Some(margin) = args.obstacle_margin {
        // The repulsion's reach moves with the margin.
        let reach = gains.repulsion.influence - gains.repulsion.margin;
        gains.repulsion.margin = margin;
        gains.repulsion.influence = margin + reach;
    }
    let law = match &args.tool {
        Some(name) => CartesianImpedance::for_tool(name, motion),
        None => CartesianImpedance::for_flange(motion),
    }
    .gains(gains);
    match args.obstacle {
        Some(ObstacleArg::Lines(_) | ObstacleArg::File(_) | ObstacleArg::Cell) => law.avoid(),
        Some(ObstacleArg::MovingSphere) => law.moving_sphere(TowardTool {
            period_s: args
                .obstacle_period
                .map_or(TowardTool::default().period_s, |d| d.as_secs_f64()),
            ..TowardTool::default()
        }),
        None => law,
    }
}

/// `--follow`'s value.
fn parse_follow(text: &str) -> Result<Follow, String> {
    if text == "zenoh" {
        return Ok(Follow::Cell);
    }
    text.parse()
        .map(Follow::Lines)
        .map_err(|e| format!("{e}; or `zenoh` for the cell's targets"))
}

/// The planning problem of `--plan`, checked before anything starts.
struct PlanSetup {
    urdf: PathBuf,
    scene: PathBuf,
    request: PathBuf,
    common: CommonArgs,
    options: PlanOptions,
    execution: PathExecution,
}

/// Flags and files checked before anything starts.
struct Setup {
    device: DeviceSpec,
    period: Option<Duration>,
    telemetry: Option<TelemetryFile>,
    plan: Option<PlanSetup>,
}

/// Runs `rl run`.
pub fn run(args: RunArgs) -> CliResult {
    let setup = check(&args)?;
    // SIGINT/SIGTERM: the first brings the arm to rest along its path, the second stops at
    // once (rl-rt's two-level stop; no signal handler runs).
    let stop = StopFlag::new();
    stop.raise_on_termination_signals()
        .map_err(|e| CliError::failed(format!("cannot watch SIGINT/SIGTERM: {e}")))?;
    // The model goes into the tool's one capacity choice (src/cli/capacity.rs), the smallest
    // that holds it; the controller, its planner and its telemetry take that capacity for both
    // bodies and joints.
    let options = LoadOptions::default();
    match &args.model {
        None => {
            let job = Drive {
                args: &args,
                setup,
                stop,
                name: None,
            };
            capacity::load_text("the embedded RV-6SL", RV6SL_XML, &options, job)
        }
        Some(path) => {
            let job = Drive {
                args: &args,
                setup,
                stop,
                name: Some(path),
            };
            capacity::load_for("--model", path, &options, job)
        }
    }
}

/// The run, for a model in whichever capacity holds it.
struct Drive<'a> {
    args: &'a RunArgs,
    setup: Setup,
    stop: StopFlag,
    /// The file, or `None` for the embedded model.
    name: Option<&'a Path>,
}

impl WithModel for Drive<'_> {
    type Output = ExitCode;

    fn run<const N: usize>(self, mut loaded: Box<LoadedModel<N>>) -> CliResult {
        for w in &loaded.warnings {
            eprintln!("rl run: warning: {w}");
        }
        let dof = loaded.model.dof();
        if let Some(a) = &self.args.armature {
            let values = a.per_dof("--armature", dof).map_err(CliError::usage)?;
            loaded
                .model
                .set_armature(&values)
                .map_err(|e| CliError::usage(format!("--armature: {e}")))?;
        }
        if self.args.joint_damping.is_some() || self.args.joint_friction.is_some() {
            let zero = crate::cli::PerJointArg(vec![0.0]);
            let d = self.args.joint_damping.as_ref().unwrap_or(&zero);
            let f = self.args.joint_friction.as_ref().unwrap_or(&zero);
            let d = d.per_dof("--joint-damping", dof).map_err(CliError::usage)?;
            let f = f
                .per_dof("--joint-friction", dof)
                .map_err(CliError::usage)?;
            loaded
                .model
                .set_joint_friction(&d, &f)
                .map_err(|e| CliError::usage(format!("--joint-damping/--joint-friction: {e}")))?;
        }
        let name = match self.name {
            None => "Mitsubishi RV-6SL (embedded)".to_owned(),
            Some(path) => model_name(&loaded.model, path),
        };
        drive::<N, N>(self.args, self.setup, *loaded, name, self.stop)
    }
}

fn model_name<const B: usize>(model: &Model<B>, path: &Path) -> String {
    if model.name().is_empty() {
        path.display().to_string()
    } else {
        format!("{} ({})", model.name(), path.display())
    }
}

/// Validates flags and files (exit code 2 for anything wrong) before anything starts.
fn check(args: &RunArgs) -> Result<Setup, CliError> {
    let mut device = DeviceSpec::parse(args.device.as_deref().unwrap_or("fake-h7"))?;
    if let Some(text) = &args.units {
        let spec = device::UnitsSpec::parse(text).map_err(|e| CliError::usage(format!("--{e}")))?;
        device.set_units(spec)?;
    }
    if args.no_supervision {
        refuse_given(
            &["tracking-bound", "rest-after-lost"],
            "with --no-supervision: no fault is acted on",
        )?;
    }
    let rest = args
        .rest_after_lost
        .unwrap_or(Supervision::default().rest_after_lost);
    let stop = args
        .stop_after_lost
        .unwrap_or(Supervision::default().max_consecutive_lost);
    if rest == 0 || stop < rest || stop > 10_000 {
        return Err(CliError::usage(format!(
            "--rest-after-lost {rest} --stop-after-lost {stop}: give 1 ≤ rest ≤ stop ≤ 10000 \
             lost replies in a row"
        )));
    }
    let period = args
        .rate
        .map(|hz| device.period_for_rate(hz))
        .transpose()
        .map_err(|e| CliError::usage(format!("--rate {}", e.message())))?;
    if let Some(s) = args.speed {
        if !(s > 0.0 && s <= 1.0) {
            return Err(CliError::usage(format!(
                "--speed {s}: give a fraction of the model's speed limits above 0 and at most 1"
            )));
        }
    }
    if let Some(bad) = args
        .tracking_bound
        .iter()
        .find(|b| !(b.is_finite() && **b > 0.0))
    {
        return Err(CliError::usage(format!(
            "--tracking-bound {bad}: give positive bounds in rad (or m)"
        )));
    }
    if let Some(path) = &args.plot {
        check_writable(path).map_err(|e| CliError::usage(format!("--plot: {e}")))?;
    }
    args.zenoh.check()?;
    if args.follow.is_some() {
        refuse_given(
            &["waypoints", "plan"],
            "with --follow: the run follows streamed targets, not a tour or a planned path",
        )?;
    }
    if args.law.is_some() {
        refuse_given(
            &["waypoints", "plan", "follow"],
            "with --law: the run's law is the task-space one, not a tour, a planned path or \
             streamed joint targets",
        )?;
        if args.task_size.is_some_and(|s| !(s.is_finite() && s >= 0.0)) {
            return Err(CliError::usage("--task-size: give a width in m, 0 or more"));
        }
        if args.task_period.is_some_and(|p| p.is_zero()) {
            return Err(CliError::usage("--task-period: give a time above 0"));
        }
        if args
            .obstacle_radius
            .is_some_and(|r| !(r.is_finite() && r >= 0.0))
        {
            return Err(CliError::usage(
                "--obstacle-radius: give a radius in m, 0 or more",
            ));
        }
        if args.obstacle_radius.is_some() && args.obstacle != Some(ObstacleArg::Cell) {
            return Err(CliError::usage(
                "--obstacle-radius is for --obstacle zenoh (obstacle lines carry their radius)",
            ));
        }
        if let Some(ObstacleArg::File(path)) = &args.obstacle {
            // Before anything connects; the stream opens it once the run runs.
            let readable = std::fs::metadata(path).and_then(|m| {
                if m.is_file() {
                    std::fs::File::open(path).map(drop)
                } else {
                    Err(std::io::Error::other("not a file"))
                }
            });
            if let Err(e) = readable {
                return Err(CliError::usage(format!(
                    "--obstacle {}: {e} (give moving-sphere, zenoh, -, udp:PORT or a file of \
                     obstacle lines)",
                    path.display()
                )));
            }
        }
        if args.obstacle_period.is_some() && args.obstacle != Some(ObstacleArg::MovingSphere) {
            return Err(CliError::usage(
                "--obstacle-period is for --obstacle moving-sphere (a stream's lines carry \
                 their own times)",
            ));
        }
        if args.obstacle == Some(ObstacleArg::Cell) && !args.zenoh.wanted() {
            return Err(CliError::usage(
                "--obstacle zenoh takes the cell's obstacles: add --zenoh ENDPOINT or \
                 --zenoh-listen ENDPOINT",
            ));
        }
    }
    if matches!(args.follow, Some(Follow::Cell)) && !args.zenoh.wanted() {
        return Err(CliError::usage(
            "--follow zenoh takes the cell's targets: add --zenoh ENDPOINT or --zenoh-listen \
             ENDPOINT",
        ));
    }
    Ok(Setup {
        device,
        period,
        telemetry: None,
        plan: check_plan(args)?,
    })
}

/// The `--plan` flags: all or none, and not with `--waypoints`.
fn check_plan(args: &RunArgs) -> Result<Option<PlanSetup>, CliError> {
    let given: Vec<&str> = [
        ("--scene", args.scene.is_some()),
        ("--request", args.request.is_some()),
        // The SRDF's allowed pairs serve the view too.
        ("--srdf", args.srdf.is_some() && args.view.is_none()),
        ("--planner", args.planner.is_some()),
        ("--seed", args.seed.is_some()),
        ("--plan-time", args.plan_time.is_some()),
        ("--limits", args.limits.is_some()),
        ("--stop-at-waypoints", args.stop_at_waypoints),
        ("--no-retime", args.no_retime),
    ]
    .iter()
    .filter(|(_, on)| *on)
    .map(|(flag, _)| *flag)
    .collect();
    if args.model.is_none() {
        refuse_given(
            &["srdf"],
            "to the embedded RV-6SL, which has no SRDF: give --model ROBOT.urdf",
        )?;
    }
    if !args.plan {
        return match given.first() {
            Some(flag) => Err(CliError::usage(format!(
                "{flag} describes a planned motion: add --plan"
            ))),
            None => Ok(None),
        };
    }
    let (Some(scene), Some(request)) = (&args.scene, &args.request) else {
        return Err(CliError::usage(
            "--plan needs --scene SCENE.yaml and --request REQUEST.yaml (a MoveIt planning \
             scene and motion plan request)",
        ));
    };
    let Some(urdf) = &args.model else {
        return Err(CliError::usage(
            "--plan needs --model ROBOT.urdf: the embedded RV-6SL has no collision geometry",
        ));
    };
    if args.waypoints.is_some() {
        return Err(CliError::usage(
            "--plan and --waypoints: the run follows either the planned path or a tour",
        ));
    }
    let mut common = CommonArgs {
        srdf: args.srdf.clone(),
        limits: args.limits.clone(),
        ..CommonArgs::default()
    };
    if let Some(p) = &args.planner {
        common.planner = p.clone();
    }
    if let Some(seed) = args.seed {
        common.seed = seed;
    }
    if let Some(t) = args.plan_time {
        common.plan_time = t;
    }
    let options = plan_options(&common)?;
    Ok(Some(PlanSetup {
        urdf: urdf.clone(),
        scene: scene.clone(),
        request: request.clone(),
        common,
        options,
        execution: if args.stop_at_waypoints {
            PathExecution::StopAtWaypoints
        } else if args.no_retime {
            PathExecution::Blended
        } else {
            PathExecution::Retimed
        },
    }))
}

/// A motion planned for `--plan`, with the request's start and goal.
struct RunPlan<const J: usize> {
    planned: PlannedMotion<J>,
    start: Vec<f64>,
    goal: Vec<f64>,
}

/// Plans the motion of `--plan` for `model` (the run's model, loaded from the same URDF), before
/// anything is opened. `Ok(None)`: cancelled by a stop request.
fn plan_for_run<const B: usize, const J: usize>(
    setup: &PlanSetup,
    model: &Model<B>,
    speed: f64,
    stop: &StopFlag,
) -> Result<Option<RunPlan<J>>, CliError> {
    let robot = load_robot(&setup.urdf, &setup.common)?;
    let scene = rl_sg::load::moveit::load_environment(&setup.scene)
        .map_err(|e| CliError::usage(format!("--scene: {e}")))?;
    let request = MotionRequest::load(&setup.request)
        .map_err(|e| CliError::usage(format!("--request: {e}")))?;
    let (start, goal) = request
        .configurations(&robot.space)
        .map_err(|e| CliError::usage(format!("--request {}: {e}", setup.request.display())))?;
    let mut checker = robot
        .hybrid_checker(&scene)
        .map_err(|e| CliError::failed(format!("--plan: collision checker: {e}")))?;
    eprintln!(
        "rl run: planning a collision-free path with {} (seed {}, {:?} budget) before starting, \
         to be executed {}",
        setup.common.planner, setup.common.seed, setup.common.plan_time, setup.execution
    );
    match plan_motion_with::<B, J>(
        model,
        &robot.space,
        &mut checker,
        &start,
        &goal,
        &setup.options,
        speed,
        Some(stop),
        setup.execution,
    ) {
        Ok(planned) => Ok(Some(RunPlan {
            planned,
            start,
            goal,
        })),
        Err(PlannedMotionError::Cancelled) => Ok(None),
        Err(e) => {
            // For a start or goal in collision, name what touches (exact meshes).
            let touching = match &e {
                PlannedMotionError::Planner(rl_plan::PlanError::InvalidEndpoint {
                    which, ..
                }) => {
                    let q = if *which == "start" { &start } else { &goal };
                    drop(checker);
                    robot
                        .exact_checker(scene)
                        .map(|mut exact| exact.collisions(q))
                        .unwrap_or_default()
                }
                _ => Vec::new(),
            };
            let touching = if touching.is_empty() {
                String::new()
            } else {
                let pairs: Vec<String> = touching
                    .iter()
                    .take(6)
                    .map(|(a, b)| format!("{a} ↔ {b}"))
                    .collect();
                format!(
                    "; touching: {}{}",
                    pairs.join(", "),
                    if touching.len() > 6 { ", …" } else { "" }
                )
            };
            Err(CliError::failed(format!(
                "refusing to move: {e}{touching} (nothing was started)"
            )))
        }
    }
}

/// Checks that `path` can be written without touching it: its directory takes a new file.
fn check_writable(path: &Path) -> Result<(), String> {
    Replacement::create(path)
        .map(drop)
        .map_err(|e| format!("cannot create {}: {e}", path.display()))
}

/// Builds the device, runs the controller through the library's [`ControlRun`], writes
/// telemetry and progress while it runs, and prints the report.
fn drive<const B: usize, const J: usize>(
    args: &RunArgs,
    mut setup: Setup,
    loaded: LoadedModel<B>,
    model_name: String,
    stop: StopFlag,
) -> CliResult {
    let model = &loaded.model;
    let joints: Vec<String> = (0..model.dof()).map(|k| joint_name(model, k)).collect();
    let waypoints = match &args.waypoints {
        None => None,
        Some(path) => Some(read_waypoints(path, model)?),
    };
    if let Some(path) = &args.telemetry {
        setup.telemetry = Some(TelemetryFile::create(path, &joints).map_err(|e| {
            CliError::usage(format!(
                "--telemetry: cannot create {}: {e}",
                path.display()
            ))
        })?);
    }
    let speed = args.speed.unwrap_or(DEFAULT_SPEED);
    let mut plan_json = None;
    let mut plan_note = None;
    let (motion, home) = match &setup.plan {
        None => (Motion::Tour, None),
        Some(p) => {
            let Some(RunPlan {
                planned,
                start,
                goal,
            }) = plan_for_run::<B, J>(p, model, speed, &stop)?
            else {
                eprintln!("rl run: {}", RunError::Cancelled);
                return Ok(ExitCode::from(130));
            };
            let r = &planned.result;
            plan_note = Some(format!(
                "plan: solved by {} in {:.1} µs ({} iterations, {} collision checks), path {:.3} \
                 rad shortened to {:.3} rad in {:.1} µs, {} waypoints, trajectory {:.2} s {} \
                 (stopping at every waypoint: {:.2} s), {}",
                r.planner,
                r.planning_time.as_secs_f64() * 1e6,
                r.iterations,
                r.planning_checks,
                r.length_before,
                r.length_after,
                r.optimization_time.as_secs_f64() * 1e6,
                planned.waypoints.len(),
                planned.duration_s,
                planned.execution,
                planned.stop_duration_s,
                match &planned.certificate {
                    Some(c) => format!(
                        "certified on the meshes ({} steps{})",
                        c.steps,
                        match planned.refused.len() {
                            0 => String::new(),
                            n => format!(", after {n} seed(s) refused"),
                        }
                    ),
                    None => "not certified (the checker has no exact geometry)".to_owned(),
                }
            ));
            plan_json = Some(serde_json::json!({
                "solved": r.solved,
                "planner": r.planner,
                // The seed of the path followed (seeds whose paths were not certified are
                // skipped: "seeds_refused").
                "seed": p.common.seed.wrapping_add(planned.refused.len() as u64),
                "scene": p.scene.display().to_string(),
                "request": p.request.display().to_string(),
                "planning_time_us": r.planning_time.as_secs_f64() * 1e6,
                "optimization_time_us": r.optimization_time.as_secs_f64() * 1e6,
                "iterations": r.iterations,
                "collision_checks": r.planning_checks,
                "optimization_collision_checks": r.optimization_checks,
                "length_before": r.length_before,
                "length_after": r.length_after,
                "start": start,
                "goal": goal,
                "waypoints": planned.waypoints,
                "trajectory_duration_s": planned.duration_s,
                "execution": match planned.execution {
                    PathExecution::Retimed => "retimed",
                    PathExecution::Blended => "blended",
                    PathExecution::StopAtWaypoints => "stop-at-waypoints",
                },
                "stop_at_waypoints_duration_s": planned.stop_duration_s,
                "blended_duration_s": planned.blended_duration_s,
                "retimed_duration_s": planned.retimed.as_ref().and_then(|r| r.as_ref().ok()),
                "not_retimed_because": planned.retimed.as_ref().and_then(|r| r.as_ref().err()),
                "blend": planned.blend.as_ref().map(|b| serde_json::json!({
                    "interior_waypoints": b.waypoints.len(),
                    "blended": b.blended(),
                    "shrunk": b.shrunk(),
                    "stopped": b.stopped(),
                    "stopped_for_collision": b.stopped_for_collision(),
                    "collision_checks": b.checks,
                    "check_step": b.check_step,
                })),
                "certified": planned.certificate.as_ref().map(|c| serde_json::json!({
                    "steps": c.steps,
                    "min_distance": c.min_distance,
                })),
                "seeds_refused": planned.refused.iter().map(|(seed, why)| serde_json::json!({
                    "seed": seed,
                    "reason": why,
                })).collect::<Vec<_>>(),
            }));
            (planned.motion, Some(start))
        }
    };
    let mut supervision = Supervision::default();
    if args.no_supervision {
        supervision.enabled = false;
    }
    if let Some(n) = args.rest_after_lost {
        supervision.rest_after_lost = n;
    }
    if let Some(n) = args.stop_after_lost {
        supervision.max_consecutive_lost = n;
    }
    // The safety chain's lines first: a line that cannot be requested starts nothing.
    let safety = safety_chain(args)?;
    let opened = setup.device.build(
        &loaded,
        setup.period,
        home.as_deref(),
        supervision.device_failure_limit(),
        args.law.is_some(),
    )?;
    let fake = opened.fake;
    let cycle = opened.robot.update_period();
    supervision.allow_device_lag(opened.lag, setup.period.map_or(cycle, |p| p.max(cycle)));
    let period = setup.period.unwrap_or_else(|| opened.robot.update_period());
    let cell = super::cell::RunCell::<J>::open(
        &args.zenoh,
        model,
        period,
        &stop,
        matches!(args.follow, Some(Follow::Cell)),
        matches!(args.obstacle, Some(ObstacleArg::Cell)),
    )?;
    if !args.tracking_bound.is_empty() {
        supervision.tracking_error = match args.tracking_bound.as_slice() {
            [one] => vec![*one; joints.len()],
            many if many.len() == joints.len() => many.to_vec(),
            many => {
                return Err(CliError::usage(format!(
                    "--tracking-bound: {} values for {} joints (give one, or one per joint)",
                    many.len(),
                    joints.len()
                )));
            }
        };
    }
    let mut options = RunOptions {
        waypoints,
        duration: args.duration,
        period: setup.period,
        cpus: args.cpu.into_iter().collect(),
        lock_memory: !args.no_mlock,
        supervision,
        telemetry: setup.telemetry.is_some() || args.plot.is_some() || cell.is_some(),
        stop: stop.clone(),
        model_name,
        device_name: opened.name,
        safety,
        ..RunOptions::default()
    };
    if let Some(s) = args.speed {
        options.speed = s;
    }
    if let Some(p) = args.priority {
        options.priority = p;
    }
    if let Some(d) = args.max_plan_duration {
        options.max_plan_duration = d;
    }
    let view = view::start(args)?;
    options.view = view.clone();
    let robot: Box<dyn JointRobot + Send> = opened.robot;
    let refused = |e: RunError| match e {
        RunError::Cancelled => {
            eprintln!("rl run: {e}");
            Ok(ExitCode::from(130))
        }
        RunError::Options(why) => Err(CliError::usage(why)),
        e => Err(CliError::failed(setup.device.explain(&e))),
    };
    if args.law.is_some() {
        // A file of obstacles is opened before anything moves.
        let file = match &args.obstacle {
            Some(ObstacleArg::File(path)) => Some(
                std::fs::File::open(path)
                    .map(|f| (path.display().to_string(), std::io::BufReader::new(f)))
                    .map_err(|e| CliError::usage(format!("--obstacle {}: {e}", path.display())))?,
            ),
            _ => None,
        };
        let run = match ControlRun::<_, B, J, _>::start_law(
            robot,
            loaded,
            options,
            task_law::<B, J>(args),
        ) {
            Ok(run) => run,
            Err(e) => return refused(e),
        };
        let obstacles = StreamOptions {
            role: "obstacles",
            rest_at_end: false,
            targets: false,
        };
        let dof = joints.len();
        let spawned = match (&args.obstacle, file) {
            (_, Some((name, file))) => Some(stream::spawn_reader_with(
                file,
                &name,
                dof,
                run.inputs(),
                stop.clone(),
                obstacles,
            )),
            (Some(ObstacleArg::Lines(source)), None) => Some(stream::spawn_with(
                source,
                dof,
                run.inputs(),
                stop.clone(),
                obstacles,
            )),
            _ => None,
        };
        let stream = match spawned {
            Some(Ok(handle)) => {
                if let Some(addr) = handle.local_addr() {
                    eprintln!("rl run: taking obstacles sent to udp:{addr}");
                }
                Some(handle)
            }
            Some(Err(e)) => {
                // The run is started: bring it to rest and report why.
                stop.request(StopLevel::Now);
                eprintln!("rl run: --obstacle: {e}");
                None
            }
            None => None,
        };
        if let (Some(ObstacleArg::Cell), Some(c)) = (&args.obstacle, &cell) {
            c.take_obstacles(
                run.inputs(),
                args.obstacle_radius.unwrap_or(DEFAULT_OBSTACLE_RADIUS),
            );
        }
        let after = After {
            cell,
            view,
            fake,
            plan_note,
            plan_json,
            stream,
        };
        return supervise(args, setup, run, after, &stop);
    }
    if let Some(follow) = &args.follow {
        if options.input_timeout.is_none() {
            options.input_timeout = Some(args.input_timeout.unwrap_or(DEFAULT_INPUT_TIMEOUT));
        }
        let run = match ControlRun::<_, B, J, _>::start_law(
            robot,
            loaded,
            options,
            TargetFollower::<J>::new(),
        ) {
            Ok(run) => run,
            Err(e) => return refused(e),
        };
        let stream = match follow {
            Follow::Lines(source) => {
                match stream::spawn(source, joints.len(), run.inputs(), stop.clone()) {
                    Ok(handle) => {
                        if let Some(addr) = handle.local_addr() {
                            eprintln!("rl run: following targets sent to udp:{addr}");
                        }
                        Some(handle)
                    }
                    Err(e) => {
                        // The run is started: bring it to rest and report why.
                        stop.request(StopLevel::Now);
                        eprintln!("rl run: --follow {source}: {e}");
                        None
                    }
                }
            }
            Follow::Cell => {
                if let Some(c) = &cell {
                    c.take_targets(run.inputs());
                }
                None
            }
        };
        let after = After {
            cell,
            view,
            fake,
            plan_note,
            plan_json,
            stream,
        };
        return supervise(args, setup, run, after, &stop);
    }
    let run = match ControlRun::<_, B, J>::start_with(robot, loaded, options, motion) {
        Ok(run) => run,
        Err(e) => return refused(e),
    };
    let after = After {
        cell,
        view,
        fake,
        plan_note,
        plan_json,
        stream: None,
    };
    supervise(args, setup, run, after, &stop)
}

/// What a run carries besides the run itself until its report is printed.
struct After<const J: usize> {
    cell: Option<super::cell::RunCell<J>>,
    view: Option<ViewHook>,
    fake: Option<device::InProcessFake>,
    plan_note: Option<String>,
    plan_json: Option<serde_json::Value>,
    stream: Option<stream::StreamHandle>,
}

/// Writes telemetry and progress while `run` goes, then completes and prints its report.
fn supervise<const B: usize, const J: usize, L: ControlLaw<B, J> + 'static>(
    args: &RunArgs,
    mut setup: Setup,
    mut run: ControlRun<Box<dyn JointRobot + Send>, B, J, L>,
    after: After<J>,
    stop: &StopFlag,
) -> CliResult {
    let After {
        mut cell,
        view,
        fake,
        plan_note,
        plan_json,
        stream,
    } = after;
    for warning in run.warnings() {
        eprintln!("rl run: warning: {warning}");
    }
    view::running(&view);

    // This (non-real-time) thread writes telemetry and shows progress while the loop runs.
    let mut display = ProgressDisplay::new(run.plan_duration_s());
    let mut plot_rows: Vec<CycleRecord<J>> = Vec::new();
    let mut stride = 1u64;
    let want_plot = args.plot.is_some();
    let mut sink = |r: &CycleRecord<J>| {
        if let Some(file) = &mut setup.telemetry {
            file.write(r);
        }
        if let Some(c) = &cell {
            c.forward(r);
        }
        if want_plot && r.cycle % stride == 0 {
            if plot_rows.len() >= PLOT_ROWS {
                stride *= 2;
                plot_rows.retain(|r| r.cycle % stride == 0);
            }
            if r.cycle % stride == 0 {
                plot_rows.push(*r);
            }
        }
    };
    let started = Instant::now();
    let mut told = StopLevel::None;
    // A cell gets the records within a few milliseconds.
    let poll = Duration::from_millis(if args.zenoh.wanted() { 2 } else { 50 });
    while let Some(p) = run.poll(poll) {
        run.drain_telemetry(&mut sink);
        if let Some(c) = &cell {
            c.progress(&p);
        }
        display.update(&p, started.elapsed());
        let level = stop.level();
        if level > told {
            told = level;
            match level {
                StopLevel::Rest => eprintln!(
                    "\nrl run: stopping: bringing the arm to rest along its path (Ctrl-C again \
                     to stop at once)"
                ),
                StopLevel::Now => eprintln!("\nrl run: stopping at once"),
                StopLevel::None => {}
            }
        }
    }
    let mut report = run.join_with(&mut sink);
    display.finish();
    let cell_json = cell.take().map(|c| c.finish(&mut report));
    if let Some(file) = setup.telemetry.take() {
        match file.finish() {
            Ok(rows) => report.telemetry_rows = Some(rows),
            Err(e) => report.fail(format!("telemetry: {e}")),
        }
    }
    if let Some(note) = plan_note {
        report.notes.insert(0, note);
    }
    // The end of standard input or a `stop` line ends a followed run as asked: that stop is
    // the run's normal end, not an interruption.
    let mut ended_by_stream = false;
    let stream_json = stream.map(|handle| {
        let seen = handle.finish();
        report.notes.extend(seen.lines_for_report());
        ended_by_stream = (seen.ended_by_eof && seen.rest_at_end) || seen.stops > 0;
        (seen.role, seen.to_json())
    });
    let fake_json = fake.as_ref().map(|fake| {
        let seen = fake.after_run(report.shutdown.stopped);
        report.notes.push(seen.note);
        report.peer_lateness = seen.lateness;
        if let Err(why) = seen.safe {
            report.fail(why);
        }
        seen.json
    });
    drop(fake);
    view::ended(&view, &report);
    if let Some(path) = &args.plot {
        if let Err(e) = draw_plot(path, &report, &plot_rows) {
            eprintln!("rl run: warning: cannot draw {}: {e}", path.display());
        }
    }
    let printed = if args.json {
        let mut json = report.to_json();
        if let (Some(obj), Some(serde_json::Value::Object(seen))) =
            (json.as_object_mut(), fake_json)
        {
            obj.extend(seen);
        }
        if let (Some(obj), Some(plan)) = (json.as_object_mut(), plan_json) {
            obj.insert("plan".into(), plan);
        }
        if let (Some(obj), Some(cell)) = (json.as_object_mut(), cell_json) {
            obj.insert("zenoh".into(), cell);
        }
        if let (Some(obj), Some((role, seen))) = (json.as_object_mut(), stream_json) {
            obj.insert(role.into(), seen);
        }
        rl::json::tag("run", 1, &mut json);
        outln!("{json}")
    } else {
        out!("{report}")
    };
    // A closed standard output ends quietly with the run's own status.
    printed.or_else(|e| if e.is_closed_output() { Ok(()) } else { Err(e) })?;
    view::hold(view, args.view_hold, stop);
    let code = if ended_by_stream
        && report.end == Some(rl::controller::RunEnd::Stopped)
        && report.failure.is_none()
    {
        0
    } else {
        report.exit_code()
    };
    Ok(ExitCode::from(code as u8))
}

/// Draws the plot next to `path` and moves it into place once drawn.
fn draw_plot<const J: usize>(
    path: &Path,
    report: &rl::controller::RunReport,
    rows: &[CycleRecord<J>],
) -> Result<(), String> {
    if rows.is_empty() {
        return Err("no cycles to draw".into());
    }
    let file = Replacement::create(path).map_err(|e| e.to_string())?;
    plot::draw(file.partial(), report, rows)?;
    file.commit().map_err(|e| e.to_string())
}

/// Reads waypoints: a header row, then one row per waypoint, one column per joint (rad or m);
/// `#` starts a comment. Each waypoint must lie within the model's position limits.
fn read_waypoints<const B: usize>(
    path: &Path,
    model: &Model<B>,
) -> Result<Vec<Vec<f64>>, CliError> {
    let shown = path.display();
    let usage = |m: String| CliError::usage(format!("--waypoints {shown}{m}"));
    // Read within the loaders' size limit (a FIFO or a device is refused unread).
    let max = rl_core::loader::InputLimits::DEFAULT.max_bytes;
    let bytes = rl_core::loader::read_bytes(path, max)
        .map_err(|e| usage(format!(": cannot read: {}", e.kind)))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(bytes.as_slice());
    let headers = reader
        .headers()
        .map_err(|e| usage(format!(":1: bad header row: {e}")))?
        .clone();
    let dof = model.dof();
    if headers.len() != dof {
        return Err(usage(format!(
            ":1: {} columns, the model has {dof} joints (one column per joint, in the model's order)",
            headers.len()
        )));
    }
    let mut points = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, csv::Position::line);
            usage(format!(":{line}: {e}"))
        })?;
        let line = record.position().map_or(0, csv::Position::line);
        let mut q = Vec::with_capacity(dof);
        for (k, field) in record.iter().enumerate() {
            let v: f64 = field
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| {
                    usage(format!(
                        ":{line}: column `{}`: `{field}` is not a finite number",
                        headers.get(k).unwrap_or("?")
                    ))
                })?;
            let l = model.limits(k);
            if !l.contains(v) {
                return Err(usage(format!(
                    ":{line}: joint {} at {v} is outside its limits [{}, {}]",
                    joint_name(model, k),
                    l.lower,
                    l.upper
                )));
            }
            q.push(v);
        }
        points.push(q);
    }
    if points.is_empty() {
        return Err(usage(": no waypoints after the header row".into()));
    }
    if points.len() > rl::controller::MAX_WAYPOINTS {
        return Err(usage(format!(
            ": {} waypoints, at most {} are supported",
            points.len(),
            rl::controller::MAX_WAYPOINTS
        )));
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn task_stiffness_is_one_or_two_positive_numbers() {
        assert_eq!(parse_stiffness("2500"), Ok((2500.0, 2500.0)));
        assert_eq!(parse_stiffness("900, 400"), Ok((900.0, 400.0)));
        for bad in ["0", "-1", "x", "1,2,3", "inf", ""] {
            assert!(parse_stiffness(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn durations_parse_with_units() {
        assert_eq!(parse_duration("3s"), Ok(Duration::from_secs(3)));
        assert_eq!(parse_duration("500ms"), Ok(Duration::from_millis(500)));
        assert_eq!(parse_duration("1.5"), Ok(Duration::from_millis(1500)));
        assert!(parse_duration("0s").is_err());
        assert!(parse_duration("3 parsecs").is_err());
    }
}
