//! The Mitsubishi H7 device (MELFA real-time external control): [`proto::h7`] packets over
//! [`UdpLink`] once per 7.11 ms cycle, set up and torn down with [`proto::r3`] commands over
//! [`TcpLink`].
//!
//! Session (as RL runs it, `shared/reference/mitsubishi-h7.md`, with the differences below):
//! - `open`: connect R3 (TCP), bind the UDP socket (to the local address of the route to the
//!   controller, not the wildcard, unless configured), and ask `JPOSF` where the arm stands:
//!   from then on [`JointDevice::dof`](crate::JointDevice::dof) is the number of axes the controller reports and
//!   [`JointPositionSensor::joint_position`](crate::JointPositionSensor::joint_position) where they are — before the servo is on.
//! - `start`: `STOP`; upload program 1432 (`NEW`, `LOAD=1432`, `ECLR`, `EMDAT`…, `SAVE`);
//!   `CNTLON`, `SRVON`, `CNTLOFF`; poll `DSTATE` until the servo is on; `CNTLON`, `SLOTINIT`,
//!   `RUN1432;1`, `CNTLOFF`.
//! - `step`: send the buffered command with the requested reply types and wait for the reply
//!   to it until the cycle's deadline ([`MitsubishiH7Config::reply_timeout`], one period).
//! - `stop` (from running or faulted): the end packet (command 255), `STOP`, `DSTATE`, and
//!   `SRVOFF` with a poll until the servo is off — every step attempted even when an earlier
//!   one failed, each bounded in time; the first error is returned. An R3 connection that
//!   dropped (before or during the stop) is opened again once and the step repeated: the servo
//!   must go off.
//! - `close`: drop both sockets (the counts stay).
//!
//! Every reply is checked: it must come from the controller's address, be 196 bytes, decode,
//! hold the requested types, and echo the counter of the packet just sent. A reply with the
//! counter of an earlier packet that has not been answered is late (counted, dropped, the wait
//! goes on); one with the counter of a packet already answered, or of none sent yet, is a
//! replayed or frozen reply (counted corrupt, the step fails). Nothing is used silently.
//!
//! Differences from RL: the reply wait is one period, not (filter + 6) × 7.11 ms; motor pulses
//! go into the first data block (RL writes the third, a bug); a missing reply is a counted
//! timeout and the next step goes on (RL throws); only `max_consecutive_failures` failed steps
//! in a row fault the device; an axis the caller gives no value for is commanded where it was
//! measured (RL sends 0); R3 replies are read until complete (RL reads once); `stop` works from
//! the faulted state.
//!
//! [`proto::h7`]: crate::proto::h7
//! [`proto::r3`]: crate::proto::r3

use core::time::Duration;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::Instant;

use crate::device::{
    DeviceError, Driver, Error, FirstError, Lifecycle, Operation, State, impl_cyclic_device,
};
use crate::proto::h7::{
    Command, Data, DataShape, DataView, DecodeError, IoType, MAX_AXES, Mode, MxtType, PACKET_LEN,
    Packet,
};
use crate::proto::r3::{self, DState, EmdatChunks, JointReport, R3Error, Reply, Request};
use crate::transport::{TcpLink, UdpLink, timestamp};

mod capabilities;
mod config;

use capabilities::f32_ulp;

pub use config::*;

/// Where the last joint positions came from.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Measured {
    None,
    /// The `JPOSF` answer at `open`.
    Report(JointReport),
    /// A real-time reply.
    Reply,
}

