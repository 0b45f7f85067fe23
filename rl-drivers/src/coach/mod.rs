//! The Coach device: streams joint positions, velocities, torques and scene poses to RL's
//! visualisers (rlCoachMdl, rlCoachKin) or simulator over TCP, and reads back joint positions
//! with `6 <i>` requests ([`proto::coach`]).
//!
//! Wire-compatible with RL's `Coach`, with these fixes: replies are reassembled from the byte
//! stream ([`LineBuffer`]) instead of one unframed `recv`; `step` waits for the reply at most
//! `reply_timeout` (one period by default) instead of sleeping until the end of the period (the
//! caller's loop keeps time); replies are matched to requests in order, so a reply to an
//! earlier request that timed out is counted late, never taken for the current one; whatever
//! piles up while the server is slow is drained at the start of the next step (bounded by its
//! deadline), and a line too long for the buffer is dropped, counted, and reading resumes at
//! the next newline. A closed connection faults the device at once; a silent or garbling server
//! after `max_consecutive_failures` steps.
//!
//! [`proto::coach`]: crate::proto::coach

use core::time::Duration;
use std::time::Instant;

use crate::capability::Pose;
use crate::device::{Driver, Error, Lifecycle, Operation, State, impl_cyclic_device};
use crate::proto::coach::{CoachError, LineBuffer, MAX_VALUES, Message, Values};
use crate::transport::TcpLink;
use rl_core::rotation::euler;

mod capabilities;
mod config;

pub use config::*;

/// Outstanding requests beyond which the server is taken to drop requests: the count starts
/// again (a later reply is then taken as current).
const MAX_OUTSTANDING: u32 = 1024;

/// A client of RL's Coach protocol (RL's `rl::hal::Coach`).
#[derive(Debug)]
pub struct Coach {
    config: CoachConfig,
    lifecycle: Lifecycle,
    link: Option<TcpLink>,
    out: [u8; OUTPUT_CAPACITY],
    out_len: usize,
    lines: LineBuffer<INPUT_CAPACITY>,
    joints: [f64; MAX_VALUES],
    have_joints: bool,
    /// Whether this step's request is out (a reply may be the current one).
    waiting: bool,
    /// This step's wait took a reply for an earlier request, leaving only its own outstanding.
    skipped_suspect: bool,
    counters: CoachCounters,
}

