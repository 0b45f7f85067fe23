//! RTDE messages. A type byte means a request from the client and its answer from the
//! controller, so decoding needs the direction ([`Message::decode_request`],
//! [`Message::decode_answer`]) and the protocol version where the layouts differ:
//!
//! | type | request (client) | answer (controller) |
//! |---|---|---|
//! | `V` | `u16` version | `u8` accepted |
//! | `v` | — | `u32` major, minor, bugfix, build |
//! | `O` | v2: `f64` frequency; names, comma-separated | v2: `u8` recipe id; types, comma-separated (`NOT_FOUND` for an unknown name) |
//! | `I` | names | `u8` recipe id (0: refused); types (`IN_USE` for an input another client writes) |
//! | `S`, `P` | — | `u8` accepted |
//! | `U` | `u8` recipe id; values | v2: `u8` recipe id; values |
//! | `M` | v2: `u8` length, message, `u8` length, source, `u8` level | the same (v1: `u8` level, message) |

use super::types::{Reader, Writer};
use super::{HEADER_LEN, Header, PackageType, RtdeError, write_header};

/// Text message levels (v2).
pub mod level {
    /// An exception.
    pub const EXCEPTION: u8 = 0;
    /// An error.
    pub const ERROR: u8 = 1;
    /// A warning.
    pub const WARNING: u8 = 2;
    /// Information.
    pub const INFO: u8 = 3;
}

/// An RTDE message (the payload borrowed from the bytes it was decoded from).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Message<'a> {
    /// `V` request: use this protocol version.
    RequestProtocolVersion(u16),
    /// `V` answer.
    ProtocolVersionAccepted(bool),
    /// `v` request.
    GetUrcontrolVersion,
    /// `v` answer.
    UrcontrolVersion {
        /// Major (3: CB3, 5: e-Series).
        major: u32,
        /// Minor.
        minor: u32,
        /// Bug fix.
        bugfix: u32,
        /// Build.
        build: u32,
    },
    /// `M`, either way.
    Text {
        /// [`level`].
        level: u8,
        /// The message.
        message: &'a str,
        /// Its source (v2; empty in v1).
        source: &'a str,
    },
    /// `O` request.
    SetupOutputs {
        /// Packages a second (v2; `None` in v1: the controller's rate).
        frequency: Option<f64>,
        /// Variable names, comma-separated.
        names: &'a str,
    },
    /// `O` answer.
    OutputsRecipe {
        /// The recipe's id (v2; `None` in v1).
        id: Option<u8>,
        /// Types, comma-separated.
        types: &'a str,
    },
    /// `I` request.
    SetupInputs {
        /// Variable names, comma-separated.
        names: &'a str,
    },
    /// `I` answer.
    InputsRecipe {
        /// The recipe's id (0: refused).
        id: u8,
        /// Types, comma-separated.
        types: &'a str,
    },
    /// `S` request.
    Start,
    /// `S` answer.
    StartAccepted(bool),
    /// `P` request.
    Pause,
    /// `P` answer.
    PauseAccepted(bool),
    /// `U`, either way.
    Data {
        /// The recipe (always from a client; from the controller in v2 only).
        recipe: Option<u8>,
        /// The values, in the recipe's order.
        payload: &'a [u8],
    },
}

fn text<'a>(b: &'a [u8], what: &'static str) -> Result<&'a str, RtdeError> {
    core::str::from_utf8(b).map_err(|_| RtdeError::NotText(what))
}

fn done(r: &Reader<'_>, what: &'static str, expected: usize) -> Result<(), RtdeError> {
    if r.rest().is_empty() {
        Ok(())
    } else {
        Err(RtdeError::TooLong {
            what,
            expected,
            got: expected + r.rest().len(),
        })
    }
}

impl<'a> Message<'a> {
    /// The package type.
    pub const fn package_type(&self) -> PackageType {
        match self {
            Self::RequestProtocolVersion(_) | Self::ProtocolVersionAccepted(_) => {
                PackageType::RequestProtocolVersion
            }
            Self::GetUrcontrolVersion | Self::UrcontrolVersion { .. } => {
                PackageType::GetUrcontrolVersion
            }
            Self::Text { .. } => PackageType::TextMessage,
            Self::SetupOutputs { .. } | Self::OutputsRecipe { .. } => PackageType::SetupOutputs,
            Self::SetupInputs { .. } | Self::InputsRecipe { .. } => PackageType::SetupInputs,
            Self::Start | Self::StartAccepted(_) => PackageType::Start,
            Self::Pause | Self::PauseAccepted(_) => PackageType::Pause,
            Self::Data { .. } => PackageType::DataPackage,
        }
    }

