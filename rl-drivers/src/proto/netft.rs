//! ATI Net F/T: the Raw Data Transfer (RDT) protocol on UDP port 49152, the calibration query
//! on TCP port 49151 (`READCALINFO`), and the force and torque units a calibration names.
//!
//! All fields are big endian (ATI's Net F/T manual, 9620-05-NET FT, "UDP Interface Using RDT"
//! and "TCP Interface"; the layouts agree with the peers the tests run, PyPI `netft` 2.0.1 and
//! `pynetft` 2.1.3):
//!
//! | message | layout | bytes |
//! |---|---|---|
//! | RDT request (client → sensor) | `u16 header = 0x1234`, `u16 command`, `u32 sample_count` (0 = endless) | 8 |
//! | RDT record (sensor → client) | `u32 rdt_sequence`, `u32 ft_sequence`, `u32 status`, `i32 Fx, Fy, Fz, Tx, Ty, Tz` (counts) | 36 |
//! | `READCALINFO` request | `u8 command = 1`, 19 reserved bytes | 20 |
//! | `READCALINFO` response | `u16 header = 0x1234`, `u8 force_units`, `u8 torque_units`, `u32 counts_per_force`, `u32 counts_per_torque`, `u16 scale_factors[6]` | 24 |
//!
//! A datagram of the buffered mode (command 3) carries several records back to back.
//! `rdt_sequence` counts the records of one stream (a gap is a lost datagram, a step back a
//! reordered or repeated one); `ft_sequence` counts the sensor's internal samples (7000 a
//! second), so it advances by more than one per record when the RDT rate is lower. A value in
//! SI units is `counts / counts_per_unit` in the calibration's unit, then converted
//! ([`ForceUnit::to_newton`], [`TorqueUnit::to_newton_metre`]). Bit 31 of `status` is the
//! sensor's error summary; the other bits name the cause and are passed on as they are.
//!
//! Decoding never panics and returns a typed [`NetFtError`] saying what and where.

use core::fmt;

/// The RDT server's UDP port.
pub const RDT_PORT: u16 = 49152;
/// The TCP command server's port (calibration query).
pub const TCP_PORT: u16 = 49151;
/// The first two bytes of an RDT request and of a TCP response.
pub const HEADER: u16 = 0x1234;
/// Bytes of an RDT request.
pub const REQUEST_LEN: usize = 8;
/// Bytes of one RDT record.
pub const RECORD_LEN: usize = 36;
/// Bytes of a TCP request.
pub const CALINFO_REQUEST_LEN: usize = 20;
/// Bytes of the `READCALINFO` response.
pub const CALINFO_RESPONSE_LEN: usize = 24;
/// The TCP command byte of `READCALINFO`.
pub const READCALINFO: u8 = 1;
/// The sensor's internal sample rate, Hz (`ft_sequence` counts these).
pub const INTERNAL_RATE_HZ: u32 = 7000;
/// Bit 31 of the status word: the sensor reports an error.
pub const STATUS_ERROR: u32 = 0x8000_0000;

/// What an RDT request asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RdtCommand {
    /// Stop streaming (0x0000).
    Stop,
    /// Stream one record per datagram at the RDT rate (0x0002).
    StartRealTime,
    /// Stream several records per datagram (0x0003).
    StartBuffered,
    /// Multi-unit streaming (0x0004).
    StartMultiUnit,
    /// Reset the threshold latch (0x0041).
    ResetThresholdLatch,
    /// Take the current reading as the zero (0x0042, "set software bias").
    SetSoftwareBias,
}

impl RdtCommand {
    /// The command's code on the wire.
    pub const fn code(self) -> u16 {
        match self {
            Self::Stop => 0x0000,
            Self::StartRealTime => 0x0002,
            Self::StartBuffered => 0x0003,
            Self::StartMultiUnit => 0x0004,
            Self::ResetThresholdLatch => 0x0041,
            Self::SetSoftwareBias => 0x0042,
        }
    }

    /// The command of a code.
    pub const fn from_code(code: u16) -> Option<Self> {
        Some(match code {
            0x0000 => Self::Stop,
            0x0002 => Self::StartRealTime,
            0x0003 => Self::StartBuffered,
            0x0004 => Self::StartMultiUnit,
            0x0041 => Self::ResetThresholdLatch,
            0x0042 => Self::SetSoftwareBias,
            _ => return None,
        })
    }
}

