//! The control law a supervised run executes: one trait, [`ControlLaw`], called once per cycle
//! inside the runtime's real-time loop.
//!
//! Each cycle the runtime reads the device, supervises the feedback (limits, jumps, tracking,
//! link, timing), takes the inputs other threads sent ([`input`](super::input)), and then
//! calls [`ControlLaw::cycle`] with a [`Context`]: the cycle's index and time, the measured
//! state (positions; velocities and torques where the device measures them), the model and its
//! [`Data`] workspace, and the inputs. The law writes a [`Command`] — joint positions,
//! velocities or torques, whichever its [`CommandMode`] says, for a device that takes them —
//! and says whether it goes on ([`LawStatus`]). The runtime checks the command (a position
//! or reference step within the speed limit, velocities within the speed limits, torques
//! clamped to the model's effort limits, nothing that is not a number), sends it and steps the
//! device. Start-up checks, supervision, the two-level stop, telemetry and the report stay the
//! runtime's.
//!
//! Stopping goes through the law: a stop request (Ctrl-C), the end of the run's duration, a
//! fault that leaves the link working, or inputs that stopped coming call
//! [`ControlLaw::brake`] once with a [`BrakeReason`]; the law brings the arm to rest its own
//! way and reports [`LawStatus::AtRest`], which ends the run. A law that has not come to rest
//! within the run's braking bound is ended at once ([`RunEnd::BrakeTimeout`]). A second stop
//! request ends the run at once without asking the law.
//!
//! [`TrajectoryFollower`](super::TrajectoryFollower) (a checked trajectory with inverse-dynamics
//! feed-forward: what `rl run` executes) is one implementation. A law of one's own:
//!
//! ```
//! use std::f64::consts::PI;
//! use rl::controller::law::{BrakeReason, Command, Context, ControlLaw, LawError, LawStatus, Start};
//!
//! /// Swings the first joint by up to 0.2 rad from where it started; braking fades the swing
//! /// out over one second.
//! struct Swing { home: f64, braking_s: Option<f64> }
//!
//! impl ControlLaw<16, 8> for Swing {
//!     type Input = ();
//!     fn start(&mut self, start: &Start<'_, 16, 8>) -> Result<(), LawError> {
//!         self.home = start.position[0];
//!         Ok(())
//!     }
//!     fn cycle(&mut self, cx: &mut Context<'_, 16, 8, ()>, out: &mut Command<8>) -> LawStatus {
//!         if let Some(s) = &mut self.braking_s { *s += cx.period_s; }
//!         let s = self.braking_s.map_or(0.0, |s| s.min(1.0));
//!         let fade = 0.5 * (1.0 + (PI * s).cos());
//!         out.position[0] = self.home + fade * 0.1 * (1.0 - (PI * cx.time_s).cos());
//!         match self.braking_s {
//!             None => LawStatus::Running,
//!             Some(_) if s < 1.0 => LawStatus::Braking,
//!             Some(_) => LawStatus::AtRest,
//!         }
//!     }
//!     fn brake(&mut self, _reason: BrakeReason) {
//!         self.braking_s.get_or_insert(0.0);
//!     }
//! }
//! # let _ = Swing { home: 0.0, braking_s: None };
//! ```
//!
//! (`examples/own_law.rs` runs a complete one against the fake H7.) Everything a law does in
//! [`cycle`](ControlLaw::cycle) runs on the real-time thread: it must not allocate, lock, block
//! or panic; the runtime's own part of the cycle allocates nothing and takes no lock.
//!
//! [`RunEnd::BrakeTimeout`]: super::RunEnd::BrakeTimeout

use core::fmt;

use rl_core::{Data, Model};

use super::input::{Input, Inputs};
use super::plan::MotionLimits;

/// What a law commands; fixed for a run and checked against the device before it starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CommandMode {
    /// Joint positions (rl-drivers' `JointPositionActuator`), with feed-forward torques for a
    /// device that takes them.
    #[default]
    Position,
    /// Joint velocities (`JointVelocityActuator`), with feed-forward torques for a device
    /// that takes them.
    Velocity,
    /// Joint torques (`JointTorqueActuator`).
    Torque,
}

impl fmt::Display for CommandMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Position => "position",
            Self::Velocity => "velocity",
            Self::Torque => "torque",
        })
    }
}

/// One cycle's command, for up to `J` joints (the first `dof` are used). Before each call of
/// [`ControlLaw::cycle`] the runtime fills it to hold the arm: `position` is the last commanded
/// position (or reference), `velocity` and `torque` are zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Command<const J: usize> {
    /// [`CommandMode::Position`]: the position to command, rad or m. Other modes: the reference
    /// position the arm should be at, which the supervisor checks the tracking error against
    /// and the telemetry records (a law without one sets the measured position).
    pub position: [f64; J],
    /// [`CommandMode::Velocity`]: the velocity to command, rad/s or m/s (within the speed
    /// limits). Otherwise informative.
    pub velocity: [f64; J],
    /// [`CommandMode::Torque`]: the torque to command, N·m or N (clamped to the model's effort
    /// limits). In the other modes: feed-forward torques, sent to a device that takes them.
    pub torque: [f64; J],
}

