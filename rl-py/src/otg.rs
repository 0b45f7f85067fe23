//! `rlrs.otg` and `rlrs.Otg`: rl-core's online trajectory generator (Ruckig's method: from any
//! state to any target state, time-optimal, jerk-limited, limits per direction, position
//! limits, waypoints, a minimum duration), offline on arrays of times and online one control
//! cycle per call.
//!
//! rl-core's `Otg<N>` fixes the number of axes at compile time; the module is built for
//! [`AXES`] and pads the axes it is not given with axes at rest at 0 whose target is 0 (unit
//! limits): they need no time, do not lengthen the others, and stay at 0 under any
//! synchronisation.

use std::time::Duration;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use rl_core::traj::Sample;
use rl_core::traj::otg::{
    self, Input, Interface, Limits, OtgError, OtgTrajectory, State, Synchronization,
    WaypointTrajectory,
};

use crate::array::{Input as Array, scalar, shape_text};
use crate::error;
use crate::traj::{Samples, sample_rows, sample_times};

/// Capacities (most axes) the generator is built for.
pub const AXES: &[usize] = &[8, 16];

/// Everything a request says, per axis (`axes` values each), before it is padded.
#[derive(Clone, Debug)]
struct Request {
    current: [Vec<f64>; 3],
    target: [Vec<f64>; 3],
    max_velocity: Vec<f64>,
    min_velocity: Option<Vec<f64>>,
    max_acceleration: Vec<f64>,
    min_acceleration: Option<Vec<f64>>,
    max_jerk: Vec<f64>,
    min_position: Option<Vec<f64>>,
    max_position: Option<Vec<f64>>,
    interface: Interface,
    synchronization: Synchronization,
    minimum_duration: Option<f64>,
    waypoints: Vec<Vec<f64>>,
}

/// `x` padded to `N` with `fill`.
fn pad<const N: usize>(x: &[f64], fill: f64) -> [f64; N] {
    let mut a = [fill; N];
    a[..x.len()].copy_from_slice(x);
    a
}

impl Request {
    fn limits<const N: usize>(&self) -> Limits<N> {
        let mut l = Limits::new(
            pad(&self.max_velocity, 1.0),
            pad(&self.max_acceleration, 1.0),
            pad(&self.max_jerk, 1.0),
        );
        if let Some(v) = &self.min_velocity {
            l.min_velocity = pad(v, -1.0);
        }
        if let Some(a) = &self.min_acceleration {
            l.min_acceleration = pad(a, -1.0);
        }
        if let Some(p) = &self.min_position {
            l.min_position = pad(p, f64::NEG_INFINITY);
        }
        if let Some(p) = &self.max_position {
            l.max_position = pad(p, f64::INFINITY);
        }
        l
    }

    fn input<const N: usize>(&self) -> Result<Input<N>, String> {
        let state = |s: &[Vec<f64>; 3]| State {
            position: pad(&s[0], 0.0),
            velocity: pad(&s[1], 0.0),
            acceleration: pad(&s[2], 0.0),
        };
        let mut input = Input::new(state(&self.current), state(&self.target), self.limits());
        input.interface = self.interface;
        input.synchronization = self.synchronization;
        input.minimum_duration = self.minimum_duration;
        for (i, w) in self.waypoints.iter().enumerate() {
            input.waypoints.push(pad(w, 0.0)).map_err(|_| {
                format!(
                    "waypoints: {} given, at most {} are supported (waypoint {i})",
                    self.waypoints.len(),
                    otg::MAX_WAYPOINTS
                )
            })?;
        }
        Ok(input)
    }
}

/// A calculated trajectory of some capacity.
trait Traj: Send + Sync {
    fn duration(&self) -> f64;
    /// Each axis' own shortest duration (`None` for a waypoint trajectory).
    fn min_durations(&self, axes: usize) -> Option<Vec<f64>>;
    /// Each section's duration (one for a trajectory without waypoints).
    fn sections(&self) -> Vec<f64>;
    /// Samples `times` into `out` = [position, velocity, acceleration, jerk], each
    /// `times.len() × axes`.
    fn sample_into(&self, times: &[f64], axes: usize, out: [&mut [f64]; 4]);
}

