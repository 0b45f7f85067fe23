//! The register map of the Robotiq 2F-85 and 2F-140 adaptive grippers (*2F-85 & 2F-140
//! Instruction Manual*, section 4: "Control"; RL's `RobotiqModelC`), carried over Modbus RTU
//! at 115200 baud 8N1 (unit 9 by default) or Modbus TCP.
//!
//! Sixteen bytes in each direction, two per register, the first byte in the register's high
//! half. The robot writes its command at 0x03E8 ("robot output"), reads the status at 0x07D0
//! ("robot input"); bytes 6 to 15 are reserved.
//!
//! | byte | command (0x03E8…) | status (0x07D0…) |
//! |---|---|---|
//! | 0 | action request: `rACT` bit 0, `rGTO` bit 3, `rATR` bit 4, `rARD` bit 5 | gripper status: `gACT` bit 0, `gGTO` bit 3, `gSTA` bits 4–5, `gOBJ` bits 6–7 |
//! | 1 | reserved | reserved |
//! | 2 | reserved | fault status: `gFLT` bits 0–3, `kFLT` bits 4–7 |
//! | 3 | position request `rPR` (0 open, 255 closed) | position request echo `gPR` |
//! | 4 | speed `rSP` (0 slowest, 255 fastest) | position `gPO` |
//! | 5 | force `rFR` (0 lowest, 255 highest) | motor current `gCU` (× 10 mA) |

use core::fmt;

/// The default Modbus unit address.
pub const DEFAULT_UNIT: u8 = 9;
/// The default baud rate of the serial line.
pub const DEFAULT_BAUD: u32 = 115_200;
/// The first command register.
pub const COMMAND_REGISTER: u16 = 0x03E8;
/// The first status register.
pub const STATUS_REGISTER: u16 = 0x07D0;
/// Registers of each map (16 bytes).
pub const MAP_REGISTERS: u16 = 8;
/// Registers that carry the command and the status (6 bytes).
pub const USED_REGISTERS: u16 = 3;

/// What the fingers are doing (`gOBJ`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ObjectStatus {
    /// Moving towards the requested position (no object detected).
    #[default]
    Moving,
    /// Stopped by a contact while opening: an object is held from inside.
    ContactOpening,
    /// Stopped by a contact while closing: an object is held.
    ContactClosing,
    /// At the requested position: no object (or it was lost).
    AtPosition,
}

impl ObjectStatus {
    const fn from_bits(b: u8) -> Self {
        match b & 3 {
            0 => Self::Moving,
            1 => Self::ContactOpening,
            2 => Self::ContactClosing,
            _ => Self::AtPosition,
        }
    }

    const fn bits(self) -> u8 {
        match self {
            Self::Moving => 0,
            Self::ContactOpening => 1,
            Self::ContactClosing => 2,
            Self::AtPosition => 3,
        }
    }

    /// Whether the fingers stopped on an object.
    pub const fn holds_object(self) -> bool {
        matches!(self, Self::ContactOpening | Self::ContactClosing)
    }
}

/// The activation state (`gSTA`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ActivationStatus {
    /// Reset (or automatic release).
    #[default]
    Reset,
    /// Activation in progress.
    Activating,
    /// Not used (value 2).
    Unused,
    /// Activation complete.
    Activated,
}

impl ActivationStatus {
    const fn from_bits(b: u8) -> Self {
        match b & 3 {
            0 => Self::Reset,
            1 => Self::Activating,
            2 => Self::Unused,
            _ => Self::Activated,
        }
    }

    const fn bits(self) -> u8 {
        match self {
            Self::Reset => 0,
            Self::Activating => 1,
            Self::Unused => 2,
            Self::Activated => 3,
        }
    }
}

/// How serious a fault is, as the manual groups them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Severity {
    /// No fault.
    None,
    /// A priority fault: the request waits (LED blue).
    Priority,
    /// A minor fault: clears itself (LED red).
    Minor,
    /// A major fault: the gripper stops; a reset and reactivation (rising `rACT`) is needed
    /// (LED blinking red/blue).
    Major,
}

