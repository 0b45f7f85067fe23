//! Eigenvalues of a symmetric 3×3 matrix (the principal moments of an inertia tensor).
//!
//! Cyclic Jacobi rotations (Golub & Van Loan, *Matrix Computations*, §8.5): each rotation zeroes
//! one off-diagonal entry; a few sweeps bring them below rounding. Accurate to a few ulps of the
//! largest eigenvalue also for repeated eigenvalues (where the closed-form trigonometric
//! solution loses half the digits). No allocation.

use glam::DMat3;

/// The eigenvalues of the symmetric `a` (its upper triangle is read), ascending.
pub fn symmetric_eigenvalues(a: &DMat3) -> [f64; 3] {
    let mut m = [
        [a.x_axis.x, a.y_axis.x, a.z_axis.x],
        [a.y_axis.x, a.y_axis.y, a.z_axis.y],
        [a.z_axis.x, a.z_axis.y, a.z_axis.z],
    ];
    for _ in 0..32 {
        let off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
        let diag = m[0][0] * m[0][0] + m[1][1] * m[1][1] + m[2][2] * m[2][2];
        if off <= 1e-36 * diag || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if m[p][q] == 0.0 {
                continue;
            }
            // The rotation in the (p, q) plane that zeroes m[p][q].
            let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
            let t = theta.signum() / (theta.abs() + libm::sqrt(theta * theta + 1.0));
            let c = 1.0 / libm::sqrt(t * t + 1.0);
            let s = t * c;
            for k in 0..3 {
                let (mkp, mkq) = (m[k][p], m[k][q]);
                m[k][p] = c * mkp - s * mkq;
                m[k][q] = s * mkp + c * mkq;
            }
            for k in 0..3 {
                let (mpk, mqk) = (m[p][k], m[q][k]);
                m[p][k] = c * mpk - s * mqk;
                m[q][k] = s * mpk + c * mqk;
            }
        }
    }
    let mut out = [m[0][0], m[1][1], m[2][2]];
    out.sort_unstable_by(f64::total_cmp); // core (no_std): `sort_by` needs alloc
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DQuat, DVec3};

    #[test]
    fn rotated_diagonal_matrices_give_their_diagonal_back() {
        let r = DMat3::from_quat(DQuat::from_scaled_axis(DVec3::new(0.3, -0.7, 1.1)));
        for d in [
            [1.0, 2.0, 3.0],
            [0.0, 0.35, 0.0],
            [-0.5, 0.1, 0.1],
            [2.0, 2.0, 2.0],
        ] {
            let a = r * DMat3::from_diagonal(DVec3::from_array(d)) * r.transpose();
            let mut want = d;
            want.sort_by(f64::total_cmp);
            let got = symmetric_eigenvalues(&a);
            for k in 0..3 {
                assert!(
                    (got[k] - want[k]).abs() < 1e-15 * 4.0,
                    "{got:?} vs {want:?}"
                );
            }
        }
        assert_eq!(
            symmetric_eigenvalues(&DMat3::from_diagonal(DVec3::new(3.0, -1.0, 2.0))),
            [-1.0, 2.0, 3.0]
        );
    }
}
