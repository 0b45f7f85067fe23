//! The "up" frame in which the profile equations are written, and the check of a candidate
//! profile against its boundary conditions and limits.
//!
//! Every profile equation is written once, for motion whose first jerk is positive ("up"). A
//! profile in the other direction is the same solution of the negated problem: positions,
//! velocities, accelerations and jerks change sign, and the limits swap (`vmax ↔ -vmin`,
//! `amax ↔ -amin`). [`Ends::flipped`] and [`Bounds::flipped`] make that swap, and a profile
//! found in the flipped frame is played with its jerks negated ([`Direction::sign`]).

/// Tolerances of a profile's end state against its target (absolute, in the axis' units; the
/// same values as Ruckig's profile check so that both accept the same profiles).
pub(crate) const P_PRECISION: f64 = 1e-8;
/// See [`P_PRECISION`].
pub(crate) const V_PRECISION: f64 = 1e-8;
/// See [`P_PRECISION`].
pub(crate) const A_PRECISION: f64 = 1e-10;
/// Rounding allowance on an end state: this many units of the last place of the largest value
/// met on the way (for profiles far from unit scale the absolute tolerances above would ask for
/// more digits than a double has).
pub(crate) const ROUNDING: f64 = 64.0 * f64::EPSILON;

/// The end state of an integrated profile and the largest magnitudes of position, velocity and
/// acceleration met on the way (for the rounding allowance).
#[derive(Clone, Copy, Debug)]
pub(crate) struct End {
    pub p: f64,
    pub v: f64,
    pub a: f64,
    pub scale: [f64; 3],
}

impl End {
    /// Whether the end is at `(p, v, a)` within [`P_PRECISION`], [`V_PRECISION`],
    /// [`A_PRECISION`] or the rounding allowance; `p` NaN is not checked.
    #[inline]
    pub fn reaches(&self, p: f64, v: f64, a: f64) -> bool {
        self.reaches_within(p, v, a, 1.0)
    }

    /// As [`Self::reaches`] with every tolerance times `factor`.
    #[inline]
    pub fn reaches_within(&self, p: f64, v: f64, a: f64, factor: f64) -> bool {
        let tol = |precision: f64, scale: f64| factor * f64::max(precision, ROUNDING * scale);
        (p.is_nan() || (self.p - p).abs() < tol(P_PRECISION, self.scale[0]))
            && (self.v - v).abs() < tol(V_PRECISION, self.scale[1])
            && (self.a - a).abs() < tol(A_PRECISION, self.scale[2])
    }
}

/// Slack on the velocity and acceleration limits inside a profile (rounding only), relative to
/// the limit where it is larger than one.
pub(crate) const V_EPS: f64 = 1e-12;
/// See [`V_EPS`].
pub(crate) const A_EPS: f64 = 1e-12;

/// `[v_min, v_max, a_min, a_max]` widened by the rounding slack.
#[inline]
pub(crate) fn slack(b: &Bounds) -> [f64; 4] {
    let widen = |x: f64, eps: f64| eps * f64::max(1.0, x.abs());
    [
        b.v_min - widen(b.v_min, V_EPS),
        b.v_max + widen(b.v_max, V_EPS),
        b.a_min - widen(b.a_min, A_EPS),
        b.a_max + widen(b.a_max, A_EPS),
    ]
}
/// Negative phase durations down to this size are rounding and are set to zero.
pub(crate) const T_EPS: f64 = 1e-12;

/// The direction of a profile: the sign of its first non-zero jerk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Direction {
    /// First jerk positive.
    Up,
    /// First jerk negative.
    Down,
}

impl Direction {
    /// `+1` or `-1`.
    #[inline]
    pub fn sign(self) -> f64 {
        match self {
            Self::Up => 1.0,
            Self::Down => -1.0,
        }
    }
}

/// Limits of one axis in the up frame: `v_min ≤ 0 ≤ v_max`, `a_min ≤ 0 ≤ a_max`, `j > 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub v_max: f64,
    pub v_min: f64,
    pub a_max: f64,
    pub a_min: f64,
    pub j: f64,
}

impl Bounds {
    /// The limits of the negated problem.
    #[inline]
    pub fn flipped(&self) -> Self {
        Self {
            v_max: -self.v_min,
            v_min: -self.v_max,
            a_max: -self.a_min,
            a_min: -self.a_max,
            j: self.j,
        }
    }

