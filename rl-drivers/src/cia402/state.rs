//! The power state machine (CiA 402-2 §6.3 / IEC 61800-7-201 figure "state machine"): the
//! drive's state decoded from the statusword (0x6041), the commands written to the controlword
//! (0x6040), the drive's own transitions (what a drive does with a controlword — the fake uses
//! it), and the master's next command on the way to a goal state.
//!
//! Statusword bits: 0 ready to switch on, 1 switched on, 2 operation enabled, 3 fault,
//! 4 voltage enabled, 5 quick stop (active low), 6 switch on disabled, 7 warning, 9 remote,
//! 10 target reached, 11 internal limit active, 12–13 mode specific (CSP: 12 the drive follows
//! the target, 13 following error).
//!
//! | state | statusword (mask) |
//! |---|---|
//! | not ready to switch on | `0x00` (0x4F) |
//! | switch on disabled | `0x40` (0x4F) |
//! | ready to switch on | `0x21` (0x6F) |
//! | switched on | `0x23` (0x6F) |
//! | operation enabled | `0x27` (0x6F) |
//! | quick stop active | `0x07` (0x6F) |
//! | fault reaction active | `0x0F` (0x4F) |
//! | fault | `0x08` (0x4F) |
//!
//! Bit 5 (quick stop) alone tells operation enabled (0x27) from quick stop active (0x07): a
//! decoder that masks it out cannot tell them apart.
//!
//! Controlword commands (bits 0 switch on, 1 enable voltage, 2 quick stop (active low),
//! 3 enable operation, 7 fault reset): shutdown 0x06, switch on 0x07, enable operation 0x0F,
//! disable voltage 0x00, quick stop 0x02, disable operation 0x07, fault reset = rising edge of
//! bit 7.

use core::fmt;

/// The statusword (0x6041).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Statusword(pub u16);

impl Statusword {
    /// Bit 3: a fault is present.
    pub const FAULT: u16 = 1 << 3;
    /// Bit 4: voltage enabled.
    pub const VOLTAGE_ENABLED: u16 = 1 << 4;
    /// Bit 5: quick stop (active low: 0 means a quick stop is active).
    pub const QUICK_STOP: u16 = 1 << 5;
    /// Bit 7: warning.
    pub const WARNING: u16 = 1 << 7;
    /// Bit 9: remote (the controlword is obeyed).
    pub const REMOTE: u16 = 1 << 9;
    /// Bit 10: target reached.
    pub const TARGET_REACHED: u16 = 1 << 10;
    /// Bit 11: internal limit active.
    pub const INTERNAL_LIMIT: u16 = 1 << 11;
    /// Bit 12: mode specific (CSP/CSV/CST: the drive follows the target).
    pub const FOLLOWS_TARGET: u16 = 1 << 12;
    /// Bit 13: mode specific (CSP: following error).
    pub const FOLLOWING_ERROR: u16 = 1 << 13;

    /// The power state, `None` for a bit pattern that is no state.
    pub const fn state(self) -> Option<PowerState> {
        PowerState::from_statusword(self.0)
    }

    /// Whether the warning bit is set.
    pub const fn warning(self) -> bool {
        self.0 & Self::WARNING != 0
    }

    /// Whether the internal limit bit is set.
    pub const fn internal_limit(self) -> bool {
        self.0 & Self::INTERNAL_LIMIT != 0
    }

    /// Whether the following error bit (CSP) is set.
    pub const fn following_error(self) -> bool {
        self.0 & Self::FOLLOWING_ERROR != 0
    }

    /// Whether the fault bit is set.
    pub const fn fault(self) -> bool {
        self.0 & Self::FAULT != 0
    }
}

