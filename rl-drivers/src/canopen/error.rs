//! What can go wrong between a CANopen master and its CiA 402 drives, typed, each naming the
//! node (and the state, object or code), the most telling part (node, code) first. The generic
//! error keeps each whole (`tests/error_texts.rs` renders the longest). The device reports them through the generic
//! [`Error`](crate::Error) with the source `"CANopen"`, `"CiA 402"`, `"EMCY"`, `"SDO"`,
//! `"heartbeat"` or `"EDS"`.

use core::fmt;
use core::time::Duration;

use crate::cia402::{Mode, PowerState, UnitsError};
use crate::proto::canopen::eds::CheckError;
use crate::proto::canopen::emcy::{self, Emergency};
use crate::proto::canopen::nmt;
use crate::proto::canopen::sdo_client::SdoError;

/// A CANopen or CiA 402 failure of one node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CanopenError {
    /// An SDO transfer failed.
    Sdo {
        /// The node.
        node: u8,
        /// Why.
        error: SdoError,
    },
    /// The node's device type (0x1000) is not a CiA 402 drive.
    NotADrive {
        /// The node.
        node: u8,
        /// 0x1000's value.
        device_type: u32,
    },
    /// The drive does not support the mode (0x6502).
    ModeUnsupported {
        /// The node.
        node: u8,
        /// The mode.
        mode: Mode,
        /// 0x6502's value.
        supported: u32,
    },
    /// The drive reports another mode (0x6061) than was set.
    ModeNotTaken {
        /// The node.
        node: u8,
        /// The mode set.
        mode: Mode,
        /// The code reported.
        display: i8,
    },
    /// A power state transition did not complete in time.
    Stuck {
        /// The node.
        node: u8,
        /// The state it stayed in (`None`: no statusword arrived).
        state: Option<PowerState>,
        /// How long it was given.
        waited: Duration,
        /// Where it was to go.
        goal: &'static str,
    },
    /// The drive is in fault (or reacting to one).
    DriveFault {
        /// The node.
        node: u8,
        /// The state.
        state: PowerState,
        /// The last emergency message it sent, if any.
        emcy: Option<Emergency>,
    },
    /// The drive left operation enabled by itself.
    Disabled {
        /// The node.
        node: u8,
        /// The state it is in now.
        state: PowerState,
    },
    /// An emergency message.
    Emergency {
        /// The node.
        node: u8,
        /// The message.
        emcy: Emergency,
    },
    /// No heartbeat within the consumer time.
    HeartbeatLost {
        /// The node.
        node: u8,
        /// The consumer time.
        timeout: Duration,
    },
    /// The node reported another NMT state than expected (a boot-up: it was reset).
    NmtState {
        /// The node.
        node: u8,
        /// The state it reported.
        state: nmt::State,
    },
    /// The drive signals a following error (statusword bit 13).
    FollowingError {
        /// The node.
        node: u8,
    },
    /// TPDOs missing at the cycle's deadline.
    TpdoLost {
        /// How many this cycle.
        count: u32,
        /// The first node missing.
        node: u8,
    },
    /// A TPDO of the wrong length.
    TpdoLength {
        /// The node.
        node: u8,
        /// Its length.
        len: usize,
        /// The mapped length.
        expected: usize,
    },
    /// The drive's units (position encoder resolution, gear ratio, feed constant, rated
    /// torque) cannot be read and were not given.
    Units {
        /// The node.
        node: u8,
        /// Which object, and why.
        error: UnitsError<SdoError>,
    },
    /// The node's EDS refuses what the master would configure.
    Eds {
        /// The node.
        node: u8,
        /// Why.
        error: CheckError,
    },
}

impl fmt::Display for CanopenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CanopenError::Sdo { node, error } => match error {
                // The code comes before the name.
                SdoError::Aborted { address, code } => {
                    write!(f, "node {node}: {address} aborted {code}")
                }
                SdoError::Timeout { address } => {
                    write!(f, "node {node}: {address} no SDO answer in time")
                }
                e => write!(f, "node {node}: {e}"),
            },
            CanopenError::NotADrive { node, device_type } => write!(
                f,
                "node {node}: device type {device_type:#010x} is not a CiA 402 drive (profile {})",
                device_type & 0xFFFF
            ),
            CanopenError::ModeUnsupported {
                node,
                mode,
                supported,
            } => write!(
                f,
                "node {node}: {mode} is not among the supported drive modes (0x6502 = {supported:#010x})"
            ),
            CanopenError::ModeNotTaken {
                node,
                mode,
                display,
            } => write!(
                f,
                "node {node}: modes of operation display is {display}, not {} ({mode})",
                mode.code()
            ),
            CanopenError::Stuck {
                node,
                state: Some(state),
                waited,
                goal,
            } => write!(
                f,
                "node {node}: `{state}` for {} ms, not {goal}",
                waited.as_millis()
            ),
            CanopenError::Stuck {
                node,
                state: None,
                waited,
                goal,
            } => write!(
                f,
                "node {node}: no statusword for {} ms on the way to {goal}",
                waited.as_millis()
            ),
            CanopenError::DriveFault {
                node,
                emcy: Some(e),
                ..
            } => write!(
                f,
                "node {node} faulted (EMCY {:#06x} {})",
                e.code,
                emcy::code_name(e.code)
            ),
            CanopenError::DriveFault {
                node,
                state,
                emcy: None,
            } => write!(f, "node {node}: drive in `{state}` (no EMCY received)"),
            CanopenError::Disabled { node, state } => {
                write!(
                    f,
                    "node {node}: the drive left operation enabled, now `{state}`"
                )
            }
            CanopenError::Emergency { node, emcy: e } => write!(
                f,
                "node {node}: EMCY {:#06x} {}, register {:#04x}",
                e.code,
                emcy::code_name(e.code),
                e.register
            ),
            CanopenError::HeartbeatLost { node, timeout } => write!(
                f,
                "node {node}: no heartbeat for {} ms",
                timeout.as_millis()
            ),
            CanopenError::NmtState { node, state } => {
                write!(f, "node {node}: unexpected NMT state `{state}`")
            }
            CanopenError::FollowingError { node } => {
                write!(f, "node {node}: following error (statusword bit 13)")
            }
            CanopenError::TpdoLost { count, node } => write!(
                f,
                "{count} TPDO(s) missing at the cycle's deadline (first: node {node})"
            ),
            CanopenError::TpdoLength {
                node,
                len,
                expected,
            } => write!(f, "node {node}: TPDO of {len} bytes, {expected} mapped"),
            CanopenError::Eds { node, error } => write!(f, "node {node}: EDS: {error}"),
            CanopenError::Units {
                node,
                error: UnitsError::Unreadable { object, error },
            } => {
                write!(
                    f,
                    "node {node}: cannot read {:#06x}:{} ({}): {}; give the axis units instead",
                    object.index,
                    object.sub,
                    object.name,
                    error.reason()
                )
            }
            CanopenError::Units { node, error } => write!(f, "node {node}: {error}"),
        }
    }
}

impl std::error::Error for CanopenError {}
