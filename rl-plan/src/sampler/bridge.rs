//! Bridge sampling in narrow passages (RL's `BridgeSampler`; Hsu, Jiang, Reif and Sun, ICRA
//! 2003): two invalid points a Gaussian step apart whose midpoint is valid. With probability
//! `1 − ratio` (RL's default ratio 5/6) a plain uniform valid point is returned instead.
//! Its [`super::Sampler`] implementation is the Gaussian sampler's ([`super::gaussian`]).

use super::Sampler;
use super::gaussian::{Search, near_obstacles};

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

    /// The search of [`Sampler::generate_valid`].
    fn search(&mut self, s: Search<'_>, out: &mut [f64]) -> bool {
        if s.rng.uniform() > self.ratio {
            return super::Uniform.generate_valid(s.space, s.validity, s.rng, s.budget, out);
        }
        self.a.resize(s.space.nq(), 0.0);
        self.b.resize(s.space.nq(), 0.0);
        loop {
            if s.budget.expired() {
                return false;
            }
            s.space.sample_uniform(s.rng, &mut self.a);
            if s.validity.is_valid(&self.a) {
                continue;
            }
            s.space
                .sample_gaussian(s.rng, &self.a, &self.sigma, &mut self.b);
            if s.validity.is_valid(&self.b) {
                continue;
            }
            s.space.interpolate(&self.a, &self.b, 0.5, out);
            if s.validity.is_valid(out) {
                return true;
            }
        }
    }
}

near_obstacles!(Bridge, "bridge");
