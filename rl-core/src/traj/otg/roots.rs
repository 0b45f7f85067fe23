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

/// `Σ |c[k] x^k|`: the size against which a computed value is compared with zero.
#[inline]
fn magnitude<const C: usize>(c: &[f64; C], x: f64) -> f64 {
    let ax = x.abs();
    let mut m = (c[C - 1]).abs();
    for k in (0..C - 1).rev() {
        m = m * ax + (c[k]).abs();
    }
    m
}

/// The root of a polynomial with `p(lo)` and `p(hi)` of opposite signs (neither zero) and no
/// other root in `[lo, hi]`: Halley steps (cubic convergence; the second derivative comes almost
/// free with Horner) from the secant point, kept inside the shrinking bracket, bisecting when a
/// step leaves it or does not halve the step before last.
fn refine<const C: usize>(c: &[f64; C], mut lo: f64, mut hi: f64, p_lo: f64) -> f64 {
    let rising = p_lo < 0.0;
    let p_hi = horner(c, hi);
    // Secant point (regula falsi) as the start: far better than the midpoint for the smooth
    // profile polynomials.
    let mut x = lo - p_lo * (hi - lo) / (p_hi - p_lo);
    if !(x > lo && x < hi) {
        x = 0.5 * (lo + hi);
    }
    let mut dx_old = hi - lo;
    let mut dx = dx_old;
    for _ in 0..MAX_ITERATIONS {
        let (p, dp, ddp) = eval_with_two_derivatives(c, x);
        // Within the rounding of the evaluation: as close as a double gets.
        if p.abs() <= 8.0 * f64::EPSILON * magnitude(c, x) {
            return x;
        }
        if (p < 0.0) == rising {
            lo = x;
        } else {
            hi = x;
        }
        let denominator = 2.0 * dp * dp - p * ddp;
        let step = if denominator != 0.0 {
            2.0 * p * dp / denominator
        } else {
            p / dp
        };
        let halley = x - step;
        let use_step = halley > lo && halley < hi && (2.0 * step).abs() <= dx_old.abs();
        dx_old = dx;
        let mut next = if use_step { halley } else { 0.5 * (lo + hi) };
        let tol = 4.0 * f64::EPSILON * x.abs() + f64::MIN_POSITIVE;
        if hi - lo <= tol {
            return next;
        }
        if (next - x).abs() <= tol {
            // A step this small means convergence, or a flat stretch (near an extremum the
            // derivative is small too): converged only if the sign changes within `tol`.
            let probe = if (p < 0.0) == rising {
                x + tol
            } else {
                x - tol
            };
            let p_probe = horner(c, probe);
            if p_probe == 0.0 || (p_probe < 0.0) != (p < 0.0) {
                return next;
            }
            if (p_probe < 0.0) == rising {
                lo = f64::max(lo, probe);
            } else {
                hi = f64::min(hi, probe);
            }
            next = 0.5 * (lo + hi);
        }
        dx = next - x;
        x = next;
    }
    x
}

/// `p(x)`, `p'(x)` and `p''(x)` for `p = Σ c[k] x^k`.
#[inline(always)]
fn eval_with_two_derivatives<const C: usize>(c: &[f64; C], x: f64) -> (f64, f64, f64) {
    let mut p = c[C - 1];
    let mut dp = 0.0;
    let mut ddp = 0.0;
    for k in (0..C - 1).rev() {
        ddp = ddp * x + 2.0 * dp;
        dp = dp * x + p;
        p = p * x + c[k];
    }
    (p, dp, ddp)
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
        } else if i + 1 < breaks.len() && p1.abs() <= TOUCH * magnitude(c, x1) {
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
    roots_between_extrema(c, &crit[..m], lo, hi, out)
}

/// The roots of `c` in `[lo, hi]` given its extrema `crit` (ascending): `c` is monotonic
/// between consecutive ones.
fn roots_between_extrema<const C: usize>(
    c: &[f64; C],
    crit: &[f64],
    lo: f64,
    hi: f64,
    out: &mut [f64; 4],
) -> usize {
    let mut breaks = [lo; 6];
    let mut nb = 1;
    for &x in crit {
        if x > lo && x < hi && nb < breaks.len() - 1 {
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

/// The values of `c` and its derivatives at `x` (`p, p', p'', p''', p''''`).
#[inline(always)]
fn derivatives_at(c: &[f64; 5], x: f64) -> [f64; 5] {
    let d4 = 24.0 * c[4];
    let d3 = 6.0 * c[3] + 24.0 * c[4] * x;
    let d2 = 2.0 * c[2] + x * (6.0 * c[3] + 12.0 * c[4] * x);
    let d1 = c[1] + x * (2.0 * c[2] + x * (3.0 * c[3] + 4.0 * c[4] * x));
    let d0 = c[0] + x * (c[1] + x * (c[2] + x * (c[3] + c[4] * x)));
    [d0, d1, d2, d3, d4]
}

/// Sign changes in a sequence, zeros skipped.
#[inline(always)]
fn sign_changes(d: &[f64; 5]) -> u32 {
    let mut last = 0.0;
    let mut n = 0;
    for &x in d {
        if x != 0.0 {
            if last != 0.0 && (x < 0.0) != (last < 0.0) {
                n += 1;
            }
            last = x;
        }
    }
    n
}

/// Real roots in `[lo, hi]` of the quartic `Σ c[k] x^k` (`c[4] ≠ 0`), ascending; returns how
/// many.
///
/// Budan–Fourier first: the sign changes of `(p, p', …, p'''')` lost from `lo` to `hi` bound the
/// number of roots in `(lo, hi]` from above, with the same parity. None lost: no root (the
/// common case, a profile type that does not apply, costs two evaluations); one lost: exactly
/// one, refined directly. Otherwise the roots are isolated between those of the derivative.
pub(crate) fn quartic_in(c: &[f64; 5], lo: f64, hi: f64, out: &mut [f64; 4]) -> usize {
    if !(lo <= hi) {
        return 0;
    }
    let at_lo = derivatives_at(c, lo);
    let at_hi = derivatives_at(c, hi);
    let lost = sign_changes(&at_lo) as i32 - sign_changes(&at_hi) as i32;
    if lost == 0 && at_lo[0] != 0.0 {
        return 0;
    }
    if lost == 1 && at_lo[0] != 0.0 {
        if at_hi[0] == 0.0 {
            out[0] = hi;
        } else {
            out[0] = refine(c, lo, hi, at_lo[0]);
        }
        return 1;
    }
    // Extrema: roots of the derivative cubic, found on [lo, hi] only.
    let d = [c[1], 2.0 * c[2], 3.0 * c[3], 4.0 * c[4]];
    let mut crit = [0.0; 4];
    let m = cubic_in(&d, lo, hi, &mut crit);
    roots_between_extrema(c, &crit[..m], lo, hi, out)
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
        // Evaluating p near a root rounds at ~1e-13 (terms up to ~400), p' there is ~2.
        for (r, e) in out.iter().zip([1.0, 2.0, 3.0, 4.0]) {
            assert!((r - e).abs() < 1e-13, "{r} vs {e}");
        }
        // Restricted interval.
        let n = quartic_in(&c, 1.5, 3.5, &mut out);
        assert_eq!(n, 2);
        assert!((out[0] - 2.0).abs() < 1e-13 && (out[1] - 3.0).abs() < 1e-13);
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
