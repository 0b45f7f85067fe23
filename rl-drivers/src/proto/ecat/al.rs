//! The application layer (AL) state machine's registers (ETG.1000.6 §6.4): AL control
//! (0x0120, what the master requests), AL status (0x0130, where the device is) and the AL status
//! code (0x0134, why a transition failed), with the codes' names.
//!
//! States: INIT 1, PRE-OP 2, BOOT 3, SAFE-OP 4, OP 8. AL control bit 4 acknowledges an error;
//! AL status bit 4 says the device refused or left a state and the code explains why.

use core::fmt;

/// An AL state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AlState {
    /// 1: INIT (no mailbox, no process data).
    Init,
    /// 2: PRE-OP (mailbox).
    PreOp,
    /// 3: BOOT (firmware update over FoE).
    Bootstrap,
    /// 4: SAFE-OP (inputs valid, outputs held safe).
    SafeOp,
    /// 8: OP (outputs applied).
    Op,
}

impl AlState {
    /// The 4-bit code.
    pub const fn code(self) -> u8 {
        match self {
            AlState::Init => 1,
            AlState::PreOp => 2,
            AlState::Bootstrap => 3,
            AlState::SafeOp => 4,
            AlState::Op => 8,
        }
    }

    /// The state of a 4-bit code.
    pub const fn from_code(code: u8) -> Option<Self> {
        Some(match code & 0x0F {
            1 => AlState::Init,
            2 => AlState::PreOp,
            3 => AlState::Bootstrap,
            4 => AlState::SafeOp,
            8 => AlState::Op,
            _ => return None,
        })
    }

    /// The name the ETG uses.
    pub const fn name(self) -> &'static str {
        match self {
            AlState::Init => "INIT",
            AlState::PreOp => "PRE-OP",
            AlState::Bootstrap => "BOOT",
            AlState::SafeOp => "SAFE-OP",
            AlState::Op => "OP",
        }
    }
}

impl fmt::Display for AlState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The AL control register (0x0120) a master writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AlControl {
    /// The requested state.
    pub state: AlState,
    /// Bit 4: acknowledge the error indicated in AL status.
    pub acknowledge: bool,
}

impl AlControl {
    /// Request `state`.
    pub const fn request(state: AlState) -> Self {
        Self {
            state,
            acknowledge: false,
        }
    }

    /// Request `state` and acknowledge an error.
    pub const fn acknowledge(state: AlState) -> Self {
        Self {
            state,
            acknowledge: true,
        }
    }

    /// The register value.
    pub const fn to_u16(self) -> u16 {
        self.state.code() as u16 | if self.acknowledge { 0x10 } else { 0 }
    }
}

/// The AL status register (0x0130).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AlStatus(pub u16);

impl AlStatus {
    /// Bit 4: the device reports an error (the code is in 0x0134).
    pub const ERROR: u16 = 0x10;

    /// The status of `state` with or without the error flag.
    pub const fn new(state: AlState, error: bool) -> Self {
        Self(state.code() as u16 | if error { Self::ERROR } else { 0 })
    }

    /// The state (`None` for a code that is no state, e.g. the OR of several devices').
    pub const fn state(self) -> Option<AlState> {
        AlState::from_code(self.0 as u8)
    }

    /// Whether the error flag is set.
    pub const fn error(self) -> bool {
        self.0 & Self::ERROR != 0
    }
}

impl fmt::Display for AlStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.state() {
            Some(s) => write!(f, "{s}")?,
            None => write!(f, "state code {:#x}", self.0 & 0x0F)?,
        }
        if self.error() {
            f.write_str(" + error")?;
        }
        Ok(())
    }
}

impl fmt::Debug for AlStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AlStatus({:#06x}: {self})", self.0)
    }
}

/// An AL status code (0x0134), named after ETG.1000.6 table 11.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AlStatusCode(pub u16);

impl AlStatusCode {
    /// 0x0000: no error.
    pub const NO_ERROR: Self = Self(0x0000);
    /// 0x0001: unspecified error.
    pub const UNSPECIFIED: Self = Self(0x0001);
    /// 0x0011: invalid requested state change.
    pub const INVALID_STATE_CHANGE: Self = Self(0x0011);
    /// 0x0012: unknown requested state.
    pub const UNKNOWN_STATE: Self = Self(0x0012);
    /// 0x0013: bootstrap not supported.
    pub const BOOTSTRAP_NOT_SUPPORTED: Self = Self(0x0013);
    /// 0x0016: invalid mailbox configuration (PRE-OP).
    pub const INVALID_MAILBOX_CONFIG: Self = Self(0x0016);
    /// 0x0017: invalid sync manager configuration.
    pub const INVALID_SM_CONFIG: Self = Self(0x0017);
    /// 0x0018: no valid inputs available.
    pub const NO_VALID_INPUTS: Self = Self(0x0018);
    /// 0x0019: no valid outputs.
    pub const NO_VALID_OUTPUTS: Self = Self(0x0019);
    /// 0x001A: synchronization error.
    pub const SYNCHRONIZATION: Self = Self(0x001A);
    /// 0x001B: sync manager watchdog.
    pub const SM_WATCHDOG: Self = Self(0x001B);
    /// 0x001D: invalid output configuration.
    pub const INVALID_OUTPUT_CONFIG: Self = Self(0x001D);
    /// 0x001E: invalid input configuration.
    pub const INVALID_INPUT_CONFIG: Self = Self(0x001E);
    /// 0x0024: invalid input mapping.
    pub const INVALID_INPUT_MAPPING: Self = Self(0x0024);
    /// 0x0025: invalid output mapping.
    pub const INVALID_OUTPUT_MAPPING: Self = Self(0x0025);
    /// 0x002C: fatal sync error.
    pub const FATAL_SYNC: Self = Self(0x002C);
    /// 0x0030: invalid DC SYNC configuration.
    pub const INVALID_DC_SYNC: Self = Self(0x0030);
    /// 0x0035: invalid DC cycle time.
    pub const INVALID_DC_CYCLE: Self = Self(0x0035);

