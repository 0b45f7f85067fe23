//! One axis between its start and target: braking, its extremal profiles, the durations in
//! which it cannot reach its target (the blocked intervals), and its profile for any other
//! duration.
//!
//! The durations in which one axis can reach its target are `[t_min, ∞)` minus at most a few
//! open intervals (Berscheid & Kröger 2021, §III-D): for a given duration `T` the profiles that
//! reach the target velocity and acceleration form a convex set (the constraints are linear in
//! the jerk function, the limits are boxes), so the reachable displacements are an interval
//! `[P_min(T), P_max(T)]`, and the target is reachable exactly when `pd` lies in it. Where
//! `P_max(T) = pd` or `P_min(T) = pd` the axis has an extremal profile; between two consecutive
//! extremal durations reachability does not change, so one test at the midpoint tells a
//! blocked interval from a free one (instead of Ruckig's count of profiles by parity).
//!
//! For a duration `T` that is not blocked, the axis plays the convex combination
//! `λ·P_max-profile + (1 − λ)·P_min-profile` with `λ` chosen for the target displacement: it has
//! exactly the duration `T`, ends in the target state (every derivative is the same combination
//! of two motions that both end there, and the displacement is linear in `λ`), and keeps every
//! limit because both motions keep them and the limits are convex. No root finding is needed in
//! this step, only the closed forms of [`super::third_order::max_displacement`].

use super::brake::{self, Brake};
use super::error::OtgError;
use super::frame::{Bounds, Direction, Ends, P_PRECISION, UDDU, V_PRECISION, holds};
use super::lower_order;
use super::profile::{Order, Shape};
use super::third_order::{self, Extremal, Extremals, MAX_EXTREMALS};
use super::velocity;

/// Which solver an axis uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// Position target, finite jerk.
    PositionJerk,
    /// Position target, infinite jerk, finite acceleration.
    PositionAcceleration,
    /// Position target, infinite acceleration.
    PositionVelocity,
    /// Position target with a zero jerk or acceleration limit: constant acceleration.
    PositionConstant,
    /// Velocity target, finite jerk.
    VelocityJerk,
    /// Velocity target, infinite jerk.
    VelocityAcceleration,
    /// Velocity target with a zero jerk limit: constant acceleration.
    VelocityConstant,
}

impl Kind {
    /// Whether the target is a velocity (position free).
    pub fn is_velocity(self) -> bool {
        matches!(
            self,
            Self::VelocityJerk | Self::VelocityAcceleration | Self::VelocityConstant
        )
    }
}

/// Room for blocked intervals per axis (at most two occur).
pub(crate) const MAX_BLOCKED: usize = 4;

/// How one axis plays a given duration (on the stack only; both variants are the same few
/// hundred bytes in the real-time path, boxing is not an option without an allocator).
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub(crate) enum Plan {
    /// One shape.
    One(Shape),
    /// `weight · first + (1 − weight) · second`.
    Blend(Shape, Shape, f64),
}

/// One axis after step 1.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Axis {
    pub kind: Kind,
    pub brake: Brake,
    /// Boundary conditions after braking, in the axis' frame.
    pub ends: Ends,
    pub bounds: Bounds,
    /// Extremal profiles sorted by duration (main part, without braking).
    pub extremals: Extremals,
    /// Shortest total duration (with braking).
    pub t_min: f64,
    /// Blocked open intervals of total duration.
    pub blocked: [(f64, f64); MAX_BLOCKED],
    pub n_blocked: usize,
}

/// Phase values of an extremal found in the frame of `x.dir`.
fn shape_of(kind: Kind, x: &Extremal, b: &Bounds, e: &Ends) -> Shape {
    let s = x.dir.sign();
    let f = b.toward(x.dir);
    let mut value = [0.0; 7];
    let mut hold = [f64::NAN; 7];
    let mut cruise = f64::NAN;
    let order = match kind {
        Kind::PositionJerk | Kind::VelocityJerk => {
            let h = holds(&f);
            for i in 0..7 {
                value[i] = s * UDDU[i] * b.j;
                hold[i] = s * h[i];
            }
            if kind == Kind::PositionJerk {
                cruise = s * f.v_max;
            }
            Order::Jerk
        }
        Kind::PositionConstant | Kind::VelocityConstant => Order::Jerk,
        Kind::PositionAcceleration => {
            let acc = lower_order::second_order_accelerations(&f);
            for i in 0..7 {
                value[i] = s * acc[i];
            }
            Order::Acceleration
        }
        Kind::VelocityAcceleration => {
            value[1] = s * f.a_max;
            Order::Acceleration
        }
        Kind::PositionVelocity => {
            value[3] = s * f.v_max;
            Order::Velocity
        }
    };
    Shape {
        t: x.t,
        value,
        order,
        hold,
        cruise,
        end_v: e.vf,
        end_a: e.af,
    }
}

