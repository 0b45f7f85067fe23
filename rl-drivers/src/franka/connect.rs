//! The connection handshake: the client's `Connect` carries its research-interface version and
//! the UDP port the robot is to send states to; the robot answers with a status and its own
//! version, and refuses a client of another version with `IncompatibleLibraryVersion` (the
//! check is the robot's: libfranka only reports the versions when refused).
//!
//! The answer's payload is packed `{status: u8, version: u16}` (3 bytes) in libfranka-common.
//! franky-sim 1.0.4 answers with 8 bytes instead, `{status: u16, version: u16, 4 padding}`;
//! libfranka reads the version of that answer at the wrong offset (2560 for 10) but ignores it
//! on success. [`ConnectResponse::decode`] tells the two forms apart by their length (3 or 8)
//! and reads both correctly; any other length is an error.

use core::fmt;

use super::message::{ConnectStatus, MessageError};
use super::wire::Reader;

/// The research-interface version this crate speaks (libfranka 0.21.2's `kVersion`).
pub const VERSION: u16 = 10;

/// `Connect`'s request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConnectRequest {
    /// The client's version.
    pub version: u16,
    /// The UDP port the client receives states on.
    pub udp_port: u16,
}

impl ConnectRequest {
    /// A request of this crate's [`VERSION`] for states on `udp_port`.
    pub const fn new(udp_port: u16) -> Self {
        Self {
            version: VERSION,
            udp_port,
        }
    }
}

/// `Connect`'s answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConnectResponse {
    /// Whether the robot accepted the client.
    pub status: ConnectStatus,
    /// The robot's version.
    pub version: u16,
}

/// Bytes of the answer's payload as libfranka-common packs it.
pub const RESPONSE_PAYLOAD_LEN: usize = 3;
/// Bytes of franky-sim 1.0.4's answer payload.
pub const RESPONSE_PAYLOAD_LEN_FRANKY_SIM: usize = 8;

impl ConnectResponse {
    /// Reads the payload after the header (status byte included): 3 bytes packed, or franky-sim's
    /// 8-byte form.
    pub fn decode(payload: &[u8]) -> Result<Self, MessageError> {
        let mut r = Reader::new(payload);
        let (status, version) = match payload.len() {
            RESPONSE_PAYLOAD_LEN => (u32::from(r.u8()), r.u16()),
            RESPONSE_PAYLOAD_LEN_FRANKY_SIM => (u32::from(r.u16()), r.u16()),
            got => {
                return Err(MessageError::TooShort {
                    what: "Connect answer (3 bytes, or franky-sim's 8)",
                    needed: RESPONSE_PAYLOAD_LEN,
                    got,
                });
            }
        };
        let status = u8::try_from(status)
            .ok()
            .and_then(ConnectStatus::from_u8)
            .ok_or(MessageError::BadValue {
                field: "Connect status",
                value: status,
            })?;
        Ok(Self { status, version })
    }

    /// The packed payload (what the robot sends).
    pub fn encode(&self) -> [u8; RESPONSE_PAYLOAD_LEN] {
        let v = self.version.to_le_bytes();
        [self.status.code(), v[0], v[1]]
    }
}

/// The robot refused the client's version.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IncompatibleVersion {
    /// The robot's version.
    pub robot: u16,
    /// The client's version.
    pub client: u16,
}

impl fmt::Display for IncompatibleVersion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "incompatible version: robot {}, client {}",
            self.robot, self.client
        )
    }
}

impl ConnectResponse {
    /// `Ok` if the robot accepted the client, else the two versions.
    pub fn check(&self, client: u16) -> Result<(), IncompatibleVersion> {
        match self.status {
            ConnectStatus::Success => Ok(()),
            ConnectStatus::IncompatibleLibraryVersion => Err(IncompatibleVersion {
                robot: self.version,
                client,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_answer_forms_decode_and_a_refusal_names_the_versions() {
        let packed = ConnectResponse {
            status: ConnectStatus::Success,
            version: VERSION,
        };
        assert_eq!(ConnectResponse::decode(&packed.encode()), Ok(packed));
        // franky-sim 1.0.4: struct.pack("<HH4x", 0, 10).
        let sim = [0u8, 0, 10, 0, 0, 0, 0, 0];
        assert_eq!(ConnectResponse::decode(&sim), Ok(packed));
        let refused = [1u8, 9, 0];
        let r = ConnectResponse::decode(&refused).unwrap();
        assert_eq!(
            r.check(VERSION).unwrap_err().to_string(),
            "incompatible version: robot 9, client 10"
        );
        assert!(ConnectResponse::decode(&[0u8, 10]).is_err());
        assert!(ConnectResponse::decode(&[7u8, 10, 0]).is_err());
    }
}
