//! Eigen-decomposition of a small symmetric matrix (up to 6×6, e.g. an operational-space
//! inverse inertia), eigenvalues and eigenvectors.
//!
//! Cyclic Jacobi rotations (Golub & Van Loan, *Matrix Computations*, §8.5): each rotation zeroes
//! one off-diagonal entry, and the product of the rotations collects the eigenvectors. The
//! sweeps stop once the off-diagonal part is below rounding of the diagonal, at most
//! [`MAX_SWEEPS`] (convergence is quadratic: 5–8 sweeps for a 6×6 in double precision), so the
//! work is bounded whatever the input. No allocation.

/// The most sweeps [`symmetric_eigen`] makes.
pub const MAX_SWEEPS: usize = 24;

/// Decomposes the leading `n × n` block of the symmetric `a` (both triangles read as one: the
/// upper one is used) as `a = V diag(values) Vᵀ`: `values[..n]` unordered, `vectors[r][c]` the
/// `r`-th element of the `c`-th eigenvector (orthonormal columns). `n ≤ 6`. Returns the sweeps
/// made.
pub fn symmetric_eigen(
    a: &[[f64; 6]; 6],
    n: usize,
    values: &mut [f64; 6],
    vectors: &mut [[f64; 6]; 6],
) -> usize {
    let n = n.min(6);
    let mut m = [[0.0; 6]; 6];
    for r in 0..n {
        for c in 0..n {
            m[r][c] = if r <= c { a[r][c] } else { a[c][r] };
        }
    }
    *vectors = [[0.0; 6]; 6];
    for (k, row) in vectors.iter_mut().enumerate() {
        row[k] = 1.0;
    }
    let mut sweeps = 0;
    while sweeps < MAX_SWEEPS {
        let mut off = 0.0;
        let mut diag = 0.0;
        for r in 0..n {
            diag += m[r][r] * m[r][r];
            for c in r + 1..n {
                off += m[r][c] * m[r][c];
            }
        }
        if off <= 1e-32 * diag || off == 0.0 {
            break;
        }
        sweeps += 1;
        for p in 0..n {
            for q in p + 1..n {
                if m[p][q] == 0.0 {
                    continue;
                }
                // The rotation in the (p, q) plane that zeroes m[p][q].
                let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                let t = theta.signum() / (theta.abs() + libm::sqrt(theta * theta + 1.0));
                let c = 1.0 / libm::sqrt(t * t + 1.0);
                let s = t * c;
                for k in 0..n {
                    let (mkp, mkq) = (m[k][p], m[k][q]);
                    m[k][p] = c * mkp - s * mkq;
                    m[k][q] = s * mkp + c * mkq;
                }
                for k in 0..n {
                    let (mpk, mqk) = (m[p][k], m[q][k]);
                    m[p][k] = c * mpk - s * mqk;
                    m[q][k] = s * mpk + c * mqk;
                }
                for row in vectors.iter_mut().take(n) {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
    }
    for k in 0..n {
        values[k] = m[k][k];
    }
    sweeps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `V diag(d) Vᵀ` for a rotation `V` built from Givens rotations, decomposed back.
    #[test]
    fn a_rotated_diagonal_is_decomposed_back() {
        for (n, d) in [
            (6, [1.0, 2.0, 3.0, 1e-6, 50.0, 2.0]),
            (3, [0.5, -0.25, 0.5, 0.0, 0.0, 0.0]),
            (6, [0.0, 0.0, 1.0, 1.0, 1.0, 4.0]),
        ] {
            let mut v = [[0.0; 6]; 6];
            for (k, row) in v.iter_mut().enumerate() {
                row[k] = 1.0;
            }
            for (i, (p, q)) in [(0, 1), (1, 2), (0, 2), (3, 4), (2, 5), (4, 5), (1, 3)]
                .into_iter()
                .enumerate()
            {
                if q >= n {
                    continue;
                }
                let (s, c) = libm::sincos(0.3 + 0.7 * i as f64);
                for row in v.iter_mut() {
                    let (a, b) = (row[p], row[q]);
                    row[p] = c * a - s * b;
                    row[q] = s * a + c * b;
                }
            }
            let mut a = [[0.0; 6]; 6];
            for r in 0..n {
                for c in 0..n {
                    a[r][c] = (0..n).map(|k| v[r][k] * d[k] * v[c][k]).sum();
                }
            }
            let (mut values, mut vectors) = ([0.0; 6], [[0.0; 6]; 6]);
            let sweeps = symmetric_eigen(&a, n, &mut values, &mut vectors);
            assert!(sweeps < MAX_SWEEPS, "{sweeps}");
            // Reassembled, and orthonormal.
            for r in 0..n {
                for c in 0..n {
                    let x: f64 = (0..n)
                        .map(|k| vectors[r][k] * values[k] * vectors[c][k])
                        .sum();
                    assert!((x - a[r][c]).abs() < 1e-13, "{r} {c}: {x} vs {}", a[r][c]);
                    let o: f64 = (0..n).map(|k| vectors[k][r] * vectors[k][c]).sum();
                    let want = if r == c { 1.0 } else { 0.0 };
                    assert!((o - want).abs() < 1e-13, "VᵀV {r} {c}: {o}");
                }
            }
            let mut got = values;
            let mut want = d;
            got[..n].sort_by(f64::total_cmp);
            want[..n].sort_by(f64::total_cmp);
            for k in 0..n {
                assert!((got[k] - want[k]).abs() < 1e-13, "{got:?} vs {want:?}");
            }
        }
    }
}
