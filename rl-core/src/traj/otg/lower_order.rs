//! Profiles of an axis without a jerk limit (infinite jerk: the acceleration jumps) or without an
//! acceleration limit (infinite acceleration: the velocity jumps).
//!
//! Position with infinite jerk: accelerate at `a_max`, cruise at `v_max` if reached, decelerate
//! at `a_min` (up frame). Without cruise the peak velocity `h` satisfies
//! `(h² − v0²)/(2 a_max) + (vf² − h²)/(2 a_min) = pd`, so
//! `h² = (a_max vf² − a_min v0² − 2 a_max a_min pd)/(a_max − a_min)`; for a given duration the
//! peak is linear in it. Position with infinite acceleration: the velocity limit all the way.
//! Velocity with infinite jerk: the acceleration limit all the way. The target acceleration
//! (and with infinite acceleration the target velocity) is taken at the end by a jump.

use super::frame::{Bounds, Direction, End, Ends, P_PRECISION, T_EPS, V_EPS, V_PRECISION};
use super::third_order::{Extremal, Extremals};

/// Up-frame acceleration of each phase of a second-order profile.
#[inline]
pub(crate) fn second_order_accelerations(b: &Bounds) -> [f64; 7] {
    [b.a_max, 0.0, b.a_min, 0.0, 0.0, 0.0, 0.0]
}

/// End of the phases `t` with accelerations `a_max, 0, a_min` from `v0` (the acceleration
/// entry is that of the last phase), with the velocity within limits after the first phase.
fn integrate_second(t: &[f64; 7], v0: f64, b: &Bounds) -> Option<End> {
    let acc = second_order_accelerations(b);
    let [v_lo, v_hi, ..] = super::frame::slack(b);
    let (mut p, mut v) = (0.0, v0);
    let mut scale = [0.0, v0.abs(), 0.0];
    for i in 0..3 {
        let ti = t[i];
        if ti < 0.0 {
            return None;
        }
        p += ti * (v + 0.5 * ti * acc[i]);
        v += ti * acc[i];
        if v > v_hi || v < v_lo {
            return None;
        }
        scale[0] = f64::max(scale[0], p.abs());
        scale[1] = f64::max(scale[1], v.abs());
    }
    Some(End {
        p,
        v,
        a: 0.0,
        scale,
    })
}

#[inline]
fn clean(t: &mut [f64; 7]) -> bool {
    super::frame::clean_times(t)
}

fn accept_second(
    mut t: [f64; 7],
    e: &Ends,
    b: &Bounds,
    dir: Direction,
    found: &mut Extremals,
) -> bool {
    if !clean(&mut t) {
        return false;
    }
    let Some(end) = integrate_second(&t, e.v0, b) else {
        return false;
    };
    if end.reaches(e.pd, e.vf, 0.0) {
        found.push(Extremal {
            t,
            dir,
            duration: t[0] + t[1] + t[2],
        });
        true
    } else {
        false
    }
}

/// Accelerate to velocity `peak`, decelerate to the target (second order, no cruise).
#[inline]
fn through_peak(peak: f64, e: &Ends, b: &Bounds) -> [f64; 7] {
    let mut t = [0.0; 7];
    t[0] = (peak - e.v0) / b.a_max;
    t[2] = (e.vf - peak) / b.a_min;
    t
}

fn second_toward(e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals, first_only: bool) {
    let (e, b) = (e.toward(dir), b.toward(dir));
    let (am, an) = (b.a_max, b.a_min);
    let h2 = (am * e.vf * e.vf - an * e.v0 * e.v0 - 2.0 * am * an * e.pd) / (am - an);
    if h2 >= 0.0 {
        let h = libm::sqrt(h2);
        for peak in [-h, h] {
            if accept_second(through_peak(peak, &e, &b), &e, &b, dir, found) && first_only {
                return;
            }
        }
    }
    if b.v_max > 0.0 && b.v_max.is_finite() {
        let mut t = [
            (b.v_max - e.v0) / am,
            0.0,
            (e.vf - b.v_max) / an,
            0.0,
            0.0,
            0.0,
            0.0,
        ];
        let d = (b.v_max * b.v_max - e.v0 * e.v0) / (2.0 * am)
            + (e.vf * e.vf - b.v_max * b.v_max) / (2.0 * an);
        t[1] = (e.pd - d) / b.v_max;
        accept_second(t, &e, &b, dir, found);
    }
}

/// Extremal profiles with infinite jerk (finite, non-zero acceleration limits).
pub(crate) fn second_order_extremals(e: &Ends, b: &Bounds, found: &mut Extremals) {
    let there = accept_second([0.0; 7], e, b, Direction::Up, found);
    if e.vf == 0.0 {
        if there {
            return;
        }
        let (first, second) = if e.pd >= 0.0 {
            (Direction::Up, Direction::Down)
        } else {
            (Direction::Down, Direction::Up)
        };
        second_toward(e, b, first, found, true);
        if found.len == 0 {
            second_toward(e, b, second, found, true);
        }
    } else {
        second_toward(e, b, Direction::Up, found, false);
        second_toward(e, b, Direction::Down, found, false);
    }
}