impl<const J: usize> Command<J> {
    /// A command holding `position` with zero velocity and torque.
    pub const fn hold(position: [f64; J]) -> Self {
        Self {
            position,
            velocity: [0.0; J],
            torque: [0.0; J],
        }
    }
}

/// What the law says after a cycle.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LawStatus {
    /// A command was written; the run goes on.
    Running,
    /// A command was written, and the law is bringing the arm to rest (asked to, or on its
    /// own, e.g. the trajectory follower's duration limit).
    Braking,
    /// The law's motion is over with the arm at rest (a trajectory's end): no command this
    /// cycle; the run ends.
    Completed,
    /// After braking, the arm is at rest: no command this cycle; the run ends. (The last
    /// command stays with the device until it is stopped: a velocity law reports this once
    /// it has commanded zero.)
    AtRest,
}

impl LawStatus {
    /// Whether the run ends with this status.
    pub fn is_over(self) -> bool {
        matches!(self, Self::Completed | Self::AtRest)
    }
}

/// Why the runtime asks the law to bring the arm to rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BrakeReason {
    /// A stop was requested (Ctrl-C, [`StopFlag`](rl_rt::StopFlag)).
    Requested,
    /// The run's duration is over.
    Duration,
    /// The supervisor found a fault that leaves the link working.
    Fault,
    /// No input came for longer than the run's input timeout.
    InputsStale,
}

impl fmt::Display for BrakeReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Requested => "stop requested",
            Self::Duration => "duration reached",
            Self::Fault => "fault",
            Self::InputsStale => "inputs stale",
        })
    }
}

/// Why a law refused an input ([`ControlLaw::input`]): counted, and the first reason is
/// reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Refused(pub &'static str);

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.0)
    }
}

/// Why a law refused to start ([`ControlLaw::start`], before the device is switched on).
pub type LawError = Box<dyn std::error::Error + Send + Sync>;

/// What a law knows before the device starts ([`ControlLaw::start`]).
#[derive(Clone, Copy, Debug)]
pub struct Start<'a, const B: usize, const J: usize> {
    /// Where the arm stands (measured, `dof` values), rad or m.
    pub position: &'a [f64],
    /// The model.
    pub model: &'a Model<B>,
    /// Speed, acceleration and jerk limits at the run's speed fraction (and the model's speed
    /// limits, or the speed assumed where it gives none).
    pub limits: &'a MotionLimits<J>,
    /// The control period, s.
    pub period_s: f64,
    /// The device's cycle, s.
    pub device_period_s: f64,
    /// The device adds the gravity torque to the torques it is given (rl-drivers'
    /// `JointTorqueActuator::adds_gravity`, e.g. a Franka arm): a torque law leaves it out.
    pub device_adds_gravity: bool,
}

/// The measured state of one cycle (`dof` values each).
#[derive(Clone, Copy, Debug)]
pub struct Measured<'a> {
    /// Joint positions, rad or m (the device's last reply).
    pub position: &'a [f64],
    /// Joint velocities, rad/s or m/s, where the device measures them.
    pub velocity: Option<&'a [f64]>,
    /// Joint torques, N·m or N, where the device measures them.
    pub torque: Option<&'a [f64]>,
    /// The torque command the device applies, as it reports it (the last it received; a
    /// Franka arm's `tau_J_d`, without gravity), where it does
    /// ([`JointTorqueActuator::applied_joint_torque`](rl_drivers::JointTorqueActuator::applied_joint_torque)).
    pub applied_torque: Option<&'a [f64]>,
    /// Whether the last step brought a fresh reply (otherwise the values are the last ones).
    pub fresh: bool,
}

/// What one cycle gives the law: for a model of up to `B` bodies and `J` joints, with inputs
/// of type `X` besides targets.
pub struct Context<'a, const B: usize, const J: usize, X> {
    /// Cycles run before this one.
    pub cycle: u64,
    /// Time of this cycle since the loop started, s: `cycle · period_s` (a late wake-up does
    /// not make a cycle longer).
    pub time_s: f64,
    /// The control period, s.
    pub period_s: f64,
    /// Joints.
    pub dof: usize,
    /// The measured state.
    pub measured: Measured<'a>,
    /// What was commanded for this cycle (the position, or the reference), `dof` values.
    pub commanded: &'a [f64],
    /// The model.
    pub model: &'a Model<B>,
    /// The model's workspace, for kinematics and dynamics (RNEA, ABA, Jacobians, ...).
    pub data: &'a mut Data<B>,
    /// Targets and other inputs sent while the run goes, with their ages.
    pub inputs: &'a Inputs<J, X>,
    /// Why the arm is being brought to rest, once [`ControlLaw::brake`] was called.
    pub braking: Option<BrakeReason>,
}

