//! Targets streamed to a running controller as text lines, from standard input or a UDP socket
//! (`rl run --follow SOURCE`).
//!
//! A stream is one non-real-time thread ([`spawn`]) that reads lines, parses each
//! ([`parse_line`]) and sends the targets through the run's [`InputSender`], which checks them
//! against the model's limits before they reach the loop. The law follows the newest target.
//! Nothing is lost silently: every line, target, refusal and drop is counted in a
//! [`StreamReport`], with the first problem of each kind described.
//!
//! # The line protocol
//!
//! One target per line, UTF-8. Values are in the model's joint order, `dof` of them (the
//! model's joints), in rad or m for positions and rad/s or m/s for velocities, as decimal
//! numbers (`0.5`, `-1`, `1e-3`).
//!
//! | line | meaning |
//! |---|---|
//! | `position q1 … qn` (or `p q1 … qn`) | go to q and stop there |
//! | `position q1 … qn velocity v1 … vn` (`p q1 … qn v v1 … vn`) | arrive at q with velocity v |
//! | `velocity v1 … vn` (or `v v1 … vn`) | reach velocity v and keep it |
//! | `stop` | bring the arm to rest and end the run |
//! | `at SECONDS` then any line | that line, acted on `SECONDS` after the stream started (a recorded file replayed in time; a time already past acts at once) |
//! | empty, or starting with `#` | ignored (a comment) |
//!
//! A law with inputs of its own takes their lines too ([`LineInput`]: e.g. the task-space
//! law's obstacles, [`crate::controller::task_space`]'s `sphere`, `capsule`, `clear` and
//! `pose`); a stream of them whose end should leave the run going is started with
//! [`StreamOptions::rest_at_end`] false ([`spawn_with`]).
//!
//! - Keywords are case-insensitive (`Position`, `P`); the line starts with one.
//! - Values are separated by spaces or tabs; commas count as spaces (`p 0, 0.5, 0, 0, 0, 0`).
//! - Whitespace around the line is ignored, so are `\r\n` line ends.
//! - A line is at most [`MAX_LINE_BYTES`] (4096) bytes, its line end not counted.
//! - `nan`, `inf` and numbers too large for an `f64` (`1e999`) are malformed (not finite).
//! - `stop` raises the run's [`StopFlag`] at [`StopLevel::Rest`]: the law brings the arm to rest
//!   and the run ends. Lines after it are still read and sent until the run is over.
//!
//! A line that does not parse is *malformed*: it is counted, the first one is described with
//! its place (`line 12: position: value 3 'abc' is not a number`), and the stream goes on with
//! the next line. A target that parses but the sender refuses (outside the joint limits,
//! beyond the speed limits) is *refused*; one the run's input queue has no room for is
//! *dropped*; one sent after the run ended is counted *after end*.
//!
//! ```text
//! # a 6-joint arm: to a pose, through a pose at speed, then drift, then rest
//! position 0 0.5 1.2 0 0.3 0
//! p 0.2 0.5 1.2 0 0.3 0 v 0.1 0 0 0 0 0
//! velocity 0.05 0 0 0 0 0
//! stop
//! ```
//!
//! # Sources
//!
//! A [`TargetSource`] is written as (the forms `rl run --follow` takes):
//!
//! - `-` or `stdin`: standard input, one line after the other. At the end of input (EOF) the
//!   stream asks the run to come to rest ([`StopLevel::Rest`]) and the report says so; a read
//!   error does the same. The reading thread may stay blocked in a read after the run is over:
//!   [`StreamHandle::finish`] does not wait for it.
//! - `udp:PORT`: a UDP socket bound to `127.0.0.1:PORT` (loopback only);
//! - `udp:HOST:PORT`: a UDP socket bound to that address: `udp:0.0.0.0:5000` for every
//!   interface, `udp:[::1]:5000` for IPv6 (the address in brackets), or a host name.
//!
//! Over UDP each datagram carries one or more lines (separated by `\n`, up to 64 KiB a
//! datagram); line numbers count within a datagram. The first sender's address becomes the
//! stream's *peer*: datagrams from any other address are counted as *foreign* and never
//! parsed. A UDP stream has no end of input: the run ends on a `stop` line, on its own
//! (a stop request, a fault, its input timeout) or when the stream is finished. The thread
//! ends within about 100 ms of the run's end or of [`StreamHandle::finish`].
//!
//! # The report
//!
//! [`StreamHandle::report`] (a snapshot) and [`StreamHandle::finish`] give a [`StreamReport`]:
//! lines read, targets sent, `stop` lines, and every line or target that did not reach the
//! run, by kind — malformed, refused, dropped, after the end, foreign — with the first
//! malformed, refused and foreign one described with its place (`line 7` on stdin,
//! `datagram 3 from 127.0.0.1:40000, line 2` over UDP). Value numbers in a message count from
//! 1 within their quantity (`velocity: value 2` is the second velocity). The counts are kept in
//! atomics and a mutex that only the stream's thread and its handle touch, never the real-time
//! thread. [`StreamReport::lines_for_report`] gives them as text for a run's report,
//! [`StreamReport::to_json`] as JSON.
//!
//! ```
//! use rl::controller::Target;
//! use rl::controller::stream::{Line, parse_line};
//!
//! let line = parse_line::<8>("velocity 0.1 0 0 0 0 0", 6)?;
//! let Some(Line::Target(Target::Velocity { velocity })) = line else { panic!() };
//! assert_eq!(velocity[0], 0.1);
//! let e = parse_line::<8>("p 0 0 abc 0 0 0", 6).expect_err("not a number");
//! assert_eq!(e.to_string(), "position: value 3 'abc' is not a number");
//! # Ok::<(), rl::controller::stream::LineError>(())
//! ```

use core::fmt;
use core::str::FromStr;
use core::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::io::{self, BufRead};
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use rl_rt::{StopFlag, StopLevel};
use serde_json::json;

use super::input::{InputError, InputSender, Target};

/// The latest time an `at` line may name, s from the stream's start (about 11.6 days).
pub const MAX_AT_S: f64 = 1e6;

/// The longest line a stream takes, in bytes (its line end not counted); a longer one is
/// malformed ([`LineError::TooLong`]).
pub const MAX_LINE_BYTES: usize = 4096;

/// The largest UDP datagram a stream reads, in bytes.
pub const MAX_DATAGRAM_BYTES: usize = 64 * 1024;

/// How long the UDP thread waits for a datagram before it looks whether to end.
pub const UDP_READ_TIMEOUT: Duration = Duration::from_millis(50);

/// The name of a stream's thread.
pub const THREAD_NAME: &str = "rl-follow";

/// Characters of an offending token an error keeps (longer ones are cut, with `…`).
const TOKEN_CHARS: usize = 24;

/// One parsed line that asks for something.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Line<const J: usize, X = ()> {
    /// A target to send (the first `dof` values set, the rest zero).
    Target(Target<J>),
    /// `stop`: bring the arm to rest and end the run.
    Stop,
    /// One of the law's own inputs ([`LineInput`]).
    Input(X),
}

/// The lines of a law's own inputs (e.g. the task-space law's obstacles), beside the joint
/// targets' `position`, `velocity` and `stop`: a law's input type says which keywords it
/// takes and parses their values. `()` (a law without inputs of its own) takes none.
pub trait LineInput: Copy + Send + 'static {
    /// The keywords, as a list for an error's text (`"sphere, capsule or clear"`); empty
    /// for none.
    const KEYWORDS: &'static str = "";

    /// The input a line starting with `keyword` asks for, from the line's other words;
    /// `None` when `keyword` is not one of this type's.
    fn parse_words(keyword: &str, words: &[&str]) -> Option<Result<Self, LineError>> {
        let _ = (keyword, words);
        None
    }
}

impl LineInput for () {}

