//! Modbus protocol data units of the register functions (*MODBUS Application Protocol
//! Specification V1.1b3*, section 6): a function code and its data, big endian.
//!
//! | function | request | normal response |
//! |---|---|---|
//! | 0x03 read holding registers | address, count (1..=125) | byte count, values |
//! | 0x04 read input registers | address, count (1..=125) | byte count, values |
//! | 0x06 write single register | address, value | the request echoed |
//! | 0x10 write multiple registers | address, count (1..=123), byte count, values | address, count |
//! | 0x17 read/write multiple registers | read address, read count (1..=125), write address, write count (1..=121), byte count, values | byte count, values read |
//!
//! An exception response is the function code with bit 7 set and an exception code.

use core::fmt;

use super::{MAX_PDU, ModbusError};

/// The function codes this codec encodes and decodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FunctionCode {
    /// 0x03.
    ReadHoldingRegisters,
    /// 0x04.
    ReadInputRegisters,
    /// 0x06.
    WriteSingleRegister,
    /// 0x10.
    WriteMultipleRegisters,
    /// 0x17.
    ReadWriteMultipleRegisters,
}

impl FunctionCode {
    /// The code on the wire.
    pub const fn code(self) -> u8 {
        match self {
            Self::ReadHoldingRegisters => 0x03,
            Self::ReadInputRegisters => 0x04,
            Self::WriteSingleRegister => 0x06,
            Self::WriteMultipleRegisters => 0x10,
            Self::ReadWriteMultipleRegisters => 0x17,
        }
    }

    /// The function of a code.
    pub const fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            0x03 => Self::ReadHoldingRegisters,
            0x04 => Self::ReadInputRegisters,
            0x06 => Self::WriteSingleRegister,
            0x10 => Self::WriteMultipleRegisters,
            0x17 => Self::ReadWriteMultipleRegisters,
            _ => return None,
        })
    }
}

/// Largest register count of a read (0x03, 0x04, and the read of 0x17).
pub const MAX_READ: u16 = 125;
/// Largest register count of 0x10.
pub const MAX_WRITE: u16 = 123;
/// Largest register count written by 0x17.
pub const MAX_READ_WRITE: u16 = 121;

/// An exception code (section 7).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ExceptionCode {
    /// 0x01: the function is not supported.
    IllegalFunction,
    /// 0x02: the address (or address + count) is not valid.
    IllegalDataAddress,
    /// 0x03: a value in the request is not allowed (e.g. the count).
    IllegalDataValue,
    /// 0x04: the server failed while performing the action.
    ServerDeviceFailure,
    /// 0x05: accepted, a long action in progress.
    Acknowledge,
    /// 0x06: busy with a long action.
    ServerDeviceBusy,
    /// 0x08: memory parity error.
    MemoryParityError,
    /// 0x0A: the gateway has no path.
    GatewayPathUnavailable,
    /// 0x0B: the gateway's target did not answer.
    GatewayTargetFailedToRespond,
}

impl ExceptionCode {
    /// The code on the wire.
    pub const fn code(self) -> u8 {
        match self {
            Self::IllegalFunction => 0x01,
            Self::IllegalDataAddress => 0x02,
            Self::IllegalDataValue => 0x03,
            Self::ServerDeviceFailure => 0x04,
            Self::Acknowledge => 0x05,
            Self::ServerDeviceBusy => 0x06,
            Self::MemoryParityError => 0x08,
            Self::GatewayPathUnavailable => 0x0A,
            Self::GatewayTargetFailedToRespond => 0x0B,
        }
    }

    /// The exception of a code.
    pub const fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            0x01 => Self::IllegalFunction,
            0x02 => Self::IllegalDataAddress,
            0x03 => Self::IllegalDataValue,
            0x04 => Self::ServerDeviceFailure,
            0x05 => Self::Acknowledge,
            0x06 => Self::ServerDeviceBusy,
            0x08 => Self::MemoryParityError,
            0x0A => Self::GatewayPathUnavailable,
            0x0B => Self::GatewayTargetFailedToRespond,
            _ => return None,
        })
    }
}

