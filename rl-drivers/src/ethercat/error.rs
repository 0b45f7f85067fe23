//! The master's typed error: small and `Copy`, saying what failed where (which device, which
//! register, which object), converted into the generic [`crate::Error`] by the driver.

use core::fmt;
use std::io;

use crate::proto::canopen::sdo_client::SdoError;
use crate::proto::ecat::al::{AlState, AlStatus, AlStatusCode};
use crate::proto::ecat::command::Command;
use crate::proto::ecat::frame::FrameError;
use crate::proto::ecat::mailbox::MailboxErrorCode;
use crate::proto::ecat::sii::SiiError;

/// A device on the segment, for messages: its position and station address.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DeviceRef {
    /// Position from the master (0-based).
    pub position: u16,
    /// Configured station address.
    pub station: u16,
}

impl fmt::Display for DeviceRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "device {} ({:#06x})", self.position, self.station)
    }
}

/// Why an EtherCAT operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EcError {
    /// The raw socket failed.
    Io {
        /// The operating system's error kind.
        kind: io::ErrorKind,
        /// Its number.
        code: Option<i32>,
    },
    /// No reply frame before the deadline.
    Timeout {
        /// What was waited for.
        what: &'static str,
        /// How long, in µs.
        waited_us: u64,
    },
    /// A datagram's working counter differs from what the addressed devices must return.
    WorkingCounter {
        /// The command.
        command: Command,
        /// Its address (ADP/ADO or logical).
        address: u32,
        /// Expected.
        expected: u16,
        /// Received.
        received: u16,
    },
    /// The reply frame does not match the request (layout, command, length).
    Reply(&'static str),
    /// A reply that did not decode.
    Frame(FrameError),
    /// No device answered.
    NoDevices,
    /// More devices than the master was configured for.
    TooManyDevices {
        /// Found.
        found: u16,
        /// The limit.
        limit: usize,
    },
    /// Reading or parsing a device's SII EEPROM failed.
    Sii {
        /// The device.
        device: DeviceRef,
        /// What went wrong.
        error: SiiError,
    },
    /// The SII interface reported an error or stayed busy.
    SiiAccess {
        /// The device.
        device: DeviceRef,
        /// The control/status register.
        status: u16,
    },
    /// A device refused an AL state change (error flag set) or did not reach it in time.
    AlTransition {
        /// The device.
        device: DeviceRef,
        /// The state requested.
        target: AlState,
        /// Its AL status.
        status: AlStatus,
        /// Its AL status code.
        code: AlStatusCode,
    },
    /// A device left the state the master keeps it in.
    AlStatus {
        /// The device.
        device: DeviceRef,
        /// Its AL status.
        status: AlStatus,
        /// Its AL status code.
        code: AlStatusCode,
    },
    /// Devices stopped answering.
    DevicesLost {
        /// Devices configured.
        expected: u16,
        /// Devices answering.
        responding: u16,
    },
    /// The device has no mailbox (or no CoE).
    NoMailbox {
        /// The device.
        device: DeviceRef,
    },
    /// The device answered with a mailbox error.
    MailboxError {
        /// The device.
        device: DeviceRef,
        /// Its code.
        code: MailboxErrorCode,
    },
    /// An unexpected mailbox answer.
    Mailbox {
        /// The device.
        device: DeviceRef,
        /// What was wrong.
        what: &'static str,
    },
    /// An SDO transfer failed (the device aborted, or the answer was out of protocol).
    Sdo {
        /// The device.
        device: DeviceRef,
        /// The error.
        error: SdoError,
    },
    /// The configuration does not fit the segment.
    Config {
        /// The device, if one.
        device: Option<DeviceRef>,
        /// What does not fit.
        what: &'static str,
    },
}

impl EcError {
    /// Wraps an I/O error.
    pub fn io(e: &io::Error) -> Self {
        EcError::Io {
            kind: e.kind(),
            code: e.raw_os_error(),
        }
    }

    /// Whether the device reported it (AL codes, mailbox errors, SDO aborts) rather than the
    /// link or the frames.
    pub fn is_device_report(&self) -> bool {
        matches!(
            self,
            EcError::AlTransition { .. }
                | EcError::AlStatus { .. }
                | EcError::MailboxError { .. }
                | EcError::Sdo {
                    error: SdoError::Aborted { .. },
                    ..
                }
        )
    }
}

impl fmt::Display for EcError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EcError::Io { kind, code } => match code {
                Some(c) => write!(f, "raw socket: {kind} (os error {c})"),
                None => write!(f, "raw socket: {kind}"),
            },
            EcError::Timeout { what, waited_us } => {
                write!(f, "no reply to {what} within {waited_us} µs")
            }
            EcError::WorkingCounter {
                command,
                address,
                expected,
                received,
            } => {
                if command.is_logical() {
                    write!(f, "{command} {address:#010x}: ")?;
                } else {
                    write!(
                        f,
                        "{command} {:#06x}:{:#06x}: ",
                        *address as u16,
                        address >> 16
                    )?;
                }
                write!(f, "working counter {received}, expected {expected}")
            }
            EcError::Reply(what) => write!(f, "reply frame: {what}"),
            EcError::Frame(e) => write!(f, "reply frame: {e}"),
            EcError::NoDevices => f.write_str("no EtherCAT device answers on the segment"),
            EcError::TooManyDevices { found, limit } => {
                write!(f, "{found} devices answer, at most {limit} configured")
            }
            EcError::Sii { device, error } => write!(f, "{device}: SII: {error}"),
            EcError::SiiAccess { device, status } => {
                write!(f, "{device}: SII interface error, status {status:#06x}")
            }
            EcError::AlTransition {
                device,
                target,
                status,
                code,
            } => write!(f, "{device}: {target} refused: {code}, AL {status}"),
            EcError::AlStatus {
                device,
                status,
                code,
                // Device and code first.
            } => write!(f, "{device}: {code}, AL {status}"),
            EcError::DevicesLost {
                expected,
                responding,
            } => write!(f, "{responding} of {expected} devices answer"),
            EcError::NoMailbox { device } => write!(f, "{device}: no CoE mailbox"),
            EcError::MailboxError { device, code } => write!(f, "{device}: {code}"),
            EcError::Mailbox { device, what } => write!(f, "{device}: mailbox: {what}"),
            EcError::Sdo { device, error } => write!(f, "{device}: SDO {error}"),
            EcError::Config { device, what } => match device {
                Some(d) => write!(f, "{d}: {what}"),
                None => f.write_str(what),
            },
        }
    }
}

impl std::error::Error for EcError {}