/// What is wrong with a line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LineError {
    /// Longer than [`MAX_LINE_BYTES`].
    TooLong {
        /// Its length in bytes.
        bytes: usize,
    },
    /// Not UTF-8 text.
    NotUtf8 {
        /// The byte where the invalid text starts.
        valid_up_to: usize,
    },
    /// The line does not start with a keyword.
    UnknownKeyword {
        /// The first word (cut to a few characters).
        keyword: String,
        /// The law's own keywords ([`LineInput::KEYWORDS`]), empty for none.
        also: &'static str,
    },
    /// Not as many values as the model has joints.
    ValueCount {
        /// `"position"` or `"velocity"`.
        quantity: &'static str,
        /// Values given.
        got: usize,
        /// The model's joints.
        dof: usize,
    },
    /// A value that is not a number.
    NotANumber {
        /// `"position"` or `"velocity"`.
        quantity: &'static str,
        /// Which value, from 1, counted within its quantity.
        index: usize,
        /// The token (cut to a few characters).
        token: String,
    },
    /// A value that is not finite (`nan`, `inf`, `1e999`).
    NotFinite {
        /// `"position"` or `"velocity"`.
        quantity: &'static str,
        /// Which value, from 1, counted within its quantity.
        index: usize,
        /// The token (cut to a few characters).
        token: String,
    },
    /// Something after `stop`, which takes no values.
    StopWithValues {
        /// The first token after it (cut to a few characters).
        token: String,
    },
    /// A law's line with the wrong number of values.
    WordCount {
        /// The keyword.
        keyword: String,
        /// Values given.
        got: usize,
        /// What it takes (`"5 (slot x y z radius), or 9 with velocity vx vy vz"`).
        takes: &'static str,
    },
    /// A value a law's line cannot take (a slot beyond the law's, a negative radius).
    Invalid {
        /// The keyword.
        keyword: String,
        /// What is wrong.
        why: String,
    },
    /// A line this stream does not take: a joint target or `stop` in a stream of a law's own
    /// inputs ([`StreamOptions::targets`] false).
    NotTaken {
        /// The keyword.
        keyword: String,
        /// What the stream takes ([`LineInput::KEYWORDS`]).
        takes: &'static str,
    },
    /// `at` without a time, or with one that is not a number of seconds from 0 to
    /// [`MAX_AT_S`].
    BadTime {
        /// The token after `at` (cut to a few characters), empty when none.
        token: String,
    },
    /// The model has more joints than the stream's capacity `J`.
    TooManyJoints {
        /// The model's joints.
        dof: usize,
        /// The capacity.
        capacity: usize,
    },
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooLong { bytes } => {
                write!(f, "line too long: {bytes} bytes, at most {MAX_LINE_BYTES}")
            }
            Self::NotUtf8 { valid_up_to } => {
                write!(f, "not UTF-8 text (invalid from byte {})", valid_up_to + 1)
            }
            Self::UnknownKeyword { keyword, also: "" } => write!(
                f,
                "unknown keyword '{keyword}' (a line starts with position, p, velocity, v or stop)"
            ),
            Self::UnknownKeyword { keyword, also } => write!(
                f,
                "unknown keyword '{keyword}' (a line starts with position, p, velocity, v, \
                 stop, {also})"
            ),
            Self::WordCount {
                keyword,
                got,
                takes,
            } => write!(
                f,
                "{keyword}: {}, it takes {takes}",
                plural(*got, "value", "values")
            ),
            Self::Invalid { keyword, why } => write!(f, "{keyword}: {why}"),
            Self::NotTaken { keyword, takes } => write!(
                f,
                "'{keyword}' is not taken here (a line starts with {takes})"
            ),
            Self::BadTime { token } if token.is_empty() => {
                f.write_str("at: no time (at SECONDS, then the line)")
            }
            Self::BadTime { token } => write!(
                f,
                "at: '{token}' is not a time (seconds from the stream's start, 0 to {MAX_AT_S}, \
                 then the line)"
            ),
            Self::ValueCount { quantity, got, dof } => write!(
                f,
                "{quantity}: {}, the model has {}",
                plural(*got, "value", "values"),
                plural(*dof, "joint", "joints")
            ),
            Self::NotANumber {
                quantity,
                index,
                token,
            } => write!(f, "{quantity}: value {index} '{token}' is not a number"),
            Self::NotFinite {
                quantity,
                index,
                token,
            } => write!(
                f,
                "{quantity}: value {index} '{token}' is not a finite number"
            ),
            Self::StopWithValues { token } => {
                write!(f, "stop: unexpected '{token}' (stop takes no values)")
            }
            Self::TooManyJoints { dof, capacity } => write!(
                f,
                "the model has {dof} joints, more than the stream's capacity of {capacity}"
            ),
        }
    }
}

impl std::error::Error for LineError {}

/// The token, cut to [`TOKEN_CHARS`] characters.
fn shown(token: &str) -> String {
    let mut chars = token.chars();
    let mut s: String = chars.by_ref().take(TOKEN_CHARS).collect();
    if chars.next().is_some() {
        s.push('…');
    }
    s
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Keyword {
    Position,
    Velocity,
    Stop,
}

fn keyword(token: &str) -> Option<Keyword> {
    let is = |k: &str| token.eq_ignore_ascii_case(k);
    if is("position") || is("p") {
        Some(Keyword::Position)
    } else if is("velocity") || is("v") {
        Some(Keyword::Velocity)
    } else if is("stop") {
        Some(Keyword::Stop)
    } else {
        None
    }
}

/// Parses the values of one quantity from `tokens` into an array, up to (not including) a
/// token for which `ends` holds; checks their count against `dof`.
fn values<'a, const J: usize>(
    tokens: &mut core::iter::Peekable<impl Iterator<Item = &'a str>>,
    quantity: &'static str,
    dof: usize,
    ends: impl Fn(&str) -> bool,
) -> Result<[f64; J], LineError> {
    let mut out = [0.0; J];
    let mut got = 0;
    while let Some(token) = tokens.next_if(|t| !ends(t)) {
        got += 1;
        let v = finite_value(quantity, got, token)?;
        if let Some(slot) = out.get_mut(got - 1) {
            *slot = v;
        }
    }
    if got != dof {
        return Err(LineError::ValueCount { quantity, got, dof });
    }
    Ok(out)
}

/// Parses one line of the [protocol](self) for a model of `dof` joints (at most `J`).
///
/// `Ok(None)` for a line that asks nothing (blank or a comment), `Ok(Some(_))` for a target
/// or `stop`, a [`LineError`] saying what is wrong otherwise. Never panics; allocates only
/// for an error's text (and a law's line's words). The values are checked to be finite numbers, not against the model's
/// limits (the [`InputSender`] does that).
pub fn parse_line<const J: usize>(line: &str, dof: usize) -> Result<Option<Line<J>>, LineError> {
    parse_line_for::<J, ()>(line, dof)
}

/// [`parse_line`] for a law whose own inputs `X` have lines too ([`LineInput`]): a line that
/// starts with one of `X`'s keywords is [`Line::Input`].
pub fn parse_line_for<const J: usize, X: LineInput>(
    line: &str,
    dof: usize,
) -> Result<Option<Line<J, X>>, LineError> {
    if line.len() > MAX_LINE_BYTES {
        return Err(LineError::TooLong { bytes: line.len() });
    }
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let mut tokens = line
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .peekable();
    let Some(first) = tokens.next() else {
        return Ok(None); // only commas
    };
    let target = match keyword(first) {
        None => {
            let words: Vec<&str> = tokens.collect();
            return match X::parse_words(first, &words) {
                Some(input) => input.map(|x| Some(Line::Input(x))),
                None => Err(LineError::UnknownKeyword {
                    keyword: shown(first),
                    also: X::KEYWORDS,
                }),
            };
        }
        Some(Keyword::Stop) => {
            return match tokens.next() {
                None => Ok(Some(Line::Stop)),
                Some(token) => Err(LineError::StopWithValues {
                    token: shown(token),
                }),
            };
        }
        Some(_) if dof > J => return Err(LineError::TooManyJoints { dof, capacity: J }),
        Some(Keyword::Velocity) => Target::Velocity {
            velocity: values(&mut tokens, "velocity", dof, |_| false)?,
        },
        Some(Keyword::Position) => {
            let is_velocity = |t: &str| keyword(t) == Some(Keyword::Velocity);
            let position = values(&mut tokens, "position", dof, is_velocity)?;
            let velocity = match tokens.next() {
                None => None,
                Some(_velocity_keyword) => Some(values(&mut tokens, "velocity", dof, |_| false)?),
            };
            Target::Position { position, velocity }
        }
    };
    Ok(Some(Line::Target(target)))
}