impl fmt::Display for ExceptionCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::IllegalFunction => "illegal function",
            Self::IllegalDataAddress => "illegal data address",
            Self::IllegalDataValue => "illegal data value",
            Self::ServerDeviceFailure => "server device failure",
            Self::Acknowledge => "acknowledge",
            Self::ServerDeviceBusy => "server device busy",
            Self::MemoryParityError => "memory parity error",
            Self::GatewayPathUnavailable => "gateway path unavailable",
            Self::GatewayTargetFailedToRespond => "gateway target failed to respond",
        })
    }
}

/// Register values: big-endian bytes from the wire, or words from the caller. Compared by
/// value.
#[derive(Clone, Copy, Debug)]
pub enum Registers<'a> {
    /// Two bytes per register, big endian (what decoding gives).
    Bytes(&'a [u8]),
    /// One word per register.
    Words(&'a [u16]),
}

impl<'a> Registers<'a> {
    /// Number of registers.
    pub const fn len(&self) -> usize {
        match self {
            Self::Bytes(b) => b.len() / 2,
            Self::Words(w) => w.len(),
        }
    }

    /// Whether there are none.
    pub const fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Register `i`, if there is one.
    pub fn get(&self, i: usize) -> Option<u16> {
        match self {
            Self::Bytes(b) => Some(u16::from_be_bytes([*b.get(2 * i)?, *b.get(2 * i + 1)?])),
            Self::Words(w) => w.get(i).copied(),
        }
    }

    /// The values in order.
    pub fn iter(&self) -> impl Iterator<Item = u16> + '_ {
        (0..self.len()).filter_map(move |i| self.get(i))
    }

    /// Copies the values into `out` (which must have [`len`](Self::len) elements or more);
    /// returns how many were copied.
    pub fn copy_to(&self, out: &mut [u16]) -> usize {
        let n = self.len().min(out.len());
        for (k, o) in out.iter_mut().enumerate().take(n) {
            *o = self.get(k).unwrap_or(0);
        }
        n
    }

    fn write(&self, out: &mut [u8]) {
        for (k, v) in self.iter().enumerate() {
            out[2 * k..2 * k + 2].copy_from_slice(&v.to_be_bytes());
        }
    }
}

impl PartialEq for Registers<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl Eq for Registers<'_> {}

/// A request PDU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request<'a> {
    /// 0x03.
    ReadHoldingRegisters {
        /// The first register.
        address: u16,
        /// How many.
        count: u16,
    },
    /// 0x04.
    ReadInputRegisters {
        /// The first register.
        address: u16,
        /// How many.
        count: u16,
    },
    /// 0x06.
    WriteSingleRegister {
        /// The register.
        address: u16,
        /// Its new value.
        value: u16,
    },
    /// 0x10.
    WriteMultipleRegisters {
        /// The first register.
        address: u16,
        /// The values.
        values: Registers<'a>,
    },
    /// 0x17: the write happens before the read.
    ReadWriteMultipleRegisters {
        /// The first register read.
        read_address: u16,
        /// How many are read.
        read_count: u16,
        /// The first register written.
        write_address: u16,
        /// The values written.
        values: Registers<'a>,
    },
}

fn be16(b: &[u8], at: usize) -> u16 {
    u16::from_be_bytes([b[at], b[at + 1]])
}

fn need(what: &'static str, bytes: &[u8], n: usize) -> Result<(), ModbusError> {
    if bytes.len() < n {
        Err(ModbusError::TooShort {
            what,
            need: n,
            got: bytes.len(),
        })
    } else {
        Ok(())
    }
}

fn exact(what: &'static str, bytes: &[u8], n: usize) -> Result<(), ModbusError> {
    need(what, bytes, n)?;
    if bytes.len() > n {
        return Err(ModbusError::TooLong {
            what,
            expected: n,
            got: bytes.len(),
        });
    }
    Ok(())
}

fn check_count(function: u8, count: u16, max: u16) -> Result<(), ModbusError> {
    if count == 0 || count > max {
        Err(ModbusError::Count {
            function,
            count,
            max,
        })
    } else {
        Ok(())
    }
}