/// One sample, per axis (capacity-sized; the caller takes its axes).
type SampleRow = [Vec<f64>; 4];

fn row<const N: usize>(s: &Sample<N>) -> SampleRow {
    [
        s.position.to_vec(),
        s.velocity.to_vec(),
        s.acceleration.to_vec(),
        s.jerk.to_vec(),
    ]
}

impl<const N: usize> Traj for OtgTrajectory<N> {
    fn duration(&self) -> f64 {
        OtgTrajectory::duration(self)
    }
    fn min_durations(&self, axes: usize) -> Option<Vec<f64>> {
        Some(OtgTrajectory::min_durations(self)[..axes].to_vec())
    }
    fn sections(&self) -> Vec<f64> {
        vec![OtgTrajectory::duration(self)]
    }
    fn sample_into(&self, times: &[f64], axes: usize, out: [&mut [f64]; 4]) {
        sample_rows(|t| self.at_time(t), times, axes, out);
    }
}

impl<const N: usize> Traj for WaypointTrajectory<N> {
    fn duration(&self) -> f64 {
        WaypointTrajectory::duration(self)
    }
    fn min_durations(&self, _: usize) -> Option<Vec<f64>> {
        None
    }
    fn sections(&self) -> Vec<f64> {
        WaypointTrajectory::sections(self)
            .iter()
            .map(OtgTrajectory::duration)
            .collect()
    }
    fn sample_into(&self, times: &[f64], axes: usize, out: [&mut [f64]; 4]) {
        sample_rows(|t| self.at_time(t), times, axes, out);
    }
}

fn calculate<const N: usize>(r: &Request) -> Result<Box<dyn Traj>, String> {
    let input = r.input::<N>()?;
    let fail = |e: OtgError| e.to_string();
    Ok(if input.waypoints.is_empty() {
        Box::new(otg::calculate(&input).map_err(fail)?)
    } else {
        Box::new(otg::calculate_waypoints(&input).map_err(fail)?)
    })
}

/// The capacity for `axes`, or a `ValueError`.
fn capacity(axes: usize) -> PyResult<usize> {
    AXES.iter()
        .copied()
        .find(|&c| c >= axes && axes > 0)
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "{axes} axes: rlrs builds the trajectory generator for 1 to {} axes \
                 (rl-py/src/otg.rs, AXES)",
                AXES[AXES.len() - 1]
            ))
        })
}

/// `x` as `axes` values: itself, or one value repeated.
fn per_axis(x: &Bound<'_, PyAny>, name: &str, axes: usize) -> PyResult<Vec<f64>> {
    if let Some(v) = scalar(x) {
        return Ok(vec![v; axes]);
    }
    let input = Array::new(x, name)?;
    match input.shape() {
        [n] if *n == axes => Ok(input.slice().to_vec()),
        s => Err(PyValueError::new_err(format!(
            "{name}: shape {}, expected one value or ({axes},)",
            shape_text(s)
        ))),
    }
}

fn optional(x: Option<&Bound<'_, PyAny>>, name: &str, axes: usize) -> PyResult<Option<Vec<f64>>> {
    x.map(|x| per_axis(x, name, axes)).transpose()
}

fn interface(name: &str) -> PyResult<Interface> {
    match name {
        "position" => Ok(Interface::Position),
        "velocity" => Ok(Interface::Velocity),
        other => Err(PyValueError::new_err(format!(
            "interface \"{other}\": use \"position\" or \"velocity\""
        ))),
    }
}

fn synchronization(name: &str) -> PyResult<Synchronization> {
    match name {
        "time" => Ok(Synchronization::Time),
        "time_if_necessary" => Ok(Synchronization::TimeIfNecessary),
        "phase" => Ok(Synchronization::Phase),
        "none" => Ok(Synchronization::None),
        other => Err(PyValueError::new_err(format!(
            "synchronization \"{other}\": use \"time\", \"time_if_necessary\", \"phase\" or \"none\""
        ))),
    }
}

/// The number of axes of a position argument.
fn axes_of(x: &Bound<'_, PyAny>, name: &str) -> PyResult<usize> {
    let input = Array::new(x, name)?;
    match input.shape() {
        [n] => Ok(*n),
        s => Err(PyValueError::new_err(format!(
            "{name}: shape {}, expected (axes,)",
            shape_text(s)
        ))),
    }
}

