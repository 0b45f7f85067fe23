//! The safety chain on Linux GPIO lines, through the GPIO character device (`/dev/gpiochipN`,
//! the kernel's line-request interface, via `gpiocdev`): what `rl run --estop gpiochip0:17
//! --watchdog gpiochip0:27 …` opens.
//!
//! A line is written `CHIP:OFFSET`: `gpiochip0:17` (the chip's name under `/dev`) or a path,
//! `/dev/gpiochip0:17`. The e-stop and the enable are requested as inputs, the watchdog and the
//! brake or contactor as outputs starting inactive (low: the relay dropped, the brake on), and
//! held for the life of the chain. Each line's text names its pin in every message.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

use embedded_hal::digital::PinState;
use gpiocdev_embedded_hal::{InputPin, OutputPin};
use rl_drivers::safety::{
    InputConfig, Level, NoPin, OutputConfig, PinName, SafetyChain, SafetyConfig, StopCategory,
};

use super::SafetyHandle;

/// One GPIO line: a chip and an offset on it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GpioLine {
    /// The chip's character device, e.g. `/dev/gpiochip0`.
    pub chip: PathBuf,
    /// The line's offset on the chip.
    pub offset: u32,
    /// As written (`gpiochip0:17`): the pin's name in messages.
    pub text: String,
}

impl FromStr for GpioLine {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let form = "write a GPIO line as CHIP:OFFSET, e.g. gpiochip0:17 or /dev/gpiochip0:17";
        let Some((chip, offset)) = text.rsplit_once(':') else {
            return Err(format!("'{text}': {form}"));
        };
        if chip.is_empty() {
            return Err(format!("'{text}': no chip; {form}"));
        }
        let offset: u32 = offset
            .parse()
            .map_err(|_| format!("'{text}': the offset '{offset}' is not a line number; {form}"))?;
        let chip = if chip.contains('/') {
            PathBuf::from(chip)
        } else {
            PathBuf::from("/dev").join(chip)
        };
        if PinName::new(text).is_err() {
            return Err(format!(
                "'{text}': longer than a pin name may be (32 bytes)"
            ));
        }
        Ok(Self {
            chip,
            offset,
            text: text.to_owned(),
        })
    }
}

impl fmt::Display for GpioLine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// The lines of a chain and how it stops.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GpioChain {
    /// The emergency-stop input (normally closed: closed reads `estop_closed`).
    pub estop: GpioLine,
    /// The level a closed e-stop reads [default: high].
    pub estop_closed: Level,
    /// The enable (dead-man) input, if one.
    pub enable: Option<GpioLine>,
    /// The level a held enable reads [default: high].
    pub enable_held: Level,
    /// The watchdog (charge-pump) output, if one.
    pub watchdog: Option<GpioLine>,
    /// The brake or contactor output (high: energised), if one.
    pub brake: Option<GpioLine>,
    /// How the chain stops.
    pub category: StopCategory,
}

/// A line that could not be requested.
#[derive(Debug)]
pub struct GpioError {
    /// Which line, as written.
    pub line: String,
    /// Its chip's device.
    pub chip: PathBuf,
    /// Its offset.
    pub offset: u32,
    /// Its role (`e-stop input`, …).
    pub role: &'static str,
    /// Why.
    pub error: gpiocdev_embedded_hal::Error,
}

impl fmt::Display for GpioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "cannot request the {} {} (line {} of {}): {}",
            self.role,
            self.line,
            self.offset,
            self.chip.display(),
            self.error
        )
    }
}

impl std::error::Error for GpioError {}

fn input(line: &GpioLine, role: &'static str) -> Result<InputPin, GpioError> {
    InputPin::new(&line.chip, line.offset).map_err(|error| GpioError {
        line: line.text.clone(),
        chip: line.chip.clone(),
        offset: line.offset,
        role,
        error,
    })
}

fn output(line: &GpioLine, role: &'static str) -> Result<OutputPin, GpioError> {
    OutputPin::new(&line.chip, line.offset, PinState::Low).map_err(|error| GpioError {
        line: line.text.clone(),
        chip: line.chip.clone(),
        offset: line.offset,
        role,
        error,
    })
}

/// The line's text as a pin name (checked when the line was parsed; `fallback` otherwise).
fn name(line: &GpioLine, fallback: PinName) -> PinName {
    PinName::new(&line.text).unwrap_or(fallback)
}

impl GpioChain {
    /// A chain on `estop` alone, category 0, levels high.
    pub fn new(estop: GpioLine) -> Self {
        Self {
            estop,
            estop_closed: Level::High,
            enable: None,
            enable_held: Level::High,
            watchdog: None,
            brake: None,
            category: StopCategory::Zero,
        }
    }

