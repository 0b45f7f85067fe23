//! Drive units ↔ joint units, per axis, as CiA 402's factor group defines them (CiA 402-2 /
//! IEC 61800-7-201 §6.3 "Factor group"):
//!
//! - 0x608F position encoder resolution `R` = encoder increments per motor revolution;
//! - 0x6091 gear ratio `G` = motor shaft revolutions per driving shaft revolution;
//! - 0x6092 feed constant `F` = feed, in position units, per driving shaft revolution;
//! - position factor = `R · G / F`: increments per position unit.
//!
//! Positions (0x6064, 0x607A) are in position units, velocities (0x606C, 0x60FF) in position
//! units per second, torques (0x6071, 0x6077, 0x60B2) in thousandths of the motor's rated
//! torque (0x6076, mN·m). The driving shaft is the joint: a rotary joint turns once per `F`
//! position units, `q [rad] = units / F · 2π`; a linear joint (`lead_m` set, the travel per
//! driving shaft revolution, which no CiA 402 object carries) moves `lead_m` per `F` units.
//! Joint torque (or force) = motor torque · `G` (· 2π / lead for a linear joint), losses ignored:
//! `τ [N·m] = ‰ / 1000 · rated_torque_nm · G`. A drive whose position unit is the encoder
//! increment has `F = R · G` ([`AxisUnits::feed`] `None`).
//!
//! A master reads `R`, `G`, `F` and the rated torque from each drive before it enables it
//! ([`UnitsOverride::resolve`]), or refuses to start ([`UnitsError`]) unless the user gives
//! them ([`UnitsOverride`]): units are never assumed.

use core::fmt;

use super::object::{self as obj, Object};

/// How one axis converts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisUnits {
    /// Encoder increments per motor revolution (0x608F).
    pub counts_per_rev: f64,
    /// Motor revolutions per joint revolution, or per driving shaft revolution of a linear axis
    /// (0x6091).
    pub gear_ratio: f64,
    /// Position units (of 0x6064, 0x607A) per joint (driving shaft) revolution (0x6092); `None`:
    /// the position unit is the encoder increment, `counts_per_rev · gear_ratio` per revolution.
    pub feed: Option<f64>,
    /// Travel per driving shaft revolution in m for a linear joint, `None` for a rotary one.
    pub lead_m: Option<f64>,
    /// The motor's rated torque in N·m (0x6076 / 1000).
    pub rated_torque_nm: f64,
}

impl Default for AxisUnits {
    /// A 20-bit encoder on a direct drive rated 1 N·m, position units = increments.
    fn default() -> Self {
        Self {
            counts_per_rev: f64::from(1u32 << 20),
            gear_ratio: 1.0,
            feed: None,
            lead_m: None,
            rated_torque_nm: 1.0,
        }
    }
}

impl AxisUnits {
    /// A robot joint: a 20-bit encoder on a motor rated 1 N·m behind a 100:1 gear, position
    /// units = increments (torques to ±3 276 N·m in steps of 0.1 N·m; ±20 joint revolutions in
    /// an `i32` of counts).
    pub const GEARED_100: Self = Self {
        counts_per_rev: 1_048_576.0,
        gear_ratio: 100.0,
        feed: None,
        lead_m: None,
        rated_torque_nm: 1.0,
    };

    /// Position units per joint (driving shaft) revolution: the feed constant.
    pub fn units_per_rev(&self) -> f64 {
        self.feed.unwrap_or(self.counts_per_rev * self.gear_ratio)
    }

    /// Joint units (rad or m) per position unit ("count").
    pub fn per_count(&self) -> f64 {
        let per_output_rev = self.lead_m.unwrap_or(core::f64::consts::TAU);
        per_output_rev / self.units_per_rev()
    }

    /// Joint units (rad or m) per encoder increment.
    pub fn per_increment(&self) -> f64 {
        let per_output_rev = self.lead_m.unwrap_or(core::f64::consts::TAU);
        per_output_rev / (self.counts_per_rev * self.gear_ratio)
    }

