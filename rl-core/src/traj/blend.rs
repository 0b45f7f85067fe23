//! Linear segments joined by polynomial blends, and the at-rest moves built from the same blend
//! shapes: trapezoidal velocity (parabolic), 4-1-4 (quartic-linear-quartic) and 6-1-6
//! (sextic-linear-sextic).
//!
//! During a blend of length `tb` the velocity goes from `va` to `vb` as `va + (vb - va) σ(τ/tb)`
//! with `σ(s) = s` (parabolic, C¹), `3s² - 2s³` (quartic, C²) or `10s³ - 15s⁴ + 6s⁵` (sextic,
//! C³). Every `σ` has mean ½, so the blend covers `tb (va + vb) / 2` whatever its shape and one
//! geometry serves all three.

use super::{
    Limits, Piecewise, Polynomial, TrajectoryError, check_finite_points, check_times,
    error::LimitKind,
};

/// The velocity shape of a blend.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlendShape {
    /// Constant acceleration (position parabola): velocity continuous.
    Parabolic,
    /// Cubic velocity (position quartic): acceleration continuous.
    Quartic,
    /// Quintic velocity (position sextic): jerk continuous.
    Sextic,
}

impl BlendShape {
    /// `Σ(s) = ∫₀ˢ σ`, coefficients of `s^k`.
    const fn integral(self) -> [f64; 7] {
        match self {
            Self::Parabolic => [0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0],
            Self::Quartic => [0.0, 0.0, 0.0, 1.0, -0.5, 0.0, 0.0],
            Self::Sextic => [0.0, 0.0, 0.0, 0.0, 2.5, -3.0, 1.0],
        }
    }

    /// `max σ'` on `[0, 1]`: peak acceleration is `|vb - va| / tb` times this.
    const fn peak_slope(self) -> f64 {
        match self {
            Self::Parabolic => 1.0,
            Self::Quartic => 1.5,
            Self::Sextic => 1.875,
        }
    }
}

/// How long blends are.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BlendTime {
    /// The same blend duration in seconds at every waypoint.
    Seconds(f64),
    /// A fraction `f ∈ (0, 1]` of the segments next to each waypoint: an interior blend lasts
    /// `f` times the shorter neighbouring segment (half on each side), an end blend `f/2` times
    /// its segment, so no segment gives more than the fraction `f` to blends and any `f ≤ 1`
    /// fits.
    Fraction(f64),
}

/// Blend polynomial starting at `p0` with velocity `va`, reaching `vb` after `tb`.
fn blend<const D: usize>(
    p0: [f64; D],
    va: [f64; D],
    vb: [f64; D],
    tb: f64,
    shape: BlendShape,
) -> Result<Polynomial<D, 7>, TrajectoryError> {
    let g = shape.integral();
    let mut c = [[0.0; D]; 7];
    c[0] = p0;
    c[1] = va;
    let mut scale = 1.0; // tb / tb^k
    for (k, gk) in g.iter().enumerate().skip(1) {
        if k > 1 {
            scale /= tb;
        }
        for axis in 0..D {
            c[k][axis] += (vb[axis] - va[axis]) * gk * scale;
        }
    }
    Polynomial::new(c, tb)
}

/// Constant velocity `v` from `p0` for `duration`.
fn line<const D: usize>(
    p0: [f64; D],
    v: [f64; D],
    duration: f64,
) -> Result<Polynomial<D, 7>, TrajectoryError> {
    let mut c = [[0.0; D]; 7];
    c[0] = p0;
    c[1] = v;
    Polynomial::new(c, duration)
}

fn advance<const D: usize>(p: &mut [f64; D], va: &[f64; D], vb: &[f64; D], duration: f64) {
    for axis in 0..D {
        p[axis] += 0.5 * (va[axis] + vb[axis]) * duration;
    }
}

