//! cannelloni: CAN frames over UDP (version 2 datagrams) and TCP (version 1 stream), the
//! protocol of the cannelloni tunnel and of CAN-to-Ethernet gateways.
//!
//! One frame, all big-endian: `can_id u32` (with the Linux EFF/RTR/ERR flags) `| len u8 |
//! [flags u8 if len & 0x80] | data`. `len & 0x80` marks CAN FD (length `len & 0x7F`, flags
//! BRS 0x01, ESI 0x02); a remote frame's `len` is its DLC and no data bytes follow.
//!
//! UDP datagram, version 2: a 5-byte header `version u8 = 2 | op_code u8 (0 DATA, 1 ACK,
//! 2 NACK) | seq_no u8 | count u16`, then `count` frames. A receiver rejects a version other
//! than 2 and an op code other than DATA, and ignores `count = 0`.
//!
//! TCP, version 1: each side first sends the 12-byte banner `CANNELLONIv1` (no NUL), then
//! frames back to back with no header and no delimiter ([`StreamDecoder`]).
//!
//! Worked example (`shared/reference/canopen.md`): SYNC and RPDO1 of node 1 in one datagram,
//! `02 00 07 00 02 | 00 00 00 80 00 | 00 00 02 01 06 0F 00 00 10 00 00` (tested below).

use core::fmt;

use super::fd::{self, FdFlags};
use super::frame::{CLASSIC_MAX_LEN, ERR_FLAG, Frame, RTR_FLAG};

/// The UDP protocol version.
pub const UDP_VERSION: u8 = 2;
/// Bytes of the UDP datagram header.
pub const HEADER_LEN: usize = 5;
/// The TCP banner each side sends first.
pub const TCP_BANNER: &[u8; 12] = b"CANNELLONIv1";
/// `len` bit marking a CAN FD frame.
pub const FD_LEN_FLAG: u8 = 0x80;
/// Most bytes one encoded frame takes (CAN FD, 64 data bytes).
pub const MAX_FRAME_LEN: usize = 4 + 1 + 1 + fd::FD_MAX_LEN;

/// The op code of a datagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpCode {
    /// Frames follow.
    Data,
    /// Acknowledge (SCTP/unused by the UDP tunnel; rejected by receivers).
    Ack,
    /// Negative acknowledge.
    Nack,
}

impl OpCode {
    /// The op code of a byte.
    pub const fn from_byte(b: u8) -> Option<Self> {
        match b {
            0 => Some(OpCode::Data),
            1 => Some(OpCode::Ack),
            2 => Some(OpCode::Nack),
            _ => None,
        }
    }

    /// The byte of the op code.
    pub const fn to_byte(self) -> u8 {
        match self {
            OpCode::Data => 0,
            OpCode::Ack => 1,
            OpCode::Nack => 2,
        }
    }
}

/// Why bytes are not cannelloni.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DecodeError {
    /// The datagram is shorter than its header.
    ShortHeader {
        /// Bytes received.
        got: usize,
    },
    /// The version byte is not 2.
    Version {
        /// The version found.
        version: u8,
    },
    /// The op code is not DATA.
    OpCode {
        /// The op code byte found.
        op: u8,
    },
    /// A frame runs past the end of the datagram.
    Truncated {
        /// Byte offset of the frame in the datagram.
        offset: usize,
        /// Index of the frame (0-based).
        index: usize,
    },
    /// A frame's identifier or length is invalid.
    Frame {
        /// Byte offset of the frame in the datagram or stream.
        offset: usize,
        /// What is wrong.
        error: super::DecodeError,
    },
    /// Bytes follow the `count` frames the header announced.
    Trailing {
        /// Byte offset of the first extra byte.
        offset: usize,
    },
    /// The TCP peer's banner is not `CANNELLONIv1`.
    Banner,
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::ShortHeader { got } => {
                write!(f, "{got} bytes, shorter than the 5-byte header")
            }
            DecodeError::Version { version } => write!(f, "version {version}, expected 2"),
            DecodeError::OpCode { op } => write!(f, "op code {op}, expected 0 (DATA)"),
            DecodeError::Truncated { offset, index } => {
                write!(f, "frame {index} at byte {offset} runs past the end")
            }
            DecodeError::Frame { offset, error } => write!(f, "frame at byte {offset}: {error}"),
            DecodeError::Trailing { offset } => {
                write!(f, "bytes after the announced frames from byte {offset}")
            }
            DecodeError::Banner => f.write_str("the peer's banner is not CANNELLONIv1"),
        }
    }
}