fn room(out: &[u8], n: usize) -> Result<(), ModbusError> {
    if out.len() < n {
        Err(ModbusError::BufferTooSmall {
            need: n,
            got: out.len(),
        })
    } else {
        Ok(())
    }
}

impl<'a> Request<'a> {
    /// The request's function.
    pub const fn function(&self) -> FunctionCode {
        match self {
            Self::ReadHoldingRegisters { .. } => FunctionCode::ReadHoldingRegisters,
            Self::ReadInputRegisters { .. } => FunctionCode::ReadInputRegisters,
            Self::WriteSingleRegister { .. } => FunctionCode::WriteSingleRegister,
            Self::WriteMultipleRegisters { .. } => FunctionCode::WriteMultipleRegisters,
            Self::ReadWriteMultipleRegisters { .. } => FunctionCode::ReadWriteMultipleRegisters,
        }
    }

    /// Checks the counts against the function's limits.
    pub fn check(&self) -> Result<(), ModbusError> {
        let f = self.function().code();
        match self {
            Self::ReadHoldingRegisters { count, .. } | Self::ReadInputRegisters { count, .. } => {
                check_count(f, *count, MAX_READ)
            }
            Self::WriteSingleRegister { .. } => Ok(()),
            Self::WriteMultipleRegisters { values, .. } => check_count(
                f,
                u16::try_from(values.len()).unwrap_or(u16::MAX),
                MAX_WRITE,
            ),
            Self::ReadWriteMultipleRegisters {
                read_count, values, ..
            } => {
                check_count(f, *read_count, MAX_READ)?;
                check_count(
                    f,
                    u16::try_from(values.len()).unwrap_or(u16::MAX),
                    MAX_READ_WRITE,
                )
            }
        }
    }

    /// Bytes of the encoded PDU.
    pub fn encoded_len(&self) -> usize {
        match self {
            Self::ReadHoldingRegisters { .. }
            | Self::ReadInputRegisters { .. }
            | Self::WriteSingleRegister { .. } => 5,
            Self::WriteMultipleRegisters { values, .. } => 6 + 2 * values.len(),
            Self::ReadWriteMultipleRegisters { values, .. } => 10 + 2 * values.len(),
        }
    }

