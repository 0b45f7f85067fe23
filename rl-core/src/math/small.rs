//! Inverse of a small symmetric positive-definite matrix (a joint's `D = Sᵀ I^A S`).

/// Inverts the leading `n × n` block of the symmetric positive-definite `a` into `out` by
/// Cholesky factorisation. Returns `false` (and leaves `out` unspecified) if `a` is not
/// positive definite. `n ≤ 6`.
pub fn invert_spd(a: &[[f64; 6]; 6], n: usize, out: &mut [[f64; 6]; 6]) -> bool {
    if n == 1 {
        if a[0][0] > 0.0 {
            out[0][0] = 1.0 / a[0][0];
            return true;
        }
        return false;
    }
    // a = L Lᵀ
    let mut l = [[0.0; 6]; 6];
    for i in 0..n {
        for j in 0..=i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if s <= 0.0 {
                    return false;
                }
                l[i][i] = libm::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    // L⁻¹ (lower triangular)
    let mut li = [[0.0; 6]; 6];
    for i in 0..n {
        li[i][i] = 1.0 / l[i][i];
        for j in 0..i {
            let mut s = 0.0;
            for k in j..i {
                s -= l[i][k] * li[k][j];
            }
            li[i][j] = s / l[i][i];
        }
    }
    // a⁻¹ = L⁻ᵀ L⁻¹
    for i in 0..n {
        for j in 0..=i {
            let mut s = 0.0;
            for k in i..n {
                s += li[k][i] * li[k][j];
            }
            out[i][j] = s;
            out[j][i] = s;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverts_a_3x3() {
        let mut a = [[0.0; 6]; 6];
        let m = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        for i in 0..3 {
            a[i][..3].copy_from_slice(&m[i]);
        }
        let mut inv = [[0.0; 6]; 6];
        assert!(invert_spd(&a, 3, &mut inv));
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| m[i][k] * inv[k][j]).sum();
                assert!((p - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        a[2][2] = -1.0;
        assert!(!invert_spd(&a, 3, &mut inv));
    }
}