/// Why bytes are not a valid Net F/T message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NetFtError {
    /// `what` needs `expected` bytes (or a multiple of them), `got` were given.
    Length {
        /// The message.
        what: &'static str,
        /// Its length (or the length of one record).
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// The header is not 0x1234.
    Header {
        /// The message.
        what: &'static str,
        /// The header found.
        got: u16,
    },
    /// An RDT request with a command code the protocol does not define.
    UnknownCommand(u16),
    /// A TCP request with a command byte other than `READCALINFO`.
    UnknownTcpCommand(u8),
    /// A unit code the calibration table does not define.
    UnknownUnit {
        /// `"force"` or `"torque"`.
        quantity: &'static str,
        /// The code.
        code: u8,
    },
    /// A calibration with zero counts per unit.
    ZeroCounts {
        /// `"force"` or `"torque"`.
        quantity: &'static str,
    },
}

impl fmt::Display for NetFtError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Length {
                what,
                expected,
                got,
            } => write!(f, "{what}: {got} bytes, expected {expected}"),
            Self::Header { what, got } => {
                write!(f, "{what}: header {got:#06x}, expected 0x1234")
            }
            Self::UnknownCommand(c) => write!(f, "RDT request: unknown command {c:#06x}"),
            Self::UnknownTcpCommand(c) => write!(f, "TCP request: unknown command {c}"),
            Self::UnknownUnit { quantity, code } => {
                write!(f, "calibration: unknown {quantity} unit code {code}")
            }
            Self::ZeroCounts { quantity } => {
                write!(f, "calibration: zero counts per {quantity} unit")
            }
        }
    }
}

fn be_u16(b: &[u8], at: usize) -> u16 {
    u16::from_be_bytes([b[at], b[at + 1]])
}

fn be_u32(b: &[u8], at: usize) -> u32 {
    u32::from_be_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// An RDT request.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RdtRequest {
    /// What to do.
    pub command: RdtCommand,
    /// Records to send before stopping (0: until told to stop).
    pub sample_count: u32,
}

impl RdtRequest {
    /// A request.
    pub const fn new(command: RdtCommand, sample_count: u32) -> Self {
        Self {
            command,
            sample_count,
        }
    }

    /// The 8 bytes on the wire.
    pub fn to_bytes(&self) -> [u8; REQUEST_LEN] {
        let mut b = [0; REQUEST_LEN];
        b[0..2].copy_from_slice(&HEADER.to_be_bytes());
        b[2..4].copy_from_slice(&self.command.code().to_be_bytes());
        b[4..8].copy_from_slice(&self.sample_count.to_be_bytes());
        b
    }

    /// Decodes exactly one request.
    pub fn decode(bytes: &[u8]) -> Result<Self, NetFtError> {
        if bytes.len() != REQUEST_LEN {
            return Err(NetFtError::Length {
                what: "RDT request",
                expected: REQUEST_LEN,
                got: bytes.len(),
            });
        }
        let header = be_u16(bytes, 0);
        if header != HEADER {
            return Err(NetFtError::Header {
                what: "RDT request",
                got: header,
            });
        }
        let code = be_u16(bytes, 2);
        let command = RdtCommand::from_code(code).ok_or(NetFtError::UnknownCommand(code))?;
        Ok(Self {
            command,
            sample_count: be_u32(bytes, 4),
        })
    }
}

/// One RDT record: a sample of the six gauges' force and torque, in counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct RdtRecord {
    /// The record's place in its stream.
    pub rdt_sequence: u32,
    /// The sensor's internal sample number.
    pub ft_sequence: u32,
    /// The sensor's status word (bit 31: error).
    pub status: u32,
    /// `Fx, Fy, Fz` then `Tx, Ty, Tz`, in counts.
    pub counts: [i32; 6],
}

impl RdtRecord {
    /// The 36 bytes on the wire.
    pub fn to_bytes(&self) -> [u8; RECORD_LEN] {
        let mut b = [0; RECORD_LEN];
        b[0..4].copy_from_slice(&self.rdt_sequence.to_be_bytes());
        b[4..8].copy_from_slice(&self.ft_sequence.to_be_bytes());
        b[8..12].copy_from_slice(&self.status.to_be_bytes());
        for (k, c) in self.counts.iter().enumerate() {
            b[12 + 4 * k..16 + 4 * k].copy_from_slice(&c.to_be_bytes());
        }
        b
    }

