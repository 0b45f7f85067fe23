//! RL's Coach protocol (the visualisers rlCoachMdl/rlCoachKin and rlSimulator): ASCII lines of
//! space-separated fields ending in `\n`, numbers in SI units written like C's `%g` (6
//! significant digits). Facts from RL's `Coach.cpp` and the demos' `Socket.cpp` (see
//! `shared/reference/coach.md`).
//!
//! | line | meaning |
//! |---|---|
//! | `0 <model> <body> x y z a b c` | body frame, `R = Rz(c)·Ry(b)·Rx(a)` |
//! | `1 <model> <body> <shape> x y z a b c` | shape's local transform |
//! | `2 <i> q1 … qn` | joint positions of model i |
//! | `3 <i> qd1 … qdn` | joint velocities |
//! | `5 <i> tau1 … taun` | joint torques |
//! | `6 <i>` / `6 <i> q1 … qn` | request / reply of joint positions |
//!
//! [`LineBuffer`] reassembles lines from a byte stream (RL's client does a single unframed
//! `recv`, which breaks when a line is split or several arrive together).

use core::fmt::{self, Write};

/// Most values one line carries (joints of one model): as many as the `rl` tool's largest model
/// capacity (RL's protocol has no limit; tiago_dual has 101 joints).
pub const MAX_VALUES: usize = 256;

/// The values of a joint line.
pub type Values = heapless::Vec<f64, MAX_VALUES>;

/// Why a line could not be built or parsed. `field` counts tokens from 0 (the command code).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CoachError {
    /// The line is not ASCII text.
    NotText {
        /// Offset of the bad byte.
        at: usize,
    },
    /// The first token is not a known command code.
    UnknownCommand,
    /// A required field is missing.
    MissingField {
        /// Its index.
        field: usize,
    },
    /// A field is not a number of the right kind.
    BadNumber {
        /// Its index.
        field: usize,
    },
    /// More fields than the command takes.
    ExtraField {
        /// Index of the first extra field.
        field: usize,
    },
    /// More joint values than [`MAX_VALUES`].
    TooManyValues,
    /// The output buffer is too small.
    TooLong {
        /// Its capacity.
        capacity: usize,
    },
    /// A line did not fit the reassembly buffer; it was discarded up to its end.
    LineTooLong {
        /// The buffer's capacity.
        capacity: usize,
    },
}

impl fmt::Display for CoachError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CoachError::NotText { at } => write!(f, "not ASCII at byte {at}"),
            CoachError::UnknownCommand => f.write_str("unknown command code (field 0)"),
            CoachError::MissingField { field } => write!(f, "field {field} is missing"),
            CoachError::BadNumber { field } => write!(f, "field {field} is not a valid number"),
            CoachError::ExtraField { field } => write!(f, "unexpected field {field}"),
            CoachError::TooManyValues => write!(f, "more than {MAX_VALUES} values"),
            CoachError::TooLong { capacity } => {
                write!(f, "line does not fit {capacity} bytes")
            }
            CoachError::LineTooLong { capacity } => {
                write!(f, "line longer than the {capacity}-byte buffer, discarded")
            }
        }
    }
}

/// One Coach line.
#[derive(Clone, Debug, PartialEq)]
pub enum Message {
    /// `0`: a scene body's frame.
    BodyPose {
        /// Model index.
        model: u32,
        /// Body index.
        body: u32,
        /// `x y z` in m then `a b c` in rad.
        pose: [f64; 6],
    },
    /// `1`: a shape's transform relative to its body.
    ShapePose {
        /// Model index.
        model: u32,
        /// Body index.
        body: u32,
        /// Shape index.
        shape: u32,
        /// `x y z` in m then `a b c` in rad.
        pose: [f64; 6],
    },
    /// `2`: joint positions (rad or m).
    JointPosition {
        /// Model index.
        model: u32,
        /// One per joint.
        values: Values,
    },
    /// `3`: joint velocities.
    JointVelocity {
        /// Model index.
        model: u32,
        /// One per joint.
        values: Values,
    },
    /// `5`: joint torques.
    JointTorque {
        /// Model index.
        model: u32,
        /// One per joint.
        values: Values,
    },
    /// `6 <i>`: a request for model i's joint positions (also a server's reply for an
    /// unknown model).
    Request {
        /// Model index.
        model: u32,
    },
    /// `6 <i> q1 … qn`: a server's reply.
    Reply {
        /// Model index.
        model: u32,
        /// One per joint.
        values: Values,
    },
    /// An empty line (rlSimulator's acknowledgement of every command).
    Empty,
}

