//! The whole program `rl run` is, as a library: [`ControlRun`] opens the device, checks the
//! model against it, reads where the arm stands, plans and checks the motion (or has the
//! user's [`ControlLaw`] prepare itself) — all before the device is started (servo on), in
//! bounded time, cancellable — then starts the device, checks the first reply, and runs the
//! supervised [`Controller`](super::Controller) with the law in a real-time thread on absolute deadlines. While it
//! runs the caller reads progress, drains telemetry and sends the law inputs
//! ([`ControlRun::inputs`]); [`ControlRun::join`] ends it, brings the device to a safe state
//! (from a fault too) and returns the [`RunReport`].
//!
//! The run is three phases, one file each: the checks and the plan before anything moves
//! (`prepare.rs`), the real-time thread's body (`rt_loop.rs`: the device's start, the phase
//! lock to a device on its own cycle, one controller cycle per period, telemetry, progress),
//! and the report after it (`finish.rs`: the device stopped and closed, the numbers gathered).
//!
//! Stopping is two-level, through rl-rt's [`StopFlag`]: the first request has the law bring the
//! arm to rest (the trajectory follower: along its path), the second ends the run at once. The
//! real-time set-up is best effort (rl-rt's own fallback): without the right to SCHED_FIFO or
//! to lock memory the run goes on at normal priority and the report says what was refused and
//! how to fix it.
//!
//! ```no_run
//! use std::time::Duration;
//! use rl::controller::{ControlRun, RunOptions, rv6sl};
//! use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
//! use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
//!
//! let options = RunOptions::default().duration(Duration::from_secs(3));
//! options.stop.raise_on_termination_signals()?; // Ctrl-C: come to rest; twice: stop now
//! let fake = FakeH7::spawn(FakeH7Config::loopback(6))?;
//! let robot = MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr()))?;
//! let mut run = ControlRun::<_, 16, 8>::start(robot, rv6sl()?, options)?;
//! while let Some(p) = run.poll(Duration::from_millis(500)) {
//!     eprintln!("t {:.2} s, tracking error {:.4} rad", p.time_s, p.error_max_rad);
//! }
//! let report = run.join();
//! println!("{report}");
//! std::process::exit(report.exit_code());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod finish;
mod prepare;
mod rt_loop;

use std::fmt;
use std::time::{Duration, Instant};

use rl_core::loader::LoadedModel;
use rl_drivers::Error as DeviceError;
use rl_rt::exchange::{MailboxReader, QueueReceiver};
use rl_rt::{RtThread, StopFlag, StopLevel, ThreadError};

use super::control::DEFAULT_MAX_BRAKING;
use super::follower::TrajectoryFollower;
use super::input::{self, InputSender};
use super::law::ControlLaw;
use super::plan::{DEFAULT_MAX_PLAN_DURATION, Motion, PlanError};
use super::report::RunReport;
use super::robot::JointRobot;
use super::supervise::Supervision;
use super::telemetry::CycleRecord;

use self::prepare::Prepared;
use self::rt_loop::LoopOutcome;

/// Default real-time priority of the control thread.
pub const DEFAULT_PRIORITY: i32 = 80;
/// Default fraction of the model's speed limits a trajectory uses: the one default of `rl run
/// --speed`, `rl plan --speed` (its `--trajectory`) and the Python `ControlRun`.
pub const DEFAULT_SPEED: f64 = 0.25;
/// Bytes of telemetry records the queue holds (the caller drains it while the loop runs).
pub const TELEMETRY_BYTES: usize = 4 << 20;