    /// Decodes exactly one record.
    pub fn decode(bytes: &[u8]) -> Result<Self, NetFtError> {
        if bytes.len() != RECORD_LEN {
            return Err(NetFtError::Length {
                what: "RDT record",
                expected: RECORD_LEN,
                got: bytes.len(),
            });
        }
        let mut counts = [0; 6];
        for (k, c) in counts.iter_mut().enumerate() {
            *c = be_u32(bytes, 12 + 4 * k) as i32;
        }
        Ok(Self {
            rdt_sequence: be_u32(bytes, 0),
            ft_sequence: be_u32(bytes, 4),
            status: be_u32(bytes, 8),
            counts,
        })
    }

    /// Whether the status word reports an error (bit 31).
    pub const fn is_error(&self) -> bool {
        self.status & STATUS_ERROR != 0
    }
}

/// The records of one datagram (one, or several in the buffered mode): its length must be a
/// non-zero multiple of [`RECORD_LEN`].
pub fn records(datagram: &[u8]) -> Result<impl Iterator<Item = RdtRecord> + '_, NetFtError> {
    if datagram.is_empty() || datagram.len() % RECORD_LEN != 0 {
        return Err(NetFtError::Length {
            what: "RDT datagram",
            expected: RECORD_LEN,
            got: datagram.len(),
        });
    }
    // Every chunk has exactly RECORD_LEN bytes, so each decode succeeds.
    Ok(datagram
        .chunks_exact(RECORD_LEN)
        .filter_map(|c| RdtRecord::decode(c).ok()))
}

/// How far `next` lies after `last` in the 32-bit sequence space: 1 for the next record, more
/// after a gap; 0 for a repeat and negative for an older record (wrap-around handled, as a
/// signed 32-bit difference).
pub const fn sequence_step(last: u32, next: u32) -> i64 {
    next.wrapping_sub(last) as i32 as i64
}

/// The force unit of a calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ForceUnit {
    /// Pound-force (code 1).
    PoundForce,
    /// Newton (code 2).
    Newton,
    /// Kilopound-force (code 3).
    KilopoundForce,
    /// Kilonewton (code 4).
    Kilonewton,
    /// Kilogram-force (code 5).
    KilogramForce,
    /// Gram-force (code 6).
    GramForce,
}

impl ForceUnit {
    /// All units, in code order.
    pub const ALL: [Self; 6] = [
        Self::PoundForce,
        Self::Newton,
        Self::KilopoundForce,
        Self::Kilonewton,
        Self::KilogramForce,
        Self::GramForce,
    ];

    /// The unit's code in `READCALINFO`.
    pub const fn code(self) -> u8 {
        match self {
            Self::PoundForce => 1,
            Self::Newton => 2,
            Self::KilopoundForce => 3,
            Self::Kilonewton => 4,
            Self::KilogramForce => 5,
            Self::GramForce => 6,
        }
    }

    /// The unit of a code.
    pub const fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            1 => Self::PoundForce,
            2 => Self::Newton,
            3 => Self::KilopoundForce,
            4 => Self::Kilonewton,
            5 => Self::KilogramForce,
            6 => Self::GramForce,
            _ => return None,
        })
    }

    /// Newtons in one of this unit (the pound-force and kilogram-force are defined from the
    /// standard gravity 9.80665 m/s²).
    pub const fn to_newton(self) -> f64 {
        match self {
            Self::PoundForce => 4.448_221_615_260_5,
            Self::Newton => 1.0,
            Self::KilopoundForce => 4_448.221_615_260_5,
            Self::Kilonewton => 1_000.0,
            Self::KilogramForce => 9.806_65,
            Self::GramForce => 0.009_806_65,
        }
    }

    /// The name the sensor's web page uses (`scfgfu` in `netftapi2.xml`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::PoundForce => "lbf",
            Self::Newton => "N",
            Self::KilopoundForce => "klbf",
            Self::Kilonewton => "kN",
            Self::KilogramForce => "kgf",
            Self::GramForce => "gf",
        }
    }
}

