//! Algebraic trajectory functions of time with exact derivatives (RL's central idea for motion):
//! position, velocity, acceleration and jerk come from closed forms, never from sampling, so
//! limits and continuity are checked exactly.
//!
//! - [`Trajectory`]: a vector-valued function on `[0, duration]` with `D` axes fixed at compile
//!   time, evaluating any derivative order; [`Piecewise`] composes any of them in time (a spline
//!   of polynomials, a spline of jerk-limited moves) and checks continuity at every boundary.
//! - [`Polynomial`]: any degree, boundary-condition constructors from linear to septic, at-rest
//!   time-optimal constructors synchronised over axes, derivative, integral and extrema.
//! - Splines through waypoints ([`spline`]): natural and clamped cubic, linear segments with
//!   parabolic, quartic or sextic blends, 4-1-4 and 6-1-6 at rest, and the 7-segment
//!   jerk-limited profile ([`JerkLimited`], Biagiotti & Melchiorri 2008, §3.4).
//! - Rotations ([`RotationTrajectory`]): slerp, a jerk-limited rotation at rest and a cubic
//!   quaternion spline, with world-frame angular velocity and acceleration.
//! - [`Segment`]: a jerk-limited move or a polynomial, so one [`Piecewise`] can mix both
//!   (stop at some waypoints, blend through others).
//! - [`Circular`] arcs in 2-D and 3-D with derivatives of every order, and Cartesian
//!   [`PoseTrajectory`] = position + rotation.
//!
//! Capacity is a const generic everywhere; construction and evaluation allocate nothing and
//! never panic: bad input is a [`TrajectoryError`]. Times outside `[0, duration]` are clamped
//! to the interval, so a finished trajectory holds its end state.
//!
//! ```
//! use rl_core::traj::{JerkLimited, Limits, Piecewise, Polynomial, Trajectory, spline};
//!
//! // Time-optimal jerk-limited move of two axes from rest to rest, synchronised.
//! let limits = Limits::uniform(1.0, 2.0, 10.0); // rad/s, rad/s², rad/s³
//! let jerk = JerkLimited::new([0.0, 0.5], [1.0, -0.5], &limits)?;
//! let s = jerk.sample(0.5 * jerk.duration());
//! assert!(s.velocity[0] <= 1.0 && s.acceleration[1].abs() <= 2.0);
//!
//! // Natural cubic spline through timed waypoints (capacity: 8 segments), C² everywhere.
//! let times = [0.0, 1.0, 2.5, 3.0];
//! let points = [[0.0, 0.0], [1.0, 0.5], [0.5, 1.0], [0.0, 0.0]];
//! let cubic: Piecewise<Polynomial<2, 4>, 8> = spline::natural_cubic(&times, &points)?;
//! cubic.check_continuity(2, 1e-12).expect("C² at every waypoint");
//! assert!((cubic.position(2.5)[1] - 1.0).abs() < 1e-12);
//! # Ok::<(), rl_core::traj::TrajectoryError>(())
//! ```

// Index loops over axes read as the math does; `!(x > 0.0)` is how NaN is rejected.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

mod blend;
mod cartesian;
mod circular;
mod error;
mod jerk_limited;
pub mod otg;
mod piecewise;
mod polynomial;
mod quaternion_spline;
mod roots;
mod segment;
pub mod spline;

pub use blend::{BlendShape, BlendTime};
pub use cartesian::{PoseSample, PoseTrajectory};
pub use circular::Circular;
pub use error::{Discontinuity, LimitKind, TrajectoryError};
pub use jerk_limited::{JerkLimited, JerkLimitedRotation};
pub use piecewise::Piecewise;
pub use polynomial::{Extrema, Limits, Polynomial};
pub use quaternion_spline::{
    CubicQuaternionSpline, RotationSample, RotationTrajectory, SlerpTrajectory,
};
pub use segment::Segment;

/// Position, velocity, acceleration and jerk of every axis at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<const D: usize> {
    /// Value of each axis.
    pub position: [f64; D],
    /// First time derivative.
    pub velocity: [f64; D],
    /// Second time derivative.
    pub acceleration: [f64; D],
    /// Third time derivative.
    pub jerk: [f64; D],
}

impl<const D: usize> Sample<D> {
    /// The `order`-th derivative (0 = position, up to 3 = jerk; zero above).
    pub fn derivative(&self, order: usize) -> [f64; D] {
        match order {
            0 => self.position,
            1 => self.velocity,
            2 => self.acceleration,
            3 => self.jerk,
            _ => [0.0; D],
        }
    }
}

/// A vector-valued function of time on `[0, duration]` with `D` axes and exact derivatives.
pub trait Trajectory<const D: usize> {
    /// Length of the time interval in seconds.
    fn duration(&self) -> f64;

    /// The `order`-th time derivative at `t` (0 = value), `t` clamped to `[0, duration]`.
    fn derivative(&self, t: f64, order: usize) -> [f64; D];

    /// Value at `t`.
    fn position(&self, t: f64) -> [f64; D] {
        self.derivative(t, 0)
    }

    /// Position, velocity, acceleration and jerk at `t` in one call (implementations fuse the
    /// four evaluations).
    fn sample(&self, t: f64) -> Sample<D> {
        Sample {
            position: self.derivative(t, 0),
            velocity: self.derivative(t, 1),
            acceleration: self.derivative(t, 2),
            jerk: self.derivative(t, 3),
        }
    }
}

/// A pointer to a trajectory is one, forwarding every method: code generic over an owned
/// trajectory (a retiming that keeps its path) takes a reference, or a box that keeps a large
/// piecewise trajectory off the stack.
macro_rules! trajectory_through_pointer {
    ($(#[$attr:meta])* $pointer:ty) => {
        $(#[$attr])*
        impl<const D: usize, T: Trajectory<D> + ?Sized> Trajectory<D> for $pointer {
            fn duration(&self) -> f64 {
                (**self).duration()
            }

            fn derivative(&self, t: f64, order: usize) -> [f64; D] {
                (**self).derivative(t, order)
            }

            fn sample(&self, t: f64) -> Sample<D> {
                (**self).sample(t)
            }
        }
    };
}

trajectory_through_pointer!(&T);
trajectory_through_pointer!(#[cfg(feature = "std")] std::boxed::Box<T>);

/// `t` clamped to `[0, duration]`; NaN stays NaN (and evaluates to NaN, never panics). Written
/// so that it compiles to one `maxsd` and one `minsd` (no branches).
#[inline]
pub(crate) fn clamp_time(t: f64, duration: f64) -> f64 {
    let t = if t < 0.0 { 0.0 } else { t };
    if duration < t { duration } else { t }
}

/// Finite check for a waypoint list, naming the first bad waypoint.
pub(crate) fn check_finite_points<const D: usize>(
    points: &[[f64; D]],
) -> Result<(), TrajectoryError> {
    if polynomial::all_finite(points.as_flattened()) {
        return Ok(());
    }
    match points.iter().position(|p| !polynomial::all_finite(p)) {
        Some(index) => Err(TrajectoryError::NotFinite {
            what: "waypoint",
            index,
        }),
        None => Ok(()),
    }
}

/// Times must be finite and strictly increasing.
pub(crate) fn check_times(times: &[f64]) -> Result<(), TrajectoryError> {
    for (index, t) in times.iter().enumerate() {
        if !t.is_finite() {
            return Err(TrajectoryError::NotFinite {
                what: "time",
                index,
            });
        }
        if index > 0 && *t <= times[index - 1] {
            return Err(TrajectoryError::NonIncreasingTime { index });
        }
    }
    Ok(())
}
