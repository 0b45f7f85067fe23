//! The candump log format of can-utils (`candump -l`, read by `canplayer` and `log2asc`): one
//! frame a line, `(1764600000.123456) can0 201#0F00001000`.
//!
//! Frame text (can-utils `lib.c`): a standard identifier is 3 hex digits, an extended one 8 (an
//! 8-digit identifier with `0x2000_0000` set is an error frame); `#` then the data as hex
//! pairs, `.` allowed between bytes; `ID#R` or `ID#R<dlc>` is a remote frame; `ID##<flags
//! nibble><data>` is CAN FD (a length that is no CAN FD length is padded with zeros to the
//! next, as can-utils does). Written in upper case, without separators.

use core::fmt;

use embedded_can::{ExtendedId, Id};

use super::fd::{self, FdFlags};
use super::frame::{CLASSIC_MAX_LEN, EFF_FLAG, ERR_FLAG, Frame, RTR_FLAG};

/// A log line's time: seconds and microseconds since the epoch (or since any start).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Timestamp {
    /// Whole seconds.
    pub secs: u64,
    /// Microseconds (0..1_000_000).
    pub micros: u32,
}

impl Timestamp {
    /// The time as a duration since the epoch.
    pub const fn as_duration(self) -> core::time::Duration {
        core::time::Duration::new(self.secs, self.micros * 1000)
    }

    /// A duration since the epoch, cut to microseconds.
    pub const fn from_duration(d: core::time::Duration) -> Self {
        Self {
            secs: d.as_secs(),
            micros: d.subsec_micros(),
        }
    }
}

/// One parsed log line; the interface name borrows from the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogLine<'a> {
    /// When the frame was received.
    pub timestamp: Timestamp,
    /// The interface (`can0`, `vcan0`, …).
    pub interface: &'a str,
    /// The frame.
    pub frame: Frame,
}

/// What is wrong with a line, and where (the byte offset in the line).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CandumpError {
    /// Byte offset in the line where the problem was found.
    pub column: usize,
    /// What was expected there.
    pub kind: CandumpErrorKind,
}

/// The kinds of [`CandumpError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CandumpErrorKind {
    /// `(` then seconds, `.`, six digits of microseconds and `)`.
    Timestamp,
    /// An interface name after the timestamp.
    Interface,
    /// An identifier of 3 or 8 hex digits followed by `#`.
    Identifier,
    /// Hex pairs of data (at most 8 bytes, 64 for CAN FD).
    Data,
    /// A remote frame's DLC (one digit 0..=8).
    RemoteLength,
    /// The CAN FD flags nibble after `##`.
    FdFlags,
    /// Unexpected text after the frame.
    Trailing,
}

impl fmt::Display for CandumpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.kind {
            CandumpErrorKind::Timestamp => "expected a timestamp `(SECONDS.MICROSECONDS)`",
            CandumpErrorKind::Interface => "expected an interface name",
            CandumpErrorKind::Identifier => "expected an identifier of 3 or 8 hex digits and `#`",
            CandumpErrorKind::Data => "expected data as hex pairs (at most 8 bytes, 64 for CAN FD)",
            CandumpErrorKind::RemoteLength => "expected a remote frame's length digit 0-8",
            CandumpErrorKind::FdFlags => "expected a CAN FD flags hex digit after `##`",
            CandumpErrorKind::Trailing => "unexpected text after the frame",
        };
        write!(f, "column {}: {what}", self.column + 1)
    }
}

fn err(column: usize, kind: CandumpErrorKind) -> CandumpError {
    CandumpError { column, kind }
}

