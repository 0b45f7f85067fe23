//! Jerk-limited position profiles of one axis: the extremal (time-optimal type) profiles that
//! reach a target state, and the extremal profiles of a given duration.
//!
//! A profile has seven phases of constant jerk `+J, 0, -J, 0, -J, 0, +J` ("UDDU", written in the
//! up frame of [`super::frame`]): the acceleration rises to `x`, may hold at `a_max`, falls
//! through zero (where the velocity may cruise at `v_max`) to `-y`, may hold at `a_min`, and
//! rises to the target acceleration. Berscheid & Kröger (RSS 2021, §III) show that every
//! boundary of the set of durations in which one axis can reach its target is such a profile,
//! in one of eight types named by the limits it reaches: cruise with or without either
//! acceleration hold (`VEL`, `ACC0_VEL`, `ACC1_VEL`, `ACC0_ACC1_VEL`), and without cruise
//! (`NONE`, `ACC0`, `ACC1`, `ACC0_ACC1`).
//!
//! Given the target position (step 1), each type is one polynomial equation in one unknown,
//! derived here (`scripts/otg-derive` prints the derivation with sympy):
//!
//! - cruise types: closed form (the two ramps to and from `v_max` are fixed; the cruise takes
//!   the remaining distance);
//! - `NONE`: with `s = x + y` and `c = J·vd + (a0² − af²)/2` the ramps give `x − y = c/s`, and
//!   the position is a depressed quartic in `s`;
//! - `ACC0` (`x = a_max`): a quartic in `y`; `ACC1` (`y = −a_min`): a quartic in `x`;
//! - `ACC0_ACC1`: a quadratic in the length of the second hold.
//!
//! The leading coefficients are short closed forms; the constant term is the position error of
//! the profile at the unknown's zero, computed by integrating its phases (which the polynomial
//! identity allows for any sign of the durations), so no long expanded formula carries rounding.
//!
//! Given the duration instead (step 2), the same types give the profile reaching the target
//! velocity and acceleration with the largest displacement ([`max_displacement`]): the
//! duration fixes `s` for `NONE` and leaves a quadratic for the others. Pontryagin's maximum
//! principle gives its shape: the costate of the acceleration is a convex parabola, so the
//! jerk is `+J, -J, +J` with holds where a limit is active.

use super::frame::{Bounds, Direction, Ends, P_PRECISION, UDDU, V_PRECISION};
use super::frame::{clean_times, integrate_checked, slack, total};
use super::roots::{quadratic, quartic_in};

/// An extremal profile of one axis: phase durations in the frame of its direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Extremal {
    pub t: [f64; 7],
    pub dir: Direction,
    pub duration: f64,
}

/// Room for the extremal profiles of one axis (at most five are distinct).
pub(crate) const MAX_EXTREMALS: usize = 8;

/// The extremal profiles found for one axis, in the order found.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Extremals {
    pub items: [Extremal; MAX_EXTREMALS],
    pub len: usize,
}

impl Extremals {
    pub const fn new() -> Self {
        Self {
            items: [Extremal {
                t: [0.0; 7],
                dir: Direction::Up,
                duration: 0.0,
            }; MAX_EXTREMALS],
            len: 0,
        }
    }

    #[inline]
    pub fn push(&mut self, e: Extremal) {
        if self.len < MAX_EXTREMALS {
            self.items[self.len] = e;
            self.len += 1;
        }
    }

    pub fn as_slice(&self) -> &[Extremal] {
        &self.items[..self.len]
    }
}

/// Integrates the UDDU phases without checking anything (also for negative durations, as the
/// polynomial identities need): end state relative to the start position.
#[inline]
fn integrate(t: &[f64; 7], v0: f64, a0: f64, j: f64) -> [f64; 3] {
    let (mut p, mut v, mut a) = (0.0, v0, a0);
    for i in 0..7 {
        let ti = t[i];
        // Each profile type has its own fixed zero phases: a well-predicted branch.
        if ti == 0.0 {
            continue;
        }
        let ji = UDDU[i] * j;
        p += ti * (v + ti * (0.5 * a + ti * ji * (1.0 / 6.0)));
        v += ti * (a + 0.5 * ti * ji);
        a += ti * ji;
    }
    [p, v, a]
}

