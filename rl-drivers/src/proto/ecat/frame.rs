//! EtherCAT frames (ETG.1000.4 §5.3; `shared/reference/ethercat.md`): an Ethernet II header
//! with EtherType 0x88A4, the 2-byte EtherCAT header `length:11 | reserved:1 | type:4`
//! (little-endian; type 1 = datagrams) and the chained datagrams, padded to the Ethernet
//! minimum of 60 bytes (without FCS).
//!
//! The master sends to the broadcast address; every device that forwards a frame sets the
//! locally administered bit (0x02) of the first source-address byte, which is how a master tells
//! a returning frame from its own echo.

use core::fmt;

use super::datagram::{self, DatagramError, DatagramHeader, Datagrams, HEADER_LEN, OVERHEAD};

/// The EtherType of EtherCAT.
pub const ETHERTYPE: u16 = 0x88A4;
/// Bytes of the Ethernet II header.
pub const ETHERNET_HEADER_LEN: usize = 14;
/// Bytes of the EtherCAT header.
pub const ECAT_HEADER_LEN: usize = 2;
/// Where the first datagram starts.
pub const DATAGRAMS_OFFSET: usize = ETHERNET_HEADER_LEN + ECAT_HEADER_LEN;
/// The shortest Ethernet frame without FCS: shorter frames are padded to this.
pub const MIN_FRAME_LEN: usize = 60;
/// The longest Ethernet frame without FCS (1500 bytes of payload).
pub const MAX_FRAME_LEN: usize = 1514;
/// The most data bytes one datagram can carry in a frame of its own (1486).
pub const MAX_DATAGRAM_DATA: usize = MAX_FRAME_LEN - DATAGRAMS_OFFSET - OVERHEAD;
/// The EtherCAT header type of datagram frames.
pub const TYPE_DATAGRAMS: u8 = 1;

/// A MAC address.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct MacAddr(pub [u8; 6]);

impl MacAddr {
    /// ff:ff:ff:ff:ff:ff, where a master sends.
    pub const BROADCAST: Self = Self([0xFF; 6]);
    /// 10:10:10:10:10:10, the source our master (and ethercrab) sends from: a unicast address
    /// with the locally administered bit clear, so that returned frames (bit set) differ from
    /// the echo of our own.
    pub const MASTER: Self = Self([0x10; 6]);
    /// The bit a forwarding device sets in the first byte.
    pub const FORWARDED_BIT: u8 = 0x02;

    /// The address as a device returns it (locally administered bit set).
    pub const fn forwarded(self) -> Self {
        let mut b = self.0;
        b[0] |= Self::FORWARDED_BIT;
        Self(b)
    }

    /// Whether the locally administered bit is set.
    pub const fn is_forwarded(self) -> bool {
        self.0[0] & Self::FORWARDED_BIT != 0
    }
}

impl fmt::Display for MacAddr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0;
        write!(
            f,
            "{:02x}:{:02x}:{:02x}:{:02x}:{:02x}:{:02x}",
            b[0], b[1], b[2], b[3], b[4], b[5]
        )
    }
}

impl fmt::Debug for MacAddr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MacAddr({self})")
    }
}

/// The Ethernet II header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EthernetHeader {
    /// Destination.
    pub destination: MacAddr,
    /// Source.
    pub source: MacAddr,
    /// EtherType.
    pub ethertype: u16,
}

impl EthernetHeader {
    /// Decodes the first 14 bytes.
    pub fn decode(bytes: &[u8]) -> Result<Self, FrameError> {
        let Some(b) = bytes.get(..ETHERNET_HEADER_LEN) else {
            return Err(FrameError::TooShort {
                len: bytes.len(),
                need: ETHERNET_HEADER_LEN,
            });
        };
        let mut destination = [0u8; 6];
        let mut source = [0u8; 6];
        destination.copy_from_slice(&b[..6]);
        source.copy_from_slice(&b[6..12]);
        Ok(Self {
            destination: MacAddr(destination),
            source: MacAddr(source),
            ethertype: u16::from_be_bytes([b[12], b[13]]),
        })
    }

    /// The 14 bytes.
    pub fn encode(&self) -> [u8; ETHERNET_HEADER_LEN] {
        let mut b = [0u8; ETHERNET_HEADER_LEN];
        b[..6].copy_from_slice(&self.destination.0);
        b[6..12].copy_from_slice(&self.source.0);
        b[12..].copy_from_slice(&self.ethertype.to_be_bytes());
        b
    }
}

