//! `rlrs.JerkLimited`: rl-core's time-optimal jerk-limited rest-to-rest profile (7 segments,
//! Biagiotti & Melchiorri 2008, §3.4; the same durations as Ruckig's), evaluated on arrays of
//! times in one call.
//!
//! rl-core's `JerkLimited<D>` fixes the number of axes at compile time; the module is built for
//! [`AXES`] and pads the axes it is not given with axes that do not move (zero distance, unit
//! limits), which changes neither the duration nor the other axes (an axis at rest needs no
//! time and is not stretched).
//!
//! Extension point: rl-core's online trajectory generator and streamed targets (being built
//! now) get their class here, next to this one.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rl_core::traj::{JerkLimited as Profile, Limits, Trajectory, TrajectoryError};

use crate::array::{Input, Output, scalar, shape_text};
use crate::error;

/// Position, velocity, acceleration and jerk arrays.
pub(crate) type Samples<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
);

/// Capacities (most axes) the profile is built for.
pub const AXES: &[usize] = &[8, 16, 64];

/// A profile of some capacity.
trait Jerk: Send + Sync {
    fn duration(&self) -> f64;
    /// Samples `times` into `out` = [position, velocity, acceleration, jerk], each
    /// `times.len() × axes`.
    fn sample(&self, times: &[f64], axes: usize, out: [&mut [f64]; 4]);
    fn axis_durations(&self, axes: usize) -> Vec<f64>;
    fn phase_ends(&self, axis: usize) -> Option<[f64; 7]>;
}

struct Padded<const D: usize> {
    profile: Profile<D>,
    start: [f64; D],
    goal: [f64; D],
    limits: Limits<D>,
}

impl<const D: usize> Jerk for Padded<D> {
    fn duration(&self) -> f64 {
        self.profile.duration()
    }

    fn sample(&self, times: &[f64], axes: usize, out: [&mut [f64]; 4]) {
        sample_rows(|t| self.profile.sample(t), times, axes, out);
    }

    fn axis_durations(&self, axes: usize) -> Vec<f64> {
        Profile::axis_durations(self.start, self.goal, &self.limits)[..axes].to_vec()
    }

    fn phase_ends(&self, axis: usize) -> Option<[f64; 7]> {
        self.profile.phase_ends(axis)
    }
}

/// `at` at each of `times` into `out` = [position, velocity, acceleration, jerk], each
/// `times.len() × axes`, row after row.
pub(crate) fn sample_rows<const N: usize>(
    at: impl Fn(f64) -> rl_core::traj::Sample<N>,
    times: &[f64],
    axes: usize,
    out: [&mut [f64]; 4],
) {
    let [p, v, a, j] = out;
    for (k, &t) in times.iter().enumerate() {
        let s = at(t);
        let row = k * axes..(k + 1) * axes;
        p[row.clone()].copy_from_slice(&s.position[..axes]);
        v[row.clone()].copy_from_slice(&s.velocity[..axes]);
        a[row.clone()].copy_from_slice(&s.acceleration[..axes]);
        j[row].copy_from_slice(&s.jerk[..axes]);
    }
}

/// Samples `t` (a time, or an (n,) array read in place) of a trajectory of `axes` axes with
/// `sample` (the GIL released): four (axes,) or (n, axes) arrays.
pub(crate) fn sample_times<'py>(
    py: Python<'py>,
    t: &Bound<'py, PyAny>,
    axes: usize,
    sample: impl FnOnce(&[f64], [&mut [f64]; 4]) + Send,
) -> PyResult<Samples<'py>> {
    let one;
    let times = match scalar(t) {
        Some(x) => {
            one = crate::array::vector(py, &[x]);
            Input::new(&one, "t")?
        }
        None => Input::new(t, "t")?,
    };
    let shape: Vec<usize> = match times.shape() {
        _ if scalar(t).is_some() => vec![axes],
        [n] => vec![*n, axes],
        s => {
            return Err(PyValueError::new_err(format!(
                "t: shape {}, expected a time or (n,) times",
                shape_text(s)
            )));
        }
    };
    let mut out: [Output<'py, f64>; 4] = std::array::from_fn(|_| Output::zeros(py, &shape));
    let [p, v, a, j] = &mut out;
    let slices = [
        p.as_mut_slice(),
        v.as_mut_slice(),
        a.as_mut_slice(),
        j.as_mut_slice(),
    ];
    let ts = times.shared()?;
    let ts_slice = crate::array::shared_slice(&ts);
    py.detach(|| sample(ts_slice, slices));
    let [p, v, a, j] = out;
    Ok((p.into_any(), v.into_any(), a.into_any(), j.into_any()))
}

