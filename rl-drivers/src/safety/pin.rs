//! Pin names and roles, and [`NoPin`], the stand-in for an input or output a chain does not
//! have.

use core::convert::Infallible;
use core::fmt;

use embedded_hal::digital::{ErrorType, InputPin, OutputPin};

/// Longest pin name a [`PinName`] holds, in bytes.
pub const PIN_NAME_CAPACITY: usize = 32;

/// A pin's name for messages, such as `gpiochip0:17` (chip and line) or `estop`. Fixed
/// capacity ([`PIN_NAME_CAPACITY`] bytes) and `Copy`, so a [`StopReason`](super::StopReason)
/// can carry it without allocating.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct PinName {
    bytes: [u8; PIN_NAME_CAPACITY],
    len: u8,
}

/// A name longer than [`PIN_NAME_CAPACITY`] bytes was given to [`PinName::new`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PinNameTooLong {
    /// Length of the refused name in bytes.
    pub len: usize,
}

impl fmt::Display for PinNameTooLong {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "pin name of {} bytes is longer than the {PIN_NAME_CAPACITY} bytes a pin name holds",
            self.len
        )
    }
}

impl core::error::Error for PinNameTooLong {}

impl PinName {
    /// `name`, or an error if it is longer than [`PIN_NAME_CAPACITY`] bytes (never truncated,
    /// so two pins cannot end up with the same name).
    pub const fn new(name: &str) -> Result<Self, PinNameTooLong> {
        let src = name.as_bytes();
        if src.len() > PIN_NAME_CAPACITY {
            return Err(PinNameTooLong { len: src.len() });
        }
        let mut bytes = [0u8; PIN_NAME_CAPACITY];
        let mut i = 0;
        while i < src.len() {
            bytes[i] = src[i];
            i += 1;
        }
        Ok(Self {
            bytes,
            len: src.len() as u8,
        })
    }

    /// The name as text.
    pub fn as_str(&self) -> &str {
        let bytes = self.bytes.get(..usize::from(self.len)).unwrap_or(&[]);
        // Always valid: `new` copies a whole `&str`.
        core::str::from_utf8(bytes).unwrap_or("?")
    }

    /// A name known to fit, for the defaults (longer names are cut at the capacity).
    const fn from_static(name: &'static str) -> Self {
        match Self::new(name) {
            Ok(n) => n,
            Err(_) => Self {
                bytes: [b'?'; PIN_NAME_CAPACITY],
                len: 1,
            },
        }
    }
}

impl fmt::Display for PinName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl fmt::Debug for PinName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl TryFrom<&str> for PinName {
    type Error = PinNameTooLong;
    fn try_from(name: &str) -> Result<Self, Self::Error> {
        Self::new(name)
    }
}

/// What a pin does in the chain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PinRole {
    /// The emergency-stop input (normally closed).
    EStop,
    /// The enable (dead-man) input.
    Enable,
    /// The brake / contactor output (energised = released / powered).
    Brake,
    /// The watchdog (charge pump) output, toggled every cycle.
    Watchdog,
}

impl PinRole {
    /// Default name of a pin in this role.
    pub const fn default_name(self) -> PinName {
        PinName::from_static(match self {
            PinRole::EStop => "estop",
            PinRole::Enable => "enable",
            PinRole::Brake => "brake",
            PinRole::Watchdog => "watchdog",
        })
    }
}

impl fmt::Display for PinRole {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            PinRole::EStop => "e-stop input",
            PinRole::Enable => "enable input",
            PinRole::Brake => "brake output",
            PinRole::Watchdog => "watchdog output",
        })
    }
}

/// A pin as messages name it: its role and its configured name (`e-stop input gpiochip0:17`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PinId {
    /// What the pin does.
    pub role: PinRole,
    /// Its configured name.
    pub name: PinName,
}

impl fmt::Display for PinId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.role, self.name)
    }
}

/// The type of an input or output a chain does not have (no enable input, no brake output).
/// A chain never reads or writes it; if called anyway it reads low and ignores writes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NoPin;

impl ErrorType for NoPin {
    type Error = Infallible;
}

impl InputPin for NoPin {
    fn is_high(&mut self) -> Result<bool, Infallible> {
        Ok(false)
    }
    fn is_low(&mut self) -> Result<bool, Infallible> {
        Ok(true)
    }
}

impl OutputPin for NoPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_kept_whole_or_refused() {
        let name = PinName::new("gpiochip0:17").unwrap();
        assert_eq!(name.as_str(), "gpiochip0:17");
        let long = "x".repeat(PIN_NAME_CAPACITY + 1);
        assert_eq!(
            PinName::new(&long),
            Err(PinNameTooLong {
                len: PIN_NAME_CAPACITY + 1
            })
        );
        let id = PinId {
            role: PinRole::EStop,
            name,
        };
        assert_eq!(id.to_string(), "e-stop input gpiochip0:17");
        assert_eq!(PinRole::Watchdog.default_name().as_str(), "watchdog");
    }
}
