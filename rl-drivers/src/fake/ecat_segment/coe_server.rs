//! The fake device's mailbox protocol handler: CoE SDO server over the object dictionary, for
//! expedited, normal and segmented uploads and downloads and complete access, and the mailbox
//! error replies a device sends for protocols and services it does not have.
//!
//! The 8-byte SDO messages are built and parsed with the CANopen SDO codec
//! ([`crate::proto::canopen::sdo`]); CoE adds the data that follows them in the mailbox.

use super::dictionary::Dictionary;
use crate::proto::canopen::sdo::{AbortCode, Address, Chunk, Request, Response};
use crate::proto::canopen::sdo_server::Dictionary as _;
use crate::proto::ecat::coe::{self, COMPLETE_ACCESS, CoeHeader, CoeService, SdoMessage};
use crate::proto::ecat::mailbox::{self, MailboxErrorCode, MailboxHeader, MailboxType};

#[derive(Clone, Debug, Default, PartialEq, Eq)]
enum Transfer {
    #[default]
    Idle,
    Download {
        address: Address,
        complete: bool,
        size: usize,
        data: Vec<u8>,
        toggle: bool,
    },
    Upload {
        data: Vec<u8>,
        pos: usize,
        toggle: bool,
    },
}

/// One device's mailbox server.
#[derive(Clone, Debug, Default)]
pub struct MailboxServer {
    transfer: Transfer,
    counter: u8,
    /// Messages answered.
    pub requests: u64,
    /// Mailbox error replies sent.
    pub errors: u64,
    /// SDO aborts sent.
    pub aborts: u64,
}

impl MailboxServer {
    /// An idle server.
    pub fn new() -> Self {
        Self::default()
    }

    fn next_counter(&mut self) -> u8 {
        self.counter = MailboxHeader::next_counter(self.counter);
        self.counter
    }

    fn error(&mut self, code: MailboxErrorCode) -> Vec<u8> {
        self.errors += 1;
        let body = code.reply_body();
        let h = MailboxHeader::new(MailboxType::Error, body.len() as u16, self.next_counter());
        let mut out = h.encode().to_vec();
        out.extend_from_slice(&body);
        out
    }

    fn sdo(&mut self, head: [u8; 8], rest: &[u8], capacity: usize) -> Vec<u8> {
        let mut out = vec![0u8; capacity.max(coe::SDO_OVERHEAD + rest.len())];
        let counter = self.next_counter();
        let n =
            coe::write_sdo(&mut out, counter, CoeService::SdoResponse, &head, rest).unwrap_or(0);
        out.truncate(n);
        out
    }

    fn segment(&mut self, command: u8, data: &[u8], capacity: usize) -> Vec<u8> {
        let mut out = vec![0u8; capacity.max(coe::SEGMENT_OVERHEAD + 7)];
        let counter = self.next_counter();
        let n = coe::write_segment(&mut out, counter, CoeService::SdoResponse, command, data)
            .unwrap_or(0);
        out.truncate(n);
        out
    }

    fn abort(&mut self, address: Address, code: AbortCode, capacity: usize) -> Vec<u8> {
        self.aborts += 1;
        self.transfer = Transfer::Idle;
        self.sdo(Response::Abort { address, code }.encode(), &[], capacity)
    }

    /// Aborts a request the server does not take: one it cannot decode, a block transfer, or a
    /// segment of no transfer in progress.
    fn abort_command(&mut self, capacity: usize) -> Vec<u8> {
        self.abort(Address::new(0, 0), AbortCode::COMMAND_SPECIFIER, capacity)
    }

    /// Acknowledges a download (its initiation, or the whole of an expedited or short one).
    fn download_ack(&mut self, address: Address, complete: bool, capacity: usize) -> Vec<u8> {
        let head = Response::DownloadInitiate { address }.encode();
        self.sdo(with_ca(head, complete), &[], capacity)
    }

    /// Stores a download that arrived whole and acknowledges it, or aborts it.
    fn store_download(
        &mut self,
        od: &mut Dictionary,
        address: Address,
        complete: bool,
        data: &[u8],
        capacity: usize,
    ) -> Vec<u8> {
        self.transfer = Transfer::Idle;
        match download(od, address, complete, data) {
            Ok(()) => self.download_ack(address, complete, capacity),
            Err(code) => self.abort(address, code, capacity),
        }
    }

