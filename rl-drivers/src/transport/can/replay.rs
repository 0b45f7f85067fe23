//! Replay of a recorded bus (a candump log): the peer's frames are handed to the device under
//! test in the recorded order, each only after the frames the device sent before it in the
//! recording have been sent again — and every frame the device sends is compared with the
//! recording. A capture of a real bus (taken with `candump -l`, or by [`record`](super::record))
//! thus replays a session deterministically, without hardware, and shows where the device's
//! behaviour on the wire departs from it (ethercrab's replay harness, for CAN).

use std::fmt;
use std::io;
use std::time::Instant;

use super::{CanTransport, Received, TransportCounters};
use crate::proto::can::Frame;
use crate::proto::can::candump::{self, CandumpError};

/// Why a log cannot be replayed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReplayError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong there.
    pub error: CandumpError,
}

impl fmt::Display for ReplayError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}, {}", self.line, self.error)
    }
}

impl std::error::Error for ReplayError {}

/// A departure from the recording: the device sent `sent` where the recording has `expected`
/// (`None`: the recording had no more frames from the device).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Mismatch {
    /// Index of the frame in the recording (0-based) where they part.
    pub index: usize,
    /// What the device sent.
    pub sent: Frame,
    /// What the recording has.
    pub expected: Option<Frame>,
}

/// A transport that replays a recording.
#[derive(Debug)]
pub struct Replay {
    frames: Vec<(Frame, bool)>,
    /// Next frame of the recording.
    next: usize,
    mismatch: Option<Mismatch>,
    counters: TransportCounters,
}

impl Replay {
    /// Reads a candump log; `sent_by_device` tells which frames the device under test sent
    /// (for a CANopen master: NMT, SYNC, RPDOs and SDO requests).
    pub fn from_candump(
        text: &str,
        sent_by_device: impl Fn(&Frame) -> bool,
    ) -> Result<Self, ReplayError> {
        let mut frames = Vec::new();
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let l =
                candump::parse_line(line).map_err(|error| ReplayError { line: i + 1, error })?;
            frames.push((l.frame, sent_by_device(&l.frame)));
        }
        Ok(Self {
            frames,
            next: 0,
            mismatch: None,
            counters: TransportCounters::default(),
        })
    }

    /// Frames in the recording.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the recording is empty.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Frames of the recording replayed or matched so far.
    pub fn position(&self) -> usize {
        self.next
    }

    /// The first departure from the recording, if any.
    pub fn mismatch(&self) -> Option<Mismatch> {
        self.mismatch
    }
}

impl CanTransport for Replay {
    fn send(&mut self, frame: &Frame) -> io::Result<()> {
        self.counters.frames_sent += 1;
        if self.mismatch.is_some() {
            return Ok(());
        }
        // Peer frames recorded before this one were seen by the device already: they are
        // skipped only if nobody took them (a departure shows up at the next device frame).
        match self.frames.get(self.next) {
            Some((f, true)) if f == frame => {
                self.next += 1;
                Ok(())
            }
            other => {
                self.mismatch = Some(Mismatch {
                    index: self.next,
                    sent: *frame,
                    expected: other.map(|(f, _)| *f),
                });
                Ok(())
            }
        }
    }

    fn flush(&mut self, _deadline: Instant) -> io::Result<()> {
        Ok(())
    }

    fn recv(&mut self, deadline: Instant) -> io::Result<Option<Received>> {
        match self.frames.get(self.next) {
            Some((frame, false)) if self.mismatch.is_none() => {
                self.next += 1;
                self.counters.frames_received += 1;
                Ok(Some(Received {
                    frame: *frame,
                    timestamp: None,
                }))
            }
            // The recording waits for the device (or has ended, or departed): nothing comes,
            // as on a quiet bus, until the deadline.
            _ => {
                let now = Instant::now();
                if deadline > now {
                    std::thread::sleep(deadline - now);
                }
                Ok(None)
            }
        }
    }

    fn counters(&self) -> TransportCounters {
        self.counters
    }
}