/// How to run: what `rl run` takes as flags, with its defaults.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Fraction of the model's speed limits to plan with, in (0, 1].
    pub speed: f64,
    /// Waypoints (one per row, a value per joint); `None`: a tour derived from the limits.
    pub waypoints: Option<Vec<Vec<f64>>>,
    /// Stop after this long: the trajectory follower is at rest on its path by then; another
    /// law is asked to brake then ([`ControlLaw::limit_cycles`]) and the run ends once it is
    /// at rest.
    pub duration: Option<Duration>,
    /// Control period; `None`: the device's update period.
    pub period: Option<Duration>,
    /// SCHED_FIFO priority of the control thread.
    pub priority: i32,
    /// CPUs to pin the control thread to (empty: any).
    pub cpus: Vec<usize>,
    /// Lock memory (mlockall) before the loop.
    pub lock_memory: bool,
    /// What the loop checks each cycle.
    pub supervision: Supervision,
    /// The longest trajectory accepted.
    pub max_plan_duration: Duration,
    /// For a device that runs its own cycle: how far ahead of its tick the loop wakes, as a
    /// fraction of the period (room for wake-up jitter before the command must be there).
    pub phase_target: f64,
    /// Keep per-cycle records for [`ControlRun::drain_telemetry`].
    pub telemetry: bool,
    /// The two-level stop: raise it (e.g. from signals) to come to rest, twice to stop now;
    /// also cancels planning.
    pub stop: StopFlag,
    /// Name of the model for the report.
    pub model_name: String,
    /// Name of the device for the report.
    pub device_name: String,
    /// Inputs the run's queue holds ([`ControlRun::inputs`]).
    pub input_capacity: usize,
    /// Bring the arm to rest (through the law) once no input has come for this long, counted
    /// from the loop's start until the first input; the run then ends with
    /// [`RunEnd::InputsStale`](super::RunEnd::InputsStale). `None`: inputs never go stale.
    pub input_timeout: Option<Duration>,
    /// End the run at once if the law has not come to rest this long after braking began.
    pub max_braking: Duration,
    /// Show the motion in this viewer: the loop publishes every cycle's measured and
    /// commanded positions through its lock-free mailbox (feature `view`).
    #[cfg(feature = "view")]
    pub view: Option<super::view::ViewHook>,
    /// The controller's safety chain (e-stop, enable, brake, watchdog pins), armed before the
    /// device starts and checked every cycle ([`super::safety`]); `None`: none.
    pub safety: Option<super::safety::SafetyHandle>,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            speed: DEFAULT_SPEED,
            waypoints: None,
            duration: None,
            period: None,
            priority: DEFAULT_PRIORITY,
            cpus: Vec::new(),
            lock_memory: true,
            supervision: Supervision::default(),
            max_plan_duration: DEFAULT_MAX_PLAN_DURATION,
            phase_target: 0.3,
            telemetry: false,
            stop: StopFlag::new(),
            model_name: String::new(),
            device_name: String::new(),
            input_capacity: input::DEFAULT_CAPACITY,
            input_timeout: None,
            max_braking: DEFAULT_MAX_BRAKING,
            #[cfg(feature = "view")]
            view: None,
            safety: None,
        }
    }
}

impl RunOptions {
    /// Stops, at rest, after `duration`.
    pub fn duration(mut self, duration: Duration) -> Self {
        self.duration = Some(duration);
        self
    }

    /// Plans with `fraction` of the model's speed limits.
    pub fn speed(mut self, fraction: f64) -> Self {
        self.speed = fraction;
        self
    }

    /// Uses this stop flag (shared with whoever raises it).
    pub fn stop_flag(mut self, stop: &StopFlag) -> Self {
        self.stop = stop.clone();
        self
    }

    /// Keeps per-cycle records for [`ControlRun::drain_telemetry`].
    pub fn telemetry(mut self, on: bool) -> Self {
        self.telemetry = on;
        self
    }

    /// Brings the arm to rest once no input has come for `timeout`.
    pub fn input_timeout(mut self, timeout: Duration) -> Self {
        self.input_timeout = Some(timeout);
        self
    }
}