/// Checks a step-1 candidate (durations `t` in the up frame of `dir`) and keeps it.
#[inline]
fn accept(t: [f64; 7], e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals) -> bool {
    accept_reaching(t, e, b, e.pd, dir, found)
}

/// As [`accept`], with the target displacement `pd` (NaN: the position is free, as for the
/// velocity interface).
#[inline]
pub(crate) fn accept_reaching(
    mut t: [f64; 7],
    e: &Ends,
    b: &Bounds,
    pd: f64,
    dir: Direction,
    found: &mut Extremals,
) -> bool {
    if !clean_times(&mut t) {
        return false;
    }
    let Some(end) = integrate_checked(&t, e.v0, e.a0, b) else {
        return false;
    };
    if end.reaches(pd, e.vf, e.af) {
        found.push(Extremal {
            t,
            dir,
            duration: total(&t),
        });
        true
    } else {
        false
    }
}

/// Phases `(t0, t1, t2)` that take `(v, a)` to `(v_peak, 0)` with jerk `+j`, a hold at `a_max`
/// if needed, and `-j` (the rising half of a cruise profile).
#[inline]
fn rise(v: f64, a: f64, v_peak: f64, a_max: f64, j: f64) -> Option<[f64; 3]> {
    let x2 = 0.5 * a * a + j * (v_peak - v);
    if !(x2 >= 0.0) {
        return None;
    }
    let x = libm::sqrt(x2);
    if x <= a_max {
        Some([(x - a) / j, 0.0, x / j])
    } else {
        let hold = (v_peak - v - (2.0 * a_max * a_max - a * a) / (2.0 * j)) / a_max;
        Some([(a_max - a) / j, hold, a_max / j])
    }
}

/// Phases `(t4, t5, t6)` that take `(v_peak, 0)` to `(vf, af)` with jerk `-j`, a hold at
/// `a_min` if needed, and `+j` (the falling half of a cruise profile).
#[inline]
fn fall(v_peak: f64, vf: f64, af: f64, a_min: f64, j: f64) -> Option<[f64; 3]> {
    let y2 = 0.5 * af * af + j * (v_peak - vf);
    if !(y2 >= 0.0) {
        return None;
    }
    let y = libm::sqrt(y2);
    if y <= -a_min {
        Some([y / j, 0.0, (af + y) / j])
    } else {
        let y = -a_min;
        let hold = (v_peak - vf - (2.0 * y * y - af * af) / (2.0 * j)) / y;
        Some([y / j, hold, (af + y) / j])
    }
}

/// The cruise types: rise to `v_max`, cruise, fall to the target.
fn cruise(e: &Ends, b: &Bounds) -> Option<[f64; 7]> {
    if !(b.v_max > 0.0) || !b.v_max.is_finite() {
        return None;
    }
    let [t0, t1, t2] = rise(e.v0, e.a0, b.v_max, b.a_max, b.j)?;
    let [t4, t5, t6] = fall(b.v_max, e.vf, e.af, b.a_min, b.j)?;
    let mut t = [t0, t1, t2, 0.0, t4, t5, t6];
    let [p, _, _] = integrate(&t, e.v0, e.a0, b.j);
    t[3] = (e.pd - p) / b.v_max;
    Some(t)
}

/// Cauchy's bound on the roots of the monic quartic `q`.
#[inline]
fn cauchy(q: &[f64; 5]) -> f64 {
    1.0 + f64::max(
        f64::max(q[0].abs(), q[1].abs()),
        f64::max(q[2].abs(), q[3].abs()),
    )
}

/// Where a profile type's unknown may lie: an interval minus up to three open intervals,
/// from the constraints of the type written as quadratic inequalities in the unknown. Solving
/// only there keeps the root finder off roots that the profile check would reject anyway.
#[derive(Clone, Copy)]
struct Pieces {
    lo: [f64; 4],
    hi: [f64; 4],
    n: usize,
}

impl Pieces {
    fn new(lo: f64, hi: f64) -> Self {
        Self {
            lo: [lo, 0.0, 0.0, 0.0],
            hi: [hi, 0.0, 0.0, 0.0],
            n: usize::from(lo <= hi),
        }
    }