/// A Mitsubishi controller in real-time external control mode (RL's `MitsubishiH7`).
#[derive(Debug)]
pub struct MitsubishiH7 {
    config: MitsubishiH7Config,
    lifecycle: Lifecycle,
    udp: Option<UdpLink>,
    r3: Option<TcpLink>,
    axes: usize,
    request: Packet,
    reply: Option<Packet>,
    c_count: u32,
    last_used: Option<u32>,
    /// The last request sent and not answered yet, and when it was sent.
    outstanding: Option<(u32, Instant)>,
    /// The controller is behind (it answered an earlier request than the outstanding one at a
    /// tick): the time by which it will have answered the outstanding request, one tick per
    /// request still queued before it, plus a reply wait.
    behind: Option<Instant>,
    measured: [f64; MAX_AXES],
    measured_from: Measured,
    commanded: Option<[f32; MAX_AXES]>,
    limit: [bool; MAX_AXES],
    last_latency: Option<Duration>,
    /// The requests whose steps gave up waiting lately (by counter modulo [`GIVEN_UP`]), each
    /// with its step's deadline on the kernel timestamps' clock: a reply to one found later
    /// tells how late it reached the kernel.
    given_up: [Option<(u32, Duration)>; GIVEN_UP],
    counters: H7Counters,
    /// Foreign datagrams counted by sockets closed since (the counts survive `close`).
    foreign_before: u64,
    tx: [u8; PACKET_LEN],
    rx: [u8; 512],
    r3_tx: [u8; 512],
    r3_rx: [u8; r3::MAX_REPLY_LEN],
}

/// Requests given up whose deadlines are kept, to time their late replies.
const GIVEN_UP: usize = 16;

/// How a received datagram relates to the packet just sent.
enum Verdict {
    /// The reply to it.
    Current(Packet),
    /// The reply to an earlier packet (its counter), after that step gave up.
    Late(u32),
    /// Not usable; counted, and the error says why.
    Bad(Error),
}

impl MitsubishiH7 {
    /// A closed device; checks the configuration.
    pub fn new(config: MitsubishiH7Config) -> Result<Self, Error> {
        if let Some(axes) = config.axes
            && (axes == 0 || axes > MAX_AXES)
        {
            return Err(Error::InvalidArgument {
                what: "axes (1..=8)",
                expected: MAX_AXES,
                got: axes,
            });
        }
        Ok(Self {
            config,
            lifecycle: Lifecycle::with_failure_limit(config.max_consecutive_failures),
            udp: None,
            r3: None,
            axes: config.axes.unwrap_or(0),
            request: Packet::default(),
            reply: None,
            c_count: 0,
            last_used: None,
            outstanding: None,
            behind: None,
            measured: [0.0; MAX_AXES],
            measured_from: Measured::None,
            commanded: None,
            limit: [false; MAX_AXES],
            last_latency: None,
            given_up: [None; GIVEN_UP],
            counters: H7Counters::default(),
            foreign_before: 0,
            tx: [0; PACKET_LEN],
            rx: [0; 512],
            r3_tx: [0; 512],
            r3_rx: [0; r3::MAX_REPLY_LEN],
        })
    }

    /// The configuration.
    pub fn config(&self) -> &MitsubishiH7Config {
        &self.config
    }

    /// Counters of the real-time exchange.
    pub fn counters(&self) -> H7Counters {
        let mut c = self.counters;
        c.foreign = self.foreign_before + self.udp.as_ref().map_or(0, |u| u.counters().foreign);
        c.consecutive_failures = self.lifecycle.consecutive_failures();
        c
    }