impl Axis {
    /// A placeholder (all bits zero, so an array of them is a memset).
    pub const IDLE: Self = Self {
        kind: Kind::PositionJerk,
        brake: Brake {
            t: [0.0; 2],
            j: [0.0; 2],
            a: 0.0,
            second_order: false,
        },
        ends: Ends {
            pd: 0.0,
            v0: 0.0,
            a0: 0.0,
            vf: 0.0,
            af: 0.0,
        },
        bounds: Bounds {
            v_max: 0.0,
            v_min: 0.0,
            a_max: 0.0,
            a_min: 0.0,
            j: 0.0,
        },
        extremals: Extremals::new(),
        t_min: 0.0,
        blocked: [(0.0, 0.0); MAX_BLOCKED],
        n_blocked: 0,
    };

    /// Braking, then the extremal profiles and blocked intervals of one axis (in place: the
    /// state is large and the real-time path copies nothing it need not).
    ///
    /// `p`, `v`, `a`: start; `pf`, `vf`, `af`: target (`pf` unused for a velocity target);
    /// `b`: limits in the axis' frame.
    #[allow(clippy::too_many_arguments)]
    pub fn init(
        &mut self,
        axis: usize,
        velocity_target: bool,
        [p, v, a]: [f64; 3],
        [pf, vf, af]: [f64; 3],
        b: Bounds,
    ) -> Result<(), OtgError> {
        let jerk_free = b.j.is_infinite();
        let acc_free = b.a_max.is_infinite() || b.a_min.is_infinite();
        let kind = if velocity_target {
            if jerk_free {
                Kind::VelocityAcceleration
            } else if b.j == 0.0 {
                Kind::VelocityConstant
            } else {
                Kind::VelocityJerk
            }
        } else if !jerk_free {
            if b.j == 0.0 || b.a_max == 0.0 || b.a_min == 0.0 {
                Kind::PositionConstant
            } else {
                Kind::PositionJerk
            }
        } else if !acc_free {
            if (b.v_max == 0.0 && b.v_min == 0.0) || b.a_max == 0.0 || b.a_min == 0.0 {
                Kind::PositionConstant
            } else {
                Kind::PositionAcceleration
            }
        } else {
            Kind::PositionVelocity
        };
        let brake = match kind {
            Kind::PositionJerk => brake::position_third(v, a, &b),
            Kind::PositionAcceleration => {
                brake::position_second(v, b.v_max, b.v_min, b.a_max, b.a_min)
            }
            Kind::VelocityJerk => brake::velocity_third(a, b.a_max, b.a_min, b.j),
            _ => Brake::default(),
        };
        let start = brake.apply(p, v, a);
        let ends = Ends {
            pd: if velocity_target { 0.0 } else { pf - start[0] },
            v0: start[1],
            a0: if matches!(kind, Kind::PositionAcceleration | Kind::PositionVelocity) {
                0.0
            } else {
                start[2]
            },
            vf,
            af,
        };
        self.kind = kind;
        self.brake = brake;
        self.ends = ends;
        self.bounds = b;
        self.extremals.len = 0;
        self.t_min = 0.0;
        self.n_blocked = 0;
        self.step1(axis)
    }

    fn step1(&mut self, axis: usize) -> Result<(), OtgError> {
        let (e, b) = (&self.ends, &self.bounds);
        let found = &mut self.extremals;
        let mut moving_single_step = false;
        match self.kind {
            Kind::PositionJerk => third_order::extremals(e, b, found),
            Kind::PositionAcceleration => lower_order::second_order_extremals(e, b, found),
            Kind::PositionVelocity => lower_order::first_order_extremal(e, b, found),
            Kind::VelocityJerk => velocity::extremals(e, b, found),
            Kind::VelocityAcceleration => lower_order::velocity_second_extremal(e, b, found),
            Kind::PositionConstant | Kind::VelocityConstant => {
                let t = if self.kind == Kind::PositionConstant {
                    lower_order::constant_acceleration(e, b)
                } else {
                    lower_order::constant_acceleration_velocity(e)
                };
                let Some(t) = t else {
                    return Err(OtgError::ZeroLimits { axis });
                };
                let mut times = [0.0; 7];
                times[3] = t;
                found.push(Extremal {
                    t: times,
                    dir: Direction::Up,
                    duration: t,
                });
                moving_single_step = e.v0.abs() > f64::EPSILON || e.a0.abs() > f64::EPSILON;
            }
        }
        if found.len == 0 {
            return Err(OtgError::NoProfile { axis });
        }
        // Sort by duration (insertion sort of at most eight) and drop repeats.
        let items = &mut found.items[..found.len];
        for i in 1..items.len() {
            let mut k = i;
            while k > 0 && items[k].duration < items[k - 1].duration {
                items.swap(k, k - 1);
                k -= 1;
            }
        }
        let mut n = 1;
        for i in 1..found.len {
            let prev = found.items[n - 1].duration;
            if found.items[i].duration - prev > 8.0 * f64::EPSILON * (1.0 + prev) {
                found.items[n] = found.items[i];
                n += 1;
            }
        }
        found.len = n;
        let brake_time = self.brake.duration();
        self.t_min = brake_time + found.items[0].duration;
        if moving_single_step {
            self.blocked[0] = (self.t_min, f64::INFINITY);
            self.n_blocked = 1;
            return Ok(());
        }
        let durations: [f64; MAX_EXTREMALS] = core::array::from_fn(|i| found.items[i].duration);
        for i in 1..n {
            let (lo, hi) = (durations[i - 1], durations[i]);
            if !self.reachable(0.5 * (lo + hi)) && self.n_blocked < MAX_BLOCKED {
                self.blocked[self.n_blocked] = (brake_time + lo, brake_time + hi);
                self.n_blocked += 1;
            }
        }
        Ok(())
    }