/// A state of the power state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PowerState {
    /// Initialising; no command accepted.
    NotReadyToSwitchOn,
    /// Initialised, power stage off; the state after a reset.
    SwitchOnDisabled,
    /// Waiting for switch on.
    ReadyToSwitchOn,
    /// Power stage on, no torque.
    SwitchedOn,
    /// Torque on: the drive follows its targets.
    OperationEnabled,
    /// Decelerating with the quick stop ramp (or holding after it).
    QuickStopActive,
    /// A fault was detected; the drive is reacting (braking).
    FaultReactionActive,
    /// Faulted, power stage off; needs a fault reset.
    Fault,
}

impl PowerState {
    /// Decodes the state from statusword bits 0–3, 5 and 6.
    pub const fn from_statusword(sw: u16) -> Option<Self> {
        match sw & 0x4F {
            0x00 => return Some(PowerState::NotReadyToSwitchOn),
            0x40 => return Some(PowerState::SwitchOnDisabled),
            0x0F => return Some(PowerState::FaultReactionActive),
            0x08 => return Some(PowerState::Fault),
            _ => {}
        }
        match sw & 0x6F {
            0x21 => Some(PowerState::ReadyToSwitchOn),
            0x23 => Some(PowerState::SwitchedOn),
            0x27 => Some(PowerState::OperationEnabled),
            0x07 => Some(PowerState::QuickStopActive),
            _ => None,
        }
    }

    /// The statusword bits 0–3, 5, 6 of the state (what a drive reports).
    pub const fn statusword_bits(self) -> u16 {
        match self {
            PowerState::NotReadyToSwitchOn => 0x00,
            PowerState::SwitchOnDisabled => 0x40,
            PowerState::ReadyToSwitchOn => 0x21,
            PowerState::SwitchedOn => 0x23,
            PowerState::OperationEnabled => 0x27,
            PowerState::QuickStopActive => 0x07,
            PowerState::FaultReactionActive => 0x0F,
            PowerState::Fault => 0x08,
        }
    }

    /// Whether the power stage is on (the motor can hold or produce torque).
    pub const fn is_powered(self) -> bool {
        matches!(
            self,
            PowerState::OperationEnabled
                | PowerState::QuickStopActive
                | PowerState::FaultReactionActive
        )
    }

    /// The state a drive enters on `controlword` (with `previous` for the fault reset edge),
    /// following the profile's transitions 2–12 and 15; states the controlword cannot leave
    /// (not ready, fault reaction) stay. Quick stop active ends in switch on disabled on
    /// "disable voltage" (quick stop option codes 0–4, the common default).
    pub const fn on_controlword(self, controlword: u16, previous: u16) -> Self {
        let cmd = Command::decode(controlword);
        let reset_edge = controlword & 0x80 != 0 && previous & 0x80 == 0;
        match (self, cmd) {
            (PowerState::Fault, _) if reset_edge => PowerState::SwitchOnDisabled,
            (
                PowerState::Fault
                | PowerState::FaultReactionActive
                | PowerState::NotReadyToSwitchOn,
                _,
            ) => self,
            (PowerState::QuickStopActive, Some(Command::DisableVoltage)) => {
                PowerState::SwitchOnDisabled
            }
            (PowerState::QuickStopActive, _) => self,
            (_, Some(Command::DisableVoltage)) => PowerState::SwitchOnDisabled,
            (PowerState::OperationEnabled, Some(Command::QuickStop)) => PowerState::QuickStopActive,
            (_, Some(Command::QuickStop)) => PowerState::SwitchOnDisabled,
            (PowerState::SwitchOnDisabled, Some(Command::Shutdown)) => PowerState::ReadyToSwitchOn,
            (PowerState::SwitchedOn | PowerState::OperationEnabled, Some(Command::Shutdown)) => {
                PowerState::ReadyToSwitchOn
            }
            (PowerState::ReadyToSwitchOn, Some(Command::SwitchOn)) => PowerState::SwitchedOn,
            (PowerState::OperationEnabled, Some(Command::SwitchOn)) => PowerState::SwitchedOn,
            (
                PowerState::ReadyToSwitchOn | PowerState::SwitchedOn,
                Some(Command::EnableOperation),
            ) => PowerState::OperationEnabled,
            _ => self,
        }
    }

