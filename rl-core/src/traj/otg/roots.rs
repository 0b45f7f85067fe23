//! Real roots of polynomials of degree ≤ 4 on an interval, for the profile equations.
//!
//! Each root is isolated between consecutive roots of the derivative (where the polynomial is
//! monotonic) and refined by Newton's method inside the bracket, falling back to bisection when
//! a step leaves the bracket or shrinks it too little ("rtsafe", Press et al., *Numerical
//! Recipes*, §9.4). The iteration count is bounded ([`MAX_ITERATIONS`]) and in practice five to
//! eight steps reach the last bit; nothing depends on a random start. Where the polynomial only
//! touches zero (a double root, common at the border between two profile types), rounding can
//! hide the sign change: a local extremum whose value is within [`TOUCH`] of zero (relative to
//! the size of the terms) is reported as a root as well, and the caller's profile check decides.
//!
//! Closed forms are used where they are exact enough: linear and quadratic equations (the
//! quadratic in the cancellation-free form).

/// Upper bound on refinement steps per root (bisection alone needs ≤ 1100 for the full double
/// range; Newton steps converge far sooner).
const MAX_ITERATIONS: usize = 100;

/// A local extremum counts as a double root when its value is below this fraction of the sum of
/// the magnitudes of the polynomial's terms there.
const TOUCH: f64 = 1e-10;

/// Real roots of `a x² + b x + c` (any of them may be zero); returns the number written.
#[inline]
pub(crate) fn quadratic(a: f64, b: f64, c: f64, out: &mut [f64; 2]) -> usize {
    if a == 0.0 {
        if b == 0.0 {
            return 0;
        }
        out[0] = -c / b;
        return 1;
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return 0;
    }
    let sq = libm::sqrt(disc);
    // q has the sign of b, so b + sign(b)·sq never cancels.
    let q = -0.5 * (b + if b < 0.0 { -sq } else { sq });
    if q == 0.0 {
        // b = 0 and disc = 0: c = 0, the double root at 0.
        out[0] = 0.0;
        return 1;
    }
    let (r1, r2) = (q / a, c / q);
    if r1 <= r2 {
        out[0] = r1;
        out[1] = r2;
    } else {
        out[0] = r2;
        out[1] = r1;
    }
    2
}

/// `p(x)` and `p'(x)` for `p = Σ c[k] x^k`.
#[inline(always)]
fn eval_with_derivative<const C: usize>(c: &[f64; C], x: f64) -> (f64, f64) {
    let mut p = c[C - 1];
    let mut dp = 0.0;
    for k in (0..C - 1).rev() {
        dp = dp * x + p;
        p = p * x + c[k];
    }
    (p, dp)
}

/// `Σ |c[k] x^k|`: the size against which a computed value is compared with zero.
#[inline]
fn magnitude<const C: usize>(c: &[f64; C], x: f64) -> f64 {
    let ax = libm::fabs(x);
    let mut m = libm::fabs(c[C - 1]);
    for k in (0..C - 1).rev() {
        m = m * ax + libm::fabs(c[k]);
    }
    m
}

/// The root of a polynomial monotonic on `[lo, hi]` with `p(lo)` and `p(hi)` of opposite
/// signs (neither zero).
fn refine<const C: usize>(c: &[f64; C], mut lo: f64, mut hi: f64, p_lo: f64) -> f64 {
    // Orient so that p(lo) < 0.
    let rising = p_lo < 0.0;
    let mut x = 0.5 * (lo + hi);
    let mut dx_old = hi - lo;
    let mut dx = dx_old;
    let (mut p, mut dp) = eval_with_derivative(c, x);
    for _ in 0..MAX_ITERATIONS {
        if p == 0.0 {
            return x;
        }
        if (p < 0.0) == rising {
            lo = x;
        } else {
            hi = x;
        }
        // Newton, unless it leaves the bracket or does not halve the step of two rounds ago.
        let newton = x - p / dp;
        let use_newton =
            newton > lo && newton < hi && libm::fabs(2.0 * p) <= libm::fabs(dx_old * dp);
        dx_old = dx;
        let next = if use_newton { newton } else { 0.5 * (lo + hi) };
        dx = next - x;
        if next == x || libm::fabs(dx) <= 2.0 * f64::EPSILON * libm::fabs(x) {
            return next;
        }
        x = next;
        (p, dp) = eval_with_derivative(c, x);
    }
    x
}

