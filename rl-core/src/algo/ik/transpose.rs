//! Jacobian-transpose step: `dq = α Jᵀ dx` with `α = ⟨dx, J Jᵀ dx⟩ / |J Jᵀ dx|²`.
//!
//! The steepest-descent direction of `|dx|²/2`, scaled by RL's `α` (the step whose
//! linearised error `dx − α J Jᵀ dx` is smallest; Buss, "Introduction to inverse kinematics
//! with Jacobian transpose, pseudoinverse and damped least squares methods", 2004, eq. 7).
//! No matrix is inverted, so it cannot blow up at a singularity, but it converges linearly
//! and slowly on badly conditioned goals: give it more iterations per attempt.
//! Does not allocate.

use super::MAX_ROWS;

/// Writes the step into `dq[..n]`. Returns `false` if `J Jᵀ dx = 0` (a stationary point of
/// the error: nothing to step along) or the step is not finite.
pub(super) fn transpose_step<const N: usize>(
    jac: &[[f64; N]; MAX_ROWS],
    m: usize,
    n: usize,
    dx: &[f64],
    h: &mut [f64; MAX_ROWS],
    dq: &mut [f64],
) -> bool {
    for (k, d) in dq.iter_mut().enumerate().take(n) {
        *d = (0..m).map(|r| jac[r][k] * dx[r]).sum();
    }
    for (r, hr) in h.iter_mut().enumerate().take(m) {
        *hr = jac[r][..n].iter().zip(&dq[..n]).map(|(a, b)| a * b).sum();
    }
    let hh: f64 = h[..m].iter().map(|x| x * x).sum();
    let dh: f64 = h[..m].iter().zip(&dx[..m]).map(|(a, b)| a * b).sum();
    if hh.is_nan() || hh <= 0.0 {
        return false;
    }
    let alpha = dh / hh;
    for d in dq[..n].iter_mut() {
        *d *= alpha;
    }
    dq[..n].iter().all(|d| d.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_for_an_orthogonal_jacobian() {
        // J = 2·I: α = 1/4 and one step lands exactly.
        let mut j = [[0.0; 2]; MAX_ROWS];
        j[0] = [2.0, 0.0];
        j[1] = [0.0, 2.0];
        let (mut h, mut dq) = ([0.0; MAX_ROWS], [0.0; 2]);
        assert!(transpose_step(&j, 2, 2, &[1.0, -0.5], &mut h, &mut dq));
        assert!((dq[0] - 0.5).abs() < 1e-15 && (dq[1] + 0.25).abs() < 1e-15);
        // A zero Jacobian gives no direction.
        let z = [[0.0; 2]; MAX_ROWS];
        assert!(!transpose_step(&z, 2, 2, &[1.0, 0.0], &mut h, &mut dq));
    }
}