    /// Decodes a package a client sent (protocol `version`).
    pub fn decode_request(
        header: Header,
        payload: &'a [u8],
        version: u16,
    ) -> Result<Self, RtdeError> {
        let ty = header
            .package_type()
            .ok_or(RtdeError::UnknownType(header.kind))?;
        let mut r = Reader::new(payload);
        let m = match ty {
            PackageType::RequestProtocolVersion => {
                let v = r.u16("protocol version request")?;
                done(&r, "protocol version request", 2)?;
                Self::RequestProtocolVersion(v)
            }
            PackageType::GetUrcontrolVersion => {
                done(&r, "controller version request", 0)?;
                Self::GetUrcontrolVersion
            }
            PackageType::TextMessage => Self::decode_text(&mut r, version)?,
            PackageType::SetupOutputs => {
                let frequency = if version >= 2 {
                    Some(r.f64("output setup")?)
                } else {
                    None
                };
                Self::SetupOutputs {
                    frequency,
                    names: text(r.rest(), "output setup")?,
                }
            }
            PackageType::SetupInputs => Self::SetupInputs {
                names: text(payload, "input setup")?,
            },
            PackageType::Start => {
                done(&r, "start", 0)?;
                Self::Start
            }
            PackageType::Pause => {
                done(&r, "pause", 0)?;
                Self::Pause
            }
            PackageType::DataPackage => {
                let recipe = r.u8("data package")?;
                Self::Data {
                    recipe: Some(recipe),
                    payload: r.rest(),
                }
            }
        };
        Ok(m)
    }