/// The gripper's fault (`gFLT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Fault {
    /// 0x00.
    #[default]
    None,
    /// 0x05: action delayed, the (re)activation must complete first.
    ActionDelayed,
    /// 0x07: the activation bit must be set before the action.
    ActivationBitNotSet,
    /// 0x08: maximum operating temperature exceeded; wait for cool-down.
    Overtemperature,
    /// 0x09: no communication during at least 1 second.
    NoCommunication,
    /// 0x0A: under the minimum operating voltage.
    Undervoltage,
    /// 0x0B: automatic release in progress.
    AutomaticReleaseInProgress,
    /// 0x0C: internal fault.
    Internal,
    /// 0x0D: activation fault (interference or another error during activation).
    ActivationFault,
    /// 0x0E: overcurrent triggered.
    Overcurrent,
    /// 0x0F: automatic release completed.
    AutomaticReleaseCompleted,
    /// A code the manual does not list.
    Other(u8),
}

impl Fault {
    /// The fault of a 4-bit code.
    pub const fn from_code(code: u8) -> Self {
        match code & 0x0F {
            0x00 => Self::None,
            0x05 => Self::ActionDelayed,
            0x07 => Self::ActivationBitNotSet,
            0x08 => Self::Overtemperature,
            0x09 => Self::NoCommunication,
            0x0A => Self::Undervoltage,
            0x0B => Self::AutomaticReleaseInProgress,
            0x0C => Self::Internal,
            0x0D => Self::ActivationFault,
            0x0E => Self::Overcurrent,
            0x0F => Self::AutomaticReleaseCompleted,
            c => Self::Other(c),
        }
    }

    /// The 4-bit code.
    pub const fn code(self) -> u8 {
        match self {
            Self::None => 0x00,
            Self::ActionDelayed => 0x05,
            Self::ActivationBitNotSet => 0x07,
            Self::Overtemperature => 0x08,
            Self::NoCommunication => 0x09,
            Self::Undervoltage => 0x0A,
            Self::AutomaticReleaseInProgress => 0x0B,
            Self::Internal => 0x0C,
            Self::ActivationFault => 0x0D,
            Self::Overcurrent => 0x0E,
            Self::AutomaticReleaseCompleted => 0x0F,
            Self::Other(c) => c & 0x0F,
        }
    }

    /// How serious it is.
    pub const fn severity(self) -> Severity {
        match self {
            Self::None => Severity::None,
            Self::ActionDelayed | Self::ActivationBitNotSet => Severity::Priority,
            Self::Overtemperature | Self::NoCommunication => Severity::Minor,
            Self::Other(c) if c < 0x0A => Severity::Minor,
            _ => Severity::Major,
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self {
            Self::None => "no fault",
            Self::ActionDelayed => "action delayed: the activation must complete first",
            Self::ActivationBitNotSet => "the activation bit must be set before the action",
            Self::Overtemperature => "maximum operating temperature exceeded",
            Self::NoCommunication => "no communication during at least 1 second",
            Self::Undervoltage => "under the minimum operating voltage",
            Self::AutomaticReleaseInProgress => "automatic release in progress",
            Self::Internal => "internal fault",
            Self::ActivationFault => "activation fault",
            Self::Overcurrent => "overcurrent triggered",
            Self::AutomaticReleaseCompleted => "automatic release completed",
            Self::Other(c) => return write!(f, "fault {c:#04x}"),
        };
        write!(f, "{text} ({:#04x})", self.code())
    }
}

/// The robot's command (bytes 0 to 5 of the robot output).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Command {
    /// `rACT`: activate (0 resets the gripper; a rising edge starts the activation).
    pub activate: bool,
    /// `rGTO`: go to the requested position (0 stops).
    pub go_to: bool,
    /// `rATR`: automatic release (slow opening or closing after an emergency; overrides all
    /// else).
    pub automatic_release: bool,
    /// `rARD`: the automatic release's direction: `true` opens, `false` closes.
    pub release_opening: bool,
    /// `rPR`: 0 open to 255 closed.
    pub position: u8,
    /// `rSP`: 0 slowest to 255 fastest.
    pub speed: u8,
    /// `rFR`: 0 lowest (no re-grasp) to 255 highest.
    pub force: u8,
}

