//! The AVX-512 lanes (x86-64 only): sixteen `f32` in a `__m512`.
//!
//! Safety argument, once for every block below: the intrinsics need the `avx512f` target
//! feature. An [`Avx512`] value is only ever created and used inside [`super::kernel`]
//! instantiated for it, which [`super::dispatch`] calls only through a
//! `#[target_feature(enable = "avx512f,avx2,fma")]` function, and only after
//! `is_x86_feature_detected!("avx512f")` returned true on this CPU. So whenever an intrinsic here
//! executes, the CPU has the features it needs. The only memory touched is by `load` and
//! `store`, within a `&Wide` / `&mut Wide` of exactly 16 numbers (unaligned intrinsics).

#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::lanes::{Lanes, Wide};

/// Sixteen `f32` in a `__m512`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx512(__m512);

impl Lanes for Avx512 {
    const N: usize = 16;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_set1_ps(x) })
    }
    #[inline(always)]
    fn load(a: &Wide) -> Self {
        // SAFETY: see the module docs; 16 numbers read from an array of 16.
        Self(unsafe { _mm512_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, a: &mut Wide) {
        // SAFETY: see the module docs; 16 numbers written into an array of 16.
        unsafe { _mm512_storeu_ps(a.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_add_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_sub_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_mul_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_fmadd_ps(self.0, b.0, c.0) })
    }
    #[inline(always)]
    fn min(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_min_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn max(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_max_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_sqrt_ps(self.0) })
    }
    #[inline(always)]
    fn round(self) -> Self {
        // SAFETY: see the module docs; round to nearest even, no exceptions.
        Self(unsafe {
            _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(self.0)
        })
    }
    #[inline(always)]
    fn floor(self) -> Self {
        // SAFETY: see the module docs; round down, no exceptions.
        Self(unsafe {
            _mm512_roundscale_ps::<{ _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC }>(self.0)
        })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm512_abs_ps(self.0) })
    }
    #[inline(always)]
    fn lt_mask(self, b: Self) -> u32 {
        // SAFETY: see the module docs.
        u32::from(unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, b.0) })
    }
    #[inline(always)]
    fn all_lt(self, b: Self) -> bool {
        // SAFETY: see the module docs.
        unsafe { _mm512_cmp_ps_mask::<_CMP_LT_OQ>(self.0, b.0) == 0xFFFF }
    }
}
