//! Elementary functions for the hot path.
//!
//! [`sin_cos`] is called once per revolute joint by every kinematics and dynamics algorithm, so
//! it is a large share of their cost: glibc's `sincos` is a call of about 120 instructions,
//! the `libm` crate's port is slower still. Here fdlibm's algorithm (the one musl and the
//! `libm` crate use: Cody–Waite reduction by π/2 in three parts, then the degree-13/14 kernels
//! of `k_sin.c`/`k_cos.c`, error < 1 ulp) is written out so that it inlines into the joint
//! transform. It returns the same bits as `libm::sincos` for |x| < 2²⁰·π/2 (a test checks
//! that) and falls back to the platform's function beyond, and for NaN and infinities.

// The constants are fdlibm's, given by their bits as fdlibm gives them.

/// 2/π.
const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
/// π/2 in three parts of 33 bits and their tails (fdlibm's `pio2_1`…`pio2_3t`): `n · PIO2_1`
/// is exact for |n| < 2²⁰.
const PIO2_1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
const PIO2_1T: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
const PIO2_2: f64 = f64::from_bits(0x3DD0_B461_1A60_0000);
const PIO2_2T: f64 = f64::from_bits(0x3BA3_198A_2E03_7073);
const PIO2_3: f64 = f64::from_bits(0x3BA3_198A_2E00_0000);
const PIO2_3T: f64 = f64::from_bits(0x397B_839A_2520_49C1);
/// Adding and subtracting 1.5·2⁵² rounds to the nearest integer.
const TO_INT: f64 = 1.5 / f64::EPSILON;

/// Minimax coefficients of `sin` on [-π/4, π/4] (fdlibm `k_sin.c`, S1…S6).
const S: [f64; 6] = [
    f64::from_bits(0xBFC5_5555_5555_5549),
    f64::from_bits(0x3F81_1111_1110_F8A6),
    f64::from_bits(0xBF2A_01A0_19C1_61D5),
    f64::from_bits(0x3EC7_1DE3_57B1_FE7D),
    f64::from_bits(0xBE5A_E5E6_8A2B_9CEB),
    f64::from_bits(0x3DE5_D93A_5ACF_D57C),
];
/// Minimax coefficients of `cos` on [-π/4, π/4] (fdlibm `k_cos.c`, C1…C6).
const C: [f64; 6] = [
    f64::from_bits(0x3FA5_5555_5555_554C),
    f64::from_bits(0xBF56_C16C_16C1_5177),
    f64::from_bits(0x3EFA_01A0_19CB_1590),
    f64::from_bits(0xBE92_7E4F_809C_52AD),
    f64::from_bits(0x3E21_EE9E_BDB4_B1C4),
    f64::from_bits(0xBDA8_FAE9_BE88_38D4),
];

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let ix = (x.to_bits() >> 32) as u32 & 0x7fff_ffff;
    if ix <= 0x3fe9_21fb {
        // |x| ≤ π/4 (the boundary itself too: the kernels hold there).
        if ix < 0x3e40_0000 {
            // |x| < 2⁻²⁷: sin x = x (keeps -0.0), cos x = 1 to the last bit.
            return (x, 1.0);
        }
        return (kernel_sin_exact(x), kernel_cos(x, 0.0));
    }
    if ix >= 0x4139_21fb {
        // |x| ≥ 2²⁰·π/2 (very rare for a joint angle), infinities and NaN.
        return platform_sin_cos(x);
    }
    let (n, y0, y1) = reduce(x, ix);
    let (s, c) = (kernel_sin(y0, y1), kernel_cos(y0, y1));
    match n & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// `x = n·π/2 + y0 + y1` with |y0 + y1| ≤ π/4, for |x| < 2²⁰·π/2 (fdlibm `e_rem_pio2.c`,
/// medium case): a second and third part of π/2 only when the first leaves too few bits.
#[inline]
fn reduce(x: f64, ix: u32) -> (i32, f64, f64) {
    let f = x * INV_PIO2 + TO_INT - TO_INT;
    let n = f as i32;
    let mut r = x - f * PIO2_1;
    let mut w = f * PIO2_1T;
    let mut y0 = r - w;
    let ex = ix >> 20;
    let ey = |y: f64| ((y.to_bits() >> 52) & 0x7ff) as u32;
    if ex.wrapping_sub(ey(y0)) as i32 > 16 {
        // Cancellation took more than 16 bits: use 33 more bits of π/2.
        let t = r;
        w = f * PIO2_2;
        r = t - w;
        w = f * PIO2_2T - ((t - r) - w);
        y0 = r - w;
        if ex.wrapping_sub(ey(y0)) as i32 > 49 {
            let t = r;
            w = f * PIO2_3;
            r = t - w;
            w = f * PIO2_3T - ((t - r) - w);
            y0 = r - w;
        }
    }
    let y1 = (r - y0) - w;
    (n, y0, y1)
}

