//! `rlrs.ControlRun`: the supervised controller of `rl run` (the root crate's
//! `rl::controller::ControlRun`) started from Python against a fake or a real device, its
//! progress, telemetry as arrays and its report.
//!
//! The real-time loop runs in its own thread in Rust (SCHED_FIFO where the process may, else
//! as an ordinary thread, said in the report); Python only waits (with the GIL released),
//! drains the telemetry queue into arrays and reads the report. Devices are named as `rl run
//! --device` names them, through the library's device table ([`rl::devices`], the one `rl run`
//! uses), so a driver added there is reachable from Python too.
//!
//! With `follow=True` the run follows targets sent from Python (`send_position`,
//! `send_velocity`) instead of a planned tour: the controller's `TargetFollower`, rl-core's
//! online trajectory generator in the loop, as `rl run --follow` runs it. A target goes through
//! the run's lock-free mailbox, checked against the joints' limits on the way in.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rl::controller::{
    ControlLaw, ControlRun as Run, CycleRecord, DEFAULT_INPUT_TIMEOUT, InputSender, JointRobot,
    Progress, RunError, RunOptions, RunReport, Supervision, TargetFollower,
};
use rl_core::loader::{LoadOptions, LoadedModel};
use rl_rt::{StopFlag, StopLevel};

use crate::array::{Input, Output, shape_text};
use crate::model::Model;

use rl::devices::{DeviceSpec, InProcessFake};

/// Telemetry drained so far, column by column.
#[derive(Default)]
struct Telemetry {
    dof: usize,
    cycle: Vec<u64>,
    time: Vec<f64>,
    commanded: Vec<f64>,
    measured: Vec<f64>,
    feed_forward: Vec<f64>,
    latency_ns: Vec<u64>,
    step_ns: Vec<u64>,
}

impl Telemetry {
    fn push<const J: usize>(&mut self, r: &CycleRecord<J>) {
        let n = self.dof;
        self.cycle.push(r.cycle);
        self.time.push(r.time_s);
        self.commanded.extend_from_slice(&r.commanded[..n]);
        self.measured.extend_from_slice(&r.measured[..n]);
        self.feed_forward.extend_from_slice(&r.feed_forward[..n]);
        self.latency_ns.push(r.wakeup_latency_ns);
        self.step_ns.push(r.step_ns);
    }
}

/// A run of some capacity.
trait Running: Send {
    fn poll(&mut self, wait: Duration) -> Option<Progress>;
    fn drain(&mut self, into: &mut Telemetry);
    fn join(self: Box<Self>, into: &mut Telemetry) -> RunReport;
    fn joints(&self) -> Vec<String>;
    fn plan_duration_s(&self) -> f64;
    fn scheduling(&self) -> String;
    fn warnings(&self) -> Vec<String>;
    /// A sender of targets to the loop, apart from the run (a send never waits for a poll).
    fn sender(&self) -> Box<dyn Send_>;
}

/// Sends targets into a run's mailbox: a position (with the velocity to pass it at), or a
/// velocity.
trait Send_: Send {
    fn send(&self, position: Option<&[f64]>, velocity: Option<&[f64]>) -> Result<(), String>;
}

impl<const N: usize, X: Copy + Send + 'static> Send_ for InputSender<N, X> {
    fn send(&self, position: Option<&[f64]>, velocity: Option<&[f64]>) -> Result<(), String> {
        match (position, velocity) {
            (Some(p), Some(v)) => self.send_position_velocity(p, v),
            (Some(p), None) => self.send_position(p),
            (None, Some(v)) => self.send_velocity(v),
            (None, None) => return Ok(()),
        }
        .map_err(|e| e.to_string())
    }
}

