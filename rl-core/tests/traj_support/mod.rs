//! Helpers shared by the trajectory tests: finite-difference checks and approximate asserts.
#![allow(dead_code)]

use rl_core::traj::Trajectory;

/// Asserts `|a - b| ≤ tol · (1 + |b|)` per element, naming the element.
#[track_caller]
pub fn assert_close<const D: usize>(what: &str, a: [f64; D], b: [f64; D], tol: f64) {
    for i in 0..D {
        assert!(
            (a[i] - b[i]).abs() <= tol * (1.0 + b[i].abs()),
            "{what}[{i}]: {} vs {} (diff {:e}, tol {tol:e})",
            a[i],
            b[i],
            a[i] - b[i]
        );
    }
}

/// Checks derivative orders 1..=max_order against central differences of the order below at
/// `n` interior times (away from segment boundaries by `h`, which `avoid` lists).
#[track_caller]
pub fn check_finite_differences<const D: usize, T: Trajectory<D>>(
    traj: &T,
    max_order: usize,
    n: usize,
    avoid: &[f64],
) {
    let duration = traj.duration();
    let h = 2e-7 * duration.max(1e-3);
    for k in 1..n {
        let t = duration * k as f64 / n as f64 + 0.37 * h;
        if avoid.iter().any(|b| (t - b).abs() < 4.0 * h) || t + h >= duration {
            continue;
        }
        for order in 1..=max_order {
            let up = traj.derivative(t + h, order - 1);
            let down = traj.derivative(t - h, order - 1);
            let exact = traj.derivative(t, order);
            let scale = up
                .iter()
                .chain(down.iter())
                .fold(1.0f64, |m, x| m.max(x.abs()));
            for i in 0..D {
                let fd = (up[i] - down[i]) / (2.0 * h);
                assert!(
                    (fd - exact[i]).abs() <= 1e-7 * (scale / duration.max(1e-3) + exact[i].abs()),
                    "order {order} axis {i} at t={t}: exact {} vs fd {fd}",
                    exact[i]
                );
            }
        }
    }
}

/// `sample` must agree with `derivative` for orders 0..=3.
#[track_caller]
pub fn check_sample_matches<const D: usize, T: Trajectory<D>>(traj: &T, n: usize) {
    for k in 0..=n {
        let t = traj.duration() * k as f64 / n as f64;
        let s = traj.sample(t);
        for (order, got) in [s.position, s.velocity, s.acceleration, s.jerk]
            .into_iter()
            .enumerate()
        {
            assert_close(
                "sample vs derivative",
                got,
                traj.derivative(t, order),
                1e-12,
            );
        }
    }
}

/// A small deterministic generator (xorshift) for tests that need many random inputs.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}
