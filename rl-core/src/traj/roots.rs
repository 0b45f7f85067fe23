//! Real roots of a scalar polynomial on an interval, by isolating each root between the roots
//! of the next derivative (where the polynomial is monotonic) and bisecting. Fixed-size, no
//! allocation; used for extrema.

/// Evaluates `Σ c[k] t^k`.
pub(crate) fn horner<const C: usize>(c: &[f64; C], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * t + ck)
}

/// The coefficients of the derivative, same length (last entry zero).
pub(crate) fn derive<const C: usize>(c: &[f64; C]) -> [f64; C] {
    let mut d = [0.0; C];
    for k in 1..C {
        d[k - 1] = c[k] * k as f64;
    }
    d
}

/// Root of a polynomial monotonic on `[a, b]`, if its sign changes there. `first` admits a root
/// exactly at `a` (later intervals get it as the previous interval's `b`).
fn bracketed<const C: usize>(c: &[f64; C], a: f64, b: f64, first: bool) -> Option<f64> {
    let fa = horner(c, a);
    let fb = horner(c, b);
    if first && fa == 0.0 {
        return Some(a);
    }
    if fb == 0.0 {
        return Some(b);
    }
    if fa == 0.0 || (fa < 0.0) == (fb < 0.0) {
        return None;
    }
    let (mut lo, mut hi) = (a, b);
    let rising = fa < 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let fm = horner(c, mid);
        if fm == 0.0 {
            return Some(mid);
        }
        if (fm < 0.0) == rising {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// Roots of `Σ c[k] t^k` in `[lo, hi]` where the sign changes (simple and odd-multiplicity
/// roots), sorted, written to `out`; returns how many.
pub(crate) fn roots_in<const C: usize>(
    c: &[f64; C],
    lo: f64,
    hi: f64,
    out: &mut [f64; C],
) -> usize {
    let Some(degree) = (0..C).rev().find(|&k| c[k] != 0.0) else {
        return 0;
    };
    if degree == 0 || !(lo <= hi) {
        return 0;
    }
    let mut derivatives = [[0.0; C]; C];
    derivatives[0] = *c;
    for k in 1..degree {
        derivatives[k] = derive(&derivatives[k - 1]);
    }
    // Roots of the (degree)-th derivative (a nonzero constant): none.
    let mut critical = [0.0; C];
    let mut n_critical = 0;
    for k in (0..degree).rev() {
        let mut found = [0.0; C];
        let mut n_found = 0;
        let mut a = lo;
        for idx in 0..=n_critical {
            let b = if idx < n_critical { critical[idx] } else { hi };
            if let Some(r) = bracketed(&derivatives[k], a, b, idx == 0) {
                if n_found < C {
                    found[n_found] = r;
                    n_found += 1;
                }
            }
            a = b;
        }
        critical = found;
        n_critical = n_found;
    }
    *out = critical;
    n_critical
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_all_roots_of_a_product() {
        // (t-0.1)(t-0.5)(t-0.9) = t³ - 1.5t² + 0.59t - 0.045
        let c = [-0.045, 0.59, -1.5, 1.0];
        let mut out = [0.0; 4];
        let n = roots_in(&c, 0.0, 1.0, &mut out);
        assert_eq!(n, 3);
        for (r, e) in out.iter().zip([0.1, 0.5, 0.9]) {
            assert!((r - e).abs() < 1e-14, "{r} vs {e}");
        }
    }
}