/// The goal's keywords, shared by `rlrs.otg` and `Otg.update`.
struct Goal<'a, 'py> {
    target_position: &'a Bound<'py, PyAny>,
    max_velocity: &'a Bound<'py, PyAny>,
    max_acceleration: &'a Bound<'py, PyAny>,
    max_jerk: &'a Bound<'py, PyAny>,
    target_velocity: Option<&'a Bound<'py, PyAny>>,
    target_acceleration: Option<&'a Bound<'py, PyAny>>,
    min_velocity: Option<&'a Bound<'py, PyAny>>,
    min_acceleration: Option<&'a Bound<'py, PyAny>>,
    min_position: Option<&'a Bound<'py, PyAny>>,
    max_position: Option<&'a Bound<'py, PyAny>>,
    interface: &'a str,
    synchronization: &'a str,
    minimum_duration: Option<f64>,
    waypoints: Option<&'a Bound<'py, PyAny>>,
}

impl Goal<'_, '_> {
    fn request(&self, current: [Vec<f64>; 3], axes: usize) -> PyResult<Request> {
        let zeros = || vec![0.0; axes];
        let waypoints = match self.waypoints {
            None => Vec::new(),
            Some(w) => {
                let input = Array::new(w, "waypoints")?;
                match input.shape() {
                    [_, n] if *n == axes => input
                        .slice()
                        .chunks_exact(axes.max(1))
                        .map(<[f64]>::to_vec)
                        .collect(),
                    [0] => Vec::new(),
                    s => {
                        return Err(PyValueError::new_err(format!(
                            "waypoints: shape {}, expected (n, {axes})",
                            shape_text(s)
                        )));
                    }
                }
            }
        };
        Ok(Request {
            current,
            target: [
                per_axis(self.target_position, "target_position", axes)?,
                optional(self.target_velocity, "target_velocity", axes)?.unwrap_or_else(zeros),
                optional(self.target_acceleration, "target_acceleration", axes)?
                    .unwrap_or_else(zeros),
            ],
            max_velocity: per_axis(self.max_velocity, "max_velocity", axes)?,
            min_velocity: optional(self.min_velocity, "min_velocity", axes)?,
            max_acceleration: per_axis(self.max_acceleration, "max_acceleration", axes)?,
            min_acceleration: optional(self.min_acceleration, "min_acceleration", axes)?,
            max_jerk: per_axis(self.max_jerk, "max_jerk", axes)?,
            min_position: optional(self.min_position, "min_position", axes)?,
            max_position: optional(self.max_position, "max_position", axes)?,
            interface: interface(self.interface)?,
            synchronization: synchronization(self.synchronization)?,
            minimum_duration: self.minimum_duration,
            waypoints,
        })
    }
}