/// A value of a law's line ([`LineInput::parse_words`]): `token` as a finite number, or the
/// error naming `keyword`'s value `index` (from 1).
pub fn finite_value(keyword: &'static str, index: usize, token: &str) -> Result<f64, LineError> {
    let v: f64 = token.parse().map_err(|_| LineError::NotANumber {
        quantity: keyword,
        index,
        token: shown(token),
    })?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(LineError::NotFinite {
            quantity: keyword,
            index,
            token: shown(token),
        })
    }
}

/// A line's time, when it starts with `at SECONDS` (case-insensitive; seconds from the
/// stream's start, finite, 0 or more), and the rest of the line; `None` and the line as it is
/// otherwise.
pub fn split_time(line: &str) -> Result<(Option<f64>, &str), LineError> {
    let trimmed = line.trim_start();
    let Some(rest) = trimmed
        .get(..3)
        .filter(|p| p.eq_ignore_ascii_case("at ") || p.eq_ignore_ascii_case("at\t"))
        .and_then(|_| trimmed.get(3..))
    else {
        return if trimmed.eq_ignore_ascii_case("at") {
            Err(LineError::BadTime {
                token: String::new(),
            })
        } else {
            Ok((None, line))
        };
    };
    let rest = rest.trim_start();
    let end = rest
        .find(|c: char| c.is_whitespace() || c == ',')
        .unwrap_or(rest.len());
    let (token, after) = rest.split_at(end);
    let blank = after
        .trim_matches(|c: char| c.is_whitespace() || c == ',')
        .is_empty();
    match token.parse::<f64>() {
        Ok(_) if blank => Err(LineError::Invalid {
            keyword: "at".into(),
            why: format!("nothing after the time '{}'", shown(token)),
        }),
        Ok(t) if (0.0..=MAX_AT_S).contains(&t) => Ok((Some(t), after)),
        _ => Err(LineError::BadTime {
            token: shown(token),
        }),
    }
}

/// Where a stream reads its targets from. Parses from the forms `rl run --follow` takes
/// (see the [module docs](self)) and displays back in one of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TargetSource {
    /// Standard input (`-` or `stdin`).
    Stdin,
    /// A UDP socket bound to this address (`udp:PORT` on loopback, `udp:HOST:PORT`).
    Udp(SocketAddr),
}

impl fmt::Display for TargetSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Stdin => f.write_str("stdin"),
            Self::Udp(addr) => write!(f, "udp:{addr}"),
        }
    }
}

/// A text that is not a [`TargetSource`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SourceError {
    /// The text.
    pub text: String,
    /// What is wrong with it, if more than the form.
    pub reason: Option<String>,
}

impl fmt::Display for SourceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "'{}' is not a target source", shown(&self.text))?;
        if let Some(r) = &self.reason {
            write!(f, " ({r})")?;
        }
        f.write_str(
            ": use '-' or 'stdin' (standard input), 'udp:PORT' (UDP on 127.0.0.1) or \
             'udp:HOST:PORT' (e.g. 'udp:0.0.0.0:5000', 'udp:[::1]:5000')",
        )
    }
}

impl std::error::Error for SourceError {}

impl FromStr for TargetSource {
    type Err = SourceError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let error = |reason: Option<String>| SourceError {
            text: s.to_owned(),
            reason,
        };
        let text = s.trim();
        if text == "-" || text.eq_ignore_ascii_case("stdin") {
            return Ok(Self::Stdin);
        }
        let Some(rest) = text
            .get(..4)
            .filter(|p| p.eq_ignore_ascii_case("udp:"))
            .and_then(|_| text.get(4..))
        else {
            return Err(error(None));
        };
        if !rest.contains(':') {
            let port: u16 = rest
                .parse()
                .map_err(|_| error(Some(format!("'{}' is not a port", shown(rest)))))?;
            return Ok(Self::Udp(SocketAddr::from(([127, 0, 0, 1], port))));
        }
        if let Ok(addr) = rest.parse::<SocketAddr>() {
            return Ok(Self::Udp(addr));
        }
        let Some((host, port)) = rest.rsplit_once(':') else {
            return Err(error(None));
        };
        if host.contains(':') && !host.starts_with('[') {
            return Err(error(Some(
                "an IPv6 address goes in brackets: udp:[::1]:PORT".into(),
            )));
        }
        let port: u16 = port
            .parse()
            .map_err(|_| error(Some(format!("'{}' is not a port", shown(port)))))?;
        match (host, port).to_socket_addrs() {
            Ok(mut addrs) => addrs
                .next()
                .map(Self::Udp)
                .ok_or_else(|| error(Some(format!("host '{}' has no address", shown(host))))),
            Err(e) => Err(error(Some(format!(
                "host '{}' not found: {e}",
                shown(host)
            )))),
        }
    }
}

/// What became of a stream's lines: a snapshot ([`StreamHandle::report`],
/// [`StreamHandle::finish`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StreamReport {
    /// What the stream carries, for its report's lines: `follow` (`rl run --follow`) or the
    /// role given to [`spawn_with`] (`obstacles`).
    pub role: &'static str,
    /// The source (`stdin`, `udp:127.0.0.1:5000` with the port bound, or a reader's name).
    pub source: String,
    /// UDP: the address datagrams are taken from (the first sender's).
    pub peer: Option<SocketAddr>,
    /// Lines read (blank and comment lines too), foreign datagrams' not counted.
    pub lines: u64,
    /// UDP: datagrams from the peer.
    pub datagrams: u64,
    /// Targets the sender queued for the run.
    pub targets_sent: u64,
    /// The law's own inputs ([`Line::Input`]) the sender queued for the run.
    pub inputs_sent: u64,
    /// `stop` lines.
    pub stops: u64,
    /// Lines that did not parse.
    pub malformed: u64,
    /// Targets the sender refused (outside the joint or speed limits).
    pub refused: u64,
    /// Targets dropped because the run's input queue was full.
    pub dropped: u64,
    /// Targets that came after the run was over.
    pub after_end: u64,
    /// UDP: datagrams from an address other than the peer, refused unread.
    pub foreign: u64,
    /// The input ended (EOF); a stream that rests at its end asked the run to come to rest
    /// ([`StreamOptions::rest_at_end`]).
    pub ended_by_eof: bool,
    /// Whether the stream asks the run to come to rest at the end of its input.
    pub rest_at_end: bool,
    /// Why reading failed, if it did (on stdin the stream then ended and asked for rest).
    pub read_error: Option<String>,
    /// The first malformed line, refused target or foreign datagram, with its place.
    pub first_problem: Option<String>,
    /// The first malformed line, with its place.
    pub first_malformed: Option<String>,
    /// The first refused target, with its place.
    pub first_refused: Option<String>,
    /// The first foreign datagram.
    pub first_foreign: Option<String>,
}

impl StreamReport {
    /// The report as text, one line per string, for a run's report: the counts, then how the
    /// stream ended when it did on its own.
    pub fn lines_for_report(&self) -> Vec<String> {
        let mut counts = Vec::new();
        if self.datagrams > 0 || self.peer.is_some() {
            counts.push(plural(self.datagrams as usize, "datagram", "datagrams"));
        }
        counts.push(plural(self.lines as usize, "line", "lines"));
        if self.targets_sent > 0 || self.inputs_sent == 0 {
            counts.push(format!(
                "{} sent",
                plural(self.targets_sent as usize, "target", "targets")
            ));
        }
        if self.inputs_sent > 0 {
            counts.push(format!(
                "{} sent",
                plural(self.inputs_sent as usize, "input", "inputs")
            ));
        }
        if self.stops > 0 {
            counts.push(plural(self.stops as usize, "stop", "stops"));
        }
        let with_first = |head: String, first: &Option<String>| {
            let mut s = head;
            if let Some(p) = first {
                s.push_str(&format!(" (first: {p})"));
            }
            s
        };
        if self.malformed > 0 {
            counts.push(with_first(
                format!("{} malformed", self.malformed),
                &self.first_malformed,
            ));
        }
        if self.refused > 0 {
            counts.push(with_first(
                format!("{} refused", self.refused),
                &self.first_refused,
            ));
        }
        if self.dropped > 0 {
            counts.push(format!("{} dropped (input queue full)", self.dropped));
        }
        if self.after_end > 0 {
            counts.push(format!("{} after the run ended", self.after_end));
        }
        if self.foreign > 0 {
            counts.push(with_first(
                format!(
                    "{} foreign {}",
                    self.foreign,
                    if self.foreign == 1 {
                        "datagram"
                    } else {
                        "datagrams"
                    }
                ),
                &self.first_foreign,
            ));
        }
        let peer = self
            .peer
            .map(|p| format!(" (peer {p})"))
            .unwrap_or_default();
        let role = self.role;
        let mut out = vec![format!(
            "{role} {}{peer}: {}",
            self.source,
            counts.join(", ")
        )];
        if let Some(e) = &self.read_error {
            out.push(format!("{role} {}: read error: {e}", self.source));
        }
        if self.ended_by_eof && self.rest_at_end {
            out.push(format!(
                "{role} {}: end of input, the run was asked to come to rest",
                self.source
            ));
        } else if self.ended_by_eof {
            out.push(format!("{role} {}: end of input", self.source));
        }
        out
    }