    /// Writes the PDU into `out`; returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, ModbusError> {
        self.check()?;
        let n = self.encoded_len();
        room(out, n)?;
        out[0] = self.function().code();
        match self {
            Self::ReadHoldingRegisters { address, count }
            | Self::ReadInputRegisters { address, count } => {
                out[1..3].copy_from_slice(&address.to_be_bytes());
                out[3..5].copy_from_slice(&count.to_be_bytes());
            }
            Self::WriteSingleRegister { address, value } => {
                out[1..3].copy_from_slice(&address.to_be_bytes());
                out[3..5].copy_from_slice(&value.to_be_bytes());
            }
            Self::WriteMultipleRegisters { address, values } => {
                out[1..3].copy_from_slice(&address.to_be_bytes());
                // Counts are checked above: at most 123 registers.
                out[3..5].copy_from_slice(&(values.len() as u16).to_be_bytes());
                out[5] = (2 * values.len()) as u8;
                values.write(&mut out[6..n]);
            }
            Self::ReadWriteMultipleRegisters {
                read_address,
                read_count,
                write_address,
                values,
            } => {
                out[1..3].copy_from_slice(&read_address.to_be_bytes());
                out[3..5].copy_from_slice(&read_count.to_be_bytes());
                out[5..7].copy_from_slice(&write_address.to_be_bytes());
                out[7..9].copy_from_slice(&(values.len() as u16).to_be_bytes());
                out[9] = (2 * values.len()) as u8;
                values.write(&mut out[10..n]);
            }
        }
        Ok(n)
    }

    /// Decodes exactly one request PDU. A function this codec does not know is
    /// [`ModbusError::UnsupportedFunction`] (a server answers it with
    /// [`ExceptionCode::IllegalFunction`]); counts out of range are [`ModbusError::Count`]
    /// (answered with [`ExceptionCode::IllegalDataValue`]).
    pub fn decode(pdu: &'a [u8]) -> Result<Self, ModbusError> {
        need("request PDU", pdu, 1)?;
        if pdu.len() > MAX_PDU {
            return Err(ModbusError::TooLong {
                what: "request PDU",
                expected: MAX_PDU,
                got: pdu.len(),
            });
        }
        let code = pdu[0];
        let function =
            FunctionCode::from_code(code).ok_or(ModbusError::UnsupportedFunction(code))?;
        let r = match function {
            FunctionCode::ReadHoldingRegisters | FunctionCode::ReadInputRegisters => {
                exact("read request", pdu, 5)?;
                let (address, count) = (be16(pdu, 1), be16(pdu, 3));
                if function == FunctionCode::ReadHoldingRegisters {
                    Self::ReadHoldingRegisters { address, count }
                } else {
                    Self::ReadInputRegisters { address, count }
                }
            }
            FunctionCode::WriteSingleRegister => {
                exact("write single register request", pdu, 5)?;
                Self::WriteSingleRegister {
                    address: be16(pdu, 1),
                    value: be16(pdu, 3),
                }
            }
            FunctionCode::WriteMultipleRegisters => {
                need("write multiple registers request", pdu, 6)?;
                let count = be16(pdu, 3);
                check_count(code, count, MAX_WRITE)?;
                let byte_count = pdu[5];
                if usize::from(byte_count) != 2 * usize::from(count) {
                    return Err(ModbusError::ByteCount {
                        function: code,
                        byte_count,
                        expected: 2 * usize::from(count),
                    });
                }
                exact(
                    "write multiple registers request",
                    pdu,
                    6 + usize::from(byte_count),
                )?;
                Self::WriteMultipleRegisters {
                    address: be16(pdu, 1),
                    values: Registers::Bytes(&pdu[6..]),
                }
            }
            FunctionCode::ReadWriteMultipleRegisters => {
                need("read/write multiple registers request", pdu, 10)?;
                let write_count = be16(pdu, 7);
                check_count(code, be16(pdu, 3), MAX_READ)?;
                check_count(code, write_count, MAX_READ_WRITE)?;
                let byte_count = pdu[9];
                if usize::from(byte_count) != 2 * usize::from(write_count) {
                    return Err(ModbusError::ByteCount {
                        function: code,
                        byte_count,
                        expected: 2 * usize::from(write_count),
                    });
                }
                exact(
                    "read/write multiple registers request",
                    pdu,
                    10 + usize::from(byte_count),
                )?;
                Self::ReadWriteMultipleRegisters {
                    read_address: be16(pdu, 1),
                    read_count: be16(pdu, 3),
                    write_address: be16(pdu, 5),
                    values: Registers::Bytes(&pdu[10..]),
                }
            }
        };
        r.check()?;
        Ok(r)
    }
}

