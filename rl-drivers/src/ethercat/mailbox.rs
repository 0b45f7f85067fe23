//! The master's mailbox and CoE SDO client: a message goes into the device's mailbox-out sync
//! manager (the write fills it only when it reaches the last byte), the answer is read from the
//! mailbox-in sync manager once its status says it is full; SDO uploads and downloads,
//! expedited (up to 4 bytes), normal (the data in the initiate message) and segmented (as many
//! segments as the mailbox needs), optionally with complete access. The 8-byte SDO messages are
//! the CANopen SDO codec's ([`crate::proto::canopen::sdo`]); only the mailbox framing is CoE's.
//! Every wait is bounded by the configured mailbox timeout.

use std::time::{Duration, Instant};

use super::error::EcError;
use super::master::Master;
use crate::proto::canopen::sdo::{AbortCode, Address, Chunk, Request, Response};
use crate::proto::canopen::sdo_client::SdoError;
use crate::proto::ecat::coe::{self, COMPLETE_ACCESS, CoeHeader, CoeService, SdoMessage};
use crate::proto::ecat::mailbox::{MailboxErrorCode, MailboxHeader, MailboxType};
use crate::proto::ecat::register as reg;
use crate::proto::ecat::sync_manager;

impl Master {
    fn mailbox_sm_in(&self, k: usize) -> u8 {
        self.devices[k]
            .sync_manager(crate::proto::ecat::sii::SmUsage::MailboxIn)
            .map_or(1, |(n, _)| n)
    }

    /// Sends one mailbox message (`message` starts with the mailbox header) to device `k`.
    pub fn mailbox_send(&mut self, k: usize, message: &[u8]) -> Result<(), EcError> {
        let d = &self.devices[k];
        if !d.has_coe() {
            return Err(EcError::NoMailbox {
                device: d.reference(),
            });
        }
        let (offset, size) = (d.mailbox_out.offset, usize::from(d.mailbox_out.size));
        if message.len() > size {
            return Err(EcError::Mailbox {
                device: d.reference(),
                what: "message longer than the mailbox",
            });
        }
        // The whole window is written so that its last byte fills the mailbox.
        let mut buf = vec![0u8; size];
        buf[..message.len()].copy_from_slice(message);
        let deadline = Instant::now() + self.config.mailbox_timeout;
        loop {
            if self.fpwr_wkc(k, offset, &buf)? == 1 {
                return Ok(());
            }
            if Instant::now() >= deadline {
                return Err(EcError::Timeout {
                    what: "an empty mailbox",
                    waited_us: self.config.mailbox_timeout.as_micros() as u64,
                });
            }
            std::thread::sleep(Duration::from_micros(200));
        }
    }

    /// Waits for device `k`'s next mailbox message and returns it (header included).
    pub fn mailbox_receive(&mut self, k: usize) -> Result<Vec<u8>, EcError> {
        let sm = self.mailbox_sm_in(k);
        let (offset, size) = {
            let d = &self.devices[k];
            (d.mailbox_in.offset, usize::from(d.mailbox_in.size))
        };
        let deadline = Instant::now() + self.config.mailbox_timeout;
        loop {
            let mut status = [0u8; 1];
            self.fprd(k, reg::SM0 + 8 * u16::from(sm) + 5, &mut status)?;
            if status[0] & sync_manager::STATUS_MAILBOX_FULL != 0 {
                let mut buf = vec![0u8; size];
                let station = self.devices[k].station;
                let wkc = self.datagram(
                    crate::proto::ecat::command::Command::Fprd,
                    crate::proto::ecat::datagram::physical(station, offset),
                    &mut buf,
                )?;
                if wkc == 1 {
                    return Ok(buf);
                }
            }
            if Instant::now() >= deadline {
                return Err(EcError::Timeout {
                    what: "a mailbox answer",
                    waited_us: self.config.mailbox_timeout.as_micros() as u64,
                });
            }
            std::thread::sleep(Duration::from_micros(100));
        }
    }

    fn next_counter(&mut self, k: usize) -> u8 {
        let c = self.devices[k].mailbox_counter;
        self.devices[k].mailbox_counter = MailboxHeader::next_counter(c);
        c
    }

