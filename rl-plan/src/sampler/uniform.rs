//! Uniform sampling over the space (RL's `UniformSampler`).

use super::Sampler;
use crate::rng::Rng;
use crate::space::JointSpace;

/// Uniform over the space: see [`JointSpace::sample_uniform`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Uniform;

impl Sampler for Uniform {
    fn name(&self) -> &'static str {
        "uniform"
    }

    fn generate(&mut self, space: &JointSpace, rng: &mut Rng, out: &mut [f64]) {
        space.sample_uniform(rng, out);
    }
}
