//! The Halton sequence (Halton 1960): point `n` has coordinate `i` equal to the radical inverse
//! of `n` in the `i`-th prime base. Low discrepancy spreads an RRT's samples more evenly than
//! random ones; VAMP samples this way by default (with bases from 3 upwards, as here). The seed
//! sets the start index, so different seeds give different (shifted) sequences.

use super::Sampler;
use crate::rng::Rng;
use crate::space::JointSpace;

const PRIMES: [u64; 24] = [
    3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97,
];

/// The Halton sampler: per dimension the digits of the index in its base, incremented like
/// an odometer, so each point costs O(1) on average instead of a division per digit.
#[derive(Clone, Debug)]
pub struct Halton {
    index: u64,
    cube: Vec<f64>,
    digits: Vec<Vec<u64>>,
    /// `b^-(k+1)` per dimension and digit position.
    weights: Vec<Vec<f64>>,
}

/// The radical inverse of `n` in base `b`.
fn radical_inverse(mut n: u64, b: u64) -> f64 {
    let inv = 1.0 / b as f64;
    let (mut x, mut f) = (0.0, inv);
    while n > 0 {
        x += (n % b) as f64 * f;
        n /= b;
        f *= inv;
    }
    x
}

impl Halton {
    /// The sequence for `space` from index `seed + 1`.
    pub fn new(space: &JointSpace, seed: u64) -> Self {
        let index = seed.wrapping_add(1);
        let dims = space.cube_dimension().min(PRIMES.len());
        let mut digits = Vec::with_capacity(dims);
        let mut weights = Vec::with_capacity(dims);
        let mut cube = vec![0.0; space.cube_dimension()];
        for (d, &b) in PRIMES.iter().enumerate().take(dims) {
            // The digits of `index` in base b, least significant first.
            let (mut n, mut ds, mut ws, mut w) = (index, Vec::new(), Vec::new(), 1.0 / b as f64);
            while n > 0 {
                ds.push(n % b);
                n /= b;
            }
            for _ in 0..64 {
                ws.push(w);
                w /= b as f64;
                if w == 0.0 {
                    break;
                }
            }
            cube[d] = radical_inverse(index, b);
            digits.push(ds);
            weights.push(ws);
        }
        Self {
            index,
            cube,
            digits,
            weights,
        }
    }

    /// Moves to the next index: adds one to every dimension's digits, updating its value.
    fn advance(&mut self) {
        self.index = self.index.wrapping_add(1);
        for (d, &b) in PRIMES.iter().enumerate().take(self.digits.len()) {
            let (ds, ws) = (&mut self.digits[d], &self.weights[d]);
            let mut x = self.cube[d];
            let mut k = 0;
            loop {
                if k == ds.len() {
                    ds.push(0);
                }
                ds[k] += 1;
                let w = ws.get(k).copied().unwrap_or(0.0);
                if ds[k] < b {
                    x += w;
                    break;
                }
                x -= (b - 1) as f64 * w;
                ds[k] = 0;
                k += 1;
            }
            self.cube[d] = x.clamp(0.0, 1.0 - f64::EPSILON);
        }
    }
}

impl Sampler for Halton {
    fn name(&self) -> &'static str {
        "halton"
    }

    fn generate(&mut self, space: &JointSpace, rng: &mut Rng, out: &mut [f64]) {
        if self.cube.len() > PRIMES.len() {
            // More dimensions than bases: fall back to uniform for the rest.
            for x in &mut self.cube[PRIMES.len()..] {
                *x = rng.uniform();
            }
        }
        space.from_unit_cube(&self.cube, out);
        self.advance();
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn odometer_matches_radical_inverse() {
        let space = crate::space::JointSpace::new(
            (0..7)
                .map(|i| {
                    (
                        format!("j{i}"),
                        crate::space::Topology::Interval {
                            lower: 0.0,
                            upper: 1.0,
                        },
                    )
                })
                .collect(),
        )
        .unwrap();
        let mut h = super::Halton::new(&space, 41);
        let mut rng = crate::rng::Rng::seed_from(0);
        let mut q = [0.0; 7];
        for n in 42..3000u64 {
            super::Sampler::generate(&mut h, &space, &mut rng, &mut q);
            for (d, &b) in super::PRIMES.iter().enumerate().take(7) {
                assert!(
                    (q[d] - super::radical_inverse(n, b)).abs() < 1e-12,
                    "n={n} d={d}"
                );
            }
        }
    }

    #[test]
    fn radical_inverse_base_3() {
        let xs: Vec<f64> = (1..=4).map(|n| super::radical_inverse(n, 3)).collect();
        let want = [1.0 / 3.0, 2.0 / 3.0, 1.0 / 9.0, 4.0 / 9.0];
        for (x, w) in xs.iter().zip(want) {
            assert!((x - w).abs() < 1e-15);
        }
    }
}
