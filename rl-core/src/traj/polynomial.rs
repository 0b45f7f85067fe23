//! Polynomials of any degree in time with exact derivatives, boundary-condition constructors
//! (linear to septic) and at-rest time-optimal constructors synchronised over axes.
//!
//! A `Polynomial<D, C>` has `C` coefficients (degree `C - 1`) per axis, stored
//! coefficient-major (`coefficients[k][axis]` multiplies `t^k`) so evaluation vectorises over
//! axes. Boundary conditions are solved in normalised time `s = t / T` (small integer matrices,
//! well conditioned) and converted to powers of `t`.

use super::{
    Sample, Trajectory, TrajectoryError, clamp_time,
    error::LimitKind,
    roots::{derive, horner, roots_in},
};

/// A polynomial trajectory: `p(t) = Σ_k c_k t^k` on `[0, duration]`, `D` axes, `C` coefficients.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polynomial<const D: usize, const C: usize> {
    coefficients: [[f64; D]; C],
    duration: f64,
}

/// Smallest and largest value of each axis on the interval and where they occur.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extrema<const D: usize> {
    /// Minimum of each axis.
    pub min: [f64; D],
    /// Maximum of each axis.
    pub max: [f64; D],
    /// Time of the minimum.
    pub time_of_min: [f64; D],
    /// Time of the maximum.
    pub time_of_max: [f64; D],
}

/// Velocity, acceleration and jerk limits per axis (symmetric, `|x| ≤ limit`).
///
/// `f64::INFINITY` leaves a quantity unlimited where the profile allows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits<const D: usize> {
    /// Velocity limit of each axis.
    pub velocity: [f64; D],
    /// Acceleration limit of each axis.
    pub acceleration: [f64; D],
    /// Jerk limit of each axis.
    pub jerk: [f64; D],
}

impl<const D: usize> Limits<D> {
    /// The same limits on every axis.
    pub const fn uniform(velocity: f64, acceleration: f64, jerk: f64) -> Self {
        Self {
            velocity: [velocity; D],
            acceleration: [acceleration; D],
            jerk: [jerk; D],
        }
    }

    /// Every limit must be positive (NaN fails); with `finite`, also finite.
    pub(crate) fn validate(&self, finite: bool) -> Result<(), TrajectoryError> {
        let bound = if finite { f64::INFINITY } else { f64::NAN };
        let ok = |x: f64| (x > 0.0) & !(x >= bound);
        // Fast path without branches; the slow path names the first bad limit.
        let all_ok = (0..D).fold(true, |acc, i| {
            acc & ok(self.velocity[i]) & ok(self.acceleration[i]) & ok(self.jerk[i])
        });
        if all_ok {
            return Ok(());
        }
        for axis in 0..D {
            for (value, kind) in [
                (self.velocity[axis], LimitKind::Velocity),
                (self.acceleration[axis], LimitKind::Acceleration),
                (self.jerk[axis], LimitKind::Jerk),
            ] {
                if !ok(value) {
                    return Err(TrajectoryError::BadLimit { axis, kind });
                }
            }
        }
        Ok(())
    }
}

/// `true` when no value is NaN or infinite: an OR over the exponent test, branch-free, so it
/// vectorises.
#[inline]
pub(crate) fn all_finite(values: &[f64]) -> bool {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    values.iter().fold(0u64, |bad, &x| {
        bad | u64::from(x.to_bits() & EXPONENT == EXPONENT)
    }) == 0
}

/// `k! / (k - m)!`
#[inline]
fn falling(k: usize, m: usize) -> f64 {
    let mut f = 1.0;
    for i in (k + 1 - m)..=k {
        f *= i as f64;
    }
    f
}

/// One boundary condition: the `order`-th derivative at the start or the end equals `value`.
#[derive(Clone, Copy)]
struct Condition<const D: usize> {
    at_end: bool,
    order: usize,
    value: [f64; D],
}

const fn at_start<const D: usize>(order: usize, value: [f64; D]) -> Condition<D> {
    Condition {
        at_end: false,
        order,
        value,
    }
}

const fn at_end<const D: usize>(order: usize, value: [f64; D]) -> Condition<D> {
    Condition {
        at_end: true,
        order,
        value,
    }
}