    /// The ETG's name for the code (`None` for a reserved or vendor-specific code).
    pub const fn name(self) -> Option<&'static str> {
        Some(match self.0 {
            0x0000 => "no error",
            0x0001 => "unspecified error",
            0x0002 => "no memory",
            0x0003 => "invalid device setup",
            0x0011 => "invalid requested state change",
            0x0012 => "unknown requested state",
            0x0013 => "bootstrap not supported",
            0x0014 => "no valid firmware",
            0x0015 => "invalid mailbox configuration (BOOT)",
            0x0016 => "invalid mailbox configuration (PRE-OP)",
            0x0017 => "invalid sync manager configuration",
            0x0018 => "no valid inputs available",
            0x0019 => "no valid outputs",
            0x001A => "synchronization error",
            0x001B => "sync manager watchdog",
            0x001C => "invalid sync manager types",
            0x001D => "invalid output configuration",
            0x001E => "invalid input configuration",
            0x001F => "invalid watchdog configuration",
            0x0020 => "device needs cold start",
            0x0021 => "device needs INIT",
            0x0022 => "device needs PRE-OP",
            0x0023 => "device needs SAFE-OP",
            0x0024 => "invalid input mapping",
            0x0025 => "invalid output mapping",
            0x0026 => "inconsistent settings",
            0x0027 => "free-run not supported",
            0x0028 => "sync mode not supported",
            0x0029 => "free-run needs 3-buffer mode",
            0x002A => "background watchdog",
            0x002B => "no valid inputs and outputs",
            0x002C => "fatal sync error",
            0x002D => "no sync error",
            0x002E => "invalid input FMMU configuration",
            0x0030 => "invalid DC SYNC configuration",
            0x0031 => "invalid DC latch configuration",
            0x0032 => "PLL error",
            0x0033 => "DC sync IO error",
            0x0034 => "DC sync timeout error",
            0x0035 => "DC invalid sync cycle time",
            0x0036 => "DC SYNC0 cycle time",
            0x0037 => "DC SYNC1 cycle time",
            0x0041 => "mailbox AoE",
            0x0042 => "mailbox EoE",
            0x0043 => "mailbox CoE",
            0x0044 => "mailbox FoE",
            0x0045 => "mailbox SoE",
            0x004F => "mailbox VoE",
            0x0050 => "EEPROM no access",
            0x0051 => "EEPROM error",
            0x0052 => "external hardware not ready",
            0x0060 => "device restarted locally",
            0x0061 => "device identification value updated",
            0x0070 => "detected module ident list does not match",
            0x0080 => "supply voltage too low",
            0x0081 => "supply voltage too high",
            0x0082 => "temperature too low",
            0x0083 => "temperature too high",
            0x00F0 => "application controller available",
            _ => return None,
        })
    }
}

impl fmt::Display for AlStatusCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(name) => write!(f, "{:#06x} ({name})", self.0),
            None if self.0 >= 0x8000 => write!(f, "{:#06x} (vendor specific)", self.0),
            None => write!(f, "{:#06x} (reserved)", self.0),
        }
    }
}

impl fmt::Debug for AlStatusCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AlStatusCode({self})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn states_status_and_codes_by_name() {
        for s in [
            AlState::Init,
            AlState::PreOp,
            AlState::Bootstrap,
            AlState::SafeOp,
            AlState::Op,
        ] {
            assert_eq!(AlState::from_code(s.code()), Some(s));
        }
        assert_eq!(AlState::from_code(6), None);
        // soem-single-lan9252.pcapng frame 4: BWR 0x0120 = 0x11 (INIT + acknowledge).
        assert_eq!(AlControl::acknowledge(AlState::Init).to_u16(), 0x11);
        assert_eq!(AlControl::request(AlState::SafeOp).to_u16(), 0x04);
        let s = AlStatus(0x14);
        assert_eq!((s.state(), s.error()), (Some(AlState::SafeOp), true));
        assert_eq!(s.to_string(), "SAFE-OP + error");
        assert_eq!(AlStatus(0x06).state(), None);
        assert_eq!(
            AlStatusCode::SM_WATCHDOG.to_string(),
            "0x001b (sync manager watchdog)"
        );
        assert_eq!(AlStatusCode(0x8001).to_string(), "0x8001 (vendor specific)");
        assert_eq!(AlStatusCode(0x0004).name(), None);
    }
}
