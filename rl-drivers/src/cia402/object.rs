//! The CiA 402 objects a cyclic master uses, with their types (CiA 402-2 §8).

use crate::proto::canopen::object::DataType;
use crate::proto::canopen::pdo::Entry;

/// One object (or sub-object) of the profile.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Object {
    /// Index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Data type.
    pub data_type: DataType,
    /// Name, for messages.
    pub name: &'static str,
}

impl Object {
    const fn new(index: u16, sub: u8, data_type: DataType, name: &'static str) -> Self {
        Self {
            index,
            sub,
            data_type,
            name,
        }
    }

    /// Bytes of its value.
    pub const fn len(&self) -> usize {
        match self.data_type.bits() {
            Some(b) => b.div_ceil(8) as usize,
            None => 0,
        }
    }

    /// Whether the value has no fixed size.
    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Its PDO mapping entry.
    pub const fn entry(&self) -> Entry {
        Entry::new(self.index, self.sub, (self.len() * 8) as u8)
    }
}

use DataType::{Integer8, Integer16, Integer32, Unsigned8, Unsigned16, Unsigned32};

/// 0x603F error code (the last fault's EMCY code).
pub const ERROR_CODE: Object = Object::new(0x603F, 0, Unsigned16, "error code");
/// 0x6040 controlword.
pub const CONTROLWORD: Object = Object::new(0x6040, 0, Unsigned16, "controlword");
/// 0x6041 statusword.
pub const STATUSWORD: Object = Object::new(0x6041, 0, Unsigned16, "statusword");
/// 0x605A quick stop option code.
pub const QUICK_STOP_OPTION: Object = Object::new(0x605A, 0, Integer16, "quick stop option code");
/// 0x6060 modes of operation.
pub const MODES_OF_OPERATION: Object = Object::new(0x6060, 0, Integer8, "modes of operation");
/// 0x6061 modes of operation display.
pub const MODES_DISPLAY: Object = Object::new(0x6061, 0, Integer8, "modes of operation display");
/// 0x6064 position actual value (counts).
pub const POSITION_ACTUAL: Object = Object::new(0x6064, 0, Integer32, "position actual value");
/// 0x6065 following error window (counts).
pub const FOLLOWING_ERROR_WINDOW: Object =
    Object::new(0x6065, 0, Unsigned32, "following error window");
/// 0x606C velocity actual value (counts/s).
pub const VELOCITY_ACTUAL: Object = Object::new(0x606C, 0, Integer32, "velocity actual value");
/// 0x6071 target torque (‰ of rated torque).
pub const TARGET_TORQUE: Object = Object::new(0x6071, 0, Integer16, "target torque");
/// 0x6072 max torque (‰ of rated torque).
pub const MAX_TORQUE: Object = Object::new(0x6072, 0, Unsigned16, "max torque");
/// 0x6076 motor rated torque (mN·m).
pub const MOTOR_RATED_TORQUE: Object = Object::new(0x6076, 0, Unsigned32, "motor rated torque");
/// 0x6077 torque actual value (‰ of rated torque).
pub const TORQUE_ACTUAL: Object = Object::new(0x6077, 0, Integer16, "torque actual value");
/// 0x607A target position (counts).
pub const TARGET_POSITION: Object = Object::new(0x607A, 0, Integer32, "target position");
/// 0x607D:1 min software position limit (counts).
pub const SOFTWARE_LIMIT_MIN: Object = Object::new(0x607D, 1, Integer32, "min position limit");
/// 0x607D:2 max software position limit (counts).
pub const SOFTWARE_LIMIT_MAX: Object = Object::new(0x607D, 2, Integer32, "max position limit");
/// 0x607F max profile velocity (counts/s).
pub const MAX_PROFILE_VELOCITY: Object = Object::new(0x607F, 0, Unsigned32, "max profile velocity");
/// 0x608F:1 position encoder resolution: encoder increments (per 0x608F:2 motor revolutions).
pub const ENCODER_INCREMENTS: Object = Object::new(0x608F, 1, Unsigned32, "encoder increments");
/// 0x608F:2 position encoder resolution: motor revolutions.
pub const ENCODER_MOTOR_REVOLUTIONS: Object =
    Object::new(0x608F, 2, Unsigned32, "encoder motor revolutions");
