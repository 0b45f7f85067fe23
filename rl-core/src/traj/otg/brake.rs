//! Braking that brings a start state beyond the limits back within them before the profile.
//!
//! A start with acceleration beyond a limit, or whose velocity beyond a limit cannot be avoided
//! any more (at full jerk against the acceleration it still overshoots), cannot follow a profile
//! of the seven-phase form within the limits. As Ruckig does (Berscheid & Kröger 2021, §III-F),
//! the axis first brakes at full jerk for at most two phases: jerk against the excess until the
//! acceleration is back at its limit or the velocity back at its limit, then holding the
//! acceleration limit while the velocity comes back. The profile then starts from the braked
//! state. During braking the limits the start already broke stay broken; nothing else does.

use super::frame::Bounds;

/// Safety margin added to braking times so the braked state is inside, not on, the limits.
const EPS: f64 = 2.2e-14;

/// Up to two phases of braking: `(duration, jerk, acceleration held)`; for the jerk-limited
/// brakes the hold has jerk 0 and keeps the acceleration reached.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Brake {
    pub t: [f64; 2],
    pub j: [f64; 2],
    /// For a second-order brake (infinite jerk): the acceleration of the first phase.
    pub a: f64,
    pub second_order: bool,
}

impl Brake {
    /// Total braking time.
    #[inline]
    pub fn duration(&self) -> f64 {
        self.t[0] + self.t[1]
    }

    /// The state after braking from `(p, v, a)`.
    pub fn apply(&self, p: f64, v: f64, a: f64) -> [f64; 3] {
        let (mut p, mut v, mut a) = (p, v, a);
        if self.second_order {
            if self.t[0] > 0.0 {
                let t = self.t[0];
                let acc = self.a;
                p += t * (v + 0.5 * t * acc);
                v += t * acc;
            }
            return [p, v, a];
        }
        for i in 0..2 {
            let (t, j) = (self.t[i], self.j[i]);
            if t > 0.0 {
                p += t * (v + t * (0.5 * a + t * j * (1.0 / 6.0)));
                v += t * (a + 0.5 * t * j);
                a += t * j;
            }
        }
        [p, v, a]
    }
}

/// Velocity after `t` at jerk `j` from `(v, a)`.
#[inline]
fn v_after(v: f64, a: f64, j: f64, t: f64) -> f64 {
    v + t * (a + 0.5 * j * t)
}

/// Velocity where the acceleration `a` reaches zero at jerk of size `j` against it.
#[inline]
fn v_at_zero_acceleration(v: f64, a: f64, j: f64) -> f64 {
    v + a * a / (2.0 * j)
}

/// Velocity beyond `v_max` (in the direction of `j`'s sign): jerk against it until the velocity
/// is back at `v_max`, holding `a_min` if reached, without undershooting `v_min`. `b` holds the
/// limits as seen in that direction (the jerk `b.j` may be negative).
fn velocity_brake(v0: f64, a0: f64, b: &Bounds) -> Brake {
    let Bounds {
        v_max,
        v_min,
        a_min,
        j,
        ..
    } = *b;
    let mut brake = Brake {
        j: [-j, 0.0],
        ..Brake::default()
    };
    let t_to_a_min = (a0 - a_min) / j;
    let t_to_v_max = a0 / j + libm::sqrt(a0 * a0 + 2.0 * j * (v0 - v_max)) / j.abs();
    let t_to_v_min = a0 / j + libm::sqrt(0.5 * a0 * a0 + j * (v0 - v_min)) / j.abs();
    let t_to_limit = f64::min(t_to_v_max, t_to_v_min);
    if t_to_a_min < t_to_limit {
        let v_at_a_min = v_after(v0, a0, -j, t_to_a_min);
        let hold_to_v_max = -(v_at_a_min - v_max) / a_min;
        let hold_to_v_min = a_min / (2.0 * j) - (v_at_a_min - v_min) / a_min;
        brake.t[0] = f64::max(t_to_a_min - EPS, 0.0);
        brake.t[1] = f64::max(f64::min(hold_to_v_max, hold_to_v_min), 0.0);
    } else {
        brake.t[0] = f64::max(t_to_limit - EPS, 0.0);
    }
    brake
}

