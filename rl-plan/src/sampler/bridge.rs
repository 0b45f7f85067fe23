//! Bridge sampling in narrow passages (RL's `BridgeSampler`; Hsu, Jiang, Reif and Sun, ICRA
//! 2003): two invalid points a Gaussian step apart whose midpoint is valid. With probability
//! `1 − ratio` (RL's default ratio 5/6) a plain uniform valid point is returned instead.

use super::Sampler;
use crate::budget::Budget;
use crate::rng::Rng;
use crate::space::JointSpace;
use crate::validity::Validity;

/// The bridge sampler.
#[derive(Clone, Debug)]
pub struct Bridge {
    /// Standard deviation per coordinate of the bridge's second end.
    pub sigma: Vec<f64>,
    /// Probability of a bridge sample (else uniform).
    pub ratio: f64,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl Bridge {
    /// A sampler with deviations `sigma` and bridge probability `ratio`.
    pub fn new(sigma: Vec<f64>, ratio: f64) -> Self {
        Self {
            sigma,
            ratio,
            a: Vec::new(),
            b: Vec::new(),
        }
    }
}

impl Sampler for Bridge {
    fn name(&self) -> &'static str {
        "bridge"
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
        if rng.uniform() > self.ratio {
            return super::Uniform.generate_valid(space, validity, rng, budget, out);
        }
        self.a.resize(space.nq(), 0.0);
        self.b.resize(space.nq(), 0.0);
        loop {
            if budget.expired() {
                return false;
            }
            space.sample_uniform(rng, &mut self.a);
            if validity.is_valid(&self.a) {
                continue;
            }
            space.sample_gaussian(rng, &self.a, &self.sigma, &mut self.b);
            if validity.is_valid(&self.b) {
                continue;
            }
            space.interpolate(&self.a, &self.b, 0.5, out);
            if validity.is_valid(out) {
                return true;
            }
        }
    }
}