impl<const D: usize, const C: usize> Polynomial<D, C> {
    /// A polynomial from coefficients of powers of `t` (`coefficients[k][axis]`).
    pub fn new(coefficients: [[f64; D]; C], duration: f64) -> Result<Self, TrajectoryError> {
        if !duration.is_finite() || duration < 0.0 {
            return Err(TrajectoryError::BadDuration);
        }
        if !all_finite(coefficients.as_flattened()) {
            for (index, c) in coefficients.iter().enumerate() {
                if !all_finite(c) {
                    return Err(TrajectoryError::NotFinite {
                        what: "coefficient",
                        index,
                    });
                }
            }
        }
        Ok(Self {
            coefficients,
            duration,
        })
    }

    /// Without checks, for coefficients computed here from validated input.
    pub(crate) const fn from_parts(coefficients: [[f64; D]; C], duration: f64) -> Self {
        Self {
            coefficients,
            duration,
        }
    }

    /// A constant (duration may be zero).
    pub fn constant(value: [f64; D], duration: f64) -> Result<Self, TrajectoryError> {
        let mut c = [[0.0; D]; C];
        if C > 0 {
            c[0] = value;
        }
        Self::new(c, duration)
    }

    /// Coefficients of powers of `t`, `[k][axis]`.
    pub const fn coefficients(&self) -> &[[f64; D]; C] {
        &self.coefficients
    }

    /// The degree, `C - 1`.
    pub const fn degree(&self) -> usize {
        C.saturating_sub(1)
    }

    /// The derivative as a polynomial with `C1 ≥ C - 1` coefficients (checked at compile time).
    pub fn derivative_polynomial<const C1: usize>(&self) -> Polynomial<D, C1> {
        const { assert!(C1 + 1 >= C, "derivative needs at least C - 1 coefficients") };
        let mut c = [[0.0; D]; C1];
        for k in 1..C {
            for axis in 0..D {
                c[k - 1][axis] = self.coefficients[k][axis] * k as f64;
            }
        }
        Polynomial {
            coefficients: c,
            duration: self.duration,
        }
    }

    /// The integral from 0 plus `constant`, with `C1 ≥ C + 1` coefficients (checked at compile
    /// time).
    pub fn integral<const C1: usize>(&self, constant: [f64; D]) -> Polynomial<D, C1> {
        const { assert!(C1 > C, "integral needs at least C + 1 coefficients") };
        let mut c = [[0.0; D]; C1];
        c[0] = constant;
        for k in 0..C {
            for axis in 0..D {
                c[k + 1][axis] = self.coefficients[k][axis] / (k + 1) as f64;
            }
        }
        Polynomial {
            coefficients: c,
            duration: self.duration,
        }
    }

    fn axis_coefficients(&self, axis: usize) -> [f64; C] {
        let mut c = [0.0; C];
        for (k, ck) in c.iter_mut().enumerate() {
            *ck = self.coefficients[k][axis];
        }
        c
    }

    /// Minimum and maximum of each axis on `[0, duration]` (endpoints and the real roots of the
    /// derivative).
    pub fn extrema(&self) -> Extrema<D> {
        let mut e = Extrema {
            min: [f64::INFINITY; D],
            max: [f64::NEG_INFINITY; D],
            time_of_min: [0.0; D],
            time_of_max: [0.0; D],
        };
        for axis in 0..D {
            let c = self.axis_coefficients(axis);
            let mut roots = [0.0; C];
            let n = roots_in(&derive(&c), 0.0, self.duration, &mut roots);
            let candidates = [0.0, self.duration]
                .into_iter()
                .chain(roots[..n].iter().copied());
            for t in candidates {
                let x = horner(&c, t);
                if x < e.min[axis] {
                    e.min[axis] = x;
                    e.time_of_min[axis] = t;
                }
                if x > e.max[axis] {
                    e.max[axis] = x;
                    e.time_of_max[axis] = t;
                }
            }
        }
        e
    }

    /// The largest `|p^(order)(t)|` of each axis on `[0, duration]`, exactly (via the roots of
    /// the next derivative). Used to check limits.
    pub fn max_abs_derivative(&self, order: usize) -> [f64; D] {
        let mut out = [0.0; D];
        for (axis, o) in out.iter_mut().enumerate() {
            let mut c = self.axis_coefficients(axis);
            for _ in 0..order {
                c = derive(&c);
            }
            let mut roots = [0.0; C];
            let n = roots_in(&derive(&c), 0.0, self.duration, &mut roots);
            let candidates = [0.0, self.duration]
                .into_iter()
                .chain(roots[..n].iter().copied());
            *o = candidates
                .map(|t| libm::fabs(horner(&c, t)))
                .fold(0.0, f64::max);
        }
        out
    }