/// 0x6091:1 gear ratio: motor shaft revolutions (per 0x6091:2 driving shaft revolutions).
pub const GEAR_MOTOR_REVOLUTIONS: Object =
    Object::new(0x6091, 1, Unsigned32, "gear motor revolutions");
/// 0x6091:2 gear ratio: driving shaft revolutions.
pub const GEAR_SHAFT_REVOLUTIONS: Object =
    Object::new(0x6091, 2, Unsigned32, "gear shaft revolutions");
/// 0x6092:1 feed constant: feed in position units (per 0x6092:2 driving shaft revolutions).
pub const FEED: Object = Object::new(0x6092, 1, Unsigned32, "feed constant");
/// 0x6092:2 feed constant: driving shaft revolutions.
pub const FEED_SHAFT_REVOLUTIONS: Object =
    Object::new(0x6092, 2, Unsigned32, "feed shaft revolutions");
/// 0x60B1 velocity offset (counts/s).
pub const VELOCITY_OFFSET: Object = Object::new(0x60B1, 0, Integer32, "velocity offset");
/// 0x60B2 torque offset (‰ of rated torque): the feed-forward torque in CSP and CSV.
pub const TORQUE_OFFSET: Object = Object::new(0x60B2, 0, Integer16, "torque offset");
/// 0x60C2:1 interpolation time period value.
pub const INTERPOLATION_PERIOD_VALUE: Object =
    Object::new(0x60C2, 1, Unsigned8, "interpolation time period value");
/// 0x60C2:2 interpolation time index (power of ten, seconds).
pub const INTERPOLATION_PERIOD_INDEX: Object =
    Object::new(0x60C2, 2, Integer8, "interpolation time index");
/// 0x60F4 following error actual value (counts).
pub const FOLLOWING_ERROR_ACTUAL: Object =
    Object::new(0x60F4, 0, Integer32, "following error actual value");
/// 0x60FF target velocity (counts/s).
pub const TARGET_VELOCITY: Object = Object::new(0x60FF, 0, Integer32, "target velocity");
/// 0x6502 supported drive modes.
pub const SUPPORTED_DRIVE_MODES: Object =
    Object::new(0x6502, 0, Unsigned32, "supported drive modes");

/// The interpolation time period (0x60C2) for a period in µs: `(value, index)` with `value ·
/// 10^index` s, the coarsest exact form whose value fits a byte (`None` if none does).
pub const fn interpolation_period(period_us: u32) -> Option<(u8, i8)> {
    let mut value = period_us;
    let mut index: i8 = -6;
    while value % 10 == 0 && value > 255 && index < 0 {
        value /= 10;
        index += 1;
    }
    while value % 10 == 0 && value >= 10 && index < -3 {
        value /= 10;
        index += 1;
    }
    if value <= 255 {
        Some((value as u8, index))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_and_the_interpolation_period() {
        assert_eq!(TARGET_POSITION.entry().to_u32(), 0x607A_0020);
        assert_eq!(STATUSWORD.entry().to_u32(), 0x6041_0010);
        assert_eq!(MODES_OF_OPERATION.entry().to_u32(), 0x6060_0008);
        assert_eq!(interpolation_period(2000), Some((2, -3)));
        assert_eq!(interpolation_period(1000), Some((1, -3)));
        assert_eq!(interpolation_period(2500), Some((25, -4)));
        assert_eq!(interpolation_period(250), Some((25, -5)));
        assert_eq!(interpolation_period(255), Some((255, -6)));
        assert_eq!(interpolation_period(1234), None);
    }
}
