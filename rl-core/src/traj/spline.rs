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
    let n = points.len();
    let last = n - 1;
    // Row i: sub[i] M_{i-1} + diag[i] M_i + sup[i] M_{i+1} = rhs[i]. The forward sweep keeps
    // c'_i and d'_i for i < last (at most MAX of them); row `last` is handled in locals.
    let mut c_prime = [0.0; MAX];
    let mut d_prime = [[0.0; D]; MAX];
    let h = |i: usize| times[i + 1] - times[i];
    let mut slopes = [[0.0; D]; MAX];
    for i in 0..last {
        let inv = 1.0 / h(i);
        for axis in 0..D {
            slopes[i][axis] = (points[i + 1][axis] - points[i][axis]) * inv;
        }
    }
    let slope = |i: usize, axis: usize| slopes[i][axis];
    let row = |i: usize| -> (f64, f64, f64, [f64; D]) {
        let mut rhs = [0.0; D];
        if i == 0 {
            match ends {
                Ends::Natural => (0.0, 1.0, 0.0, rhs),
                Ends::Clamped(v0, _) => {
                    for (axis, r) in rhs.iter_mut().enumerate() {
                        *r = 6.0 * (slope(0, axis) - v0[axis]);
                    }
                    (0.0, 2.0 * h(0), h(0), rhs)
                }
            }
        } else if i == last {
            match ends {
                Ends::Natural => (0.0, 1.0, 0.0, rhs),
                Ends::Clamped(_, v1) => {
                    for (axis, r) in rhs.iter_mut().enumerate() {
                        *r = 6.0 * (v1[axis] - slope(i - 1, axis));
                    }
                    (h(i - 1), 2.0 * h(i - 1), 0.0, rhs)
                }
            }
        } else {
            for (axis, r) in rhs.iter_mut().enumerate() {
                *r = 6.0 * (slope(i, axis) - slope(i - 1, axis));
            }
            (h(i - 1), 2.0 * (h(i - 1) + h(i)), h(i), rhs)
        }
    };
    let mut prev_c = 0.0;
    let mut prev_d = [0.0; D];
    let mut m_last = [0.0; D];
    for i in 0..n {
        let (sub, diag, sup, rhs) = row(i);
        let denom = diag - sub * prev_c;
        if denom == 0.0 || !denom.is_finite() {
            return Err(TrajectoryError::Degenerate);
        }
        let inv = 1.0 / denom;
        let c = sup * inv;
        let mut d = [0.0; D];
        for axis in 0..D {
            d[axis] = (rhs[axis] - sub * prev_d[axis]) * inv;
        }
        if i < last {
            c_prime[i] = c;
            d_prime[i] = d;
        } else {
            m_last = d;
        }
        prev_c = c;
        prev_d = d;
    }
    // Back substitution into d_prime: M_i = d'_i - c'_i M_{i+1}.
    let mut next = m_last;
    for i in (0..last).rev() {
        for axis in 0..D {
            d_prime[i][axis] -= c_prime[i] * next[axis];
        }
        next = d_prime[i];
    }
    let mut spline = Piecewise::new();
    for i in 0..last {
        let hi = h(i);
        let m0 = d_prime[i];
        let m1 = if i + 1 < last { d_prime[i + 1] } else { m_last };
        let mut c = [[0.0; D]; 4];
        let inv6h = 1.0 / (6.0 * hi);
        for axis in 0..D {
            c[0][axis] = points[i][axis];
            c[1][axis] = slope(i, axis) - hi * (2.0 * m0[axis] + m1[axis]) * (1.0 / 6.0);
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
