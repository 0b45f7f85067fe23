//! `f32` lanes: the vector type the sphere kernel is written in, once, generically.
//!
//! Three implementations: [`Portable`] (eight lanes, `[f32; 8]` with plain loops, which the
//! compiler vectorises for the target it builds for — SSE2 on any x86-64, NEON on aarch64) and,
//! on x86-64 CPUs that have them, AVX2 with FMA (eight lanes, [`super::avx2::Avx2`]) and
//! AVX-512 (sixteen lanes, [`super::avx512::Avx512`]), chosen at run time. The kernel
//! instantiated for a SIMD type is compiled inside a `#[target_feature]` function, so every
//! lane operation inlines to one instruction.
//!
//! Lane values are stored in [`Wide`] arrays of [`WIDTH`] numbers whatever the lane count;
//! a type of `N` lanes uses the first `N`.
//!
//! [`sin_cos`] is written on top of the trait (no lookup tables, no branches): Cody–Waite
//! reduction by π/2 into `[−π/4, π/4]`, Cephes' single-precision minimax polynomials, and the
//! quadrant applied arithmetically. Its error is below 1e-6 for |x| < 100 (tested against
//! `f64`).

/// The most lanes of any implementation.
pub(crate) const WIDTH: usize = 16;

/// Storage of one lane vector (the first [`Lanes::N`] used).
pub(crate) type Wide = [f32; WIDTH];

/// The operations the kernel needs on `N` lanes.
pub(crate) trait Lanes: Copy {
    /// The number of lanes.
    const N: usize;
    /// All lanes `x`.
    fn splat(x: f32) -> Self;
    /// Lanes from the first `N` numbers of `a`.
    fn load(a: &Wide) -> Self;
    /// The lanes into the first `N` numbers of `a`.
    fn store(self, a: &mut Wide);
    /// `a + b`.
    fn add(self, b: Self) -> Self;
    /// `a − b`.
    fn sub(self, b: Self) -> Self;
    /// `a · b`.
    fn mul(self, b: Self) -> Self;
    /// `a · b + c` (fused where the hardware has it).
    fn mul_add(self, b: Self, c: Self) -> Self;
    /// Lane-wise minimum.
    fn min(self, b: Self) -> Self;
    /// Lane-wise maximum.
    fn max(self, b: Self) -> Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Rounded to the nearest integer (ties to even).
    fn round(self) -> Self;
    /// Rounded down.
    fn floor(self) -> Self;
    /// `|a|`.
    fn abs(self) -> Self;
    /// Whether `a < b` in every lane.
    fn all_lt(self, b: Self) -> bool;
    /// The lanes where `a < b`, as bits `0..N`.
    fn lt_mask(self, b: Self) -> u32;

    /// Every lane's bit.
    #[inline(always)]
    fn full() -> u32 {
        (1u32 << Self::N) - 1
    }

    /// The lanes as an array (the first `N` numbers).
    #[inline(always)]
    fn to_wide(self) -> Wide {
        let mut w = [0.0; WIDTH];
        self.store(&mut w);
        w
    }

    /// `−a`.
    #[inline(always)]
    fn neg(self) -> Self {
        Self::splat(0.0).sub(self)
    }

    /// `a · s + c` with a scalar `s`.
    #[inline(always)]
    fn mul_add_s(self, s: f32, c: Self) -> Self {
        self.mul_add(Self::splat(s), c)
    }
}

/// The portable implementation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable([f32; 8]);

macro_rules! lanewise {
    ($a:expr, $b:expr, |$x:ident, $y:ident| $e:expr) => {{
        let (a, b) = ($a.0, $b.0);
        let mut o = [0.0f32; 8];
        for i in 0..8 {
            let ($x, $y) = (a[i], b[i]);
            o[i] = $e;
        }
        Portable(o)
    }};
}