    /// Keeps `u² + b u + c ≤ 0` (nothing if it has no real root).
    fn keep_below(&mut self, b: f64, c: f64) {
        let mut r = [0.0; 2];
        if quadratic(1.0, b, c, &mut r) < 2 {
            // No real roots (or a double root): the quadratic is positive nearly everywhere;
            // keep the double root's neighbourhood only through the widening below.
            if r[0].is_finite() && b * b - 4.0 * c == 0.0 {
                self.clip(r[0], r[0]);
            } else {
                self.n = 0;
            }
            return;
        }
        self.clip(r[0], r[1]);
    }

    fn clip(&mut self, lo: f64, hi: f64) {
        let mut k = 0;
        for i in 0..self.n {
            let (l, h) = (f64::max(self.lo[i], lo), f64::min(self.hi[i], hi));
            if l <= h {
                self.lo[k] = l;
                self.hi[k] = h;
                k += 1;
            }
        }
        self.n = k;
    }

    /// Keeps `u² + b u + c ≥ 0`: removes the open interval between its roots.
    fn keep_above(&mut self, b: f64, c: f64) {
        let mut r = [0.0; 2];
        if quadratic(1.0, b, c, &mut r) < 2 {
            return;
        }
        let (cut_lo, cut_hi) = (r[0], r[1]);
        let mut lo = [0.0; 4];
        let mut hi = [0.0; 4];
        let mut k = 0;
        for i in 0..self.n {
            let (l, h) = (self.lo[i], self.hi[i]);
            if h <= cut_lo || l >= cut_hi {
                lo[k] = l;
                hi[k] = h;
                k += 1;
                continue;
            }
            if l < cut_lo && k < 4 {
                lo[k] = l;
                hi[k] = cut_lo;
                k += 1;
            }
            if h > cut_hi && k < 4 {
                lo[k] = cut_hi;
                hi[k] = h;
                k += 1;
            }
        }
        self.lo = lo;
        self.hi = hi;
        self.n = k;
    }

    /// Roots of the monic quartic `q` in the pieces, each piece widened a little so that roots
    /// on a border (a phase of zero length) survive rounding, and bounded by Cauchy's bound.
    fn roots(&self, q: &[f64; 5], out: &mut [f64; 4]) -> usize {
        let bound = cauchy(q);
        let mut n = 0;
        for i in 0..self.n {
            let lo = f64::max(self.lo[i], -bound);
            let hi = f64::min(self.hi[i], bound);
            let widen = 1e-9 * (lo.abs() + hi.abs()) + f64::MIN_POSITIVE;
            let mut found = [0.0; 4];
            let m = quartic_in(q, lo - widen, hi + widen, &mut found);
            for &r in &found[..m] {
                if n < out.len() {
                    out[n] = r;
                    n += 1;
                }
            }
        }
        n
    }
}

/// Solves the quartic `q` on `pieces` and keeps the profiles `times` gives for its roots.
fn accept_roots(
    q: &[f64; 5],
    pieces: &Pieces,
    times: impl Fn(f64) -> [f64; 7],
    (e, b, dir): (&Ends, &Bounds, Direction),
    found: &mut Extremals,
    first_only: bool,
) {
    let mut roots = [0.0; 4];
    let n = pieces.roots(q, &mut roots);
    for &u in &roots[..n] {
        if accept(times(u), e, b, dir, found) && first_only {
            return;
        }
    }
}