/// The bytes `frame` takes encoded.
pub fn encoded_len(frame: &Frame) -> usize {
    5 + usize::from(frame.is_fd()) + frame.bytes().len()
}

/// Encodes one frame into `out`; returns the bytes written, `None` if `out` is too small.
pub fn encode_frame(frame: &Frame, out: &mut [u8]) -> Option<usize> {
    let n = encoded_len(frame);
    let out = out.get_mut(..n)?;
    out[..4].copy_from_slice(&frame.raw_id().to_be_bytes());
    let data = frame.bytes();
    let mut at = 5;
    match frame.fd_flags() {
        Some(flags) => {
            out[4] = data.len() as u8 | FD_LEN_FLAG;
            out[5] = flags.masked().0;
            at = 6;
        }
        None => out[4] = frame.len() as u8,
    }
    out[at..].copy_from_slice(data);
    Some(n)
}

/// What [`decode_frame`] found at the start of its input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decoded {
    /// A frame and the bytes it took.
    Frame(Frame, usize),
    /// The input ends inside the frame: at least this many bytes are needed.
    Incomplete(usize),
}

/// Decodes the frame at the start of `bytes` (errors name offset 0; callers add theirs).
pub fn decode_frame(bytes: &[u8]) -> Result<Decoded, super::DecodeError> {
    if bytes.len() < 5 {
        return Ok(Decoded::Incomplete(5));
    }
    let can_id = u32::from_be_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
    let len_byte = bytes[4];
    if len_byte & FD_LEN_FLAG != 0 {
        let len = usize::from(len_byte & !FD_LEN_FLAG);
        if !fd::is_fd_len(len) {
            return Err(super::DecodeError::DataLength { len, fd: true });
        }
        let need = 6 + len;
        if bytes.len() < need {
            return Ok(Decoded::Incomplete(need));
        }
        let frame = Frame::from_raw(can_id, &bytes[6..need], Some(FdFlags(bytes[5]).masked()))?;
        return Ok(Decoded::Frame(frame, need));
    }
    let len = usize::from(len_byte);
    if can_id & RTR_FLAG != 0 && can_id & ERR_FLAG == 0 {
        let frame = Frame::remote_from_raw(can_id & !RTR_FLAG, len)?;
        return Ok(Decoded::Frame(frame, 5));
    }
    if len > CLASSIC_MAX_LEN {
        return Err(super::DecodeError::DataLength { len, fd: false });
    }
    let need = 5 + len;
    if bytes.len() < need {
        return Ok(Decoded::Incomplete(need));
    }
    Ok(Decoded::Frame(
        Frame::from_raw(can_id, &bytes[5..need], None)?,
        need,
    ))
}

/// The header of a UDP datagram.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// Op code.
    pub op: OpCode,
    /// Sequence number (wraps at 256).
    pub seq: u8,
    /// Frames that follow.
    pub count: u16,
}

/// Builds one UDP datagram in a caller's buffer: a header, then frames appended one by one.
#[derive(Debug)]
pub struct DatagramWriter<'a> {
    buf: &'a mut [u8],
    len: usize,
    count: u16,
}

impl<'a> DatagramWriter<'a> {
    /// An empty DATA datagram with sequence number `seq`; `None` if `buf` cannot hold the
    /// header.
    pub fn new(buf: &'a mut [u8], seq: u8) -> Option<Self> {
        let header = buf.get_mut(..HEADER_LEN)?;
        header.copy_from_slice(&[UDP_VERSION, OpCode::Data.to_byte(), seq, 0, 0]);
        Some(Self {
            buf,
            len: HEADER_LEN,
            count: 0,
        })
    }

    /// Appends a frame; hands it back if it does not fit.
    pub fn push(&mut self, frame: &Frame) -> Result<(), Frame> {
        if self.count == u16::MAX {
            return Err(*frame);
        }
        match encode_frame(frame, &mut self.buf[self.len..]) {
            Some(n) => {
                self.len += n;
                self.count += 1;
                self.buf[3..5].copy_from_slice(&self.count.to_be_bytes());
                Ok(())
            }
            None => Err(*frame),
        }
    }