    /// Answers one message the master wrote into the mailbox (`message`: the whole mailbox
    /// buffer); `capacity` is the size of the mailbox the answer goes into. `None`: no answer
    /// (the master aborted a transfer).
    pub fn handle(
        &mut self,
        message: &[u8],
        od: &mut Dictionary,
        capacity: usize,
    ) -> Option<Vec<u8>> {
        self.requests += 1;
        let (header, body) = match MailboxHeader::split(message) {
            Ok(x) => x,
            Err(_) => return Some(self.error(MailboxErrorCode::INVALID_SIZE)),
        };
        if header.kind != MailboxType::Coe {
            return Some(self.error(MailboxErrorCode::UNSUPPORTED_PROTOCOL));
        }
        if body.len() < coe::HEADER_LEN {
            return Some(self.error(MailboxErrorCode::SIZE_TOO_SHORT));
        }
        let service = CoeHeader::decode([body[0], body[1]]).service;
        if service != CoeService::SdoRequest {
            return Some(self.error(MailboxErrorCode::SERVICE_NOT_SUPPORTED));
        }
        let Ok(m) = SdoMessage::parse(body) else {
            return Some(self.error(MailboxErrorCode::SIZE_TOO_SHORT));
        };
        let sdo_part = coe::sdo_part(body);
        let complete = m.complete_access();
        let request = match m.request() {
            Ok(r) => r,
            Err(_) => {
                return Some(self.abort_command(capacity));
            }
        };
        // Bytes of data an answer can carry after the 8-byte SDO message.
        let room = capacity.saturating_sub(coe::SDO_OVERHEAD);
        let seg_room = capacity.saturating_sub(coe::SEGMENT_OVERHEAD);
        Some(match request {
            Request::Abort { .. } => {
                self.transfer = Transfer::Idle;
                return None;
            }
            Request::Block { .. } => self.abort_command(capacity),
            Request::DownloadExpedited { address, data } => {
                self.store_download(od, address, complete, data.as_slice(), capacity)
            }
            Request::DownloadInitiate { address, size } => {
                let size = size.map_or(m.rest.len(), |s| s as usize);
                let data = m.normal_data(size).to_vec();
                if data.len() >= size {
                    self.store_download(od, address, complete, &data, capacity)
                } else {
                    self.transfer = Transfer::Download {
                        address,
                        complete,
                        size,
                        data,
                        toggle: false,
                    };
                    self.download_ack(address, complete, capacity)
                }
            }
            Request::DownloadSegment { toggle, last, .. } => {
                let Transfer::Download {
                    address,
                    complete,
                    size,
                    mut data,
                    toggle: expected,
                } = std::mem::take(&mut self.transfer)
                else {
                    return Some(self.abort_command(capacity));
                };
                if toggle != expected {
                    return Some(self.abort(address, AbortCode::TOGGLE_BIT, capacity));
                }
                data.extend_from_slice(m.segment_data(sdo_part));
                if last || data.len() >= size {
                    if data.len() != size {
                        let code = if data.len() > size {
                            AbortCode::LENGTH_TOO_HIGH
                        } else {
                            AbortCode::LENGTH_TOO_LOW
                        };
                        return Some(self.abort(address, code, capacity));
                    }
                    let r = download(od, address, complete, &data);
                    if let Err(code) = r {
                        return Some(self.abort(address, code, capacity));
                    }
                } else {
                    self.transfer = Transfer::Download {
                        address,
                        complete,
                        size,
                        data,
                        toggle: !toggle,
                    };
                }
                let head = Response::DownloadSegment { toggle }.encode();
                self.sdo(head, &[], capacity)
            }
            Request::UploadInitiate { address } => {
                self.transfer = Transfer::Idle;
                let mut value = Vec::new();
                let r = if complete {
                    od.read_complete(address.index, &mut value)
                } else {
                    let mut buf = vec![0u8; 4096];
                    od.read(address, &mut buf).map(|n| {
                        value.extend_from_slice(&buf[..n]);
                    })
                };
                if let Err(code) = r {
                    return Some(self.abort(address, code, capacity));
                }
                if (1..=4).contains(&value.len()) {
                    let head = Response::UploadExpedited {
                        address,
                        data: Chunk::truncated(&value),
                    }
                    .encode();
                    self.sdo(with_ca(head, complete), &[], capacity)
                } else {
                    let head = Response::UploadInitiate {
                        address,
                        size: Some(value.len() as u32),
                    }
                    .encode();
                    let first = value.len().min(room);
                    let answer = self.sdo(with_ca(head, complete), &value[..first], capacity);
                    if first < value.len() {
                        self.transfer = Transfer::Upload {
                            data: value,
                            pos: first,
                            toggle: false,
                        };
                    }
                    answer
                }
            }
            Request::UploadSegment { toggle } => {
                let Transfer::Upload {
                    data,
                    pos,
                    toggle: expected,
                } = std::mem::take(&mut self.transfer)
                else {
                    return Some(self.abort_command(capacity));
                };
                if toggle != expected {
                    return Some(self.abort(Address::new(0, 0), AbortCode::TOGGLE_BIT, capacity));
                }
                let n = (data.len() - pos).min(seg_room.max(7));
                let last = pos + n == data.len();
                let command = (u8::from(toggle) << 4) | u8::from(last);
                let answer = self.segment(command, &data[pos..pos + n], capacity);
                if !last {
                    self.transfer = Transfer::Upload {
                        data,
                        pos: pos + n,
                        toggle: !toggle,
                    };
                }
                answer
            }
        })
    }
}

/// Stores a download: the whole object (complete access) or one entry.
fn download(
    od: &mut Dictionary,
    address: Address,
    complete: bool,
    data: &[u8],
) -> Result<(), AbortCode> {
    if complete {
        od.write_complete(address.index, data)
    } else {
        od.write(address, data)
    }
}

