//! The MELFA R3 text protocol that sets up real-time control over TCP: requests
//! `<robot>;<slot>;<CMD><args>` without terminator, replies `QoK...` (success) or `QeR<n>`
//! (error `n`), the `DSTATE` status reply, the `JPOSF` joint position reply, and the 4-line MXT
//! program RL uploads.
//!
//! Facts from RL's `MitsubishiR3` / `MitsubishiH7` (see `shared/reference/mitsubishi-h7.md`) and
//! from MELFA client libraries (sources in `rl-drivers/NOTES.md`):
//! - A reply ends with a carriage return ([`TERMINATOR`]) on the serial port; on Ethernet the
//!   end code is a port parameter of the controller, so a reply may come without one. RL reads a
//!   reply with a single `recv`; [`reply_end`] finds the end of a framed reply.
//! - `Qok` / `Qer` (lower-case second letter) are the success and error answers of a
//!   controller that is itself in an error state.
//! - `JPOSF` answers `QoKJ1;<deg>;J2;<deg>;…;J6;<deg>;;****,****;<ovrd>;<speed>;<limit>`: one
//!   `J<n>;<value>` pair per axis (degrees, or mm for a linear axis), then fields this crate
//!   does not use ([`JointReport`]).

use core::fmt::{self, Write};
use core::net::IpAddr;

use super::h7::Mode;

/// Most bytes RL reads for one reply.
pub const MAX_REPLY_LEN: usize = 256;
/// The byte that ends a reply (carriage return) when the controller sends an end code.
pub const TERMINATOR: u8 = b'\r';
/// Most axes a `JPOSF` reply reports (six robot axes and two additional axes).
pub const MAX_REPORTED_AXES: usize = 8;
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
    /// A `JPOSF` reply is malformed.
    BadJointReport {
        /// Where parsing stopped (offset in the text after `QoK`).
        at: usize,
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
            R3Error::BadJointReport { at } => write!(f, "malformed JPOSF reply at byte {at}"),
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
    /// Parses a reply. Trailing NUL, CR and LF are ignored; `Qok` and `Qer` (sent by a
    /// controller in an error state) count as `QoK` and `QeR`.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, R3Error> {
        let text = core::str::from_utf8(bytes).map_err(|e| R3Error::NotText {
            at: e.valid_up_to(),
        })?;
        let text = text.trim_end_matches(['\0', '\r', '\n']);
        if let Some(payload) = text
            .strip_prefix("QoK")
            .or_else(|| text.strip_prefix("Qok"))
        {
            Ok(Reply::Ok(payload))
        } else if let Some(code) = text
            .strip_prefix("QeR")
            .or_else(|| text.strip_prefix("Qer"))
        {
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

/// The length of the first complete reply in `bytes` including its [`TERMINATOR`], or `None`
/// while no terminator has arrived.
pub fn reply_end(bytes: &[u8]) -> Option<usize> {
    bytes.iter().position(|&b| b == TERMINATOR).map(|i| i + 1)
}

/// The axes of a `JPOSF` reply: `J<n>;<value>` pairs for `J1`, `J2`, … in order, values in
/// degrees (mm for a linear axis) as printed, with the number of decimals each was printed
/// with (its resolution).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointReport {
    /// Axes reported.
    pub axes: usize,
    /// The values as printed (degrees, or mm for a linear axis); zero beyond `axes`.
    pub values: [f64; MAX_REPORTED_AXES],
    /// Decimal places each value was printed with.
    pub decimals: [u8; MAX_REPORTED_AXES],
}

impl JointReport {
    /// Parses the payload after `QoK`: the leading `J<n>;<value>;` pairs, `J1` first and
    /// numbered in order; what follows the last pair (structure flags, override, speed, limit
    /// word) is not read. At least one axis is required.
    pub fn parse(payload: &str) -> Result<Self, R3Error> {
        let mut r = JointReport::default();
        let mut at = 0;
        let mut fields = payload.split(';');
        while let Some(number) = fields
            .next()
            .and_then(|name| name.strip_prefix('J'))
            .filter(|n| !n.is_empty())
        {
            let name_len = number.len() + 1;
            let bad = R3Error::BadJointReport { at };
            let n: usize = number.parse().map_err(|_| bad)?;
            if n != r.axes + 1 || r.axes == MAX_REPORTED_AXES {
                return Err(bad);
            }
            at += name_len + 1;
            let value = fields.next().ok_or(R3Error::BadJointReport { at })?;
            let v: f64 = value
                .trim()
                .parse()
                .map_err(|_| R3Error::BadJointReport { at })?;
            if !v.is_finite() {
                return Err(R3Error::BadJointReport { at });
            }
            let decimals = value.trim().split_once('.').map_or(0, |(_, d)| d.len());
            r.values[r.axes] = v;
            r.decimals[r.axes] = u8::try_from(decimals).unwrap_or(u8::MAX);
            r.axes += 1;
            at += value.len() + 1;
        }
        if r.axes == 0 {
            return Err(R3Error::BadJointReport { at: 0 });
        }
        Ok(r)
    }

    /// Writes a payload (without `QoK`) as a controller does: two decimals per axis, then
    /// the fields a joint position has no use for (`****,****` flags, override 100, speed 0,
    /// limit word 0).
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, R3Error> {
        let capacity = out.len();
        let mut w = SliceWriter {
            out,
            len: 0,
            needed: 0,
        };
        let mut go = || -> fmt::Result {
            for (i, v) in self.values.iter().take(self.axes).enumerate() {
                write!(w, "J{};{v:.2};", i + 1)?;
            }
            w.write_str(";****,****;100;0.00;00000000")
        };
        go().map_err(|_| R3Error::TooLong {
            needed: w.needed,
            capacity,
        })?;
        Ok(w.len)
    }

    /// Half the last printed digit of axis `i`: how far the printed value can be from the
    /// controller's own (in the printed unit).
    pub fn resolution(&self, i: usize) -> f64 {
        let d = self.decimals.get(i).copied().unwrap_or(0);
        (0..d).fold(0.5, |r, _| r / 10.0)
    }
}

/// The controller status from a `DSTATE` reply: `QoK` + RunSts (2 hex digits) + StopSts (2 hex
/// digits) + `errorNo;stepNo;mechNo`.
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

/// What a controller takes from an uploaded MXT program: where to send real-time replies
/// (`OPEN "ENET:<ip>"`), what the client commands and the filter time constant
/// (`MXT <file>,<mode>,<filter ms>`; the filter is in milliseconds, 0 when omitted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProgramInfo {
    /// The client address of the `ENET:` line.
    pub client: IpAddr,
    /// The MXT mode.
    pub mode: Mode,
    /// The MXT filter time constant in ms.
    pub filter_ms: u32,
}

