//! The SDO client's side of one transfer, without I/O: it says which 8-byte message to send
//! next and consumes the server's answers, for expedited and segmented uploads and downloads.
//! The caller owns the transport and the clock: it sends what the client returns, feeds back
//! each SDO response, and calls [`Client::timeout`] when its deadline passes (which yields
//! the abort message "SDO protocol timed out" to send). Allocation-free; a transfer holds at
//! most [`MAX_TRANSFER`] bytes.

use core::fmt;

use super::sdo::{AbortCode, Address, Chunk, Request, Response};

/// Most bytes one transfer carries (longer uploads are aborted with "out of memory").
pub const MAX_TRANSFER: usize = 256;

/// Why a transfer failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SdoError {
    /// The server aborted it.
    Aborted {
        /// The object.
        address: Address,
        /// The server's reason.
        code: AbortCode,
    },
    /// The server answered out of protocol; the client aborted with `code`.
    Protocol {
        /// The object.
        address: Address,
        /// What was wrong.
        what: &'static str,
        /// The abort code sent.
        code: AbortCode,
    },
    /// No answer before the deadline; the client aborted.
    Timeout {
        /// The object.
        address: Address,
    },
    /// The data does not fit [`MAX_TRANSFER`] bytes.
    TooLong {
        /// The object.
        address: Address,
        /// The size announced or attempted.
        size: usize,
    },
    /// No transfer is in progress (a response arrived unasked).
    Idle,
}

impl fmt::Display for SdoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SdoError::Aborted { address, code } => {
                write!(f, "object {address}: the server aborted with {code}")
            }
            SdoError::Protocol {
                address,
                what,
                code,
            } => {
                write!(f, "object {address}: {what}; aborted with {code}")
            }
            SdoError::Timeout { address } => {
                write!(
                    f,
                    "object {address}: no answer in time; aborted (SDO protocol timed out)"
                )
            }
            SdoError::TooLong { address, size } => write!(
                f,
                "object {address}: {size} bytes exceed the client's {MAX_TRANSFER}-byte buffer"
            ),
            SdoError::Idle => f.write_str("SDO response without a transfer in progress"),
        }
    }
}

impl SdoError {
    /// The reason without the object's address, for a message that names the object itself.
    pub fn reason(&self) -> SdoReason {
        SdoReason(*self)
    }
}

/// [`SdoError::reason`]: the error without its object address.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SdoReason(SdoError);

impl fmt::Display for SdoReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            SdoError::Aborted { code, .. } => write!(f, "aborted {code}"),
            SdoError::Protocol { what, code, .. } => {
                write!(f, "{what} (aborted {:#010x})", code.0)
            }
            SdoError::Timeout { .. } => f.write_str("no SDO answer in time"),
            SdoError::TooLong { size, .. } => {
                write!(f, "{size} bytes exceed the {MAX_TRANSFER}-byte buffer")
            }
            SdoError::Idle => f.write_str("SDO response without a transfer in progress"),
        }
    }
}

/// What the caller does next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// Send this message and wait for the answer.
    Send([u8; 8]),
    /// The transfer is complete (an upload's data is in [`Client::data`]).
    Done,
}

/// A failed transfer: the error, and the abort message to send if the client aborts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Failure {
    /// Why.
    pub error: SdoError,
    /// The abort to send to the server (`None` when the server aborted).
    pub send: Option<[u8; 8]>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Idle,
    DownloadInitiated,
    DownloadSegments,
    UploadInitiated,
    UploadSegments,
}

/// One SDO client channel (one transfer at a time, as CiA 301 requires per server).
#[derive(Clone, Debug)]
pub struct Client {
    phase: Phase,
    address: Address,
    toggle: bool,
    buf: [u8; MAX_TRANSFER],
    len: usize,
    pos: usize,
    /// Bytes of the last segment sent (a download) — for the next position.
    last_sent: usize,
}

impl Default for Client {
    fn default() -> Self {
        Self::new()
    }
}

impl Client {
    /// An idle client.
    pub const fn new() -> Self {
        Self {
            phase: Phase::Idle,
            address: Address::new(0, 0),
            toggle: false,
            buf: [0; MAX_TRANSFER],
            len: 0,
            pos: 0,
            last_sent: 0,
        }
    }

    /// The object of the current (or last) transfer.
    pub fn address(&self) -> Address {
        self.address
    }

    /// Whether a transfer is in progress.
    pub fn is_busy(&self) -> bool {
        self.phase != Phase::Idle
    }