fn hex(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

/// Parses one log line (a trailing newline, and a trailing direction mark `R` or `T` as newer
/// candump versions write, are accepted).
pub fn parse_line(line: &str) -> Result<LogLine<'_>, CandumpError> {
    let b = line.as_bytes();
    let line_end = line.trim_end_matches(['\n', '\r']).len();
    // Timestamp.
    if b.first() != Some(&b'(') {
        return Err(err(0, CandumpErrorKind::Timestamp));
    }
    let close = line[..line_end]
        .find(')')
        .ok_or(err(0, CandumpErrorKind::Timestamp))?;
    let timestamp = parse_timestamp(&line[1..close]).ok_or(err(1, CandumpErrorKind::Timestamp))?;
    // Interface.
    let rest = &line[close + 1..line_end];
    let iface_start = close + 1 + (rest.len() - rest.trim_start_matches(' ').len());
    if iface_start == close + 1 {
        return Err(err(iface_start, CandumpErrorKind::Interface));
    }
    let after = &line[iface_start..line_end];
    let iface_len = after
        .find(' ')
        .ok_or(err(iface_start, CandumpErrorKind::Interface))?;
    if iface_len == 0 {
        return Err(err(iface_start, CandumpErrorKind::Interface));
    }
    let interface = &after[..iface_len];
    // Frame, then an optional direction mark.
    let frame_start = iface_start + iface_len + 1;
    let text = &line[frame_start..line_end];
    let (frame_text, trailing) = match text.split_once(' ') {
        Some((f, t)) => (f, Some(t)),
        None => (text, None),
    };
    let frame = parse_frame(frame_text).map_err(|e| err(e.column + frame_start, e.kind))?;
    if let Some(t) = trailing {
        if !matches!(t.trim(), "R" | "T" | "") {
            return Err(err(
                frame_start + frame_text.len() + 1,
                CandumpErrorKind::Trailing,
            ));
        }
    }
    Ok(LogLine {
        timestamp,
        interface,
        frame,
    })
}

fn parse_timestamp(s: &str) -> Option<Timestamp> {
    let (secs, micros) = s.split_once('.')?;
    if secs.is_empty() || !secs.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    if micros.len() != 6 || !micros.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    Some(Timestamp {
        secs: secs.parse().ok()?,
        micros: micros.parse().ok()?,
    })
}

/// Parses the frame text `ID#DATA` (columns in errors count from its start).
pub fn parse_frame(text: &str) -> Result<Frame, CandumpError> {
    let b = text.as_bytes();
    let hash = text.find('#').ok_or(err(0, CandumpErrorKind::Identifier))?;
    let mut can_id = 0u32;
    for (i, &c) in b[..hash].iter().enumerate() {
        can_id = (can_id << 4) | u32::from(hex(c).ok_or(err(i, CandumpErrorKind::Identifier))?);
    }
    match hash {
        3 if can_id <= 0x7FF => {}
        8 if can_id & ERR_FLAG != 0 => can_id &= ERR_FLAG | 0x1FFF_FFFF,
        8 if can_id <= 0x1FFF_FFFF => can_id |= EFF_FLAG,
        _ => return Err(err(0, CandumpErrorKind::Identifier)),
    }
    let mut pos = hash + 1;
    let mut fd = None;
    match b.get(pos) {
        Some(b'#') => {
            let flags = b
                .get(pos + 1)
                .and_then(|&c| hex(c))
                .ok_or(err(pos + 1, CandumpErrorKind::FdFlags))?;
            fd = Some(FdFlags(flags).masked());
            pos += 2;
        }
        Some(b'R') if can_id & ERR_FLAG == 0 => {
            let dlc = match b.get(pos + 1) {
                None => 0,
                Some(&c @ b'0'..=b'8') if b.len() == pos + 2 => usize::from(c - b'0'),
                Some(_) => return Err(err(pos + 1, CandumpErrorKind::RemoteLength)),
            };
            return Frame::remote_from_raw(can_id | RTR_FLAG, dlc)
                .map_err(|_| err(0, CandumpErrorKind::Identifier));
        }
        _ => {}
    }
    let max = if fd.is_some() {
        fd::FD_MAX_LEN
    } else {
        CLASSIC_MAX_LEN
    };
    let mut data = [0u8; fd::FD_MAX_LEN];
    let mut len = 0;
    while pos < b.len() {
        if b[pos] == b'.' {
            pos += 1;
            continue;
        }
        let hi = hex(b[pos]).ok_or(err(pos, CandumpErrorKind::Data))?;
        let lo = b
            .get(pos + 1)
            .and_then(|&c| hex(c))
            .ok_or(err(pos + 1, CandumpErrorKind::Data))?;
        if len == max {
            return Err(err(pos, CandumpErrorKind::Data));
        }
        data[len] = (hi << 4) | lo;
        len += 1;
        pos += 2;
    }
    if fd.is_some() {
        len = fd::dlc_to_len(fd::len_to_dlc(len));
    }
    Frame::from_raw(can_id, &data[..len], fd).map_err(|_| err(0, CandumpErrorKind::Identifier))
}