/// Linear segments through `points` at `times` with blends at every waypoint, starting and
/// ending at rest (Craig's construction): the first blend starts at `points[0]` at `times[0]`,
/// the last ends at the last waypoint at its time, and the lines pass through the interior
/// waypoints at their times while the blends round them off (as RL's `LinearParabolic`).
///
/// Needs capacity for `2n - 1` segments.
pub fn linear_with_blends<const D: usize, const MAX: usize>(
    times: &[f64],
    points: &[[f64; D]],
    shape: BlendShape,
    blend_time: BlendTime,
) -> Result<Piecewise<Polynomial<D, 7>, MAX>, TrajectoryError> {
    let n = points.len();
    if times.len() != n {
        return Err(TrajectoryError::TooFewWaypoints {
            required: n,
            given: times.len(),
        });
    }
    if n < 2 {
        return Err(TrajectoryError::TooFewWaypoints {
            required: 2,
            given: n,
        });
    }
    if 2 * n - 1 > MAX {
        return Err(TrajectoryError::Capacity {
            capacity: MAX,
            requested: 2 * n - 1,
        });
    }
    check_times(times)?;
    check_finite_points(points)?;
    let tb = |i: usize| -> f64 {
        match blend_time {
            BlendTime::Seconds(s) => s,
            BlendTime::Fraction(f) => {
                let left = if i > 0 {
                    times[i] - times[i - 1]
                } else {
                    f64::INFINITY
                };
                let right = if i + 1 < n {
                    times[i + 1] - times[i]
                } else {
                    f64::INFINITY
                };
                // End blends lie wholly inside their segment: half as long, same share.
                let share = if i == 0 || i == n - 1 { 0.5 * f } else { f };
                share * left.min(right)
            }
        }
    };
    for i in 0..n {
        let b = tb(i);
        if !(b > 0.0 && b.is_finite()) {
            return Err(TrajectoryError::BlendTooLong { waypoint: i });
        }
    }
    // Room each blend takes from the segments next to it: all of an end blend, half of others.
    let taken = |i: usize| {
        if i == 0 || i == n - 1 {
            tb(i)
        } else {
            0.5 * tb(i)
        }
    };
    for k in 0..n - 1 {
        let room = times[k + 1] - times[k] - taken(k) - taken(k + 1);
        if room < -1e-12 * (times[k + 1] - times[k]) {
            return Err(TrajectoryError::BlendTooLong { waypoint: k + 1 });
        }
    }
    let velocity = |k: usize| -> [f64; D] {
        let mut span = times[k + 1] - times[k];
        if k == 0 {
            span -= 0.5 * tb(0);
        }
        if k == n - 2 {
            span -= 0.5 * tb(n - 1);
        }
        let mut v = [0.0; D];
        for (axis, vi) in v.iter_mut().enumerate() {
            *vi = (points[k + 1][axis] - points[k][axis]) / span;
        }
        v
    };
    let mut spline = Piecewise::new();
    let mut p = points[0];
    let mut v_prev = [0.0; D];
    let mut t = times[0];
    for i in 0..n {
        let (b, blend_start) = if i == 0 {
            (tb(0), times[0])
        } else if i == n - 1 {
            (tb(i), times[i] - tb(i))
        } else {
            (tb(i), times[i] - 0.5 * tb(i))
        };
        // Line up to the blend.
        let run = blend_start - t;
        if run > 0.0 {
            spline.push(line(p, v_prev, run)?)?;
            for axis in 0..D {
                p[axis] += v_prev[axis] * run;
            }
        }
        let v_next = if i < n - 1 { velocity(i) } else { [0.0; D] };
        spline.push(blend(p, v_prev, v_next, b, shape)?)?;
        advance(&mut p, &v_prev, &v_next, b);
        v_prev = v_next;
        t = blend_start + b;
    }
    Ok(spline)
}

