//! The Coach device: streams joint positions, velocities, torques and scene poses to RL's
//! visualisers (rlCoachMdl, rlCoachKin) or simulator over TCP, and reads back joint positions
//! with `6 <i>` requests ([`proto::coach`]).
//!
//! Wire-compatible with RL's `Coach`, with two fixes: replies are reassembled from the byte
//! stream ([`LineBuffer`]) instead of one unframed `recv`, and `step` waits for the reply at most
//! `reply_timeout` instead of sleeping until the end of the period (the caller's loop keeps time).
//!
//! [`proto::coach`]: crate::proto::coach

use core::time::Duration;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::Instant;

use crate::capability::{
    JointDevice, JointPositionActuator, JointPositionSensor, JointTorqueActuator,
    JointTorqueFeedForward, JointVelocityActuator, LinkStatistics, LinkStatisticsSensor, Pose,
};
use crate::device::{CyclicDevice, Device, Error, Lifecycle, Operation, State};
use crate::proto::coach::{CoachError, LineBuffer, MAX_VALUES, Message, Values};
use crate::transport::TcpLink;
use rl_core::rotation::euler;

/// The port RL's visualisers listen on.
pub const DEFAULT_PORT: u16 = 11235;
/// Bytes of commands one step can carry.
pub const OUTPUT_CAPACITY: usize = 8192;
/// Bytes of received lines buffered for reassembly.
pub const INPUT_CAPACITY: usize = 4096;

/// How to reach the Coach server.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoachConfig {
    /// Server address (RL: localhost:11235).
    pub server: SocketAddr,
    /// Model index `i` in the lines.
    pub model: u32,
    /// Joints of the model (at most [`MAX_VALUES`]).
    pub dof: usize,
    /// The period the caller steps at.
    pub update_period: Duration,
    /// Bound on waiting for the `6 <i>` reply (and on sending).
    pub reply_timeout: Duration,
    /// Ask for joint positions each step (`6 <i>`); off for rlSimulator, which does not answer.
    pub request_joints: bool,
    /// Bound on connecting.
    pub connect_timeout: Duration,
}

impl CoachConfig {
    /// Model 0 at 127.0.0.1:11235, 10 ms period, 100 ms reply bound, joints requested.
    pub fn new(dof: usize) -> Self {
        Self {
            server: SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), DEFAULT_PORT),
            model: 0,
            dof,
            update_period: Duration::from_millis(10),
            reply_timeout: Duration::from_millis(100),
            request_joints: true,
            connect_timeout: Duration::from_secs(2),
        }
    }
}

/// What the line exchange has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CoachCounters {
    /// Steps that sent their lines.
    pub sent: u64,
    /// Joint replies used.
    pub replies: u64,
    /// Steps whose reply did not arrive in time.
    pub timeouts: u64,
    /// Replies to earlier requests found at the start of a step (after a timeout), dropped.
    pub late: u64,
    /// Lines that did not parse or did not fit the buffer.
    pub bad_lines: u64,
    /// Well-formed lines that were not a reply for our model (such as rlSimulator's empty lines).
    pub other_lines: u64,
}

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
    counters: CoachCounters,
}