    /// Whether the factors are finite and positive.
    pub fn is_valid(&self) -> bool {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        ok(self.counts_per_rev)
            && ok(self.gear_ratio)
            && ok(self.rated_torque_nm)
            && self.feed.is_none_or(ok)
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

    /// How far a reported position can be from the truth: half a position unit, or half an
    /// encoder increment at the joint where that is coarser.
    pub fn position_resolution(&self) -> f64 {
        0.5 * self.per_count().max(self.per_increment())
    }
}

/// `value` as the `(numerator, denominator)` of 32-bit integers a factor-group object (0x608F,
/// 0x6091, 0x6092) holds: exact for a decimal with up to six places; `None` for a value that
/// does not fit.
pub fn ratio(value: f64) -> Option<(u32, u32)> {
    let mut d = 1u32;
    while d <= 1_000_000 {
        let n = value * f64::from(d);
        if n.is_finite()
            && n >= 1.0
            && n <= f64::from(u32::MAX)
            && libm::fabs(n - libm::round(n)) < 1e-9 * n
        {
            return Some((libm::round(n) as u32, d));
        }
        d *= 10;
    }
    None
}

fn saturate_i32(v: f64) -> i32 {
    let v = libm::round(v);
    if v.is_nan() {
        0
    } else {
        v.clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
    }
}

/// Units the user gives for an axis: each value given replaces the drive's object, each one
/// left `None` is read from the drive ([`resolve`](Self::resolve)). [`UnitsOverride::NONE`]
/// reads everything; [`UnitsOverride::all`] reads nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UnitsOverride {
    /// Replaces 0x608F (encoder increments per motor revolution).
    pub counts_per_rev: Option<f64>,
    /// Replaces 0x6091 (motor revolutions per joint revolution).
    pub gear_ratio: Option<f64>,
    /// Replaces 0x6092 (position units per joint revolution).
    pub feed: Option<f64>,
    /// Replaces 0x6076 (the motor's rated torque, N·m).
    pub rated_torque_nm: Option<f64>,
    /// Travel per driving shaft revolution of a linear joint, m (no object carries it).
    pub lead_m: Option<f64>,
}

impl UnitsOverride {
    /// Nothing given: every unit object is read from the drive.
    pub const NONE: Self = Self {
        counts_per_rev: None,
        gear_ratio: None,
        feed: None,
        rated_torque_nm: None,
        lead_m: None,
    };

    /// All of `units` given: nothing is read (position units = increments when its feed is
    /// `None`).
    pub fn all(units: AxisUnits) -> Self {
        Self {
            counts_per_rev: Some(units.counts_per_rev),
            gear_ratio: Some(units.gear_ratio),
            feed: Some(units.units_per_rev()),
            rated_torque_nm: Some(units.rated_torque_nm),
            lead_m: units.lead_m,
        }
    }

    /// Whether nothing is given.
    pub fn is_empty(&self) -> bool {
        *self == Self::NONE
    }

