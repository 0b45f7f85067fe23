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
//! Exit codes: 0 done, 1 failed (device fault, limits crossed, stop failed), 2 bad flags or
//! files, 130 stopped by Ctrl-C before the end.

mod device;
mod plot;
mod progress;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::{Duration, Instant};

use clap::Args;
use nix::sys::signal::{SigSet, Signal};
use rl::controller::plan::joint_name;
use rl::controller::report::{RunReport, Shutdown};
use rl::controller::{
    Controller, CycleRecord, JointRobot, MAX_BODIES, MotionLimits, Plan, RobotModel, RunEnd,
    default_waypoints, telemetry,
};
use rl_core::loader::{self, LoadedModel, UrdfOptions};
use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_rt::exchange::{QueueSender, mailbox, queue};
use rl_rt::{CyclicLoop, LoopStats, MonoTime, OverrunPolicy, Policy, RtThreadBuilder, ThreadError};

use self::device::DeviceSpec;
use self::progress::{Progress, ProgressDisplay};
use super::{CliError, CliResult};

/// A positive duration: the shared [`super::parse_duration`] units, zero refused.
fn parse_duration(text: &str) -> Result<Duration, String> {
    match super::parse_duration(text)? {
        d if d.is_zero() => Err(format!("`{text}`: the duration must be positive")),
        d => Ok(d),
    }
}

/// Default real-time priority of the control thread.
const DEFAULT_PRIORITY: i32 = 80;
/// Default fraction of the model's speed limits the plan uses.
const DEFAULT_SPEED: f64 = 0.25;
/// Telemetry records the queue holds (about a minute at 140 Hz; the writer drains it every
/// 100 ms).
const TELEMETRY_CAPACITY: usize = 8192;
/// Rows kept in memory for the plot (older ones are thinned out when it fills).
const PLOT_ROWS: usize = 50_000;

/// Arguments of `rl run`. Every field is optional so `RunArgs::default()` is the plain `rl`.
#[derive(Args, Debug, Default)]
pub struct RunArgs {
    /// Robot model (URDF or RL XML) [default: the embedded Mitsubishi RV-6SL].
    #[arg(long, value_name = "FILE")]
    pub model: Option<PathBuf>,
    /// The robot: fake-h7 (in-process fake controller), h7://HOST[:PORT][?r3=PORT] (a MELFA
    /// controller; ports 10000 and 10001 by default) or coach://HOST[:PORT] (stream the
    /// commanded joints to an RL visualiser; port 11235) [default: fake-h7].
    #[arg(long, value_name = "DEVICE")]
    pub device: Option<String>,
    /// Waypoints in rad (m for prismatic joints): a header row, then one row per waypoint with a
    /// column per joint in the model's order. The tour starts where the robot is and returns
    /// there [default: a tour derived from the joint limits].
    #[arg(long, value_name = "FILE.csv")]
    pub waypoints: Option<PathBuf>,
    /// Stop (at rest, along the path) after this long: e.g. 3s, 500ms, 2m.
    #[arg(long, value_parser = parse_duration)]
    pub duration: Option<Duration>,
    /// Control rate in Hz, for devices that allow it (fake-h7, coach) [default: the device's
    /// period: 7.11 ms for H7, 10 ms for Coach].
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// SCHED_FIFO priority of the control thread [default: 80].
    #[arg(long)]
    pub priority: Option<i32>,
    /// Pin the control thread to this CPU.
    #[arg(long)]
    pub cpu: Option<usize>,
    /// Fraction of the model's speed limits to plan with, in (0, 1] [default: 0.25].
    #[arg(long)]
    pub speed: Option<f64>,
    /// Write per-cycle telemetry as CSV: time, commanded and measured joints, feed-forward
    /// torques, wake-up latency, step time.
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
}

/// Everything checked before anything starts.
struct Setup {
    args: RunArgs,
    device: DeviceSpec,
    loaded: LoadedModel<MAX_BODIES>,
    model_name: String,
    joints: Vec<String>,
    waypoints: Option<Vec<Vec<f64>>>,
    limits: MotionLimits,
    thread: RtThreadBuilder,
    telemetry_file: Option<BufWriter<File>>,
}