    /// Frames so far.
    pub fn count(&self) -> u16 {
        self.count
    }

    /// The datagram so far.
    pub fn as_bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }
}

/// Reads the header of a datagram and checks it (version 2, DATA).
pub fn read_header(datagram: &[u8]) -> Result<Header, DecodeError> {
    let Some(h) = datagram.get(..HEADER_LEN) else {
        return Err(DecodeError::ShortHeader {
            got: datagram.len(),
        });
    };
    if h[0] != UDP_VERSION {
        return Err(DecodeError::Version { version: h[0] });
    }
    let op = OpCode::from_byte(h[1]).ok_or(DecodeError::OpCode { op: h[1] })?;
    if op != OpCode::Data {
        return Err(DecodeError::OpCode { op: h[1] });
    }
    Ok(Header {
        op,
        seq: h[2],
        count: u16::from_be_bytes([h[3], h[4]]),
    })
}

/// The frames of one datagram, decoded lazily: an iterator of `Result<Frame, DecodeError>`
/// that stops after the first error.
#[derive(Clone, Debug)]
pub struct DatagramFrames<'a> {
    bytes: &'a [u8],
    offset: usize,
    index: usize,
    count: usize,
    failed: bool,
}

/// Checks a datagram's header and returns it with an iterator over its frames.
pub fn read_datagram(datagram: &[u8]) -> Result<(Header, DatagramFrames<'_>), DecodeError> {
    let header = read_header(datagram)?;
    Ok((
        header,
        DatagramFrames {
            bytes: datagram,
            offset: HEADER_LEN,
            index: 0,
            count: usize::from(header.count),
            failed: false,
        },
    ))
}

impl Iterator for DatagramFrames<'_> {
    type Item = Result<Frame, DecodeError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed {
            return None;
        }
        if self.index == self.count {
            if self.offset != self.bytes.len() {
                self.failed = true;
                return Some(Err(DecodeError::Trailing {
                    offset: self.offset,
                }));
            }
            return None;
        }
        let offset = self.offset;
        let r = match decode_frame(&self.bytes[offset..]) {
            Ok(Decoded::Frame(frame, n)) => {
                self.offset += n;
                self.index += 1;
                Ok(frame)
            }
            Ok(Decoded::Incomplete(_)) => Err(DecodeError::Truncated {
                offset,
                index: self.index,
            }),
            Err(error) => Err(DecodeError::Frame { offset, error }),
        };
        self.failed = r.is_err();
        Some(r)
    }
}

/// Reassembles frames from a TCP byte stream (after the banner): bytes go in as they arrive,
/// whole frames come out. Holds at most one partial frame; allocation-free.
#[derive(Clone, Debug)]
pub struct StreamDecoder {
    buf: [u8; MAX_FRAME_LEN],
    len: usize,
    consumed: u64,
}