impl Command {
    /// The action request byte.
    pub const fn action_request(&self) -> u8 {
        (self.activate as u8)
            | (self.go_to as u8) << 3
            | (self.automatic_release as u8) << 4
            | (self.release_opening as u8) << 5
    }

    /// The three registers written at [`COMMAND_REGISTER`].
    pub const fn to_registers(&self) -> [u16; 3] {
        [
            (self.action_request() as u16) << 8,
            self.position as u16,
            (self.speed as u16) << 8 | self.force as u16,
        ]
    }

    /// The command in the first three registers of the robot output (reserved bits and bytes
    /// are ignored).
    pub const fn from_registers(r: [u16; 3]) -> Self {
        let action = (r[0] >> 8) as u8;
        Self {
            activate: action & 1 != 0,
            go_to: action & (1 << 3) != 0,
            automatic_release: action & (1 << 4) != 0,
            release_opening: action & (1 << 5) != 0,
            position: (r[1] & 0xFF) as u8,
            speed: (r[2] >> 8) as u8,
            force: (r[2] & 0xFF) as u8,
        }
    }
}

/// The gripper's status (bytes 0 to 5 of the robot input).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Status {
    /// `gACT`: the activation bit as the gripper took it.
    pub activated: bool,
    /// `gGTO`: the go-to bit as the gripper took it.
    pub going: bool,
    /// `gSTA`.
    pub activation: ActivationStatus,
    /// `gOBJ`.
    pub object: ObjectStatus,
    /// `gFLT`.
    pub fault: Fault,
    /// `kFLT`: the controller's own fault code (see its documentation).
    pub controller_fault: u8,
    /// `gPR`: the position request the gripper took.
    pub position_request: u8,
    /// `gPO`: 0 open to 255 closed.
    pub position: u8,
    /// `gCU`: the motor current in units of about 10 mA.
    pub current: u8,
}

impl Status {
    /// The three registers at [`STATUS_REGISTER`].
    pub const fn to_registers(&self) -> [u16; 3] {
        let byte0 = (self.activated as u8)
            | (self.going as u8) << 3
            | self.activation.bits() << 4
            | self.object.bits() << 6;
        let byte2 = self.fault.code() | (self.controller_fault & 0x0F) << 4;
        [
            (byte0 as u16) << 8,
            (byte2 as u16) << 8 | self.position_request as u16,
            (self.position as u16) << 8 | self.current as u16,
        ]
    }

    /// The status in the first three registers of the robot input.
    pub const fn from_registers(r: [u16; 3]) -> Self {
        let byte0 = (r[0] >> 8) as u8;
        let byte2 = (r[1] >> 8) as u8;
        Self {
            activated: byte0 & 1 != 0,
            going: byte0 & (1 << 3) != 0,
            activation: ActivationStatus::from_bits(byte0 >> 4),
            object: ObjectStatus::from_bits(byte0 >> 6),
            fault: Fault::from_code(byte2),
            controller_fault: byte2 >> 4,
            position_request: (r[1] & 0xFF) as u8,
            position: (r[2] >> 8) as u8,
            current: (r[2] & 0xFF) as u8,
        }
    }

    /// Whether the gripper is activated and ready to move.
    pub const fn is_ready(&self) -> bool {
        self.activated && matches!(self.activation, ActivationStatus::Activated)
    }

