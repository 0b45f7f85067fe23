//! Emergency messages (COB-ID 0x080 + node): `error code u16 | error register u8 | 5 vendor
//! bytes`, little-endian (CiA 301 §7.2.7). Code 0x0000 announces that the errors are reset.
//!
//! Error code classes (CiA 301 table 21) and the CiA 402 drive codes a commissioning engineer
//! meets most (CiA 402-2 annex), named by [`code_name`].

use core::fmt;

use super::{Function, NodeId};
use crate::proto::can::Frame;

/// One emergency message.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Emergency {
    /// The error code (0x0000: error reset / no error).
    pub code: u16,
    /// The node's error register (object 0x1001).
    pub register: u8,
    /// Manufacturer-specific bytes.
    pub vendor: [u8; 5],
}

/// Why an EMCY frame is malformed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DecodeError {
    /// Its data length (must be 8).
    pub len: usize,
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "EMCY with {} data bytes, expected 8", self.len)
    }
}

impl Emergency {
    /// Decodes an EMCY frame's data.
    pub fn decode(data: &[u8]) -> Result<Self, DecodeError> {
        let [c0, c1, register, v0, v1, v2, v3, v4] = *data else {
            return Err(DecodeError { len: data.len() });
        };
        Ok(Self {
            code: u16::from_le_bytes([c0, c1]),
            register,
            vendor: [v0, v1, v2, v3, v4],
        })
    }

    /// The 8 data bytes.
    pub fn to_bytes(&self) -> [u8; 8] {
        let [c0, c1] = self.code.to_le_bytes();
        let [v0, v1, v2, v3, v4] = self.vendor;
        [c0, c1, self.register, v0, v1, v2, v3, v4]
    }

    /// The EMCY frame of `node`.
    pub fn frame(&self, node: NodeId) -> Frame {
        Frame::standard(Function::Emcy(node).cob_id(), &self.to_bytes())
            .unwrap_or_else(super::nmt::no_frame)
    }

    /// Whether this announces that the node's errors were reset.
    pub const fn is_reset(&self) -> bool {
        self.code == 0
    }
}

/// A name for an error code: the CiA 402 drive code if known, else the CiA 301 class.
pub fn code_name(code: u16) -> &'static str {
    match code {
        0x0000 => "error reset or no error",
        0x1000 => "generic error",
        0x2310 => "continuous over-current",
        0x2320 => "short circuit or earth leakage",
        0x3210 => "DC link over-voltage",
        0x3220 => "DC link under-voltage",
        0x4210 => "excess temperature device",
        0x4310 => "excess temperature drive",
        0x5441 => "enable input off (safe torque off)",
        0x7121 => "motor blocked",
        0x7305 => "incremental sensor 1 fault",
        0x8110 => "CAN overrun (objects lost)",
        0x8120 => "CAN in error passive mode",
        0x8130 => "life guard or heartbeat error",
        0x8140 => "recovered from bus off",
        0x8210 => "PDO not processed due to length error",
        0x8220 => "PDO length exceeded",
        0x8240 => "unexpected SYNC data length",
        0x8250 => "RPDO timeout",
        0x8611 => "following error",
        0x8612 => "reference limit",
        0xFF00..=0xFFFF => "device specific",
        _ => match code >> 12 {
            0x1 => "generic error",
            0x2 => "current",
            0x3 => "voltage",
            0x4 => "temperature",
            0x5 => "device hardware",
            0x6 => "device software",
            0x7 => "additional modules",
            0x8 => "monitoring (communication or control)",
            0x9 => "external error",
            0xF => "additional functions",
            _ => "unknown error code",
        },
    }
}

impl fmt::Display for Emergency {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.vendor;
        write!(
            f,
            "error code {:#06x} ({}), error register {:#04x}, vendor {:02x} {:02x} {:02x} {:02x} {:02x}",
            self.code,
            code_name(self.code),
            self.register,
            v[0],
            v[1],
            v[2],
            v[3],
            v[4]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_emcy_reports_code_register_and_vendor_bytes() {
        let e = Emergency::decode(&[0x11, 0x86, 0x81, 1, 2, 3, 4, 5]).unwrap();
        assert_eq!(
            (e.code, e.register, e.vendor),
            (0x8611, 0x81, [1, 2, 3, 4, 5])
        );
        assert_eq!(
            e.to_string(),
            "error code 0x8611 (following error), error register 0x81, vendor 01 02 03 04 05"
        );
        let f = e.frame(NodeId::new(3).unwrap());
        assert_eq!(f.standard_id(), Some(0x083));
        assert_eq!(Emergency::decode(f.bytes()), Ok(e));
        assert_eq!(Emergency::decode(&[0; 7]), Err(DecodeError { len: 7 }));
        assert_eq!(code_name(0x2311), "current");
        assert_eq!(code_name(0xFF01), "device specific");
    }
}