    /// One SDO request message and its response (emergency messages in between are skipped).
    fn sdo_exchange(
        &mut self,
        k: usize,
        message: &[u8],
        address: Address,
    ) -> Result<Vec<u8>, EcError> {
        self.mailbox_send(k, message)?;
        let device = self.devices[k].reference();
        for _ in 0..8 {
            let answer = self.mailbox_receive(k)?;
            let (h, body) = MailboxHeader::split(&answer).map_err(|_| EcError::Mailbox {
                device,
                what: "malformed mailbox header",
            })?;
            match h.kind {
                MailboxType::Error => {
                    let code = MailboxErrorCode::from_reply(body).unwrap_or(MailboxErrorCode(0));
                    return Err(EcError::MailboxError { device, code });
                }
                MailboxType::Coe => {
                    if body.len() < coe::HEADER_LEN {
                        return Err(EcError::Mailbox {
                            device,
                            what: "CoE message too short",
                        });
                    }
                    match CoeHeader::decode([body[0], body[1]]).service {
                        CoeService::SdoResponse => return Ok(answer),
                        CoeService::Emergency => continue,
                        _ => {
                            return Err(EcError::Sdo {
                                device,
                                error: SdoError::Protocol {
                                    address,
                                    what: "an unexpected CoE service",
                                    code: AbortCode::GENERAL,
                                },
                            });
                        }
                    }
                }
                _ => {
                    return Err(EcError::Mailbox {
                        device,
                        what: "an answer of another mailbox protocol",
                    });
                }
            }
        }
        Err(EcError::Mailbox {
            device,
            what: "only emergency messages, no SDO response",
        })
    }

    fn sdo_message(&mut self, k: usize, head: [u8; 8], rest: &[u8]) -> Result<Vec<u8>, EcError> {
        let size = usize::from(self.devices[k].mailbox_out.size);
        let mut out = vec![0u8; size];
        let c = self.next_counter(k);
        let n = coe::write_sdo(&mut out, c, CoeService::SdoRequest, &head, rest).map_err(|_| {
            EcError::Mailbox {
                device: self.devices[k].reference(),
                what: "SDO message longer than the mailbox",
            }
        })?;
        out.truncate(n);
        Ok(out)
    }

    fn sdo_failed(
        &mut self,
        k: usize,
        address: Address,
        error: SdoError,
        abort: Option<AbortCode>,
    ) -> EcError {
        if let Some(code) = abort {
            // Tell the device the transfer is over (no answer expected).
            if let Ok(m) = self.sdo_message(k, Request::Abort { address, code }.encode(), &[]) {
                let _ = self.mailbox_send(k, &m);
            }
        }
        EcError::Sdo {
            device: self.devices[k].reference(),
            error,
        }
    }

    /// Reads object `address` of device `k` (`complete`: the whole object, sub-index 0 as 16
    /// bits then every sub-index). Returns its bytes.
    pub fn sdo_upload(
        &mut self,
        k: usize,
        address: Address,
        complete: bool,
    ) -> Result<Vec<u8>, EcError> {
        let mut head = Request::UploadInitiate { address }.encode();
        if complete {
            head[0] |= COMPLETE_ACCESS;
        }
        let m = self.sdo_message(k, head, &[])?;
        let answer = self.sdo_exchange(k, &m, address)?;
        let (_, body) = MailboxHeader::split(&answer).map_err(|_| EcError::Reply("mailbox"))?;
        let msg = SdoMessage::parse(body).map_err(|_| EcError::Reply("SDO response"))?;
        let protocol = |what| SdoError::Protocol {
            address,
            what,
            code: AbortCode::COMMAND_SPECIFIER,
        };
        match msg.response() {
            Ok(Response::Abort { address, code }) => {
                Err(self.sdo_failed(k, address, SdoError::Aborted { address, code }, None))
            }
            Ok(Response::UploadExpedited { address: a, data }) if a == address => {
                Ok(data.as_slice().to_vec())
            }
            Ok(Response::UploadInitiate { address: a, size }) if a == address => {
                let size = size.map_or(msg.rest.len(), |s| s as usize);
                let mut data = msg.normal_data(size).to_vec();
                let mut toggle = false;
                while data.len() < size {
                    let m = self.sdo_message(k, Request::UploadSegment { toggle }.encode(), &[])?;
                    let answer = self.sdo_exchange(k, &m, address)?;
                    let (_, body) =
                        MailboxHeader::split(&answer).map_err(|_| EcError::Reply("mailbox"))?;
                    let seg = SdoMessage::parse(body).map_err(|_| EcError::Reply("SDO segment"))?;
                    match seg.response() {
                        Ok(Response::UploadSegment {
                            toggle: t, last, ..
                        }) => {
                            if t != toggle {
                                let e = protocol("toggle bit not alternated");
                                return Err(self.sdo_failed(
                                    k,
                                    address,
                                    e,
                                    Some(AbortCode::TOGGLE_BIT),
                                ));
                            }
                            data.extend_from_slice(seg.segment_data(coe::sdo_part(body)));
                            toggle = !toggle;
                            if last {
                                break;
                            }
                        }
                        Ok(Response::Abort { code, .. }) => {
                            return Err(self.sdo_failed(
                                k,
                                address,
                                SdoError::Aborted { address, code },
                                None,
                            ));
                        }
                        _ => {
                            let e = protocol("an answer that is no upload segment");
                            return Err(self.sdo_failed(
                                k,
                                address,
                                e,
                                Some(AbortCode::COMMAND_SPECIFIER),
                            ));
                        }
                    }
                }
                if data.len() != size {
                    let e = protocol("segments do not add up to the announced size");
                    return Err(self.sdo_failed(k, address, e, None));
                }
                Ok(data)
            }
            _ => {
                let e = protocol("an answer that does not fit an upload");
                Err(self.sdo_failed(k, address, e, Some(AbortCode::COMMAND_SPECIFIER)))
            }
        }
    }