/// Writes `v` like C's `%g` (and C++ iostreams' default): 6 significant digits, trailing zeros
/// removed, exponent form below 1e-4 and from 1e6 up.
pub fn write_g6<W: Write>(w: &mut W, v: f64) -> fmt::Result {
    if v.is_nan() {
        return w.write_str("nan");
    }
    if v.is_infinite() {
        return w.write_str(if v < 0.0 { "-inf" } else { "inf" });
    }
    if v == 0.0 {
        return w.write_str(if v.is_sign_negative() { "-0" } else { "0" });
    }
    let mut sci = heapless::String::<32>::new();
    write!(sci, "{v:.5e}")?;
    let (mantissa, exp) = sci.split_once('e').ok_or(fmt::Error)?;
    let exp: i32 = exp.parse().map_err(|_| fmt::Error)?;
    if (-4..6).contains(&exp) {
        // Fixed notation from the same 6 rounded digits (what %g does), without formatting again.
        if mantissa.starts_with('-') {
            w.write_char('-')?;
        }
        let mut digits = [b'0'; 6];
        for (d, b) in digits
            .iter_mut()
            .zip(mantissa.bytes().filter(u8::is_ascii_digit))
        {
            *d = b;
        }
        let digits = core::str::from_utf8(&digits).map_err(|_| fmt::Error)?;
        let (int, frac, zeros) = if exp >= 0 {
            let e = exp as usize + 1;
            (&digits[..e], &digits[e..], 0)
        } else {
            ("0", digits, (-exp - 1) as usize)
        };
        w.write_str(int)?;
        let frac = frac.trim_end_matches('0');
        if !frac.is_empty() {
            w.write_char('.')?;
            for _ in 0..zeros {
                w.write_char('0')?;
            }
            w.write_str(frac)?;
        }
        Ok(())
    } else {
        w.write_str(trim_zeros(mantissa))?;
        write!(
            w,
            "e{}{:02}",
            if exp < 0 { '-' } else { '+' },
            exp.unsigned_abs()
        )
    }
}

fn trim_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

struct Cursor<'a> {
    out: &'a mut [u8],
    len: usize,
}

impl Write for Cursor<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let end = self.len + s.len();
        self.out
            .get_mut(self.len..end)
            .ok_or(fmt::Error)?
            .copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// Writes fields: a code, indices, then numbers in `%g` form, and the newline.
fn write_line(out: &mut [u8], code: u8, ids: &[u32], values: &[f64]) -> Result<usize, CoachError> {
    let capacity = out.len();
    let mut c = Cursor { out, len: 0 };
    let mut go = || -> fmt::Result {
        write!(c, "{code}")?;
        for id in ids {
            write!(c, " {id}")?;
        }
        for &v in values {
            c.write_char(' ')?;
            write_g6(&mut c, v)?;
        }
        c.write_char('\n')
    };
    go().map_err(|_| CoachError::TooLong { capacity })?;
    Ok(c.len)
}

impl Message {
    /// Writes the line, newline included, into `out` and returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, CoachError> {
        match self {
            Message::BodyPose { model, body, pose } => write_line(out, 0, &[*model, *body], pose),
            Message::ShapePose {
                model,
                body,
                shape,
                pose,
            } => write_line(out, 1, &[*model, *body, *shape], pose),
            Message::JointPosition { model, values } => write_line(out, 2, &[*model], values),
            Message::JointVelocity { model, values } => write_line(out, 3, &[*model], values),
            Message::JointTorque { model, values } => write_line(out, 5, &[*model], values),
            Message::Request { model } => write_line(out, 6, &[*model], &[]),
            Message::Reply { model, values } => write_line(out, 6, &[*model], values),
            Message::Empty => match out.first_mut() {
                Some(b) => {
                    *b = b'\n';
                    Ok(1)
                }
                None => Err(CoachError::TooLong { capacity: 0 }),
            },
        }
    }

    /// Parses one line (without or with its `\n`; a trailing `\r` is accepted). Never panics.
    pub fn parse(line: &[u8]) -> Result<Message, CoachError> {
        let text = core::str::from_utf8(line).map_err(|e| CoachError::NotText {
            at: e.valid_up_to(),
        })?;
        let mut tokens = text.split_ascii_whitespace();
        let Some(code) = tokens.next() else {
            return Ok(Message::Empty);
        };
        let mut field = 0;
        let mut next_id = |tokens: &mut core::str::SplitAsciiWhitespace<'_>| {
            field += 1;
            let t = tokens.next().ok_or(CoachError::MissingField { field })?;
            t.parse::<u32>()
                .map_err(|_| CoachError::BadNumber { field })
        };
        let msg = match code {
            "0" => {
                let (model, body) = (next_id(&mut tokens)?, next_id(&mut tokens)?);
                Message::BodyPose {
                    model,
                    body,
                    pose: pose(&mut tokens, 3)?,
                }
            }
            "1" => {
                let (model, body) = (next_id(&mut tokens)?, next_id(&mut tokens)?);
                let shape = next_id(&mut tokens)?;
                Message::ShapePose {
                    model,
                    body,
                    shape,
                    pose: pose(&mut tokens, 4)?,
                }
            }
            "2" | "3" | "5" | "6" => {
                let model = next_id(&mut tokens)?;
                let values = values(&mut tokens, 2)?;
                match code {
                    "2" => Message::JointPosition { model, values },
                    "3" => Message::JointVelocity { model, values },
                    "5" => Message::JointTorque { model, values },
                    _ if values.is_empty() => Message::Request { model },
                    _ => Message::Reply { model, values },
                }
            }
            _ => return Err(CoachError::UnknownCommand),
        };
        Ok(msg)
    }

    /// The model index the line is about, if any.
    pub fn model(&self) -> Option<u32> {
        match self {
            Message::BodyPose { model, .. }
            | Message::ShapePose { model, .. }
            | Message::JointPosition { model, .. }
            | Message::JointVelocity { model, .. }
            | Message::JointTorque { model, .. }
            | Message::Request { model }
            | Message::Reply { model, .. } => Some(*model),
            Message::Empty => None,
        }
    }
}