/// `NONE`: no hold, no cruise. Roots `s = x + y` of the depressed quartic.
fn none(e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals, first_only: bool) {
    let j = b.j;
    let vd = e.vf - e.v0;
    let (a0, af) = (e.a0, e.af);
    let (a0_2, af_2) = (a0 * a0, af * af);
    let h = 2.0 * j * vd + a0_2 - af_2;
    let q = [
        -0.25 * h * h,
        -(4.0 / 3.0)
            * (3.0 * j * j * e.pd + 3.0 * j * (a0 * e.v0 - af * e.vf) + af_2 * af - a0_2 * a0),
        2.0 * (2.0 * j * (e.v0 + e.vf) - a0_2 - af_2),
        0.0,
        1.0,
    ];
    let c = 0.5 * h;
    // With x = (s + c/s)/2 and y = (s − c/s)/2 (s > 0): x ≤ a_max, y ≤ −a_min, x ≥ a0
    // (t0 ≥ 0) and y ≥ −af (t6 ≥ 0), each a quadratic inequality in s.
    let mut pieces = Pieces::new(f64::max(a0 - af, 0.0), b.a_max - b.a_min);
    if b.a_max.is_finite() {
        pieces.keep_below(-2.0 * b.a_max, c);
    }
    if b.a_min.is_finite() {
        pieces.keep_below(2.0 * b.a_min, -c);
    }
    pieces.keep_above(-2.0 * a0, c);
    pieces.keep_above(2.0 * af, -c);
    let mut roots = [0.0; 4];
    let n = pieces.roots(&q, &mut roots);
    for &s in &roots[..n] {
        if !(s > 0.0) {
            continue;
        }
        let x = 0.5 * (s + c / s);
        let y = 0.5 * (s - c / s);
        let t = [(x - a0) / j, 0.0, s / j, 0.0, 0.0, 0.0, (af + y) / j];
        if accept(t, e, b, dir, found) && first_only {
            return;
        }
    }
}

/// `ACC0`: hold at `a_max`, then fall to `-y` and rise to the target. Roots `y` of a quartic.
fn acc0(e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals, first_only: bool) {
    let (j, am) = (b.j, b.a_max);
    let (a0, af) = (e.a0, e.af);
    let vd = e.vf - e.v0;
    let af_2 = af * af;
    let times = |y: f64| {
        let hold = (2.0 * j * vd + a0 * a0 - af_2 - 2.0 * am * am + 2.0 * y * y) / (2.0 * j * am);
        [
            (am - a0) / j,
            hold,
            (am + y) / j,
            0.0,
            0.0,
            0.0,
            (af + y) / j,
        ]
    };
    // monic(y) = 2 J² a_max (p(y) − pd)
    let [p, _, _] = integrate(&times(0.0), e.v0, a0, j);
    let q = [
        2.0 * j * j * am * (p - e.pd),
        2.0 * am * (2.0 * j * e.vf - af_2),
        2.0 * j * e.vf + am * am - af_2,
        2.0 * am,
        1.0,
    ];
    // y in [max(−af, −a_max), −a_min], and the hold t1 ≥ 0: y² ≥ a_max² − (2J·vd + a0² − af²)/2.
    let mut pieces = Pieces::new(f64::max(-af, -am), -b.a_min);
    pieces.keep_above(0.0, 0.5 * (2.0 * j * vd + a0 * a0 - af_2) - am * am);
    accept_roots(&q, &pieces, times, (e, b, dir), found, first_only);
}

/// `ACC1`: rise to `x`, fall to `a_min`, hold there, rise to the target. Roots `x` of a quartic.
fn acc1(e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals, first_only: bool) {
    let (j, an) = (b.j, b.a_min);
    let (a0, af) = (e.a0, e.af);
    let vd = e.vf - e.v0;
    let a0_2 = a0 * a0;
    let times = |x: f64| {
        let hold = (2.0 * x * x - a0_2 + af * af - 2.0 * an * an - 2.0 * j * vd) / (-2.0 * j * an);
        [
            (x - a0) / j,
            0.0,
            (x - an) / j,
            0.0,
            0.0,
            hold,
            (af - an) / j,
        ]
    };
    // monic(x) = −2 J² a_min (p(x) − pd)
    let [p, _, _] = integrate(&times(0.0), e.v0, a0, j);
    let q = [
        -2.0 * j * j * an * (p - e.pd),
        -2.0 * an * (2.0 * j * e.v0 - a0_2),
        2.0 * j * e.v0 - a0_2 + an * an,
        -2.0 * an,
        1.0,
    ];
    // x in [max(a0, a_min), a_max], and the hold t5 ≥ 0: x² ≥ a_min² + (a0² − af²)/2 + J·vd.
    let mut pieces = Pieces::new(f64::max(a0, an), b.a_max);
    pieces.keep_above(0.0, -(an * an + 0.5 * (a0_2 - af * af) + j * vd));
    accept_roots(&q, &pieces, times, (e, b, dir), found, first_only);
}

