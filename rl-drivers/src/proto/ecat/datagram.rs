//! Datagrams (ETG.1000.4 §5.4; `shared/reference/ethercat.md`): a 10-byte header, the data and
//! a 2-byte working counter, all little-endian, several chained in one frame by the "more
//! follows" bit.
//!
//! ```text
//! byte 0     command            byte 1     index (the master's tag, echoed)
//! bytes 2-5  address: ADP u16 + ADO u16, or one 32-bit logical address (LRD, LWR, LRW)
//! bytes 6-7  len:11 | reserved:3 | circulating:1 | more follows:1
//! bytes 8-9  IRQ (devices OR their event requests in)
//! len bytes  data
//! 2 bytes    working counter
//! ```
//!
//! [`DatagramHeader`] encodes and decodes the header; [`Span`] locates a datagram's parts in a
//! buffer so a device can process it in place; [`Datagrams`] walks the chain read-only.

use core::fmt;
use core::ops::Range;

use super::command::Command;

/// Bytes of a datagram header.
pub const HEADER_LEN: usize = 10;
/// Bytes of the working counter after the data.
pub const WKC_LEN: usize = 2;
/// Bytes a datagram adds around its data.
pub const OVERHEAD: usize = HEADER_LEN + WKC_LEN;
/// The largest data length the 11-bit field holds.
pub const MAX_LEN_FIELD: u16 = 0x07FF;

const CIRCULATING: u16 = 1 << 14;
const MORE_FOLLOWS: u16 = 1 << 15;

/// A datagram header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DatagramHeader {
    /// The command code (0..=14 are defined; see [`command`](Self::command)).
    pub cmd: u8,
    /// The master's index, returned unchanged: it matches replies to requests.
    pub index: u8,
    /// ADP (low 16 bits) and ADO (high 16 bits), or a logical address.
    pub address: u32,
    /// Data bytes (11 bits).
    pub len: u16,
    /// Set by a device that finds a frame circulating (port 0 closed); the next device that
    /// sees it set again drops the frame.
    pub circulating: bool,
    /// Another datagram follows in the frame.
    pub more_follows: bool,
    /// The IRQ field: devices OR in their AL event requests (masked by 0x0200).
    pub irq: u16,
}

impl DatagramHeader {
    /// A header for `command` at `address` with `len` data bytes (index 0, no flags).
    pub const fn new(command: Command, address: u32, len: u16) -> Self {
        Self {
            cmd: command.code(),
            index: 0,
            address,
            len,
            circulating: false,
            more_follows: false,
            irq: 0,
        }
    }

    /// The command (`None` for a code above 14, which devices pass on untouched).
    pub const fn command(&self) -> Option<Command> {
        Command::from_code(self.cmd)
    }

    /// ADP: the position (auto-increment, broadcast) or station address.
    pub const fn adp(&self) -> u16 {
        self.address as u16
    }

    /// ADO: the register (physical memory address) in the device.
    pub const fn ado(&self) -> u16 {
        (self.address >> 16) as u16
    }

    /// Decodes the first [`HEADER_LEN`] bytes of `bytes`.
    pub fn decode(bytes: &[u8]) -> Result<Self, DatagramError> {
        let Some(b) = bytes.get(..HEADER_LEN) else {
            return Err(DatagramError::Truncated {
                offset: 0,
                need: HEADER_LEN,
                have: bytes.len(),
            });
        };
        let flags = u16::from_le_bytes([b[6], b[7]]);
        Ok(Self {
            cmd: b[0],
            index: b[1],
            address: u32::from_le_bytes([b[2], b[3], b[4], b[5]]),
            len: flags & MAX_LEN_FIELD,
            circulating: flags & CIRCULATING != 0,
            more_follows: flags & MORE_FOLLOWS != 0,
            irq: u16::from_le_bytes([b[8], b[9]]),
        })
    }

    /// Writes the header into the first [`HEADER_LEN`] bytes of `out` (the reserved bits are
    /// written as zero; `len` is cut to 11 bits).
    pub fn encode(&self, out: &mut [u8; HEADER_LEN]) {
        let flags = (self.len & MAX_LEN_FIELD)
            | if self.circulating { CIRCULATING } else { 0 }
            | if self.more_follows { MORE_FOLLOWS } else { 0 };
        out[0] = self.cmd;
        out[1] = self.index;
        out[2..6].copy_from_slice(&self.address.to_le_bytes());
        out[6..8].copy_from_slice(&flags.to_le_bytes());
        out[8..10].copy_from_slice(&self.irq.to_le_bytes());
    }

    /// Bytes of the whole datagram (header, data, working counter).
    pub const fn total_len(&self) -> usize {
        OVERHEAD + self.len as usize
    }
}

/// An ADP + ADO address: `register` in the device at `adp`.
pub const fn physical(adp: u16, register: u16) -> u32 {
    adp as u32 | (register as u32) << 16
}

/// The ADP that addresses the device at auto-increment `position` (0 for the first device,
/// −1 for the second as seen by the master, …).
pub const fn position(position: u16, register: u16) -> u32 {
    physical(0u16.wrapping_sub(position), register)
}

/// Why a datagram chain does not decode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DatagramError {
    /// The buffer ends inside the datagram at `offset` (counted from the first datagram).
    Truncated {
        /// Where the datagram starts.
        offset: usize,
        /// Bytes it needs from there.
        need: usize,
        /// Bytes there are.
        have: usize,
    },
}

impl fmt::Display for DatagramError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DatagramError::Truncated { offset, need, have } => write!(
                f,
                "datagram at byte {offset} needs {need} bytes, {have} remain"
            ),
        }
    }
}