    /// The motor current, A (the manual's "about 10 × value mA").
    pub fn current_amps(&self) -> f64 {
        f64::from(self.current) * 0.01
    }
}

/// The two models: their stroke, speed and force ranges (2F-85 & 2F-140 manual, section 6,
/// "Specifications").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Model {
    /// 85 mm stroke, 20–150 mm/s, 20–235 N.
    #[default]
    TwoF85,
    /// 140 mm stroke, 30–250 mm/s, 10–125 N.
    TwoF140,
}

impl Model {
    /// The opening when fully open, m.
    pub const fn stroke_m(self) -> f64 {
        match self {
            Self::TwoF85 => 0.085,
            Self::TwoF140 => 0.140,
        }
    }

    /// Slowest and fastest closing speed, m/s.
    pub const fn speed_range(self) -> (f64, f64) {
        match self {
            Self::TwoF85 => (0.020, 0.150),
            Self::TwoF140 => (0.030, 0.250),
        }
    }

    /// Lowest and highest grip force, N.
    pub const fn force_range(self) -> (f64, f64) {
        match self {
            Self::TwoF85 => (20.0, 235.0),
            Self::TwoF140 => (10.0, 125.0),
        }
    }

    /// The model's name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::TwoF85 => "2F-85",
            Self::TwoF140 => "2F-140",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_manuals_registers_decode_as_it_explains() {
        // "Open at full speed and force": 0x0900 0x0000 0xFFFF.
        let c = Command::from_registers([0x0900, 0x0000, 0xFFFF]);
        assert!(c.activate && c.go_to && !c.automatic_release);
        assert_eq!((c.position, c.speed, c.force), (0, 255, 255));
        assert_eq!(c.to_registers(), [0x0900, 0x0000, 0xFFFF]);
        // Activation in progress: 0x1100; complete: 0x3100.
        let s = Status::from_registers([0x1100, 0, 0]);
        assert!(s.activated && s.activation == ActivationStatus::Activating);
        let s = Status::from_registers([0x3100, 0, 0]);
        assert!(s.is_ready());
        // In motion at 187/255 drawing 160 mA: 0x3900 0x0000 0xBB10.
        let s = Status::from_registers([0x3900, 0x0000, 0xBB10]);
        assert!(s.going && s.object == ObjectStatus::Moving);
        assert_eq!((s.position, s.current), (0xBB, 0x10));
        assert!((s.current_amps() - 0.16).abs() < 1e-12);
        // Grasp complete on an object at 189/255: 0xB900 0x00FF 0xBD00.
        let s = Status::from_registers([0xB900, 0x00FF, 0xBD00]);
        assert_eq!(s.object, ObjectStatus::ContactClosing);
        assert!(s.object.holds_object());
        assert_eq!((s.position_request, s.position), (0xFF, 0xBD));
        assert_eq!(s.to_registers(), [0xB900, 0x00FF, 0xBD00]);
        // Opening complete at 13/255 (the software limit): 0xF900 0x0000 0x0D00.
        let s = Status::from_registers([0xF900, 0x0000, 0x0D00]);
        assert_eq!((s.object, s.position), (ObjectStatus::AtPosition, 13));
    }

    #[test]
    fn faults_and_their_severity() {
        for code in 0..16u8 {
            let f = Fault::from_code(code);
            assert_eq!(f.code(), code);
        }
        assert_eq!(Fault::from_code(0x07).severity(), Severity::Priority);
        assert_eq!(Fault::from_code(0x09).severity(), Severity::Minor);
        assert_eq!(Fault::from_code(0x0E).severity(), Severity::Major);
        assert_eq!(Fault::from_code(0x03).severity(), Severity::Minor);
        let s = Status::from_registers([0, 0x2E00, 0]);
        assert_eq!((s.fault, s.controller_fault), (Fault::Overcurrent, 2));
        assert_eq!(s.to_registers(), [0, 0x2E00, 0]);
    }
}