/// `ACC0_ACC1`: holds at both acceleration limits. A quadratic in the second hold.
fn acc0_acc1(e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals, first_only: bool) {
    let (j, am, an) = (b.j, b.a_max, b.a_min);
    let (a0, af) = (e.a0, e.af);
    let vd = e.vf - e.v0;
    let times = |t5: f64| {
        let hold0 = (2.0 * j * vd + a0 * a0 - af * af - 2.0 * am * am + 2.0 * an * an
            - 2.0 * j * t5 * an)
            / (2.0 * j * am);
        [
            (am - a0) / j,
            hold0,
            (am - an) / j,
            0.0,
            0.0,
            t5,
            (af - an) / j,
        ]
    };
    let [p, _, _] = integrate(&times(0.0), e.v0, a0, j);
    let c2 = -an * (am - an) / (2.0 * am);
    let c1 = (am - an) * (2.0 * j * e.vf - am * an + 2.0 * an * an - af * af) / (2.0 * j * am);
    let mut roots = [0.0; 2];
    let n = quadratic(c2, c1, p - e.pd, &mut roots);
    for &t5 in &roots[..n] {
        if accept(times(t5), e, b, dir, found) && first_only {
            return;
        }
    }
}

/// All extremal profiles of one direction (up frame of `dir`), or the first one found with
/// `first_only` (a target at rest has exactly one).
fn extremals_toward(e: &Ends, b: &Bounds, dir: Direction, found: &mut Extremals, first_only: bool) {
    let e = e.toward(dir);
    let b = b.toward(dir);
    let before = found.len;
    let done = |found: &Extremals| first_only && found.len > before;
    // Closed forms first (with `first_only` the search stops at the first profile found).
    if let Some(t) = cruise(&e, &b)
        && accept(t, &e, &b, dir, found)
        && first_only
    {
        return;
    }
    if b.a_max.is_finite() && b.a_min.is_finite() {
        acc0_acc1(&e, &b, dir, found, first_only);
        if done(found) {
            return;
        }
    }
    // The quartic types, the likeliest first.
    let order = if first_only && e.vf == 0.0 && e.af == 0.0 {
        rest_order(&e, &b)
    } else {
        [Quartic::None, Quartic::Acc0, Quartic::Acc1]
    };
    for kind in order {
        match kind {
            Quartic::None => none(&e, &b, dir, found, first_only),
            Quartic::Acc0 if b.a_max.is_finite() => acc0(&e, &b, dir, found, first_only),
            Quartic::Acc1 if b.a_min.is_finite() => acc1(&e, &b, dir, found, first_only),
            _ => {}
        }
        if done(found) {
            return;
        }
    }
}

/// The profile types solved by a quartic.
#[derive(Clone, Copy)]
enum Quartic {
    None,
    Acc0,
    Acc1,
}

/// For a target at rest (up frame), the quartic types in the order to try them: the profile
/// whose acceleration crosses zero at peak velocity `v` has a displacement increasing with `v`,
/// and its rise holds at `a_max` from `v_a = v0 + (a_max² − a0²/2)/J` on, its fall at `a_min`
/// from `v_b = a_min²/J` on; comparing the target displacement with those two profiles' tells
/// the type (all are still tried if it is not found, so this only orders the search).
fn rest_order(e: &Ends, b: &Bounds) -> [Quartic; 3] {
    let j = b.j;
    let v_low = f64::max(e.v0 + e.a0 * e.a0.abs() / (2.0 * j), 0.0);
    let reaches = |v: f64| {
        if !(v >= v_low && v < b.v_max) {
            return false;
        }
        let (Some([t0, t1, t2]), Some([t4, t5, t6])) = (
            rise(e.v0, e.a0, v, b.a_max, j),
            fall(v, 0.0, 0.0, b.a_min, j),
        ) else {
            return false;
        };
        let [p, _, _] = integrate(&[t0, t1, t2, 0.0, t4, t5, t6], e.v0, e.a0, j);
        e.pd >= p
    };
    if b.a_max.is_finite() && reaches(e.v0 + (b.a_max * b.a_max - 0.5 * e.a0 * e.a0) / j) {
        [Quartic::Acc0, Quartic::None, Quartic::Acc1]
    } else if b.a_min.is_finite() && reaches(b.a_min * b.a_min / j) {
        [Quartic::Acc1, Quartic::None, Quartic::Acc0]
    } else {
        [Quartic::None, Quartic::Acc1, Quartic::Acc0]
    }
}