fn number(t: &str, field: usize) -> Result<f64, CoachError> {
    t.parse::<f64>()
        .map_err(|_| CoachError::BadNumber { field })
}

fn pose(
    tokens: &mut core::str::SplitAsciiWhitespace<'_>,
    first: usize,
) -> Result<[f64; 6], CoachError> {
    let mut p = [0.0; 6];
    for (i, v) in p.iter_mut().enumerate() {
        let field = first + i;
        *v = number(
            tokens.next().ok_or(CoachError::MissingField { field })?,
            field,
        )?;
    }
    match tokens.next() {
        Some(_) => Err(CoachError::ExtraField { field: first + 6 }),
        None => Ok(p),
    }
}

fn values(
    tokens: &mut core::str::SplitAsciiWhitespace<'_>,
    first: usize,
) -> Result<Values, CoachError> {
    let mut v = Values::new();
    for (i, t) in tokens.enumerate() {
        v.push(number(t, first + i)?)
            .map_err(|_| CoachError::TooManyValues)?;
    }
    Ok(v)
}

/// Reassembles `\n`-terminated lines from a byte stream in a fixed buffer of `CAPACITY` bytes.
///
/// Read into [`spare`](Self::spare), [`commit`](Self::commit) what was read, then take lines with
/// [`next_line`](Self::next_line) until it returns `None`. A line longer than the buffer is
/// reported once as [`CoachError::LineTooLong`] and skipped up to its newline.
#[derive(Clone, Debug)]
pub struct LineBuffer<const CAPACITY: usize> {
    buf: [u8; CAPACITY],
    start: usize,
    end: usize,
    discarding: bool,
}

impl<const CAPACITY: usize> Default for LineBuffer<CAPACITY> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAPACITY: usize> LineBuffer<CAPACITY> {
    /// An empty buffer.
    pub const fn new() -> Self {
        Self {
            buf: [0; CAPACITY],
            start: 0,
            end: 0,
            discarding: false,
        }
    }

    /// Drops all buffered bytes.
    pub fn clear(&mut self) {
        self.start = 0;
        self.end = 0;
        self.discarding = false;
    }

    /// Bytes buffered but not yet returned as lines.
    pub fn pending(&self) -> usize {
        self.end - self.start
    }

    /// Free space to read into (moves pending bytes to the front first).
    pub fn spare(&mut self) -> &mut [u8] {
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        &mut self.buf[self.end..]
    }

    /// Marks `n` bytes of [`spare`](Self::spare) as filled.
    pub fn commit(&mut self, n: usize) {
        self.end = (self.end + n).min(CAPACITY);
    }

    /// Copies `bytes` in as far as they fit and returns how many were taken.
    pub fn extend(&mut self, bytes: &[u8]) -> usize {
        let spare = self.spare();
        let n = bytes.len().min(spare.len());
        spare[..n].copy_from_slice(&bytes[..n]);
        self.commit(n);
        n
    }