    /// The report as JSON: the counts (plain numbers, no unit), the source, the peer and the
    /// problems as strings or `null`.
    pub fn to_json(&self) -> serde_json::Value {
        json!({
            "source": self.source,
            "peer": self.peer.map(|p| p.to_string()),
            "lines": self.lines,
            "datagrams": self.datagrams,
            "targets_sent": self.targets_sent,
            "inputs_sent": self.inputs_sent,
            "stops": self.stops,
            "malformed": self.malformed,
            "refused": self.refused,
            "dropped": self.dropped,
            "after_end": self.after_end,
            "foreign": self.foreign,
            "ended_by_eof": self.ended_by_eof,
            "rest_at_end": self.rest_at_end,
            "read_error": self.read_error,
            "first_problem": self.first_problem,
            "first_malformed": self.first_malformed,
            "first_refused": self.first_refused,
            "first_foreign": self.first_foreign,
        })
    }
}

/// The texts a stream keeps, behind a mutex only stream threads and the handle take.
#[derive(Debug, Default)]
struct Texts {
    peer: Option<SocketAddr>,
    read_error: Option<String>,
    first_problem: Option<String>,
    first_malformed: Option<String>,
    first_refused: Option<String>,
    first_foreign: Option<String>,
}

/// The kinds of problem whose first text a report keeps.
#[derive(Clone, Copy, Debug)]
enum Problem {
    Malformed,
    Refused,
    Foreign,
}

impl Texts {
    fn first(&mut self, kind: Problem) -> &mut Option<String> {
        match kind {
            Problem::Malformed => &mut self.first_malformed,
            Problem::Refused => &mut self.first_refused,
            Problem::Foreign => &mut self.first_foreign,
        }
    }
}

/// What a stream's thread and its handle share (never the real-time thread).
#[derive(Debug, Default)]
struct Shared {
    role: &'static str,
    source: String,
    lines: AtomicU64,
    datagrams: AtomicU64,
    targets_sent: AtomicU64,
    inputs_sent: AtomicU64,
    stops: AtomicU64,
    malformed: AtomicU64,
    refused: AtomicU64,
    dropped: AtomicU64,
    after_end: AtomicU64,
    foreign: AtomicU64,
    ended_by_eof: AtomicBool,
    rest_at_end: bool,
    finishing: AtomicBool,
    texts: Mutex<Texts>,
}

impl Shared {
    fn new(options: StreamOptions, source: String) -> Self {
        Self {
            role: options.role,
            rest_at_end: options.rest_at_end,
            source,
            ..Self::default()
        }
    }

    fn texts(&self) -> MutexGuard<'_, Texts> {
        self.texts.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn count(counter: &AtomicU64) {
        counter.fetch_add(1, Ordering::Relaxed);
    }

    /// Counts a problem of `kind` and keeps its text if it is the first of its kind or the
    /// first problem at all.
    fn problem(&self, kind: Problem, text: impl FnOnce() -> String) {
        Self::count(match kind {
            Problem::Malformed => &self.malformed,
            Problem::Refused => &self.refused,
            Problem::Foreign => &self.foreign,
        });
        let mut texts = self.texts();
        let kind_is_new = texts.first(kind).is_none();
        if kind_is_new || texts.first_problem.is_none() {
            let text = text();
            if kind_is_new {
                *texts.first(kind) = Some(text.clone());
            }
            texts.first_problem.get_or_insert(text);
        }
    }

    fn is_finishing(&self) -> bool {
        self.finishing.load(Ordering::Acquire)
    }

    fn report(&self) -> StreamReport {
        let n = |c: &AtomicU64| c.load(Ordering::Relaxed);
        let texts = self.texts();
        StreamReport {
            role: self.role,
            source: self.source.clone(),
            peer: texts.peer,
            lines: n(&self.lines),
            datagrams: n(&self.datagrams),
            targets_sent: n(&self.targets_sent),
            inputs_sent: n(&self.inputs_sent),
            stops: n(&self.stops),
            malformed: n(&self.malformed),
            refused: n(&self.refused),
            dropped: n(&self.dropped),
            after_end: n(&self.after_end),
            foreign: n(&self.foreign),
            ended_by_eof: self.ended_by_eof.load(Ordering::Acquire),
            rest_at_end: self.rest_at_end,
            read_error: texts.read_error.clone(),
            first_problem: texts.first_problem.clone(),
            first_malformed: texts.first_malformed.clone(),
            first_refused: texts.first_refused.clone(),
            first_foreign: texts.first_foreign.clone(),
        }
    }
}

/// What a stream's thread holds to act on a line.
struct Follow<const J: usize, X> {
    dof: usize,
    sender: InputSender<J, X>,
    stop: StopFlag,
    shared: Arc<Shared>,
    options: StreamOptions,
    /// When the stream started: `at` lines count from here.
    started: Instant,
}

impl<const J: usize, X: LineInput> Follow<J, X> {
    /// Waits until `at` seconds after the stream's start, in slices that look whether the
    /// stream is finishing or the run over; false when it is (the line is not acted on).
    fn wait_until(&self, at: f64) -> bool {
        let due = self.started + Duration::from_secs_f64(at);
        loop {
            if self.shared.is_finishing() || self.sender.is_ended() {
                return false;
            }
            let now = Instant::now();
            if now >= due {
                return true;
            }
            std::thread::sleep((due - now).min(UDP_READ_TIMEOUT));
        }
    }

    /// Acts on one line's bytes (without its line end, possibly cut: `len` is its whole
    /// length); `place` says where it was, for a problem's text.
    fn line(&self, bytes: &[u8], len: usize, place: impl Fn() -> String) {
        let s = &self.shared;
        Shared::count(&s.lines);
        let parsed = if len > MAX_LINE_BYTES {
            Err(LineError::TooLong { bytes: len })
        } else {
            match core::str::from_utf8(bytes) {
                Ok(text) => split_time(text).and_then(|(at, rest)| {
                    parse_line_for::<J, X>(rest, self.dof).map(|l| l.map(|l| (at, l)))
                }),
                Err(e) => Err(LineError::NotUtf8 {
                    valid_up_to: e.valid_up_to(),
                }),
            }
        };
        let parsed = match parsed {
            Ok(Some((_, Line::Target(_) | Line::Stop))) if !self.options.targets => {
                let word = core::str::from_utf8(bytes)
                    .ok()
                    .and_then(|t| split_time(t).ok())
                    .and_then(|(_, rest)| rest.split_whitespace().next())
                    .unwrap_or_default();
                Err(LineError::NotTaken {
                    keyword: shown(word),
                    takes: X::KEYWORDS,
                })
            }
            Ok(Some((Some(at), line))) => {
                if !self.wait_until(at) {
                    Shared::count(&s.after_end);
                    return;
                }
                Ok(Some(line))
            }
            other => other.map(|l| l.map(|(_, line)| line)),
        };
        match parsed {
            Ok(None) => {}
            Ok(Some(Line::Input(input))) => match self.sender.send(input) {
                Ok(()) => Shared::count(&s.inputs_sent),
                Err(InputError::Full) => Shared::count(&s.dropped),
                Err(InputError::Ended) => Shared::count(&s.after_end),
                Err(e) => s.problem(Problem::Refused, || format!("{}: {e}", place())),
            },
            Ok(Some(Line::Stop)) => {
                Shared::count(&s.stops);
                self.stop.request(StopLevel::Rest);
            }
            Ok(Some(Line::Target(target))) => match self.sender.send_target(target) {
                Ok(()) => Shared::count(&s.targets_sent),
                Err(InputError::Full) => Shared::count(&s.dropped),
                Err(InputError::Ended) => Shared::count(&s.after_end),
                Err(e) => s.problem(Problem::Refused, || format!("{}: {e}", place())),
            },
            Err(e) => s.problem(Problem::Malformed, || format!("{}: {e}", place())),
        }
    }