    /// The objects to read for the values not given, in the order [`resolve`](Self::resolve)
    /// asks for them.
    pub fn objects_to_read(&self) -> impl Iterator<Item = Object> + '_ {
        let pairs: [(bool, [Option<Object>; 2]); 4] = [
            (
                self.counts_per_rev.is_none(),
                [
                    Some(obj::ENCODER_INCREMENTS),
                    Some(obj::ENCODER_MOTOR_REVOLUTIONS),
                ],
            ),
            (
                self.gear_ratio.is_none(),
                [
                    Some(obj::GEAR_MOTOR_REVOLUTIONS),
                    Some(obj::GEAR_SHAFT_REVOLUTIONS),
                ],
            ),
            (
                self.feed.is_none(),
                [Some(obj::FEED), Some(obj::FEED_SHAFT_REVOLUTIONS)],
            ),
            (
                self.rated_torque_nm.is_none(),
                [Some(obj::MOTOR_RATED_TORQUE), None],
            ),
        ];
        pairs
            .into_iter()
            .filter(|(read, _)| *read)
            .flat_map(|(_, objects)| objects.into_iter().flatten())
    }

    /// The axis's units: the values given, and the others from `read` (an SDO upload of the
    /// object, as an unsigned integer). The first object that cannot be read, or holds zero, is
    /// the error; a value given that is not finite and positive is refused too.
    pub fn resolve<E>(
        &self,
        mut read: impl FnMut(Object) -> Result<u64, E>,
    ) -> Result<AxisUnits, UnitsError<E>> {
        let mut ratio = |num: Object, den: Object| -> Result<f64, UnitsError<E>> {
            let mut get = |o: Object| match read(o) {
                Ok(0) => Err(UnitsError::Zero { object: o }),
                Ok(v) => Ok(v as f64),
                Err(error) => Err(UnitsError::Unreadable { object: o, error }),
            };
            let n = get(num)?;
            let d = get(den)?;
            Ok(n / d)
        };
        let given = |v: Option<f64>, what: &'static str| match v {
            Some(v) if !(v.is_finite() && v > 0.0) => Err(UnitsError::Given { what, value: v }),
            v => Ok(v),
        };
        let counts_per_rev = match given(self.counts_per_rev, "counts per revolution")? {
            Some(v) => v,
            None => ratio(obj::ENCODER_INCREMENTS, obj::ENCODER_MOTOR_REVOLUTIONS)?,
        };
        let gear_ratio = match given(self.gear_ratio, "gear ratio")? {
            Some(v) => v,
            None => ratio(obj::GEAR_MOTOR_REVOLUTIONS, obj::GEAR_SHAFT_REVOLUTIONS)?,
        };
        let feed = match given(self.feed, "feed")? {
            Some(v) => v,
            None => ratio(obj::FEED, obj::FEED_SHAFT_REVOLUTIONS)?,
        };
        let rated_torque_nm = match given(self.rated_torque_nm, "rated torque")? {
            Some(v) => v,
            None => match read(obj::MOTOR_RATED_TORQUE) {
                Ok(0) => {
                    return Err(UnitsError::Zero {
                        object: obj::MOTOR_RATED_TORQUE,
                    });
                }
                Ok(mnm) => mnm as f64 / 1000.0,
                Err(error) => {
                    return Err(UnitsError::Unreadable {
                        object: obj::MOTOR_RATED_TORQUE,
                        error,
                    });
                }
            },
        };
        let lead_m = given(self.lead_m, "lead")?;
        Ok(AxisUnits {
            counts_per_rev,
            gear_ratio,
            feed: Some(feed),
            lead_m,
            rated_torque_nm,
        })
    }
}

/// Why an axis's units cannot be had: the master then refuses to start (nothing is enabled).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UnitsError<E> {
    /// The drive does not give the object (it lacks it, or the transfer failed).
    Unreadable {
        /// The object.
        object: Object,
        /// Why.
        error: E,
    },
    /// The object holds zero (a ratio needs both of its terms).
    Zero {
        /// The object.
        object: Object,
    },
    /// A value the user gave is not finite and positive.
    Given {
        /// Which value.
        what: &'static str,
        /// The value.
        value: f64,
    },
}

impl<E> UnitsError<E> {
    /// The object concerned, if one.
    pub fn object(&self) -> Option<Object> {
        match self {
            UnitsError::Unreadable { object, .. } | UnitsError::Zero { object } => Some(*object),
            UnitsError::Given { .. } => None,
        }
    }
}

