//! The sequential order (RL's `SequentialVerifier`): interior points from start to end.

/// Appends `j / n` for `j = 1 … n−1`.
pub fn fractions(n: usize, out: &mut Vec<f64>) {
    out.extend((1..n).map(|j| j as f64 / n as f64));
}