/// The extremal profiles of one axis with finite, positive jerk and acceleration limits.
///
/// A target at rest (`vf = af = 0`) is reached by exactly one extremal profile (no duration is
/// blocked); its direction is tried first by the sign of the displacement, and the search
/// stops at the first profile found. Otherwise every extremal profile of both directions is
/// collected (up to five, the borders of the blocked intervals).
pub(crate) fn extremals(e: &Ends, b: &Bounds, found: &mut Extremals) {
    // Already there: the profile of zero duration (the only one for a target at rest).
    let there = e.pd.abs() < 1e3 * P_PRECISION
        && (e.v0 - e.vf).abs() < V_PRECISION
        && accept([0.0; 7], e, b, Direction::Up, found);
    if e.vf == 0.0 && e.af == 0.0 {
        if there {
            return;
        }
        let first = if e.pd >= 0.0 {
            Direction::Up
        } else {
            Direction::Down
        };
        let second = match first {
            Direction::Up => Direction::Down,
            Direction::Down => Direction::Up,
        };
        extremals_toward(e, b, first, found, true);
        if found.len == 0 {
            extremals_toward(e, b, second, found, true);
        }
    } else {
        extremals_toward(e, b, Direction::Up, found, false);
        extremals_toward(e, b, Direction::Down, found, false);
    }
}

/// Keeps the candidate of duration `duration` with the largest displacement.
#[inline]
fn better(mut t: [f64; 7], e: &Ends, b: &Bounds, best: &mut Option<([f64; 7], f64)>) {
    if !clean_times(&mut t) {
        return;
    }
    let Some(end) = integrate_checked(&t, e.v0, e.a0, b) else {
        return;
    };
    if end.reaches(f64::NAN, e.vf, e.af) && best.is_none_or(|(_, p_best)| end.p > p_best) {
        *best = Some((t, end.p));
    }
}

