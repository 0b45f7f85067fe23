//! The whole program `rl run` is, as a library: [`ControlRun`] opens the device, checks the
//! model against it, reads where the arm stands, plans and checks the motion — all before the
//! device is started (servo on), in bounded time, cancellable — then starts the device, checks
//! the first reply, and runs the supervised [`Controller`] in a real-time thread on absolute
//! deadlines. While it runs the caller reads progress and drains telemetry; [`ControlRun::join`]
//! ends it, brings the device to a safe state (from a fault too) and returns the
//! [`RunReport`].
//!
//! Stopping is two-level, through rl-rt's [`StopFlag`]: the first request brings the arm to
//! rest along its path, the second ends the run at once. The real-time set-up is best effort
//! (rl-rt's own fallback): without the right to SCHED_FIFO or to lock memory the run goes on at
//! normal priority and the report says what was refused and how to fix it.
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

use std::fmt;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use rl_core::loader::LoadedModel;
use rl_drivers::{DeviceError as _, Error as DeviceError, ErrorKind};
use rl_rt::exchange::{MailboxReader, QueueReceiver, QueueSender, mailbox, queue};
use rl_rt::{
    CyclicLoop, LoopStats, MonoTime, OverrunPolicy, PhaseShift, Policy, RtThread, RtThreadBuilder,
};
use rl_rt::{StopFlag, StopLevel, ThreadError};

use super::control::{Controller, CycleTiming, RunEnd, supervision_bounds};
use super::plan::{
    DEFAULT_MAX_PLAN_DURATION, Motion, MotionLimits, Plan, PlanBudget, PlanError, UNKNOWN_SPEED,
    default_waypoints, joint_name,
};
use super::report::{RunReport, Shutdown};
use super::robot::JointRobot;
use super::supervise::Supervision;
use super::telemetry::CycleRecord;

/// Default real-time priority of the control thread.
pub const DEFAULT_PRIORITY: i32 = 80;
/// Default fraction of the model's speed limits the plan uses.
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
    /// Stop (at rest, along the path) after this long.
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
    /// Show the motion in this viewer: the loop publishes every cycle's measured and
    /// commanded positions through its lock-free mailbox (feature `view`).
    #[cfg(feature = "view")]
    pub view: Option<super::view::ViewHook>,
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
            #[cfg(feature = "view")]
            view: None,
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
    /// A stop was requested before the loop started.
    Cancelled,
    /// The real-time thread could not be started.
    Thread(ThreadError),
    /// The loop could not be set up (period out of range).
    Loop(String),
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
            RunError::Cancelled => f.write_str("stopped on request before the motion started"),
            RunError::Thread(e) => write!(f, "cannot start the control thread: {e}"),
            RunError::Loop(e) => write!(f, "control loop: {e}"),
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

/// What the control thread hands back.
struct LoopOutcome<R, const B: usize, const J: usize> {
    controller: Box<Controller<R, B, J>>,
    stats: LoopStats,
    loop_error: Option<String>,
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
}

/// A running controller: a real-time thread stepping a [`Controller`] for a model of up to `B`
/// bodies and `J` joints on the device `R`.
pub struct ControlRun<R, const B: usize, const J: usize> {
    thread: RtThread<Option<LoopOutcome<R, B, J>>>,
    telemetry: Option<QueueReceiver<CycleRecord<J>>>,
    progress: MailboxReader<Progress>,
    stop: StopFlag,
    info: RunInfo,
}

