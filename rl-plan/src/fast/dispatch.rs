//! Which lanes run the kernel: AVX2 with FMA when this CPU has them (detected once, at run
//! time), the portable lanes otherwise. The kernel is instantiated twice; the AVX2 copy is
//! compiled inside a `#[target_feature]` function so its lane operations inline to single
//! instructions.

use super::environment::Environment;
use super::kernel::{FrameStore, batch_mask, batch_valid};
use super::lanes::Portable;
use super::robot::SphereRobot;

/// The lane implementation in use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// `std::arch` AVX2 + FMA (x86-64).
    Avx2,
    /// `[f32; 8]` loops, vectorised by the compiler for the build target.
    Portable,
}

impl Backend {
    /// The best backend this CPU supports.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
                return Self::Avx2;
            }
        }
        Self::Portable
    }

    /// Whether this CPU can run it.
    pub fn is_supported(self) -> bool {
        match self {
            Self::Portable => true,
            Self::Avx2 => Self::detect() == Self::Avx2,
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx2 => "avx2+fma",
            Self::Portable => "portable",
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn batch_avx2(
    robot: &SphereRobot,
    env: &Environment,
    q: &[[f32; 8]],
    frames: &mut [FrameStore],
) -> bool {
    batch_valid::<super::avx2::Avx2>(robot, env, q, frames)
}

fn batch_portable(
    robot: &SphereRobot,
    env: &Environment,
    q: &[[f32; 8]],
    frames: &mut [FrameStore],
) -> bool {
    batch_valid::<Portable>(robot, env, q, frames)
}

/// Runs the kernel on `backend`: whether all eight configurations of `q` are valid.
#[inline]
pub(crate) fn run(
    backend: Backend,
    robot: &SphereRobot,
    env: &Environment,
    q: &[[f32; 8]],
    frames: &mut [FrameStore],
) -> bool {
    match backend {
        #[cfg(target_arch = "x86_64")]
        Backend::Avx2 => {
            // SAFETY: a checker holds `Backend::Avx2` only after `Backend::detect` (or
            // `is_supported`) found AVX2 and FMA on this CPU, which is all the target
            // features of `batch_avx2` require.
            #[allow(unsafe_code)]
            unsafe {
                batch_avx2(robot, env, q, frames)
            }
        }
        _ => batch_portable(robot, env, q, frames),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn mask_avx2(
    robot: &SphereRobot,
    env: &Environment,
    q: &[[f32; 8]],
    frames: &mut [FrameStore],
    live: u32,
) -> u32 {
    batch_mask::<super::avx2::Avx2>(robot, env, q, frames, live)
}

/// Runs the kernel on `backend` for every lane of `live`: the lanes in collision.
#[inline]
pub(crate) fn run_mask(
    backend: Backend,
    robot: &SphereRobot,
    env: &Environment,
    q: &[[f32; 8]],
    frames: &mut [FrameStore],
    live: u32,
) -> u32 {
    match backend {
        #[cfg(target_arch = "x86_64")]
        Backend::Avx2 => {
            // SAFETY: as in `run`: `Backend::Avx2` is only held after AVX2 and FMA were
            // detected on this CPU.
            #[allow(unsafe_code)]
            unsafe {
                mask_avx2(robot, env, q, frames, live)
            }
        }
        _ => batch_mask::<Portable>(robot, env, q, frames, live),
    }
}
