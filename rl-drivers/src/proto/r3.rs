//! The MELFA R3 text protocol that sets up real-time control over TCP: requests
//! `<robot>;<slot>;<CMD><args>` without terminator, replies `QoK...` (success) or `QeR<n>`
//! (error `n`), the `DSTATE` status reply, and the 4-line MXT program RL uploads.
//!
//! Facts from RL's `MitsubishiR3` / `MitsubishiH7` (see `shared/reference/mitsubishi-h7.md`).

use core::fmt::{self, Write};
use core::net::IpAddr;

use super::h7::Mode;

/// Most bytes RL reads for one reply.
pub const MAX_REPLY_LEN: usize = 256;
/// Longest `EMDAT` payload RL sends at once.
pub const EMDAT_CHUNK_LEN: usize = 246;
/// The program number RL loads the MXT program as.
pub const PROGRAM_NAME: &str = "1432";
/// Separator between the lines of an uploaded program (vertical tab).
pub const LINE_SEPARATOR: char = '\u{b}';

/// `DSTATE` RunSts bits.
pub mod run_bits {
    /// Repeat.
    pub const REPEAT: u8 = 1 << 0;
    /// Cycle stop off.
    pub const CYCLE_STOP_OFF: u8 = 1 << 1;
    /// Machine lock.
    pub const MLOCK: u8 = 1 << 2;
    /// Teach mode.
    pub const TEACH: u8 = 1 << 3;
    /// Teach run.
    pub const TEACH_RUN: u8 = 1 << 4;
    /// Servo on.
    pub const SERVO_ON: u8 = 1 << 5;
    /// A program runs.
    pub const RUN: u8 = 1 << 6;
    /// Operation enabled.
    pub const OPERATION_ENABLED: u8 = 1 << 7;
}

/// `DSTATE` StopSts bits.
pub mod stop_bits {
    /// Emergency stop.
    pub const EMERGENCY_STOP: u8 = 1 << 0;
    /// Stop.
    pub const STOP: u8 = 1 << 1;
    /// Wait.
    pub const WAIT: u8 = 1 << 2;
    /// Stop signal off.
    pub const STOP_SIGNAL_OFF: u8 = 1 << 3;
    /// Program selection enabled.
    pub const PROGRAM_SELECT_ENABLED: u8 = 1 << 4;
    /// Pseudo input.
    pub const PSEUDO_INPUT: u8 = 1 << 6;
}

/// Why R3 text could not be built or parsed. Positions are byte offsets in the text.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum R3Error {
    /// The output buffer is too small.
    TooLong {
        /// Bytes needed (at least).
        needed: usize,
        /// Bytes available.
        capacity: usize,
    },
    /// The text is not valid UTF-8 (R3 is ASCII).
    NotText {
        /// Where the invalid byte is.
        at: usize,
    },
    /// A request is not `<robot>;<slot>;<command>`.
    BadRequest {
        /// Where parsing stopped.
        at: usize,
    },
    /// A reply starts with neither `QoK` nor `QeR`.
    BadReply,
    /// The controller answered `QeR<code>`.
    Controller {
        /// The error number.
        code: u32,
    },
    /// A `DSTATE` reply is malformed.
    BadState {
        /// Where parsing stopped (offset in the text after `QoK`).
        at: usize,
    },
    /// One program line is longer than an `EMDAT` chunk.
    LineTooLong {
        /// Its length.
        len: usize,
    },
}

impl fmt::Display for R3Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            R3Error::TooLong { needed, capacity } => {
                write!(f, "needs {needed} bytes, buffer holds {capacity}")
            }
            R3Error::NotText { at } => write!(f, "not ASCII text at byte {at}"),
            R3Error::BadRequest { at } => {
                write!(f, "not `<robot>;<slot>;<command>` (byte {at})")
            }
            R3Error::BadReply => f.write_str("reply starts with neither QoK nor QeR"),
            R3Error::Controller { code } => write!(f, "controller error QeR{code}"),
            R3Error::BadState { at } => write!(f, "malformed DSTATE reply at byte {at}"),
            R3Error::LineTooLong { len } => {
                write!(f, "program line of {len} bytes exceeds {EMDAT_CHUNK_LEN}")
            }
        }
    }
}