/// Builds the profile in capacity `D` from per-axis values (padded).
fn build<const D: usize>(
    start: &[f64],
    goal: &[f64],
    limits: [&[f64]; 3],
) -> Result<Box<dyn Jerk>, TrajectoryError> {
    let pad = |x: &[f64], fill: f64| {
        let mut a = [fill; D];
        a[..x.len()].copy_from_slice(x);
        a
    };
    let (start, goal) = (pad(start, 0.0), pad(goal, 0.0));
    let limits = Limits {
        velocity: pad(limits[0], 1.0),
        acceleration: pad(limits[1], 1.0),
        jerk: pad(limits[2], 1.0),
    };
    let profile = Profile::new(start, goal, &limits)?;
    Ok(Box::new(Padded {
        profile,
        start,
        goal,
        limits,
    }))
}

/// Time-optimal jerk-limited motion from rest at `start` to rest at `goal`, all axes
/// synchronised to the slowest (rl-core's `JerkLimited`).
///
/// Args:
///     start, goal: positions per axis (n,).
///     max_velocity, max_acceleration, max_jerk: finite positive limits, one per axis or one
///         for all.
///
/// Raises TrajectoryError for limits that are not finite and positive or points that are not
/// finite, ValueError for more than 64 axes.
#[pyclass(frozen, module = "rlrs")]
pub struct JerkLimited {
    inner: Box<dyn Jerk>,
    axes: usize,
}

/// `x` as `axes` values: itself, or one value repeated.
fn per_axis(x: &Bound<'_, PyAny>, name: &str, axes: usize) -> PyResult<Vec<f64>> {
    if let Some(v) = scalar(x) {
        return Ok(vec![v; axes]);
    }
    let input = Input::new(x, name)?;
    match input.shape() {
        [n] if *n == axes => Ok(input.slice().to_vec()),
        s => Err(PyValueError::new_err(format!(
            "{name}: shape {}, expected one value or ({axes},)",
            shape_text(s)
        ))),
    }
}

#[pymethods]
impl JerkLimited {
    #[new]
    fn new(
        start: &Bound<'_, PyAny>,
        goal: &Bound<'_, PyAny>,
        max_velocity: &Bound<'_, PyAny>,
        max_acceleration: &Bound<'_, PyAny>,
        max_jerk: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let start = Input::new(start, "start")?;
        let axes = match start.shape() {
            [n] => *n,
            s => {
                return Err(PyValueError::new_err(format!(
                    "start: shape {}, expected (axes,)",
                    shape_text(s)
                )));
            }
        };
        let goal = per_axis(goal, "goal", axes)?;
        let limits = [
            per_axis(max_velocity, "max_velocity", axes)?,
            per_axis(max_acceleration, "max_acceleration", axes)?,
            per_axis(max_jerk, "max_jerk", axes)?,
        ];
        let l = [&limits[0][..], &limits[1][..], &limits[2][..]];
        let s = start.slice();
        let built = match AXES.iter().find(|&&c| c >= axes) {
            Some(8) => build::<8>(s, &goal, l),
            Some(16) => build::<16>(s, &goal, l),
            Some(_) => build::<64>(s, &goal, l),
            None => {
                return Err(PyValueError::new_err(format!(
                    "{axes} axes: rlrs builds jerk-limited profiles for up to {} axes \
                     (rl-py/src/traj.rs, AXES)",
                    AXES[AXES.len() - 1]
                )));
            }
        };
        let inner = built.map_err(|e| error::TrajectoryError::new_err(e.to_string()))?;
        Ok(Self { inner, axes })
    }

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

    /// The time-optimal duration of each axis alone, s (the profile takes the largest).
    #[getter]
    fn axis_durations<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        crate::array::vector(py, &self.inner.axis_durations(self.axes))
    }

    /// End times of the seven phases of `axis` (jerk +J, 0, -J, 0, -J, 0, +J), s.
    fn phase_ends<'py>(&self, py: Python<'py>, axis: usize) -> PyResult<Bound<'py, PyAny>> {
        if axis >= self.axes {
            return Err(PyValueError::new_err(format!(
                "axis {axis}: the profile has {} axes",
                self.axes
            )));
        }
        let ends = self.inner.phase_ends(axis).unwrap_or([f64::NAN; 7]);
        Ok(crate::array::vector(py, &ends))
    }

    /// Position, velocity, acceleration and jerk at `t` (times outside [0, duration] are
    /// clamped to it): a tuple of four (axes,) arrays for one time, of (len(t), axes) arrays
    /// for an array of times.
    fn sample<'py>(&self, py: Python<'py>, t: &Bound<'py, PyAny>) -> PyResult<Samples<'py>> {
        let (inner, axes) = (&*self.inner, self.axes);
        sample_times(py, t, axes, |times, out| inner.sample(times, axes, out))
    }

    /// Position at `t`: (axes,) for one time, (len(t), axes) for an array of times.
    fn __call__<'py>(&self, py: Python<'py>, t: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        Ok(self.sample(py, t)?.0)
    }

    fn __repr__(&self) -> String {
        format!(
            "<rlrs.JerkLimited {} axes, {:.6} s>",
            self.axes,
            self.inner.duration()
        )
    }
}
