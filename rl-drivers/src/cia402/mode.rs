//! Modes of operation (0x6060, reported in 0x6061) and the supported drive modes bit field
//! (0x6502: bit `mode − 1` for modes 1–10).

use core::fmt;

/// A mode of operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// 1: profile position.
    ProfilePosition,
    /// 3: profile velocity.
    ProfileVelocity,
    /// 4: profile torque.
    ProfileTorque,
    /// 6: homing.
    Homing,
    /// 7: interpolated position.
    InterpolatedPosition,
    /// 8: cyclic synchronous position (CSP).
    CyclicPosition,
    /// 9: cyclic synchronous velocity (CSV).
    CyclicVelocity,
    /// 10: cyclic synchronous torque (CST).
    CyclicTorque,
}

impl Mode {
    /// The code written to 0x6060.
    pub const fn code(self) -> i8 {
        match self {
            Mode::ProfilePosition => 1,
            Mode::ProfileVelocity => 3,
            Mode::ProfileTorque => 4,
            Mode::Homing => 6,
            Mode::InterpolatedPosition => 7,
            Mode::CyclicPosition => 8,
            Mode::CyclicVelocity => 9,
            Mode::CyclicTorque => 10,
        }
    }

    /// The mode of a code.
    pub const fn from_code(code: i8) -> Option<Self> {
        Some(match code {
            1 => Mode::ProfilePosition,
            3 => Mode::ProfileVelocity,
            4 => Mode::ProfileTorque,
            6 => Mode::Homing,
            7 => Mode::InterpolatedPosition,
            8 => Mode::CyclicPosition,
            9 => Mode::CyclicVelocity,
            10 => Mode::CyclicTorque,
            _ => return None,
        })
    }

    /// Its bit in the supported drive modes (0x6502).
    pub const fn supported_bit(self) -> u32 {
        1 << (self.code() as u32 - 1)
    }

    /// Whether 0x6502's value says the mode is supported.
    pub const fn is_supported_by(self, supported_drive_modes: u32) -> bool {
        supported_drive_modes & self.supported_bit() != 0
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Mode::ProfilePosition => "profile position",
            Mode::ProfileVelocity => "profile velocity",
            Mode::ProfileTorque => "profile torque",
            Mode::Homing => "homing",
            Mode::InterpolatedPosition => "interpolated position",
            Mode::CyclicPosition => "cyclic synchronous position (CSP)",
            Mode::CyclicVelocity => "cyclic synchronous velocity (CSV)",
            Mode::CyclicTorque => "cyclic synchronous torque (CST)",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_and_supported_bits() {
        assert_eq!(Mode::CyclicPosition.code(), 8);
        assert_eq!(Mode::CyclicPosition.supported_bit(), 0x80);
        assert_eq!(Mode::CyclicTorque.supported_bit(), 0x200);
        assert!(Mode::CyclicVelocity.is_supported_by(0x3A5));
        assert_eq!(Mode::from_code(2), None);
    }
}