/// Acceleration beyond `a_max` (in the direction of `j`'s sign): jerk against it down to
/// `a_max`, then either the velocity brake (if the velocity would overshoot `v_max` anyway) or a
/// hold at `a_max` while the velocity climbs back from below `v_min`.
fn acceleration_brake(v0: f64, a0: f64, bounds: &Bounds) -> Brake {
    let Bounds {
        v_max,
        v_min,
        a_max,
        j,
        ..
    } = *bounds;
    let mut b = Brake {
        j: [-j, 0.0],
        ..Brake::default()
    };
    let t_to_a_max = (a0 - a_max) / j;
    let t_to_a_zero = a0 / j;
    let v_at_a_max = v_after(v0, a0, -j, t_to_a_max);
    let v_at_a_zero = v_after(v0, a0, -j, t_to_a_zero);
    let up = j > 0.0;
    if (v_at_a_zero > v_max && up) || (v_at_a_zero < v_max && !up) {
        return velocity_brake(v0, a0, bounds);
    }
    if (v_at_a_max < v_min && up) || (v_at_a_max > v_min && !up) {
        let hold_to_v_min = -(v_at_a_max - v_min) / a_max;
        let hold_to_v_max = -a_max / (2.0 * j) - (v_at_a_max - v_max) / a_max;
        b.t[0] = t_to_a_max + EPS;
        b.t[1] = f64::max(f64::min(hold_to_v_min, hold_to_v_max - EPS), 0.0);
    } else {
        b.t[0] = t_to_a_max + EPS;
    }
    b
}

/// Braking for the jerk-limited position interface (none if the start is within reach).
pub(crate) fn position_third(v0: f64, a0: f64, b: &Bounds) -> Brake {
    if b.j == 0.0 || b.a_max == 0.0 || b.a_min == 0.0 {
        // Zero limits: the motion keeps its acceleration; nothing to brake with.
        return Brake::default();
    }
    // The limits seen braking the other way: the same values with the roles of the maximum and
    // the minimum swapped, and the jerk negated.
    let reversed = Bounds {
        v_max: b.v_min,
        v_min: b.v_max,
        a_max: b.a_min,
        a_min: b.a_max,
        j: -b.j,
    };
    if a0 > b.a_max {
        acceleration_brake(v0, a0, b)
    } else if a0 < b.a_min {
        acceleration_brake(v0, a0, &reversed)
    } else if (v0 > b.v_max && v_at_zero_acceleration(v0, a0, -b.j) > b.v_min)
        || (a0 > 0.0 && v_at_zero_acceleration(v0, a0, b.j) > b.v_max)
    {
        velocity_brake(v0, a0, b)
    } else if (v0 < b.v_min && v_at_zero_acceleration(v0, a0, b.j) < b.v_max)
        || (a0 < 0.0 && v_at_zero_acceleration(v0, a0, -b.j) < b.v_min)
    {
        velocity_brake(v0, a0, &reversed)
    } else {
        Brake::default()
    }
}

/// Braking for the position interface with infinite jerk: constant acceleration back to the
/// velocity limit.
pub(crate) fn position_second(v0: f64, v_max: f64, v_min: f64, a_max: f64, a_min: f64) -> Brake {
    let mut b = Brake {
        second_order: true,
        ..Brake::default()
    };
    if a_max == 0.0 || a_min == 0.0 {
        return b;
    }
    if v0 > v_max {
        b.a = a_min;
        b.t[0] = (v_max - v0) / a_min + EPS;
    } else if v0 < v_min {
        b.a = a_max;
        b.t[0] = (v_min - v0) / a_max + EPS;
    }
    b
}

/// Braking for the jerk-limited velocity interface: jerk back to the acceleration limit.
pub(crate) fn velocity_third(a0: f64, a_max: f64, a_min: f64, j: f64) -> Brake {
    let mut b = Brake::default();
    if j == 0.0 {
        return b;
    }
    if a0 > a_max {
        b.j[0] = -j;
        b.t[0] = (a0 - a_max) / j + EPS;
    } else if a0 < a_min {
        b.j[0] = j;
        b.t[0] = (a_min - a0) / j + EPS;
    }
    b
}