impl<R: JointRobot + Send + 'static, const B: usize, const J: usize> ControlRun<R, B, J> {
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
        mut robot: R,
        loaded: LoadedModel<B>,
        options: RunOptions,
        motion: Motion<J>,
    ) -> Result<Self, RunError> {
        let model = loaded.model;
        if !(options.speed > 0.0 && options.speed <= 1.0) {
            return Err(RunError::Options(format!(
                "speed fraction {} must be above 0 and at most 1 (of the model's speed limits)",
                options.speed
            )));
        }
        let limits = MotionLimits::<J>::from_model(&model, options.speed)?;
        let mut builder = RtThreadBuilder::new("rl-control")
            .policy(Policy::Fifo)
            .priority(options.priority)
            .lock_memory(options.lock_memory)
            .best_effort(true);
        if !options.cpus.is_empty() {
            builder = builder.cpus(options.cpus.iter().copied());
        }
        // Try the scheduling on a throw-away thread before anything starts: a bad priority or
        // CPU is refused here; a missing privilege is degraded (best effort) and reported.
        let probe = builder
            .clone()
            .lock_memory(false)
            .spawn(|| ())
            .map_err(|e| RunError::Options(format!("priority/CPU: {e}")))?;
        // The probe thread does nothing; its end cannot fail.
        let _ = probe.join();
        let dof = model.dof();
        let joints: Vec<String> = (0..dof).map(|k| joint_name(&model, k)).collect();
        let stop = options.stop.clone();
        #[cfg(feature = "view")]
        let mut view = options.view.as_ref().map(|v| v.attach(dof)).transpose()?;

        robot.open().map_err(|error| RunError::Device {
            stage: "open",
            error,
        })?;
        // From here on, every error path closes the device again.
        let planned = (|| -> Result<_, RunError> {
            if robot.dof() != dof {
                return Err(RunError::Plan(PlanError::DeviceJoints {
                    model: dof,
                    device: robot.dof(),
                }));
            }
            let mut start = vec![0.0; dof];
            robot
                .joint_position(&mut start)
                .map_err(|error| RunError::Device {
                    stage: "read the start position",
                    error,
                })?;
            // A joint standing on its limit may be reported a rounding beyond it.
            for (k, q) in start.iter_mut().enumerate() {
                let l = model.limits(k);
                let tolerance = robot.joint_position_resolution(*q);
                if !l.wraparound && q.is_finite() {
                    if *q < l.lower && *q >= l.lower - tolerance {
                        *q = l.lower;
                    } else if *q > l.upper && *q <= l.upper + tolerance {
                        *q = l.upper;
                    }
                }
            }
            let device_period = robot.update_period();
            let period = options.period.unwrap_or(device_period);
            if period.is_zero() {
                return Err(RunError::Options(
                    "the control period must be positive".into(),
                ));
            }
            if period < device_period {
                return Err(RunError::Options(format!(
                    "a control period of {:.3} ms is shorter than the device's cycle of {:.3} ms: \
                     the device cannot answer more often",
                    period.as_secs_f64() * 1e3,
                    device_period.as_secs_f64() * 1e3
                )));
            }
            let budget = PlanBudget {
                max_duration: options.max_plan_duration,
                stop: Some(stop.clone()),
            };
            let (plan, source, description) = match motion {
                Motion::Tour => {
                    let waypoints = options
                        .waypoints
                        .clone()
                        .unwrap_or_else(|| default_waypoints(&model, &start));
                    let n = waypoints.len();
                    let plan =
                        Plan::<J>::with_budget(&model, &start, &waypoints, &limits, &budget)?;
                    let description = format!(
                        "tour through {n} waypoint{} and back to the start",
                        if n == 1 { "" } else { "s" }
                    );
                    (plan, "tour".to_owned(), description)
                }
                Motion::Trajectory(follow) => {
                    let plan =
                        Plan::<J>::from_trajectory(&model, follow.trajectory, &limits, &budget)?;
                    // The arm must stand where the trajectory starts, within the tracking
                    // bound the run supervises.
                    let bounds = supervision_bounds(
                        &model,
                        &plan,
                        &options.supervision,
                        period.as_secs_f64(),
                        device_period,
                    );
                    for (k, (&measured, &planned)) in start.iter().zip(plan.start()).enumerate() {
                        let tolerance =
                            bounds.tracking[k] + robot.joint_position_resolution(planned);
                        let off = (measured - planned).abs();
                        if off.is_nan() || off > tolerance {
                            return Err(RunError::NotAtStart {
                                joint: joints[k].clone(),
                                start: planned,
                                measured,
                                tolerance,
                            });
                        }
                    }
                    start.copy_from_slice(plan.start());
                    (plan, follow.source, follow.description)
                }
            };
            plan.check_step(&model, period, device_period)?;
            Ok((start, plan, period, device_period, source, description))
        })();
        let (start, plan, period, device_period, trajectory_source, trajectory_description) =
            match planned {
                Ok(p) => p,
                Err(e) => {
                    let _ = robot.close();
                    return Err(e);
                }
            };
        let plan_duration_s = plan.duration_s();
        let assumed_speed: Vec<String> = (0..dof)
            .filter(|&k| limits.assumed_speed[k])
            .map(|k| joints[k].clone())
            .collect();
        let looped = match CyclicLoop::new(period) {
            Ok(l) => l.overrun_policy(OverrunPolicy::Skip),
            Err(e) => {
                let _ = robot.close();
                return Err(RunError::Loop(e.to_string()));
            }
        };
        if stop.is_stop_requested() {
            let _ = robot.close();
            return Err(RunError::Cancelled);
        }

        let mut controller = match Controller::<R, B, J>::with_supervision(
            robot,
            model,
            plan,
            period,
            &options.supervision,
        ) {
            Ok(c) => Box::new(c),
            // Dropping the opened device closes its connections.
            Err(e) => return Err(e.into()),
        };
        if let Some(d) = options.duration {
            controller.limit_cycles((d.as_secs_f64() / period.as_secs_f64()).round() as u64);
        }

        let (mut tx, rx) = if options.telemetry {
            let records = (TELEMETRY_BYTES / size_of::<CycleRecord<J>>()).max(256);
            let (tx, rx) = queue::<CycleRecord<J>>(records);
            (Some(tx), Some(rx))
        } else {
            (None, None)
        };
        let (mut progress_tx, progress_rx) = mailbox(Progress::default());
        let stop_rt = stop.clone();
        let joints_rt = joints.clone();
        let lock = controller
            .robot()
            .runs_own_cycle()
            .then(|| PhaseLock::new(period, options.phase_target));
        let looped = match &lock {
            Some(l) => looped.phase_shift(&l.shift),
            None => looped,
        };
        let period_ns = period.as_nanos().min(u128::from(u64::MAX)) as u64;
        // The device is switched on in the real-time thread, once memory is locked and the
        // thread runs at its priority, right before the loop: a drive that faults when its
        // cycle stops (a CiA 402 SYNC watchdog) sees no gap. The start's outcome comes back
        // through this channel.
        let (started_tx, started_rx) = std::sync::mpsc::sync_channel::<Result<(), RunError>>(1);
        let spawned = builder.spawn(move || {
            let mut controller = controller;
            let mut lock = lock;
            let started = if stop_rt.is_stop_requested() {
                Err(RunError::Cancelled)
            } else {
                start_device(&mut controller, &start, &joints_rt)
            };
            // For a device on its own cycle, the first reply came at one of its ticks.
            let first_tick = MonoTime::now();
            if let Err(e) = started {
                let robot = controller.robot_mut();
                let _ = robot.stop();
                let _ = robot.close();
                let _ = started_tx.send(Err(e));
                return None;
            }
            let _ = started_tx.send(Ok(()));
            // Start on the device's grid of ticks, the target fraction of a period before one.
            let looped = match &lock {
                Some(l) => looped.start_at(l.first_deadline(first_tick, MonoTime::now())),
                None => looped,
            };
            let mut stats = looped.new_stats();
            let mut worst_latency_ns = 0u64;
            let mut halted = false;
            let result = looped.run_into(&mut stats, |cycle| {
                let level = stop_rt.level();
                match level {
                    StopLevel::None => {}
                    StopLevel::Rest => {
                        if !halted {
                            controller.request_halt();
                            halted = true;
                        }
                    }
                    StopLevel::Now => controller.abort(),
                }
                let failed_before = controller.failed_steps();
                // Leave a tenth of the period after the device's step for the rest of the cycle.
                let next = cycle.deadline.as_nanos() + period_ns;
                let budget_ns = next
                    .saturating_sub(MonoTime::now().as_nanos())
                    .saturating_sub(period_ns / 10);
                let out = controller.cycle_timed(CycleTiming {
                    skipped_deadlines: cycle.skipped_before,
                    overran: cycle.skipped_before > 0,
                    step_budget: Some(Duration::from_nanos(budget_ns)),
                });
                let mut record = out.record;
                record.wakeup_latency_ns = cycle.wakeup_latency_ns;
                record.step_ns = MonoTime::now().nanos_since(cycle.woke);
                if let Some(l) = &mut lock {
                    if !out.finished && controller.failed_steps() == failed_before {
                        l.observe(record.step_ns);
                    }
                }
                worst_latency_ns = worst_latency_ns.max(cycle.wakeup_latency_ns);
                if let Some(tx) = &mut tx {
                    // A full queue hands the record back and counts the drop.
                    let _ = QueueSender::try_send(tx, record);
                }
                progress_tx.publish(Progress {
                    cycle: record.cycle,
                    time_s: record.time_s,
                    error_max_rad: controller.tracking().max_error(),
                    worst_latency_ns,
                    lost: controller.failed_steps(),
                    halting: controller.clock().halting().is_some(),
                    faulted: controller.fault().is_some(),
                    stop: level,
                });
                #[cfg(feature = "view")]
                if let Some(v) = &mut view {
                    v.show(&record);
                }
                if out.finished {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            });
            drop(tx);
            Some(LoopOutcome {
                controller,
                stats,
                loop_error: result.err().map(|e| e.to_string()),
            })
        });
        let thread = spawned.map_err(RunError::Thread)?;
        match started_rx.recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => {
                let _ = thread.join();
                return Err(e);
            }
            Err(_) => {
                return Err(RunError::Loop(
                    "the control thread ended before starting the device".into(),
                ));
            }
        }
        let granted = thread.granted();
        let scheduling = match (granted.policy, thread.degraded().is_empty()) {
            (Some(p), _) if p.is_realtime() => format!(
                "{p} priority {} on CPUs {:?}",
                granted.priority, granted.cpus
            ),
            (Some(p), _) => format!("{p} on CPUs {:?} (not real-time)", granted.cpus),
            (None, _) => "unknown scheduling".to_owned(),
        };
        let warnings: Vec<String> = thread
            .degraded()
            .iter()
            .map(|e| match e {
                ThreadError::Memory(_) => {
                    format!("{e}; running without locked memory (or pass --no-mlock)")
                }
                e => format!("{e}; running the loop at SCHED_OTHER, so its latency is not bounded"),
            })
            .collect();
        let memory_locked = options.lock_memory
            && !thread
                .degraded()
                .iter()
                .any(|e| matches!(e, ThreadError::Memory(_)));
        Ok(Self {
            thread,
            telemetry: rx,
            progress: progress_rx,
            stop,
            info: RunInfo {
                model: options.model_name,
                device: options.device_name,
                joints,
                period,
                device_period,
                scheduling,
                warnings,
                memory_locked,
                plan_duration_s,
                trajectory_source,
                trajectory_description,
                assumed_speed,
                started: Instant::now(),
            },
        })
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

    /// The planned trajectory's duration, s.
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
        let info = self.info;
        let outcome = match self.thread.join() {
            Ok(Some(o)) => o,
            Ok(None) | Err(_) => {
                let mut report = RunReport::failed_early(
                    info.model,
                    info.device,
                    info.joints,
                    "the control thread panicked; the device was not stopped by the run",
                );
                report.trajectory_source = info.trajectory_source;
                report.trajectory_description = info.trajectory_description;
                return report;
            }
        };
        let LoopOutcome {
            mut controller,
            stats,
            loop_error,
        } = outcome;
        let fault_before_stop = controller.robot().fault().map(|e| e.to_string());
        let robot = controller.robot_mut();
        let mut shutdown = Shutdown {
            description: robot.stop_description().to_owned(),
            fault_before_stop,
            ..Shutdown::default()
        };
        match robot.stop() {
            Ok(()) => shutdown.stopped = true,
            Err(e) => shutdown.error = Some(e.to_string()),
        }
        if let Err(e) = robot.close() {
            shutdown.error.get_or_insert(e.to_string());
        }
        let end = controller.end();
        let mut failure = loop_error.map(|e| format!("control loop: {e}"));
        if let Some(RunEnd::Fault(f)) = end {
            failure.get_or_insert(f.describe(&info.joints));
        }
        if !shutdown.stopped {
            failure.get_or_insert(format!(
                "the device did not stop cleanly: {}",
                shutdown.error.as_deref().unwrap_or("unknown")
            ));
        }
        let tracking = controller.tracking();
        let bounds = controller.supervisor().bounds();
        let dof = info.joints.len();
        let assumed =
            (!info.assumed_speed.is_empty()).then_some((UNKNOWN_SPEED, info.assumed_speed));
        RunReport {
            model: info.model,
            device: info.device,
            joints: info.joints,
            period_s: info.period.as_secs_f64(),
            device_period_s: info.device_period.as_secs_f64(),
            scheduling: info.scheduling,
            warnings: info.warnings,
            memory_locked: info.memory_locked,
            plan_duration_s: info.plan_duration_s,
            trajectory_source: info.trajectory_source,
            trajectory_description: info.trajectory_description,
            trajectory_time_s: controller.clock().time_s(),
            wall_time_s: info.started.elapsed().as_secs_f64(),
            end,
            stats,
            link: controller.link_statistics(),
            lost_packets: controller.failed_steps(),
            tracking_max: tracking.max_per_joint().to_vec(),
            tracking_rms: tracking.rms_per_joint()[..dof].to_vec(),
            tracking_final: tracking.last_error().to_vec(),
            tracking_bound: bounds.tracking[..dof].to_vec(),
            peak_feed_forward: tracking.peak_feed_forward().to_vec(),
            tracking_error_max: tracking.max_error(),
            tracking_error_rms: tracking.rms_error(),
            limit_violations: tracking.violations(),
            first_violation: tracking.first_violation(),
            supervised: controller.supervisor().is_enabled(),
            assumed_speed: assumed,
            shutdown,
            telemetry_rows: None,
            telemetry_dropped: dropped,
            notes: Vec::new(),
            failure,
        }
    }
}