/// Where one datagram's parts lie in a buffer of datagrams (offsets from the buffer's start).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Span {
    /// The decoded header.
    pub header: DatagramHeader,
    /// Where the header starts.
    pub start: usize,
    /// The data bytes.
    pub data: Range<usize>,
    /// Where the working counter is (2 bytes).
    pub wkc: usize,
}

impl Span {
    /// Locates the datagram starting at `start` in `buf`.
    pub fn at(buf: &[u8], start: usize) -> Result<Self, DatagramError> {
        let rest = buf.get(start..).unwrap_or(&[]);
        let header = DatagramHeader::decode(rest).map_err(|_| DatagramError::Truncated {
            offset: start,
            need: HEADER_LEN,
            have: rest.len(),
        })?;
        let need = header.total_len();
        if rest.len() < need {
            return Err(DatagramError::Truncated {
                offset: start,
                need,
                have: rest.len(),
            });
        }
        let data_start = start + HEADER_LEN;
        let data_end = data_start + usize::from(header.len);
        Ok(Self {
            header,
            start,
            data: data_start..data_end,
            wkc: data_end,
        })
    }

    /// Where the next datagram starts.
    pub fn end(&self) -> usize {
        self.wkc + WKC_LEN
    }

    /// The working counter in `buf`.
    pub fn read_wkc(&self, buf: &[u8]) -> u16 {
        u16::from_le_bytes([buf[self.wkc], buf[self.wkc + 1]])
    }

    /// Stores `wkc` in `buf`.
    pub fn write_wkc(&self, buf: &mut [u8], wkc: u16) {
        buf[self.wkc..self.wkc + 2].copy_from_slice(&wkc.to_le_bytes());
    }
}

/// A decoded datagram borrowing its data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Datagram<'a> {
    /// The header.
    pub header: DatagramHeader,
    /// The data.
    pub data: &'a [u8],
    /// The working counter.
    pub wkc: u16,
}

/// Walks a chain of datagrams (each yields its datagram or the error that ends the walk).
#[derive(Clone, Debug)]
pub struct Datagrams<'a> {
    buf: &'a [u8],
    pos: usize,
    done: bool,
}

impl<'a> Datagrams<'a> {
    /// The chain starting at the beginning of `buf` (the bytes after the EtherCAT header,
    /// cut to the header's length).
    pub const fn new(buf: &'a [u8]) -> Self {
        Self {
            buf,
            pos: 0,
            done: buf.is_empty(),
        }
    }

    /// Bytes after the last datagram (once the walk has ended without an error).
    pub fn remainder(&self) -> &'a [u8] {
        self.buf.get(self.pos..).unwrap_or(&[])
    }
}

impl<'a> Iterator for Datagrams<'a> {
    type Item = Result<Datagram<'a>, DatagramError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        match Span::at(self.buf, self.pos) {
            Ok(span) => {
                self.pos = span.end();
                self.done = !span.header.more_follows;
                Some(Ok(Datagram {
                    header: span.header,
                    data: &self.buf[span.data.clone()],
                    wkc: span.read_wkc(self.buf),
                }))
            }
            Err(e) => {
                self.done = true;
                Some(Err(e))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_brd_header_round_trips() {
        // shared/reference/ethercat.md: BRD of register 0x0000, 2 bytes.
        let bytes = [0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00];
        let h = DatagramHeader::decode(&bytes).unwrap();
        assert_eq!(h.command(), Some(Command::Brd));
        assert_eq!((h.adp(), h.ado(), h.len), (0, 0, 2));
        assert!(!h.more_follows && !h.circulating);
        let mut out = [0u8; HEADER_LEN];
        h.encode(&mut out);
        assert_eq!(out, bytes);
        // soem-single-lan9252.pcapng frame 43: FPRD 0x1001:0x0012, 2 bytes.
        let f = [0x04, 0x06, 0x01, 0x10, 0x12, 0x00, 0x02, 0x80, 0x00, 0x00];
        let h = DatagramHeader::decode(&f).unwrap();
        assert_eq!((h.cmd, h.index, h.adp(), h.ado()), (4, 6, 0x1001, 0x0012));
        assert!(h.more_follows);
        assert_eq!(position(1, 0x0010), physical(0xFFFF, 0x0010));
    }

    #[test]
    fn a_chain_walks_to_its_end_and_reports_truncation() {
        let mut buf = [0u8; 64];
        let mut a = DatagramHeader::new(Command::Lrw, 0x0001_0000, 3);
        a.more_follows = true;
        a.encode((&mut buf[..10]).try_into().unwrap());
        buf[10..13].copy_from_slice(&[1, 2, 3]);
        buf[13..15].copy_from_slice(&3u16.to_le_bytes());
        let b = DatagramHeader::new(Command::Brd, physical(0, 0x130), 2);
        b.encode((&mut buf[15..25]).try_into().unwrap());
        buf[27..29].copy_from_slice(&2u16.to_le_bytes());
        let all: Vec<_> = Datagrams::new(&buf[..29]).collect();
        assert_eq!(all.len(), 2);
        let first = all[0].unwrap();
        assert_eq!((first.data, first.wkc), (&[1u8, 2, 3][..], 3));
        assert_eq!(all[1].unwrap().header.ado(), 0x130);
        let cut: Vec<_> = Datagrams::new(&buf[..20]).collect();
        assert_eq!(
            cut[1],
            Err(DatagramError::Truncated {
                offset: 15,
                need: 10,
                have: 5
            })
        );
    }
}