    /// The next complete line without its `\n`, an error for an overlong line, or `None` when
    /// no complete line is buffered.
    pub fn next_line(&mut self) -> Option<Result<&[u8], CoachError>> {
        loop {
            let pending = &self.buf[self.start..self.end];
            match pending.iter().position(|&b| b == b'\n') {
                Some(i) => {
                    let line_start = self.start;
                    self.start += i + 1;
                    if self.discarding {
                        self.discarding = false;
                        continue;
                    }
                    return Some(Ok(&self.buf[line_start..line_start + i]));
                }
                None if self.end - self.start == CAPACITY
                    || (self.discarding && self.start < self.end) =>
                {
                    self.start = 0;
                    self.end = 0;
                    if self.discarding {
                        return None;
                    }
                    self.discarding = true;
                    return Some(Err(CoachError::LineTooLong { capacity: CAPACITY }));
                }
                None => return None,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn g(v: f64) -> heapless::String<32> {
        let mut s = heapless::String::new();
        write_g6(&mut s, v).unwrap();
        s
    }

    /// Expected strings are what `printf("%g")` prints for the same values (glibc).
    #[test]
    fn numbers_print_like_printf_g() {
        let cases = [
            (0.0, "0"),
            (1.0, "1"),
            (-0.5, "-0.5"),
            (1.23456789, "1.23457"),
            (123456.7, "123457"),
            (999999.5, "1e+06"),
            (1234567.0, "1.23457e+06"),
            (0.0001, "0.0001"),
            (0.00001234, "1.234e-05"),
            (1e-300, "1e-300"),
            (100.0, "100"),
            (100000.0, "100000"),
            (-0.000123456, "-0.000123456"),
            (0.00005, "5e-05"),
            (12.5, "12.5"),
            (-99999.95, "-99999.9"),
            (0.1 + 0.2, "0.3"),
        ];
        for (v, want) in cases {
            assert_eq!(g(v).as_str(), want, "value {v:e}");
        }
    }

    #[test]
    fn lines_encode_and_parse() {
        let values = Values::from_slice(&[0.1, -1.5, 2.0]).unwrap();
        let m = Message::JointPosition { model: 0, values };
        let mut buf = [0u8; 128];
        let n = m.encode(&mut buf).unwrap();
        assert_eq!(&buf[..n], b"2 0 0.1 -1.5 2\n");
        assert_eq!(Message::parse(&buf[..n]), Ok(m));
        assert_eq!(Message::parse(b"6 3"), Ok(Message::Request { model: 3 }));
        assert_eq!(Message::parse(b"\r"), Ok(Message::Empty));
        let body = Message::parse(b"0 1 2 0.5 0 0 0 0 1.25").unwrap();
        assert_eq!(
            body,
            Message::BodyPose {
                model: 1,
                body: 2,
                pose: [0.5, 0.0, 0.0, 0.0, 0.0, 1.25]
            }
        );
    }

    #[test]
    fn bad_lines_say_which_field() {
        assert_eq!(Message::parse(b"4 0"), Err(CoachError::UnknownCommand));
        assert_eq!(
            Message::parse(b"0 1 2 0 0 0 0 0"),
            Err(CoachError::MissingField { field: 8 })
        );
        assert_eq!(
            Message::parse(b"0 1 2 0 0 0 0 0 0 9"),
            Err(CoachError::ExtraField { field: 9 })
        );
        assert_eq!(
            Message::parse(b"2 x 1"),
            Err(CoachError::BadNumber { field: 1 })
        );
        assert_eq!(
            Message::parse(b"2 0 1 y"),
            Err(CoachError::BadNumber { field: 3 })
        );
        assert_eq!(
            Message::parse(b"6 -1"),
            Err(CoachError::BadNumber { field: 1 })
        );
        assert_eq!(
            Message::parse(&[b'2', b' ', 0xFF]),
            Err(CoachError::NotText { at: 2 })
        );
    }

    #[test]
    fn partial_and_multiple_lines_are_reassembled() {
        let mut b = LineBuffer::<64>::new();
        b.extend(b"6 0 1 ");
        assert!(b.next_line().is_none());
        b.extend(b"2\n\n2 0 3\n6 0");
        assert_eq!(b.next_line(), Some(Ok(&b"6 0 1 2"[..])));
        assert_eq!(b.next_line(), Some(Ok(&b""[..])));
        assert_eq!(b.next_line(), Some(Ok(&b"2 0 3"[..])));
        assert!(b.next_line().is_none());
        assert_eq!(b.pending(), 3);
        b.extend(b" 4\n");
        assert_eq!(b.next_line(), Some(Ok(&b"6 0 4"[..])));
    }

    #[test]
    fn an_overlong_line_is_reported_once_and_skipped() {
        let mut b = LineBuffer::<8>::new();
        assert_eq!(b.extend(b"123456789"), 8);
        assert_eq!(
            b.next_line(),
            Some(Err(CoachError::LineTooLong { capacity: 8 }))
        );
        b.extend(b"9999\nok\n");
        assert_eq!(b.next_line(), Some(Ok(&b"ok"[..])));
        assert!(b.next_line().is_none());
    }
}
