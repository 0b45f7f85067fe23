//! Drive units ↔ joint units, per axis: positions in encoder counts (0x6064, 0x607A),
//! velocities in counts/s (0x606C, 0x60FF), torques in thousandths of the motor's rated
//! torque (0x6071, 0x6077, 0x60B2; rated torque in mN·m from 0x6076).
//!
//! A rotary joint: `q [rad] = counts / (counts_per_rev · gear_ratio) · 2π`, where
//! `gear_ratio` is motor revolutions per joint revolution. A linear joint (`lead_m` set):
//! `q [m] = counts / (counts_per_rev · gear_ratio) · lead_m`, with `lead_m` the travel per
//! output revolution. Joint torque (or force) = motor torque · gear ratio (· 2π / lead for a
//! linear joint), losses ignored: `τ [N·m] = ‰ / 1000 · rated_torque_nm · gear_ratio`.

/// How one axis converts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisUnits {
    /// Encoder counts per motor revolution.
    pub counts_per_rev: f64,
    /// Motor revolutions per joint revolution (or per output revolution of a linear axis).
    pub gear_ratio: f64,
    /// Travel per output revolution in m for a linear joint, `None` for a rotary one.
    pub lead_m: Option<f64>,
    /// The motor's rated torque in N·m (0x6076 / 1000).
    pub rated_torque_nm: f64,
}

impl Default for AxisUnits {
    /// A 20-bit encoder on a direct drive rated 1 N·m.
    fn default() -> Self {
        Self {
            counts_per_rev: f64::from(1u32 << 20),
            gear_ratio: 1.0,
            lead_m: None,
            rated_torque_nm: 1.0,
        }
    }
}

impl AxisUnits {
    /// A robot joint: a 20-bit encoder on a motor rated 1 N·m behind a 100:1 gear (torques to
    /// ±3 276 N·m in steps of 0.1 N·m; ±20 joint revolutions in an `i32` of counts).
    pub const GEARED_100: Self = Self {
        counts_per_rev: 1_048_576.0,
        gear_ratio: 100.0,
        lead_m: None,
        rated_torque_nm: 1.0,
    };

    /// Joint units (rad or m) per count.
    pub fn per_count(&self) -> f64 {
        let per_output_rev = self.lead_m.unwrap_or(core::f64::consts::TAU);
        per_output_rev / (self.counts_per_rev * self.gear_ratio)
    }

    /// Whether the factors are finite and positive.
    pub fn is_valid(&self) -> bool {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        ok(self.counts_per_rev)
            && ok(self.gear_ratio)
            && ok(self.rated_torque_nm)
            && self.lead_m.is_none_or(ok)
    }

    /// Counts to joint position.
    pub fn position(&self, counts: i32) -> f64 {
        f64::from(counts) * self.per_count()
    }

    /// Joint position to counts (rounded, saturated to `i32`).
    pub fn position_counts(&self, q: f64) -> i32 {
        saturate_i32(q / self.per_count())
    }

    /// Counts/s to joint velocity.
    pub fn velocity(&self, counts_per_s: i32) -> f64 {
        f64::from(counts_per_s) * self.per_count()
    }

    /// Joint velocity to counts/s.
    pub fn velocity_counts(&self, qd: f64) -> i32 {
        saturate_i32(qd / self.per_count())
    }

    /// Joint torque (or force) per thousandth of the rated motor torque.
    pub fn per_permille(&self) -> f64 {
        let per_rev = match self.lead_m {
            Some(lead) => core::f64::consts::TAU / lead,
            None => 1.0,
        };
        self.rated_torque_nm * self.gear_ratio * per_rev / 1000.0
    }

    /// Thousandths of rated torque to joint torque.
    pub fn torque(&self, permille: i16) -> f64 {
        f64::from(permille) * self.per_permille()
    }

    /// Joint torque to thousandths of rated torque (rounded, saturated to `i16`).
    pub fn torque_permille(&self, tau: f64) -> i16 {
        let v = libm::round(tau / self.per_permille());
        if v.is_nan() {
            0
        } else {
            v.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
        }
    }

    /// Half a count in joint units: how far a reported position can be from the truth.
    pub fn position_resolution(&self) -> f64 {
        0.5 * self.per_count()
    }
}

fn saturate_i32(v: f64) -> i32 {
    let v = libm::round(v);
    if v.is_nan() {
        0
    } else {
        v.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_radians_and_torque() {
        let u = AxisUnits {
            counts_per_rev: 4096.0,
            gear_ratio: 100.0,
            lead_m: None,
            rated_torque_nm: 0.64,
        };
        // One joint revolution is 409 600 counts.
        assert_eq!(u.position_counts(core::f64::consts::TAU), 409_600);
        assert!((u.position(204_800) - core::f64::consts::PI).abs() < 1e-12);
        assert!(
            (u.position(u.position_counts(1.234_567)) - 1.234_567).abs() <= u.position_resolution()
        );
        // 1000 ‰ of 0.64 N·m through a 100:1 gear: 64 N·m at the joint.
        assert!((u.torque(1000) - 64.0).abs() < 1e-12);
        assert_eq!(u.torque_permille(32.0), 500);
        assert_eq!(u.torque_permille(1e9), i16::MAX);
        assert_eq!(u.position_counts(f64::NAN), 0);
        let screw = AxisUnits {
            lead_m: Some(0.005),
            gear_ratio: 1.0,
            ..u
        };
        assert!((screw.position(4096) - 0.005).abs() < 1e-15);
        assert!(
            u.is_valid()
                && !AxisUnits {
                    gear_ratio: 0.0,
                    ..u
                }
                .is_valid()
        );
    }
}
