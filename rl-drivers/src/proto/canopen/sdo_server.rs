//! The SDO server's side, without I/O: it answers each client message from an object
//! dictionary the caller provides ([`Dictionary`]), for expedited and segmented transfers.
//! Block transfers and unknown command specifiers are refused with the abort "command
//! specifier not valid or unknown", as a device without block transfer answers them.

use super::sdo::{AbortCode, Address, Chunk, Request, Response};
use super::sdo_client::MAX_TRANSFER;

/// An object dictionary as the SDO server sees it.
pub trait Dictionary {
    /// Reads `address` into `out` (at most [`MAX_TRANSFER`] bytes); returns the length.
    fn read(&mut self, address: Address, out: &mut [u8]) -> Result<usize, AbortCode>;
    /// Writes `data` to `address`.
    fn write(&mut self, address: Address, data: &[u8]) -> Result<(), AbortCode>;
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Idle,
    Downloading,
    Uploading,
}

/// One SDO server channel.
#[derive(Clone, Debug)]
pub struct Server {
    phase: Phase,
    address: Address,
    toggle: bool,
    buf: [u8; MAX_TRANSFER],
    len: usize,
    pos: usize,
    size: Option<usize>,
}

impl Default for Server {
    fn default() -> Self {
        Self::new()
    }
}

impl Server {
    /// An idle server.
    pub const fn new() -> Self {
        Self {
            phase: Phase::Idle,
            address: Address::new(0, 0),
            toggle: false,
            buf: [0; MAX_TRANSFER],
            len: 0,
            pos: 0,
            size: None,
        }
    }

    fn abort(&mut self, address: Address, code: AbortCode) -> Option<[u8; 8]> {
        self.phase = Phase::Idle;
        Some(Response::Abort { address, code }.encode())
    }