/// Runs `rl run`.
pub fn run(args: RunArgs) -> CliResult {
    let mut setup = check(args)?;
    // Block SIGINT/SIGTERM before any thread starts (threads inherit the mask); one thread
    // takes them with sigwait: the first asks for a controlled stop, the second for an
    // immediate one. No signal handler runs.
    let signals = watch_signals()?;
    match setup.device.clone() {
        DeviceSpec::FakeH7 => {
            let model = &setup.loaded.model;
            let dof = model.dof();
            let lower: Vec<f64> = (0..dof).map(|k| model.limits(k).lower).collect();
            let upper: Vec<f64> = (0..dof).map(|k| model.limits(k).upper).collect();
            let speed: Vec<f64> = (0..dof).map(|k| model.limits(k).velocity).collect();
            let mut config = FakeH7Config::loopback(dof)
                .with_limits(&lower, &upper)
                .and_then(|c| c.with_speed_limits(&speed))
                .map_err(|e| CliError::failed(format!("fake H7 from the model: {e}")))?;
            let home = setup.loaded.home_or_neutral();
            for (k, (initial, h)) in config.initial_rad.iter_mut().zip(&home).enumerate() {
                *initial = model.limits(k).clamp(*h);
            }
            let fake = FakeH7::spawn(config)
                .map_err(|e| CliError::failed(format!("cannot start the fake H7: {e}")))?;
            let robot = MitsubishiH7::new(MitsubishiH7Config::new(
                dof,
                fake.udp_addr(),
                fake.r3_addr(),
            ))
            .map_err(|e| CliError::failed(format!("H7 device: {e}")))?;
            let name = format!(
                "fake H7 in-process on {} (R3 {})",
                fake.udp_addr(),
                fake.r3_addr()
            );
            drive(robot, name, &mut setup, &signals, Some(&fake), None)
        }
        DeviceSpec::H7 { server, r3 } => {
            let robot = MitsubishiH7::new(MitsubishiH7Config::new(
                setup.loaded.model.dof(),
                server,
                r3,
            ))
            .map_err(|e| CliError::usage(format!("--device: {e}")))?;
            let name = format!("H7 at {server} (R3 {r3})");
            drive(robot, name, &mut setup, &signals, None, None)
        }
        DeviceSpec::Coach { server } => {
            let mut config = CoachConfig::new(setup.loaded.model.dof());
            config.server = server;
            config.update_period = period_for(&setup, config.update_period);
            let robot =
                Coach::new(config).map_err(|e| CliError::usage(format!("--device: {e}")))?;
            // A visualiser shows what it is sent: start it at the model's home position.
            let model = &setup.loaded.model;
            let home: Vec<f64> = (0..model.dof())
                .zip(setup.loaded.home_or_neutral())
                .map(|(k, h)| model.limits(k).clamp(h))
                .collect();
            let name = format!("Coach at {server}");
            drive(robot, name, &mut setup, &signals, None, Some(home))
        }
    }
}

/// The loop period: `--rate` or the device's own.
fn period_for(setup: &Setup, device_period: Duration) -> Duration {
    setup
        .args
        .rate
        .map_or(device_period, |hz| Duration::from_secs_f64(1.0 / hz))
}

/// Validates flags and files (exit code 2 for anything wrong) before anything starts.
fn check(args: RunArgs) -> Result<Setup, CliError> {
    let device = DeviceSpec::parse(args.device.as_deref().unwrap_or("fake-h7"))?;
    if let Some(hz) = args.rate {
        if !(hz.is_finite() && (0.1..=20_000.0).contains(&hz)) {
            return Err(CliError::usage(format!(
                "--rate {hz}: give a control rate in Hz between 0.1 and 20000"
            )));
        }
        if matches!(device, DeviceSpec::H7 { .. }) {
            return Err(CliError::usage(
                "--rate: an H7 controller runs at its own 7.11 ms cycle; --rate applies to \
                 fake-h7 and coach://",
            ));
        }
    }
    let speed = args.speed.unwrap_or(DEFAULT_SPEED);
    let priority = args.priority.unwrap_or(DEFAULT_PRIORITY);
    let mut probe = RtThreadBuilder::new("rl-control")
        .policy(Policy::Fifo)
        .priority(priority);
    if let Some(cpu) = args.cpu {
        probe = probe.cpus([cpu]);
    }
    // Try the scheduling on a throw-away thread before anything starts: a bad CPU is a usage
    // error, a missing privilege a fallback to SCHED_OTHER with one warning.
    let thread = match probe.clone().spawn(|| ()).map(|t| t.join()) {
        Ok(_) => probe,
        Err(e @ ThreadError::PermissionDenied { .. }) => {
            eprintln!(
                "rl run: warning: {e}; running the loop at SCHED_OTHER, so its latency is not \
                 bounded"
            );
            probe.policy(Policy::Other).priority(0)
        }
        Err(e) => return Err(CliError::usage(format!("--priority/--cpu: {e}"))),
    };

    let (loaded, model_name) = match &args.model {
        None => (
            rl::controller::rv6sl()
                .map_err(|e| CliError::failed(format!("embedded model: {e}")))?,
            "Mitsubishi RV-6SL (embedded)".to_owned(),
        ),
        Some(path) => {
            let loaded = loader::load_file_with::<MAX_BODIES>(path, &UrdfOptions::default())
                .map_err(|e| CliError::usage(format!("--model: {e}")))?;
            let name = if loaded.model.name().is_empty() {
                path.display().to_string()
            } else {
                format!("{} ({})", loaded.model.name(), path.display())
            };
            (loaded, name)
        }
    };
    let model = &loaded.model;
    let limits = MotionLimits::from_model(model, speed).map_err(|e| {
        CliError::usage(match e {
            rl::controller::PlanError::SpeedFraction(_) => format!("--speed: {e}"),
            e => format!("model: {e}"),
        })
    })?;
    let joints: Vec<String> = (0..model.dof()).map(|k| joint_name(model, k)).collect();
    let waypoints = match &args.waypoints {
        None => None,
        Some(path) => Some(read_waypoints(path, model)?),
    };
    let telemetry_file = match &args.telemetry {
        None => None,
        Some(path) => Some(BufWriter::new(File::create(path).map_err(|e| {
            CliError::usage(format!(
                "--telemetry: cannot create {}: {e}",
                path.display()
            ))
        })?)),
    };
    if let Some(path) = &args.plot {
        File::create(path).map_err(|e| {
            CliError::usage(format!("--plot: cannot create {}: {e}", path.display()))
        })?;
    }
    Ok(Setup {
        args,
        device,
        loaded,
        model_name,
        joints,
        waypoints,
        limits,
        thread,
        telemetry_file,
    })
}