/// The torque unit of a calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TorqueUnit {
    /// Pound-force inch (code 1).
    PoundForceInch,
    /// Pound-force foot (code 2).
    PoundForceFoot,
    /// Newton metre (code 3).
    NewtonMetre,
    /// Newton millimetre (code 4).
    NewtonMillimetre,
    /// Kilogram-force centimetre (code 5).
    KilogramForceCentimetre,
    /// Kilonewton metre (code 6).
    KilonewtonMetre,
}

impl TorqueUnit {
    /// All units, in code order.
    pub const ALL: [Self; 6] = [
        Self::PoundForceInch,
        Self::PoundForceFoot,
        Self::NewtonMetre,
        Self::NewtonMillimetre,
        Self::KilogramForceCentimetre,
        Self::KilonewtonMetre,
    ];

    /// The unit's code in `READCALINFO`.
    pub const fn code(self) -> u8 {
        match self {
            Self::PoundForceInch => 1,
            Self::PoundForceFoot => 2,
            Self::NewtonMetre => 3,
            Self::NewtonMillimetre => 4,
            Self::KilogramForceCentimetre => 5,
            Self::KilonewtonMetre => 6,
        }
    }

    /// The unit of a code.
    pub const fn from_code(code: u8) -> Option<Self> {
        Some(match code {
            1 => Self::PoundForceInch,
            2 => Self::PoundForceFoot,
            3 => Self::NewtonMetre,
            4 => Self::NewtonMillimetre,
            5 => Self::KilogramForceCentimetre,
            6 => Self::KilonewtonMetre,
            _ => return None,
        })
    }

    /// Newton metres in one of this unit.
    pub const fn to_newton_metre(self) -> f64 {
        match self {
            // 1 lbf × 0.0254 m and × 0.3048 m.
            Self::PoundForceInch => 0.112_984_829_027_616_7,
            Self::PoundForceFoot => 1.355_817_948_331_400_4,
            Self::NewtonMetre => 1.0,
            Self::NewtonMillimetre => 0.001,
            Self::KilogramForceCentimetre => 0.098_066_5,
            Self::KilonewtonMetre => 1_000.0,
        }
    }

    /// The name the sensor's web page uses (`scfgtu` in `netftapi2.xml`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::PoundForceInch => "lbf-in",
            Self::PoundForceFoot => "lbf-ft",
            Self::NewtonMetre => "Nm",
            Self::NewtonMillimetre => "Nmm",
            Self::KilogramForceCentimetre => "kgf-cm",
            Self::KilonewtonMetre => "kNm",
        }
    }
}

/// A sensor's calibration: how many counts make one unit, and which units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// Counts per force unit.
    pub counts_per_force: u32,
    /// Counts per torque unit.
    pub counts_per_torque: u32,
    /// The force unit.
    pub force_unit: ForceUnit,
    /// The torque unit.
    pub torque_unit: TorqueUnit,
    /// The six scale factors `READCALINFO` reports (used by the sensor's analog output; passed
    /// on as they are).
    pub scale_factors: [u16; 6],
}

impl Calibration {
    /// A calibration in N and N·m.
    pub const fn si(counts_per_force: u32, counts_per_torque: u32) -> Self {
        Self {
            counts_per_force,
            counts_per_torque,
            force_unit: ForceUnit::Newton,
            torque_unit: TorqueUnit::NewtonMetre,
            scale_factors: [1; 6],
        }
    }

    /// Checks that both counts are positive.
    pub fn check(&self) -> Result<(), NetFtError> {
        if self.counts_per_force == 0 {
            return Err(NetFtError::ZeroCounts { quantity: "force" });
        }
        if self.counts_per_torque == 0 {
            return Err(NetFtError::ZeroCounts { quantity: "torque" });
        }
        Ok(())
    }

    /// N per force count.
    pub fn newton_per_count(&self) -> f64 {
        self.force_unit.to_newton() / f64::from(self.counts_per_force.max(1))
    }

    /// N·m per torque count.
    pub fn newton_metre_per_count(&self) -> f64 {
        self.torque_unit.to_newton_metre() / f64::from(self.counts_per_torque.max(1))
    }

    /// A record's counts as `[Fx, Fy, Fz, Tx, Ty, Tz]` in N and N·m.
    pub fn to_si(&self, counts: &[i32; 6]) -> [f64; 6] {
        let (f, t) = (self.newton_per_count(), self.newton_metre_per_count());
        let mut out = [0.0; 6];
        for k in 0..3 {
            out[k] = f64::from(counts[k]) * f;
            out[k + 3] = f64::from(counts[k + 3]) * t;
        }
        out
    }