/// The second-order profile of exactly `duration` reaching `vf` with the largest displacement
/// (up frame), and that displacement.
pub(crate) fn second_order_max_displacement(
    e: &Ends,
    b: &Bounds,
    duration: f64,
) -> Option<([f64; 7], f64)> {
    let (am, an) = (b.a_max, b.a_min);
    let peak = (duration + e.v0 / am - e.vf / an) / (1.0 / am - 1.0 / an);
    let mut t = if peak <= b.v_max {
        through_peak(peak, e, b)
    } else {
        let (t0, t2) = ((b.v_max - e.v0) / am, (e.vf - b.v_max) / an);
        [t0, duration - t0 - t2, t2, 0.0, 0.0, 0.0, 0.0]
    };
    if !clean(&mut t) {
        return None;
    }
    let end = integrate_second(&t, e.v0, b)?;
    end.reaches(f64::NAN, e.vf, 0.0).then_some((t, end.p))
}

/// The first-order profile (velocity limit throughout, in the direction of the displacement).
pub(crate) fn first_order_extremal(e: &Ends, b: &Bounds, found: &mut Extremals) {
    let dir = if e.pd >= 0.0 {
        Direction::Up
    } else {
        Direction::Down
    };
    let (e, b) = (e.toward(dir), b.toward(dir));
    let mut t = [0.0; 7];
    if e.pd > 0.0 {
        t[3] = e.pd / b.v_max;
    }
    if t[3].is_finite() && t[3] >= 0.0 && (t[3] * b.v_max - e.pd).abs() < P_PRECISION || e.pd == 0.0
    {
        found.push(Extremal {
            t,
            dir,
            duration: t[3],
        });
    }
}

/// Largest displacement in `duration` with infinite acceleration (up frame): the velocity limit.
pub(crate) fn first_order_max_displacement(b: &Bounds, duration: f64) -> Option<([f64; 7], f64)> {
    if !b.v_max.is_finite() {
        return None;
    }
    let mut t = [0.0; 7];
    t[3] = duration;
    Some((t, b.v_max * duration))
}

/// Velocity interface with infinite jerk: the acceleration limit towards the target velocity.
pub(crate) fn velocity_second_extremal(e: &Ends, b: &Bounds, found: &mut Extremals) {
    let vd = e.vf - e.v0;
    let dir = if vd >= 0.0 {
        Direction::Up
    } else {
        Direction::Down
    };
    let b = b.toward(dir);
    let vd = vd * dir.sign();
    let mut t = [0.0; 7];
    if vd > 0.0 {
        t[1] = vd / b.a_max;
    }
    if t[1].is_finite() && (vd == 0.0 || (t[1] * b.a_max - vd).abs() < V_PRECISION) {
        found.push(Extremal {
            t,
            dir,
            duration: t[1],
        });
    }
}

/// Largest final velocity in `duration` with infinite jerk (up frame).
pub(crate) fn velocity_second_max(e: &Ends, b: &Bounds, duration: f64) -> Option<([f64; 7], f64)> {
    if !b.a_max.is_finite() {
        return None;
    }
    let mut t = [0.0; 7];
    t[1] = duration;
    Some((t, e.v0 + b.a_max * duration))
}

/// A single phase of constant acceleration `a0` (the only motion when a jerk or acceleration
/// limit is zero): its duration if it reaches the target, `None` otherwise. Velocity limits
/// are checked at the end.
pub(crate) fn constant_acceleration(e: &Ends, b: &Bounds) -> Option<f64> {
    if (e.af - e.a0).abs() > f64::EPSILON {
        return None;
    }
    let reaches = |t: f64| {
        if !(t >= -T_EPS) || !t.is_finite() {
            return false;
        }
        let t = t.max(0.0);
        let p = t * (e.v0 + 0.5 * t * e.a0);
        let v = e.v0 + t * e.a0;
        (p - e.pd).abs() < P_PRECISION
            && (v - e.vf).abs() < V_PRECISION
            && v <= b.v_max + V_EPS
            && v >= b.v_min - V_EPS
    };
    let mut candidates = [f64::NAN; 2];
    if e.a0.abs() > f64::EPSILON {
        let q = libm::sqrt(2.0 * e.a0 * e.pd + e.v0 * e.v0);
        candidates = [(-e.v0 + q) / e.a0, -(e.v0 + q) / e.a0];
    } else if e.v0.abs() > f64::EPSILON {
        candidates[0] = e.pd / e.v0;
    } else if e.pd.abs() < f64::EPSILON {
        candidates[0] = 0.0;
    }
    candidates
        .into_iter()
        .find(|&t| reaches(t))
        .map(|t| t.max(0.0))
}

/// The velocity interface's single phase of constant acceleration (zero jerk limit).
pub(crate) fn constant_acceleration_velocity(e: &Ends) -> Option<f64> {
    if (e.af - e.a0).abs() > f64::EPSILON {
        return None;
    }
    let vd = e.vf - e.v0;
    if e.a0.abs() > f64::EPSILON {
        let t = vd / e.a0;
        (t >= 0.0).then_some(t)
    } else if vd.abs() < f64::EPSILON {
        Some(0.0)
    } else {
        None
    }
}