/// Reads waypoints: a header row, then one row per waypoint, one column per joint (rad or m);
/// `#` starts a comment. Each waypoint must lie within the model's position limits.
fn read_waypoints(path: &Path, model: &RobotModel) -> Result<Vec<Vec<f64>>, CliError> {
    let shown = path.display();
    let usage = |m: String| CliError::usage(format!("--waypoints {shown}{m}"));
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| usage(format!(": cannot read: {e}")))?;
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

/// Stop requests so far (SIGINT or SIGTERM).
type Signals = Arc<AtomicU8>;

fn watch_signals() -> Result<Signals, CliError> {
    let mut set = SigSet::empty();
    set.add(Signal::SIGINT);
    set.add(Signal::SIGTERM);
    set.thread_block()
        .map_err(|e| CliError::failed(format!("cannot block SIGINT/SIGTERM: {e}")))?;
    let count = Arc::new(AtomicU8::new(0));
    let seen = count.clone();
    std::thread::Builder::new()
        .name("rl-signals".into())
        .stack_size(64 << 10)
        .spawn(move || {
            while set.wait().is_ok() {
                let n = seen.fetch_add(1, Ordering::AcqRel) + 1;
                if n == 1 {
                    eprintln!(
                        "\nrl run: stopping: bringing the arm to rest along its path (Ctrl-C \
                         again to stop at once)"
                    );
                }
            }
        })
        .map_err(|e| CliError::failed(format!("cannot start the signal thread: {e}")))?;
    Ok(count)
}

/// What the control thread hands back.
struct LoopOutcome<R> {
    controller: Box<Controller<R>>,
    stats: LoopStats,
    loop_error: Option<String>,
}

