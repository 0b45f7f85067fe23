//! Phase two of a run: the real-time thread. It switches the device on (once memory is locked
//! and the thread runs at its priority, so a drive that faults when its cycle stops sees no
//! gap), checks the first reply, locks its deadlines to the ticks of a device that runs its own
//! cycle, and then, once per period, turns the stop request into the law's braking or an
//! abort, runs one [`Controller`] cycle (supervision, inputs, the law, the device's step) and
//! hands the cycle's record to the telemetry queue, the progress mailbox and the viewer — all
//! lock-free and allocation-free.

use std::ops::ControlFlow;
use std::sync::mpsc::SyncSender;
use std::time::Duration;

use rl_drivers::{DeviceError as _, ErrorKind};
use rl_rt::exchange::{MailboxWriter, QueueReceiver, QueueSender, mailbox, queue};
use rl_rt::{
    CyclicLoop, LoopStats, MonoTime, PhaseShift, RtThread, StopFlag, StopLevel, ThreadError,
    ThreadWait,
};

use super::prepare::LoopSetup;
use super::{Progress, RunError, RunOptions, TELEMETRY_BYTES};
use crate::controller::control::{Controller, CycleTiming};
use crate::controller::input::InputReceiver;
use crate::controller::law::ControlLaw;
use crate::controller::robot::JointRobot;
use crate::controller::safety::SafetyHandle;
use crate::controller::telemetry::CycleRecord;

/// Exchanges tried before the first reply counts as missing.
const FIRST_EXCHANGE_TRIES: u32 = 5;

/// What the control thread hands back.
pub(super) struct LoopOutcome<R, const B: usize, const J: usize, L: ControlLaw<B, J>> {
    pub(super) controller: Box<Controller<R, B, J, L>>,
    pub(super) stats: LoopStats,
    pub(super) loop_error: Option<String>,
    /// How long the thread waited for its CPU, in all, during the loop (schedstat).
    pub(super) run_delay: Option<Duration>,
}

/// The running thread and what the caller reads of it.
pub(super) struct Spawned<R, const B: usize, const J: usize, L: ControlLaw<B, J>> {
    pub(super) thread: RtThread<Option<LoopOutcome<R, B, J, L>>>,
    pub(super) telemetry: Option<QueueReceiver<CycleRecord<J>>>,
    pub(super) progress: rl_rt::exchange::MailboxReader<Progress>,
    pub(super) scheduling: String,
    pub(super) warnings: Vec<String>,
    pub(super) memory_locked: bool,
}

/// Starts the real-time thread with `controller` (taking inputs from `inputs`) and waits until
/// it has switched the device on and checked its first reply.
pub(super) fn spawn<R, const B: usize, const J: usize, L>(
    mut controller: Box<Controller<R, B, J, L>>,
    inputs: InputReceiver<J, L::Input>,
    setup: LoopSetup,
    options: &RunOptions,
) -> Result<Spawned<R, B, J, L>, RunError>
where
    R: JointRobot + Send + 'static,
    L: ControlLaw<B, J> + 'static,
{
    controller.attach_inputs(inputs);
    let (tx, rx) = if options.telemetry {
        let records = (TELEMETRY_BYTES / size_of::<CycleRecord<J>>()).max(256);
        let (tx, rx) = queue::<CycleRecord<J>>(records);
        (Some(tx), Some(rx))
    } else {
        (None, None)
    };
    let (progress_tx, progress_rx) = mailbox(Progress::default());
    let lock = controller
        .robot()
        .runs_own_cycle()
        .then(|| PhaseLock::new(setup.period, options.phase_target));
    let looped = match &lock {
        Some(l) => setup.looped.phase_shift(&l.shift),
        None => setup.looped,
    };
    let body = LoopBody {
        controller,
        lock,
        telemetry: tx,
        progress: progress_tx,
        stop: options.stop.clone(),
        safety: options.safety.clone(),
        #[cfg(feature = "view")]
        view: setup.view,
        period_ns: setup.period.as_nanos().min(u128::from(u64::MAX)) as u64,
        worst_latency_ns: 0,
        halted: false,
    };
    // The start's outcome comes back through this channel.
    let (started_tx, started_rx) = std::sync::mpsc::sync_channel::<Result<(), RunError>>(1);
    let (start, joints) = (setup.start, setup.joints);
    let thread = setup
        .builder
        .spawn(move || body.run(looped, &start, &joints, started_tx))
        .map_err(RunError::Thread)?;
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
    let (scheduling, warnings, memory_locked) = granted(&thread, options.lock_memory);
    Ok(Spawned {
        thread,
        telemetry: rx,
        progress: progress_rx,
        scheduling,
        warnings,
        memory_locked,
    })
}