    /// Solves `C` boundary conditions for a duration `T > 0`.
    fn from_conditions(
        duration: f64,
        conditions: &[Condition<D>],
    ) -> Result<Self, TrajectoryError> {
        if !duration.is_finite() || duration <= 0.0 {
            return Err(TrajectoryError::BadDuration);
        }
        for (index, cond) in conditions.iter().enumerate() {
            if cond.value.iter().any(|x| !x.is_finite()) {
                return Err(TrajectoryError::NotFinite {
                    what: "boundary condition",
                    index,
                });
            }
        }
        // Rows: conditions in s = t/T; a^(m)(s) = T^m p^(m)(t).
        let mut m = [[0.0; C]; C];
        let mut rhs = [[0.0; D]; C];
        for (row, cond) in conditions.iter().enumerate().take(C) {
            let scale = libm::pow(duration, cond.order as f64);
            if cond.at_end {
                for k in cond.order..C {
                    m[row][k] = falling(k, cond.order);
                }
            } else if cond.order < C {
                m[row][cond.order] = falling(cond.order, cond.order);
            }
            for axis in 0..D {
                rhs[row][axis] = cond.value[axis] * scale;
            }
        }
        // Gaussian elimination with partial pivoting.
        for col in 0..C {
            let pivot = (col..C)
                .max_by(|&a, &b| libm::fabs(m[a][col]).total_cmp(&libm::fabs(m[b][col])))
                .unwrap_or(col);
            if m[pivot][col] == 0.0 {
                return Err(TrajectoryError::Degenerate);
            }
            m.swap(col, pivot);
            rhs.swap(col, pivot);
            for row in (col + 1)..C {
                let f = m[row][col] / m[col][col];
                if f != 0.0 {
                    for k in col..C {
                        m[row][k] -= f * m[col][k];
                    }
                    for axis in 0..D {
                        rhs[row][axis] -= f * rhs[col][axis];
                    }
                }
            }
        }
        let mut a = [[0.0; D]; C];
        for row in (0..C).rev() {
            for axis in 0..D {
                let mut x = rhs[row][axis];
                for k in (row + 1)..C {
                    x -= m[row][k] * a[k][axis];
                }
                a[row][axis] = x / m[row][row];
            }
        }
        // a_k s^k = (a_k / T^k) t^k
        let mut scale = 1.0;
        for ak in a.iter_mut() {
            for x in ak.iter_mut() {
                *x /= scale;
            }
            scale *= duration;
        }
        Ok(Self {
            coefficients: a,
            duration,
        })
    }

    /// Scales the normalised shape `f(s)` (with `f(0) = 0`, `f(1) = 1`) between `x0` and `x1`
    /// over `duration`.
    fn from_shape(x0: [f64; D], x1: [f64; D], shape: &[f64; C], duration: f64) -> Self {
        let mut c = [[0.0; D]; C];
        if C > 0 {
            c[0] = x0;
        }
        if duration > 0.0 {
            let inv = 1.0 / duration;
            let mut scale = 1.0;
            for k in 1..C {
                scale *= inv;
                let f = shape[k] * scale;
                for axis in 0..D {
                    c[k][axis] = (x1[axis] - x0[axis]) * f;
                }
            }
        }
        Self {
            coefficients: c,
            duration,
        }
    }
}

/// Peaks of `|f'|`, `|f''|`, `|f'''|` on `[0, 1]` of the at-rest shapes (derived in closed form:
/// cubic 3s²-2s³; quintic 10s³-15s⁴+6s⁵; septic 35s⁴-84s⁵+70s⁶-20s⁷).
const CUBIC_PEAKS: [f64; 3] = [1.5, 6.0, 12.0];
const QUINTIC_PEAKS: [f64; 3] = [1.875, 5.773_502_691_896_258, 60.0];
const SEPTIC_PEAKS: [f64; 3] = [2.1875, 7.513_188_404_399_293, 52.5];
const CUBIC_SHAPE: [f64; 4] = [0.0, 0.0, 3.0, -2.0];
const QUINTIC_SHAPE: [f64; 6] = [0.0, 0.0, 0.0, 10.0, -15.0, 6.0];
const SEPTIC_SHAPE: [f64; 8] = [0.0, 0.0, 0.0, 0.0, 35.0, -84.0, 70.0, -20.0];