/// A response PDU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Response<'a> {
    /// 0x03: the registers read.
    ReadHoldingRegisters(Registers<'a>),
    /// 0x04: the registers read.
    ReadInputRegisters(Registers<'a>),
    /// 0x06: the request echoed.
    WriteSingleRegister {
        /// The register.
        address: u16,
        /// Its value.
        value: u16,
    },
    /// 0x10: what was written.
    WriteMultipleRegisters {
        /// The first register.
        address: u16,
        /// How many.
        count: u16,
    },
    /// 0x17: the registers read.
    ReadWriteMultipleRegisters(Registers<'a>),
    /// The server refused the request.
    Exception {
        /// The request's function code (without bit 7).
        function: u8,
        /// Why.
        code: ExceptionCode,
    },
}

impl<'a> Response<'a> {
    /// The function code on the wire (with bit 7 for an exception).
    pub const fn function_code(&self) -> u8 {
        match self {
            Self::ReadHoldingRegisters(_) => 0x03,
            Self::ReadInputRegisters(_) => 0x04,
            Self::WriteSingleRegister { .. } => 0x06,
            Self::WriteMultipleRegisters { .. } => 0x10,
            Self::ReadWriteMultipleRegisters(_) => 0x17,
            Self::Exception { function, .. } => *function | 0x80,
        }
    }

    /// Bytes of the encoded PDU.
    pub fn encoded_len(&self) -> usize {
        match self {
            Self::ReadHoldingRegisters(r)
            | Self::ReadInputRegisters(r)
            | Self::ReadWriteMultipleRegisters(r) => 2 + 2 * r.len(),
            Self::WriteSingleRegister { .. } | Self::WriteMultipleRegisters { .. } => 5,
            Self::Exception { .. } => 2,
        }
    }

    /// Writes the PDU into `out`; returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, ModbusError> {
        let n = self.encoded_len();
        room(out, n)?;
        out[0] = self.function_code();
        match self {
            Self::ReadHoldingRegisters(r)
            | Self::ReadInputRegisters(r)
            | Self::ReadWriteMultipleRegisters(r) => {
                check_count(out[0], u16::try_from(r.len()).unwrap_or(u16::MAX), MAX_READ)?;
                out[1] = (2 * r.len()) as u8;
                r.write(&mut out[2..n]);
            }
            Self::WriteSingleRegister { address, value } => {
                out[1..3].copy_from_slice(&address.to_be_bytes());
                out[3..5].copy_from_slice(&value.to_be_bytes());
            }
            Self::WriteMultipleRegisters { address, count } => {
                out[1..3].copy_from_slice(&address.to_be_bytes());
                out[3..5].copy_from_slice(&count.to_be_bytes());
            }
            Self::Exception { code, .. } => out[1] = code.code(),
        }
        Ok(n)
    }

    /// Decodes exactly one response PDU.
    pub fn decode(pdu: &'a [u8]) -> Result<Self, ModbusError> {
        need("response PDU", pdu, 2)?;
        let code = pdu[0];
        if code & 0x80 != 0 {
            exact("exception response", pdu, 2)?;
            let e =
                ExceptionCode::from_code(pdu[1]).ok_or(ModbusError::UnknownException(pdu[1]))?;
            return Ok(Self::Exception {
                function: code & 0x7F,
                code: e,
            });
        }
        let function =
            FunctionCode::from_code(code).ok_or(ModbusError::UnsupportedFunction(code))?;
        Ok(match function {
            FunctionCode::ReadHoldingRegisters
            | FunctionCode::ReadInputRegisters
            | FunctionCode::ReadWriteMultipleRegisters => {
                let byte_count = pdu[1];
                if byte_count == 0 || byte_count % 2 != 0 || u16::from(byte_count) > 2 * MAX_READ {
                    return Err(ModbusError::ByteCount {
                        function: code,
                        byte_count,
                        expected: 2 * usize::from(byte_count / 2).max(1),
                    });
                }
                exact("read response", pdu, 2 + usize::from(byte_count))?;
                let r = Registers::Bytes(&pdu[2..]);
                match function {
                    FunctionCode::ReadHoldingRegisters => Self::ReadHoldingRegisters(r),
                    FunctionCode::ReadInputRegisters => Self::ReadInputRegisters(r),
                    _ => Self::ReadWriteMultipleRegisters(r),
                }
            }
            FunctionCode::WriteSingleRegister => {
                exact("write single register response", pdu, 5)?;
                Self::WriteSingleRegister {
                    address: be16(pdu, 1),
                    value: be16(pdu, 3),
                }
            }
            FunctionCode::WriteMultipleRegisters => {
                exact("write multiple registers response", pdu, 5)?;
                Self::WriteMultipleRegisters {
                    address: be16(pdu, 1),
                    count: be16(pdu, 3),
                }
            }
        })
    }

    /// Checks that this answers `request`: the same function (or its exception), as many
    /// registers as asked, a write echoed as sent. An exception passes: the caller handles it.
    pub fn check_answers(&self, request: &Request<'_>) -> Result<(), ModbusError> {
        let expected = request.function().code();
        let got = self.function_code() & 0x7F;
        if got != expected {
            return Err(ModbusError::WrongFunction { expected, got });
        }
        let mismatch = |byte_count: usize, registers: usize| ModbusError::ByteCount {
            function: expected,
            byte_count: u8::try_from(byte_count).unwrap_or(u8::MAX),
            expected: 2 * registers,
        };
        match (self, request) {
            (Self::Exception { .. }, _) => Ok(()),
            (
                Self::ReadHoldingRegisters(r) | Self::ReadInputRegisters(r),
                Request::ReadHoldingRegisters { count, .. }
                | Request::ReadInputRegisters { count, .. },
            )
            | (
                Self::ReadWriteMultipleRegisters(r),
                Request::ReadWriteMultipleRegisters {
                    read_count: count, ..
                },
            ) => {
                if r.len() == usize::from(*count) {
                    Ok(())
                } else {
                    Err(mismatch(2 * r.len(), usize::from(*count)))
                }
            }
            (
                Self::WriteSingleRegister { address, value },
                Request::WriteSingleRegister {
                    address: a,
                    value: v,
                },
            ) if address == a && value == v => Ok(()),
            (
                Self::WriteMultipleRegisters { address, count },
                Request::WriteMultipleRegisters { address: a, values },
            ) if address == a && usize::from(*count) == values.len() => Ok(()),
            _ => Err(ModbusError::WrongFunction { expected, got }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip() {
        let words = [0x0900, 0x0000, 0xFFFF];
        for r in [
            Request::ReadHoldingRegisters {
                address: 0x07D0,
                count: 3,
            },
            Request::ReadInputRegisters {
                address: 0x07D0,
                count: 1,
            },
            Request::WriteSingleRegister {
                address: 0x03E8,
                value: 0x0100,
            },
            Request::WriteMultipleRegisters {
                address: 0x03E8,
                values: Registers::Words(&words),
            },
            Request::ReadWriteMultipleRegisters {
                read_address: 0x07D0,
                read_count: 2,
                write_address: 0x03E8,
                values: Registers::Words(&words),
            },
        ] {
            let mut b = [0u8; 32];
            let n = r.encode(&mut b).unwrap();
            assert_eq!(n, r.encoded_len());
            assert_eq!(Request::decode(&b[..n]), Ok(r));
        }
    }

    #[test]
    fn counts_and_byte_counts_are_checked() {
        assert_eq!(
            Request::decode(&[0x03, 0, 0, 0, 0]),
            Err(ModbusError::Count {
                function: 3,
                count: 0,
                max: 125
            })
        );
        assert_eq!(
            Request::decode(&[0x04, 0, 0, 0, 126]),
            Err(ModbusError::Count {
                function: 4,
                count: 126,
                max: 125
            })
        );
        assert_eq!(
            Request::decode(&[0x10, 0, 0, 0, 1, 4, 0, 0, 0, 0]),
            Err(ModbusError::ByteCount {
                function: 0x10,
                byte_count: 4,
                expected: 2
            })
        );
        assert_eq!(
            Request::decode(&[0x2B, 0x0E, 1, 0]),
            Err(ModbusError::UnsupportedFunction(0x2B))
        );
        assert!(Request::decode(&[0x03, 0, 0, 0, 1, 9]).is_err(), "too long");
    }

    #[test]
    fn responses_round_trip_and_match_their_requests() {
        let read = Response::ReadInputRegisters(Registers::Bytes(&[0x31, 0x00]));
        let mut b = [0u8; 16];
        let n = read.encode(&mut b).unwrap();
        assert_eq!(&b[..n], &[0x04, 0x02, 0x31, 0x00]);
        assert_eq!(Response::decode(&b[..n]), Ok(read));
        let ask = Request::ReadInputRegisters {
            address: 0x07D0,
            count: 1,
        };
        assert_eq!(read.check_answers(&ask), Ok(()));
        let ask3 = Request::ReadInputRegisters {
            address: 0x07D0,
            count: 3,
        };
        assert!(read.check_answers(&ask3).is_err());
        let e = Response::decode(&[0x84, 0x02]).unwrap();
        assert_eq!(
            e,
            Response::Exception {
                function: 4,
                code: ExceptionCode::IllegalDataAddress
            }
        );
        assert_eq!(e.check_answers(&ask), Ok(()));
        assert_eq!(
            Response::decode(&[0x84, 0x07]),
            Err(ModbusError::UnknownException(7))
        );
        assert!(
            Response::decode(&[0x03, 0x03, 1, 2, 3]).is_err(),
            "odd byte count"
        );
    }
}
