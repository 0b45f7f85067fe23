//! Damped least squares (Levenberg–Marquardt) step: `dq = Jᵀ (J Jᵀ + λ² I)⁻¹ dx`.
//!
//! Wampler, "Manipulator inverse kinematic solutions based on vector formulations and damped
//! least-squares methods" (IEEE Trans. SMC 16, 1986); Nakamura and Hanafusa (1986). The
//! damping `λ` bounds the step near singularities at the cost of a slower final approach in
//! directions whose singular value is below `λ`. RL's "dls" passes `λ = 0`, which is the
//! undamped right pseudo-inverse; here `λ` is real. The `m × m` system (`m` = stacked error
//! rows, at most [`super::MAX_ROWS`]) is solved by Cholesky. Does not allocate.

use super::MAX_ROWS;

/// Writes the DLS step into `dq[..n]`. `jac` holds the `m × n` Jacobian, `dx` the error.
/// Returns `false` if `J Jᵀ + λ² I` is not positive definite (only possible for `λ = 0` at a
/// singularity) or the result is not finite.
#[allow(clippy::too_many_arguments)] // the scratch buffers are the solver's, passed in
pub(super) fn dls_step<const N: usize>(
    jac: &[[f64; N]; MAX_ROWS],
    m: usize,
    n: usize,
    dx: &[f64],
    lambda: f64,
    a: &mut [[f64; MAX_ROWS]; MAX_ROWS],
    y: &mut [f64; MAX_ROWS],
    dq: &mut [f64],
) -> bool {
    let l2 = lambda * lambda;
    for r in 0..m {
        for c in 0..=r {
            let mut s: f64 = jac[r][..n]
                .iter()
                .zip(&jac[c][..n])
                .map(|(x, z)| x * z)
                .sum();
            if r == c {
                s += l2;
            }
            a[r][c] = s;
        }
    }
    if !cholesky_in_place(a, m) {
        return false;
    }
    y[..m].copy_from_slice(&dx[..m]);
    cholesky_solve(a, m, y);
    for (k, d) in dq.iter_mut().enumerate().take(n) {
        *d = (0..m).map(|r| jac[r][k] * y[r]).sum();
    }
    dq[..n].iter().all(|d| d.is_finite())
}

/// Cholesky `A = L Lᵀ` of the lower triangle of `a[..m][..m]`, `L` written over it.
fn cholesky_in_place(a: &mut [[f64; MAX_ROWS]; MAX_ROWS], m: usize) -> bool {
    // A pivot below this fraction of the largest diagonal counts as zero.
    let scale = (0..m).fold(0.0f64, |s, k| s.max(a[k][k]));
    let floor = scale * 1e-14;
    for j in 0..m {
        let d = a[j][j] - a[j][..j].iter().map(|x| x * x).sum::<f64>();
        if d.is_nan() || d <= floor {
            return false;
        }
        let d = libm::sqrt(d);
        a[j][j] = d;
        for i in j + 1..m {
            let s = a[i][j]
                - a[i][..j]
                    .iter()
                    .zip(&a[j][..j])
                    .map(|(x, y)| x * y)
                    .sum::<f64>();
            a[i][j] = s / d;
        }
    }
    true
}

/// Solves `L Lᵀ y = b` in place with the factor from [`cholesky_in_place`].
fn cholesky_solve(l: &[[f64; MAX_ROWS]; MAX_ROWS], m: usize, y: &mut [f64; MAX_ROWS]) {
    for i in 0..m {
        let mut s = y[i];
        for k in 0..i {
            s -= l[i][k] * y[k];
        }
        y[i] = s / l[i][i];
    }
    for i in (0..m).rev() {
        let mut s = y[i];
        for k in i + 1..m {
            s -= l[k][i] * y[k];
        }
        y[i] = s / l[i][i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_the_normal_equations() {
        // J (2×3), λ = 0.1: check (J Jᵀ + λ² I) (J dq-part) ... directly: dq = Jᵀ y with
        // (J Jᵀ + λ² I) y = dx.
        let mut j = [[0.0; 3]; MAX_ROWS];
        j[0] = [1.0, 2.0, 0.5];
        j[1] = [-0.3, 0.7, 1.1];
        let dx = [0.2, -0.4];
        let (mut a, mut y, mut dq) = ([[0.0; MAX_ROWS]; MAX_ROWS], [0.0; MAX_ROWS], [0.0; 3]);
        assert!(dls_step(&j, 2, 3, &dx, 0.1, &mut a, &mut y, &mut dq));
        // (JᵀJ + λ² I) dq = Jᵀ dx is the equivalent joint-space form.
        for c in 0..3 {
            let lhs: f64 = (0..3)
                .map(|k| {
                    let jtj: f64 = (0..2).map(|r| j[r][c] * j[r][k]).sum();
                    (jtj + if c == k { 0.01 } else { 0.0 }) * dq[k]
                })
                .sum();
            let rhs: f64 = (0..2).map(|r| j[r][c] * dx[r]).sum();
            assert!((lhs - rhs).abs() < 1e-14, "{lhs} vs {rhs}");
        }
    }

    #[test]
    fn undamped_singular_system_is_refused() {
        let mut j = [[0.0; 2]; MAX_ROWS];
        j[0] = [1.0, 0.0];
        j[1] = [2.0, 0.0];
        let (mut a, mut y, mut dq) = ([[0.0; MAX_ROWS]; MAX_ROWS], [0.0; MAX_ROWS], [0.0; 2]);
        assert!(!dls_step(
            &j,
            2,
            2,
            &[1.0, 0.0],
            0.0,
            &mut a,
            &mut y,
            &mut dq
        ));
        assert!(dls_step(
            &j,
            2,
            2,
            &[1.0, 0.0],
            1e-3,
            &mut a,
            &mut y,
            &mut dq
        ));
    }
}