impl Lanes for Portable {
    const N: usize = 8;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self([x; 8])
    }
    #[inline(always)]
    fn load(a: &Wide) -> Self {
        let mut o = [0.0; 8];
        o.copy_from_slice(&a[..8]);
        Self(o)
    }
    #[inline(always)]
    fn store(self, a: &mut Wide) {
        a[..8].copy_from_slice(&self.0);
    }
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        lanewise!(self, b, |x, y| x + y)
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        lanewise!(self, b, |x, y| x - y)
    }
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        lanewise!(self, b, |x, y| x * y)
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        // Not fused: a software fma would be far slower than the rounding it saves.
        self.mul(b).add(c)
    }
    #[inline(always)]
    fn min(self, b: Self) -> Self {
        lanewise!(self, b, |x, y| if x < y { x } else { y })
    }
    #[inline(always)]
    fn max(self, b: Self) -> Self {
        lanewise!(self, b, |x, y| if x > y { x } else { y })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(self.0.map(f32::sqrt))
    }
    #[inline(always)]
    fn round(self) -> Self {
        Self(self.0.map(f32::round_ties_even))
    }
    #[inline(always)]
    fn floor(self) -> Self {
        Self(self.0.map(f32::floor))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self(self.0.map(f32::abs))
    }
    #[inline(always)]
    fn all_lt(self, b: Self) -> bool {
        let mut m = true;
        for i in 0..8 {
            m &= self.0[i] < b.0[i];
        }
        m
    }
    #[inline(always)]
    fn lt_mask(self, b: Self) -> u32 {
        let mut m = 0;
        for i in 0..8 {
            m |= u32::from(self.0[i] < b.0[i]) << i;
        }
        m
    }
}

/// Sine and cosine of every lane (see the module docs).
#[inline(always)]
pub(crate) fn sin_cos<L: Lanes>(x: L) -> (L, L) {
    // Cody–Waite split of π/2 (Cephes): the products with k are exact for |k| < 2⁸.
    const PIO2_1: f32 = 1.570_312_5;
    const PIO2_2: f32 = 4.837_513e-4;
    const PIO2_3: f32 = 7.549_79e-8;
    let k = x.mul(L::splat(std::f32::consts::FRAC_2_PI)).round();
    let r = k
        .mul_add_s(-PIO2_1, x)
        .add(k.mul(L::splat(-PIO2_2)))
        .add(k.mul(L::splat(-PIO2_3)));
    let r2 = r.mul(r);
    // sin r = r + r³ (s1 + r² (s2 + r² s3)), cos r = 1 − r²/2 + r⁴ (c1 + r² (c2 + r² c3)).
    let sp = r2
        .mul_add_s(-1.951_529_6e-4, L::splat(8.332_161e-3))
        .mul_add(r2, L::splat(-1.666_665_5e-1));
    let s = sp.mul(r2).mul_add(r, r);
    let cp = r2
        .mul_add_s(2.443_315_7e-5, L::splat(-1.388_731_6e-3))
        .mul_add(r2, L::splat(4.166_664_6e-2));
    let c = cp
        .mul(r2)
        .mul(r2)
        .add(r2.mul(L::splat(-0.5)))
        .add(L::splat(1.0));
    // Quadrant q = k mod 4: odd swaps sine and cosine, q ≥ 2 flips both signs.
    let q = k.sub(k.mul(L::splat(0.25)).floor().mul(L::splat(4.0)));
    let odd = q.sub(q.mul(L::splat(0.5)).floor().mul(L::splat(2.0)));
    let even = L::splat(1.0).sub(odd);
    let sign = L::splat(1.0).sub(q.mul(L::splat(0.5)).floor().mul(L::splat(2.0)));
    let sin = even.mul(s).add(odd.mul(c)).mul(sign);
    let cos = even.mul(c).sub(odd.mul(s)).mul(sign);
    (sin, cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_matches_f64() {
        let mut worst = 0.0f64;
        let mut x = -40.0f32;
        while x < 40.0 {
            let lanes: Wide = std::array::from_fn(|i| x + i as f32 * 0.0137);
            let (s, c) = sin_cos(Portable::load(&lanes));
            for i in 0..8 {
                let v = lanes[i] as f64;
                worst = worst
                    .max((s.to_wide()[i] as f64 - v.sin()).abs())
                    .max((c.to_wide()[i] as f64 - v.cos()).abs());
            }
            x += 0.1013;
        }
        assert!(worst < 1e-6, "worst error {worst}");
    }

    #[test]
    fn comparisons() {
        let a = Portable(std::array::from_fn(|i| i as f32));
        assert_eq!(a.lt_mask(Portable::splat(0.5)), 1);
        assert_eq!(a.lt_mask(Portable::splat(0.0)), 0);
        assert_eq!(a.lt_mask(Portable::splat(6.5)), 0x7F);
        assert!(a.all_lt(Portable::splat(7.5)));
        assert!(!a.all_lt(Portable::splat(7.0)));
    }
}