/// Why a run did not start. Nothing moved; the device, if it was opened, is stopped and
/// closed again.
#[derive(Debug)]
pub enum RunError {
    /// An option is out of range (speed fraction, period).
    Options(String),
    /// The model, the waypoints or the plan were refused.
    Plan(PlanError),
    /// The device failed during `stage` ("open", "read the start position", "start",
    /// "first exchange").
    Device {
        /// What was being done.
        stage: &'static str,
        /// The device's error.
        error: DeviceError,
    },
    /// After starting, the arm was not where it stood when the plan was made.
    Moved {
        /// The joint's name.
        joint: String,
        /// Where the plan starts.
        planned: f64,
        /// Where the device reports it.
        measured: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// Before starting, the arm does not stand where the trajectory to follow starts.
    NotAtStart {
        /// The joint's name.
        joint: String,
        /// Where the trajectory starts.
        start: f64,
        /// Where the device reports the joint.
        measured: f64,
        /// The tolerance (the tracking bound and the device's resolution).
        tolerance: f64,
    },
    /// The law refused to start ([`ControlLaw::start`]).
    Law(String),
    /// A stop was requested before the loop started.
    Cancelled,
    /// The real-time thread could not be started.
    Thread(ThreadError),
    /// The loop could not be set up (period out of range).
    Loop(String),
    /// The safety chain does not allow motion (an e-stop open, the enable released, a pin
    /// that cannot be read or written, or the chain in use by another run): nothing started.
    Safety(String),
}

impl RunError {
    /// The process exit code: 130 for a stop request, 2 for options, 1 otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            RunError::Cancelled => 130,
            RunError::Options(_) => 2,
            _ => 1,
        }
    }
}

impl fmt::Display for RunError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunError::Options(why) => f.write_str(why),
            RunError::Plan(e) => write!(f, "refusing to move: {e}"),
            RunError::Device { stage, error } => {
                write!(f, "the device failed to {stage}: {error}")
            }
            RunError::Moved {
                joint,
                planned,
                measured,
                tolerance,
            } => write!(
                f,
                "refusing to move: after starting, joint {joint} is at {measured}, not at \
                 {planned} where the plan starts (tolerance {tolerance:.2e})"
            ),
            RunError::NotAtStart {
                joint,
                start,
                measured,
                tolerance,
            } => write!(
                f,
                "refusing to move: joint {joint} is at {measured}, not at {start} where the \
                 trajectory starts (tolerance {tolerance:.2e}); bring the robot to the start \
                 first"
            ),
            RunError::Law(why) => write!(f, "refusing to move: the law refused to start: {why}"),
            RunError::Cancelled => f.write_str("stopped on request before the motion started"),
            RunError::Thread(e) => write!(f, "cannot start the control thread: {e}"),
            RunError::Loop(e) => write!(f, "control loop: {e}"),
            RunError::Safety(e) => write!(f, "safety chain: {e}; nothing was started"),
        }
    }
}

impl std::error::Error for RunError {}

impl From<PlanError> for RunError {
    fn from(e: PlanError) -> Self {
        match e {
            PlanError::Cancelled => RunError::Cancelled,
            e => RunError::Plan(e),
        }
    }
}

/// What the control thread publishes every cycle (through a latest-value mailbox).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Progress {
    /// Cycle index.
    pub cycle: u64,
    /// Trajectory time, s.
    pub time_s: f64,
    /// Largest tracking error so far, rad or m.
    pub error_max_rad: f64,
    /// Worst wake-up latency so far, ns.
    pub worst_latency_ns: u64,
    /// Failed steps so far.
    pub lost: u64,
    /// Whether the arm is being brought to rest.
    pub halting: bool,
    /// Whether a fault was found (the run is ending).
    pub faulted: bool,
    /// The stop level requested so far.
    pub stop: StopLevel,
}