fn with_ca(mut head: [u8; 8], complete: bool) -> [u8; 8] {
    if complete {
        head[0] |= COMPLETE_ACCESS;
    }
    head
}

/// The mailbox header length, re-exported for the firmware.
pub const MAILBOX_HEADER_LEN: usize = mailbox::HEADER_LEN;

#[cfg(test)]
mod tests {
    use super::super::dictionary::{Access, le_bytes};
    use super::*;
    use crate::proto::canopen::object::DataType;

    fn od() -> Dictionary {
        let mut d = Dictionary::new();
        d.var(
            0x1008,
            "name",
            DataType::VisibleString,
            Access::Ro,
            false,
            b"a long device name, longer than a mailbox of 48 bytes allows in one go".to_vec(),
        );
        d.var(
            0x6064,
            "position",
            DataType::Integer32,
            Access::Rw,
            true,
            le_bytes(1234, 4),
        );
        d
    }

    fn request(head: [u8; 8], rest: &[u8], counter: u8) -> Vec<u8> {
        let mut out = vec![0u8; 128];
        let n = coe::write_sdo(&mut out, counter, CoeService::SdoRequest, &head, rest).unwrap();
        out.truncate(n);
        out
    }

    fn response(answer: &[u8]) -> (Response, Vec<u8>) {
        let (_, body) = MailboxHeader::split(answer).unwrap();
        let m = SdoMessage::parse(body).unwrap();
        (m.response().unwrap(), coe::sdo_part(body).to_vec())
    }

    #[test]
    fn expedited_normal_and_segmented_uploads() {
        let mut s = MailboxServer::new();
        let mut d = od();
        let up = Request::UploadInitiate {
            address: Address::new(0x6064, 0),
        }
        .encode();
        let a = s.handle(&request(up, &[], 1), &mut d, 48).unwrap();
        let (r, _) = response(&a);
        assert!(
            matches!(r, Response::UploadExpedited { data, .. } if data.as_slice() == 1234i32.to_le_bytes())
        );
        // 0x1008 does not fit a 48-byte mailbox: normal initiate + segments.
        let up = Request::UploadInitiate {
            address: Address::new(0x1008, 0),
        }
        .encode();
        let a = s.handle(&request(up, &[], 2), &mut d, 48).unwrap();
        let (r, part) = response(&a);
        let Response::UploadInitiate {
            size: Some(size), ..
        } = r
        else {
            panic!("{r:?}")
        };
        let mut got = part[8..].to_vec();
        let mut toggle = false;
        while got.len() < size as usize {
            let seg = [0x60 | (u8::from(toggle) << 4), 0, 0, 0, 0, 0, 0, 0];
            let a = s.handle(&request(seg, &[], 3), &mut d, 48).unwrap();
            let (_, body) = MailboxHeader::split(&a).unwrap();
            let m = SdoMessage::parse(body).unwrap();
            got.extend_from_slice(m.segment_data(coe::sdo_part(body)));
            toggle = !toggle;
        }
        assert_eq!(got, d.get(0x1008, 0).unwrap());
        // A wrong toggle aborts.
        let a = s
            .handle(&request([0x70, 0, 0, 0, 0, 0, 0, 0], &[], 4), &mut d, 48)
            .unwrap();
        assert!(matches!(
            response(&a).0,
            Response::Abort {
                code: AbortCode::COMMAND_SPECIFIER,
                ..
            }
        ));
    }

    #[test]
    fn downloads_and_refusals() {
        let mut s = MailboxServer::new();
        let mut d = od();
        let w = Request::DownloadExpedited {
            address: Address::new(0x6064, 0),
            data: Chunk::new(&7i32.to_le_bytes()).unwrap(),
        }
        .encode();
        let a = s.handle(&request(w, &[], 1), &mut d, 48).unwrap();
        assert!(matches!(response(&a).0, Response::DownloadInitiate { .. }));
        assert_eq!(d.int(0x6064, 0), 7);
        let w = Request::DownloadExpedited {
            address: Address::new(0x1008, 0),
            data: Chunk::new(b"x").unwrap(),
        }
        .encode();
        let a = s.handle(&request(w, &[], 2), &mut d, 48).unwrap();
        assert!(matches!(
            response(&a).0,
            Response::Abort {
                code: AbortCode::READ_ONLY,
                ..
            }
        ));
        // Another protocol: mailbox error "protocol not supported".
        let mut foe = MailboxHeader::new(MailboxType::Foe, 4, 1).encode().to_vec();
        foe.extend_from_slice(&[0; 4]);
        let a = s.handle(&foe, &mut d, 48).unwrap();
        let (h, body) = MailboxHeader::split(&a).unwrap();
        assert_eq!(h.kind, MailboxType::Error);
        assert_eq!(
            MailboxErrorCode::from_reply(body),
            Some(MailboxErrorCode::UNSUPPORTED_PROTOCOL)
        );
    }
}
