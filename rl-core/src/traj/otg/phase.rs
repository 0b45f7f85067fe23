//! Phase synchronisation: straight lines in joint space.
//!
//! When every axis' boundary data — displacement, start and target velocity and acceleration —
//! is the same vector scaled per axis (`d_i = r_i · d_L` for the limiting axis `L`), every axis
//! can follow the limiting axis' profile scaled by `r_i`: jerk, acceleration, velocity and
//! displacement all scale by `r_i`, so the boundary conditions hold and the joint-space path is
//! the straight line through start and target (Berscheid & Kröger 2021, §III-E). It is used when
//! every scaled profile keeps its axis' limits; otherwise the axes are time-synchronised (same
//! duration, other paths). Axes that brake first are not phase-synchronised.

use super::block::{Axis, Kind};
use super::frame::slack;
use super::profile::{Order, Shape};

/// Relative tolerance of the collinearity test.
const COLLINEAR: f64 = 1e-12;

/// The scaled shapes of every axis, if the input is collinear and each keeps its limits.
pub(crate) fn scaled<const N: usize>(
    axes: &[Axis; N],
    limiting: usize,
    duration: f64,
) -> Option<[Shape; N]> {
    let lead = &axes[limiting];
    if axes
        .iter()
        .any(|a| a.kind != lead.kind || a.brake.duration() > 0.0)
    {
        return None;
    }
    if !matches!(lead.kind, Kind::PositionJerk | Kind::VelocityJerk) {
        return None;
    }
    let velocity = lead.kind.is_velocity();
    let data = |i: usize| {
        let e = &axes[i].ends;
        [if velocity { 0.0 } else { e.pd }, e.v0, e.a0, e.vf, e.af]
    };
    let reference = data(limiting);
    let norm2: f64 = reference.iter().map(|x| x * x).sum();
    if !(norm2 > 0.0) {
        return None;
    }
    let norm = libm::sqrt(norm2);
    let shape = match lead.plan(limiting, duration) {
        Ok(super::block::Plan::One(s)) => s,
        _ => return None,
    };
    let mut shapes = [Shape::EMPTY; N];
    for i in 0..N {
        let d = data(i);
        let ratio = d.iter().zip(&reference).map(|(a, b)| a * b).sum::<f64>() / norm2;
        let scale = libm::sqrt(d.iter().map(|x| x * x).sum::<f64>()).max(norm);
        if d.iter()
            .zip(&reference)
            .any(|(a, b)| (a - ratio * b).abs() > COLLINEAR * scale)
        {
            return None;
        }
        let mut s = shape;
        for (v, h) in s.value.iter_mut().zip(s.hold.iter_mut()) {
            *v *= ratio;
            *h *= ratio;
        }
        s.cruise *= ratio;
        s.end_v = axes[i].ends.vf;
        s.end_a = axes[i].ends.af;
        if !keeps_limits(&s, &axes[i]) {
            return None;
        }
        shapes[i] = s;
    }
    Some(shapes)
}

/// Whether a jerk shape keeps the jerk, acceleration and (for a position target) velocity limits
/// of `axis` from its start state.
fn keeps_limits(s: &Shape, axis: &Axis) -> bool {
    if s.order != Order::Jerk {
        return false;
    }
    let b = &axis.bounds;
    let [v_lo, v_hi, a_lo, a_hi] = slack(b);
    let velocity = axis.kind.is_velocity();
    let (mut v, mut a) = (axis.ends.v0, axis.ends.a0);
    for i in 0..7 {
        let (t, j) = (s.t[i], s.value[i]);
        if t == 0.0 {
            continue;
        }
        if j.abs() > b.j * (1.0 + 1e-12) + 1e-12 {
            return false;
        }
        let a1 = a + t * j;
        if !velocity && a * a1 < 0.0 {
            let v_ext = v - a * a / (2.0 * j);
            if v_ext > v_hi || v_ext < v_lo {
                return false;
            }
        }
        v += t * (a + 0.5 * t * j);
        a = a1;
        if a > a_hi || a < a_lo {
            return false;
        }
        if !velocity && (v > v_hi || v < v_lo) {
            return false;
        }
    }
    true
}