/// A `fmt::Write` into a byte slice that remembers overflow.
struct SliceWriter<'a> {
    out: &'a mut [u8],
    len: usize,
    needed: usize,
}

impl Write for SliceWriter<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        self.needed += s.len();
        if self.len + s.len() > self.out.len() {
            return Err(fmt::Error);
        }
        self.out[self.len..self.len + s.len()].copy_from_slice(s.as_bytes());
        self.len += s.len();
        Ok(())
    }
}

/// Formats into `out` and returns the number of bytes written.
pub fn format_into(out: &mut [u8], args: fmt::Arguments<'_>) -> Result<usize, R3Error> {
    let capacity = out.len();
    let mut w = SliceWriter {
        out,
        len: 0,
        needed: 0,
    };
    match w.write_fmt(args) {
        Ok(()) => Ok(w.len),
        Err(_) => Err(R3Error::TooLong {
            needed: w.needed,
            capacity,
        }),
    }
}

/// One request: `<robot>;<slot>;<body>`, where the body is a command name in capitals followed
/// by its arguments (`RUN1432;1`, `LOAD=1432`, `DSTATE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Request<'a> {
    /// Robot number (1 for the first robot).
    pub robot: u8,
    /// Task slot (1 for normal commands, 9 for program editing as RL uses it).
    pub slot: u8,
    /// Command name and arguments.
    pub body: &'a str,
}

impl<'a> Request<'a> {
    /// Writes the request into `out`, returning its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, R3Error> {
        format_into(
            out,
            format_args!("{};{};{}", self.robot, self.slot, self.body),
        )
    }

    /// The command name: the leading capital letters of the body.
    pub fn name(&self) -> &'a str {
        let end = self
            .body
            .bytes()
            .position(|b| !b.is_ascii_uppercase())
            .unwrap_or(self.body.len());
        &self.body[..end]
    }

    /// The arguments: the body after the name.
    pub fn args(&self) -> &'a str {
        &self.body[self.name().len()..]
    }

    /// Parses a request (the controller's side).
    pub fn parse(bytes: &'a [u8]) -> Result<Self, R3Error> {
        let text = core::str::from_utf8(bytes).map_err(|e| R3Error::NotText {
            at: e.valid_up_to(),
        })?;
        let (robot, rest, at) = number_field(text, 0)?;
        let (slot, body, _) = number_field(rest, at)?;
        Ok(Request { robot, slot, body })
    }
}

/// Parses `<u8>;` at the start of `text`, returning the number, the rest and its offset.
fn number_field(text: &str, base: usize) -> Result<(u8, &str, usize), R3Error> {
    let semi = text.find(';').ok_or(R3Error::BadRequest {
        at: base + text.len(),
    })?;
    let n = text[..semi]
        .parse()
        .map_err(|_| R3Error::BadRequest { at: base })?;
    Ok((n, &text[semi + 1..], base + semi + 1))
}

/// A reply, borrowed from the received bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Reply<'a> {
    /// `QoK<payload>`.
    Ok(&'a str),
    /// `QeR<code>`.
    Error(u32),
}

impl<'a> Reply<'a> {
    /// Parses a reply. Trailing NUL, CR and LF are ignored.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, R3Error> {
        let text = core::str::from_utf8(bytes).map_err(|e| R3Error::NotText {
            at: e.valid_up_to(),
        })?;
        let text = text.trim_end_matches(['\0', '\r', '\n']);
        if let Some(payload) = text.strip_prefix("QoK") {
            Ok(Reply::Ok(payload))
        } else if let Some(code) = text.strip_prefix("QeR") {
            let digits = code.bytes().take_while(u8::is_ascii_digit).count();
            Ok(Reply::Error(code[..digits].parse().unwrap_or(0)))
        } else {
            Err(R3Error::BadReply)
        }
    }

    /// The payload of a success, or the controller's error.
    pub fn into_result(self) -> Result<&'a str, R3Error> {
        match self {
            Reply::Ok(p) => Ok(p),
            Reply::Error(code) => Err(R3Error::Controller { code }),
        }
    }
}