/// The EtherCAT header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EcatHeader {
    /// Bytes of datagrams that follow (11 bits).
    pub length: u16,
    /// The reserved bit.
    pub reserved: bool,
    /// 1: datagrams; 4: network variables; 5: mailbox (gateway).
    pub kind: u8,
}

impl EcatHeader {
    /// A datagram header over `length` bytes.
    pub const fn datagrams(length: u16) -> Self {
        Self {
            length,
            reserved: false,
            kind: TYPE_DATAGRAMS,
        }
    }

    /// Decodes 2 bytes.
    pub fn decode(b: [u8; 2]) -> Self {
        let v = u16::from_le_bytes(b);
        Self {
            length: v & 0x07FF,
            reserved: v & 0x0800 != 0,
            kind: (v >> 12) as u8,
        }
    }

    /// The 2 bytes.
    pub fn encode(&self) -> [u8; 2] {
        let v = (self.length & 0x07FF)
            | if self.reserved { 0x0800 } else { 0 }
            | (u16::from(self.kind & 0x0F) << 12);
        v.to_le_bytes()
    }
}

/// Why bytes are not an EtherCAT frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameError {
    /// Shorter than the headers.
    TooShort {
        /// Bytes given.
        len: usize,
        /// Bytes needed.
        need: usize,
    },
    /// Another protocol's frame.
    NotEthercat {
        /// Its EtherType.
        ethertype: u16,
    },
    /// An EtherCAT header type other than datagrams.
    UnsupportedType {
        /// The type.
        kind: u8,
    },
    /// The EtherCAT header claims more bytes than the frame holds.
    Length {
        /// The header's length.
        declared: u16,
        /// Bytes after the header.
        available: usize,
    },
    /// A datagram does not fit (offsets from the start of the frame).
    Datagram(DatagramError),
    /// The buffer cannot hold what is being encoded.
    Full {
        /// Bytes needed.
        need: usize,
        /// Bytes available.
        capacity: usize,
    },
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::TooShort { len, need } => {
                write!(f, "frame of {len} bytes, its headers need {need}")
            }
            FrameError::NotEthercat { ethertype } => {
                write!(f, "EtherType {ethertype:#06x}, not EtherCAT (0x88a4)")
            }
            FrameError::UnsupportedType { kind } => {
                write!(
                    f,
                    "EtherCAT header type {kind}, only datagrams (1) are handled"
                )
            }
            FrameError::Length {
                declared,
                available,
            } => write!(
                f,
                "EtherCAT header declares {declared} bytes of datagrams, the frame holds {available}"
            ),
            FrameError::Datagram(DatagramError::Truncated { offset, need, have }) => write!(
                f,
                "datagram at frame byte {} needs {need} bytes, {have} remain",
                offset + DATAGRAMS_OFFSET
            ),
            FrameError::Full { need, capacity } => {
                write!(f, "frame needs {need} bytes, the buffer holds {capacity}")
            }
        }
    }
}

/// A decoded frame borrowing its bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame<'a> {
    /// The Ethernet header.
    pub ethernet: EthernetHeader,
    /// The EtherCAT header.
    pub header: EcatHeader,
    /// The datagram bytes (cut to the header's length, without padding).
    pub payload: &'a [u8],
    /// Bytes inside the header's length after the last datagram (an early ethercrab counted
    /// its padding into the length; devices and Wireshark ignore such bytes, and so do we).
    pub trailing: usize,
}

impl<'a> Frame<'a> {
    /// Decodes the headers and checks that the datagram chain fits the header's length (bytes
    /// after the chain are ignored; captured frames may be unpadded).
    pub fn decode(bytes: &'a [u8]) -> Result<Self, FrameError> {
        let ethernet = EthernetHeader::decode(bytes)?;
        if ethernet.ethertype != ETHERTYPE {
            return Err(FrameError::NotEthercat {
                ethertype: ethernet.ethertype,
            });
        }
        let Some(h) = bytes.get(ETHERNET_HEADER_LEN..DATAGRAMS_OFFSET) else {
            return Err(FrameError::TooShort {
                len: bytes.len(),
                need: DATAGRAMS_OFFSET,
            });
        };
        let header = EcatHeader::decode([h[0], h[1]]);
        if header.kind != TYPE_DATAGRAMS {
            return Err(FrameError::UnsupportedType { kind: header.kind });
        }
        let available = bytes.len() - DATAGRAMS_OFFSET;
        let len = usize::from(header.length);
        if len > available {
            return Err(FrameError::Length {
                declared: header.length,
                available,
            });
        }
        let payload = &bytes[DATAGRAMS_OFFSET..DATAGRAMS_OFFSET + len];
        let mut walk = Datagrams::new(payload);
        for d in walk.by_ref() {
            d.map_err(FrameError::Datagram)?;
        }
        let trailing = walk.remainder().len();
        Ok(Self {
            ethernet,
            header,
            payload: &payload[..len - trailing],
            trailing,
        })
    }