/// The time-optimal jerk-limited trajectory from the current state to the target state
/// (rl-core's online trajectory generator, Ruckig's method; the same durations as Ruckig's).
///
/// Args:
///     current_position, target_position: per axis (axes,), 1 to 16 axes.
///     max_velocity, max_acceleration, max_jerk: limits, one per axis or one for all; may be
///         `inf` (that derivative is free) or 0.
///     current_velocity, current_acceleration, target_velocity, target_acceleration: default 0.
///     min_velocity, min_acceleration: the limits in the negative direction (default the
///         negated maxima).
///     min_position, max_position: position limits, never crossed (default none).
///     interface: "position", or "velocity" (reach the target velocity, position free).
///     synchronization: "time" (all axes arrive together), "time_if_necessary", "phase" (a
///         straight line in joint space where the input allows) or "none".
///     minimum_duration: the trajectory takes at least this long, s.
///     waypoints: up to 8 positions (n, axes) to pass on the way.
///
/// Raises TrajectoryError with the generator's reason and axis when no trajectory exists
/// (a target outside the limits, position limits that cannot be kept, …), ValueError for
/// arguments of the wrong shape.
#[pyfunction(name = "otg")]
#[pyo3(signature = (current_position, target_position, max_velocity, max_acceleration, max_jerk, *, current_velocity=None, current_acceleration=None, target_velocity=None, target_acceleration=None, min_velocity=None, min_acceleration=None, min_position=None, max_position=None, interface="position", synchronization="time", minimum_duration=None, waypoints=None))]
#[allow(clippy::too_many_arguments)]
pub fn otg_calculate(
    current_position: &Bound<'_, PyAny>,
    target_position: &Bound<'_, PyAny>,
    max_velocity: &Bound<'_, PyAny>,
    max_acceleration: &Bound<'_, PyAny>,
    max_jerk: &Bound<'_, PyAny>,
    current_velocity: Option<&Bound<'_, PyAny>>,
    current_acceleration: Option<&Bound<'_, PyAny>>,
    target_velocity: Option<&Bound<'_, PyAny>>,
    target_acceleration: Option<&Bound<'_, PyAny>>,
    min_velocity: Option<&Bound<'_, PyAny>>,
    min_acceleration: Option<&Bound<'_, PyAny>>,
    min_position: Option<&Bound<'_, PyAny>>,
    max_position: Option<&Bound<'_, PyAny>>,
    interface: &str,
    synchronization: &str,
    minimum_duration: Option<f64>,
    waypoints: Option<&Bound<'_, PyAny>>,
) -> PyResult<OtgTrajectoryPy> {
    let axes = axes_of(current_position, "current_position")?;
    let cap = capacity(axes)?;
    let zeros = || vec![0.0; axes];
    let current = [
        per_axis(current_position, "current_position", axes)?,
        optional(current_velocity, "current_velocity", axes)?.unwrap_or_else(zeros),
        optional(current_acceleration, "current_acceleration", axes)?.unwrap_or_else(zeros),
    ];
    let request = Goal {
        target_position,
        max_velocity,
        max_acceleration,
        max_jerk,
        target_velocity,
        target_acceleration,
        min_velocity,
        min_acceleration,
        min_position,
        max_position,
        interface,
        synchronization,
        minimum_duration,
        waypoints,
    }
    .request(current, axes)?;
    let built = match cap {
        8 => calculate::<8>(&request),
        _ => calculate::<16>(&request),
    };
    let inner = built.map_err(error::TrajectoryError::new_err)?;
    Ok(OtgTrajectoryPy { inner, axes })
}

/// A trajectory of `rlrs.otg`: its duration, each axis' own shortest duration, and samples
/// on arrays of times.
#[pyclass(frozen, name = "OtgTrajectory", module = "rlrs")]
pub struct OtgTrajectoryPy {
    inner: Box<dyn Traj>,
    axes: usize,
}

#[pymethods]
impl OtgTrajectoryPy {
    /// The duration, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration()
    }

    /// Number of axes.
    #[getter]
    fn axes(&self) -> usize {
        self.axes
    }

    /// Each axis' own shortest duration, s (None for a trajectory through waypoints).
    #[getter]
    fn min_durations<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        self.inner
            .min_durations(self.axes)
            .map(|d| crate::array::vector(py, &d))
    }

    /// Each section's duration, s (between waypoints; one section without them).
    #[getter]
    fn sections<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        crate::array::vector(py, &self.inner.sections())
    }

    /// Position, velocity, acceleration and jerk at `t` (before 0 the start state, after the
    /// duration the target state continued): four (axes,) arrays for one time, four
    /// (len(t), axes) arrays for an array of times.
    fn sample<'py>(&self, py: Python<'py>, t: &Bound<'py, PyAny>) -> PyResult<Samples<'py>> {
        let (inner, axes) = (&*self.inner, self.axes);
        sample_times(py, t, axes, |times, out| {
            inner.sample_into(times, axes, out)
        })
    }

    /// Position at `t`: (axes,) for one time, (len(t), axes) for an array of times.
    fn __call__<'py>(&self, py: Python<'py>, t: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        Ok(self.sample(py, t)?.0)
    }

    fn __repr__(&self) -> String {
        format!(
            "<rlrs.OtgTrajectory {} axes, {:.6} s>",
            self.axes,
            self.inner.duration()
        )
    }
}