impl<const N: usize, L> Running for Run<Box<dyn JointRobot + Send>, N, N, L>
where
    L: ControlLaw<N, N> + 'static,
    L::Input: Send,
{
    fn poll(&mut self, wait: Duration) -> Option<Progress> {
        Run::poll(self, wait)
    }

    fn drain(&mut self, into: &mut Telemetry) {
        self.drain_telemetry(|r| into.push(r));
    }

    fn join(self: Box<Self>, into: &mut Telemetry) -> RunReport {
        self.join_with(|r| into.push(r))
    }

    fn joints(&self) -> Vec<String> {
        Run::joints(self).to_vec()
    }

    fn plan_duration_s(&self) -> f64 {
        Run::plan_duration_s(self)
    }

    fn scheduling(&self) -> String {
        Run::scheduling(self).to_owned()
    }

    fn warnings(&self) -> Vec<String> {
        Run::warnings(self).to_vec()
    }

    fn sender(&self) -> Box<dyn Send_> {
        Box::new(self.inputs())
    }
}

/// A supervised controller run (what `rl run` does): the device is opened, the model checked
/// against it, a jerk-limited tour through the waypoints planned and checked against the
/// model's position, speed and effort limits before anything moves, then a real-time thread
/// follows it with inverse-dynamics feed-forward until the end, a stop request or a fault, and
/// stops the device safely.
///
/// Args:
///     device: as `rl run --device` (the device table `rl::devices::DEVICE_FORMS`, listed by
///         `rl run --help`): `fake-h7` (default: a fake Mitsubishi H7 in this process on
///         loopback), `h7://HOST[:PORT][?r3=PORT]`, `coach://HOST[:PORT]`, `fake-cia402`,
///         `cannelloni+udp://HOST:PORT[?nodes=1-6]`, `cannelloni+tcp://HOST:PORT`,
///         `socketcan://IFACE`, `ethercat://IF`, `franka://HOST[:PORT]`,
///         `ur://HOST[:PORT][?power-on]`.
///     model: a `Model` or a model file (default: the embedded Mitsubishi RV-6SL).
///     duration: stop (at rest, along the path) after this many seconds.
///     speed: fraction of the model's speed limits, in (0, 1] (default 0.25, as `rl run`).
///     waypoints: (k, dof) joint positions to visit (default: a tour from the limits).
///     rate: control rate, Hz, 0.1 to 20000 (the H7, on its fixed cycle, refuses any).
///     priority: SCHED_FIFO priority of the loop thread.
///     cpus: CPUs to pin the loop thread to.
///     lock_memory: mlockall before the loop (locks the whole Python process; off by default).
///     supervision: the per-cycle checks that end a run on a fault.
///     tracking_bound: the largest tracking error, rad (or m): one value or one per joint.
///     telemetry: keep one record per cycle for `telemetry()`.
///     follow: follow the targets sent with `send_position` and `send_velocity` (rl-core's
///         online trajectory generator in the loop, as `rl run --follow`) instead of a tour;
///         the arm holds where it stands until the first.
///     input_timeout: with `follow`, the longest wait for the next target, s (default 2):
///         then the arm is brought to rest and the run fails.
///
/// Raises RunError when the run does not start (nothing moved).
#[pyclass(frozen, module = "rlrs")]
pub struct ControlRun {
    run: Mutex<Option<Box<dyn Running>>>,
    telemetry: Mutex<Telemetry>,
    fake: Mutex<Option<InProcessFake>>,
    stop: StopFlag,
    joints: Vec<String>,
    plan_duration_s: f64,
    scheduling: String,
    warnings: Vec<String>,
    report: Mutex<Option<Py<PyAny>>>,
    /// Targets into the loop (`follow=True`; dropped with the run's end).
    targets: Mutex<Option<Box<dyn Send_>>>,
    follow: bool,
    dof: usize,
}

