//! Closest points between segments and points: the two primitives of the capsule kernel.
//!
//! A capsule is the set of points within `radius` of a segment, so capsule–capsule distance is
//! segment–segment distance minus both radii, and capsule–sphere distance is point–segment
//! distance minus both radii. Both closest-point problems are solved in closed form after
//! Ericson, *Real-Time Collision Detection* (2005), §5.1.2 (point–segment) and §5.1.9
//! (segment–segment), with degenerate (zero-length) segments handled as points. No loops, no
//! allocation, no panics; NaN inputs give NaN outputs.

use glam::DVec3;

/// Squared lengths below this count as zero (a segment this short is a point).
const TINY: f64 = 1e-24;

/// The parameter `t ∈ [0, 1]` of the point of segment `a + t·d` closest to `p`, given
/// `inv_dd = 1 / (d·d)` (0 for a degenerate segment).
#[inline(always)]
pub fn point_segment_parameter(p: DVec3, a: DVec3, d: DVec3, inv_dd: f64) -> f64 {
    ((p - a).dot(d) * inv_dd).clamp(0.0, 1.0)
}

/// `1 / (d·d)`, or 0 when the segment is a point.
#[inline(always)]
pub fn inverse_length_squared(d: DVec3) -> f64 {
    let dd = d.dot(d);
    if dd > TINY { 1.0 / dd } else { 0.0 }
}

/// The closest points of segments `p1 + s·d1` and `p2 + t·d2` (`s, t ∈ [0, 1]`): returns
/// `(s, t)`.
#[inline]
pub fn segment_segment_parameters(p1: DVec3, d1: DVec3, p2: DVec3, d2: DVec3) -> (f64, f64) {
    let r = p1 - p2;
    let a = d1.dot(d1);
    let e = d2.dot(d2);
    let f = d2.dot(r);
    if a <= TINY && e <= TINY {
        return (0.0, 0.0);
    }
    if a <= TINY {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(r);
    if e <= TINY {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    // Parallel segments (denom = 0): any s works; take 0 and let the clamping below fix t.
    let mut s = if denom > TINY * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(p1: DVec3, d1: DVec3, p2: DVec3, d2: DVec3) -> f64 {
        let mut best = f64::INFINITY;
        let n = 400;
        for i in 0..=n {
            let a = p1 + d1 * (i as f64 / n as f64);
            let t = point_segment_parameter(a, p2, d2, inverse_length_squared(d2));
            best = best.min((a - (p2 + d2 * t)).length());
        }
        best
    }

    #[test]
    fn crossing_segments_meet() {
        let (s, t) = segment_segment_parameters(
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, -1.0, 1.0),
            DVec3::new(0.0, 2.0, 0.0),
        );
        assert!((s - 0.5).abs() < 1e-15 && (t - 0.5).abs() < 1e-15);
    }

    #[test]
    fn parallel_and_degenerate_segments() {
        // Parallel, overlapping in x: distance 1.
        let (p1, d1) = (DVec3::ZERO, DVec3::X);
        let (p2, d2) = (DVec3::new(0.5, 1.0, 0.0), DVec3::X * 2.0);
        let (s, t) = segment_segment_parameters(p1, d1, p2, d2);
        assert!(((p1 + d1 * s) - (p2 + d2 * t)).length() - 1.0 < 1e-15);
        // A point against a segment.
        let (s, t) = segment_segment_parameters(DVec3::new(3.0, 1.0, 0.0), DVec3::ZERO, p1, d1);
        assert_eq!((s, t), (0.0, 1.0));
        // Two points.
        assert_eq!(
            segment_segment_parameters(DVec3::ONE, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO),
            (0.0, 0.0)
        );
    }

    #[test]
    fn agrees_with_brute_force_sampling() {
        let mut rng = rl_core::algo::ik::SplitMix64::new(0x1234_5678_9abc_def0);
        let mut r = || rng.next_f64() * 2.0 - 1.0;
        for _ in 0..500 {
            let mut v = || DVec3::new(r(), r(), r());
            let (p1, d1, p2, d2) = (v(), v(), v(), v());
            let (s, t) = segment_segment_parameters(p1, d1, p2, d2);
            let d = ((p1 + d1 * s) - (p2 + d2 * t)).length();
            let b = brute(p1, d1, p2, d2);
            // The sampled minimum can only be larger; it is close for 400 samples.
            assert!(d <= b + 1e-12, "{d} > {b}");
            assert!(b - d < 2e-2, "{d} vs {b}");
        }
    }
}
