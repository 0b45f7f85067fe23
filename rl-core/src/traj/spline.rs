//! Splines through waypoints: natural and clamped cubic splines (times given), sequences of
//! at-rest polynomials, linear segments with blends, 4-1-4 / 6-1-6 and jerk-limited moves.
//!
//! Waypoints are `&[[f64; D]]`; times (where a spline needs them) are `&[f64]`, strictly
//! increasing, and the trajectory's time 0 is `times[0]`. A spline of `n` waypoints needs
//! capacity for its segments (`n - 1` for cubic splines and at-rest sequences).

use super::{
    Limits, Piecewise, Polynomial, TrajectoryError, check_finite_points, check_times,
    polynomial::at_rest_shape,
};

pub use super::blend::{
    four_one_four_at_rest, linear_with_blends, six_one_six_at_rest, smooth_trapezoid_at_rest,
};
pub use super::jerk_limited::jerk_limited_through;

/// Which end conditions a cubic spline has.
#[derive(Clone, Copy)]
enum Ends<const D: usize> {
    Natural,
    Clamped([f64; D], [f64; D]),
}

fn check_waypoints<const D: usize>(
    times: &[f64],
    points: &[[f64; D]],
    capacity: usize,
) -> Result<(), TrajectoryError> {
    if times.len() != points.len() {
        return Err(TrajectoryError::TooFewWaypoints {
            required: points.len(),
            given: times.len(),
        });
    }
    if points.len() < 2 {
        return Err(TrajectoryError::TooFewWaypoints {
            required: 2,
            given: points.len(),
        });
    }
    if points.len() - 1 > capacity {
        return Err(TrajectoryError::Capacity {
            capacity,
            requested: points.len() - 1,
        });
    }
    check_times(times)?;
    check_finite_points(points)
}

/// Natural cubic spline (zero acceleration at both ends) through `points` at `times`: C² with
/// continuous acceleration at every interior waypoint.
pub fn natural_cubic<const D: usize, const MAX: usize>(
    times: &[f64],
    points: &[[f64; D]],
) -> Result<Piecewise<Polynomial<D, 4>, MAX>, TrajectoryError> {
    cubic(times, points, Ends::Natural)
}

/// Clamped cubic spline through `points` at `times` with velocities `v0` at the start and `v1`
/// at the end: C² at every interior waypoint.
pub fn clamped_cubic<const D: usize, const MAX: usize>(
    times: &[f64],
    points: &[[f64; D]],
    v0: [f64; D],
    v1: [f64; D],
) -> Result<Piecewise<Polynomial<D, 4>, MAX>, TrajectoryError> {
    if v0.iter().chain(v1.iter()).any(|v| !v.is_finite()) {
        return Err(TrajectoryError::NotFinite {
            what: "end velocity",
            index: 0,
        });
    }
    cubic(times, points, Ends::Clamped(v0, v1))
}

