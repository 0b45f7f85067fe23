//! One-sided Jacobi (Hestenes) SVD of the stacked Jacobian, by rotating pairs of its rows.
//!
//! Plane rotations applied to the rows of `J` (`m × n`, `m ≤ MAX_ROWS`) until they are
//! mutually orthogonal give `B = Uᵀ J` with `U` orthogonal, so `J = U B = Σ uᵢ σᵢ vᵢᵀ` with
//! `σᵢ = |bᵢ|` and `vᵢ = bᵢ / σᵢ`: an SVD without forming `JᵀJ` (which would square the
//! condition number). Demmel and Veselić, "Jacobi's method is more accurate than QR" (SIAM
//! J. Matrix Anal. Appl. 13, 1992). Fixed-size storage; does not allocate.

use super::MAX_ROWS;

/// Sweeps before giving up; for the ≤ 24 rows used here convergence takes 5 to 10.
const MAX_SWEEPS: usize = 40;

/// Two rows count as orthogonal once `|bₚ·b_r| ≤ TOL_PER_COLUMN · n · |bₚ| |b_r|`: the
/// rounding error of an `n`-term dot product is about `n ε |bₚ| |b_r|`, so a tighter test
/// could never be met and would spin until `MAX_SWEEPS`.
const TOL_PER_COLUMN: f64 = 2.0 * f64::EPSILON;

/// Rotates the first `m` rows (first `n` columns) of `b` until they are mutually orthogonal,
/// writing the accumulated rotation into `u` (`m × m`), so that on return the original `J`
/// equals `u · b`. Returns `false` if the sweeps ran out (not seen in practice), or if
/// `b` contains a non-finite value.
pub(super) fn orthogonalize_rows<const N: usize>(
    b: &mut [[f64; N]; MAX_ROWS],
    m: usize,
    n: usize,
    u: &mut [[f64; MAX_ROWS]; MAX_ROWS],
) -> bool {
    for (k, row) in u.iter_mut().enumerate().take(m) {
        row[..m].fill(0.0);
        row[k] = 1.0;
    }
    // Rows below this squared norm are zero to working precision (a rank deficiency): rotating
    // them against large rows only mixes in rounding noise and never converges.
    let frob2: f64 = b
        .iter()
        .take(m)
        .map(|row| row[..n].iter().map(|x| x * x).sum::<f64>())
        .sum();
    let negligible = frob2 * (4.0 * f64::EPSILON) * (4.0 * f64::EPSILON);
    let tol = TOL_PER_COLUMN * n.max(1) as f64;
    for _sweep in 0..MAX_SWEEPS {
        let mut rotated = false;
        for p in 0..m {
            for r in p + 1..m {
                let (alpha, beta, gamma) = dots(&b[p][..n], &b[r][..n]);
                if !(alpha.is_finite() && beta.is_finite() && gamma.is_finite()) {
                    return false;
                }
                if gamma == 0.0
                    || alpha <= negligible
                    || beta <= negligible
                    || libm::fabs(gamma) <= tol * libm::sqrt(alpha * beta)
                {
                    continue;
                }
                rotated = true;
                // The rotation angle that zeroes the off-diagonal element of the 2×2 Gram
                // matrix [[α, γ], [γ, β]] (Golub and Van Loan, Algorithm 8.5.2), smaller root.
                let zeta = (beta - alpha) / (2.0 * gamma);
                let sign = if zeta >= 0.0 { 1.0 } else { -1.0 };
                let t = sign / (libm::fabs(zeta) + libm::sqrt(1.0 + zeta * zeta));
                let c = 1.0 / libm::sqrt(1.0 + t * t);
                let s = c * t;
                let (lo, hi) = b.split_at_mut(r);
                for (x, y) in lo[p][..n].iter_mut().zip(hi[0][..n].iter_mut()) {
                    let (bp, br) = (*x, *y);
                    *x = c * bp - s * br;
                    *y = s * bp + c * br;
                }
                for row in u.iter_mut().take(m) {
                    let (up, ur) = (row[p], row[r]);
                    row[p] = c * up - s * ur;
                    row[r] = s * up + c * ur;
                }
            }
        }
        if !rotated {
            #[cfg(test)]
            SWEEPS.with(|c| c.set(c.get().max(_sweep + 1)));
            return true;
        }
    }
    false
}

/// `(a·a, b·b, a·b)`.
fn dots(a: &[f64], b: &[f64]) -> (f64, f64, f64) {
    let (mut aa, mut bb, mut ab) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        aa += x * x;
        bb += y * y;
        ab += x * y;
    }
    (aa, bb, ab)
}

#[cfg(test)]
extern crate std;

#[cfg(test)]
std::thread_local! {
    /// The most sweeps any call on this thread needed (tests only).
    static SWEEPS: core::cell::Cell<usize> = const { core::cell::Cell::new(0) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn converges_in_few_sweeps() {
        // Random 6×n matrices (n = 3..13), some with a rank deficiency.
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for trial in 0..2000 {
            let n = 3 + trial % 11;
            let mut j = [[0.0; 13]; MAX_ROWS];
            for row in j.iter_mut().take(6) {
                for x in row.iter_mut().take(n) {
                    *x = next();
                }
            }
            if trial % 3 == 0 {
                let (r0, r1) = (j[0], j[1]);
                for (k, x) in j[4].iter_mut().enumerate() {
                    *x = r0[k] - 2.0 * r1[k];
                }
            }
            let mut u = [[0.0; MAX_ROWS]; MAX_ROWS];
            assert!(orthogonalize_rows(&mut j, 6, n, &mut u), "trial {trial}");
        }
        let worst = SWEEPS.with(|c| c.get());
        assert!(worst <= 12, "needed {worst} sweeps");
    }

    #[test]
    fn reconstructs_and_orthogonalises() {
        // A 6×7 matrix with a rank deficiency (row 5 = row 0 + row 1).
        let mut j = [[0.0; 8]; MAX_ROWS];
        let mut seed = 1u64;
        for row in j.iter_mut().take(5) {
            for x in row.iter_mut().take(7) {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                *x = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            }
        }
        let (r0, r1) = (j[0], j[1]);
        for (k, x) in j[5].iter_mut().enumerate().take(7) {
            *x = r0[k] + r1[k];
        }
        let original = j;
        let mut u = [[0.0; MAX_ROWS]; MAX_ROWS];
        assert!(orthogonalize_rows(&mut j, 6, 7, &mut u));
        for p in 0..6 {
            for r in 0..6 {
                let brr: f64 = (0..7).map(|k| j[p][k] * j[r][k]).sum();
                let uu: f64 = (0..6).map(|k| u[k][p] * u[k][r]).sum();
                if p != r {
                    assert!(brr.abs() < 1e-14, "rows {p},{r} not orthogonal: {brr}");
                }
                assert!((uu - if p == r { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        for i in 0..6 {
            for k in 0..7 {
                let back: f64 = (0..6).map(|p| u[i][p] * j[p][k]).sum();
                assert!((back - original[i][k]).abs() < 1e-14);
            }
        }
        // exactly one singular value vanishes
        let small = (0..6).filter(|&p| (0..7).map(|k| j[p][k] * j[p][k]).sum::<f64>() < 1e-24);
        assert_eq!(small.count(), 1);
    }
}
