//! Pseudo-inverse step through the SVD: `dq = Σᵢ vᵢ f(σᵢ) uᵢᵀ dx`.
//!
//! `f(σ) = 1/σ` for singular values at or above the threshold `σ₀` (the exact Moore–Penrose
//! pseudo-inverse there) and `f(σ) = σ/σ₀²` below it: continuous at `σ₀` and falling to zero
//! with `σ`, so directions near a singularity are damped, and directions exactly singular
//! are dropped (truncated), instead of blowing the step up. RL's `svd` variant applies no
//! damping until `σ_min < 1e-9`. With the row-orthogonal form `J = U B` of
//! [`super::jacobi_svd`], `vᵢ/σᵢ = bᵢ/σᵢ²`, so `dq = Σᵢ bᵢ (uᵢ·dx) / max(σᵢ, σ₀)²`.
//! Does not allocate.

use super::MAX_ROWS;
use super::jacobi_svd::orthogonalize_rows;

/// Writes the step into `dq[..n]`; `jac` (`m × n`) is overwritten by `B`. Returns `false` if
/// the SVD did not converge or the step is not finite.
pub(super) fn pseudo_inverse_step<const N: usize>(
    jac: &mut [[f64; N]; MAX_ROWS],
    m: usize,
    n: usize,
    dx: &[f64],
    threshold: f64,
    u: &mut [[f64; MAX_ROWS]; MAX_ROWS],
    dq: &mut [f64],
) -> bool {
    if !orthogonalize_rows(jac, m, n, u) {
        return false;
    }
    dq[..n].fill(0.0);
    for i in 0..m {
        let sigma2: f64 = jac[i][..n].iter().map(|x| x * x).sum();
        let sigma = libm::sqrt(sigma2);
        if sigma == 0.0 {
            continue;
        }
        let floor = sigma.max(threshold);
        let coeff: f64 = (0..m).map(|r| u[r][i] * dx[r]).sum::<f64>() / (floor * floor);
        for (d, b) in dq[..n].iter_mut().zip(&jac[i][..n]) {
            *d += coeff * b;
        }
    }
    dq[..n].iter().all(|d| d.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverts_a_well_conditioned_square_matrix() {
        let mut j = [[0.0; 3]; MAX_ROWS];
        j[0] = [2.0, 1.0, 0.0];
        j[1] = [0.0, 1.0, -1.0];
        j[2] = [1.0, 0.0, 3.0];
        let original = j;
        let dx = [1.0, -2.0, 0.5];
        let (mut u, mut dq) = ([[0.0; MAX_ROWS]; MAX_ROWS], [0.0; 3]);
        assert!(pseudo_inverse_step(
            &mut j, 3, 3, &dx, 1e-6, &mut u, &mut dq
        ));
        for r in 0..3 {
            let back: f64 = (0..3).map(|k| original[r][k] * dq[k]).sum();
            assert!((back - dx[r]).abs() < 1e-13);
        }
    }

    #[test]
    fn drops_a_singular_direction() {
        // Rank 1: both rows along (1, 1); dx has a component the matrix cannot produce.
        let mut j = [[0.0; 2]; MAX_ROWS];
        j[0] = [1.0, 1.0];
        j[1] = [1.0, 1.0];
        let (mut u, mut dq) = ([[0.0; MAX_ROWS]; MAX_ROWS], [0.0; 2]);
        assert!(pseudo_inverse_step(
            &mut j,
            2,
            2,
            &[1.0, 0.0],
            1e-6,
            &mut u,
            &mut dq
        ));
        // Minimum-norm least-squares solution: J⁺ dx = (0.25, 0.25).
        assert!(
            (dq[0] - 0.25).abs() < 1e-14 && (dq[1] - 0.25).abs() < 1e-14,
            "{dq:?}"
        );
    }
}