impl<E: fmt::Display> fmt::Display for UnitsError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UnitsError::Unreadable { object, error } => write!(
                f,
                "cannot read {:#06X}:{} ({}): {error}; give the axis units instead",
                object.index, object.sub, object.name
            ),
            UnitsError::Zero { object } => write!(
                f,
                "{:#06X}:{} ({}) is 0; give the axis units instead",
                object.index, object.sub, object.name
            ),
            UnitsError::Given { what, value } => {
                write!(
                    f,
                    "the {what} given ({value:e}) must be finite and positive"
                )
            }
        }
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
            feed: None,
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

    #[test]
    fn the_feed_constant_sets_the_position_unit() {
        // A drive scaled to millidegrees: 360 000 position units per joint revolution, whatever
        // its encoder and gear.
        let u = AxisUnits {
            counts_per_rev: 4096.0,
            gear_ratio: 121.0,
            feed: Some(360_000.0),
            lead_m: None,
            rated_torque_nm: 1.0,
        };
        assert_eq!(u.position_counts(core::f64::consts::PI), 180_000);
        // The millidegree is coarser than an increment (1/495 616 rev): it sets the resolution.
        assert!((u.position_resolution() - 0.5 * core::f64::consts::TAU / 360_000.0).abs() < 1e-18);
        // With a 50:1 gear the increment (1/204 800 rev) is the coarser one.
        let coarse = AxisUnits {
            gear_ratio: 50.0,
            ..u
        };
        let per_increment = core::f64::consts::TAU / 204_800.0;
        assert!((coarse.position_resolution() - 0.5 * per_increment).abs() < 1e-18);
        // Torque still goes through the gear.
        assert!((u.torque(1000) - 121.0).abs() < 1e-12);
    }

    #[test]
    fn units_are_read_or_given_and_a_missing_object_is_named() {
        let drive = |o: Object| -> Result<u64, &'static str> {
            Ok(match (o.index, o.sub) {
                (0x608F, 1) => 131_072,
                (0x608F, 2) => 1,
                (0x6091, 1) => 121,
                (0x6091, 2) => 1,
                (0x6092, 1) => 131_072 * 121,
                (0x6092, 2) => 1,
                (0x6076, 0) => 640,
                _ => return Err("no such object"),
            })
        };
        let u = UnitsOverride::NONE.resolve(drive).unwrap();
        assert_eq!(
            (u.counts_per_rev, u.gear_ratio, u.units_per_rev()),
            (131_072.0, 121.0, 131_072.0 * 121.0)
        );
        assert!((u.rated_torque_nm - 0.64).abs() < 1e-15);
        // A drive without a feed constant is refused, naming the object …
        let no_feed = |o: Object| {
            if o.index == 0x6092 {
                Err("no object")
            } else {
                drive(o)
            }
        };
        let e = UnitsOverride::NONE.resolve(no_feed).unwrap_err();
        assert_eq!(e.object(), Some(obj::FEED));
        assert!(e.to_string().contains("0x6092:1"), "{e}");
        // … unless the feed is given.
        let given = UnitsOverride {
            feed: Some(1000.0),
            ..UnitsOverride::NONE
        };
        assert_eq!(given.resolve(no_feed).unwrap().units_per_rev(), 1000.0);
        assert_eq!(given.objects_to_read().count(), 5);
        // A zero term is refused.
        let zero = |o: Object| {
            if o == obj::GEAR_SHAFT_REVOLUTIONS {
                Ok(0)
            } else {
                drive(o)
            }
        };
        assert_eq!(
            UnitsOverride::NONE.resolve(zero).unwrap_err(),
            UnitsError::Zero {
                object: obj::GEAR_SHAFT_REVOLUTIONS
            }
        );
        // Everything given: nothing is read.
        let all = UnitsOverride::all(AxisUnits::GEARED_100);
        assert_eq!(all.objects_to_read().count(), 0);
        let nothing = |_: Object| -> Result<u64, &'static str> { Err("not asked") };
        let u = all.resolve(nothing).unwrap();
        assert_eq!(u.per_count(), AxisUnits::GEARED_100.per_count());
        assert!(
            UnitsOverride {
                gear_ratio: Some(-1.0),
                ..all
            }
            .resolve(nothing)
            .is_err()
        );
    }
}