/// Appends the roots of `c` (degree `C - 1`, monotonic between consecutive `breaks`) found in
/// each piece `[breaks[i], breaks[i + 1]]`: sign changes are refined, values within [`TOUCH`] of
/// zero at an interior break (an extremum) are taken as double roots.
fn roots_between<const C: usize>(c: &[f64; C], breaks: &[f64], out: &mut [f64; 4], n: &mut usize) {
    let mut x0 = breaks[0];
    let mut p0 = horner(c, x0);
    if p0 == 0.0 {
        push(out, n, x0);
    }
    for (i, &x1) in breaks.iter().enumerate().skip(1) {
        let p1 = horner(c, x1);
        if p1 == 0.0 {
            push(out, n, x1);
        } else if p0 != 0.0 && (p0 < 0.0) != (p1 < 0.0) {
            push(out, n, refine(c, x0, x1, p0));
        } else if i + 1 < breaks.len() && libm::fabs(p1) <= TOUCH * magnitude(c, x1) {
            // An interior extremum touching zero.
            push(out, n, x1);
        }
        x0 = x1;
        p0 = p1;
    }
}

#[inline]
fn push(out: &mut [f64; 4], n: &mut usize, x: f64) {
    if *n < out.len() && (*n == 0 || out[*n - 1] != x) {
        out[*n] = x;
        *n += 1;
    }
}

#[inline(always)]
fn horner<const C: usize>(c: &[f64; C], x: f64) -> f64 {
    let mut p = c[C - 1];
    for k in (0..C - 1).rev() {
        p = p * x + c[k];
    }
    p
}

/// Real roots in `[lo, hi]` of the cubic `Σ c[k] x^k` (`c[3] ≠ 0`), ascending; returns how many.
pub(crate) fn cubic_in(c: &[f64; 4], lo: f64, hi: f64, out: &mut [f64; 4]) -> usize {
    if !(lo <= hi) {
        return 0;
    }
    let mut crit = [0.0; 2];
    let m = quadratic(3.0 * c[3], 2.0 * c[2], c[1], &mut crit);
    let mut breaks = [lo; 4];
    let mut nb = 1;
    for &x in &crit[..m] {
        if x > lo && x < hi {
            breaks[nb] = x;
            nb += 1;
        }
    }
    breaks[nb] = hi;
    nb += 1;
    let mut n = 0;
    roots_between(c, &breaks[..nb], out, &mut n);
    n
}

/// Real roots in `[lo, hi]` of the quartic `Σ c[k] x^k` (`c[4] ≠ 0`), ascending; returns how
/// many.
pub(crate) fn quartic_in(c: &[f64; 5], lo: f64, hi: f64, out: &mut [f64; 4]) -> usize {
    if !(lo <= hi) {
        return 0;
    }
    // Extrema: roots of the derivative cubic, found on [lo, hi] only.
    let d = [c[1], 2.0 * c[2], 3.0 * c[3], 4.0 * c[4]];
    let mut crit = [0.0; 4];
    let m = cubic_in(&d, lo, hi, &mut crit);
    let mut breaks = [lo; 6];
    let mut nb = 1;
    for &x in &crit[..m] {
        if x > lo && x < hi {
            breaks[nb] = x;
            nb += 1;
        }
    }
    breaks[nb] = hi;
    nb += 1;
    let mut n = 0;
    roots_between(c, &breaks[..nb], out, &mut n);
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quartic_with_four_roots() {
        // (x-1)(x-2)(x-3)(x-4) = x⁴ - 10x³ + 35x² - 50x + 24
        let c = [24.0, -50.0, 35.0, -10.0, 1.0];
        let mut out = [0.0; 4];
        let n = quartic_in(&c, 0.0, 5.0, &mut out);
        assert_eq!(n, 4);
        for (r, e) in out.iter().zip([1.0, 2.0, 3.0, 4.0]) {
            assert!((r - e).abs() < 1e-14, "{r} vs {e}");
        }
        // Restricted interval.
        let n = quartic_in(&c, 1.5, 3.5, &mut out);
        assert_eq!(&out[..n], &[2.0, 3.0]);
    }

    #[test]
    fn double_root_is_found() {
        // (x - 0.3)² (x + 1)(x - 2)
        let r = [0.3, 0.3, -1.0, 2.0];
        let c = [
            r[0] * r[1] * r[2] * r[3],
            -(r[0] * r[1] * r[2] + r[0] * r[1] * r[3] + r[0] * r[2] * r[3] + r[1] * r[2] * r[3]),
            r[0] * r[1] + r[0] * r[2] + r[0] * r[3] + r[1] * r[2] + r[1] * r[3] + r[2] * r[3],
            -(r[0] + r[1] + r[2] + r[3]),
            1.0,
        ];
        let mut out = [0.0; 4];
        let n = quartic_in(&c, 0.0, 1.0, &mut out);
        assert_eq!(n, 1);
        assert!((out[0] - 0.3).abs() < 1e-7, "{}", out[0]);
    }

    #[test]
    fn quadratic_without_cancellation() {
        let mut out = [0.0; 2];
        assert_eq!(quadratic(1.0, -1e8, 1.0, &mut out), 2);
        assert!((out[0] - 1e-8).abs() < 1e-22);
        assert_eq!(quadratic(1.0, 0.0, 1.0, &mut out), 0);
    }
}