impl Default for StreamDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl StreamDecoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            consumed: 0,
        }
    }

    /// Bytes of a partial frame held.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Feeds `input`; calls `on_frame` for each whole frame. An invalid frame is an `Err` with
    /// its offset in the stream: the stream cannot be trusted after it (there is no delimiter
    /// to resynchronise on), so the connection should be dropped.
    pub fn feed(
        &mut self,
        mut input: &[u8],
        mut on_frame: impl FnMut(Frame),
    ) -> Result<(), DecodeError> {
        while !input.is_empty() {
            // Top up the held bytes and try to decode a frame from them.
            let take = input.len().min(MAX_FRAME_LEN - self.len);
            self.buf[self.len..self.len + take].copy_from_slice(&input[..take]);
            let held = self.len + take;
            match decode_frame(&self.buf[..held]) {
                Ok(Decoded::Frame(frame, n)) => {
                    // `n > self.len`: the held bytes alone were incomplete.
                    input = &input[n - self.len..];
                    self.len = 0;
                    self.consumed += n as u64;
                    on_frame(frame);
                }
                Ok(Decoded::Incomplete(_)) => {
                    self.len = held;
                    input = &input[take..];
                }
                Err(error) => {
                    return Err(DecodeError::Frame {
                        offset: self.consumed as usize,
                        error,
                    });
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_datagram() {
        let sync = Frame::standard(0x080, &[]).unwrap();
        let rpdo = Frame::standard(0x201, &[0x0F, 0, 0, 0x10, 0, 0]).unwrap();
        let mut buf = [0u8; 64];
        let mut w = DatagramWriter::new(&mut buf, 7).unwrap();
        w.push(&sync).unwrap();
        w.push(&rpdo).unwrap();
        let expected = [
            0x02, 0x00, 0x07, 0x00, 0x02, 0x00, 0x00, 0x00, 0x80, 0x00, 0x00, 0x00, 0x02, 0x01,
            0x06, 0x0F, 0x00, 0x00, 0x10, 0x00, 0x00,
        ];
        assert_eq!(w.as_bytes(), &expected);
        let (h, frames) = read_datagram(&expected).unwrap();
        assert_eq!((h.seq, h.count), (7, 2));
        let got: Vec<_> = frames.collect::<Result<_, _>>().unwrap();
        assert_eq!(got, vec![sync, rpdo]);
    }

    #[test]
    fn bad_datagrams_are_refused_with_the_place() {
        assert_eq!(
            read_header(&[2, 0, 0]),
            Err(DecodeError::ShortHeader { got: 3 })
        );
        assert_eq!(
            read_header(&[1, 0, 0, 0, 0]),
            Err(DecodeError::Version { version: 1 })
        );
        assert_eq!(
            read_header(&[2, 1, 0, 0, 0]),
            Err(DecodeError::OpCode { op: 1 })
        );
        let d = [2, 0, 0, 0, 1, 0, 0, 0, 0x80, 3, 1];
        let (_, mut f) = read_datagram(&d).unwrap();
        assert_eq!(
            f.next(),
            Some(Err(DecodeError::Truncated {
                offset: 5,
                index: 0
            }))
        );
        assert_eq!(f.next(), None);
        let d = [2, 0, 0, 0, 0, 9];
        let (_, mut f) = read_datagram(&d).unwrap();
        assert_eq!(f.next(), Some(Err(DecodeError::Trailing { offset: 5 })));
    }

    #[test]
    fn remote_and_fd_frames_encode_as_cannelloni_does() {
        let r = Frame::remote_from_raw(0x701, 1).unwrap();
        let mut b = [0u8; 80];
        assert_eq!(encode_frame(&r, &mut b), Some(5));
        assert_eq!(&b[..5], &[0x40, 0, 7, 1, 1]);
        let id = embedded_can::Id::Standard(embedded_can::StandardId::new(0x123).unwrap());
        let f = Frame::fd(id, &[1; 12], FdFlags::new(true, true)).unwrap();
        assert_eq!(encode_frame(&f, &mut b), Some(18));
        assert_eq!(&b[..6], &[0, 0, 1, 0x23, 0x8C, 0x03]);
        assert_eq!(decode_frame(&b[..18]), Ok(Decoded::Frame(f, 18)));
        assert_eq!(decode_frame(&b[..10]), Ok(Decoded::Incomplete(18)));
    }

    #[test]
    fn the_stream_decoder_reassembles_frames_split_anywhere() {
        let frames: Vec<Frame> = (0..20u16)
            .map(|k| Frame::standard(0x180 + k, &[k as u8; 8][..usize::from(k % 9)]).unwrap())
            .collect();
        let mut stream = Vec::new();
        for f in &frames {
            let mut b = [0u8; MAX_FRAME_LEN];
            let n = encode_frame(f, &mut b).unwrap();
            stream.extend_from_slice(&b[..n]);
        }
        for chunk in [1, 2, 3, 7, 13, 100, 1000] {
            let mut d = StreamDecoder::new();
            let mut got = Vec::new();
            for piece in stream.chunks(chunk) {
                d.feed(piece, |f| got.push(f)).unwrap();
            }
            assert_eq!(got, frames, "chunk {chunk}");
            assert_eq!(d.pending(), 0);
        }
        let mut d = StreamDecoder::new();
        assert_eq!(
            d.feed(&[0, 0, 0x08, 0, 0], |_| {}),
            Err(DecodeError::Frame {
                offset: 0,
                error: crate::proto::can::DecodeError::Identifier { can_id: 0x800 }
            })
        );
    }
}