/// Exchanges tried before the first reply counts as missing.
const FIRST_EXCHANGE_TRIES: u32 = 5;

/// Keeps the loop's deadlines a fixed fraction of a period ahead of the ticks of a device that
/// runs its own cycle: the step's duration (wake-up to reply) is the distance to the tick; a
/// proportional correction, at most 2 % of a period per cycle, moves the loop's grid toward the
/// target.
struct PhaseLock {
    shift: PhaseShift,
    period_ns: u64,
    target_ns: i64,
}

impl PhaseLock {
    /// Correction applied per cycle, as a fraction of the error.
    const GAIN: f64 = 0.2;
    /// Largest correction per cycle, as a fraction of the period.
    const MAX_STEP: f64 = 0.02;

    fn new(period: Duration, target: f64) -> Self {
        let period_ns = period.as_nanos().max(1) as u64;
        Self {
            shift: PhaseShift::new(),
            period_ns,
            target_ns: (target.clamp(0.05, 0.9) * period_ns as f64) as i64,
        }
    }

    /// The first deadline after `now` on the grid of ticks through `tick`, the target ahead of
    /// a tick (with one period of room for the thread to start).
    fn first_deadline(&self, tick: MonoTime, now: MonoTime) -> MonoTime {
        let p = self.period_ns;
        let ahead = p - (self.target_ns as u64).min(p);
        let elapsed = now.nanos_since(tick);
        let n = elapsed / p + 2;
        MonoTime::from_nanos(
            tick.as_nanos()
                .saturating_add(n * p)
                .saturating_sub(p - ahead),
        )
    }