/// The controller status from a `DSTATE` reply: `QoK` + RunSts (2 hex digits) + StopSts (2 hex
/// digits) + `errorNo;stepNo;mechNo`. (RL's `doDstate` reads StopSts from the RunSts digits
/// again, a bug; this parser reads digits 3 and 4.)
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct DState {
    /// RunSts bits ([`run_bits`]).
    pub run: u8,
    /// StopSts bits ([`stop_bits`]).
    pub stop: u8,
    /// Current error number (0: none).
    pub error_no: u32,
    /// Executing step number.
    pub step_no: u32,
    /// Mechanism number.
    pub mech_no: u32,
}

impl DState {
    /// Whether the servo is on.
    pub const fn servo_on(&self) -> bool {
        self.run & run_bits::SERVO_ON != 0
    }

    /// Whether a program is running.
    pub const fn running(&self) -> bool {
        self.run & run_bits::RUN != 0
    }

    /// Parses the payload after `QoK`.
    pub fn parse(payload: &str) -> Result<Self, R3Error> {
        let b = payload.as_bytes();
        let hex = |at: usize| -> Result<u8, R3Error> {
            b.get(at..at + 2)
                .and_then(|s| core::str::from_utf8(s).ok())
                .and_then(|s| u8::from_str_radix(s, 16).ok())
                .ok_or(R3Error::BadState { at })
        };
        let run = hex(0)?;
        let stop = hex(2)?;
        let mut fields = [0u32; 3];
        let mut at = 4;
        let rest = payload.get(4..).ok_or(R3Error::BadState { at })?;
        let mut parts = rest.trim_end().split(';');
        for f in fields.iter_mut() {
            let part = parts.next().ok_or(R3Error::BadState { at })?;
            *f = part.trim().parse().map_err(|_| R3Error::BadState { at })?;
            at += part.len() + 1;
        }
        if parts.next().is_some() {
            return Err(R3Error::BadState { at });
        }
        Ok(DState {
            run,
            stop,
            error_no: fields[0],
            step_no: fields[1],
            mech_no: fields[2],
        })
    }

    /// Writes the payload (without `QoK`), as a controller would.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, R3Error> {
        format_into(
            out,
            format_args!(
                "{:02X}{:02X}{};{};{}",
                self.run, self.stop, self.error_no, self.step_no, self.mech_no
            ),
        )
    }
}

/// Writes RL's MXT program, lines joined by [`LINE_SEPARATOR`]: open `ENET:<client>` as #1,
/// `MXT 1,<mode>,<filter>`, `HLT`, `END`. Returns its length.
pub fn write_program(
    out: &mut [u8],
    client: IpAddr,
    mode: Mode,
    filter: u32,
) -> Result<usize, R3Error> {
    format_into(
        out,
        format_args!(
            "10 OPEN \"ENET:{client}\" AS #1\u{b}20 MXT 1,{},{filter}\u{b}30 HLT\u{b}40 END",
            mode.code()
        ),
    )
}

/// Splits a program into `EMDAT` payloads of at most [`EMDAT_CHUNK_LEN`] bytes, cutting only at
/// line separators (RL's rule).
#[derive(Clone, Debug)]
pub struct EmdatChunks<'a> {
    rest: &'a str,
}

impl<'a> EmdatChunks<'a> {
    /// Chunks of `program`.
    pub fn new(program: &'a str) -> Self {
        Self { rest: program }
    }
}