/// Shortest duration for which the at-rest shape with `peaks` respects every axis's limits
/// (all axes synchronised to the slowest). Infinite limits do not bound.
pub(crate) fn at_rest_duration<const D: usize>(
    x0: &[f64; D],
    x1: &[f64; D],
    limits: &Limits<D>,
    peaks: [f64; 3],
) -> Result<f64, TrajectoryError> {
    limits.validate(false)?;
    for axis in 0..D {
        if !x0[axis].is_finite() {
            return Err(TrajectoryError::NotFinite {
                what: "start of axis",
                index: axis,
            });
        }
        if !x1[axis].is_finite() {
            return Err(TrajectoryError::NotFinite {
                what: "goal of axis",
                index: axis,
            });
        }
    }
    // The root functions are monotonic, so take the maxima first and one root of each.
    let (mut tv, mut ta2, mut tj3) = (0.0f64, 0.0f64, 0.0f64);
    let mut moving = false;
    for axis in 0..D {
        let h = libm::fabs(x1[axis] - x0[axis]);
        moving |= h != 0.0;
        tv = tv.max(h * peaks[0] / limits.velocity[axis]);
        ta2 = ta2.max(h * peaks[1] / limits.acceleration[axis]);
        tj3 = tj3.max(h * peaks[2] / limits.jerk[axis]);
    }
    let duration = tv.max(libm::sqrt(ta2)).max(libm::cbrt(tj3));
    if moving && !(duration > 0.0 && duration.is_finite()) {
        return Err(TrajectoryError::Unreachable);
    }
    Ok(duration)
}

impl<const D: usize> Polynomial<D, 2> {
    /// Straight line from `x0` to `x1` in `duration`.
    pub fn linear(x0: [f64; D], x1: [f64; D], duration: f64) -> Result<Self, TrajectoryError> {
        Self::from_conditions(duration, &[at_start(0, x0), at_end(0, x1)])
    }
}

impl<const D: usize> Polynomial<D, 3> {
    /// Quadratic from positions and the start velocity.
    pub fn quadratic(
        x0: [f64; D],
        x1: [f64; D],
        v0: [f64; D],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_conditions(duration, &[at_start(0, x0), at_start(1, v0), at_end(0, x1)])
    }
}

impl<const D: usize> Polynomial<D, 4> {
    /// Cubic from positions and velocities at both ends (RL's `CubicFirst`).
    pub fn cubic(
        x0: [f64; D],
        x1: [f64; D],
        v0: [f64; D],
        v1: [f64; D],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_conditions(
            duration,
            &[
                at_start(0, x0),
                at_start(1, v0),
                at_end(0, x1),
                at_end(1, v1),
            ],
        )
    }

    /// Cubic from positions and accelerations at both ends (RL's `CubicSecond`).
    pub fn cubic_from_accelerations(
        x0: [f64; D],
        x1: [f64; D],
        a0: [f64; D],
        a1: [f64; D],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_conditions(
            duration,
            &[
                at_start(0, x0),
                at_start(2, a0),
                at_end(0, x1),
                at_end(2, a1),
            ],
        )
    }

    /// Shortest cubic from rest to rest within the limits, all axes synchronised.
    pub fn cubic_at_rest(
        x0: [f64; D],
        x1: [f64; D],
        limits: &Limits<D>,
    ) -> Result<Self, TrajectoryError> {
        at_rest_shape(x0, x1, limits)
    }
}

impl<const D: usize> Polynomial<D, 5> {
    /// Quartic from positions, velocities and the start acceleration.
    pub fn quartic(
        x0: [f64; D],
        x1: [f64; D],
        v0: [f64; D],
        v1: [f64; D],
        a0: [f64; D],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_conditions(
            duration,
            &[
                at_start(0, x0),
                at_start(1, v0),
                at_start(2, a0),
                at_end(0, x1),
                at_end(1, v1),
            ],
        )
    }
}

impl<const D: usize> Polynomial<D, 6> {
    /// Quintic from positions, velocities and accelerations at both ends.
    #[allow(clippy::too_many_arguments)]
    pub fn quintic(
        x0: [f64; D],
        x1: [f64; D],
        v0: [f64; D],
        v1: [f64; D],
        a0: [f64; D],
        a1: [f64; D],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_conditions(
            duration,
            &[
                at_start(0, x0),
                at_start(1, v0),
                at_start(2, a0),
                at_end(0, x1),
                at_end(1, v1),
                at_end(2, a1),
            ],
        )
    }

    /// Shortest quintic from rest to rest within the limits, all axes synchronised.
    pub fn quintic_at_rest(
        x0: [f64; D],
        x1: [f64; D],
        limits: &Limits<D>,
    ) -> Result<Self, TrajectoryError> {
        at_rest_shape(x0, x1, limits)
    }
}