    /// The local UDP address (once open).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.udp.as_ref().and_then(|u| u.local_addr().ok())
    }

    /// The packet the next step will send (buffered commands).
    pub fn request(&self) -> &Packet {
        &self.request
    }

    /// The last valid reply.
    pub fn reply(&self) -> Option<&Packet> {
        self.reply.as_ref()
    }

    /// How long the last used reply took after its packet was sent: near the reply timeout,
    /// the loop's phase sits at the controller's cycle edge.
    pub fn last_reply_latency(&self) -> Option<Duration> {
        self.last_latency
    }

    /// Commands motor pulses (pulse mode); written to the first data block.
    pub fn set_motor_pulse(&mut self, pulses: &[i32]) -> Result<(), Error> {
        self.check_command(Mode::Pulse, pulses.len())?;
        let mut p = [0i32; MAX_AXES];
        p[..pulses.len()].copy_from_slice(pulses);
        self.request.dat = Data::from_i32s(&p);
        self.request.command = Command::Move;
        self.request.send_type = MxtType::Pulse;
        Ok(())
    }

    /// The last received motor pulses (from the first reply block of pulse shape).
    pub fn motor_pulse(&self, pulses: &mut [i32]) -> Result<(), Error> {
        self.read_i32s(DataShape::Pulse, "no pulse data in the last reply", pulses)
    }

    /// The last received current feedback in % (from the first reply block of current shape).
    pub fn current_feedback(&self, currents: &mut [i32]) -> Result<(), Error> {
        self.read_i32s(
            DataShape::Current,
            "no current data in the last reply",
            currents,
        )
    }

    /// Writes `data` under `mask` to the output word at `bit_top` with the next step (replaces a
    /// pending [`request_input`](Self::request_input): a packet carries one `bitTop`).
    pub fn set_output(&mut self, bit_top: u16, mask: u16, data: u16) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        // One `bitTop` per packet: an output replaces a pending input request (as in RL).
        self.request.send_io_type = IoType::Output;
        self.request.recv_io_type = IoType::Null;
        self.request.bit_top = bit_top;
        self.request.bit_mask = mask;
        self.request.io_data = data;
        Ok(())
    }

    /// Asks for the input word at `bit_top` with the next step; read it with [`io_data`](Self::io_data).
    pub fn request_input(&mut self, bit_top: u16) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        // One `bitTop` per packet: an input request replaces a pending output (as in RL).
        self.request.recv_io_type = IoType::Input;
        self.request.send_io_type = IoType::Null;
        self.request.bit_top = bit_top;
        Ok(())
    }

    /// The I/O word of the last reply.
    pub fn io_data(&self) -> Result<u16, Error> {
        self.lifecycle.check(Operation::Get)?;
        Ok(self.last_reply()?.io_data)
    }

    fn check_command(&self, mode: Mode, len: usize) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        if self.config.mode != mode {
            return Err(Error::InvalidArgument {
                what: "command kind does not match the configured mode (code)",
                expected: usize::from(self.config.mode.code()),
                got: usize::from(mode.code()),
            });
        }
        Error::check_len("joint vector length", self.axes, len)
    }

    fn last_reply(&self) -> Result<&Packet, Error> {
        self.reply
            .as_ref()
            .ok_or_else(|| Error::protocol(Operation::Get, "H7 packet", &"no reply received yet"))
    }

    fn find_shape(&self, shape: DataShape, missing: &'static str) -> Result<DataView, Error> {
        self.lifecycle.check(Operation::Get)?;
        let reply = self.last_reply()?;
        reply
            .blocks()
            .iter()
            .find(|(t, _)| t.shape() == shape)
            .map(|(t, d)| d.view(*t))
            .ok_or_else(|| Error::protocol(Operation::Get, "H7 packet", &missing))
    }

    fn read_i32s(
        &self,
        shape: DataShape,
        missing: &'static str,
        out: &mut [i32],
    ) -> Result<(), Error> {
        Error::check_len("output length", self.axes, out.len())?;
        match self.find_shape(shape, missing)? {
            DataView::Pulse(v) | DataView::Current(v) => {
                out.copy_from_slice(&v[..self.axes]);
                Ok(())
            }
            _ => Err(Error::protocol(Operation::Get, "H7 packet", &missing)),
        }
    }

    /// Drops the R3 and UDP links (the socket's count of foreign datagrams is kept).
    fn drop_links(&mut self) {
        if let Some(udp) = self.udp.take() {
            self.foreign_before += udp.counters().foreign;
        }
        self.r3 = None;
    }

    fn udp(&mut self, operation: Operation) -> Result<&mut UdpLink, Error> {
        self.udp.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })
    }

    /// Sends one R3 request and returns the reply's payload (after `QoK`). The reply is read
    /// until it is complete: up to its carriage return, or — from a controller that sends no
    /// end code — until `r3_quiet` passes without a byte; bytes already waiting before the
    /// request (the answer to an earlier request that timed out) are dropped and counted.
    fn r3_exchange(&mut self, operation: Operation, slot: u8, body: &str) -> Result<&str, Error> {
        let request = Request {
            robot: self.config.robot,
            slot,
            body,
        };
        let n = request
            .encode(&mut self.r3_tx)
            .map_err(|e| Error::protocol(operation, "R3 request", &e))?;
        let timeout = self.config.r3_timeout;
        let quiet = self.config.r3_quiet;
        let deadline = Instant::now() + timeout;
        let link = self.r3.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })?;
        let map = |e: std::io::Error| r3_io_error(operation, timeout, &e);
        let disconnected = Error::Disconnected { operation };
        while let Some(stale) = link.try_recv(&mut self.r3_rx).map_err(map)? {
            if stale == 0 {
                return Err(disconnected);
            }
            self.counters.r3_stale_bytes += stale as u64;
        }
        link.send_all(&self.r3_tx[..n], deadline).map_err(map)?;
        let mut len = 0;
        let end = loop {
            if let Some(end) = r3::reply_end(&self.r3_rx[..len]) {
                break end;
            }
            if len == self.r3_rx.len() {
                return Err(Error::protocol(
                    operation,
                    "R3 reply",
                    &"longer than 256 bytes without an end",
                ));
            }
            // Without an end code yet: wait for more, but once some bytes are here, a pause of
            // `r3_quiet` ends the reply.
            let wait_until = if len == 0 {
                deadline
            } else {
                deadline.min(Instant::now() + quiet)
            };
            match link.recv(&mut self.r3_rx[len..], wait_until) {
                Ok(0) => return Err(disconnected),
                Ok(got) => len += got,
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut && len > 0 => {
                    if Instant::now() >= deadline {
                        return Err(map(e));
                    }
                    break len;
                }
                Err(e) => return Err(map(e)),
            }
        };
        if end < len {
            self.counters.r3_stale_bytes += (len - end) as u64;
        }
        match Reply::parse(&self.r3_rx[..end])
            .map_err(|e| Error::protocol(operation, "R3 reply", &e))?
        {
            Reply::Ok(payload) => Ok(payload),
            Reply::Error(code) => Err(Error::device(
                operation,
                "R3 reply",
                &R3Error::Controller { code },
            )),
        }
    }

    fn r3_command(&mut self, operation: Operation, slot: u8, body: &str) -> Result<(), Error> {
        self.r3_exchange(operation, slot, body).map(|_| ())
    }

    /// Connects R3 (again).
    fn connect_r3(&mut self, operation: Operation) -> Result<(), Error> {
        let timeout = self.config.r3_timeout;
        self.r3 = None;
        let r3 = TcpLink::connect(self.config.r3, timeout)
            .map_err(|e| r3_io_error(operation, timeout, &e))?;
        self.r3 = Some(r3);
        Ok(())
    }

    /// Runs an R3 step of the stop; if the connection is gone (reset or closed by the
    /// controller, before or during the stop), connects again once and repeats the step.
    fn stop_r3<T>(&mut self, step: impl Fn(&mut Self) -> Result<T, Error>) -> Result<T, Error> {
        match step(self) {
            Err(e) if e.kind().is_link_loss() || self.r3.is_none() => {
                self.connect_r3(Operation::Stop)?;
                self.counters.r3_reconnects += 1;
                step(self)
            }
            r => r,
        }
    }

    fn dstate(&mut self, operation: Operation) -> Result<DState, Error> {
        let payload = self.r3_exchange(operation, 1, "DSTATE")?;
        DState::parse(payload).map_err(|e| Error::protocol(operation, "R3 DSTATE", &e))
    }

    /// Polls DSTATE until the servo is `on` (or off), bounded by `servo_timeout`.
    fn wait_servo(&mut self, operation: Operation, on: bool) -> Result<(), Error> {
        let start = Instant::now();
        loop {
            if self.dstate(operation)?.servo_on() == on {
                return Ok(());
            }
            if start.elapsed() > self.config.servo_timeout {
                return Err(Error::Timeout {
                    operation,
                    waited: self.config.servo_timeout,
                });
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Asks `JPOSF` where the arm stands and how many axes it has.
    fn read_joint_report(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Open;
        let report = self.r3_exchange(OP, 1, "JPOSF").and_then(|payload| {
            JointReport::parse(payload).map_err(|e| Error::protocol(OP, "R3 JPOSF", &e))
        });
        let report = match (report, self.config.axes) {
            (Ok(report), Some(axes)) if report.axes != axes => {
                return Err(Error::InvalidArgument {
                    what: "axes: the controller reports (JPOSF) another number than configured",
                    expected: report.axes,
                    got: axes,
                });
            }
            (Ok(report), _) => report,
            // No report: the configured count stands, the position is unknown until a reply.
            (Err(_), Some(axes)) => {
                self.axes = axes;
                self.measured_from = Measured::None;
                return Ok(());
            }
            (Err(e), None) => return Err(e),
        };
        self.axes = report.axes;
        for (i, m) in self.measured.iter_mut().enumerate() {
            let v = report.values[i];
            *m = if self.config.linear_axes[i] {
                v
            } else {
                v.to_radians()
            };
        }
        self.measured_from = Measured::Report(report);
        Ok(())
    }

    /// Notes how long the datagram just read waited in the socket after the kernel received it.
    fn note_wait(&mut self) {
        if let Some(at) = self.udp.as_ref().and_then(UdpLink::received_at) {
            let waited = timestamp::since_epoch().saturating_sub(at);
            self.counters.delivery.note_wait(waited);
        }
    }

    /// Notes how long after its step's deadline the late reply to request `c`, just read,
    /// reached the kernel.
    fn note_late_arrival(&mut self, c: u32) {
        let at = self.udp.as_ref().and_then(UdpLink::received_at);
        let slot = &mut self.given_up[c as usize % GIVEN_UP];
        if let (Some(at), Some((given_up, deadline))) = (at, *slot)
            && given_up == c
        {
            *slot = None;
            self.counters
                .delivery
                .note_after_deadline(at.saturating_sub(deadline));
        }
    }

    /// The controller answered request `c` at a tick while this step waits for `sent`: it needs
    /// `sent − c` more ticks (when that is a backlog it can have: fewer than [`GIVEN_UP`]).
    fn note_behind(&mut self, c: u32, sent: u32) {
        let ahead = sent.wrapping_sub(c);
        if (1..GIVEN_UP as u32).contains(&ahead) {
            self.behind = Some(Instant::now() + UPDATE_PERIOD * ahead + self.config.reply_timeout);
        }
    }

    /// Classifies a datagram of `n` bytes in `rx` against the packet with counter `sent`.
    fn verdict(&mut self, n: usize, sent: u32) -> Verdict {
        const OP: Operation = Operation::Step;
        let reply = match Packet::decode(&self.rx[..n]) {
            Ok(p) => p,
            Err(e @ DecodeError::Length { .. }) => {
                self.counters.wrong_length += 1;
                return Verdict::Bad(Error::protocol(OP, "H7 packet", &e));
            }
            Err(e) => {
                self.counters.corrupt += 1;
                return Verdict::Bad(Error::protocol(OP, "H7 packet", &e));
            }
        };
        if [
            reply.recv_type,
            reply.recv_type1,
            reply.recv_type2,
            reply.recv_type3,
        ] != self.config.feedback
        {
            self.counters.corrupt += 1;
            return Verdict::Bad(Error::protocol(
                OP,
                "H7 packet",
                &"reply holds other data types than requested",
            ));
        }
        let c = reply.c_count;
        let replayed = match self.config.counter_check {
            CounterCheck::Off => false,
            CounterCheck::Advancing => Some(c) == self.last_used,
            CounterCheck::Echo => {
                if c == sent {
                    false
                } else {
                    // Packets sent since the reply's and since the last one answered.
                    let age = sent.wrapping_sub(c);
                    let answered = self.last_used.map_or(u32::MAX, |u| sent.wrapping_sub(u));
                    if age < answered && age < u32::MAX / 2 {
                        self.counters.late += 1;
                        return Verdict::Late(c);
                    }
                    true
                }
            }
        };
        if replayed {
            self.counters.replayed += 1;
            return Verdict::Bad(Error::protocol(
                OP,
                "H7 packet",
                &"replayed reply: its counter is of a packet already answered or never sent",
            ));
        }
        Verdict::Current(reply)
    }

    /// Uses the reply to a request of an earlier step: it came a cycle late (counted late),
    /// and the controller's queue is empty again.
    fn accept_held(&mut self, reply: Packet) {
        self.counters.late += 1;
        self.outstanding = None;
        self.accept(reply);
    }

    /// Uses a checked reply: measured joints, and the joints whose command the controller
    /// changed (clamped at a position or speed limit).
    fn accept(&mut self, reply: Packet) {
        // In step again: the controller answered the request this step waited for.
        self.behind = None;
        self.last_used = Some(reply.c_count);
        self.counters.replies += 1;
        let joints = [
            MxtType::JointFeedback,
            MxtType::JointFiltered,
            MxtType::Joint,
        ]
        .into_iter()
        .find_map(|t| reply.find(t));
        if let Some(DataView::Joint(j)) = joints {
            for (m, v) in self.measured.iter_mut().zip(j) {
                *m = f64::from(v);
            }
            self.measured_from = Measured::Reply;
        }
        self.limit = [false; MAX_AXES];
        if let (Some(DataView::Joint(taken)), Some(sent)) =
            (reply.find(MxtType::Joint), self.commanded)
        {
            for i in 0..self.axes {
                let (t, s) = (taken[i], sent[i]);
                self.limit[i] = !(t == s || (t - s).abs() <= f32_ulp(s));
            }
        }
        self.reply = Some(reply);
    }
}

/// An R3 socket error: an expired deadline is a timeout of `waited`, anything else I/O.
fn r3_io_error(operation: Operation, waited: Duration, e: &std::io::Error) -> Error {
    if e.kind() == std::io::ErrorKind::TimedOut {
        Error::Timeout { operation, waited }
    } else {
        Error::io(operation, e)
    }
}

/// The local address the system would use to reach `server` (a connected UDP socket sends
/// nothing; connecting only picks the route).
fn route_ip(server: SocketAddr) -> std::io::Result<IpAddr> {
    let any: SocketAddr = if server.is_ipv6() {
        SocketAddr::new(IpAddr::V6(std::net::Ipv6Addr::UNSPECIFIED), 0)
    } else {
        SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0)
    };
    let probe = std::net::UdpSocket::bind(any)?;
    probe.connect(server)?;
    Ok(probe.local_addr()?.ip())
}

impl Driver for MitsubishiH7 {
    const STOP_DESCRIPTION: &'static str = "end packet sent, program stopped, servo off";
    /// The controller answers at its own 7.11 ms ticks.
    const RUNS_OWN_CYCLE: bool = true;

    fn open_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Open;
        self.connect_r3(OP)?;
        // A wildcard address would hear every interface: bind to the one that routes to
        // the controller.
        let mut local = self.config.local;
        let bound = (|| {
            if local.ip().is_unspecified() {
                local.set_ip(route_ip(self.config.server)?);
            }
            UdpLink::bind(local, self.config.server)
        })();
        let udp = bound.map_err(|e| {
            self.r3 = None;
            Error::io(OP, &e)
        })?;
        self.udp = Some(udp);
        self.reply = None;
        self.read_joint_report().inspect_err(|_| self.drop_links())
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Start;
        self.request = Packet::default();
        self.reply = None;
        self.c_count = 0;
        self.last_used = None;
        self.outstanding = None;
        self.behind = None;
        self.commanded = None;
        self.limit = [false; MAX_AXES];
        self.last_latency = None;
        let client = match self.config.client_ip {
            Some(ip) => ip,
            None => {
                let ip = self
                    .udp(OP)?
                    .local_addr()
                    .map_err(|e| Error::io(OP, &e))?
                    .ip();
                if ip.is_unspecified() {
                    route_ip(self.config.server).map_err(|e| Error::io(OP, &e))?
                } else {
                    ip
                }
            }
        };
        let mut program = [0u8; 256];
        let n = r3::write_program(&mut program, client, self.config.mode, self.config.filter)
            .map_err(|e| Error::protocol(OP, "R3 program", &e))?;
        let program = core::str::from_utf8(&program[..n])
            .unwrap_or_default()
            .to_owned();
        self.r3_command(OP, 1, "STOP")?;
        self.r3_command(OP, 1, "NEW")?;
        self.r3_command(OP, 1, &format!("LOAD={}", r3::PROGRAM_NAME))?;
        self.r3_command(OP, 9, "ECLR")?;
        for chunk in EmdatChunks::new(&program) {
            let chunk = chunk.map_err(|e| Error::protocol(OP, "R3 program", &e))?;
            self.r3_command(OP, 9, &format!("EMDAT{chunk}"))?;
        }
        self.r3_command(OP, 1, "SAVE")?;
        self.r3_command(OP, 1, "CNTLON")?;
        self.r3_command(OP, 1, "SRVON")?;
        self.r3_command(OP, 1, "CNTLOFF")?;
        self.wait_servo(OP, true)?;
        self.r3_command(OP, 1, "CNTLON")?;
        self.r3_command(OP, 1, "SLOTINIT")?;
        self.r3_command(OP, 1, &format!("RUN{};1", r3::PROGRAM_NAME))?;
        self.r3_command(OP, 1, "CNTLOFF")?;
        Ok(())
    }

    /// End packet, program stop, servo off: every step is attempted even if an earlier one
    /// failed (each is bounded by `r3_timeout` or `servo_timeout`); the first error is returned.
    fn stop_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Stop;
        let mut steps = FirstError::default();
        let end = Packet {
            command: Command::End,
            c_count: self.c_count,
            ..Packet::default()
        };
        end.encode(&mut self.tx);
        let tx = self.tx;
        let sent = self
            .udp(OP)
            .and_then(|udp| udp.send(&tx).map_err(|e| Error::io(OP, &e)));
        if sent.is_ok() {
            self.counters.sent += 1;
        }
        steps.keep(sent);
        steps.keep(self.stop_r3(|d| d.r3_command(OP, 1, "STOP")));
        // If the state cannot be read, switch the servo off anyway.
        let servo_on = match self.stop_r3(|d| d.dstate(OP)) {
            Ok(state) => state.servo_on(),
            Err(e) => {
                steps.keep(Err(e));
                true
            }
        };
        if servo_on {
            steps.keep(self.stop_r3(|d| d.r3_command(OP, 1, "SRVOFF")));
            steps.keep(self.stop_r3(|d| d.wait_servo(OP, false)));
        }
        steps.into_result()
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        self.drop_links();
        self.measured_from = Measured::None;
        Ok(())
    }

    fn period(&self) -> Duration {
        UPDATE_PERIOD
    }

    fn exchange(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Step;
        let begin = Instant::now();
        let timeout = self
            .lifecycle
            .step_budget()
            .map_or(self.config.reply_timeout, |b| {
                b.min(self.config.reply_timeout)
            });
        let deadline = begin + timeout;
        let deadline_epoch = timestamp::since_epoch().saturating_add(timeout);
        // A controller behind (requests reached it faster than it answers them, one per cycle:
        // the last step saw the reply to an earlier packet than its own) stays behind while we
        // send one packet a cycle — after its thread or the network stalled for a few cycles,
        // for good. This step then sends nothing and waits for the reply to the last request,
        // so the controller's queue drains by one a cycle; a request not answered by a reply
        // wait
        // plus the ticks the controller still needed is given up instead.
        let held = self
            .outstanding
            .filter(|_| self.behind.is_some_and(|until| begin < until))
            .map(|(c, _)| c);
        let sent = held.unwrap_or(self.c_count);
        if held.is_some() {
            // Counted here: its reply may already be waiting below.
            self.counters.held += 1;
        } else {
            let [t0, t1, t2, t3] = self.config.feedback;
            self.request.recv_type = t0;
            self.request.recv_type1 = t1;
            self.request.recv_type2 = t2;
            self.request.recv_type3 = t3;
            self.request.c_count = sent;
            self.request.encode(&mut self.tx);
        }
        // Anything from the controller still queued answers an earlier step that gave up.
        loop {
            let udp = self.udp.as_mut().ok_or(Error::State {
                operation: OP,
                state: State::Closed,
            })?;
            match udp
                .try_recv(&mut self.rx, deadline)
                .map_err(|e| Error::io(OP, &e))?
            {
                Some(n) => match self.verdict(n, sent) {
                    // The held request's reply, already here: use it.
                    Verdict::Current(reply) if held.is_some() => {
                        self.accept_held(reply);
                        return Ok(());
                    }
                    // A reply carrying the counter of the packet not sent yet is a bogus one.
                    Verdict::Current(_) => {
                        if self.config.counter_check == CounterCheck::Echo {
                            self.counters.replayed += 1;
                        } else {
                            self.counters.late += 1;
                        }
                    }
                    // Late or corrupt: counted, never used. A late reply's kernel timestamp
                    // tells how late it reached this machine; while holding, it tells how far
                    // behind the controller still is.
                    Verdict::Late(c) => {
                        self.note_late_arrival(c);
                        if held.is_some() {
                            self.note_behind(c, sent);
                        }
                    }
                    Verdict::Bad(_) => {}
                },
                None => break,
            }
        }
        let sent_at = Instant::now();
        if held.is_none() {
            let tx = self.tx;
            self.udp(OP)?.send(&tx).map_err(|e| Error::io(OP, &e))?;
            self.counters.sent += 1;
            self.c_count = self.c_count.wrapping_add(1);
            self.outstanding = Some((sent, sent_at));
            if self.request.command == Command::Move && self.request.send_type == MxtType::Joint {
                self.commanded = Some(self.request.dat.joints());
            }
            // As RL: after sending, the one-shot command and I/O fields are cleared.
            self.request.command = Command::Null;
            self.request.send_type = MxtType::Null;
            self.request.send_io_type = IoType::Null;
            self.request.recv_io_type = IoType::Null;
            self.request.bit_top = 0;
            self.request.bit_mask = 0;
            self.request.io_data = 0;
        }
        loop {
            let udp = self.udp.as_mut().ok_or(Error::State {
                operation: OP,
                state: State::Closed,
            })?;
            let Some(n) = udp
                .recv_until(&mut self.rx, deadline)
                .map_err(|e| Error::io(OP, &e))?
            else {
                self.counters.timeouts += 1;
                self.given_up[sent as usize % GIVEN_UP] = Some((sent, deadline_epoch));
                return Err(Error::Timeout {
                    operation: OP,
                    waited: timeout,
                });
            };
            // The step was waiting for this reply: the time it spent in the socket is how late
            // this thread woke up to read it.
            self.note_wait();
            match self.verdict(n, sent) {
                Verdict::Current(reply) if held.is_some() => {
                    self.accept_held(reply);
                    return Ok(());
                }
                Verdict::Current(reply) => {
                    self.last_latency = Some(sent_at.elapsed());
                    self.outstanding = None;
                    self.accept(reply);
                    return Ok(());
                }
                // The controller answered an earlier packet only now, at this cycle's tick: it
                // is behind by the packets after it, and would stay so while we send one packet
                // a cycle.
                Verdict::Late(c) => {
                    self.note_late_arrival(c);
                    self.note_behind(c, sent);
                }
                Verdict::Bad(e) => return Err(e),
            }
        }
    }
}

impl_cyclic_device!(MitsubishiH7, lifecycle);