impl ProgramInfo {
    /// Reads the `OPEN "ENET:…"` and `MXT` lines of a program (lines separated by
    /// [`LINE_SEPARATOR`] or newlines, keywords in any case, optional line numbers). The error
    /// gives the byte offset of the line that is wrong, or the program's length when a line is
    /// missing.
    pub fn parse(program: &str) -> Result<Self, R3Error> {
        let mut client = None;
        let mut mxt = None;
        let mut at = 0;
        for line in program.split([LINE_SEPARATOR, '\n', '\r']) {
            let bad = R3Error::BadRequest { at };
            // Drop the line number.
            let body = line
                .trim()
                .trim_start_matches(|c: char| c.is_ascii_digit())
                .trim();
            let upper =
                |s: &str, kw: &str| s.len() >= kw.len() && s[..kw.len()].eq_ignore_ascii_case(kw);
            if upper(body, "OPEN") {
                if let Some(rest) = body.find(':').map(|i| &body[i + 1..]) {
                    let ip = rest.split('"').next().unwrap_or("").trim();
                    client = Some(ip.parse::<IpAddr>().map_err(|_| bad)?);
                }
            } else if upper(body, "MXT") {
                let mut args = body[3..].split(',').map(str::trim);
                let _file = args.next();
                let mode = match args.next().map(str::parse::<u8>) {
                    Some(Ok(0)) => Mode::Pose,
                    Some(Ok(1)) => Mode::Joint,
                    Some(Ok(2)) => Mode::Pulse,
                    _ => return Err(bad),
                };
                let filter_ms = match args.next() {
                    None => 0,
                    Some(f) => f.parse().map_err(|_| bad)?,
                };
                mxt = Some((mode, filter_ms));
            }
            at += line.len() + 1;
        }
        let missing = R3Error::BadRequest { at: program.len() };
        let (mode, filter_ms) = mxt.ok_or(missing)?;
        Ok(ProgramInfo {
            client: client.ok_or(missing)?,
            mode,
            filter_ms,
        })
    }
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