/// What is known about a run before its loop starts, for the report.
#[derive(Clone, Debug)]
struct RunInfo {
    model: String,
    device: String,
    joints: Vec<String>,
    period: Duration,
    device_period: Duration,
    scheduling: String,
    warnings: Vec<String>,
    memory_locked: bool,
    plan_duration_s: f64,
    trajectory_source: String,
    trajectory_description: String,
    assumed_speed: Vec<String>,
    started: Instant,
    /// The host's steal and interrupt times when the loop started.
    host_before: Option<rl_rt::HostTimes>,
    /// Other programs' real-time threads when the loop started.
    rt_before: Vec<rl_rt::preflight::rt_threads::RtThread>,
    /// Where the safety chain goes back after the run.
    safety: Option<super::safety::SafetyHandle>,
}

/// A running controller: a real-time thread stepping a [`Controller`](super::Controller) with the law `L` (by
/// default the [`TrajectoryFollower`]) for a model of up to `B` bodies and `J` joints on the
/// device `R`.
pub struct ControlRun<R, const B: usize, const J: usize, L = TrajectoryFollower<J>>
where
    L: ControlLaw<B, J>,
{
    thread: RtThread<Option<LoopOutcome<R, B, J, L>>>,
    telemetry: Option<QueueReceiver<CycleRecord<J>>>,
    progress: MailboxReader<Progress>,
    inputs: InputSender<J, L::Input>,
    stop: StopFlag,
    info: RunInfo,
}

impl<R: JointRobot + Send + 'static, const B: usize, const J: usize>
    ControlRun<R, B, J, TrajectoryFollower<J>>
{
    /// Opens `robot`, checks `model` against it, reads the start, plans and checks the motion
    /// (a tour through [`RunOptions::waypoints`] and back), starts the device, checks its first
    /// reply and starts the real-time loop. On an error nothing has moved and the device is
    /// stopped and closed.
    pub fn start(robot: R, loaded: LoadedModel<B>, options: RunOptions) -> Result<Self, RunError> {
        Self::start_with(robot, loaded, options, Motion::Tour)
    }

    /// [`start`](Self::start) with the motion to make: [`Motion::Tour`], or
    /// [`Motion::Trajectory`] to follow a given trajectory (e.g. a planned collision-free path,
    /// see [`super::planned`]). A trajectory is checked against the model's limits like a tour,
    /// and the arm must stand at its start before the device starts: otherwise
    /// [`RunError::NotAtStart`], and nothing moves.
    pub fn start_with(
        robot: R,
        loaded: LoadedModel<B>,
        options: RunOptions,
        motion: Motion<J>,
    ) -> Result<Self, RunError> {
        Self::launch(robot, loaded, options, |prepared, options| {
            prepared.plan(motion, options)
        })
    }
}