/// Opens, starts and primes the device, plans, runs the loop, stops the device and reports.
fn drive<R: JointRobot + Send + 'static>(
    mut robot: R,
    device_name: String,
    setup: &mut Setup,
    signals: &Signals,
    fake: Option<&FakeH7>,
    initial_command: Option<Vec<f64>>,
) -> CliResult {
    let model = setup.loaded.model.clone();
    let dof = model.dof();
    let period = period_for(setup, robot.update_period());
    robot
        .open()
        .map_err(|e| CliError::failed(format!("cannot open {device_name}: {e}")))?;
    if let Err(e) = robot.start() {
        let _ = robot.close();
        return Err(CliError::failed(format!("cannot start {device_name}: {e}")));
    }
    // The first exchange tells where the arm is; the plan starts there. (A robot is never
    // sent a position before that; a visualiser is sent its initial one.)
    let mut start = vec![0.0; dof];
    if let Err(e) = initial_command
        .map_or(Ok(()), |q| robot.set_joint_position(&q))
        .and_then(|()| robot.step())
        .and_then(|()| robot.joint_position(&mut start))
    {
        let _ = shut_down(&mut robot, fake);
        return Err(CliError::failed(format!(
            "no joint positions from {device_name}: {e}"
        )));
    }
    let waypoints = setup
        .waypoints
        .clone()
        .unwrap_or_else(|| default_waypoints(&model, &start));
    let plan = match Plan::new(&model, &start, &waypoints, &setup.limits) {
        Ok(plan) => plan,
        Err(e) => {
            let _ = shut_down(&mut robot, fake);
            return Err(CliError::failed(format!("refusing to move: {e}")));
        }
    };
    if signals.load(Ordering::Acquire) > 0 {
        let _ = shut_down(&mut robot, fake);
        return Ok(ExitCode::from(130));
    }
    let plan_duration_s = plan.duration_s();
    let mut controller = Box::new(
        Controller::new(robot, model, plan, period)
            .map_err(|e| CliError::failed(format!("controller: {e}")))?,
    );
    if let Some(d) = setup.args.duration {
        controller.limit_cycles((d.as_secs_f64() / period.as_secs_f64()).round() as u64);
    }

    // Real-time set-up, with a fallback when this process may not have it.
    let memory_locked = !setup.args.no_mlock
        && match rl_rt::memory::lock_memory() {
            Ok(()) => true,
            Err(e) => {
                eprintln!(
                    "rl run: warning: {e}; running without locked memory (or pass --no-mlock)"
                );
                false
            }
        };
    let builder = setup.thread.clone();

    let collect = setup.telemetry_file.is_some() || setup.args.plot.is_some();
    let (tx, mut rx) = if collect {
        let (tx, rx) = queue::<CycleRecord>(TELEMETRY_CAPACITY);
        (Some(tx), Some(rx))
    } else {
        (None, None)
    };
    let (mut progress_tx, mut progress_rx) = mailbox(Progress::default());
    let looped = CyclicLoop::new(period)
        .map_err(|e| CliError::usage(format!("--rate: {e}")))?
        .overrun_policy(OverrunPolicy::Skip);
    let signals_rt = signals.clone();
    let thread = builder.spawn(move || {
        let mut controller = controller;
        let mut tx: Option<QueueSender<CycleRecord>> = tx;
        let mut stats = looped.new_stats();
        let mut worst_latency_ns = 0u64;
        let mut halted = false;
        let result = looped.run_into(&mut stats, |cycle| {
            match signals_rt.load(Ordering::Acquire) {
                0 => {}
                1 => {
                    if !halted {
                        controller.request_halt();
                        halted = true;
                    }
                }
                _ => controller.abort(),
            }
            let out = controller.cycle();
            let mut record = out.record;
            record.wakeup_latency_ns = cycle.wakeup_latency_ns;
            record.step_ns = MonoTime::now().nanos_since(cycle.woke);
            worst_latency_ns = worst_latency_ns.max(cycle.wakeup_latency_ns);
            if let Some(tx) = &mut tx {
                // A full queue hands the record back and counts the drop.
                let _ = tx.try_send(record);
            }
            progress_tx.publish(Progress {
                cycle: record.cycle,
                time_s: record.time_s,
                error_max_rad: controller.tracking().max_error(),
                worst_latency_ns,
                lost: controller.failed_steps(),
                halting: controller.clock().halting().is_some(),
            });
            if out.finished {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        drop(tx);
        LoopOutcome {
            controller,
            stats,
            loop_error: result.err().map(|e| e.to_string()),
        }
    });
    let thread = match thread {
        Ok(t) => t,
        Err(e) => {
            return Err(CliError::failed(format!(
                "cannot start the control thread: {e}"
            )));
        }
    };
    let scheduling = thread.granted().to_string();

    // This (non-real-time) thread writes telemetry and shows progress while the loop runs.
    let mut display = ProgressDisplay::new(plan_duration_s);
    let mut rows_written = 0u64;
    let mut plot_rows: Vec<CycleRecord> = Vec::new();
    let mut stride = 1u64;
    let mut write_error: Option<String> = None;
    if let Some(w) = &mut setup.telemetry_file {
        if let Err(e) = telemetry::write_header(w, &setup.joints) {
            write_error = Some(e.to_string());
        }
    }
    let mut drain = |rx: &mut Option<rl_rt::exchange::QueueReceiver<CycleRecord>>,
                     setup: &mut Setup| {
        let Some(rx) = rx else { return };
        while let Some(r) = rx.try_recv() {
            if let Some(w) = &mut setup.telemetry_file {
                if write_error.is_none() {
                    match telemetry::write_row(&mut *w, &r, dof) {
                        Ok(()) => rows_written += 1,
                        Err(e) => write_error = Some(e.to_string()),
                    }
                }
            }
            if setup.args.plot.is_some() && r.cycle % stride == 0 {
                if plot_rows.len() >= PLOT_ROWS {
                    stride *= 2;
                    plot_rows.retain(|r| r.cycle % stride == 0);
                }
                if r.cycle % stride == 0 {
                    plot_rows.push(r);
                }
            }
        }
    };
    let started = Instant::now();
    while !thread.is_finished() {
        std::thread::sleep(Duration::from_millis(50));
        drain(&mut rx, setup);
        display.update(progress_rx.read(), started.elapsed());
    }
    let outcome = match thread.join() {
        Ok(o) => o,
        Err(_) => return Err(CliError::failed("the control thread panicked")),
    };
    drain(&mut rx, setup);
    let dropped = rx.as_ref().map_or(0, |rx| rx.dropped());
    display.finish();
    if let Some(w) = &mut setup.telemetry_file {
        if let Err(e) = w.flush() {
            write_error.get_or_insert(e.to_string());
        }
    }

    let LoopOutcome {
        mut controller,
        stats,
        loop_error,
    } = outcome;
    let shutdown = shut_down(controller.robot_mut(), fake);
    let end = controller.end();
    let tracking = *controller.tracking();
    let mut failure = loop_error.map(|e| format!("control loop: {e}"));
    if let Some(RunEnd::DeviceFault(e)) = end {
        failure.get_or_insert(format!("device fault: {e}"));
    }
    if tracking.violations() > 0 {
        failure.get_or_insert(format!(
            "the measured motion crossed the model's limits {} times",
            tracking.violations()
        ));
    }
    if !shutdown.stopped {
        failure.get_or_insert(format!(
            "the device did not stop cleanly: {}",
            shutdown.error.as_deref().unwrap_or("unknown")
        ));
    }
    if let Some(e) = &write_error {
        failure.get_or_insert(format!("telemetry: {e}"));
    }
    let report = RunReport {
        model: setup.model_name.clone(),
        device: device_name,
        joints: setup.joints.clone(),
        period_s: period.as_secs_f64(),
        scheduling,
        memory_locked,
        plan_duration_s,
        trajectory_time_s: controller.clock().time_s(),
        end,
        stats,
        link: controller.robot().link_statistics(),
        lost_packets: controller.failed_steps(),
        tracking,
        shutdown,
        telemetry: setup
            .telemetry_file
            .as_ref()
            .map(|_| (rows_written, dropped)),
        failure,
    };
    if let Some(path) = &setup.args.plot {
        if let Err(e) = plot::draw(path, &report, &plot_rows) {
            eprintln!("rl run: warning: cannot draw {}: {e}", path.display());
        }
    }
    if setup.args.json {
        println!("{}", report.to_json());
    } else {
        print!("{report}");
    }
    Ok(if report.failure.is_some() {
        ExitCode::from(1)
    } else if matches!(end, Some(RunEnd::Stopped | RunEnd::Aborted)) {
        ExitCode::from(130)
    } else {
        ExitCode::SUCCESS
    })
}

/// Stops and closes the device (for the H7: end packet, program stop, servo off), and reads
/// what the in-process fake saw.
fn shut_down<R: JointRobot>(robot: &mut R, fake: Option<&FakeH7>) -> Shutdown {
    let mut shutdown = Shutdown {
        detail: robot.stop_description().to_owned(),
        ..Shutdown::default()
    };
    match robot.stop() {
        Ok(()) => shutdown.stopped = true,
        Err(e) => shutdown.error = Some(e.to_string()),
    }
    if let Err(e) = robot.close() {
        shutdown.error.get_or_insert(e.to_string());
    }
    if let Some(fake) = fake {
        // The end packet is a datagram sent without waiting; give the fake a moment.
        let deadline = Instant::now() + Duration::from_millis(500);
        let mut status = fake.status();
        while shutdown.stopped && status.ends == 0 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(5));
            status = fake.status();
        }
        shutdown.fake_end_packets = Some(status.ends);
        shutdown.fake_servo_on = Some(status.servo_on);
        shutdown.fake_limit_hits = Some(status.limit_hits);
    }
    shutdown
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse_with_units() {
        assert_eq!(parse_duration("3s"), Ok(Duration::from_secs(3)));
        assert_eq!(parse_duration("500ms"), Ok(Duration::from_millis(500)));
        assert_eq!(parse_duration("1.5"), Ok(Duration::from_millis(1500)));
        assert!(parse_duration("0s").is_err());
        assert!(parse_duration("3 parsecs").is_err());
    }
}
