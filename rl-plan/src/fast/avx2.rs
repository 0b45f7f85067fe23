//! The AVX2 + FMA lanes (x86-64 only). The unsafe code of rl-plan is in this file, in
//! `avx512.rs` (the same for AVX-512) and in the dispatch's calls of target-feature functions.
//!
//! Safety argument, once for every block below: the intrinsics need the `avx` (register
//! type), `avx2` and `fma` target features. An [`Avx2`] value is only ever created and
//! used inside [`super::kernel`] instantiated for it, which [`super::dispatch`] calls only
//! through a `#[target_feature(enable = "avx2,fma")]` function, and only after
//! `is_x86_feature_detected!("avx2")` and `…("fma")` returned true on this CPU. So whenever an
//! intrinsic here executes, the CPU has the features it needs. The only memory touched is by
//! `load` and `store`, within a `&Wide` / `&mut Wide` of 16 numbers (the first 8; unaligned
//! intrinsics, so the array's alignment does not matter).

#![allow(unsafe_code)]

use std::arch::x86_64::*;

use super::lanes::{Lanes, Wide};

/// Eight `f32` in a `__m256`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(__m256);

impl Lanes for Avx2 {
    const N: usize = 8;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        // SAFETY: see the module docs (AVX present whenever this runs).
        Self(unsafe { _mm256_set1_ps(x) })
    }
    #[inline(always)]
    fn load(a: &Wide) -> Self {
        // SAFETY: see the module docs; an unaligned load of the first 8 of 16 numbers.
        Self(unsafe { _mm256_loadu_ps(a.as_ptr()) })
    }
    #[inline(always)]
    fn store(self, a: &mut Wide) {
        // SAFETY: see the module docs; an unaligned store into the first 8 of 16 numbers.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) }
    }
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm256_add_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm256_sub_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm256_mul_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn mul_add(self, b: Self, c: Self) -> Self {
        // SAFETY: see the module docs (FMA detected with AVX2).
        Self(unsafe { _mm256_fmadd_ps(self.0, b.0, c.0) })
    }
    #[inline(always)]
    fn min(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm256_min_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn max(self, b: Self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm256_max_ps(self.0, b.0) })
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm256_sqrt_ps(self.0) })
    }
    #[inline(always)]
    fn round(self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe {
            _mm256_round_ps::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(self.0)
        })
    }
    #[inline(always)]
    fn floor(self) -> Self {
        // SAFETY: see the module docs.
        Self(unsafe { _mm256_floor_ps(self.0) })
    }
    #[inline(always)]
    fn abs(self) -> Self {
        // SAFETY: see the module docs; clearing the sign bit.
        Self(unsafe { _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0) })
    }
    #[inline(always)]
    fn lt_mask(self, b: Self) -> u32 {
        // SAFETY: see the module docs.
        unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, b.0)) as u32 }
    }
    #[inline(always)]
    fn all_lt(self, b: Self) -> bool {
        // SAFETY: see the module docs.
        unsafe { _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(self.0, b.0)) == 0xFF }
    }
}