    /// Reads lines from `reader` until its end, a read error or [`StreamHandle::finish`].
    fn read<R: BufRead>(&self, mut reader: R) {
        let s = &self.shared;
        let mut buf = Vec::with_capacity(256);
        let mut number: u64 = 0;
        loop {
            let read = read_capped_line(&mut reader, &mut buf);
            if s.is_finishing() {
                return;
            }
            match read {
                Ok(Some(len)) => {
                    number += 1;
                    self.line(&buf, len, || format!("line {number}"));
                }
                Ok(None) => {
                    s.ended_by_eof.store(true, Ordering::Release);
                    if self.options.rest_at_end {
                        self.stop.request(StopLevel::Rest);
                    }
                    return;
                }
                Err(e) => {
                    s.texts()
                        .read_error
                        .get_or_insert_with(|| format!("after line {number}: {e}"));
                    if self.options.rest_at_end {
                        self.stop.request(StopLevel::Rest);
                    }
                    return;
                }
            }
        }
    }

    /// Takes datagrams from `socket` until the run is over or [`StreamHandle::finish`].
    fn receive(&self, socket: &UdpSocket) {
        let s = &self.shared;
        let mut buf = vec![0u8; MAX_DATAGRAM_BYTES];
        let mut peer = None;
        while !s.is_finishing() && !self.sender.is_ended() {
            let (n, from) = match socket.recv_from(&mut buf) {
                Ok(r) => r,
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::WouldBlock
                            | io::ErrorKind::TimedOut
                            | io::ErrorKind::Interrupted
                    ) =>
                {
                    continue;
                }
                Err(e) => {
                    s.texts().read_error.get_or_insert_with(|| e.to_string());
                    std::thread::sleep(UDP_READ_TIMEOUT);
                    continue;
                }
            };
            let peer = *peer.get_or_insert_with(|| {
                s.texts().peer = Some(from);
                from
            });
            if from != peer {
                s.problem(Problem::Foreign, || {
                    format!("datagram from {from} refused: the stream follows {peer}")
                });
                continue;
            }
            Shared::count(&s.datagrams);
            let datagram = s.datagrams.load(Ordering::Relaxed);
            let data = buf.get(..n).unwrap_or_default();
            let data = data.strip_suffix(b"\n").unwrap_or(data);
            for (k, line) in data.split(|&b| b == b'\n').enumerate() {
                self.line(line, line.len(), || {
                    format!("datagram {datagram} from {from}, line {}", k + 1)
                });
            }
        }
    }
}

/// Reads one line (its `\n` not kept) into `buf`, keeping at most [`MAX_LINE_BYTES`] + 1
/// bytes of it; returns its whole length, or `None` at the end of input.
fn read_capped_line<R: BufRead>(reader: &mut R, buf: &mut Vec<u8>) -> io::Result<Option<usize>> {
    buf.clear();
    let mut len: usize = 0;
    let mut any = false;
    loop {
        let (used, done) = {
            let available = match reader.fill_buf() {
                Ok(a) => a,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            if available.is_empty() {
                return Ok(any.then_some(len));
            }
            any = true;
            let (part, used, done) = match available.iter().position(|&b| b == b'\n') {
                Some(i) => (&available[..i], i + 1, true),
                None => (available, available.len(), false),
            };
            let room = (MAX_LINE_BYTES + 1).saturating_sub(buf.len());
            buf.extend_from_slice(&part[..part.len().min(room)]);
            len = len.saturating_add(part.len());
            (used, done)
        };
        reader.consume(used);
        if done {
            return Ok(Some(len));
        }
    }
}

/// A running stream: its report at any time, and [`finish`](Self::finish) to end it.
/// Dropping it ends it too (without waiting).
#[derive(Debug)]
pub struct StreamHandle {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    local_addr: Option<SocketAddr>,
    /// Whether `finish` waits for the thread (UDP: it ends within a read timeout).
    joins: bool,
}

impl StreamHandle {
    /// UDP: the address the socket is bound to (the port chosen for `udp:0`).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.local_addr
    }

    /// What the stream counted so far.
    pub fn report(&self) -> StreamReport {
        self.shared.report()
    }

    /// Whether the stream's thread has ended (at the end of input, on a read error, when
    /// the run is over (UDP) or after `finish`).
    pub fn is_finished(&self) -> bool {
        self.thread.as_ref().is_none_or(JoinHandle::is_finished)
    }

    /// Ends the stream and returns what it counted. A UDP stream's thread is waited for (it
    /// ends within about [`UDP_READ_TIMEOUT`]); a reader's (stdin's) is not when it is still
    /// blocked in a read: it is left to end at its next line, which it does not act on.
    pub fn finish(mut self) -> StreamReport {
        self.shared.finishing.store(true, Ordering::Release);
        let thread = self.thread.take().filter(|t| self.joins || t.is_finished());
        if thread.is_some_and(|t| t.join().is_err()) {
            self.shared
                .texts()
                .read_error
                .get_or_insert_with(|| "the stream's thread panicked".into());
        }
        self.shared.report()
    }
}

impl Drop for StreamHandle {
    fn drop(&mut self) {
        self.shared.finishing.store(true, Ordering::Release);
    }
}

fn start(shared: &Arc<Shared>, body: impl FnOnce() + Send + 'static) -> io::Result<JoinHandle<()>> {
    std::thread::Builder::new()
        .name(THREAD_NAME.into())
        .spawn(body)
        .map_err(|e| {
            io::Error::new(
                e.kind(),
                format!(
                    "{} {}: cannot start its thread: {e}",
                    shared.role, shared.source
                ),
            )
        })
}

/// How a stream behaves beyond its source: what its report calls it, and what the end of its
/// input means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamOptions {
    /// What the stream carries, first word of its report's lines (`follow`, `obstacles`).
    pub role: &'static str,
    /// At the end of input (EOF) or a read error, ask the run to come to rest (a stream of
    /// targets: nothing more will come). `false` for a stream beside the law's own motion
    /// (obstacles: the run goes on with the last ones).
    pub rest_at_end: bool,
    /// Whether joint targets and `stop` lines are taken; `false` for a stream of a law's own
    /// inputs alone (such lines are then malformed: [`LineError::NotTaken`]).
    pub targets: bool,
}

impl Default for StreamOptions {
    /// `rl run --follow`'s: `follow`, resting at the end of input.
    fn default() -> Self {
        Self {
            role: "follow",
            rest_at_end: true,
            targets: true,
        }
    }
}

/// Starts a stream from `source` to a run: one non-real-time thread ([`THREAD_NAME`]) that
/// reads lines, sends each target through `sender` and raises `stop` at
/// [`StopLevel::Rest`] on a `stop` line or (stdin) at the end of input. `dof` is the model's
/// joints (the values each line carries).
///
/// UDP: the socket is bound here; a bind error is returned, naming the address.
pub fn spawn<const J: usize, X: LineInput>(
    source: &TargetSource,
    dof: usize,
    sender: InputSender<J, X>,
    stop: StopFlag,
) -> io::Result<StreamHandle> {
    spawn_with(source, dof, sender, stop, StreamOptions::default())
}

