//! Elementary functions: the platform's `std` implementations when the `std` feature is on
//! (glibc's are several times faster than a portable port), `libm` otherwise.

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    #[cfg(feature = "std")]
    {
        x.sin_cos()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::sincos(x)
    }
}