/// The profile of exactly `duration` from `(v0, a0)` to `(vf, af)` (up frame) with the largest
/// displacement, and that displacement; `None` if no profile of that duration reaches the
/// target velocity and acceleration. `e.pd` is not used.
pub(crate) fn max_displacement(e: &Ends, b: &Bounds, duration: f64) -> Option<([f64; 7], f64)> {
    let j = b.j;
    let (a0, af) = (e.a0, e.af);
    let vd = e.vf - e.v0;
    let jt = j * duration;
    let mut best = None;
    let mut roots = [0.0; 2];
    if duration == 0.0 {
        better([0.0; 7], e, b, &mut best);
        return best;
    }

    // Cruise at v_max for whatever the ramps leave (also at a zero v_max: standing still).
    if b.v_max >= 0.0
        && b.v_max.is_finite()
        && let (Some([t0, t1, t2]), Some([t4, t5, t6])) = (
            rise(e.v0, a0, b.v_max, b.a_max, j),
            fall(b.v_max, e.vf, af, b.a_min, j),
        )
    {
        let cruise = duration - (t0 + t1 + t2 + t4 + t5 + t6);
        if cruise >= 0.0 {
            better([t0, t1, t2, cruise, t4, t5, t6], e, b, &mut best);
            if best.is_some() {
                // The fastest rise to v_max, the cruise and the latest fall bound the velocity
                // of every profile of this duration from above at every instant: nothing has
                // more displacement.
                return best;
            }
        }
    }

    // The peak x and trough −y of the acceleration must lie within the limits: checked before
    // integrating (most candidates of the wrong type fail here).
    let [_, _, a_lo, a_hi] = slack(b);

    // NONE: J·T = 2s + af − a0 fixes s = x + y; x − y = c/s from the velocity.
    let s = 0.5 * (jt + a0 - af);
    if s > 0.0 {
        let c = j * vd + 0.5 * (a0 * a0 - af * af);
        let x = 0.5 * (s + c / s);
        let y = 0.5 * (s - c / s);
        if x <= a_hi && -y >= a_lo {
            better(
                [(x - a0) / j, 0.0, s / j, 0.0, 0.0, 0.0, (af + y) / j],
                e,
                b,
                &mut best,
            );
        }
    }

    if b.a_max.is_finite() {
        // ACC0: x = a_max; the hold takes the rest of the duration; y² + 2 a_max y + k = 0.
        let am = b.a_max;
        let k = j * vd + am * am + 0.5 * (a0 * a0 - af * af) - am * (jt - af + a0);
        let n = quadratic(1.0, 2.0 * am, k, &mut roots);
        for &y in &roots[..n] {
            if -y < a_lo {
                continue;
            }
            let hold = duration - (2.0 * am + 2.0 * y + af - a0) / j;
            better(
                [
                    (am - a0) / j,
                    hold,
                    (am + y) / j,
                    0.0,
                    0.0,
                    0.0,
                    (af + y) / j,
                ],
                e,
                b,
                &mut best,
            );
        }
    }

    if b.a_min.is_finite() {
        // ACC1: y = −a_min; x² + 2 y x + k = 0.
        let y = -b.a_min;
        let k = 0.5 * (af * af - a0 * a0) + y * y - y * (jt - af + a0) - j * vd;
        let n = quadratic(1.0, 2.0 * y, k, &mut roots);
        for &x in &roots[..n] {
            if x > a_hi {
                continue;
            }
            let hold = duration - (2.0 * x + 2.0 * y + af - a0) / j;
            better(
                [(x - a0) / j, 0.0, (x + y) / j, 0.0, 0.0, hold, (af + y) / j],
                e,
                b,
                &mut best,
            );
        }
    }

    if b.a_max.is_finite() && b.a_min.is_finite() {
        // ACC0_ACC1: both holds share what the ramps leave; the velocity splits them.
        let (am, y) = (b.a_max, -b.a_min);
        let holds = duration - (2.0 * am + 2.0 * y + af - a0) / j;
        let m = (2.0 * j * vd - 2.0 * am * am + a0 * a0 + 2.0 * y * y - af * af) / (2.0 * j);
        let hold0 = (m + y * holds) / (am + y);
        better(
            [
                (am - a0) / j,
                hold0,
                (am + y) / j,
                0.0,
                0.0,
                holds - hold0,
                (af + y) / j,
            ],
            e,
            b,
            &mut best,
        );
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bounds() -> Bounds {
        Bounds {
            v_max: 1.0,
            v_min: -1.5,
            a_max: 2.0,
            a_min: -2.5,
            j: 10.0,
        }
    }

    #[test]
    fn rest_to_rest_matches_the_double_s_profile() {
        // Long move: ACC0_ACC1_VEL, T = pd/v + v/a + a/j (symmetric limits).
        let b = Bounds {
            v_max: 1.0,
            v_min: -1.0,
            a_max: 2.0,
            a_min: -2.0,
            j: 10.0,
        };
        let e = Ends {
            pd: 3.0,
            v0: 0.0,
            a0: 0.0,
            vf: 0.0,
            af: 0.0,
        };
        let mut found = Extremals::new();
        extremals(&e, &b, &mut found);
        assert_eq!(found.len, 1);
        let expect = 3.0 / 1.0 + 1.0 / 2.0 + 2.0 / 10.0;
        assert!((found.items[0].duration - expect).abs() < 1e-12);
    }

    #[test]
    fn every_type_reaches_its_target() {
        // Small and large moves from moving starts, both directions: whatever is found must
        // integrate to the target (accept() checks) and the fixed-duration extremal of that
        // duration must reach at least the displacement.
        let b = bounds();
        let mut any = 0;
        for &pd in &[-4.0, -0.3, -0.01, 0.0, 0.02, 0.4, 5.0] {
            for &(v0, a0) in &[(0.0, 0.0), (0.5, 1.0), (-0.8, 1.5), (0.9, -2.0)] {
                for &(vf, af) in &[(0.0, 0.0), (0.5, 0.0), (-0.3, 1.0)] {
                    let e = Ends { pd, v0, a0, vf, af };
                    let mut found = Extremals::new();
                    extremals(&e, &b, &mut found);
                    for x in found.as_slice() {
                        any += 1;
                        let frame = b.toward(x.dir);
                        let ends = e.toward(x.dir);
                        let (_, p) = max_displacement(&ends, &frame, x.duration)
                            .expect("a profile of an extremal duration");
                        assert!(p >= ends.pd - 1e-7, "{e:?} {x:?}: {p}");
                    }
                }
            }
        }
        assert!(any > 40, "{any}");
    }
}