impl<R, const B: usize, const J: usize, L> ControlRun<R, B, J, L>
where
    R: JointRobot + Send + 'static,
    L: ControlLaw<B, J> + 'static,
{
    /// Runs `law` instead of a trajectory: opens `robot`, checks `model` against it, reads
    /// the start, lets the law prepare itself ([`ControlLaw::start`]), checks that the device
    /// takes the law's [`CommandMode`](super::law::CommandMode), starts the device, checks its
    /// first reply and starts the real-time loop. On an error nothing has moved and the device
    /// is stopped and closed.
    pub fn start_law(
        robot: R,
        loaded: LoadedModel<B>,
        options: RunOptions,
        law: L,
    ) -> Result<Self, RunError> {
        Self::launch(robot, loaded, options, |prepared, _| {
            prepared.start_law(law)
        })
    }

    /// The three phases: checks and plan (`make` makes the law), the real-time thread, and
    /// what is known for the report.
    fn launch(
        robot: R,
        loaded: LoadedModel<B>,
        options: RunOptions,
        make: impl FnOnce(&mut Prepared<R, B, J>, &RunOptions) -> Result<L, RunError>,
    ) -> Result<Self, RunError> {
        let mut prepared = Prepared::open(robot, loaded.model, &options)?;
        let law = match make(&mut prepared, &options) {
            Ok(law) => law,
            Err(e) => return Err(prepared.abandon(e)),
        };
        let (law_info, controller, setup) = prepared.into_controller(law, &options)?;
        let (inputs_tx, inputs_rx) = input::channel(controller.model(), options.input_capacity);
        let host_before = rl_rt::HostTimes::read();
        let rt_before = rl_rt::preflight::rt_threads::other_rt_threads();
        let spawned = rt_loop::spawn(controller, inputs_rx, setup, &options)?;
        Ok(Self {
            thread: spawned.thread,
            telemetry: spawned.telemetry,
            progress: spawned.progress,
            inputs: inputs_tx,
            stop: options.stop.clone(),
            info: RunInfo {
                model: options.model_name,
                device: options.device_name,
                joints: law_info.joints,
                period: law_info.period,
                device_period: law_info.device_period,
                scheduling: spawned.scheduling,
                warnings: spawned.warnings,
                memory_locked: spawned.memory_locked,
                plan_duration_s: law_info.duration_s,
                trajectory_source: law_info.source,
                trajectory_description: law_info.description,
                assumed_speed: law_info.assumed_speed,
                started: Instant::now(),
                host_before,
                rt_before,
                safety: options.safety.clone(),
            },
        })
    }

    /// A sender of targets and of the law's own inputs to the running loop: clone it for any
    /// number of threads (see [`input`]).
    pub fn inputs(&self) -> InputSender<J, L::Input> {
        self.inputs.clone()
    }

    /// Waits up to `max_wait` and returns the latest progress, or `None` once the loop has
    /// ended (call [`join`](Self::join) then).
    pub fn poll(&mut self, max_wait: Duration) -> Option<Progress> {
        let until = Instant::now() + max_wait;
        while !self.thread.is_finished() && Instant::now() < until {
            std::thread::sleep(Duration::from_millis(5).min(until - Instant::now()));
        }
        if self.thread.is_finished() {
            None
        } else {
            Some(*self.progress.read())
        }
    }

    /// The latest progress.
    pub fn progress(&mut self) -> Progress {
        *self.progress.read()
    }

    /// Whether the loop has ended.
    pub fn is_finished(&self) -> bool {
        self.thread.is_finished()
    }

    /// The run's stop flag (raise it to come to rest, twice to stop now).
    pub fn stop_flag(&self) -> &StopFlag {
        &self.stop
    }

    /// Scheduling the loop got, e.g. `SCHED_FIFO priority 80 on CPUs [1]`.
    pub fn scheduling(&self) -> &str {
        &self.info.scheduling
    }

    /// What the real-time set-up could not get (each with its fix); the run goes on without.
    pub fn warnings(&self) -> &[String] {
        &self.info.warnings
    }

    /// The planned trajectory's duration (the law's, if it knows one; else 0), s.
    pub fn plan_duration_s(&self) -> f64 {
        self.info.plan_duration_s
    }

    /// The joints' names.
    pub fn joints(&self) -> &[String] {
        &self.info.joints
    }

    /// Hands every telemetry record queued so far to `sink` (with telemetry on).
    pub fn drain_telemetry(&mut self, mut sink: impl FnMut(&CycleRecord<J>)) {
        if let Some(rx) = &mut self.telemetry {
            while let Some(r) = rx.try_recv() {
                sink(&r);
            }
        }
    }

    /// Waits for the loop to end, brings the device to a safe state (stop, from a fault too)
    /// and closes it, and returns the report.
    pub fn join(self) -> RunReport {
        self.join_with(|_| {})
    }

    /// [`join`](Self::join), handing the telemetry records still queued to `sink` first.
    pub fn join_with(mut self, mut sink: impl FnMut(&CycleRecord<J>)) -> RunReport {
        while !self.thread.is_finished() {
            self.drain_telemetry(&mut sink);
            std::thread::sleep(Duration::from_millis(5));
        }
        self.drain_telemetry(&mut sink);
        let dropped = self.telemetry.as_ref().map(QueueReceiver::dropped);
        finish::report(self.thread.join(), self.info, dropped)
    }
}