/// A generator of some capacity, for the control loop.
trait Gen: Send + Sync {
    fn update(&mut self, r: &Request) -> Result<(SampleRow, bool, bool), String>;
    fn step(&mut self) -> (SampleRow, bool);
    fn brake(&mut self, r: &Request) -> Result<(), String>;
    fn state(&self) -> [Vec<f64>; 3];
    fn time(&self) -> f64;
    fn duration(&self) -> f64;
}

impl<const N: usize> Gen for otg::Otg<N> {
    fn update(&mut self, r: &Request) -> Result<(SampleRow, bool, bool), String> {
        let input = r.input::<N>()?;
        let out = otg::Otg::update(self, &input).map_err(|e| e.to_string())?;
        Ok((row(&out.sample), out.finished, out.recalculated))
    }
    fn step(&mut self) -> (SampleRow, bool) {
        let out = otg::Otg::step(self);
        (row(&out.sample), out.finished)
    }
    fn brake(&mut self, r: &Request) -> Result<(), String> {
        otg::Otg::brake(self, &r.limits::<N>(), r.synchronization).map_err(|e| e.to_string())
    }
    fn state(&self) -> [Vec<f64>; 3] {
        let s = otg::Otg::state(self);
        [
            s.position.to_vec(),
            s.velocity.to_vec(),
            s.acceleration.to_vec(),
        ]
    }
    fn time(&self) -> f64 {
        otg::Otg::time(self)
    }
    fn duration(&self) -> f64 {
        self.trajectory().duration()
    }
}

fn generator<const N: usize>(cycle: Duration, state: &[Vec<f64>; 3]) -> Box<dyn Gen> {
    Box::new(otg::Otg::<N>::new(
        cycle,
        State {
            position: pad(&state[0], 0.0),
            velocity: pad(&state[1], 0.0),
            acceleration: pad(&state[2], 0.0),
        },
    ))
}

/// The online trajectory generator of a control loop: one call per cycle with the newest
/// goal; it recalculates from the state it commanded last only when the goal changed, and
/// otherwise steps along the trajectory (rl-core's `Otg`, as `rl run --follow` uses it).
///
/// Args:
///     cycle: the control period, s.
///     position, velocity, acceleration: the state it starts from (axes,), 1 to 16 axes;
///         velocity and acceleration default to 0.
#[pyclass(name = "Otg", module = "rlrs")]
pub struct OtgPy {
    inner: Box<dyn Gen>,
    axes: usize,
}

impl OtgPy {
    fn out<'py>(
        &self,
        py: Python<'py>,
        s: &SampleRow,
        finished: bool,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let a = self.axes;
        PyTuple::new(
            py,
            [
                crate::array::vector(py, &s[0][..a]),
                crate::array::vector(py, &s[1][..a]),
                crate::array::vector(py, &s[2][..a]),
                finished.into_pyobject(py)?.to_owned().into_any(),
            ],
        )
    }
}