impl<'a> Iterator for EmdatChunks<'a> {
    type Item = Result<&'a str, R3Error>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.rest.is_empty() {
            return None;
        }
        let mut end = 0;
        for (i, _) in self
            .rest
            .match_indices(LINE_SEPARATOR)
            .chain([(self.rest.len(), "")])
        {
            if i <= EMDAT_CHUNK_LEN {
                end = i;
            } else {
                break;
            }
        }
        if end == 0 {
            let len = self.rest.find(LINE_SEPARATOR).unwrap_or(self.rest.len());
            self.rest = "";
            return Some(Err(R3Error::LineTooLong { len }));
        }
        let chunk = &self.rest[..end];
        self.rest = self.rest.get(end + 1..).unwrap_or("");
        Some(Ok(chunk))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_are_robot_slot_body() {
        let mut buf = [0u8; 32];
        let n = Request {
            robot: 1,
            slot: 1,
            body: "RUN1432;1",
        }
        .encode(&mut buf)
        .unwrap();
        assert_eq!(&buf[..n], b"1;1;RUN1432;1");
        let r = Request::parse(&buf[..n]).unwrap();
        assert_eq!(
            (r.robot, r.slot, r.name(), r.args()),
            (1, 1, "RUN", "1432;1")
        );
        assert_eq!(Request::parse(b"1;9;LOAD=1432").unwrap().args(), "=1432");
        assert_eq!(
            Request::parse(b"x;1;STOP"),
            Err(R3Error::BadRequest { at: 0 })
        );
        assert_eq!(Request::parse(b"1;1"), Err(R3Error::BadRequest { at: 3 }));
        assert_eq!(
            Request {
                robot: 1,
                slot: 1,
                body: "STOP"
            }
            .encode(&mut [0; 4]),
            Err(R3Error::TooLong {
                needed: 8,
                capacity: 4
            })
        );
    }

    #[test]
    fn replies_and_dstate_from_the_reference() {
        assert_eq!(Reply::parse(b"QoK20000;0;1"), Ok(Reply::Ok("20000;0;1")));
        assert_eq!(Reply::parse(b"QeR0041"), Ok(Reply::Error(41)));
        assert_eq!(Reply::parse(b"nope"), Err(R3Error::BadReply));
        let s = DState::parse("20000;0;1").unwrap();
        assert!(s.servo_on() && !s.running());
        assert_eq!((s.stop, s.error_no, s.step_no, s.mech_no), (0, 0, 0, 1));
        let s = DState::parse("E3021234;10;1\r\n").unwrap();
        assert_eq!(
            (s.run, s.stop, s.error_no, s.step_no),
            (0xE3, 0x02, 1234, 10)
        );
        assert_eq!(DState::parse("2"), Err(R3Error::BadState { at: 0 }));
        assert_eq!(DState::parse("2000x;0;1"), Err(R3Error::BadState { at: 4 }));
        let mut buf = [0; 32];
        let n = s.encode(&mut buf).unwrap();
        assert_eq!(
            DState::parse(core::str::from_utf8(&buf[..n]).unwrap()),
            Ok(s)
        );
    }

    #[test]
    fn the_program_is_rls_four_lines_in_one_chunk() {
        let mut buf = [0u8; 128];
        let n = write_program(&mut buf, "127.0.0.1".parse().unwrap(), Mode::Joint, 2).unwrap();
        let p = core::str::from_utf8(&buf[..n]).unwrap();
        assert_eq!(
            p,
            "10 OPEN \"ENET:127.0.0.1\" AS #1\u{b}20 MXT 1,1,2\u{b}30 HLT\u{b}40 END"
        );
        let mut chunks = EmdatChunks::new(p);
        assert_eq!(chunks.next(), Some(Ok(p)));
        assert_eq!(chunks.next(), None);
    }

    #[test]
    fn long_programs_split_at_line_separators() {
        let line = "X".repeat(100);
        let program = [line.as_str(); 5].join("\u{b}");
        let chunks: Vec<_> = EmdatChunks::new(&program).map(Result::unwrap).collect();
        assert_eq!(chunks.len(), 3);
        assert!(chunks.iter().all(|c| c.len() <= EMDAT_CHUNK_LEN));
        assert_eq!(chunks.join("\u{b}"), program);
        let long = "Y".repeat(300);
        assert_eq!(
            EmdatChunks::new(&long).next(),
            Some(Err(R3Error::LineTooLong { len: 300 }))
        );
    }
}