    /// Writes `data` to object `address` of device `k`: expedited up to 4 bytes, else normal,
    /// with segments for what does not fit the mailbox.
    pub fn sdo_download(
        &mut self,
        k: usize,
        address: Address,
        data: &[u8],
        complete: bool,
    ) -> Result<(), EcError> {
        let out_size = usize::from(self.devices[k].mailbox_out.size);
        let protocol = |what| SdoError::Protocol {
            address,
            what,
            code: AbortCode::COMMAND_SPECIFIER,
        };
        let (mut head, first) = if (1..=4).contains(&data.len()) {
            let chunk = Chunk::new(data).ok_or(EcError::Reply("chunk"))?;
            (
                Request::DownloadExpedited {
                    address,
                    data: chunk,
                }
                .encode(),
                0,
            )
        } else {
            let room = out_size.saturating_sub(coe::SDO_OVERHEAD);
            (
                Request::DownloadInitiate {
                    address,
                    size: Some(data.len() as u32),
                }
                .encode(),
                data.len().min(room),
            )
        };
        if complete {
            head[0] |= COMPLETE_ACCESS;
        }
        let m = self.sdo_message(k, head, &data[..first])?;
        let answer = self.sdo_exchange(k, &m, address)?;
        let (_, body) = MailboxHeader::split(&answer).map_err(|_| EcError::Reply("mailbox"))?;
        let msg = SdoMessage::parse(body).map_err(|_| EcError::Reply("SDO response"))?;
        match msg.response() {
            Ok(Response::DownloadInitiate { address: a }) if a == address => {}
            Ok(Response::Abort { code, .. }) => {
                return Err(self.sdo_failed(k, address, SdoError::Aborted { address, code }, None));
            }
            _ => {
                let e = protocol("an answer that does not fit a download");
                return Err(self.sdo_failed(k, address, e, Some(AbortCode::COMMAND_SPECIFIER)));
            }
        }
        let seg_room = out_size.saturating_sub(coe::SEGMENT_OVERHEAD).max(7);
        let mut pos = if data.len() <= 4 { data.len() } else { first };
        let mut toggle = false;
        while pos < data.len() {
            let n = (data.len() - pos).min(seg_room);
            let last = pos + n == data.len();
            let mut out = vec![0u8; out_size.max(coe::SEGMENT_OVERHEAD + 7)];
            let c = self.next_counter(k);
            let command = (u8::from(toggle) << 4) | u8::from(last);
            let len = coe::write_segment(
                &mut out,
                c,
                CoeService::SdoRequest,
                command,
                &data[pos..pos + n],
            )
            .map_err(|_| EcError::Reply("segment"))?;
            out.truncate(len);
            let answer = self.sdo_exchange(k, &out, address)?;
            let (_, body) = MailboxHeader::split(&answer).map_err(|_| EcError::Reply("mailbox"))?;
            let msg = SdoMessage::parse(body).map_err(|_| EcError::Reply("SDO response"))?;
            match msg.response() {
                Ok(Response::DownloadSegment { toggle: t }) if t == toggle => {}
                Ok(Response::Abort { code, .. }) => {
                    return Err(self.sdo_failed(
                        k,
                        address,
                        SdoError::Aborted { address, code },
                        None,
                    ));
                }
                _ => {
                    let e = protocol("an answer that is no download segment acknowledge");
                    return Err(self.sdo_failed(k, address, e, Some(AbortCode::COMMAND_SPECIFIER)));
                }
            }
            pos += n;
            toggle = !toggle;
        }
        Ok(())
    }

    /// Reads an integer object of up to 8 bytes (little-endian, zero-extended).
    pub fn sdo_read_u64(&mut self, k: usize, index: u16, sub: u8) -> Result<u64, EcError> {
        let d = self.sdo_upload(k, Address::new(index, sub), false)?;
        let mut b = [0u8; 8];
        let n = d.len().min(8);
        b[..n].copy_from_slice(&d[..n]);
        Ok(u64::from_le_bytes(b))
    }
}