    /// The counts nearest to a wrench in N and N·m (saturated at the `i32` range, as the
    /// sensor's own counts are).
    pub fn to_counts(&self, wrench: &[f64; 6]) -> [i32; 6] {
        let (f, t) = (self.newton_per_count(), self.newton_metre_per_count());
        let mut out = [0; 6];
        for k in 0..6 {
            let per = if k < 3 { f } else { t };
            let c = libm::round(wrench[k] / per);
            // `as` saturates at the i32 range and maps NaN to 0.
            out[k] = c as i32;
        }
        out
    }

    /// The `READCALINFO` response.
    pub fn to_bytes(&self) -> [u8; CALINFO_RESPONSE_LEN] {
        let mut b = [0; CALINFO_RESPONSE_LEN];
        b[0..2].copy_from_slice(&HEADER.to_be_bytes());
        b[2] = self.force_unit.code();
        b[3] = self.torque_unit.code();
        b[4..8].copy_from_slice(&self.counts_per_force.to_be_bytes());
        b[8..12].copy_from_slice(&self.counts_per_torque.to_be_bytes());
        for (k, s) in self.scale_factors.iter().enumerate() {
            b[12 + 2 * k..14 + 2 * k].copy_from_slice(&s.to_be_bytes());
        }
        b
    }

    /// Decodes a `READCALINFO` response (and checks it: known units, counts not zero).
    pub fn decode(bytes: &[u8]) -> Result<Self, NetFtError> {
        if bytes.len() != CALINFO_RESPONSE_LEN {
            return Err(NetFtError::Length {
                what: "READCALINFO response",
                expected: CALINFO_RESPONSE_LEN,
                got: bytes.len(),
            });
        }
        let header = be_u16(bytes, 0);
        if header != HEADER {
            return Err(NetFtError::Header {
                what: "READCALINFO response",
                got: header,
            });
        }
        let force_unit = ForceUnit::from_code(bytes[2]).ok_or(NetFtError::UnknownUnit {
            quantity: "force",
            code: bytes[2],
        })?;
        let torque_unit = TorqueUnit::from_code(bytes[3]).ok_or(NetFtError::UnknownUnit {
            quantity: "torque",
            code: bytes[3],
        })?;
        let mut scale_factors = [0; 6];
        for (k, s) in scale_factors.iter_mut().enumerate() {
            *s = be_u16(bytes, 12 + 2 * k);
        }
        let c = Self {
            counts_per_force: be_u32(bytes, 4),
            counts_per_torque: be_u32(bytes, 8),
            force_unit,
            torque_unit,
            scale_factors,
        };
        c.check()?;
        Ok(c)
    }
}

/// The `READCALINFO` request.
pub const fn calinfo_request() -> [u8; CALINFO_REQUEST_LEN] {
    let mut b = [0; CALINFO_REQUEST_LEN];
    b[0] = READCALINFO;
    b
}

