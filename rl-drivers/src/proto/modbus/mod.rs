//! Modbus (Modbus Organization, *MODBUS Application Protocol Specification V1.1b3* and *MODBUS
//! over Serial Line V1.02*): the protocol data units of the register functions, and their two
//! framings — RTU on a serial line (unit address + PDU + CRC-16) and TCP (MBAP header + PDU).
//!
//! - [`pdu`]: requests and responses of the register functions (read holding registers 0x03,
//!   read input registers 0x04, write single register 0x06, write multiple registers 0x10,
//!   read/write multiple registers 0x17) and exception responses;
//! - [`rtu`]: RTU framing, the CRC, frame lengths for a receiver that reads byte by byte, and
//!   the silent intervals at a baud rate;
//! - [`tcp`]: the MBAP header.
//!
//! Everything is `no_std` and allocation-free: a PDU borrows its register bytes, encoding
//! writes into the caller's buffer. Decoding never panics and names what is wrong.

pub mod pdu;
pub mod rtu;
pub mod tcp;

use core::fmt;

pub use pdu::{ExceptionCode, FunctionCode, Registers, Request, Response};

/// The largest PDU (function code + data), bytes.
pub const MAX_PDU: usize = 253;

/// Why bytes are not a valid Modbus frame or PDU.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModbusError {
    /// Fewer bytes than `need`.
    TooShort {
        /// The part being read.
        what: &'static str,
        /// Bytes needed.
        need: usize,
        /// Bytes given.
        got: usize,
    },
    /// More bytes than the part has.
    TooLong {
        /// The part being read.
        what: &'static str,
        /// Its length.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// The CRC does not match the frame.
    Crc {
        /// The CRC of the bytes.
        computed: u16,
        /// The CRC the frame carries.
        received: u16,
    },
    /// A register count outside what the function allows.
    Count {
        /// The function.
        function: u8,
        /// The count given.
        count: u16,
        /// The largest allowed.
        max: u16,
    },
    /// A byte count that does not match the register count (or is odd).
    ByteCount {
        /// The function.
        function: u8,
        /// The byte count.
        byte_count: u8,
        /// What it should be.
        expected: usize,
    },
    /// A function code this codec does not decode.
    UnsupportedFunction(u8),
    /// An exception code the specification does not define.
    UnknownException(u8),
    /// An MBAP header whose protocol identifier is not 0.
    ProtocolId(u16),
    /// An MBAP length field outside 2..=254 or other than the bytes that follow.
    MbapLength(u16),
    /// The output buffer is too small.
    BufferTooSmall {
        /// Bytes needed.
        need: usize,
        /// Bytes available.
        got: usize,
    },
    /// A response to another function than the request's.
    WrongFunction {
        /// The request's.
        expected: u8,
        /// The response's.
        got: u8,
    },
    /// A response from another unit than the one asked.
    WrongUnit {
        /// The unit asked.
        expected: u8,
        /// The unit that answered.
        got: u8,
    },
}

impl fmt::Display for ModbusError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooShort { what, need, got } => {
                write!(f, "{what}: {got} bytes, need {need}")
            }
            Self::TooLong {
                what,
                expected,
                got,
            } => write!(f, "{what}: {got} bytes, expected {expected}"),
            Self::Crc { computed, received } => {
                write!(f, "CRC {received:#06x}, computed {computed:#06x}")
            }
            Self::Count {
                function,
                count,
                max,
            } => write!(
                f,
                "function {function:#04x}: {count} registers, allowed 1 to {max}"
            ),
            Self::ByteCount {
                function,
                byte_count,
                expected,
            } => write!(
                f,
                "function {function:#04x}: byte count {byte_count}, expected {expected}"
            ),
            Self::UnsupportedFunction(c) => write!(f, "function {c:#04x} not supported"),
            Self::UnknownException(c) => write!(f, "unknown exception code {c:#04x}"),
            Self::ProtocolId(p) => write!(f, "MBAP protocol id {p}, expected 0"),
            Self::MbapLength(l) => write!(f, "MBAP length {l} does not fit the frame"),
            Self::BufferTooSmall { need, got } => {
                write!(f, "buffer of {got} bytes, need {need}")
            }
            Self::WrongFunction { expected, got } => {
                write!(f, "response to function {got:#04x}, asked {expected:#04x}")
            }
            Self::WrongUnit { expected, got } => {
                write!(f, "response from unit {got}, asked unit {expected}")
            }
        }
    }
}