    /// These limits (`Up`) or the flipped ones (`Down`).
    #[inline]
    pub fn toward(&self, dir: Direction) -> Self {
        match dir {
            Direction::Up => *self,
            Direction::Down => self.flipped(),
        }
    }
}

/// Boundary conditions of one axis: displacement `pd = pf - p0`, start and end velocity and
/// acceleration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ends {
    pub pd: f64,
    pub v0: f64,
    pub a0: f64,
    pub vf: f64,
    pub af: f64,
}

impl Ends {
    /// The negated problem.
    #[inline]
    pub fn flipped(&self) -> Self {
        Self {
            pd: -self.pd,
            v0: -self.v0,
            a0: -self.a0,
            vf: -self.vf,
            af: -self.af,
        }
    }

    /// These conditions (`Up`) or the negated ones (`Down`).
    #[inline]
    pub fn toward(&self, dir: Direction) -> Self {
        match dir {
            Direction::Up => *self,
            Direction::Down => self.flipped(),
        }
    }
}

/// The jerk of each of the seven phases of an up profile, in units of the jerk limit: up, hold,
/// down, cruise, down, hold, up ("UDDU" in Berscheid & Kröger 2021).
pub(crate) const UDDU: [f64; 7] = [1.0, 0.0, -1.0, 0.0, -1.0, 0.0, 1.0];

/// The acceleration of the zero-jerk phases 1, 3, 5 of a UDDU profile in the up frame (the
/// acceleration limit, zero for the cruise, the deceleration limit; NaN for the jerk phases).
#[inline]
pub(crate) fn holds(b: &Bounds) -> [f64; 7] {
    [
        f64::NAN,
        b.a_max,
        f64::NAN,
        0.0,
        f64::NAN,
        b.a_min,
        f64::NAN,
    ]
}

/// Rounds durations within [`T_EPS`] below zero up to zero; `false` if one is more negative
/// (or NaN).
#[inline]
pub(crate) fn clean_times(t: &mut [f64; 7]) -> bool {
    let mut ok = true;
    for ti in t.iter_mut() {
        if !(*ti >= 0.0) {
            if *ti > -T_EPS {
                *ti = 0.0;
            } else {
                ok = false;
            }
        }
    }
    ok
}

/// The end state (position relative to the start) of a UDDU profile with phase durations `t`
/// from `(v0, a0)`, if every acceleration stays within limits and the velocity within limits
/// from phase 2 on (in phases 0 and 1 a start beyond the velocity limit is still being brought
/// back, as in Ruckig). `None` on a violated limit.
#[inline]
pub(crate) fn integrate_checked(t: &[f64; 7], v0: f64, a0: f64, b: &Bounds) -> Option<End> {
    let [v_lo, v_hi, a_lo, a_hi] = slack(b);
    let (mut p, mut v, mut a) = (0.0, v0, a0);
    let mut scale = [0.0, v0.abs(), a0.abs()];
    let holds = holds(b);
    for i in 0..7 {
        let ti = t[i];
        if ti == 0.0 {
            continue;
        }
        if i % 2 == 1 {
            // A hold is at its limit, a cruise at zero acceleration and at the velocity limit,
            // exactly (over a long phase the rounding of the ramp before it would drift).
            a = holds[i];
            if i == 3 {
                v = b.v_max;
            }
        }
        let j = UDDU[i] * b.j;
        let a1 = a + ti * j;
        if i >= 2 && a * a1 < 0.0 {
            // Velocity extremum inside the phase, where the acceleration crosses zero.
            let v_ext = v - a * a / (2.0 * j);
            if v_ext > v_hi || v_ext < v_lo {
                return None;
            }
        }
        p += ti * (v + ti * (0.5 * a + ti * j * (1.0 / 6.0)));
        v += ti * (a + 0.5 * ti * j);
        a = a1;
        if a > a_hi || a < a_lo {
            return None;
        }
        if (2..6).contains(&i) && (v > v_hi || v < v_lo) {
            return None;
        }
        scale[0] = f64::max(scale[0], p.abs());
        scale[1] = f64::max(scale[1], v.abs());
        scale[2] = f64::max(scale[2], a.abs());
    }
    Some(End { p, v, a, scale })
}

/// Sum of the phase durations, accumulated in order (as the phase start times are).
#[inline]
pub(crate) fn total(t: &[f64; 7]) -> f64 {
    t.iter().fold(0.0, |sum, ti| sum + ti)
}
