//! Eigenvalues of a symmetric 3×3 matrix (the principal moments of an inertia tensor).
//!
//! The cyclic Jacobi rotations of [`super::symmetric_eigen`] (Golub & Van Loan, *Matrix
//! Computations*, §8.5): accurate to a few ulps of the largest eigenvalue also for repeated
//! eigenvalues (where the closed-form trigonometric solution loses half the digits). No
//! allocation.

use glam::DMat3;

use super::jacobi::symmetric_eigen;

/// The eigenvalues of the symmetric `a` (its upper triangle is read), ascending.
pub fn symmetric_eigenvalues(a: &DMat3) -> [f64; 3] {
    let mut m = [[0.0; 6]; 6];
    m[0][..3].copy_from_slice(&[a.x_axis.x, a.y_axis.x, a.z_axis.x]);
    m[1][1..3].copy_from_slice(&[a.y_axis.y, a.z_axis.y]);
    m[2][2] = a.z_axis.z;
    let (mut values, mut vectors) = ([0.0; 6], [[0.0; 6]; 6]);
    symmetric_eigen(&m, 3, &mut values, &mut vectors);
    let mut out = [values[0], values[1], values[2]];
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