    /// The datagrams (the chain was checked by [`decode`](Self::decode), so none is an error).
    pub fn datagrams(&self) -> Datagrams<'a> {
        Datagrams::new(self.payload)
    }
}

/// Writes a frame datagram by datagram into a caller's buffer, then fixes the EtherCAT header
/// and pads (allocation-free).
#[derive(Debug)]
pub struct FrameBuilder<'a> {
    buf: &'a mut [u8],
    len: usize,
    last: Option<usize>,
}

impl<'a> FrameBuilder<'a> {
    /// Starts a frame from `source` to broadcast in `buf` (at most [`MAX_FRAME_LEN`] bytes of
    /// it are used).
    pub fn new(buf: &'a mut [u8], source: MacAddr) -> Result<Self, FrameError> {
        let capacity = buf.len().min(MAX_FRAME_LEN);
        if capacity < MIN_FRAME_LEN {
            return Err(FrameError::Full {
                need: MIN_FRAME_LEN,
                capacity,
            });
        }
        let eth = EthernetHeader {
            destination: MacAddr::BROADCAST,
            source,
            ethertype: ETHERTYPE,
        };
        buf[..ETHERNET_HEADER_LEN].copy_from_slice(&eth.encode());
        Ok(Self {
            buf,
            len: DATAGRAMS_OFFSET,
            last: None,
        })
    }

    /// Bytes left for further datagrams' data (after their headers and counters).
    pub fn room(&self) -> usize {
        self.buf
            .len()
            .min(MAX_FRAME_LEN)
            .saturating_sub(self.len + OVERHEAD)
    }

    /// Whether no datagram was added.
    pub fn is_empty(&self) -> bool {
        self.last.is_none()
    }

    /// Appends a datagram with `data` (its header's `len` and `more_follows` are set here;
    /// the working counter is 0). Returns where its data starts in the frame.
    pub fn push(&mut self, header: DatagramHeader, data: &[u8]) -> Result<usize, FrameError> {
        let at = self.reserve(header, data.len())?;
        self.buf[at..at + data.len()].copy_from_slice(data);
        Ok(at)
    }

    /// Appends a datagram with `len` zero bytes of data (for reads). Returns where its data
    /// starts in the frame.
    pub fn push_zeroed(&mut self, header: DatagramHeader, len: usize) -> Result<usize, FrameError> {
        let at = self.reserve(header, len)?;
        self.buf[at..at + len].fill(0);
        Ok(at)
    }

    /// The data of the datagram whose data starts at `at` (as returned by `push`), to fill in
    /// place.
    pub fn data_mut(&mut self, at: usize, len: usize) -> &mut [u8] {
        &mut self.buf[at..at + len]
    }

    fn reserve(&mut self, mut header: DatagramHeader, len: usize) -> Result<usize, FrameError> {
        let capacity = self.buf.len().min(MAX_FRAME_LEN);
        let need = self.len + OVERHEAD + len;
        if len > usize::from(datagram::MAX_LEN_FIELD) || need > capacity {
            return Err(FrameError::Full { need, capacity });
        }
        if let Some(last) = self.last {
            // Set "more follows" in the previous header (bit 15 of bytes 6-7).
            self.buf[last + 7] |= 0x80;
        }
        header.len = len as u16;
        header.more_follows = false;
        let start = self.len;
        let mut h = [0u8; HEADER_LEN];
        header.encode(&mut h);
        self.buf[start..start + HEADER_LEN].copy_from_slice(&h);
        let at = start + HEADER_LEN;
        self.buf[at + len..at + len + 2].fill(0);
        self.last = Some(start);
        self.len = need;
        Ok(at)
    }

