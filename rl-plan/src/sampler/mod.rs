//! Samplers (RL's `Sampler`): where a planner looks next.
//!
//! - [`Uniform`]: uniformly over the space (RL's `UniformSampler`).
//! - [`Gaussian`]: near obstacles — a uniform point and a Gaussian neighbour, one valid and one
//!   not; the valid one is kept (RL's `GaussianSampler`, Boor et al. 1999).
//! - [`Bridge`]: in narrow passages — two invalid points a Gaussian step apart whose midpoint is
//!   valid; with probability `1 − ratio` a uniform valid point instead (RL's `BridgeSampler`,
//!   Hsu et al. 2003).
//! - [`Halton`]: the Halton low-discrepancy sequence (VAMP's default sampler), deterministic,
//!   its start index set by the seed.
//!
//! Every loop that searches for a valid sample is bounded by the call's [`Budget`].

mod bridge;
mod gaussian;
mod halton;
mod uniform;

pub use bridge::Bridge;
pub use gaussian::Gaussian;
pub use halton::Halton;
pub use uniform::Uniform;

use crate::budget::Budget;
use crate::rng::Rng;
use crate::space::JointSpace;
use crate::validity::Validity;

/// Draws configurations.
pub trait Sampler {
    /// A short name (`uniform`, `gaussian`, `bridge`, `halton`).
    fn name(&self) -> &'static str;

    /// A configuration, not checked (RL's `generate`).
    fn generate(&mut self, space: &JointSpace, rng: &mut Rng, out: &mut [f64]);

    /// A valid configuration (RL's `generateCollisionFree`); `false` if the budget ran out
    /// first. The default draws with [`Sampler::generate`] until one is valid.
    fn generate_valid(
        &mut self,
        space: &JointSpace,
        validity: &mut dyn Validity,
        rng: &mut Rng,
        budget: &Budget,
        out: &mut [f64],
    ) -> bool {
        let mut i = 0u64;
        loop {
            if i.is_multiple_of(4) && budget.expired() {
                return false;
            }
            i += 1;
            self.generate(space, rng, out);
            if validity.is_valid(out) {
                return true;
            }
        }
    }
}

/// Which sampler, with its settings.
#[derive(Clone, Debug, PartialEq)]
pub enum SamplerKind {
    /// [`Uniform`].
    Uniform,
    /// [`Gaussian`] with standard deviations per coordinate (`None`: a tenth of each range).
    Gaussian(Option<Vec<f64>>),
    /// [`Bridge`] with standard deviations and the ratio of bridge samples.
    Bridge(Option<Vec<f64>>, f64),
    /// [`Halton`].
    Halton,
}

impl SamplerKind {
    /// The sampler for `space`, seeded by `seed` where it needs one (Halton's start index).
    pub fn build(&self, space: &JointSpace, seed: u64) -> Box<dyn Sampler> {
        match self {
            Self::Uniform => Box::new(Uniform),
            Self::Gaussian(s) => Box::new(Gaussian::new(sigma_or_default(space, s))),
            Self::Bridge(s, ratio) => Box::new(Bridge::new(sigma_or_default(space, s), *ratio)),
            Self::Halton => Box::new(Halton::new(space, seed)),
        }
    }

    /// A short name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Uniform => "uniform",
            Self::Gaussian(_) => "gaussian",
            Self::Bridge(..) => "bridge",
            Self::Halton => "halton",
        }
    }
}

/// The given deviations, or a tenth of each coordinate's range (π/10 for circles and
/// rotations).
pub fn sigma_or_default(space: &JointSpace, sigma: &Option<Vec<f64>>) -> Vec<f64> {
    if let Some(s) = sigma {
        return s.clone();
    }
    space
        .coordinates()
        .iter()
        .map(|c| match c.topology {
            crate::space::Topology::Interval { lower, upper } => 0.1 * (upper - lower),
            _ => 0.1 * std::f64::consts::PI,
        })
        .collect()
}