/// Solves for the second derivatives `M_i` (tridiagonal, Thomas algorithm) and builds the
/// segments `p = y_i + b τ + M_i/2 τ² + (M_{i+1} - M_i)/(6h) τ³`.
fn cubic<const D: usize, const MAX: usize>(
    times: &[f64],
    points: &[[f64; D]],
    ends: Ends<D>,
) -> Result<Piecewise<Polynomial<D, 4>, MAX>, TrajectoryError> {
    check_waypoints(times, points, MAX)?;
    let last = points.len() - 1;
    // Interval lengths and chord slopes (`last ≤ MAX` of each).
    let mut h = [0.0; MAX];
    let mut slopes = [[0.0; D]; MAX];
    for ((h, slope), (t, p)) in h
        .iter_mut()
        .zip(slopes.iter_mut())
        .zip(times.windows(2).zip(points.windows(2)))
    {
        *h = t[1] - t[0];
        let inv = 1.0 / *h;
        for axis in 0..D {
            slope[axis] = (p[1][axis] - p[0][axis]) * inv;
        }
    }
    // Row i: sub_i M_{i-1} + diag_i M_i + sup_i M_{i+1} = rhs_i. Forward sweep: c'_i and d'_i
    // for the rows before `last` go to `c_prime` and `m` (the back substitution turns d'_i
    // into M_i); row `last` is solved in `m_last`.
    let mut c_prime = [0.0; MAX];
    let mut m = [[0.0; D]; MAX];
    // Row 0: natural M_0 = 0, or clamped 2h_0 M_0 + h_0 M_1 = 6 (s_0 - v0).
    let mut prev_c = 0.0;
    let mut prev_d = [0.0; D];
    if let Ends::Clamped(v0, _) = ends {
        let inv = 1.0 / (2.0 * h[0]);
        prev_c = h[0] * inv;
        for axis in 0..D {
            prev_d[axis] = 6.0 * (slopes[0][axis] - v0[axis]) * inv;
        }
    }
    c_prime[0] = prev_c;
    m[0] = prev_d;
    // Interior rows: h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1} = 6 (s_i - s_{i-1}).
    for i in 1..last {
        let (sub, sup) = (h[i - 1], h[i]);
        let denom = 2.0 * (sub + sup) - sub * prev_c;
        if denom == 0.0 || !denom.is_finite() {
            return Err(TrajectoryError::Degenerate);
        }
        let inv = 1.0 / denom;
        let mut d = [0.0; D];
        for axis in 0..D {
            let rhs = 6.0 * (slopes[i][axis] - slopes[i - 1][axis]);
            d[axis] = (rhs - sub * prev_d[axis]) * inv;
        }
        prev_c = sup * inv;
        prev_d = d;
        c_prime[i] = prev_c;
        m[i] = d;
    }
    // Row `last`: natural M_last = 0, or clamped h M_{last-1} + 2h M_last = 6 (v1 - s_{last-1}).
    let mut m_last = [0.0; D];
    if let Ends::Clamped(_, v1) = ends {
        let sub = h[last - 1];
        let denom = 2.0 * sub - sub * prev_c;
        if denom == 0.0 || !denom.is_finite() {
            return Err(TrajectoryError::Degenerate);
        }
        let inv = 1.0 / denom;
        for axis in 0..D {
            let rhs = 6.0 * (v1[axis] - slopes[last - 1][axis]);
            m_last[axis] = (rhs - sub * prev_d[axis]) * inv;
        }
    }
    // Back substitution, M_i = d'_i - c'_i M_{i+1}, and the segments from the last one back.
    let mut next = m_last;
    for i in (0..last).rev() {
        for axis in 0..D {
            m[i][axis] -= c_prime[i] * next[axis];
        }
        next = m[i];
    }
    let mut spline = Piecewise::new();
    for i in 0..last {
        let hi = h[i];
        let m0 = m[i];
        let m1 = if i + 1 < last { m[i + 1] } else { m_last };
        let mut c = [[0.0; D]; 4];
        let inv6h = 1.0 / (6.0 * hi);
        for axis in 0..D {
            c[0][axis] = points[i][axis];
            c[1][axis] = slopes[i][axis] - hi * (2.0 * m0[axis] + m1[axis]) * (1.0 / 6.0);
            c[2][axis] = 0.5 * m0[axis];
            c[3][axis] = (m1[axis] - m0[axis]) * inv6h;
        }
        // Finite: from validated times and points.
        spline.push(Polynomial::from_parts(c, hi))?;
    }
    Ok(spline)
}

/// Rest-to-rest polynomial moves through `points` in order, each as short as the limits allow
/// with all axes synchronised: cubic for `C = 4`, quintic for `C = 6`, septic for `C = 8`
/// (other `C` give [`TrajectoryError::Degenerate`]). No times needed.
pub fn at_rest_through<const D: usize, const C: usize, const MAX: usize>(
    points: &[[f64; D]],
    limits: &Limits<D>,
) -> Result<Piecewise<Polynomial<D, C>, MAX>, TrajectoryError> {
    if points.len() < 2 {
        return Err(TrajectoryError::TooFewWaypoints {
            required: 2,
            given: points.len(),
        });
    }
    if points.len() - 1 > MAX {
        return Err(TrajectoryError::Capacity {
            capacity: MAX,
            requested: points.len() - 1,
        });
    }
    check_finite_points(points)?;
    let mut spline = Piecewise::new();
    for pair in points.windows(2) {
        spline.push(at_rest_shape::<D, C>(pair[0], pair[1], limits)?)?;
    }
    Ok(spline)
}