/// [`spawn`] with [`StreamOptions`]: e.g. a stream of a law's own inputs ([`LineInput`])
/// whose end leaves the run going.
pub fn spawn_with<const J: usize, X: LineInput>(
    source: &TargetSource,
    dof: usize,
    sender: InputSender<J, X>,
    stop: StopFlag,
    options: StreamOptions,
) -> io::Result<StreamHandle> {
    match *source {
        TargetSource::Stdin => spawn_reader_with(
            io::BufReader::new(io::stdin()),
            &source.to_string(),
            dof,
            sender,
            stop,
            options,
        ),
        TargetSource::Udp(addr) => {
            let role = options.role;
            let fail = |e: io::Error| {
                io::Error::new(e.kind(), format!("{role}: cannot bind udp:{addr}: {e}"))
            };
            let socket = UdpSocket::bind(addr).map_err(fail)?;
            socket
                .set_read_timeout(Some(UDP_READ_TIMEOUT))
                .map_err(fail)?;
            let local = socket.local_addr().map_err(fail)?;
            let shared = Arc::new(Shared::new(options, TargetSource::Udp(local).to_string()));
            let follow = Follow {
                dof,
                sender,
                stop,
                shared: Arc::clone(&shared),
                options,
                started: Instant::now(),
            };
            let thread = start(&shared, move || follow.receive(&socket))?;
            Ok(StreamHandle {
                shared,
                thread: Some(thread),
                local_addr: Some(local),
                joins: true,
            })
        }
    }
}

/// Starts a stream reading lines from any `reader`, as [`spawn`] does from stdin (`name` is
/// the source in the report): at its end the stream raises `stop` at [`StopLevel::Rest`].
pub fn spawn_reader<const J: usize, X: LineInput>(
    reader: impl BufRead + Send + 'static,
    name: &str,
    dof: usize,
    sender: InputSender<J, X>,
    stop: StopFlag,
) -> io::Result<StreamHandle> {
    spawn_reader_with(reader, name, dof, sender, stop, StreamOptions::default())
}

/// [`spawn_reader`] with [`StreamOptions`] (e.g. a file of timed obstacle lines).
pub fn spawn_reader_with<const J: usize, X: LineInput>(
    reader: impl BufRead + Send + 'static,
    name: &str,
    dof: usize,
    sender: InputSender<J, X>,
    stop: StopFlag,
    options: StreamOptions,
) -> io::Result<StreamHandle> {
    let shared = Arc::new(Shared::new(options, name.to_owned()));
    let follow = Follow {
        dof,
        sender,
        stop,
        shared: Arc::clone(&shared),
        options,
        started: Instant::now(),
    };
    let thread = start(&shared, move || follow.read(reader))?;
    Ok(StreamHandle {
        shared,
        thread: Some(thread),
        local_addr: None,
        joins: false,
    })
}

#[cfg(test)]
mod tests {
    use std::io::{Cursor, Read};
    use std::sync::mpsc;
    use std::time::Instant;

    use rl_core::Model;
    use rl_rt::MonoTime;

    use super::super::input::{Input, InputReceiver, Inputs, channel};
    use super::*;

    const DOF: usize = 6;

    fn model() -> Model<16> {
        super::super::rv6sl().expect("embedded model").model
    }

    fn parse(line: &str) -> Result<Option<Line<8>>, LineError> {
        parse_line::<8>(line, DOF)
    }

    fn arr(v: &[f64]) -> [f64; 8] {
        let mut a = [0.0; 8];
        a[..v.len()].copy_from_slice(v);
        a
    }

    /// Takes every target queued on `rx`.
    fn received(rx: &mut InputReceiver<8, ()>) -> Vec<Target<8>> {
        let mut inputs = Inputs::<8, ()>::default();
        let mut out = Vec::new();
        inputs.receive(rx, MonoTime::now(), |i| {
            if let Input::Target(t) = i {
                out.push(*t);
            }
            Ok(())
        });
        out
    }

    fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
        let deadline = Instant::now() + Duration::from_secs(5);
        while !done() {
            assert!(Instant::now() < deadline, "timed out waiting for {what}");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn every_line_form_parses_to_its_target() {
        let q = [0.1, -0.2, 0.3, 0.0, 1.5, -3.0];
        let v = [0.01, 0.0, -0.02, 0.0, 0.0, 0.5];
        let at_rest = Some(Line::Target(Target::Position {
            position: arr(&q),
            velocity: None,
        }));
        assert_eq!(parse("position 0.1 -0.2 0.3 0 1.5 -3"), Ok(at_rest));
        assert_eq!(parse("p 0.1 -0.2 0.3 0 1.5 -3"), Ok(at_rest));
        assert_eq!(parse("  P\t0.1, -0.2, 0.3, 0, 1.5e0, -3.0 \r"), Ok(at_rest));
        let passing = Some(Line::Target(Target::Position {
            position: arr(&q),
            velocity: Some(arr(&v)),
        }));
        assert_eq!(
            parse("position 0.1 -0.2 0.3 0 1.5 -3 velocity 0.01 0 -0.02 0 0 0.5"),
            Ok(passing)
        );
        assert_eq!(
            parse("p 0.1 -0.2 0.3 0 1.5 -3 v 0.01 0 -0.02 0 0 0.5"),
            Ok(passing)
        );
        let moving = Some(Line::Target(Target::Velocity { velocity: arr(&v) }));
        assert_eq!(parse("velocity 0.01 0 -0.02 0 0 0.5"), Ok(moving));
        assert_eq!(parse("V 1e-2,0,-2e-2,0,0,.5"), Ok(moving));
        assert_eq!(parse("stop"), Ok(Some(Line::Stop)));
        assert_eq!(parse("  STOP "), Ok(Some(Line::Stop)));
        for nothing in ["", "   ", "\t\r", "# a comment", "  #p 1 2 3"] {
            assert_eq!(parse(nothing), Ok(None), "{nothing:?}");
        }
    }

    #[test]
    fn errors_name_what_is_wrong_and_where() {
        let e = |line: &str| parse(line).expect_err(line).to_string();
        assert_eq!(
            e("position 0 0 abc 0 0 0"),
            "position: value 3 'abc' is not a number"
        );
        assert_eq!(
            e("p 0 0 0 0 0 0 v 0 x 0 0 0 0"),
            "velocity: value 2 'x' is not a number"
        );
        assert_eq!(e("p 0 0 0"), "position: 3 values, the model has 6 joints");
        assert_eq!(
            e("velocity 0 0 0 0 0 0 0"),
            "velocity: 7 values, the model has 6 joints"
        );
        assert_eq!(
            e("p 0 0 0 0 0 0 velocity"),
            "velocity: 0 values, the model has 6 joints"
        );
        assert_eq!(
            e("p 0 0 nan 0 0 0"),
            "position: value 3 'nan' is not a finite number"
        );
        assert_eq!(
            e("v 0 0 0 0 0 1e999"),
            "velocity: value 6 '1e999' is not a finite number"
        );
        assert_eq!(
            e("move 0 0 0 0 0 0"),
            "unknown keyword 'move' (a line starts with position, p, velocity, v or stop)"
        );
        assert_eq!(
            e("stop now"),
            "stop: unexpected 'now' (stop takes no values)"
        );
        assert_eq!(
            parse_line::<4>("p 0 0 0 0 0 0", DOF),
            Err(LineError::TooManyJoints {
                dof: 6,
                capacity: 4
            })
        );
        let long = format!("p {}", "0 ".repeat(3000));
        assert_eq!(parse(&long), Err(LineError::TooLong { bytes: long.len() }));
        let cut = e(&format!("p {} 0 0 0 0 0", "x".repeat(100)));
        assert!(cut.contains(&format!("'{}…'", "x".repeat(24))), "{cut}");
    }

    #[test]
    fn odd_inputs_never_panic() {
        let huge = "9".repeat(100_000);
        let odd = [
            "",
            "p",
            "v",
            "position",
            "velocity",
            "stop stop",
            "NaN",
            "p NaN NaN NaN NaN NaN NaN",
            "p inf -inf 0 0 0 0",
            "p 1e308 1e309 0 0 0 0",
            &huge,
            "p ①②③ 0 0 0 0 0",
            "é 1 2 3",
            "\u{feff}position 0 0 0 0 0 0",
            "p 0 0 0 0 0 0 v v v",
            "p 0 0 0 0 0 0 velocity 0 0 0 0 0 0 velocity 0 0 0 0 0 0",
            ",,,",
            ", p , 0",
            "-",
            "p --1 +1 0x10 1_0 .e1 1e",
            "\0\0\0",
        ];
        for line in odd {
            for dof in [0, 1, 6, 8, 9] {
                let _ = parse_line::<8>(line, dof);
                let _ = parse_line::<0>(line, dof);
            }
        }
        assert_eq!(parse(",,,"), Ok(None));
        assert!(matches!(
            parse("p ①②③ 0 0 0 0 0"),
            Err(LineError::NotANumber { index: 1, .. })
        ));
        assert!(matches!(parse(&huge), Err(LineError::TooLong { .. })));
    }

    #[test]
    fn sources_parse_and_display_back() {
        let s = |t: &str| t.parse::<TargetSource>();
        assert_eq!(s("-"), Ok(TargetSource::Stdin));
        assert_eq!(s("stdin"), Ok(TargetSource::Stdin));
        let loopback: SocketAddr = "127.0.0.1:5000".parse().expect("address");
        assert_eq!(s("udp:5000"), Ok(TargetSource::Udp(loopback)));
        let any: SocketAddr = "0.0.0.0:5000".parse().expect("address");
        assert_eq!(s("udp:0.0.0.0:5000"), Ok(TargetSource::Udp(any)));
        let v6: SocketAddr = "[::1]:5000".parse().expect("address");
        assert_eq!(s("udp:[::1]:5000"), Ok(TargetSource::Udp(v6)));
        for source in ["stdin", "udp:127.0.0.1:5000", "udp:[::1]:0"] {
            let parsed = s(source).expect(source);
            assert_eq!(parsed.to_string(), source);
            assert_eq!(s(&parsed.to_string()), Ok(parsed));
        }
        for bad in [
            "",
            "udp",
            "udp:",
            "udp:70000",
            "tcp:5000",
            "udp:::1:5000",
            "file.txt",
        ] {
            let e = s(bad).expect_err(bad).to_string();
            assert!(e.contains("'udp:PORT'") && e.contains("'stdin'"), "{e}");
        }
        assert!(
            s("udp:::1:5000")
                .expect_err("unbracketed")
                .to_string()
                .contains("brackets")
        );
    }

    #[test]
    fn a_reader_sends_the_good_targets_and_counts_the_rest() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, ()>(&m, 64);
        let stop = StopFlag::new();
        let text = "# targets\n\
                    p 0 0 0 0 0 0\n\
                    \n\
                    position 0 0.1 abc 0 0 0\n\
                    p 0 3 0 0 0 0\n\
                    velocity 0.01 0 0 0 0 0\n\
                    p 0 0 0\n\
                    p 0 0.2 0 0 0 0 v 0 0.01 0 0 0 0";
        let stream =
            spawn_reader(Cursor::new(text), "test", DOF, tx, stop.clone()).expect("thread starts");
        wait_until("the end of input", || stream.is_finished());
        assert_eq!(
            stop.level(),
            StopLevel::Rest,
            "the end of input asks for rest"
        );
        let r = stream.finish();
        assert_eq!(
            received(&mut rx),
            [
                Target::Position {
                    position: arr(&[0.0; 6]),
                    velocity: None
                },
                Target::Velocity {
                    velocity: arr(&[0.01, 0.0, 0.0, 0.0, 0.0, 0.0])
                },
                Target::Position {
                    position: arr(&[0.0, 0.2, 0.0, 0.0, 0.0, 0.0]),
                    velocity: Some(arr(&[0.0, 0.01, 0.0, 0.0, 0.0, 0.0]))
                },
            ]
        );
        assert_eq!(
            (r.lines, r.targets_sent, r.malformed, r.refused, r.stops),
            (8, 3, 2, 1, 0)
        );
        assert_eq!((r.dropped, r.after_end, r.foreign), (0, 0, 0));
        assert!(r.ended_by_eof);
        assert_eq!(
            r.first_malformed.as_deref(),
            Some("line 4: position: value 3 'abc' is not a number")
        );
        assert_eq!(r.first_problem, r.first_malformed);
        let refused = r.first_refused.as_deref().expect("a refusal");
        assert!(
            refused.starts_with("line 5: target refused: joint joint1 at 3"),
            "{refused}"
        );
        let text = r.lines_for_report();
        assert_eq!(text.len(), 2, "{text:?}");
        assert!(
            text[0].starts_with(
                "follow test: 8 lines, 3 targets sent, 2 malformed (first: line 4: position: \
                 value 3 'abc' is not a number), 1 refused (first: line 5: "
            ),
            "{text:?}"
        );
        assert!(text[1].contains("end of input"), "{text:?}");
        let json = r.to_json();
        assert_eq!(json["targets_sent"], 3);
        assert_eq!(json["malformed"], 2);
        assert_eq!(json["ended_by_eof"], true);
        assert_eq!(json["peer"], serde_json::Value::Null);
    }

    /// A law's own input for the tests: `mark N`.
    #[derive(Clone, Copy, Debug, PartialEq)]
    struct Mark(u32);

    impl LineInput for Mark {
        const KEYWORDS: &'static str = "mark";

        fn parse_words(keyword: &str, words: &[&str]) -> Option<Result<Self, LineError>> {
            keyword.eq_ignore_ascii_case("mark").then(|| match words {
                [n] => n.parse().map(Mark).map_err(|_| LineError::Invalid {
                    keyword: "mark".into(),
                    why: format!("'{n}' is not a count"),
                }),
                _ => Err(LineError::WordCount {
                    keyword: "mark".into(),
                    got: words.len(),
                    takes: "1",
                }),
            })
        }
    }