impl<const D: usize> Polynomial<D, 7> {
    /// Sextic from positions, velocities, accelerations and the start jerk.
    #[allow(clippy::too_many_arguments)]
    pub fn sextic(
        x0: [f64; D],
        x1: [f64; D],
        v0: [f64; D],
        v1: [f64; D],
        a0: [f64; D],
        a1: [f64; D],
        j0: [f64; D],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_conditions(
            duration,
            &[
                at_start(0, x0),
                at_start(1, v0),
                at_start(2, a0),
                at_start(3, j0),
                at_end(0, x1),
                at_end(1, v1),
                at_end(2, a1),
            ],
        )
    }
}

impl<const D: usize> Polynomial<D, 8> {
    /// Septic from positions, velocities, accelerations and jerks at both ends.
    #[allow(clippy::too_many_arguments)]
    pub fn septic(
        x0: [f64; D],
        x1: [f64; D],
        v0: [f64; D],
        v1: [f64; D],
        a0: [f64; D],
        a1: [f64; D],
        j0: [f64; D],
        j1: [f64; D],
        duration: f64,
    ) -> Result<Self, TrajectoryError> {
        Self::from_conditions(
            duration,
            &[
                at_start(0, x0),
                at_start(1, v0),
                at_start(2, a0),
                at_start(3, j0),
                at_end(0, x1),
                at_end(1, v1),
                at_end(2, a1),
                at_end(3, j1),
            ],
        )
    }

    /// Shortest septic from rest to rest (zero velocity, acceleration and jerk at both ends)
    /// within the limits, all axes synchronised.
    pub fn septic_at_rest(
        x0: [f64; D],
        x1: [f64; D],
        limits: &Limits<D>,
    ) -> Result<Self, TrajectoryError> {
        at_rest_shape(x0, x1, limits)
    }
}

/// The shortest polynomial with `C` coefficients from rest to rest within the limits, all axes
/// synchronised: the cubic, quintic and septic at-rest constructors, and the segments of
/// [`crate::traj::spline::at_rest_through`]. Other degrees are [`TrajectoryError::Degenerate`].
pub(crate) fn at_rest_shape<const D: usize, const C: usize>(
    x0: [f64; D],
    x1: [f64; D],
    limits: &Limits<D>,
) -> Result<Polynomial<D, C>, TrajectoryError> {
    let (shape, peaks): (&[f64], [f64; 3]) = match C {
        4 => (&CUBIC_SHAPE, CUBIC_PEAKS),
        6 => (&QUINTIC_SHAPE, QUINTIC_PEAKS),
        8 => (&SEPTIC_SHAPE, SEPTIC_PEAKS),
        _ => return Err(TrajectoryError::Degenerate),
    };
    let mut s = [0.0; C];
    s.copy_from_slice(&shape[..C]);
    let t = at_rest_duration(&x0, &x1, limits, peaks)?;
    Ok(Polynomial::from_shape(x0, x1, &s, t))
}

impl<const D: usize, const C: usize> Trajectory<D> for Polynomial<D, C> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        let t = clamp_time(t, self.duration);
        let mut out = [0.0; D];
        if order >= C {
            return out;
        }
        for k in (order..C).rev() {
            let f = falling(k, order);
            for axis in 0..D {
                out[axis] = out[axis] * t + self.coefficients[k][axis] * f;
            }
        }
        out
    }

    #[inline]
    fn sample(&self, t: f64) -> Sample<D> {
        let t = clamp_time(t, self.duration);
        // Powers of t shared by all axes, then one independent dot product per quantity and
        // axis (no Horner dependency chain; the loops vectorise over axes and skip the terms
        // a derivative removes).
        let mut pow = [1.0; C];
        for k in 1..C {
            pow[k] = pow[k - 1] * t;
        }
        Sample {
            position: self.derivative_from_powers::<0>(&pow),
            velocity: self.derivative_from_powers::<1>(&pow),
            acceleration: self.derivative_from_powers::<2>(&pow),
            jerk: self.derivative_from_powers::<3>(&pow),
        }
    }
}

impl<const D: usize, const C: usize> Polynomial<D, C> {
    /// The `M`-th derivative of each axis, `Σ_{k ≥ M} k!/(k-M)! c_k t^(k-M)`, from the powers
    /// `pow[k] = t^k`: one dot product per axis (`M` is a constant, so the weights fold).
    #[inline(always)]
    fn derivative_from_powers<const M: usize>(&self, pow: &[f64; C]) -> [f64; D] {
        let mut out = [0.0; D];
        for k in M..C {
            let w = falling(k, M) * pow[k - M];
            for axis in 0..D {
                out[axis] += self.coefficients[k][axis] * w;
            }
        }
        out
    }
}