    /// Ends the frame: writes the EtherCAT header, pads to [`MIN_FRAME_LEN`] and returns the
    /// frame's length.
    pub fn finish(self) -> usize {
        let datagrams = (self.len - DATAGRAMS_OFFSET) as u16;
        self.buf[ETHERNET_HEADER_LEN..DATAGRAMS_OFFSET]
            .copy_from_slice(&EcatHeader::datagrams(datagrams).encode());
        let total = self.len.max(MIN_FRAME_LEN);
        self.buf[self.len..total].fill(0);
        total
    }
}

#[cfg(test)]
mod tests {
    use super::super::command::Command;
    use super::super::datagram::physical;
    use super::*;

    /// The BRD example of `shared/reference/ethercat.md`, byte for byte.
    const REFERENCE_BRD: [u8; 30] = [
        0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x88, 0xa4, 0x0e,
        0x10, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
    ];

    #[test]
    fn the_reference_brd_frame_encodes_and_decodes() {
        let mut buf = [0u8; 64];
        let mut b = FrameBuilder::new(&mut buf, MacAddr::MASTER).unwrap();
        b.push_zeroed(DatagramHeader::new(Command::Brd, physical(0, 0), 2), 2)
            .unwrap();
        let n = b.finish();
        assert_eq!(n, MIN_FRAME_LEN);
        assert_eq!(&buf[..30], &REFERENCE_BRD[..]);
        assert!(buf[30..60].iter().all(|&b| b == 0));
        // Unpadded, as a capture of the sending side holds it.
        let f = Frame::decode(&REFERENCE_BRD).unwrap();
        assert_eq!(f.header.length, 14);
        let d: Vec<_> = f.datagrams().map(Result::unwrap).collect();
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].header.command(), Some(Command::Brd));
        assert_eq!(d[0].data, &[0, 0]);
    }

    #[test]
    fn malformed_frames_are_typed_errors() {
        assert_eq!(
            Frame::decode(&REFERENCE_BRD[..10]),
            Err(FrameError::TooShort { len: 10, need: 14 })
        );
        let mut ip = REFERENCE_BRD;
        ip[12..14].copy_from_slice(&[0x08, 0x00]);
        assert_eq!(
            Frame::decode(&ip),
            Err(FrameError::NotEthercat { ethertype: 0x0800 })
        );
        let mut long = REFERENCE_BRD;
        long[14] = 0x20;
        assert_eq!(
            Frame::decode(&long),
            Err(FrameError::Length {
                declared: 0x20,
                available: 14
            })
        );
        let mut more = REFERENCE_BRD;
        more[23] |= 0x80;
        assert!(matches!(
            Frame::decode(&more),
            Err(FrameError::Datagram(DatagramError::Truncated {
                offset: 14,
                ..
            }))
        ));
        let mut mailbox = REFERENCE_BRD;
        mailbox[15] = 0x50;
        assert_eq!(
            Frame::decode(&mailbox),
            Err(FrameError::UnsupportedType { kind: 5 })
        );
    }

    #[test]
    fn several_datagrams_chain_and_a_full_frame_is_refused() {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let mut b = FrameBuilder::new(&mut buf, MacAddr::MASTER).unwrap();
        b.push(DatagramHeader::new(Command::Lrw, 0x1000, 4), &[1, 2, 3, 4])
            .unwrap();
        b.push_zeroed(
            DatagramHeader::new(Command::Frmw, physical(0x1001, 0x910), 8),
            8,
        )
        .unwrap();
        assert_eq!(
            b.room(),
            MAX_FRAME_LEN - DATAGRAMS_OFFSET - 16 - 20 - OVERHEAD
        );
        assert!(matches!(
            b.push_zeroed(DatagramHeader::new(Command::Lrd, 0, 0), 2000),
            Err(FrameError::Full { .. })
        ));
        let n = b.finish();
        let f = Frame::decode(&buf[..n]).unwrap();
        let d: Vec<_> = f.datagrams().map(Result::unwrap).collect();
        assert_eq!(d.len(), 2);
        assert!(d[0].header.more_follows && !d[1].header.more_follows);
        assert_eq!(d[1].header.adp(), 0x1001);
        assert_eq!(MAX_DATAGRAM_DATA, 1486);
        assert!(MacAddr::MASTER.forwarded().is_forwarded());
        assert_eq!(MacAddr::MASTER.forwarded().to_string(), "12:10:10:10:10:10");
    }
}
