//! Gaussian sampling near obstacle boundaries (RL's `GaussianSampler`; Boor, Overmars and van
//! der Stappen, ICRA 1999): of a uniform point and a Gaussian neighbour of it, when exactly one
//! is valid, that one is returned.
//!
//! Also the [`super::Sampler`] implementation it shares with the bridge sampler
//! ([`super::Bridge`], which RL derives from `GaussianSampler`): `generate` draws uniformly
//! (RL derives both from `UniformSampler`), `generate_valid` is the sampler's own search.

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

    /// The search of [`super::Sampler::generate_valid`].
    fn search(&mut self, s: Search<'_>, out: &mut [f64]) -> bool {
        let mut near = std::mem::take(&mut self.scratch);
        near.resize(s.space.nq(), 0.0);
        let ok = loop {
            if s.budget.expired() {
                break false;
            }
            s.space.sample_uniform(s.rng, out);
            s.space.sample_gaussian(s.rng, out, &self.sigma, &mut near);
            let (a, b) = (s.validity.is_valid(out), s.validity.is_valid(&near));
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

/// What a search for a valid sample works with: the arguments of
/// [`super::Sampler::generate_valid`].
pub(super) struct Search<'a> {
    pub(super) space: &'a JointSpace,
    pub(super) validity: &'a mut dyn Validity,
    pub(super) rng: &'a mut Rng,
    pub(super) budget: &'a Budget,
}

/// Implements [`super::Sampler`] for a sampler near obstacles named `$name`: `generate` draws
/// uniformly, `generate_valid` is the type's `search(&mut self, Search, out) -> bool`.
macro_rules! near_obstacles {
    ($sampler:ty, $name:literal) => {
        impl $crate::sampler::Sampler for $sampler {
            fn name(&self) -> &'static str {
                $name
            }

            fn generate(
                &mut self,
                space: &$crate::space::JointSpace,
                rng: &mut $crate::rng::Rng,
                out: &mut [f64],
            ) {
                space.sample_uniform(rng, out);
            }

            fn generate_valid(
                &mut self,
                space: &$crate::space::JointSpace,
                validity: &mut dyn $crate::validity::Validity,
                rng: &mut $crate::rng::Rng,
                budget: &$crate::budget::Budget,
                out: &mut [f64],
            ) -> bool {
                let search = $crate::sampler::gaussian::Search {
                    space,
                    validity,
                    rng,
                    budget,
                };
                self.search(search, out)
            }
        }
    };
}

pub(super) use near_obstacles;

near_obstacles!(Gaussian, "gaussian");