impl Coach {
    /// A closed device; checks the configuration.
    pub fn new(config: CoachConfig) -> Result<Self, Error> {
        if config.dof == 0 || config.dof > MAX_VALUES {
            return Err(Error::InvalidArgument {
                what: "dof (1..=32)",
                expected: MAX_VALUES,
                got: config.dof,
            });
        }
        Ok(Self {
            config,
            lifecycle: Lifecycle::new(),
            link: None,
            out: [0; OUTPUT_CAPACITY],
            out_len: 0,
            lines: LineBuffer::new(),
            joints: [0.0; MAX_VALUES],
            have_joints: false,
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

    /// Takes buffered lines; returns whether a joint reply for our model was among them.
    fn take_lines(&mut self) -> Result<bool, Error> {
        let mut got = false;
        let mut failure = None;
        while let Some(line) = self.lines.next_line() {
            match line.and_then(Message::parse) {
                Ok(Message::Reply { model, values }) if model == self.config.model => {
                    if values.len() == self.config.dof {
                        self.joints[..values.len()].copy_from_slice(&values);
                        self.have_joints = true;
                        if got {
                            self.counters.late += 1;
                        }
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

    fn exchange(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Step;
        if self.config.request_joints {
            self.push(&Message::Request {
                model: self.config.model,
            })?;
        }
        let timeout = self.config.reply_timeout;
        let deadline = Instant::now() + timeout;
        let link = self.link.as_mut().ok_or(Error::State {
            operation: OP,
            state: State::Closed,
        })?;
        let io = |e: std::io::Error| {
            if e.kind() == std::io::ErrorKind::TimedOut {
                Error::Timeout {
                    operation: OP,
                    waited: timeout,
                }
            } else {
                Error::io(OP, &e)
            }
        };
        // Replies already here answer requests of earlier, timed-out steps.
        loop {
            match link.try_recv(self.lines.spare()).map_err(io)? {
                Some(0) => {
                    return Err(Error::io(OP, &std::io::ErrorKind::ConnectionAborted.into()));
                }
                Some(n) => self.lines.commit(n),
                None => break,
            }
        }
        if self.lines.pending() > 0 && self.take_lines().unwrap_or(false) {
            self.counters.late += 1;
        }
        let link = self.link.as_mut().ok_or(Error::State {
            operation: OP,
            state: State::Closed,
        })?;
        link.send_all(&self.out[..self.out_len], deadline)
            .map_err(io)?;
        self.out_len = 0;
        self.counters.sent += 1;
        if !self.config.request_joints {
            return Ok(());
        }
        loop {
            let link = self.link.as_mut().ok_or(Error::State {
                operation: OP,
                state: State::Closed,
            })?;
            let n = match link.recv(self.lines.spare(), deadline) {
                Ok(0) => return Err(Error::io(OP, &std::io::ErrorKind::ConnectionAborted.into())),
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {
                    self.counters.timeouts += 1;
                    return Err(Error::Timeout {
                        operation: OP,
                        waited: timeout,
                    });
                }
                Err(e) => return Err(Error::io(OP, &e)),
            };
            self.lines.commit(n);
            if self.take_lines()? {
                self.counters.replies += 1;
                return Ok(());
            }
        }
    }
}

/// `x y z a b c` of a pose: metres and the `Z-Y'-X''` angles.
fn flat(p: &Pose) -> [f64; 6] {
    let [x, y, z] = p.translation.to_array();
    let [a, b, c] = euler::to_zyx(&p.rotation);
    [x, y, z, a, b, c]
}

fn lifecycle(coach: &mut Coach) -> &mut Lifecycle {
    &mut coach.lifecycle
}

impl Device for Coach {
    type Error = Error;

    fn open(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Open, lifecycle, |coach| {
            const OP: Operation = Operation::Open;
            let timeout = coach.config.connect_timeout;
            let link = TcpLink::connect(coach.config.server, timeout).map_err(|e| {
                if e.kind() == std::io::ErrorKind::TimedOut {
                    Error::Timeout {
                        operation: OP,
                        waited: timeout,
                    }
                } else {
                    Error::io(OP, &e)
                }
            })?;
            coach.link = Some(link);
            coach.lines.clear();
            Ok(())
        })
    }

    fn start(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Start, lifecycle, |coach| {
            coach.out_len = 0;
            Ok(())
        })
    }

    fn stop(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Stop, lifecycle, |coach| {
            coach.out_len = 0;
            Ok(())
        })
    }

    fn close(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Close, lifecycle, |coach| {
            coach.link = None;
            coach.have_joints = false;
            Ok(())
        })
    }

    fn state(&self) -> State {
        self.lifecycle.state()
    }

    fn fault(&self) -> Option<Error> {
        self.lifecycle.fault()
    }

    fn stop_description(&self) -> &'static str {
        "nothing to switch off: a visualiser"
    }
}

impl CyclicDevice for Coach {
    /// Sends the buffered lines (and `6 <i>`) and waits at most `reply_timeout` for the reply.
    fn step(&mut self) -> Result<(), Error> {
        Lifecycle::step(self, lifecycle, Self::exchange)
    }

    fn update_period(&self) -> Duration {
        self.config.update_period
    }
}

impl LinkStatisticsSensor for Coach {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters;
        LinkStatistics {
            sent: c.sent,
            received: c.replies,
            lost: c.timeouts,
            late: c.late,
            rejected: c.other_lines,
            corrupt: c.bad_lines,
            consecutive_failures: self.lifecycle.consecutive_failures(),
        }
    }
}

impl JointTorqueFeedForward for Coach {
    /// Shows the feed-forward torques in the visualiser (`5 <i> τ…`).
    fn set_joint_torque_feed_forward(&mut self, tau: &[f64]) -> Result<(), Error> {
        self.set_joint_torque(tau)
    }
}

impl JointDevice for Coach {
    fn dof(&self) -> usize {
        self.config.dof
    }

    fn torque_feed_forward(&mut self) -> Option<&mut dyn JointTorqueFeedForward<Error = Error>> {
        Some(self)
    }
}

impl JointPositionActuator for Coach {
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        let values = self.values(q)?;
        self.push(&Message::JointPosition {
            model: self.config.model,
            values,
        })
    }
}

impl JointVelocityActuator for Coach {
    fn set_joint_velocity(&mut self, qd: &[f64]) -> Result<(), Error> {
        let values = self.values(qd)?;
        self.push(&Message::JointVelocity {
            model: self.config.model,
            values,
        })
    }
}

impl JointTorqueActuator for Coach {
    fn set_joint_torque(&mut self, tau: &[f64]) -> Result<(), Error> {
        let values = self.values(tau)?;
        self.push(&Message::JointTorque {
            model: self.config.model,
            values,
        })
    }
}

impl JointPositionSensor for Coach {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.config.dof, q.len())?;
        if !self.have_joints {
            return Err(Error::protocol(
                Operation::Get,
                "Coach line",
                &"no joint reply received yet",
            ));
        }
        q.copy_from_slice(&self.joints[..self.config.dof]);
        Ok(())
    }
}