impl ControlRun {
    /// `x` as one value per joint.
    fn joint_vector(&self, x: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
        let input = Input::new(x, name)?;
        if input.shape() != [self.dof] {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {}, expected ({},)",
                shape_text(input.shape()),
                self.dof
            )));
        }
        Ok(input.slice().to_vec())
    }

    fn send(&self, py: Python<'_>, p: Option<&[f64]>, v: Option<&[f64]>) -> PyResult<()> {
        if !self.follow {
            return Err(PyValueError::new_err(
                "this run follows its tour: start it with follow=True to send it targets",
            ));
        }
        let targets = crate::gil::lock(py, &self.targets);
        let Some(targets) = targets.as_ref() else {
            return Err(crate::error::RunError::new_err("the run has ended"));
        };
        targets.send(p, v).map_err(PyValueError::new_err)
    }
}

/// The model of a run, loaded at capacity `N` (16 or 64).
enum RunModel {
    Small(Box<LoadedModel<16>>),
    Large(Box<LoadedModel<64>>),
}

fn run_model(model: Option<&Bound<'_, PyAny>>) -> PyResult<(RunModel, String)> {
    let Some(model) = model else {
        let m = rl::controller::rv6sl().map_err(crate::error::load)?;
        return Ok((
            RunModel::Small(Box::new(m)),
            "Mitsubishi RV-6SL (embedded)".into(),
        ));
    };
    let (any, name) = if let Ok(m) = model.cast::<Model>() {
        let m = m.get();
        (Some(m.kin.loaded()), m.name_and_path())
    } else {
        (None, String::new())
    };
    if let Some(any) = any {
        if let Some(l) = any.downcast_ref::<LoadedModel<16>>() {
            return Ok((RunModel::Small(Box::new(l.clone())), name));
        }
        if let Some(l) = any.downcast_ref::<LoadedModel<64>>() {
            return Ok((RunModel::Large(Box::new(l.clone())), name));
        }
        return Err(PyValueError::new_err(
            "model: a controller run takes models of up to 64 bodies and joints",
        ));
    }
    let path: PathBuf = model.extract()?;
    let options = LoadOptions::default();
    match rl_core::loader::load_file_options::<16>(&path, &options) {
        Ok(m) => Ok((RunModel::Small(Box::new(m)), path.display().to_string())),
        Err(_) => {
            let m = rl_core::loader::load_file_options::<64>(&path, &options)
                .map_err(crate::error::load)?;
            Ok((RunModel::Large(Box::new(m)), path.display().to_string()))
        }
    }
}

/// Starts the run at capacity `N`: the planned tour, or (`follow`) the target follower.
fn start<const N: usize>(
    spec: &DeviceSpec,
    loaded: LoadedModel<N>,
    period: Option<Duration>,
    mut options: RunOptions,
    follow: bool,
) -> PyResult<(Box<dyn Running>, Option<InProcessFake>)> {
    let opened = spec
        .build(
            &loaded,
            period,
            None,
            options.supervision.device_failure_limit(),
            false,
        )
        .map_err(|e| {
            if e.is_input() {
                PyValueError::new_err(e.to_string())
            } else {
                crate::error::RunError::new_err(e.to_string())
            }
        })?;
    options.device_name = opened.name;
    let cycle = opened.robot.update_period();
    options
        .supervision
        .allow_device_lag(opened.lag, period.map_or(cycle, |p| p.max(cycle)));
    let robot: Box<dyn JointRobot + Send> = opened.robot;
    let refused = |e: RunError| match e {
        RunError::Options(why) => PyValueError::new_err(why),
        e => crate::error::RunError::new_err(e.to_string()),
    };
    let run: Box<dyn Running> = if follow {
        Box::new(
            Run::<_, N, N, _>::start_law(robot, loaded, options, TargetFollower::<N>::new())
                .map_err(refused)?,
        )
    } else {
        Box::new(Run::<_, N, N>::start(robot, loaded, options).map_err(refused)?)
    };
    Ok((run, opened.fake))
}