    /// The data of the last completed upload.
    pub fn data(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    /// Starts reading `address`: the message to send.
    pub fn upload(&mut self, address: Address) -> [u8; 8] {
        self.address = address;
        self.phase = Phase::UploadInitiated;
        self.len = 0;
        Request::UploadInitiate { address }.encode()
    }

    /// Starts writing `data` to `address` (expedited up to 4 bytes, else segmented).
    pub fn download(&mut self, address: Address, data: &[u8]) -> Result<[u8; 8], SdoError> {
        self.address = address;
        if data.len() > MAX_TRANSFER {
            return Err(SdoError::TooLong {
                address,
                size: data.len(),
            });
        }
        self.buf[..data.len()].copy_from_slice(data);
        self.len = data.len();
        self.pos = 0;
        self.toggle = false;
        self.phase = Phase::DownloadInitiated;
        if (1..=4).contains(&data.len()) {
            let chunk = Chunk::truncated(data);
            return Ok(Request::DownloadExpedited {
                address,
                data: chunk,
            }
            .encode());
        }
        Ok(Request::DownloadInitiate {
            address,
            size: Some(data.len() as u32),
        }
        .encode())
    }

    /// The deadline passed: the transfer ends, and the abort "SDO protocol timed out" is to be
    /// sent.
    pub fn timeout(&mut self) -> Failure {
        self.abort(
            SdoError::Timeout {
                address: self.address,
            },
            AbortCode::TIMEOUT,
        )
    }

    fn abort(&mut self, error: SdoError, code: AbortCode) -> Failure {
        self.phase = Phase::Idle;
        Failure {
            error,
            send: Some(
                Request::Abort {
                    address: self.address,
                    code,
                }
                .encode(),
            ),
        }
    }

    fn protocol(&mut self, what: &'static str, code: AbortCode) -> Failure {
        let address = self.address;
        self.abort(
            SdoError::Protocol {
                address,
                what,
                code,
            },
            code,
        )
    }

    fn next_segment(&mut self) -> [u8; 8] {
        let n = (self.len - self.pos).min(7);
        let data = Chunk::truncated(&self.buf[self.pos..self.pos + n]);
        self.last_sent = n;
        Request::DownloadSegment {
            toggle: self.toggle,
            data,
            last: self.pos + n == self.len,
        }
        .encode()
    }

    /// Consumes the server's answer (an SDO message from COB-ID 0x580 + node).
    pub fn on_response(&mut self, payload: &[u8]) -> Result<Next, Failure> {
        if self.phase == Phase::Idle {
            return Err(Failure {
                error: SdoError::Idle,
                send: None,
            });
        }
        let Ok(response) = Response::decode(payload) else {
            return Err(self.protocol("malformed response", AbortCode::COMMAND_SPECIFIER));
        };
        if let Response::Abort { address, code } = response {
            self.phase = Phase::Idle;
            return Err(Failure {
                error: SdoError::Aborted { address, code },
                send: None,
            });
        }
        match (self.phase, response) {
            (Phase::DownloadInitiated, Response::DownloadInitiate { address }) => {
                if address != self.address {
                    return Err(self.protocol("response for another object", AbortCode::GENERAL));
                }
                if self.len <= 4 && self.len > 0 {
                    self.phase = Phase::Idle;
                    return Ok(Next::Done);
                }
                self.phase = Phase::DownloadSegments;
                Ok(Next::Send(self.next_segment()))
            }
            (Phase::DownloadSegments, Response::DownloadSegment { toggle }) => {
                if toggle != self.toggle {
                    return Err(self.protocol("toggle bit not alternated", AbortCode::TOGGLE_BIT));
                }
                self.pos += self.last_sent;
                self.toggle = !self.toggle;
                if self.pos == self.len {
                    self.phase = Phase::Idle;
                    return Ok(Next::Done);
                }
                Ok(Next::Send(self.next_segment()))
            }
            (Phase::UploadInitiated, Response::UploadExpedited { address, data }) => {
                if address != self.address {
                    return Err(self.protocol("response for another object", AbortCode::GENERAL));
                }
                let d = data.as_slice();
                self.buf[..d.len()].copy_from_slice(d);
                self.len = d.len();
                self.phase = Phase::Idle;
                Ok(Next::Done)
            }
            (Phase::UploadInitiated, Response::UploadInitiate { address, size }) => {
                if address != self.address {
                    return Err(self.protocol("response for another object", AbortCode::GENERAL));
                }
                if let Some(size) = size {
                    if size as usize > MAX_TRANSFER {
                        let a = self.address;
                        return Err(self.abort(
                            SdoError::TooLong {
                                address: a,
                                size: size as usize,
                            },
                            AbortCode::OUT_OF_MEMORY,
                        ));
                    }
                }
                self.phase = Phase::UploadSegments;
                self.toggle = false;
                self.len = 0;
                Ok(Next::Send(
                    Request::UploadSegment { toggle: false }.encode(),
                ))
            }
            (Phase::UploadSegments, Response::UploadSegment { toggle, data, last }) => {
                if toggle != self.toggle {
                    return Err(self.protocol("toggle bit not alternated", AbortCode::TOGGLE_BIT));
                }
                let d = data.as_slice();
                if self.len + d.len() > MAX_TRANSFER {
                    let (a, size) = (self.address, self.len + d.len());
                    return Err(self.abort(
                        SdoError::TooLong { address: a, size },
                        AbortCode::OUT_OF_MEMORY,
                    ));
                }
                self.buf[self.len..self.len + d.len()].copy_from_slice(d);
                self.len += d.len();
                self.toggle = !self.toggle;
                if last {
                    self.phase = Phase::Idle;
                    return Ok(Next::Done);
                }
                Ok(Next::Send(
                    Request::UploadSegment {
                        toggle: self.toggle,
                    }
                    .encode(),
                ))
            }
            _ => Err(self.protocol(
                "response does not fit the transfer",
                AbortCode::COMMAND_SPECIFIER,
            )),
        }
    }
}
