//! Gaussian sampling near obstacle boundaries (RL's `GaussianSampler`; Boor, Overmars and van
//! der Stappen, ICRA 1999): of a uniform point and a Gaussian neighbour of it, when exactly one
//! is valid, that one is returned.

use super::Sampler;
use crate::budget::Budget;
use crate::rng::Rng;
use crate::space::JointSpace;
use crate::validity::Validity;

/// The Gaussian sampler.
#[derive(Clone, Debug)]
pub struct Gaussian {
    /// Standard deviation per coordinate.
    pub sigma: Vec<f64>,
    scratch: Vec<f64>,
}

impl Gaussian {
    /// A sampler with deviations `sigma` (one per coordinate).
    pub fn new(sigma: Vec<f64>) -> Self {
        Self {
            sigma,
            scratch: Vec::new(),
        }
    }
}

impl Sampler for Gaussian {
    fn name(&self) -> &'static str {
        "gaussian"
    }

    fn generate(&mut self, space: &JointSpace, rng: &mut Rng, out: &mut [f64]) {
        space.sample_uniform(rng, out);
    }

    fn generate_valid(
        &mut self,
        space: &JointSpace,
        validity: &mut dyn Validity,
        rng: &mut Rng,
        budget: &Budget,
        out: &mut [f64],
    ) -> bool {
        let mut near = std::mem::take(&mut self.scratch);
        near.resize(space.nq(), 0.0);
        let ok = loop {
            if budget.expired() {
                break false;
            }
            space.sample_uniform(rng, out);
            space.sample_gaussian(rng, out, &self.sigma, &mut near);
            let (a, b) = (validity.is_valid(out), validity.is_valid(&near));
            if a && !b {
                break true;
            }
            if !a && b {
                out.copy_from_slice(&near);
                break true;
            }
        };
        self.scratch = near;
        ok
    }
}