/// Checks a TCP request: 20 bytes whose first is `READCALINFO`.
pub fn decode_tcp_request(bytes: &[u8]) -> Result<u8, NetFtError> {
    if bytes.len() != CALINFO_REQUEST_LEN {
        return Err(NetFtError::Length {
            what: "TCP request",
            expected: CALINFO_REQUEST_LEN,
            got: bytes.len(),
        });
    }
    match bytes[0] {
        READCALINFO => Ok(READCALINFO),
        other => Err(NetFtError::UnknownTcpCommand(other)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_match_the_bytes_the_python_peers_send() {
        // PyPI `netft` 2.0.1 and `pynetft` 2.1.3 send these for "start streaming" and "stop"
        // (captured from them in this repository's peer test).
        let start = RdtRequest::new(RdtCommand::StartRealTime, 0).to_bytes();
        assert_eq!(start, [0x12, 0x34, 0x00, 0x02, 0, 0, 0, 0]);
        let stop = RdtRequest::new(RdtCommand::Stop, 0).to_bytes();
        assert_eq!(stop, [0x12, 0x34, 0, 0, 0, 0, 0, 0]);
        let bias = RdtRequest::decode(&[0x12, 0x34, 0x00, 0x42, 0, 0, 0, 5]).unwrap();
        assert_eq!(bias, RdtRequest::new(RdtCommand::SetSoftwareBias, 5));
        assert_eq!(
            RdtRequest::decode(&[0x12, 0x35, 0, 2, 0, 0, 0, 0]),
            Err(NetFtError::Header {
                what: "RDT request",
                got: 0x1235
            })
        );
        assert_eq!(
            RdtRequest::decode(&[0x12, 0x34, 0, 9, 0, 0, 0, 0]),
            Err(NetFtError::UnknownCommand(9))
        );
    }

    #[test]
    fn records_round_trip_and_split_buffered_datagrams() {
        let r = RdtRecord {
            rdt_sequence: 7,
            ft_sequence: 123_456,
            status: 0x8000_0002,
            counts: [1, -2, 300_000, -4_000_000, 5, i32::MIN],
        };
        assert_eq!(RdtRecord::decode(&r.to_bytes()), Ok(r));
        assert!(r.is_error());
        let mut two = [0u8; 2 * RECORD_LEN];
        two[..RECORD_LEN].copy_from_slice(&r.to_bytes());
        let s = RdtRecord {
            rdt_sequence: 8,
            ..r
        };
        two[RECORD_LEN..].copy_from_slice(&s.to_bytes());
        let got: heapless::Vec<RdtRecord, 4> = records(&two).unwrap().collect();
        assert_eq!(&got[..], &[r, s]);
        assert!(records(&two[..35]).is_err());
        assert!(records(&[]).is_err());
    }

    #[test]
    fn sequence_steps_wrap() {
        assert_eq!(sequence_step(1, 2), 1);
        assert_eq!(sequence_step(1, 5), 4);
        assert_eq!(sequence_step(u32::MAX, 0), 1);
        assert_eq!(sequence_step(u32::MAX - 1, 1), 3);
        assert_eq!(sequence_step(5, 5), 0);
        assert_eq!(sequence_step(5, 3), -2);
    }

    #[test]
    fn calibrations_convert_and_round_trip() {
        // A calibration like the Nano17's: 1 000 000 counts per N, 1 000 000 per N·mm.
        let c = Calibration {
            counts_per_force: 1_000_000,
            counts_per_torque: 1_000_000,
            force_unit: ForceUnit::Newton,
            torque_unit: TorqueUnit::NewtonMillimetre,
            scale_factors: [1; 6],
        };
        let w = c.to_si(&[2_500_000, 0, -1_000_000, 1_000_000, 0, 0]);
        assert_eq!(w, [2.5, 0.0, -1.0, 0.001, 0.0, 0.0]);
        assert_eq!(c.to_counts(&w), [2_500_000, 0, -1_000_000, 1_000_000, 0, 0]);
        assert_eq!(Calibration::decode(&c.to_bytes()), Ok(c));
        let lbf = Calibration {
            force_unit: ForceUnit::PoundForce,
            ..c
        };
        assert!((lbf.to_si(&[1_000_000, 0, 0, 0, 0, 0])[0] - 4.448_221_615_260_5).abs() < 1e-12);
        let mut bad = c.to_bytes();
        bad[2] = 9;
        assert_eq!(
            Calibration::decode(&bad),
            Err(NetFtError::UnknownUnit {
                quantity: "force",
                code: 9
            })
        );
        let mut zero = c.to_bytes();
        zero[4..8].copy_from_slice(&[0; 4]);
        assert_eq!(
            Calibration::decode(&zero),
            Err(NetFtError::ZeroCounts { quantity: "force" })
        );
        // Saturation, as the sensor's counts saturate.
        assert_eq!(
            c.to_counts(&[1e9, -1e9, f64::NAN, 0.0, 0.0, 0.0])[..3],
            [i32::MAX, i32::MIN, 0]
        );
        for u in ForceUnit::ALL {
            assert_eq!(ForceUnit::from_code(u.code()), Some(u));
        }
        for u in TorqueUnit::ALL {
            assert_eq!(TorqueUnit::from_code(u.code()), Some(u));
        }
    }

    #[test]
    fn tcp_requests() {
        assert_eq!(decode_tcp_request(&calinfo_request()), Ok(READCALINFO));
        let mut other = calinfo_request();
        other[0] = 3;
        assert_eq!(
            decode_tcp_request(&other),
            Err(NetFtError::UnknownTcpCommand(3))
        );
        assert!(decode_tcp_request(&other[..19]).is_err());
    }
}