    /// The chain's configuration: pin names from the lines, the levels, the category.
    pub fn config(&self) -> SafetyConfig {
        let mut config = SafetyConfig {
            category: self.category,
            ..SafetyConfig::default()
        };
        config.estop = InputConfig {
            name: name(&self.estop, config.estop.name),
            closed_level: self.estop_closed,
            ..config.estop
        };
        if let Some(line) = &self.enable {
            config.enable = InputConfig {
                name: name(line, config.enable.name),
                closed_level: self.enable_held,
                ..config.enable
            };
        }
        if let Some(line) = &self.watchdog {
            config.watchdog = OutputConfig {
                name: name(line, config.watchdog.name),
                ..config.watchdog
            };
        }
        if let Some(line) = &self.brake {
            config.brake = OutputConfig {
                name: name(line, config.brake.name),
                ..config.brake
            };
        }
        config
    }

    /// Requests the lines and makes the chain, ready for a run's
    /// [`RunOptions::safety`](crate::controller::RunOptions::safety).
    pub fn open(&self) -> Result<SafetyHandle, GpioError> {
        let config = self.config();
        let estop = input(&self.estop, "e-stop input")?;
        let enable = self
            .enable
            .as_ref()
            .map(|l| input(l, "enable input"))
            .transpose()?;
        let watchdog = self
            .watchdog
            .as_ref()
            .map(|l| output(l, "watchdog output"))
            .transpose()?;
        let brake = self
            .brake
            .as_ref()
            .map(|l| output(l, "brake output"))
            .transpose()?;
        // One chain type per set of pins; the handle hides which.
        Ok(match (watchdog, enable, brake) {
            (Some(w), Some(e), Some(b)) => SafetyHandle::new(
                SafetyChain::new(config, estop, w)
                    .with_enable(e)
                    .with_brake(b),
            ),
            (Some(w), Some(e), None) => {
                SafetyHandle::new(SafetyChain::new(config, estop, w).with_enable(e))
            }
            (Some(w), None, Some(b)) => {
                SafetyHandle::new(SafetyChain::new(config, estop, w).with_brake(b))
            }
            (Some(w), None, None) => SafetyHandle::new(SafetyChain::new(config, estop, w)),
            (None, Some(e), Some(b)) => SafetyHandle::new(
                SafetyChain::new(config, estop, NoPin)
                    .with_enable(e)
                    .with_brake(b),
            ),
            (None, Some(e), None) => {
                SafetyHandle::new(SafetyChain::new(config, estop, NoPin).with_enable(e))
            }
            (None, None, Some(b)) => {
                SafetyHandle::new(SafetyChain::new(config, estop, NoPin).with_brake(b))
            }
            (None, None, None) => SafetyHandle::new(SafetyChain::new(config, estop, NoPin)),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_parsed_with_their_chip_and_offset_or_refused_with_the_form() {
        let l: GpioLine = "gpiochip0:17".parse().expect("line");
        assert_eq!(l.chip, PathBuf::from("/dev/gpiochip0"));
        assert_eq!(l.offset, 17);
        let l: GpioLine = "/dev/gpiochip2:3".parse().expect("line");
        assert_eq!(l.chip, PathBuf::from("/dev/gpiochip2"));
        for bad in ["gpiochip0", "gpiochip0:x", ":3", "gpiochip0:-1", ""] {
            let e = bad.parse::<GpioLine>().expect_err(bad);
            assert!(e.contains("CHIP:OFFSET"), "{bad}: {e}");
        }
        let e = format!("gpiochip0:{}", "1".repeat(40))
            .parse::<GpioLine>()
            .expect_err("too long");
        assert!(
            e.contains("not a line number") || e.contains("32 bytes"),
            "{e}"
        );
    }

    #[test]
    fn a_chip_that_is_not_there_is_named_in_the_error() {
        let chain = GpioChain::new("gpiochip97:5".parse().expect("line"));
        let e = chain.open().expect_err("no such chip");
        let text = e.to_string();
        assert!(text.contains("e-stop input gpiochip97:5"), "{text}");
        assert!(text.contains("line 5 of /dev/gpiochip97"), "{text}");
    }

    #[test]
    fn the_config_names_every_pin_after_its_line() {
        let mut chain = GpioChain::new("gpiochip0:17".parse().expect("line"));
        chain.watchdog = Some("gpiochip0:27".parse().expect("line"));
        chain.estop_closed = Level::Low;
        chain.category = StopCategory::One;
        let c = chain.config();
        assert_eq!(c.estop.name.as_str(), "gpiochip0:17");
        assert_eq!(c.estop.closed_level, Level::Low);
        assert_eq!(c.watchdog.name.as_str(), "gpiochip0:27");
        assert_eq!(c.category, StopCategory::One);
    }
}