/// `sin(x + y)` for |x + y| ≤ π/4, `y` the tail of `x`.
#[inline]
fn kernel_sin(x: f64, y: f64) -> f64 {
    let (z, r) = sin_poly(x);
    let v = z * x;
    x - ((z * (0.5 * y - v * r) - y) - v * S[0])
}

/// `sin x` for |x| ≤ π/4 (no tail); rounds differently from `kernel_sin(x, 0.0)`.
#[inline]
fn kernel_sin_exact(x: f64) -> f64 {
    let (z, r) = sin_poly(x);
    x + z * x * (S[0] + z * r)
}

/// `(x², the degree-2…10 part of the sine polynomial in x²)`.
#[inline]
fn sin_poly(x: f64) -> (f64, f64) {
    let z = x * x;
    let w = z * z;
    (z, S[1] + z * (S[2] + z * S[3]) + z * w * (S[4] + z * S[5]))
}

/// `cos(x + y)` for |x + y| ≤ π/4, `y` the tail of `x`.
#[inline]
fn kernel_cos(x: f64, y: f64) -> f64 {
    let z = x * x;
    let w = z * z;
    let r = z * (C[0] + z * (C[1] + z * C[2])) + w * w * (C[3] + z * (C[4] + z * C[5]));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    w + (((1.0 - w) - hz) + (z * r - x * y))
}

/// The platform's `sincos` (glibc's with `std`), `libm`'s without.
#[cold]
fn platform_sin_cos(x: f64) -> (f64, f64) {
    #[cfg(feature = "std")]
    {
        x.sin_cos()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::sincos(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units in the last place between two finite doubles of the same sign.
    #[cfg(feature = "std")]
    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        let key = |x: f64| {
            let i = x.to_bits() as i64;
            if i < 0 { i64::MIN - i } else { i }
        };
        key(a).abs_diff(key(b))
    }

    /// A fixed pseudo-random sequence in [0, 1).
    fn uniform(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    fn check(x: f64) {
        let (s, c) = sin_cos(x);
        let (ls, lc) = libm::sincos(x);
        assert_eq!(
            (s.to_bits(), c.to_bits()),
            (ls.to_bits(), lc.to_bits()),
            "x = {x:e}: ours ({s:e}, {c:e}), libm ({ls:e}, {lc:e})"
        );
    }

    #[test]
    fn same_bits_as_libm_over_joint_ranges_and_far_out() {
        let mut seed = 7;
        for scale in [1e-9, 1e-3, 0.7, 1.0, 3.2, 10.0, 100.0, 1e4, 1.6e6] {
            for _ in 0..20_000 {
                check(scale * (2.0 * uniform(&mut seed) - 1.0));
            }
        }
    }

    #[test]
    fn same_bits_as_libm_next_to_multiples_of_half_pi() {
        // Here the reduction cancels most bits and needs its second and third parts.
        for n in -2000i32..=2000 {
            let x = f64::from(n) * core::f64::consts::FRAC_PI_2;
            let mut y = x;
            let mut z = x;
            for _ in 0..8 {
                check(y);
                check(z);
                y = f64::from_bits(y.to_bits() + 1);
                z = f64::from_bits(z.to_bits().wrapping_sub(1));
            }
        }
        // Doubles known to sit extremely close to a multiple of π/2.
        for x in [
            core::f64::consts::FRAC_PI_2,
            -core::f64::consts::FRAC_PI_2,
            3.0 * core::f64::consts::FRAC_PI_2,
            1_073_741_823.5 * core::f64::consts::PI,
        ] {
            check(x);
        }
    }

    /// Against an independent implementation: glibc's table-based `sin`/`cos`.
    #[cfg(feature = "std")]
    #[test]
    fn within_one_ulp_of_glibc() {
        let mut seed = 11;
        for _ in 0..200_000 {
            let x = 20.0 * (2.0 * uniform(&mut seed) - 1.0);
            let (s, c) = sin_cos(x);
            let (ps, pc) = (x.sin(), x.cos());
            assert!(ulps(s, ps) <= 1 && ulps(c, pc) <= 1, "x = {x:e}");
        }
    }

    #[test]
    fn special_values() {
        let (s, c) = sin_cos(-0.0);
        assert_eq!((s.to_bits(), c), ((-0.0f64).to_bits(), 1.0));
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan(), "{x}");
        }
        let (s, c) = sin_cos(core::f64::consts::FRAC_PI_4);
        assert_eq!((s, c), libm::sincos(core::f64::consts::FRAC_PI_4));
        assert!((s - c).abs() < 2e-16);
    }
}