    /// Decodes a package the controller sent (protocol `version`).
    pub fn decode_answer(
        header: Header,
        payload: &'a [u8],
        version: u16,
    ) -> Result<Self, RtdeError> {
        let ty = header
            .package_type()
            .ok_or(RtdeError::UnknownType(header.kind))?;
        let mut r = Reader::new(payload);
        let flag = |r: &mut Reader<'_>, what| -> Result<bool, RtdeError> {
            let v = r.u8(what)?;
            done(r, what, 1)?;
            match v {
                0 => Ok(false),
                1 => Ok(true),
                value => Err(RtdeError::NotAFlag { what, value }),
            }
        };
        let m = match ty {
            PackageType::RequestProtocolVersion => {
                Self::ProtocolVersionAccepted(flag(&mut r, "protocol version answer")?)
            }
            PackageType::GetUrcontrolVersion => {
                let m = Self::UrcontrolVersion {
                    major: r.u32("controller version")?,
                    minor: r.u32("controller version")?,
                    bugfix: r.u32("controller version")?,
                    build: r.u32("controller version")?,
                };
                done(&r, "controller version", 16)?;
                m
            }
            PackageType::TextMessage => Self::decode_text(&mut r, version)?,
            PackageType::SetupOutputs => {
                let id = if version >= 2 {
                    Some(r.u8("output recipe")?)
                } else {
                    None
                };
                Self::OutputsRecipe {
                    id,
                    types: text(r.rest(), "output recipe")?,
                }
            }
            PackageType::SetupInputs => Self::InputsRecipe {
                id: r.u8("input recipe")?,
                types: text(r.rest(), "input recipe")?,
            },
            PackageType::Start => Self::StartAccepted(flag(&mut r, "start answer")?),
            PackageType::Pause => Self::PauseAccepted(flag(&mut r, "pause answer")?),
            PackageType::DataPackage => {
                let recipe = if version >= 2 {
                    Some(r.u8("data package")?)
                } else {
                    None
                };
                Self::Data {
                    recipe,
                    payload: r.rest(),
                }
            }
        };
        Ok(m)
    }

    fn decode_text(r: &mut Reader<'a>, version: u16) -> Result<Self, RtdeError> {
        if version >= 2 {
            let n = usize::from(r.u8("text message")?);
            let message = text(r.take(n, "text message")?, "text message")?;
            let n = usize::from(r.u8("text message source")?);
            let source = text(r.take(n, "text message source")?, "text message source")?;
            let level = r.u8("text message level")?;
            done(r, "text message", 0)?;
            Ok(Self::Text {
                level,
                message,
                source,
            })
        } else {
            let level = r.u8("text message")?;
            Ok(Self::Text {
                level,
                message: text(r.rest(), "text message")?,
                source: "",
            })
        }
    }

    /// Writes the package (header included) into `out` for protocol `version`; returns its
    /// length.
    pub fn encode(&self, version: u16, out: &mut [u8]) -> Result<usize, RtdeError> {
        if out.len() < HEADER_LEN {
            return Err(RtdeError::BufferTooSmall {
                need: HEADER_LEN,
                got: out.len(),
            });
        }
        let (head, body) = out.split_at_mut(HEADER_LEN);
        let mut w = Writer::new(body);
        match *self {
            Self::RequestProtocolVersion(v) => w.u16(v)?,
            Self::ProtocolVersionAccepted(a) | Self::StartAccepted(a) | Self::PauseAccepted(a) => {
                w.u8(u8::from(a))?;
            }
            Self::GetUrcontrolVersion | Self::Start | Self::Pause => {}
            Self::UrcontrolVersion {
                major,
                minor,
                bugfix,
                build,
            } => {
                w.u32(major)?;
                w.u32(minor)?;
                w.u32(bugfix)?;
                w.u32(build)?;
            }
            Self::Text {
                level,
                message,
                source,
            } => {
                if version >= 2 {
                    let m = &message.as_bytes()[..message.len().min(255)];
                    let s = &source.as_bytes()[..source.len().min(255)];
                    w.u8(m.len() as u8)?;
                    w.put(m)?;
                    w.u8(s.len() as u8)?;
                    w.put(s)?;
                    w.u8(level)?;
                } else {
                    w.u8(level)?;
                    w.put(message.as_bytes())?;
                }
            }
            Self::SetupOutputs { frequency, names } => {
                if version >= 2 {
                    w.f64(frequency.unwrap_or(0.0))?;
                }
                w.put(names.as_bytes())?;
            }
            Self::OutputsRecipe { id, types } => {
                if version >= 2 {
                    w.u8(id.unwrap_or(0))?;
                }
                w.put(types.as_bytes())?;
            }
            Self::SetupInputs { names } => w.put(names.as_bytes())?,
            Self::InputsRecipe { id, types } => {
                w.u8(id)?;
                w.put(types.as_bytes())?;
            }
            Self::Data { recipe, payload } => {
                if let Some(r) = recipe {
                    w.u8(r)?;
                }
                w.put(payload)?;
            }
        }
        let n = w.len();
        write_header(self.package_type(), n, head)?;
        Ok(HEADER_LEN + n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::proto::rtde::split;

    fn round_trip(m: Message<'_>, request: bool, version: u16) {
        let mut buf = [0u8; 256];
        let n = m.encode(version, &mut buf).unwrap();
        let (h, payload, rest) = split(&buf[..n]).unwrap().unwrap();
        assert!(rest.is_empty());
        let back = if request {
            Message::decode_request(h, payload, version)
        } else {
            Message::decode_answer(h, payload, version)
        }
        .unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn messages_round_trip_in_both_versions() {
        for v in [1, 2] {
            round_trip(Message::RequestProtocolVersion(2), true, v);
            round_trip(Message::ProtocolVersionAccepted(true), false, v);
            round_trip(Message::GetUrcontrolVersion, true, v);
            round_trip(
                Message::UrcontrolVersion {
                    major: 5,
                    minor: 11,
                    bugfix: 0,
                    build: 108_249,
                },
                false,
                v,
            );
            round_trip(
                Message::SetupInputs {
                    names: "input_int_register_24",
                },
                true,
                v,
            );
            round_trip(
                Message::InputsRecipe {
                    id: 1,
                    types: "INT32",
                },
                false,
                v,
            );
            round_trip(Message::Start, true, v);
            round_trip(Message::PauseAccepted(true), false, v);
            round_trip(
                Message::Data {
                    recipe: Some(1),
                    payload: &[0, 0, 0, 1],
                },
                true,
                v,
            );
        }
        round_trip(
            Message::SetupOutputs {
                frequency: Some(500.0),
                names: "timestamp,actual_q",
            },
            true,
            2,
        );
        round_trip(
            Message::OutputsRecipe {
                id: Some(1),
                types: "DOUBLE,VECTOR6D",
            },
            false,
            2,
        );
        round_trip(
            Message::Text {
                level: level::WARNING,
                message: "watchdog",
                source: "RTDE",
            },
            false,
            2,
        );
    }

    #[test]
    fn the_bytes_ur_rtde_sends() {
        // ur_rtde 1.6.5 asking for version 2 (captured from it in this repository's test).
        let (h, p, _) = split(&[0, 5, b'V', 0, 2]).unwrap().unwrap();
        assert_eq!(
            Message::decode_request(h, p, 1),
            Ok(Message::RequestProtocolVersion(2))
        );
        // Its output setup starts with 500.0 as a big-endian double.
        let mut b = [0u8; 64];
        let n = Message::SetupOutputs {
            frequency: Some(500.0),
            names: "timestamp,",
        }
        .encode(2, &mut b)
        .unwrap();
        assert_eq!(&b[3..11], &[0x40, 0x7F, 0x40, 0, 0, 0, 0, 0]);
        assert_eq!(&b[11..n], b"timestamp,");
        assert!(
            Message::decode_request(
                Header {
                    size: 4,
                    kind: b'Q'
                },
                &[0],
                2
            )
            .is_err()
        );
    }

    #[test]
    fn an_accepted_byte_other_than_0_or_1_is_refused() {
        // Found by the fuzz target: a pause answer of 0xB8 decoded as `true` and re-encoded
        // as 1. The guide's `accepted` is 0 or 1; anything else is malformed.
        let (h, p, _) = split(&[0, 4, b'P', 0xB8]).unwrap().unwrap();
        assert_eq!(
            Message::decode_answer(h, p, 2),
            Err(RtdeError::NotAFlag {
                what: "pause answer",
                value: 0xB8
            })
        );
        let (h, p, _) = split(&[0, 4, b'P', 1]).unwrap().unwrap();
        assert_eq!(
            Message::decode_answer(h, p, 2),
            Ok(Message::PauseAccepted(true))
        );
    }
}