    /// The command a master writes next to bring a drive from this state toward `goal`
    /// (`None` when there, or in fault on the way to power off: write [`Controlword::hold`]).
    /// Fault needs a rising edge of bit 7: the master writes [`Command::FaultReset`] after a
    /// cycle without it.
    pub const fn next_command(self, goal: Goal) -> Option<Command> {
        match (goal, self) {
            // Only the way to operation enabled resets a fault; power off is reached already.
            (Goal::OperationEnabled, PowerState::Fault) => Some(Command::FaultReset),
            (_, PowerState::Fault) => None,
            (_, PowerState::NotReadyToSwitchOn | PowerState::FaultReactionActive) => {
                Some(Command::DisableVoltage)
            }
            (Goal::OperationEnabled, PowerState::OperationEnabled) => None,
            (Goal::OperationEnabled, PowerState::SwitchOnDisabled) => Some(Command::Shutdown),
            (Goal::OperationEnabled, PowerState::ReadyToSwitchOn) => Some(Command::SwitchOn),
            (Goal::OperationEnabled, PowerState::SwitchedOn) => Some(Command::EnableOperation),
            (Goal::OperationEnabled, PowerState::QuickStopActive) => Some(Command::DisableVoltage),
            (Goal::SwitchOnDisabled, PowerState::SwitchOnDisabled) => None,
            (Goal::SwitchOnDisabled, _) => Some(Command::DisableVoltage),
            (Goal::QuickStop, PowerState::OperationEnabled) => Some(Command::QuickStop),
            (Goal::QuickStop, PowerState::QuickStopActive | PowerState::SwitchOnDisabled) => None,
            (Goal::QuickStop, _) => Some(Command::DisableVoltage),
        }
    }
}

/// Where a master drives the state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Goal {
    /// Torque on, following targets.
    OperationEnabled,
    /// Decelerate with the quick stop ramp (then hold or switch off, per 0x605A).
    QuickStop,
    /// Power stage off.
    SwitchOnDisabled,
}

impl fmt::Display for PowerState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PowerState::NotReadyToSwitchOn => "not ready to switch on",
            PowerState::SwitchOnDisabled => "switch on disabled",
            PowerState::ReadyToSwitchOn => "ready to switch on",
            PowerState::SwitchedOn => "switched on",
            PowerState::OperationEnabled => "operation enabled",
            PowerState::QuickStopActive => "quick stop active",
            PowerState::FaultReactionActive => "fault reaction active",
            PowerState::Fault => "fault",
        })
    }
}

/// A device control command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    /// 0x06: to ready to switch on.
    Shutdown,
    /// 0x07: to switched on (from operation enabled: disable operation).
    SwitchOn,
    /// 0x0F: to operation enabled.
    EnableOperation,
    /// 0x00: power stage off.
    DisableVoltage,
    /// 0x02: quick stop.
    QuickStop,
    /// 0x80 after a cycle without bit 7: reset a fault.
    FaultReset,
}

impl Command {
    /// The controlword bits of the command (bits 0–3 and 7).
    pub const fn bits(self) -> u16 {
        match self {
            Command::Shutdown => 0x06,
            Command::SwitchOn => 0x07,
            Command::EnableOperation => 0x0F,
            Command::DisableVoltage => 0x00,
            Command::QuickStop => 0x02,
            Command::FaultReset => 0x80,
        }
    }

    /// The command a controlword holds, by the profile's masks (fault reset is an edge, so
    /// bit 7 set decodes as [`Command::FaultReset`]).
    pub const fn decode(cw: u16) -> Option<Self> {
        if cw & 0x80 != 0 {
            return Some(Command::FaultReset);
        }
        if cw & 0x02 == 0 {
            return Some(Command::DisableVoltage);
        }
        if cw & 0x06 == 0x02 {
            return Some(Command::QuickStop);
        }
        match cw & 0x0F {
            0x06 | 0x0E => Some(Command::Shutdown),
            0x07 => Some(Command::SwitchOn),
            0x0F => Some(Command::EnableOperation),
            _ => None,
        }
    }
}

