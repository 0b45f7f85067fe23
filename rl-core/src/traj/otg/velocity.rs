//! The velocity interface: reach a target velocity and acceleration, position free.
//!
//! With a jerk limit the acceleration follows `+J`, a hold at `a_max` if reached, `−J` (written
//! in the up frame of [`super::frame`]; the down direction is the flipped problem). Step 1:
//! with the acceleration peak `x`, the velocity change is `(2x² − a0² − af²)/(2J)`, so
//! `x = ±√((a0² + af²)/2 + J·vd)` without a hold, or `x = a_max` and the hold takes the rest.
//! Step 2 (a given duration `T`): the profile with the largest final velocity has
//! `x = (J·T + a0 + af)/2`, or `x = a_max` and a hold of what the ramps leave (the costate of the
//! acceleration is linear in time, so the jerk switches once). As in Ruckig, the velocity limits
//! do not constrain this interface (it is how one stops or follows a velocity).

use super::frame::{Bounds, Direction, Ends, clean_times, integrate_checked};
use super::third_order::{Extremals, accept_reaching};

/// The bounds without velocity limits.
#[inline]
fn free(b: &Bounds) -> Bounds {
    Bounds {
        v_max: f64::INFINITY,
        v_min: f64::NEG_INFINITY,
        ..*b
    }
}

fn accept(t: [f64; 7], e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals) -> bool {
    accept_reaching(t, e, &free(b), f64::NAN, dir, found)
}

fn toward(e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals, first_only: bool) {
    let (e, b) = (e.toward(dir), b.toward(dir));
    let j = b.j;
    let vd = e.vf - e.v0;
    let (a0, af) = (e.a0, e.af);
    let h2 = 0.5 * (a0 * a0 + af * af) + j * vd;
    if h2 >= 0.0 {
        let h = libm::sqrt(h2);
        for x in [-h, h] {
            if accept(
                [(x - a0) / j, 0.0, (x - af) / j, 0.0, 0.0, 0.0, 0.0],
                &e,
                &b,
                dir,
                found,
            ) && first_only
            {
                return;
            }
        }
    }
    if b.a_max.is_finite() {
        let am = b.a_max;
        let hold = (a0 * a0 + af * af) / (2.0 * am * j) - am / j + vd / am;
        accept(
            [(am - a0) / j, hold, (am - af) / j, 0.0, 0.0, 0.0, 0.0],
            &e,
            &b,
            dir,
            found,
        );
    }
}

/// The extremal profiles of one axis (positive, finite jerk limit); with `af = 0` the first
/// found (there is no blocked duration).
pub(crate) fn extremals(e: &Ends, b: &Bounds, found: &mut Extremals) {
    let there = accept([0.0; 7], e, b, Direction::Up, found);
    if e.af == 0.0 {
        if there {
            return;
        }
        let (first, second) = if e.vf - e.v0 >= 0.0 {
            (Direction::Up, Direction::Down)
        } else {
            (Direction::Down, Direction::Up)
        };
        toward(e, b, first, found, true);
        if found.len == 0 {
            toward(e, b, second, found, true);
        }
    } else {
        toward(e, b, Direction::Up, found, false);
        toward(e, b, Direction::Down, found, false);
    }
}

/// The profile of exactly `duration` from `a0` to `af` (up frame) with the largest final
/// velocity, and that velocity.
pub(crate) fn max_velocity(e: &Ends, b: &Bounds, duration: f64) -> Option<([f64; 7], f64)> {
    let j = b.j;
    let (a0, af) = (e.a0, e.af);
    let x = 0.5 * (j * duration + a0 + af);
    let mut t = if x <= b.a_max {
        [(x - a0) / j, 0.0, (x - af) / j, 0.0, 0.0, 0.0, 0.0]
    } else {
        let am = b.a_max;
        let (t0, t2) = ((am - a0) / j, (am - af) / j);
        [t0, duration - t0 - t2, t2, 0.0, 0.0, 0.0, 0.0]
    };
    if !clean_times(&mut t) {
        return None;
    }
    let end = integrate_checked(&t, e.v0, e.a0, &free(b))?;
    end.reaches(f64::NAN, end.v, af).then_some((t, end.v))
}
