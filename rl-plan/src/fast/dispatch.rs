//! Which lanes run the kernel: AVX-512 (sixteen lanes) when this CPU has it, else AVX2 with FMA
//! (eight), else the portable lanes (eight) — detected once, at run time. The kernel is
//! instantiated once per lane type; the SIMD copies are compiled inside `#[target_feature]`
//! functions so their lane operations inline to single instructions.

use super::environment::Environment;
use super::kernel::{FrameStore, batch_mask, batch_valid};
use super::lanes::{Lanes, Portable, Wide};
use super::robot::SphereRobot;

/// The lane implementation in use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// `std::arch` AVX-512F, sixteen lanes (x86-64).
    Avx512,
    /// `std::arch` AVX2 + FMA, eight lanes (x86-64).
    Avx2,
    /// `[f32; 8]` loops, vectorised by the compiler for the build target.
    Portable,
}

impl Backend {
    /// Every backend, widest first.
    pub const ALL: [Backend; 3] = [Backend::Avx512, Backend::Avx2, Backend::Portable];

    /// The best backend this CPU supports — or the one the environment variable
    /// `RL_PLAN_BACKEND` names (`avx512`, `avx2`, `portable`; for measurements), if this CPU
    /// supports it.
    pub fn detect() -> Self {
        if let Some(b) = std::env::var("RL_PLAN_BACKEND")
            .ok()
            .and_then(|v| Self::parse(&v))
            .filter(|b| b.is_supported())
        {
            return b;
        }
        Self::ALL
            .into_iter()
            .find(|b| b.is_supported())
            .unwrap_or(Self::Portable)
    }

    /// Whether this CPU can run it.
    pub fn is_supported(self) -> bool {
        match self {
            Self::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Self::Avx2 => {
                std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Self::Avx512 => {
                std::is_x86_feature_detected!("avx512f")
                    && std::is_x86_feature_detected!("avx2")
                    && std::is_x86_feature_detected!("fma")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// Configurations it checks in one pass.
    pub fn lanes(self) -> usize {
        match self {
            Self::Avx512 => 16,
            Self::Avx2 | Self::Portable => 8,
        }
    }

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "avx512f",
            Self::Avx2 => "avx2+fma",
            Self::Portable => "portable",
        }
    }

    /// The backend of a name ([`Backend::name`], or `avx512`, `avx2`).
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "avx512f" | "avx512" => Some(Self::Avx512),
            "avx2+fma" | "avx2" => Some(Self::Avx2),
            "portable" => Some(Self::Portable),
            _ => None,
        }
    }
}

/// The kernel's entry points for one lane type, as plain functions.
macro_rules! entry {
    ($valid:ident, $mask:ident, $lanes:ty, $features:literal) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        fn $valid(
            robot: &SphereRobot,
            env: &Environment,
            q: &[Wide],
            frames: &mut [FrameStore],
        ) -> bool {
            batch_valid::<$lanes>(robot, env, q, frames)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        fn $mask(
            robot: &SphereRobot,
            env: &Environment,
            q: &[Wide],
            frames: &mut [FrameStore],
            live: u32,
        ) -> u32 {
            batch_mask::<$lanes>(robot, env, q, frames, live)
        }
    };
}

entry!(valid_avx2, mask_avx2, super::avx2::Avx2, "avx2,fma");
entry!(
    valid_avx512,
    mask_avx512,
    super::avx512::Avx512,
    "avx512f,avx2,fma"
);

/// Runs the kernel on `backend`: whether all its lanes of `q` are valid.
#[inline]
pub(crate) fn run(
    backend: Backend,
    robot: &SphereRobot,
    env: &Environment,
    q: &[Wide],
    frames: &mut [FrameStore],
) -> bool {
    match backend {
        // SAFETY (both arms): a checker holds a SIMD backend only after `Backend::detect` or
        // `Backend::is_supported` found its features on this CPU, which are all the target
        // features of the function called.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Backend::Avx512 => unsafe { valid_avx512(robot, env, q, frames) },
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Backend::Avx2 => unsafe { valid_avx2(robot, env, q, frames) },
        _ => batch_valid::<Portable>(robot, env, q, frames),
    }
}

/// Runs the kernel on `backend` for every lane of `live`: the lanes in collision.
#[inline]
pub(crate) fn run_mask(
    backend: Backend,
    robot: &SphereRobot,
    env: &Environment,
    q: &[Wide],
    frames: &mut [FrameStore],
    live: u32,
) -> u32 {
    match backend {
        // SAFETY (both arms): as in `run`.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Backend::Avx512 => unsafe { mask_avx512(robot, env, q, frames, live) },
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Backend::Avx2 => unsafe { mask_avx2(robot, env, q, frames, live) },
        _ => batch_mask::<Portable>(robot, env, q, frames, live & Portable::full()),
    }
}