    #[test]
    fn a_laws_own_lines_go_in_time_and_their_end_leaves_the_run_going() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, Mark>(&m, 64);
        let stop = StopFlag::new();
        let text = "mark 1\n\
                    at 0.3 mark 2\n\
                    at 0.1, mark 3\n\
                    at -1 mark 4\n\
                    at\n\
                    mark x\n\
                    box 1\n\
                    AT 0.35 p 0 0 0 0 0 0\n";
        let began = Instant::now();
        let options = StreamOptions {
            role: "marks",
            rest_at_end: false,
            targets: true,
        };
        let stream = spawn_reader_with(
            Cursor::new(text),
            "recorded",
            DOF,
            tx,
            stop.clone(),
            options,
        )
        .expect("thread starts");
        wait_until("the end of input", || stream.is_finished());
        let took = began.elapsed();
        // The lines wait for their time (0.3 s, then 0.35 s; 0.1 s was already past).
        assert!(took >= Duration::from_millis(350), "{took:?}");
        assert_eq!(
            stop.level(),
            StopLevel::None,
            "the end leaves the run going"
        );
        let mut inputs = Inputs::<8, Mark>::default();
        let (mut marks, mut targets) = (Vec::new(), 0);
        inputs.receive(&mut rx, MonoTime::now(), |i| {
            match i {
                Input::Other(Mark(n)) => marks.push(*n),
                Input::Target(_) => targets += 1,
            }
            Ok(())
        });
        assert_eq!((marks, targets), (vec![1, 2, 3], 1));
        let r = stream.finish();
        assert_eq!(
            (r.lines, r.inputs_sent, r.targets_sent, r.malformed),
            (8, 3, 1, 4)
        );
        assert!(r.ended_by_eof && !r.rest_at_end);
        assert_eq!(
            r.first_malformed.as_deref(),
            Some(
                "line 4: at: '-1' is not a time (seconds from the stream's start, 0 to 1000000, \
                 then the line)"
            )
        );
        let text = r.lines_for_report();
        assert!(
            text[0]
                .starts_with("marks recorded: 8 lines, 1 target sent, 3 inputs sent, 4 malformed"),
            "{text:?}"
        );
        assert_eq!(text[1], "marks recorded: end of input", "{text:?}");
        assert_eq!(
            parse_line_for::<8, Mark>("box 1", DOF)
                .expect_err("unknown")
                .to_string(),
            "unknown keyword 'box' (a line starts with position, p, velocity, v, stop, mark)"
        );
        assert_eq!(
            split_time("at").expect_err("no time").to_string(),
            "at: no time (at SECONDS, then the line)"
        );
        assert_eq!(split_time("p 0").expect("no time"), (None, "p 0"));
    }

    #[test]
    fn a_stream_of_a_laws_inputs_alone_takes_no_targets_and_no_stop() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, Mark>(&m, 64);
        let stop = StopFlag::new();
        let text = "p 0 0 0 0 0 0\nat 0.01 stop\nat 0.01\nat 1e7 mark 2\nmark 1\n";
        let options = StreamOptions {
            role: "marks",
            rest_at_end: false,
            targets: false,
        };
        let stream = spawn_reader_with(Cursor::new(text), "only", DOF, tx, stop.clone(), options)
            .expect("thread starts");
        wait_until("the end of input", || stream.is_finished());
        assert_eq!(stop.level(), StopLevel::None, "no stop line taken");
        let mut inputs = Inputs::<8, Mark>::default();
        let mut got = Vec::new();
        inputs.receive(&mut rx, MonoTime::now(), |i| {
            got.push(*i);
            Ok(())
        });
        assert_eq!(got, [Input::Other(Mark(1))]);
        let r = stream.finish();
        assert_eq!((r.lines, r.inputs_sent, r.malformed), (5, 1, 4));
        assert_eq!(
            r.first_malformed.as_deref(),
            Some("line 1: 'p' is not taken here (a line starts with mark)")
        );
        assert_eq!(
            split_time("at 0.01")
                .expect_err("nothing after")
                .to_string(),
            "at: nothing after the time '0.01'"
        );
    }

    #[test]
    fn long_and_broken_lines_are_malformed_and_the_next_ones_read() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, ()>(&m, 8);
        let mut text = b"p ".to_vec();
        text.extend(std::iter::repeat_n(b'0', 10_000));
        text.extend_from_slice(b"\np 0 0 \xff 0 0 0\r\np 0 0 0 0 0 0\r\n");
        let stream = spawn_reader(Cursor::new(text), "bytes", DOF, tx, StopFlag::new())
            .expect("thread starts");
        wait_until("the end of input", || stream.is_finished());
        let r = stream.finish();
        assert_eq!(received(&mut rx).len(), 1);
        assert_eq!((r.lines, r.malformed, r.targets_sent), (3, 2, 1));
        assert_eq!(
            r.first_malformed.as_deref(),
            Some("line 1: line too long: 10002 bytes, at most 4096")
        );
    }

    #[test]
    fn a_full_queue_and_an_ended_run_are_counted() {
        let m = model();
        let (tx, rx) = channel::<16, 8, ()>(&m, 2);
        let text = "p 0 0 0 0 0 0\n".repeat(3);
        let stream = spawn_reader(Cursor::new(text), "full", DOF, tx.clone(), StopFlag::new())
            .expect("thread starts");
        wait_until("the end of input", || stream.is_finished());
        let r = stream.finish();
        assert_eq!((r.targets_sent, r.dropped), (2, 1));
        drop(rx);
        let stream = spawn_reader(
            Cursor::new("v 0 0 0 0 0 0"),
            "late",
            DOF,
            tx,
            StopFlag::new(),
        )
        .expect("thread starts");
        wait_until("the end of input", || stream.is_finished());
        assert_eq!(stream.finish().after_end, 1);
    }

    /// A reader fed line by line from a channel: blocks until the next line, ends when the
    /// channel's sender is dropped.
    struct Feed(mpsc::Receiver<Vec<u8>>, Cursor<Vec<u8>>);

    impl Read for Feed {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
            loop {
                let n = self.1.read(buf)?;
                if n > 0 || buf.is_empty() {
                    return Ok(n);
                }
                match self.0.recv() {
                    Ok(next) => self.1 = Cursor::new(next),
                    Err(_) => return Ok(0),
                }
            }
        }
    }

    #[test]
    fn a_stop_line_asks_for_rest_and_finish_does_not_wait_for_a_blocked_reader() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, ()>(&m, 8);
        let stop = StopFlag::new();
        let (feed, lines) = mpsc::channel();
        let reader = io::BufReader::new(Feed(lines, Cursor::new(Vec::new())));
        let stream = spawn_reader(reader, "feed", DOF, tx, stop.clone()).expect("thread starts");
        feed.send(b"p 0 0 0 0 0 0\nstop\n".to_vec()).expect("fed");
        wait_until("the stop line", || stream.report().stops == 1);
        assert_eq!(stop.level(), StopLevel::Rest);
        assert_eq!(received(&mut rx).len(), 1);
        assert!(!stream.is_finished(), "blocked in a read");
        let t0 = Instant::now();
        let r = stream.finish();
        assert!(
            t0.elapsed() < Duration::from_millis(200),
            "{:?}",
            t0.elapsed()
        );
        assert_eq!((r.lines, r.targets_sent, r.stops), (2, 1, 1));
        assert!(!r.ended_by_eof);
        feed.send(b"p 0 0 0 0 0 0\n".to_vec()).expect("fed");
        drop(feed);
    }

    #[test]
    fn udp_takes_its_peers_datagrams_and_refuses_others() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, ()>(&m, 64);
        let stop = StopFlag::new();
        let source: TargetSource = "udp:0".parse().expect("source");
        let stream = spawn(&source, DOF, tx, stop.clone()).expect("bound");
        let addr = stream.local_addr().expect("udp");
        assert!(addr.ip().is_loopback() && addr.port() != 0);
        assert_eq!(stream.report().source, format!("udp:{addr}"));
        let peer = UdpSocket::bind("127.0.0.1:0").expect("peer");
        let other = UdpSocket::bind("127.0.0.1:0").expect("other");
        peer.send_to(b"p 0 0 0 0 0 0\nv 0 0 0 0 0 0\n", addr)
            .expect("sent");
        wait_until("the first datagram", || stream.report().datagrams == 1);
        other
            .send_to(b"p 0 0.1 0 0 0 0\nstop\n", addr)
            .expect("sent");
        peer.send_to(b"p 0 0.3 0 0 0 0\np 0 x 0 0 0 0", addr)
            .expect("sent");
        wait_until("all datagrams", || {
            let r = stream.report();
            r.datagrams == 2 && r.foreign == 1
        });
        let t0 = Instant::now();
        let r = stream.finish();
        assert!(
            t0.elapsed() < Duration::from_millis(200),
            "{:?}",
            t0.elapsed()
        );
        assert_eq!(
            stop.level(),
            StopLevel::None,
            "the foreign stop was not read"
        );
        assert_eq!(received(&mut rx).len(), 3);
        assert_eq!(
            (r.datagrams, r.lines, r.targets_sent, r.malformed, r.foreign),
            (2, 4, 3, 1, 1)
        );
        assert_eq!(r.peer, peer.local_addr().ok());
        let foreign = r.first_foreign.as_deref().expect("foreign");
        let other_addr = other.local_addr().expect("address");
        assert!(foreign.starts_with(&format!("datagram from {other_addr} refused")));
        assert_eq!(r.first_problem.as_deref(), Some(foreign));
        assert_eq!(
            r.first_malformed.as_deref(),
            Some(
                format!(
                    "datagram 2 from {}, line 2: position: value 2 'x' is not a number",
                    peer.local_addr().expect("address")
                )
                .as_str()
            )
        );
        let text = r.lines_for_report();
        assert!(
            text[0].contains("1 foreign datagram (first: datagram from"),
            "{text:?}"
        );
        assert_eq!(r.to_json()["foreign"], 1);
    }

    #[test]
    fn udp_ends_with_the_run_and_names_the_address_it_cannot_bind() {
        let m = model();
        let (tx, rx) = channel::<16, 8, ()>(&m, 8);
        let stream = spawn(
            &"udp:0".parse().expect("source"),
            DOF,
            tx.clone(),
            StopFlag::new(),
        )
        .expect("bound");
        let addr = stream.local_addr().expect("udp");
        let e = spawn(&TargetSource::Udp(addr), DOF, tx, StopFlag::new()).expect_err("taken");
        assert!(e.to_string().contains(&format!("udp:{addr}")), "{e}");
        drop(rx);
        wait_until("the run's end", || stream.is_finished());
        assert_eq!(stream.finish().lines, 0);
    }
}