/// A control law in the supervised runtime, for a model of up to `B` bodies and `J` joints.
///
/// Only [`cycle`](Self::cycle) and [`brake`](Self::brake) must be written; the rest have
/// defaults. [`cycle`](Self::cycle) and [`input`](Self::input) run on the real-time thread.
pub trait ControlLaw<const B: usize, const J: usize>: Send {
    /// Inputs besides targets that the law takes while it runs (e.g. obstacle spheres); `()`
    /// for none. Sent through the run's [`InputSender`](super::input::InputSender).
    type Input: Copy + Send + 'static;

    /// What the law commands (checked against the device before it starts).
    fn mode(&self) -> CommandMode {
        CommandMode::Position
    }

    /// A short tag for the report (`trajectory_source`), e.g. `"tour"`.
    fn name(&self) -> &str {
        "law"
    }

    /// One line for the report (off the real-time thread).
    fn describe(&self) -> String {
        String::new()
    }

    /// Prepares the law before the device starts (off the real-time thread; may allocate).
    /// An error refuses the run: nothing moves.
    fn start(&mut self, start: &Start<'_, B, J>) -> Result<(), LawError> {
        let _ = start;
        Ok(())
    }

    /// Takes an input another thread sent, in order of arrival, before the cycle that
    /// follows it; a refusal is counted and the input is not seen by
    /// [`Context::inputs`]. Real-time thread.
    fn input(&mut self, input: &Input<J, Self::Input>) -> Result<(), Refused> {
        let _ = input;
        Ok(())
    }

    /// The command of the device's first exchange, right after it is switched on and before
    /// the loop: the arm must stay where it stands. `out` comes prefilled with the start
    /// position, zero velocity and zero torque, which is the default; a torque law on a device
    /// that does not compensate gravity itself writes the torque that holds the arm (e.g.
    /// `RNEA(q, 0, 0)`). `cx` is the state the device reported when it was switched on.
    fn hold(&mut self, cx: &mut Context<'_, B, J, Self::Input>, out: &mut Command<J>) {
        let _ = (cx, out);
    }

    /// One cycle: writes the command into `out` (prefilled to hold the arm) and says whether
    /// the run goes on. Real-time thread: no allocation, no lock, no panic.
    fn cycle(&mut self, cx: &mut Context<'_, B, J, Self::Input>, out: &mut Command<J>)
    -> LawStatus;

    /// Begin bringing the arm to rest, for `reason` (called once per run); the law then
    /// returns [`LawStatus::Braking`] until it reports [`LawStatus::AtRest`]. Real-time
    /// thread.
    fn brake(&mut self, reason: BrakeReason);

    /// The run must end after `cycles` cycles (its duration). `true`: the law arranges to be
    /// at rest on the last of them itself (as the trajectory follower does); `false` (the
    /// default): the runtime calls [`brake`](Self::brake) with [`BrakeReason::Duration`]
    /// when they are over, and the run ends once the law is at rest.
    fn limit_cycles(&mut self, cycles: u64) -> bool {
        let _ = cycles;
        false
    }

    /// The law's own time of the current cycle, s, for telemetry and progress (the
    /// trajectory follower's trajectory time, which slows down while it brakes); `None`: the
    /// run's time.
    fn time_s(&self) -> Option<f64> {
        None
    }

    /// How long the law's motion lasts if it knows (a trajectory's duration), s.
    fn duration_s(&self) -> Option<f64> {
        None
    }

    /// What the law has to say in the run's report, after the run (off the real-time thread):
    /// lines for its notes and an object for its JSON's `law` key. `None` (the default):
    /// nothing.
    fn summary(&self) -> Option<LawSummary> {
        None
    }
}

/// What a law says in the run's report ([`ControlLaw::summary`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LawSummary {
    /// Lines for the report's notes.
    pub lines: Vec<String>,
    /// An object for the JSON report's `law` key.
    pub json: serde_json::Value,
    /// The law's headline results, an object whose keys go to the top of the JSON report too
    /// (e.g. the task-space law's `task_error_max_m`); a key the report has of its own keeps
    /// the report's value. `Null`: none.
    pub headline: serde_json::Value,
    /// The law's own failure, if it had one (e.g. cycles it could not compute): the run fails
    /// with it (exit 1) unless it failed already.
    pub failure: Option<String>,
}