impl Coach {
    /// A closed device; checks the configuration.
    pub fn new(config: CoachConfig) -> Result<Self, Error> {
        if config.dof == 0 || config.dof > MAX_VALUES {
            return Err(Error::InvalidArgument {
                what: "dof (1..=256)",
                expected: MAX_VALUES,
                got: config.dof,
            });
        }
        Ok(Self {
            config,
            lifecycle: Lifecycle::with_failure_limit(config.max_consecutive_failures),
            link: None,
            out: [0; OUTPUT_CAPACITY],
            out_len: 0,
            lines: LineBuffer::new(),
            joints: [0.0; MAX_VALUES],
            have_joints: false,
            waiting: false,
            skipped_suspect: false,
            counters: CoachCounters::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &CoachConfig {
        &self.config
    }

    /// Counters of the exchange.
    pub fn counters(&self) -> CoachCounters {
        self.counters
    }

    /// Buffers a scene body's frame (`0 <model> <body> x y z a b c`).
    pub fn set_body_pose(&mut self, body: u32, pose: &Pose) -> Result<(), Error> {
        let m = Message::BodyPose {
            model: self.config.model,
            body,
            pose: flat(pose),
        };
        self.push(&m)
    }

    /// Buffers a shape's transform relative to its body (`1 <model> <body> <shape> ...`).
    pub fn set_shape_pose(&mut self, body: u32, shape: u32, pose: &Pose) -> Result<(), Error> {
        let m = Message::ShapePose {
            model: self.config.model,
            body,
            shape,
            pose: flat(pose),
        };
        self.push(&m)
    }

    fn values(&self, q: &[f64]) -> Result<Values, Error> {
        self.lifecycle.check(Operation::Set)?;
        Error::check_len("joint vector length", self.config.dof, q.len())?;
        Values::from_slice(q).map_err(|_| Error::InvalidArgument {
            what: "joint vector length",
            expected: MAX_VALUES,
            got: q.len(),
        })
    }

    fn push(&mut self, m: &Message) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        let n = m
            .encode(&mut self.out[self.out_len..])
            .map_err(|_| Error::InvalidArgument {
                what: "commands buffered in one step (bytes)",
                expected: OUTPUT_CAPACITY,
                got: OUTPUT_CAPACITY + 1,
            })?;
        self.out_len += n;
        Ok(())
    }

    fn bad_line(e: CoachError) -> Error {
        Error::protocol(Operation::Step, "Coach line", &e)
    }

    /// Takes the complete lines buffered. A reply for our model answers the oldest outstanding
    /// request: the current one if only one is outstanding (used; returns `true`), else an
    /// earlier one (late, dropped). The error is the last bad line's, if no reply was used.
    fn take_lines(&mut self) -> Result<bool, Error> {
        let mut got = false;
        let mut failure = None;
        while let Some(line) = self.lines.next_line() {
            match line.and_then(Message::parse) {
                Ok(Message::Reply { model, values }) if model == self.config.model => {
                    // Before this step's request is sent, every reply is for an earlier one.
                    let current = self.waiting && self.counters.outstanding <= 1;
                    if self.counters.outstanding == 0 && self.counters.unanswered > 0 {
                        // One taken as unanswered was answered after all.
                        self.counters.unanswered -= 1;
                    } else {
                        self.counters.outstanding = self.counters.outstanding.saturating_sub(1);
                    }
                    if !current {
                        self.counters.late += 1;
                        if self.waiting {
                            self.skipped_suspect = true;
                        }
                    } else if values.len() == self.config.dof {
                        self.joints[..values.len()].copy_from_slice(&values);
                        self.have_joints = true;
                        got = true;
                    } else {
                        self.counters.bad_lines += 1;
                        failure = Some(Error::protocol(
                            Operation::Step,
                            "Coach line",
                            &"reply has another number of joints than dof",
                        ));
                    }
                }
                Ok(Message::Request { model }) if model == self.config.model => {
                    // A server that does not know the model answers `6 <i>` without values.
                    self.counters.outstanding = self.counters.outstanding.saturating_sub(1);
                    self.counters.bad_lines += 1;
                    failure = Some(Error::protocol(
                        Operation::Step,
                        "Coach line",
                        &"the server does not know the model",
                    ));
                }
                Ok(_) => self.counters.other_lines += 1,
                Err(e) => {
                    self.counters.bad_lines += 1;
                    failure = Some(Self::bad_line(e));
                }
            }
        }
        match failure {
            Some(e) if !got => Err(e),
            _ => Ok(got),
        }
    }

    /// Reads once into the line buffer (waiting until `deadline` if `wait`), then takes the
    /// complete lines. `Ok(None)`: nothing to read (or the deadline passed while waiting).
    fn read_lines(&mut self, deadline: Instant, wait: bool) -> Result<Option<bool>, Error> {
        const OP: Operation = Operation::Step;
        if self.lines.spare().is_empty() {
            // A partial line fills the buffer: `next_line` reports it and drops it up to its
            // newline, which frees the buffer.
            return self.take_lines().map(Some);
        }
        let link = self.link.as_mut().ok_or(Error::State {
            operation: OP,
            state: State::Closed,
        })?;
        let read = if wait {
            match link.recv(self.lines.spare(), deadline) {
                Ok(n) => Some(n),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => None,
                Err(e) => return Err(Error::io(OP, &e)),
            }
        } else {
            link.try_recv(self.lines.spare())
                .map_err(|e| Error::io(OP, &e))?
        };
        match read {
            None => Ok(None),
            Some(0) => Err(Error::Disconnected { operation: OP }),
            Some(n) => {
                self.lines.commit(n);
                self.take_lines().map(Some)
            }
        }
    }

    /// At open: sends `6 <i>` and waits (at most `connect_timeout`: a server thread may take a
    /// moment to serve a new connection) for the reply, so the joint positions can be read
    /// before the device starts.
    fn query_joints(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Open;
        let waited = self.config.connect_timeout;
        let deadline = Instant::now() + waited;
        let n = Message::Request {
            model: self.config.model,
        }
        .encode(&mut self.out)
        .map_err(|e| Error::protocol(OP, "Coach line", &e))?;
        let link = self.link.as_mut().ok_or(Error::State {
            operation: OP,
            state: State::Closed,
        })?;
        link.send_all(&self.out[..n], deadline)
            .map_err(|e| link_error(OP, &e, waited))?;
        self.counters.sent += 1;
        self.counters.outstanding = 1;
        self.waiting = true;
        let result = self.wait_reply(deadline);
        self.waiting = false;
        match result {
            Ok(()) => Ok(()),
            Err(Error::Timeout { .. }) => Err(Error::Timeout {
                operation: OP,
                waited,
            }),
            Err(e) => Err(e),
        }
    }

    /// Waits for the reply until `deadline`. Bad lines on the way are counted and skipped; if
    /// no reply comes, the step fails with the last bad line's error (else a timeout).
    fn wait_reply(&mut self, deadline: Instant) -> Result<(), Error> {
        let mut bad = None;
        loop {
            match self.read_lines(deadline, true) {
                Ok(Some(true)) => {
                    self.counters.replies += 1;
                    return Ok(());
                }
                Ok(Some(false)) => {}
                Err(e @ Error::Protocol { .. }) => bad = Some(e),
                Err(e) => return Err(e),
                Ok(None) => {
                    self.counters.timeouts += 1;
                    return Err(bad.unwrap_or(Error::Timeout {
                        operation: Operation::Step,
                        waited: self.config.reply_timeout,
                    }));
                }
            }
        }
    }
}

/// A socket error of `operation`: a timeout after `waited`, else the I/O error.
fn link_error(operation: Operation, e: &std::io::Error, waited: Duration) -> Error {
    if e.kind() == std::io::ErrorKind::TimedOut {
        Error::Timeout { operation, waited }
    } else {
        Error::io(operation, e)
    }
}

/// `x y z a b c` of a pose: metres and the `Z-Y'-X''` angles.
fn flat(p: &Pose) -> [f64; 6] {
    let [x, y, z] = p.translation.to_array();
    let [a, b, c] = euler::to_zyx(&p.rotation);
    [x, y, z, a, b, c]
}

impl Driver for Coach {
    const STOP_DESCRIPTION: &'static str = "nothing to switch off: a visualiser";

    fn open_sequence(&mut self) -> Result<(), Error> {
        self.counters.outstanding = 0;
        const OP: Operation = Operation::Open;
        let timeout = self.config.connect_timeout;
        let link = TcpLink::connect(self.config.server, timeout)
            .map_err(|e| link_error(OP, &e, timeout))?;
        self.link = Some(link);
        self.lines.clear();
        self.have_joints = false;
        if self.config.request_joints {
            // Where the viewer shows the robot now: the pose a controller starts from.
            self.query_joints()?;
        }
        Ok(())
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        self.out_len = 0;
        Ok(())
    }

    fn stop_sequence(&mut self) -> Result<(), Error> {
        self.out_len = 0;
        Ok(())
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        self.link = None;
        self.have_joints = false;
        Ok(())
    }

    fn period(&self) -> Duration {
        self.config.update_period
    }

    /// Sends the buffered lines (and `6 <i>`) and waits at most `reply_timeout` (or the step's
    /// budget, if shorter) for the reply.
    fn exchange(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Step;
        let timeout = self
            .lifecycle
            .step_budget()
            .map_or(self.config.reply_timeout, |b| {
                b.min(self.config.reply_timeout)
            });
        let deadline = Instant::now() + timeout;
        // What piled up answers requests of earlier steps: drain it (within the deadline).
        while Instant::now() < deadline {
            match self.read_lines(deadline, false) {
                Ok(None) => break,
                // Late replies are counted in `take_lines`; a bad line here is only counted.
                Ok(Some(_)) | Err(Error::Protocol { .. }) => {}
                Err(e) => return Err(e),
            }
        }
        if self.config.request_joints {
            self.push(&Message::Request {
                model: self.config.model,
            })?;
        }
        let link = self.link.as_mut().ok_or(Error::State {
            operation: OP,
            state: State::Closed,
        })?;
        let sent = link.send_all(&self.out[..self.out_len], deadline);
        self.out_len = 0;
        if let Err(e) = sent {
            if e.kind() == std::io::ErrorKind::TimedOut {
                self.counters.timeouts += 1;
            }
            return Err(link_error(OP, &e, timeout));
        }
        self.counters.sent += 1;
        if !self.config.request_joints {
            return Ok(());
        }
        self.counters.outstanding += 1;
        if self.counters.outstanding > MAX_OUTSTANDING {
            self.counters.outstanding = 1;
        }
        self.waiting = true;
        self.skipped_suspect = false;
        let result = self.wait_reply(deadline);
        self.waiting = false;
        if result.is_err() && self.skipped_suspect {
            // A reply came during the wait and then nothing until the deadline: the server
            // skipped requests, and the reply taken as late was this step's. Start counting
            // again (a reply that still comes moves from `unanswered` to `late`).
            self.counters.unanswered += u64::from(self.counters.outstanding);
            self.counters.outstanding = 0;
        }
        result
    }
}

impl_cyclic_device!(Coach, lifecycle);