    /// Corrects the phase from one successful step of `step_ns`.
    fn observe(&mut self, step_ns: u64) {
        let error = step_ns as f64 - self.target_ns as f64;
        let max = Self::MAX_STEP * self.period_ns as f64;
        let correction = (error * Self::GAIN).clamp(-max, max);
        self.shift.shift(correction as i64);
    }
}

/// Switches the device on (`start`: for a robot controller, servo on) and checks its first
/// reply.
fn start_device<R: JointRobot, const B: usize, const J: usize>(
    controller: &mut Controller<R, B, J>,
    start: &[f64],
    joints: &[String],
) -> Result<(), RunError> {
    controller
        .robot_mut()
        .start()
        .map_err(|error| RunError::Device {
            stage: "start",
            error,
        })?;
    first_exchange(controller, start, joints)
}

/// Commands the plan's start once and checks that the device reports the arm there.
fn first_exchange<R: JointRobot, const B: usize, const J: usize>(
    controller: &mut Controller<R, B, J>,
    start: &[f64],
    joints: &[String],
) -> Result<(), RunError> {
    let dof = start.len();
    let tolerance: Vec<f64> = controller.supervisor().bounds().tracking[..dof].to_vec();
    let robot = controller.robot_mut();
    // A device on its own cycle may let the first request wait past a reply timeout while its
    // cycle settles: a few tries, each after the device has had time to answer the last one,
    // before giving up.
    let mut tries = 0;
    loop {
        tries += 1;
        match robot.set_joint_position(start).and_then(|()| robot.step()) {
            Ok(()) => break,
            Err(e) if tries < FIRST_EXCHANGE_TRIES && e.kind() == ErrorKind::Timeout => {
                // Let a device that answers on its own cycle work off the request before the
                // next one, so no second request waits in its queue.
                std::thread::sleep(2 * robot.update_period());
            }
            Err(error) => {
                return Err(RunError::Device {
                    stage: "complete the first exchange",
                    error,
                });
            }
        }
    }
    let mut measured = vec![0.0; dof];
    robot
        .joint_position(&mut measured)
        .map_err(|error| RunError::Device {
            stage: "report the joints after starting",
            error,
        })?;
    for k in 0..dof {
        let tol = tolerance[k] + robot.joint_position_resolution(start[k]);
        let off = (measured[k] - start[k]).abs();
        if off.is_nan() || off > tol {
            return Err(RunError::Moved {
                joint: joints[k].clone(),
                planned: start[k],
                measured: measured[k],
                tolerance: tol,
            });
        }
    }
    Ok(())
}
