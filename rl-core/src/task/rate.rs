//! A torque-rate limit: each joint's command moves at most `max_step` from the previous one.

/// Limits `tau` to within `max_step` (N·m) of `previous`, joint by joint; returns how many
/// joints were limited. A non-finite `tau[k]` is replaced by `previous[k]` (and counted); a
/// `max_step` that is negative or NaN counts as 0. Never panics. The slices should have the
/// same length (the shorter one decides otherwise).
///
/// ```
/// let mut tau = [5.0, -0.2, 1.0];
/// assert_eq!(rl_core::task::limit_rate(&[0.0, 0.0, 0.9], &mut tau, 1.0), 1);
/// assert_eq!(tau, [1.0, -0.2, 1.0]);
/// ```
pub fn limit_rate(previous: &[f64], tau: &mut [f64], max_step: f64) -> usize {
    let step = if max_step >= 0.0 { max_step } else { 0.0 };
    let mut limited = 0;
    for (t, p) in tau.iter_mut().zip(previous) {
        // max/min, not clamp: no panic whatever the bounds.
        let clamped = if t.is_finite() {
            t.max(p - step).min(p + step)
        } else {
            *p
        };
        if clamped != *t {
            limited += 1;
            *t = clamped;
        }
    }
    limited
}