    /// Whether a total duration `t` is blocked. Within a few units in the last place of an
    /// interval's ends `t` is that end's extremal profile (which [`Self::plan`] plays): two axes
    /// whose durations agree in exact arithmetic (2 s and 1.9999999999999996 s, the start of a
    /// blocked interval) must not push the common duration past the interval.
    #[inline]
    pub fn is_blocked(&self, t: f64) -> bool {
        let tol = 2.0 * f64::EPSILON * (1.0 + t);
        t < self.t_min
            || self.blocked[..self.n_blocked]
                .iter()
                .any(|&(lo, hi)| lo + tol < t && t < hi - tol)
    }

    /// The measure the target fixes: displacement, or final velocity for a velocity target.
    #[inline]
    fn target_measure(&self) -> f64 {
        if self.kind.is_velocity() {
            self.ends.vf
        } else {
            self.ends.pd
        }
    }

    /// The largest measure reachable in `duration` (main part) with the profile that reaches
    /// it, in the frame of `dir` (negate for the smallest).
    fn extreme(&self, dir: Direction, duration: f64) -> Option<([f64; 7], f64)> {
        let e = self.ends.toward(dir);
        let b = self.bounds.toward(dir);
        match self.kind {
            Kind::PositionJerk => third_order::max_displacement(&e, &b, duration),
            Kind::PositionAcceleration => {
                lower_order::second_order_max_displacement(&e, &b, duration)
            }
            Kind::PositionVelocity => lower_order::first_order_max_displacement(&b, duration),
            Kind::VelocityJerk => velocity::max_velocity(&e, &b, duration),
            Kind::VelocityAcceleration => lower_order::velocity_second_max(&e, &b, duration),
            Kind::PositionConstant | Kind::VelocityConstant => None,
        }
    }

    /// Tolerance on the target measure.
    #[inline]
    fn precision(&self) -> f64 {
        if self.kind.is_velocity() {
            V_PRECISION
        } else {
            P_PRECISION
        }
    }

    /// Whether the target is reachable in main duration `duration`.
    fn reachable(&self, duration: f64) -> bool {
        let target = self.target_measure();
        let tol = self.precision();
        let up = self.extreme(Direction::Up, duration);
        let down = self.extreme(Direction::Down, duration);
        matches!((up, down), (Some((_, hi)), Some((_, lo))) if -lo <= target + tol && target <= hi + tol)
    }

    /// How this axis plays total duration `t` (not blocked).
    pub fn plan(&self, axis: usize, t: f64) -> Result<Plan, OtgError> {
        if matches!(self.kind, Kind::PositionConstant | Kind::VelocityConstant) {
            // Not blocked: either the single phase itself, or at rest (then it holds).
            return Ok(Plan::One(self.fastest()));
        }
        let brake_time = self.brake.duration();
        let duration = t - brake_time;
        let tol = 4.0 * f64::EPSILON * (1.0 + t);
        for x in self.extremals.as_slice() {
            if (x.duration - duration).abs() <= tol {
                return Ok(Plan::One(shape_of(self.kind, x, &self.bounds, &self.ends)));
            }
        }
        let fail = OtgError::NoSynchronization { axis, duration: t };
        let up = self.extreme(Direction::Up, duration);
        let down = self.extreme(Direction::Down, duration);
        let target = self.target_measure();
        let tol = self.precision();
        let up_x = up.map(|(t, m)| {
            (
                Extremal {
                    t,
                    dir: Direction::Up,
                    duration,
                },
                m,
            )
        });
        let down_x = down.map(|(t, m)| {
            (
                Extremal {
                    t,
                    dir: Direction::Down,
                    duration,
                },
                -m,
            )
        });
        let shape = |x: &Extremal| shape_of(self.kind, x, &self.bounds, &self.ends);
        match (up_x, down_x) {
            (Some((xu, hi)), Some((xd, lo))) => {
                if !(lo <= target + tol && target <= hi + tol) {
                    return Err(fail);
                }
                let span = hi - lo;
                if span <= 0.0 {
                    return Ok(Plan::One(shape(&xu)));
                }
                let weight = ((target - lo) / span).clamp(0.0, 1.0);
                Ok(Plan::Blend(shape(&xu), shape(&xd), weight))
            }
            (Some((x, m)), None) | (None, Some((x, m))) if (m - target).abs() <= tol => {
                Ok(Plan::One(shape(&x)))
            }
            _ => Err(fail),
        }
    }

    /// The shape of the shortest profile (main part).
    pub fn fastest(&self) -> Shape {
        shape_of(
            self.kind,
            &self.extremals.items[0],
            &self.bounds,
            &self.ends,
        )
    }
}