/// Validates velocity and acceleration limits (must be finite and positive).
fn check_va<const D: usize>(limits: &Limits<D>) -> Result<(), TrajectoryError> {
    for axis in 0..D {
        if !(limits.velocity[axis] > 0.0 && limits.velocity[axis].is_finite()) {
            return Err(TrajectoryError::BadLimit {
                axis,
                kind: LimitKind::Velocity,
            });
        }
        if !(limits.acceleration[axis] > 0.0 && limits.acceleration[axis].is_finite()) {
            return Err(TrajectoryError::BadLimit {
                axis,
                kind: LimitKind::Acceleration,
            });
        }
    }
    Ok(())
}

/// Rest-to-rest moves through `points` in order, each an acceleration blend, a constant-velocity
/// run and a deceleration blend of the given shape (parabolic: trapezoidal velocity; quartic:
/// 4-1-4; sextic: 6-1-6), as short as the velocity and acceleration limits allow with all axes
/// synchronised (they share the phase times). Jerk limits are not used.
///
/// With `A = max_i k hᵢ/aᵢ` and `V = max_i hᵢ/vᵢ` (`k` the blend's peak slope), the shortest
/// duration is `2√A` when `V ≤ √A` (no cruise) and `V + A/V` otherwise. Needs capacity for
/// three segments per move.
pub fn smooth_trapezoid_at_rest<const D: usize, const MAX: usize>(
    points: &[[f64; D]],
    limits: &Limits<D>,
    shape: BlendShape,
) -> Result<Piecewise<Polynomial<D, 7>, MAX>, TrajectoryError> {
    check_va(limits)?;
    if points.len() < 2 {
        return Err(TrajectoryError::TooFewWaypoints {
            required: 2,
            given: points.len(),
        });
    }
    let moves = points.len() - 1;
    if 3 * moves > MAX {
        return Err(TrajectoryError::Capacity {
            capacity: MAX,
            requested: 3 * moves,
        });
    }
    check_finite_points(points)?;
    let k = shape.peak_slope();
    let mut spline = Piecewise::new();
    for pair in points.windows(2) {
        let (x0, x1) = (pair[0], pair[1]);
        let mut a_term: f64 = 0.0;
        let mut v_term: f64 = 0.0;
        for axis in 0..D {
            let h = libm::fabs(x1[axis] - x0[axis]);
            a_term = a_term.max(k * h / limits.acceleration[axis]);
            v_term = v_term.max(h / limits.velocity[axis]);
        }
        if a_term == 0.0 {
            spline.push(line(x0, [0.0; D], 0.0)?)?;
            continue;
        }
        let root = libm::sqrt(a_term);
        let (total, ta) = if v_term <= root {
            (2.0 * root, root)
        } else {
            (v_term + a_term / v_term, a_term / v_term)
        };
        let cruise = (total - 2.0 * ta).max(0.0);
        let mut v = [0.0; D];
        for axis in 0..D {
            v[axis] = (x1[axis] - x0[axis]) / (total - ta);
        }
        let mut p = x0;
        spline.push(blend(p, [0.0; D], v, ta, shape)?)?;
        advance(&mut p, &[0.0; D], &v, ta);
        spline.push(line(p, v, cruise)?)?;
        for axis in 0..D {
            p[axis] += v[axis] * cruise;
        }
        spline.push(blend(p, v, [0.0; D], ta, shape)?)?;
    }
    Ok(spline)
}

/// 4-1-4 moves at rest: quartic acceleration, linear, quartic deceleration.
pub fn four_one_four_at_rest<const D: usize, const MAX: usize>(
    points: &[[f64; D]],
    limits: &Limits<D>,
) -> Result<Piecewise<Polynomial<D, 7>, MAX>, TrajectoryError> {
    smooth_trapezoid_at_rest(points, limits, BlendShape::Quartic)
}

/// 6-1-6 moves at rest: sextic acceleration, linear, sextic deceleration.
pub fn six_one_six_at_rest<const D: usize, const MAX: usize>(
    points: &[[f64; D]],
    limits: &Limits<D>,
) -> Result<Piecewise<Polynomial<D, 7>, MAX>, TrajectoryError> {
    smooth_trapezoid_at_rest(points, limits, BlendShape::Sextic)
}