/// Builds controlwords, keeping the mode-specific bits (4–6, 8: halt) apart from the command.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Controlword(pub u16);

impl Controlword {
    /// Bit 8: halt.
    pub const HALT: u16 = 1 << 8;

    /// The controlword of a command.
    pub const fn of(command: Command) -> Self {
        Self(command.bits())
    }

    /// The controlword that keeps a drive in `state` (enable operation in operation enabled,
    /// …).
    pub const fn hold(state: PowerState) -> Self {
        Self(match state {
            PowerState::OperationEnabled => 0x0F,
            PowerState::SwitchedOn => 0x07,
            PowerState::ReadyToSwitchOn => 0x06,
            PowerState::QuickStopActive => 0x02,
            _ => 0x00,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_statuswords_decode_and_bit_5_separates_quick_stop() {
        let table = [
            (0x0000, PowerState::NotReadyToSwitchOn),
            (0x0040, PowerState::SwitchOnDisabled),
            (0x0021, PowerState::ReadyToSwitchOn),
            (0x0023, PowerState::SwitchedOn),
            (0x0027, PowerState::OperationEnabled),
            (0x0007, PowerState::QuickStopActive),
            (0x000F, PowerState::FaultReactionActive),
            (0x0008, PowerState::Fault),
            // Bits the decoder must ignore: voltage, warning, remote, target reached, limit.
            (0x1EB7, PowerState::OperationEnabled),
            (0x0660, PowerState::SwitchOnDisabled),
            (0x0228, PowerState::Fault),
        ];
        for (sw, state) in table {
            assert_eq!(PowerState::from_statusword(sw), Some(state), "{sw:#06x}");
            assert_eq!(
                PowerState::from_statusword(state.statusword_bits()),
                Some(state)
            );
        }
        assert_ne!(
            PowerState::from_statusword(0x27),
            PowerState::from_statusword(0x07)
        );
        assert_eq!(PowerState::from_statusword(0x0001), None);
    }

    #[test]
    fn a_master_walks_a_drive_to_operation_enabled_and_back() {
        let mut state = PowerState::Fault;
        let mut previous = 0u16;
        let mut steps = 0;
        while let Some(cmd) = state.next_command(Goal::OperationEnabled) {
            // The fault reset needs an edge: a cycle with bit 7 clear first.
            let cw = if cmd == Command::FaultReset && previous & 0x80 != 0 {
                0
            } else {
                cmd.bits()
            };
            state = state.on_controlword(cw, previous);
            previous = cw;
            steps += 1;
            assert!(steps < 10);
        }
        assert_eq!((state, steps), (PowerState::OperationEnabled, 4));
        assert_eq!(
            state.on_controlword(0x02, 0x0F),
            PowerState::QuickStopActive
        );
        let qs = PowerState::QuickStopActive;
        assert_eq!(
            qs.next_command(Goal::SwitchOnDisabled),
            Some(Command::DisableVoltage)
        );
        assert_eq!(qs.on_controlword(0x00, 0x02), PowerState::SwitchOnDisabled);
        // Holding bit 7 high does not reset twice; only the edge does.
        assert_eq!(
            PowerState::Fault.on_controlword(0x80, 0x80),
            PowerState::Fault
        );
        assert_eq!(
            PowerState::SwitchedOn.on_controlword(0x06, 0x07),
            PowerState::ReadyToSwitchOn
        );
        assert_eq!(Command::decode(0x0F), Some(Command::EnableOperation));
        assert_eq!(Command::decode(0x0B), Some(Command::QuickStop));
    }
}