/// Writes the frame text (`123#0F00`, `1ABCDEF0#R2`, `123##1AABB`).
pub fn write_frame(w: &mut dyn fmt::Write, frame: &Frame) -> fmt::Result {
    let raw = frame.raw_id();
    if raw & ERR_FLAG != 0 {
        write!(w, "{:08X}#", raw & (ERR_FLAG | 0x1FFF_FFFF))?;
    } else if raw & EFF_FLAG != 0 {
        write!(w, "{:08X}#", frame.id_bits())?;
    } else {
        write!(w, "{:03X}#", frame.id_bits())?;
    }
    if raw & RTR_FLAG != 0 && raw & ERR_FLAG == 0 {
        w.write_char('R')?;
        let dlc = frame.len();
        if dlc != 0 {
            write!(w, "{dlc}")?;
        }
        return Ok(());
    }
    if let Some(flags) = frame.fd_flags() {
        write!(w, "#{:X}", flags.masked().0)?;
    }
    for byte in frame.bytes() {
        write!(w, "{byte:02X}")?;
    }
    Ok(())
}

/// Writes one log line with its newline: `(0000000012.000345) can0 201#0F00`.
pub fn write_line(
    w: &mut dyn fmt::Write,
    timestamp: Timestamp,
    interface: &str,
    frame: &Frame,
) -> fmt::Result {
    write!(
        w,
        "({:010}.{:06}) {interface} ",
        timestamp.secs, timestamp.micros
    )?;
    write_frame(w, frame)?;
    w.write_char('\n')
}

/// An extended identifier (for tests and tools).
pub fn extended(id: u32) -> Option<Id> {
    ExtendedId::new(id).map(Id::Extended)
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::Frame as _;

    #[test]
    fn the_reference_line_parses_and_writes_back() {
        let line = "(1764600000.123456) can0 201#0F00001000\n";
        let l = parse_line(line).unwrap();
        assert_eq!(
            l.timestamp,
            Timestamp {
                secs: 1_764_600_000,
                micros: 123_456
            }
        );
        assert_eq!(l.interface, "can0");
        assert_eq!(l.frame.standard_id(), Some(0x201));
        assert_eq!(l.frame.bytes(), &[0x0F, 0, 0, 0x10, 0]);
        let mut out = String::new();
        write_line(&mut out, l.timestamp, l.interface, &l.frame).unwrap();
        assert_eq!(out, line);
    }

    #[test]
    fn remote_extended_fd_and_error_frames() {
        let r = parse_frame("701#R").unwrap();
        assert!(r.is_remote_frame() && r.dlc() == 0);
        let r = parse_frame("12345678#R2").unwrap();
        assert!(r.is_remote_frame() && r.is_extended() && r.dlc() == 2);
        assert_eq!(r.to_string(), "12345678#R2");
        let f = parse_frame("123##1AA.BB.CC").unwrap();
        assert_eq!(f.fd_flags(), Some(FdFlags(1)));
        assert_eq!(f.bytes(), &[0xAA, 0xBB, 0xCC]);
        // Nine bytes are padded to the next CAN FD length, as can-utils does.
        let f = parse_frame("123##0000102030405060708").unwrap();
        assert_eq!(f.len(), 12);
        let e = parse_frame("20000004#0004000000000000").unwrap();
        assert!(e.is_error_frame());
        assert_eq!(e.to_string(), "20000004#0004000000000000");
        assert_eq!(parse_frame("00000123#11").unwrap().raw_id(), 0x8000_0123);
    }

    #[test]
    fn errors_say_where() {
        let cases = [
            ("1764600000.1 can0 1#", 0, CandumpErrorKind::Timestamp),
            ("(1.12345) can0 123#", 1, CandumpErrorKind::Timestamp),
            ("(1.123456) can0 1234#00", 16, CandumpErrorKind::Identifier),
            ("(1.123456) can0 123#0", 21, CandumpErrorKind::Data),
            (
                "(1.123456) can0 123#000000000000000000",
                36,
                CandumpErrorKind::Data,
            ),
            ("(1.123456) can0 123#R9", 21, CandumpErrorKind::RemoteLength),
            ("(1.123456) can0 123##G", 21, CandumpErrorKind::FdFlags),
            ("(1.123456) can0 123#00 X", 23, CandumpErrorKind::Trailing),
            ("(1.123456) can0", 11, CandumpErrorKind::Interface),
            ("(1.123456) can0 800#", 16, CandumpErrorKind::Identifier),
        ];
        for (line, column, kind) in cases {
            assert_eq!(
                parse_line(line),
                Err(CandumpError { column, kind }),
                "{line}"
            );
        }
        assert!(parse_line("(1.123456) can0 123#00 R").is_ok());
    }
}