    /// The reply a serial-port client logged for `1;1;JPOSF` (NOTES.md, sources).
    #[test]
    fn jposf_reports_axes_in_degrees_with_their_decimals() {
        let logged = "J1;10.90;J2;70.76;J3;64.16;J4;-160.00;J5;40.06;J6;-183.40;;****,****;20;30.28;00000000";
        let r = JointReport::parse(logged).unwrap();
        assert_eq!(r.axes, 6);
        assert_eq!(r.values[..6], [10.90, 70.76, 64.16, -160.0, 40.06, -183.40]);
        assert_eq!(r.decimals[..6], [2; 6]);
        assert!((r.resolution(0) - 0.005).abs() < 1e-15);
        let mut buf = [0u8; 128];
        let n = r.encode(&mut buf).unwrap();
        assert_eq!(
            core::str::from_utf8(&buf[..n]).unwrap(),
            logged.replace(";20;30.28;", ";100;0.00;")
        );
        assert_eq!(
            JointReport::parse(core::str::from_utf8(&buf[..n]).unwrap()),
            Ok(r)
        );
        // Seven and eight axes (additional axes), and no trailing fields.
        assert_eq!(
            JointReport::parse("J1;1;J2;2;J3;3;J4;4;J5;5;J6;6;J7;7.5;J8;8")
                .unwrap()
                .axes,
            8
        );
        assert_eq!(JointReport::parse("J1;0.1").unwrap().decimals[0], 1);
        // Out of order, missing value, not a number, nothing at all.
        assert_eq!(
            JointReport::parse("J2;1.00;"),
            Err(R3Error::BadJointReport { at: 0 })
        );
        assert_eq!(
            JointReport::parse("J1;1.00;J3;2.00"),
            Err(R3Error::BadJointReport { at: 8 })
        );
        assert_eq!(
            JointReport::parse("J1"),
            Err(R3Error::BadJointReport { at: 3 })
        );
        assert_eq!(
            JointReport::parse("J1;x;"),
            Err(R3Error::BadJointReport { at: 3 })
        );
        assert_eq!(
            JointReport::parse("J1;inf;"),
            Err(R3Error::BadJointReport { at: 3 })
        );
        assert_eq!(
            JointReport::parse(";****"),
            Err(R3Error::BadJointReport { at: 0 })
        );
    }

    #[test]
    fn a_reply_ends_at_its_carriage_return() {
        assert_eq!(reply_end(b"QoK20"), None);
        assert_eq!(reply_end(b"QoK20000;0;1\rQoK"), Some(13));
        assert_eq!(Reply::parse(b"QoK20000;0;1\r"), Ok(Reply::Ok("20000;0;1")));
        assert_eq!(Reply::parse(b"Qok"), Ok(Reply::Ok("")));
        assert_eq!(Reply::parse(b"Qer0041\r"), Ok(Reply::Error(41)));
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
        let info = ProgramInfo::parse(p).unwrap();
        assert_eq!(
            info,
            ProgramInfo {
                client: "127.0.0.1".parse().unwrap(),
                mode: Mode::Joint,
                filter_ms: 2
            }
        );
        // The program of Mitsubishi's ROS driver documentation: no filter given, mixed case.
        let melfa = "Open \"ENET:192.168.0.12\" As #1\nMxt 1,0\nEnd";
        let info = ProgramInfo::parse(melfa).unwrap();
        assert_eq!((info.mode, info.filter_ms), (Mode::Pose, 0));
        assert_eq!(
            ProgramInfo::parse("10 MXT 1,1,0"),
            Err(R3Error::BadRequest { at: 12 })
        );
        assert_eq!(
            ProgramInfo::parse("10 OPEN \"ENET:x\" AS #1\u{b}20 MXT 1,1"),
            Err(R3Error::BadRequest { at: 0 })
        );
        assert_eq!(
            ProgramInfo::parse("10 OPEN \"ENET:1.2.3.4\" AS #1\u{b}20 MXT 1,7,0"),
            Err(R3Error::BadRequest { at: 29 })
        );
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