/// The scheduling the thread got, what it could not get (each with its fix), and whether
/// memory is locked.
fn granted<T>(thread: &RtThread<T>, lock_memory: bool) -> (String, Vec<String>, bool) {
    let granted = thread.granted();
    let scheduling = match granted.policy {
        Some(p) if p.is_realtime() => format!(
            "{p} priority {} on CPUs {:?}",
            granted.priority, granted.cpus
        ),
        Some(p) => format!("{p} on CPUs {:?} (not real-time)", granted.cpus),
        None => "unknown scheduling".to_owned(),
    };
    let warnings = thread
        .degraded()
        .iter()
        .map(|e| match e {
            ThreadError::Memory(_) => {
                format!("{e}; running without locked memory (or pass --no-mlock)")
            }
            e => format!("{e}; running the loop at SCHED_OTHER, so its latency is not bounded"),
        })
        .collect();
    let memory_locked = lock_memory
        && !thread
            .degraded()
            .iter()
            .any(|e| matches!(e, ThreadError::Memory(_)));
    (scheduling, warnings, memory_locked)
}

/// The real-time thread's state.
struct LoopBody<R, const B: usize, const J: usize, L: ControlLaw<B, J>> {
    controller: Box<Controller<R, B, J, L>>,
    lock: Option<PhaseLock>,
    telemetry: Option<QueueSender<CycleRecord<J>>>,
    progress: MailboxWriter<Progress>,
    stop: StopFlag,
    /// Where the safety chain goes back if the device does not start.
    safety: Option<SafetyHandle>,
    #[cfg(feature = "view")]
    view: Option<crate::controller::view::ViewPublisher>,
    period_ns: u64,
    worst_latency_ns: u64,
    halted: bool,
}

impl<R: JointRobot, const B: usize, const J: usize, L: ControlLaw<B, J>> LoopBody<R, B, J, L> {
    /// The thread's body: start the device, then run the loop until the controller ends.
    fn run(
        mut self,
        looped: CyclicLoop,
        start: &[f64],
        joints: &[String],
        started: SyncSender<Result<(), RunError>>,
    ) -> Option<LoopOutcome<R, B, J, L>> {
        let switched_on = if self.stop.is_stop_requested() {
            Err(RunError::Cancelled)
        } else {
            // The safety chain first: motion never starts with it open.
            self.controller
                .arm_safety()
                .map_err(|reason| RunError::Safety(reason.to_string()))
                .and_then(|()| start_device(&mut self.controller, start, joints))
        };
        // For a device on its own cycle, the first reply came at one of its ticks.
        let first_tick = MonoTime::now();
        if let Err(e) = switched_on {
            let robot = self.controller.robot_mut();
            let _ = robot.stop();
            let _ = robot.close();
            if let (Some(handle), Some(chain)) = (&self.safety, self.controller.detach_safety()) {
                handle.put_back(chain);
            }
            let _ = started.send(Err(e));
            return None;
        }
        let _ = started.send(Ok(()));
        if let Some(l) = &mut self.lock {
            l.late = self.controller.robot().link_statistics().late;
        }
        // Start on the device's grid of ticks, the target fraction of a period before one.
        let looped = match &self.lock {
            Some(l) => looped.start_at(l.first_deadline(first_tick, MonoTime::now())),
            None => looped,
        };
        let mut stats = looped.new_stats();
        // The thread's wait for its CPU over the loop (read without allocating): a late
        // wake-up longer than it was the host's, not another thread's.
        let waited_before = ThreadWait::current();
        let result = looped.run_into(&mut stats, |cycle| self.cycle(cycle));
        let run_delay = waited_before
            .zip(ThreadWait::current())
            .map(|(before, after)| after.since(&before).run_delay);
        self.controller.close_inputs();
        Some(LoopOutcome {
            controller: self.controller,
            stats,
            loop_error: result.err().map(|e| e.to_string()),
            run_delay,
        })
    }