    /// Answers one client message (`None`: no answer, after a client's abort).
    pub fn on_request(&mut self, payload: &[u8], od: &mut dyn Dictionary) -> Option<[u8; 8]> {
        let Ok(request) = Request::decode(payload) else {
            return self.abort(Address::new(0, 0), AbortCode::COMMAND_SPECIFIER);
        };
        match request {
            Request::Abort { .. } => {
                self.phase = Phase::Idle;
                None
            }
            Request::Block { .. } => self.abort(Address::new(0, 0), AbortCode::COMMAND_SPECIFIER),
            Request::DownloadExpedited { address, data } => {
                self.phase = Phase::Idle;
                match od.write(address, data.as_slice()) {
                    Ok(()) => Some(Response::DownloadInitiate { address }.encode()),
                    Err(code) => self.abort(address, code),
                }
            }
            Request::DownloadInitiate { address, size } => {
                let size = size.map(|s| s as usize);
                if size.is_some_and(|s| s > MAX_TRANSFER) {
                    return self.abort(address, AbortCode::OUT_OF_MEMORY);
                }
                self.phase = Phase::Downloading;
                self.address = address;
                self.toggle = false;
                self.len = 0;
                self.size = size;
                Some(Response::DownloadInitiate { address }.encode())
            }
            Request::DownloadSegment { toggle, data, last } => {
                let address = self.address;
                if self.phase != Phase::Downloading {
                    return self.abort(address, AbortCode::COMMAND_SPECIFIER);
                }
                if toggle != self.toggle {
                    return self.abort(address, AbortCode::TOGGLE_BIT);
                }
                let d = data.as_slice();
                if self.len + d.len() > MAX_TRANSFER {
                    return self.abort(address, AbortCode::OUT_OF_MEMORY);
                }
                self.buf[self.len..self.len + d.len()].copy_from_slice(d);
                self.len += d.len();
                self.toggle = !self.toggle;
                if last {
                    self.phase = Phase::Idle;
                    if let Some(size) = self.size {
                        if size != self.len {
                            let code = if self.len > size {
                                AbortCode::LENGTH_TOO_HIGH
                            } else {
                                AbortCode::LENGTH_TOO_LOW
                            };
                            return self.abort(address, code);
                        }
                    }
                    let (buf, len) = (self.buf, self.len);
                    if let Err(code) = od.write(address, &buf[..len]) {
                        return self.abort(address, code);
                    }
                }
                Some(Response::DownloadSegment { toggle }.encode())
            }
            Request::UploadInitiate { address } => {
                self.phase = Phase::Idle;
                let mut buf = [0u8; MAX_TRANSFER];
                let len = match od.read(address, &mut buf) {
                    Ok(len) => len.min(MAX_TRANSFER),
                    Err(code) => return self.abort(address, code),
                };
                if (1..=4).contains(&len) {
                    let data = Chunk::truncated(&buf[..len]);
                    return Some(Response::UploadExpedited { address, data }.encode());
                }
                self.buf = buf;
                self.len = len;
                self.pos = 0;
                self.toggle = false;
                self.address = address;
                self.phase = Phase::Uploading;
                Some(
                    Response::UploadInitiate {
                        address,
                        size: Some(len as u32),
                    }
                    .encode(),
                )
            }
            Request::UploadSegment { toggle } => {
                let address = self.address;
                if self.phase != Phase::Uploading {
                    return self.abort(address, AbortCode::COMMAND_SPECIFIER);
                }
                if toggle != self.toggle {
                    return self.abort(address, AbortCode::TOGGLE_BIT);
                }
                let n = (self.len - self.pos).min(7);
                let data = Chunk::truncated(&self.buf[self.pos..self.pos + n]);
                self.pos += n;
                self.toggle = !self.toggle;
                let last = self.pos == self.len;
                if last {
                    self.phase = Phase::Idle;
                }
                Some(Response::UploadSegment { toggle, data, last }.encode())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::sdo_client::{Client, Failure, Next, SdoError};
    use super::*;

    /// Two objects: 0x1008 (a 20-byte string, read-only) and 0x2000:01 (rw, any length).
    struct Od {
        name: [u8; 20],
        value: [u8; 64],
        value_len: usize,
    }

    impl Dictionary for Od {
        fn read(&mut self, a: Address, out: &mut [u8]) -> Result<usize, AbortCode> {
            match (a.index, a.sub) {
                (0x1008, 0) => {
                    out[..20].copy_from_slice(&self.name);
                    Ok(20)
                }
                (0x2000, 1) => {
                    out[..self.value_len].copy_from_slice(&self.value[..self.value_len]);
                    Ok(self.value_len)
                }
                (0x2000, _) => Err(AbortCode::NO_SUB_INDEX),
                _ => Err(AbortCode::NO_OBJECT),
            }
        }

        fn write(&mut self, a: Address, data: &[u8]) -> Result<(), AbortCode> {
            match (a.index, a.sub) {
                (0x1008, 0) => Err(AbortCode::READ_ONLY),
                (0x2000, 1) if data.len() <= 64 => {
                    self.value[..data.len()].copy_from_slice(data);
                    self.value_len = data.len();
                    Ok(())
                }
                (0x2000, 1) => Err(AbortCode::LENGTH_TOO_HIGH),
                _ => Err(AbortCode::NO_OBJECT),
            }
        }
    }

    fn run(
        client: &mut Client,
        server: &mut Server,
        od: &mut Od,
        first: [u8; 8],
    ) -> Result<(), Failure> {
        let mut msg = first;
        for _ in 0..100 {
            let answer = server.on_request(&msg, od).expect("an answer");
            match client.on_response(&answer)? {
                Next::Send(m) => msg = m,
                Next::Done => return Ok(()),
            }
        }
        panic!("transfer did not end");
    }

    #[test]
    fn expedited_and_segmented_transfers_between_our_client_and_server() {
        let mut od = Od {
            name: *b"rl-rs fake CiA 402  ",
            value: [0; 64],
            value_len: 2,
        };
        let (mut c, mut s) = (Client::new(), Server::new());
        let first = c.upload(Address::new(0x1008, 0));
        run(&mut c, &mut s, &mut od, first).unwrap();
        assert_eq!(c.data(), b"rl-rs fake CiA 402  ");
        for len in [1usize, 4, 5, 7, 8, 14, 15, 64] {
            let data: Vec<u8> = (0..len as u8).collect();
            let first = c.download(Address::new(0x2000, 1), &data).unwrap();
            run(&mut c, &mut s, &mut od, first).unwrap();
            let first = c.upload(Address::new(0x2000, 1));
            run(&mut c, &mut s, &mut od, first).unwrap();
            assert_eq!(c.data(), &data[..], "{len} bytes");
        }
        let first = c.download(Address::new(0x1008, 0), &[1, 2]).unwrap();
        let e = run(&mut c, &mut s, &mut od, first).unwrap_err();
        assert_eq!(
            e.error,
            SdoError::Aborted {
                address: Address::new(0x1008, 0),
                code: AbortCode::READ_ONLY
            }
        );
        let first = c.upload(Address::new(0x2000, 9));
        let e = run(&mut c, &mut s, &mut od, first).unwrap_err();
        assert_eq!(
            e.error.to_string(),
            "object 0x2000:09: the server aborted with 0x06090011 (sub-index does not exist)"
        );
    }

    #[test]
    fn a_wrong_toggle_and_a_timeout_abort_the_transfer() {
        let mut c = Client::new();
        c.upload(Address::new(0x1008, 0));
        let init = Response::UploadInitiate {
            address: Address::new(0x1008, 0),
            size: Some(20),
        };
        assert!(matches!(c.on_response(&init.encode()), Ok(Next::Send(_))));
        let bad = Response::UploadSegment {
            toggle: true,
            data: Chunk::truncated(b"abc"),
            last: false,
        };
        let f = c.on_response(&bad.encode()).unwrap_err();
        assert_eq!(f.send.unwrap()[4..], AbortCode::TOGGLE_BIT.0.to_le_bytes());
        assert!(!c.is_busy());
        c.upload(Address::new(0x6064, 0));
        let f = c.timeout();
        assert_eq!(
            f.error,
            SdoError::Timeout {
                address: Address::new(0x6064, 0)
            }
        );
        assert_eq!(f.send.unwrap(), [0x80, 0x64, 0x60, 0, 0, 0, 0x04, 0x05]);
        let mut s = Server::new();
        let mut od = Od {
            name: [0; 20],
            value: [0; 64],
            value_len: 0,
        };
        let r = s.on_request(&[0xC0, 0, 0, 0, 0, 0, 0, 0], &mut od).unwrap();
        assert_eq!(
            Response::decode(&r),
            Ok(Response::Abort {
                address: Address::new(0, 0),
                code: AbortCode::COMMAND_SPECIFIER
            })
        );
    }
}