#[pymethods]
impl OtgPy {
    #[new]
    #[pyo3(signature = (cycle, position, velocity=None, acceleration=None))]
    fn new(
        cycle: f64,
        position: &Bound<'_, PyAny>,
        velocity: Option<&Bound<'_, PyAny>>,
        acceleration: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        if !(cycle > 0.0 && cycle.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "cycle {cycle}: a control period in seconds, finite and positive"
            )));
        }
        let axes = axes_of(position, "position")?;
        let cap = capacity(axes)?;
        let zeros = || vec![0.0; axes];
        let state = [
            per_axis(position, "position", axes)?,
            optional(velocity, "velocity", axes)?.unwrap_or_else(zeros),
            optional(acceleration, "acceleration", axes)?.unwrap_or_else(zeros),
        ];
        if state.iter().flatten().any(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(
                "position, velocity, acceleration: not finite",
            ));
        }
        let period = Duration::from_secs_f64(cycle);
        let inner = match cap {
            8 => generator::<8>(period, &state),
            _ => generator::<16>(period, &state),
        };
        Ok(Self { inner, axes })
    }

    /// One cycle toward the goal (the keywords of `rlrs.otg`, without the current state: the
    /// generator goes on from the state it commanded last): `(position, velocity,
    /// acceleration, finished)` to command now. On a goal that cannot be reached it raises
    /// TrajectoryError and the motion under way goes on unchanged (call `step`, or `brake`).
    #[pyo3(signature = (target_position, max_velocity, max_acceleration, max_jerk, *, target_velocity=None, target_acceleration=None, min_velocity=None, min_acceleration=None, min_position=None, max_position=None, interface="position", synchronization="time", minimum_duration=None, waypoints=None))]
    #[allow(clippy::too_many_arguments)]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        target_position: &Bound<'py, PyAny>,
        max_velocity: &Bound<'py, PyAny>,
        max_acceleration: &Bound<'py, PyAny>,
        max_jerk: &Bound<'py, PyAny>,
        target_velocity: Option<&Bound<'py, PyAny>>,
        target_acceleration: Option<&Bound<'py, PyAny>>,
        min_velocity: Option<&Bound<'py, PyAny>>,
        min_acceleration: Option<&Bound<'py, PyAny>>,
        min_position: Option<&Bound<'py, PyAny>>,
        max_position: Option<&Bound<'py, PyAny>>,
        interface: &str,
        synchronization: &str,
        minimum_duration: Option<f64>,
        waypoints: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let request = Goal {
            target_position,
            max_velocity,
            max_acceleration,
            max_jerk,
            target_velocity,
            target_acceleration,
            min_velocity,
            min_acceleration,
            min_position,
            max_position,
            interface,
            synchronization,
            minimum_duration,
            waypoints,
        }
        .request(self.inner.state(), self.axes)?;
        let (s, finished, _) = self
            .inner
            .update(&request)
            .map_err(error::TrajectoryError::new_err)?;
        self.out(py, &s, finished)
    }

    /// One cycle along the trajectory under way: `(position, velocity, acceleration,
    /// finished)`.
    fn step<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let (s, finished) = self.inner.step();
        self.out(py, &s, finished)
    }

    /// Replaces the goal by the time-optimal stop from the state commanded last (velocity and
    /// acceleration to zero within the limits); the following `step`s follow it.
    #[pyo3(signature = (max_velocity, max_acceleration, max_jerk, *, min_velocity=None, min_acceleration=None, synchronization="phase"))]
    fn brake(
        &mut self,
        max_velocity: &Bound<'_, PyAny>,
        max_acceleration: &Bound<'_, PyAny>,
        max_jerk: &Bound<'_, PyAny>,
        min_velocity: Option<&Bound<'_, PyAny>>,
        min_acceleration: Option<&Bound<'_, PyAny>>,
        synchronization: &str,
    ) -> PyResult<()> {
        let axes = self.axes;
        let state = self.inner.state();
        let request = Request {
            target: state.clone(),
            current: state,
            max_velocity: per_axis(max_velocity, "max_velocity", axes)?,
            min_velocity: optional(min_velocity, "min_velocity", axes)?,
            max_acceleration: per_axis(max_acceleration, "max_acceleration", axes)?,
            min_acceleration: optional(min_acceleration, "min_acceleration", axes)?,
            max_jerk: per_axis(max_jerk, "max_jerk", axes)?,
            min_position: None,
            max_position: None,
            interface: Interface::Velocity,
            synchronization: self::synchronization(synchronization)?,
            minimum_duration: None,
            waypoints: Vec::new(),
        };
        self.inner
            .brake(&request)
            .map_err(error::TrajectoryError::new_err)
    }

    /// The state commanded last: `(position, velocity, acceleration)`.
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let s = self.inner.state();
        let a = self.axes;
        PyTuple::new(
            py,
            [
                crate::array::vector(py, &s[0][..a]),
                crate::array::vector(py, &s[1][..a]),
                crate::array::vector(py, &s[2][..a]),
            ],
        )
    }

    /// Time along the trajectory under way, s.
    #[getter]
    fn time(&self) -> f64 {
        self.inner.time()
    }

    /// The duration of the trajectory under way, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration()
    }

    /// Number of axes.
    #[getter]
    fn axes(&self) -> usize {
        self.axes
    }

    fn __repr__(&self) -> String {
        format!(
            "<rlrs.Otg {} axes, {:.6} of {:.6} s>",
            self.axes,
            self.inner.time(),
            self.inner.duration()
        )
    }
}