    /// One period: the stop request, one controller cycle, and its record handed on.
    fn cycle(&mut self, cycle: &rl_rt::Cycle) -> ControlFlow<()> {
        let level = self.stop.level();
        match level {
            StopLevel::None => {}
            StopLevel::Rest if !self.halted => {
                self.controller.request_halt();
                self.halted = true;
            }
            StopLevel::Rest => {}
            StopLevel::Now => self.controller.abort(),
        }
        let failed_before = self.controller.failed_steps();
        // Leave a tenth of the period after the device's step for the rest of the cycle.
        let next = cycle.deadline.as_nanos() + self.period_ns;
        let budget_ns = next
            .saturating_sub(MonoTime::now().as_nanos())
            .saturating_sub(self.period_ns / 10);
        let out = self.controller.cycle_timed(CycleTiming {
            skipped_deadlines: cycle.skipped_before,
            overran: cycle.skipped_before > 0,
            step_budget: Some(Duration::from_nanos(budget_ns)),
        });
        let mut record = out.record;
        record.wakeup_latency_ns = cycle.wakeup_latency_ns;
        record.step_ns = MonoTime::now().nanos_since(cycle.woke);
        if let Some(l) = &mut self.lock {
            let late = self.controller.robot().link_statistics().late;
            if !out.finished && self.controller.failed_steps() == failed_before {
                l.observe(record.step_ns, late);
            }
        }
        self.worst_latency_ns = self.worst_latency_ns.max(cycle.wakeup_latency_ns);
        if let Some(tx) = &mut self.telemetry {
            // A full queue hands the record back and counts the drop.
            let _ = QueueSender::try_send(tx, record);
        }
        let c = &self.controller;
        self.progress.publish(Progress {
            cycle: record.cycle,
            time_s: record.time_s,
            error_max_rad: c.tracking().max_error(),
            worst_latency_ns: self.worst_latency_ns,
            lost: c.failed_steps(),
            halting: c.is_braking(),
            faulted: c.fault().is_some(),
            stop: level,
        });
        // A lost reply's stale measurement is not shown: the page's tracking error is the
        // statistics' (which skip it), and the view keeps the last fresh pose.
        #[cfg(feature = "view")]
        if let Some(v) = &mut self.view {
            if self.controller.feedback_fresh() {
                v.show(&record);
            }
        }
        if out.finished {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }
}

/// Keeps the loop's deadlines a fixed fraction of a period ahead of the ticks of a device that
/// runs its own cycle: the step's duration (wake-up to reply) is the distance to the tick; a
/// proportional correction, at most 2 % of a period per cycle, moves the loop's grid toward the
/// target.
///
/// A step that came late — the device's next reply was waiting already (its `late` count
/// rose) and the step returned at once — woke after the tick: its duration says nothing of the
/// distance, and a device that streams its state (a Franka arm) would have every later step
/// answer one state behind. The grid then moves half a period earlier at once; a second such
/// step moves it again, and the steps that wait for their tick take over.
struct PhaseLock {
    shift: PhaseShift,
    period_ns: u64,
    target_ns: i64,
    late: u64,
}

impl PhaseLock {
    /// Correction applied per cycle, as a fraction of the error.
    const GAIN: f64 = 0.2;
    /// Largest correction per cycle, as a fraction of the period.
    const MAX_STEP: f64 = 0.02;
    /// A step shorter than this fraction of the period returned at once.
    const AT_ONCE: f64 = 0.05;

    fn new(period: Duration, target: f64) -> Self {
        let period_ns = period.as_nanos().max(1) as u64;
        Self {
            shift: PhaseShift::new(),
            period_ns,
            target_ns: (target.clamp(0.05, 0.9) * period_ns as f64) as i64,
            late: 0,
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

    /// Corrects the phase from one successful step of `step_ns`, with the device's count of
    /// late replies after it.
    fn observe(&mut self, step_ns: u64, late: u64) {
        let came_late = late > self.late;
        self.late = late;
        if came_late && (step_ns as f64) < Self::AT_ONCE * self.period_ns as f64 {
            self.shift.shift(-((self.period_ns / 2) as i64));
            return;
        }
        let error = step_ns as f64 - self.target_ns as f64;
        let max = Self::MAX_STEP * self.period_ns as f64;
        let correction = (error * Self::GAIN).clamp(-max, max);
        self.shift.shift(correction as i64);
    }
}

/// Switches the device on (`start`: for a robot controller, servo on) and checks its first
/// reply.
fn start_device<R: JointRobot, const B: usize, const J: usize, L: ControlLaw<B, J>>(
    controller: &mut Controller<R, B, J, L>,
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

/// Commands the start once (the law's hold: the start position, zero velocity or torque) and
/// checks that the device reports the arm there.
fn first_exchange<R: JointRobot, const B: usize, const J: usize, L: ControlLaw<B, J>>(
    controller: &mut Controller<R, B, J, L>,
    start: &[f64],
    joints: &[String],
) -> Result<(), RunError> {
    let dof = start.len();
    let tolerance: Vec<f64> = controller.supervisor().bounds().tracking[..dof].to_vec();
    // A device on its own cycle may let the first request wait past a reply timeout while its
    // cycle settles: a few tries, one period apart as the loop's cycles would be, before
    // giving up.
    let period = controller.robot().update_period();
    let mut tries = 0;
    loop {
        tries += 1;
        let began = std::time::Instant::now();
        match controller.first_exchange() {
            Ok(()) => break,
            Err(e) if tries < FIRST_EXCHANGE_TRIES && e.kind() == ErrorKind::Timeout => {
                // The next try a period after this one began: a device that answers on its
                // own cycle has had its tick to answer this one, and a drive that watches the
                // master's cycle (a CiA 402 drive faults after two SYNC periods without one)
                // sees no gap. A pause of two periods here faulted such a drive.
                std::thread::sleep(
                    (began + period).saturating_duration_since(std::time::Instant::now()),
                );
            }
            Err(error) => {
                return Err(RunError::Device {
                    stage: "complete the first exchange",
                    error,
                });
            }
        }
    }
    let robot = controller.robot();
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