#[pymethods]
impl ControlRun {
    #[new]
    #[pyo3(signature = (device="fake-h7", model=None, duration=None, speed=rl::controller::runtime::DEFAULT_SPEED, waypoints=None, rate=None, priority=80, cpus=Vec::new(), lock_memory=false, supervision=true, tracking_bound=None, telemetry=true, follow=false, input_timeout=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        device: &str,
        model: Option<&Bound<'_, PyAny>>,
        duration: Option<f64>,
        speed: f64,
        waypoints: Option<&Bound<'_, PyAny>>,
        rate: Option<f64>,
        priority: i32,
        cpus: Vec<usize>,
        lock_memory: bool,
        supervision: bool,
        tracking_bound: Option<&Bound<'_, PyAny>>,
        telemetry: bool,
        follow: bool,
        input_timeout: Option<f64>,
    ) -> PyResult<Self> {
        if !follow && input_timeout.is_some() {
            return Err(PyValueError::new_err(
                "input_timeout: only a run that follows targets (follow=True) waits for them",
            ));
        }
        if follow && waypoints.is_some() {
            return Err(PyValueError::new_err(
                "waypoints: a run that follows targets (follow=True) has no tour",
            ));
        }
        let input_timeout = match input_timeout {
            None => follow.then_some(DEFAULT_INPUT_TIMEOUT),
            Some(s) if s.is_finite() && s > 0.0 => Some(Duration::from_secs_f64(s)),
            Some(s) => {
                return Err(PyValueError::new_err(format!(
                    "input_timeout={s}: give a positive number of seconds"
                )));
            }
        };
        let spec = DeviceSpec::parse(device).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let period = rate
            .map(|hz| spec.period_for_rate(hz))
            .transpose()
            .map_err(|e| PyValueError::new_err(format!("rate={}", e.message())))?;
        let duration = match duration {
            None => None,
            Some(s) if s.is_finite() && s > 0.0 => Some(Duration::from_secs_f64(s)),
            Some(s) => {
                return Err(PyValueError::new_err(format!(
                    "duration={s}: give a positive number of seconds"
                )));
            }
        };
        let (loaded, model_name) = run_model(model)?;
        let dof = match &loaded {
            RunModel::Small(l) => l.model.dof(),
            RunModel::Large(l) => l.model.dof(),
        };
        let waypoints = match waypoints {
            None => None,
            Some(w) => {
                let w = Input::new(w, "waypoints")?;
                match w.shape() {
                    [_, n] if *n == dof => {}
                    s => {
                        return Err(PyValueError::new_err(format!(
                            "waypoints: shape {}, expected (k, {dof})",
                            shape_text(s)
                        )));
                    }
                }
                Some(
                    w.slice()
                        .chunks_exact(dof.max(1))
                        .map(<[f64]>::to_vec)
                        .collect(),
                )
            }
        };
        let mut supervise = Supervision {
            enabled: supervision,
            ..Supervision::default()
        };
        if let Some(b) = tracking_bound {
            supervise.tracking_error = match crate::array::scalar(b) {
                Some(x) => vec![x; dof],
                None => {
                    let b = Input::new(b, "tracking_bound")?;
                    if b.shape() != [dof] {
                        return Err(PyValueError::new_err(format!(
                            "tracking_bound: shape {}, expected one value or ({dof},)",
                            shape_text(b.shape())
                        )));
                    }
                    b.slice().to_vec()
                }
            };
            if supervise
                .tracking_error
                .iter()
                .any(|x| !(x.is_finite() && *x > 0.0))
            {
                return Err(PyValueError::new_err(
                    "tracking_bound: give positive bounds in rad (or m)",
                ));
            }
        }
        let stop = StopFlag::new();
        let options = RunOptions {
            speed,
            waypoints,
            duration,
            period,
            priority,
            cpus,
            lock_memory,
            supervision: supervise,
            telemetry,
            stop: stop.clone(),
            model_name,
            input_timeout,
            ..RunOptions::default()
        };
        let started = py.detach(|| match loaded {
            RunModel::Small(l) => start::<16>(&spec, *l, period, options, follow),
            RunModel::Large(l) => start::<64>(&spec, *l, period, options, follow),
        });
        let (run, fake) = started?;
        let targets = follow.then(|| run.sender());
        Ok(Self {
            targets: Mutex::new(targets),
            joints: run.joints(),
            plan_duration_s: run.plan_duration_s(),
            scheduling: run.scheduling(),
            warnings: run.warnings(),
            run: Mutex::new(Some(run)),
            telemetry: Mutex::new(Telemetry {
                dof,
                ..Telemetry::default()
            }),
            fake: Mutex::new(fake),
            stop,
            report: Mutex::new(None),
            follow,
            dof,
        })
    }

    /// Sends a position target (follow=True): the arm goes there along the time-optimal
    /// jerk-limited motion from the state commanded last, and arrives at rest or, with
    /// `velocity`, passing it at that velocity. Raises ValueError for a target the joints'
    /// limits refuse (naming the joint) and for a run that follows a tour.
    #[pyo3(signature = (position, velocity=None))]
    fn send_position(
        &self,
        py: Python<'_>,
        position: &Bound<'_, PyAny>,
        velocity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let p = self.joint_vector(position, "position")?;
        let v = velocity
            .map(|v| self.joint_vector(v, "velocity"))
            .transpose()?;
        self.send(py, Some(&p), v.as_deref())
    }

    /// Sends a velocity target (follow=True): the arm reaches that joint velocity and keeps it
    /// (until a new target, a stop, or a position limit ahead, where it brakes).
    fn send_velocity(&self, py: Python<'_>, velocity: &Bound<'_, PyAny>) -> PyResult<()> {
        let v = self.joint_vector(velocity, "velocity")?;
        self.send(py, None, Some(&v))
    }

    /// Whether the run follows targets sent from Python (`follow=True`).
    #[getter]
    fn follows(&self) -> bool {
        self.follow
    }

    /// The joints driven, in order.
    #[getter]
    fn joints(&self) -> Vec<String> {
        self.joints.clone()
    }

    /// The planned trajectory's duration, s.
    #[getter]
    fn plan_duration(&self) -> f64 {
        self.plan_duration_s
    }

    /// How the loop thread is scheduled (policy, priority, CPUs, or why not).
    #[getter]
    fn scheduling(&self) -> &str {
        &self.scheduling
    }

    /// What the set-up noted (no SCHED_FIFO, no mlockall, assumed speeds).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Waits up to `timeout` seconds (GIL released) for the loop's progress: {cycle, time,
    /// error_max, worst_latency_ns, lost, halting, faulted, stop}; None once the run has
    /// ended. Drains the telemetry as it goes.
    #[pyo3(signature = (timeout=0.1))]
    fn poll<'py>(&self, py: Python<'py>, timeout: f64) -> PyResult<Option<Bound<'py, PyAny>>> {
        let wait = Duration::from_secs_f64(timeout.clamp(0.0, 3600.0));
        let mut running = crate::gil::lock(py, &self.run);
        let Some(run) = running.as_mut() else {
            return Ok(None);
        };
        let mut drained = crate::gil::lock(py, &self.telemetry);
        let telemetry: &mut Telemetry = &mut drained;
        let progress = py.detach(|| {
            let p = run.poll(wait);
            run.drain(telemetry);
            p
        });
        progress.map(|p| progress_dict(py, &p)).transpose()
    }

    /// Asks the run to stop: come to rest along the path, or (`now=True`) at once.
    #[pyo3(signature = (now=false))]
    fn stop(&self, now: bool) {
        self.stop
            .request(if now { StopLevel::Now } else { StopLevel::Rest });
    }

    /// Waits for the end (GIL released; Ctrl-C in Python is not seen meanwhile: bound it with
    /// `duration` or call `stop` from another thread) and returns the report (see `join`).
    fn wait<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        while self.poll(py, 0.2)?.is_some() {
            py.check_signals()?;
        }
        self.join(py)
    }

    /// Ends the run (waits for the loop to finish), stops the device safely and returns the
    /// report as a dict (`rl run --json`'s keys, plus "text": the report `rl run` prints, and
    /// for an in-process fake what it saw). Later calls return the same report.
    fn join<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut cached = crate::gil::lock(py, &self.report);
        if let Some(r) = cached.as_ref() {
            return Ok(r.bind(py).clone());
        }
        crate::gil::lock(py, &self.targets).take();
        let run = crate::gil::lock(py, &self.run).take();
        let Some(run) = run else {
            return Err(PyValueError::new_err("the run has no report"));
        };
        let mut drained = crate::gil::lock(py, &self.telemetry);
        let telemetry: &mut Telemetry = &mut drained;
        let fake = crate::gil::lock(py, &self.fake).take();
        let (report, fake_json) = py.detach(|| {
            let mut report = run.join(telemetry);
            let seen = fake.as_ref().map(|f| f.after_run(report.shutdown.stopped));
            let json = seen.map(|s| {
                report.notes.push(s.note);
                report.peer_lateness = s.lateness;
                if let Err(why) = s.safe {
                    report.fail(why);
                }
                s.json
            });
            drop(fake);
            (report, json)
        });
        let mut json = report.to_json();
        if let (Some(obj), Some(serde_json::Value::Object(seen))) =
            (json.as_object_mut(), fake_json)
        {
            obj.extend(seen);
        }
        let loads = py.import("json")?.getattr("loads")?;
        let dict = loads.call1((json.to_string(),))?;
        dict.set_item("text", report.to_string())?;
        dict.set_item("exit_code", report.exit_code())?;
        *cached = Some(dict.clone().unbind());
        Ok(dict)
    }

    /// The telemetry so far (after `poll`, `wait` or `join` drained it), one row per cycle:
    /// {cycle, t, commanded (n, dof), measured (n, dof), feed_forward (n, dof), latency_ns,
    /// step_ns}.
    fn telemetry<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = crate::gil::lock(py, &self.telemetry);
        let n = t.cycle.len();
        let d = PyDict::new(py);
        let column = |values: &[f64], shape: &[usize]| {
            let mut o = Output::<f64>::zeros(py, shape);
            o.as_mut_slice().copy_from_slice(values);
            o.into_any()
        };
        let ints = |values: &[u64]| {
            let mut o = Output::<u64>::zeros(py, &[values.len()]);
            o.as_mut_slice().copy_from_slice(values);
            o.into_any()
        };
        d.set_item("cycle", ints(&t.cycle))?;
        d.set_item("t", column(&t.time, &[n]))?;
        d.set_item("commanded", column(&t.commanded, &[n, t.dof]))?;
        d.set_item("measured", column(&t.measured, &[n, t.dof]))?;
        d.set_item("feed_forward", column(&t.feed_forward, &[n, t.dof]))?;
        d.set_item("latency_ns", ints(&t.latency_ns))?;
        d.set_item("step_ns", ints(&t.step_ns))?;
        Ok(d.into_any())
    }
}

fn progress_dict<'py>(py: Python<'py>, p: &Progress) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("cycle", p.cycle)?;
    d.set_item("time", p.time_s)?;
    d.set_item("error_max", p.error_max_rad)?;
    d.set_item("worst_latency_ns", p.worst_latency_ns)?;
    d.set_item("lost", p.lost)?;
    d.set_item("halting", p.halting)?;
    d.set_item("faulted", p.faulted)?;
    d.set_item(
        "stop",
        match p.stop {
            StopLevel::None => "none",
            StopLevel::Rest => "rest",
            StopLevel::Now => "now",
        },
    )?;
    Ok(d.into_any())
}
