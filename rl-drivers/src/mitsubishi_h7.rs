//! The Mitsubishi H7 device (MELFA real-time external control): [`proto::h7`] packets over
//! [`UdpLink`] once per 7.11 ms cycle, set up and torn down with [`proto::r3`] commands over
//! [`TcpLink`].
//!
//! Session (as RL runs it, `shared/reference/mitsubishi-h7.md`):
//! - `open`: connect R3 (TCP) and bind the UDP socket.
//! - `start`: `STOP`; upload program 1432 (`NEW`, `LOAD=1432`, `ECLR`, `EMDAT`…, `SAVE`);
//!   `CNTLON`, `SRVON`, `CNTLOFF`; poll `DSTATE` until the servo is on; `CNTLON`, `SLOTINIT`,
//!   `RUN1432;1`, `CNTLOFF`.
//! - `step`: send the buffered command with the requested reply types, wait at most
//!   (filter + 6) × 7.11 ms for the reply from the controller's address.
//! - `stop`: send the end packet (command 255) without waiting, `STOP`, `DSTATE`, and if the
//!   servo is on `SRVOFF` and poll until it is off.
//! - `close`: drop both sockets.
//!
//! Differences from RL: motor pulses go into the first data block (RL writes the third, a bug);
//! a late or missing reply is a counted timeout and the next step goes on (RL throws); only
//! `max_consecutive_failures` failed steps in a row fault the device; datagrams from any other
//! address than the controller's are dropped and counted.
//!
//! [`proto::h7`]: crate::proto::h7
//! [`proto::r3`]: crate::proto::r3

use core::time::Duration;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::Instant;

use crate::capability::{
    CartesianPositionActuator, CartesianPositionSensor, Gripper, JointDevice,
    JointPositionActuator, JointPositionSensor, LinkStatistics, LinkStatisticsSensor, Pose,
};
use crate::device::{CyclicDevice, Device, Error, Lifecycle, Operation, State};
use crate::proto::h7::{
    CYCLE_US, Command, Data, DataShape, DataView, DecodeError, IoType, MAX_AXES, Mode, MxtType,
    PACKET_LEN, Packet, PoseData,
};
use crate::proto::r3::{self, DState, EmdatChunks, R3Error, Reply, Request};
use crate::transport::{TcpLink, UdpLink};
use glam::DVec3;
use rl_core::rotation::euler;

/// The controller's cycle as the device's update period.
pub const UPDATE_PERIOD: Duration = Duration::from_micros(CYCLE_US);

/// The I/O word the gripper commands are written to (RL's defaults).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GripperIo {
    /// First output bit (RL: 900).
    pub bit_top: u16,
    /// Mask (RL: 0x00FF).
    pub mask: u16,
    /// Value for halt (RL: 0xAA).
    pub halt: u16,
    /// Value for release (RL: 0xA6).
    pub release: u16,
    /// Value for shut (RL: 0xA9).
    pub shut: u16,
}

impl Default for GripperIo {
    fn default() -> Self {
        Self {
            bit_top: 900,
            mask: 0x00FF,
            halt: 0x00AA,
            release: 0x00A6,
            shut: 0x00A9,
        }
    }
}

/// How to reach and drive the controller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MitsubishiH7Config {
    /// Joints (at most 8).
    pub dof: usize,
    /// The controller's real-time UDP address (port 10000 on a real controller).
    pub server: SocketAddr,
    /// The controller's R3 TCP address (port 10001).
    pub r3: SocketAddr,
    /// Local UDP address to bind. Default: 127.0.0.1:0 when the controller is on loopback,
    /// otherwise any address (0.0.0.0:0) so the route to the controller decides.
    pub local: SocketAddr,
    /// Address written into the program's `ENET:` line (where the controller sends replies).
    /// Default: the bound local address, or, if that is unspecified, the local address of the
    /// route to the controller.
    pub client_ip: Option<IpAddr>,
    /// What the client commands (the MXT program's mode).
    pub mode: Mode,
    /// The controller's filter argument (`MXT 1,<mode>,<filter>`); the reply deadline is
    /// (filter + 6) × 7.11 ms.
    pub filter: u32,
    /// Reply types requested in `dat`, `dat1`, `dat2`, `dat3`. Default: encoder feedback of
    /// joints, pose and pulses, and current feedback. [`MitsubishiH7Config::RL_FEEDBACK`] is RL's.
    pub feedback: [MxtType; 4],
    /// Gripper I/O.
    pub gripper: GripperIo,
    /// Failed steps in a row (timeouts or bad replies) that fault the device.
    pub max_consecutive_failures: u32,
    /// Bound on each R3 exchange and on connecting.
    pub r3_timeout: Duration,
    /// Bound on waiting for the servo to switch.
    pub servo_timeout: Duration,
    /// Robot number in R3 commands.
    pub robot: u8,
}

impl MitsubishiH7Config {
    /// RL's reply types: joint, pose, pulse (commanded values) and current feedback.
    pub const RL_FEEDBACK: [MxtType; 4] = [
        MxtType::Joint,
        MxtType::Pose,
        MxtType::Pulse,
        MxtType::CurrentFeedback,
    ];

    /// Joint mode, filter 0, RL's gripper I/O, 10 failures to fault, 2 s R3 and 5 s servo bounds.
    pub fn new(dof: usize, server: SocketAddr, r3: SocketAddr) -> Self {
        Self {
            dof,
            server,
            r3,
            local: if server.ip().is_loopback() {
                SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 0)
            } else if server.is_ipv6() {
                SocketAddr::new(IpAddr::V6(std::net::Ipv6Addr::UNSPECIFIED), 0)
            } else {
                SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0)
            },
            client_ip: None,
            mode: Mode::Joint,
            filter: 0,
            feedback: [
                MxtType::JointFeedback,
                MxtType::PoseFeedback,
                MxtType::PulseFeedback,
                MxtType::CurrentFeedback,
            ],
            gripper: GripperIo::default(),
            max_consecutive_failures: 10,
            r3_timeout: Duration::from_secs(2),
            servo_timeout: Duration::from_secs(5),
            robot: 1,
        }
    }

    /// The bound on waiting for one reply: (filter + 6) × 7.11 ms.
    pub fn reply_timeout(&self) -> Duration {
        UPDATE_PERIOD * (self.filter.saturating_add(6))
    }
}

/// What happened to the real-time exchange so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct H7Counters {
    /// Packets sent (including end packets).
    pub sent: u64,
    /// Valid replies used.
    pub replies: u64,
    /// Steps without a reply before the deadline (dropped or late replies).
    pub timeouts: u64,
    /// Replies that arrived after their step had timed out (found and dropped at the next step).
    pub late: u64,
    /// Datagrams from any other address than the controller's, dropped.
    pub foreign: u64,
    /// Replies of the wrong length.
    pub wrong_length: u64,
    /// Replies that did not decode or did not hold the requested types.
    pub corrupt: u64,
    /// Current run of failed steps.
    pub consecutive_failures: u32,
}

/// A Mitsubishi controller in real-time external control mode (RL's `MitsubishiH7`).
#[derive(Debug)]
pub struct MitsubishiH7 {
    config: MitsubishiH7Config,
    lifecycle: Lifecycle,
    udp: Option<UdpLink>,
    r3: Option<TcpLink>,
    request: Packet,
    reply: Option<Packet>,
    c_count: u32,
    counters: H7Counters,
    /// Foreign datagrams counted by sockets closed since (the counts survive `close`).
    foreign_before: u64,
    tx: [u8; PACKET_LEN],
    rx: [u8; 512],
    r3_tx: [u8; 512],
    r3_rx: [u8; r3::MAX_REPLY_LEN],
}

impl MitsubishiH7 {
    /// A closed device; checks the configuration.
    pub fn new(config: MitsubishiH7Config) -> Result<Self, Error> {
        if config.dof == 0 || config.dof > MAX_AXES {
            return Err(Error::InvalidArgument {
                what: "dof (1..=8)",
                expected: MAX_AXES,
                got: config.dof,
            });
        }
        Ok(Self {
            config,
            lifecycle: Lifecycle::with_failure_limit(config.max_consecutive_failures),
            udp: None,
            r3: None,
            request: Packet::default(),
            reply: None,
            c_count: 0,
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
        Error::check_len("joint vector length", self.config.dof, len)
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
        Error::check_len("output length", self.config.dof, out.len())?;
        match self.find_shape(shape, missing)? {
            DataView::Pulse(v) | DataView::Current(v) => {
                out.copy_from_slice(&v[..self.config.dof]);
                Ok(())
            }
            _ => Err(Error::protocol(Operation::Get, "H7 packet", &missing)),
        }
    }

    fn udp(&mut self, operation: Operation) -> Result<&mut UdpLink, Error> {
        self.udp.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })
    }

    /// Sends one R3 request and returns the reply payload's length in `r3_rx` (after `QoK`).
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
        let deadline = Instant::now() + timeout;
        let link = self.r3.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })?;
        let map = |e: std::io::Error| {
            if e.kind() == std::io::ErrorKind::TimedOut {
                Error::Timeout {
                    operation,
                    waited: timeout,
                }
            } else {
                Error::io(operation, &e)
            }
        };
        link.send_all(&self.r3_tx[..n], deadline).map_err(map)?;
        // RL reads a reply with one receive; we do the same but bounded by the deadline.
        let got = link.recv(&mut self.r3_rx, deadline).map_err(map)?;
        if got == 0 {
            return Err(Error::io(
                operation,
                &std::io::ErrorKind::ConnectionAborted.into(),
            ));
        }
        match Reply::parse(&self.r3_rx[..got])
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

    fn start_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Start;
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

    fn stop_sequence(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Stop;
        let end = Packet {
            command: Command::End,
            c_count: self.c_count,
            ..Packet::default()
        };
        end.encode(&mut self.tx);
        let tx = self.tx;
        self.udp(OP)?.send(&tx).map_err(|e| Error::io(OP, &e))?;
        self.counters.sent += 1;
        self.r3_command(OP, 1, "STOP")?;
        if self.dstate(OP)?.servo_on() {
            self.r3_command(OP, 1, "SRVOFF")?;
            self.wait_servo(OP, false)?;
        }
        Ok(())
    }

    fn exchange(&mut self) -> Result<(), Error> {
        const OP: Operation = Operation::Step;
        let [t0, t1, t2, t3] = self.config.feedback;
        self.request.recv_type = t0;
        self.request.recv_type1 = t1;
        self.request.recv_type2 = t2;
        self.request.recv_type3 = t3;
        self.request.c_count = self.c_count;
        self.request.encode(&mut self.tx);
        let timeout = self.config.reply_timeout();
        let udp = self.udp.as_mut().ok_or(Error::State {
            operation: OP,
            state: State::Closed,
        })?;
        // Anything from the controller still queued answers an earlier step that timed out.
        while udp
            .try_recv(&mut self.rx)
            .map_err(|e| Error::io(OP, &e))?
            .is_some()
        {
            self.counters.late += 1;
        }
        udp.send(&self.tx).map_err(|e| Error::io(OP, &e))?;
        self.counters.sent += 1;
        self.c_count = self.c_count.wrapping_add(1);
        // As RL: after sending, the one-shot command and I/O fields are cleared.
        self.request.command = Command::Null;
        self.request.send_type = MxtType::Null;
        self.request.send_io_type = IoType::Null;
        self.request.recv_io_type = IoType::Null;
        self.request.bit_top = 0;
        self.request.bit_mask = 0;
        self.request.io_data = 0;
        let deadline = Instant::now() + timeout;
        let Some(n) = udp
            .recv_until(&mut self.rx, deadline)
            .map_err(|e| Error::io(OP, &e))?
        else {
            self.counters.timeouts += 1;
            return Err(Error::Timeout {
                operation: OP,
                waited: timeout,
            });
        };
        let reply = match Packet::decode(&self.rx[..n]) {
            Ok(p) => p,
            Err(e @ DecodeError::Length { .. }) => {
                self.counters.wrong_length += 1;
                return Err(Error::protocol(OP, "H7 packet", &e));
            }
            Err(e) => {
                self.counters.corrupt += 1;
                return Err(Error::protocol(OP, "H7 packet", &e));
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
            return Err(Error::protocol(
                OP,
                "H7 packet",
                &"reply holds other data types than requested",
            ));
        }
        self.reply = Some(reply);
        self.counters.replies += 1;
        Ok(())
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

fn lifecycle(h7: &mut MitsubishiH7) -> &mut Lifecycle {
    &mut h7.lifecycle
}

impl Device for MitsubishiH7 {
    type Error = Error;

    fn open(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Open, lifecycle, |h7| {
            const OP: Operation = Operation::Open;
            let timeout = h7.config.r3_timeout;
            let r3 = TcpLink::connect(h7.config.r3, timeout).map_err(|e| {
                if e.kind() == std::io::ErrorKind::TimedOut {
                    Error::Timeout {
                        operation: OP,
                        waited: timeout,
                    }
                } else {
                    Error::io(OP, &e)
                }
            })?;
            let udp =
                UdpLink::bind(h7.config.local, h7.config.server).map_err(|e| Error::io(OP, &e))?;
            h7.r3 = Some(r3);
            h7.udp = Some(udp);
            Ok(())
        })
    }

    fn start(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Start, lifecycle, |h7| {
            h7.request = Packet::default();
            h7.reply = None;
            h7.c_count = 0;
            h7.start_sequence()
        })
    }

    fn stop(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Stop, lifecycle, Self::stop_sequence)
    }

    fn close(&mut self) -> Result<(), Error> {
        Lifecycle::transition(self, Operation::Close, lifecycle, |h7| {
            if let Some(udp) = h7.udp.take() {
                h7.foreign_before += udp.counters().foreign;
            }
            h7.r3 = None;
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
        "end packet sent, program stopped, servo off"
    }
}

impl CyclicDevice for MitsubishiH7 {
    fn step(&mut self) -> Result<(), Error> {
        Lifecycle::step(self, lifecycle, Self::exchange)
    }

    fn update_period(&self) -> Duration {
        UPDATE_PERIOD
    }
}

impl LinkStatisticsSensor for MitsubishiH7 {
    fn link_statistics(&self) -> LinkStatistics {
        let c = self.counters();
        LinkStatistics {
            sent: c.sent,
            received: c.replies,
            lost: c.timeouts,
            late: c.late,
            rejected: c.foreign,
            corrupt: c.wrong_length + c.corrupt,
            consecutive_failures: c.consecutive_failures,
        }
    }
}

impl JointDevice for MitsubishiH7 {
    fn dof(&self) -> usize {
        self.config.dof
    }
}

impl JointPositionActuator for MitsubishiH7 {
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        self.check_command(Mode::Joint, q.len())?;
        let mut j = [0f32; MAX_AXES];
        for (d, s) in j.iter_mut().zip(q) {
            *d = *s as f32;
        }
        self.request.dat = Data::from_joints(&j);
        self.request.command = Command::Move;
        self.request.send_type = MxtType::Joint;
        Ok(())
    }
}

impl JointPositionSensor for MitsubishiH7 {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        Error::check_len("joint vector length", self.config.dof, q.len())?;
        match self.find_shape(DataShape::Joint, "no joint data in the last reply")? {
            DataView::Joint(j) => {
                for (d, s) in q.iter_mut().zip(j) {
                    *d = f64::from(s);
                }
                Ok(())
            }
            _ => Err(Error::protocol(
                Operation::Get,
                "H7 packet",
                &"no joint data in the last reply",
            )),
        }
    }

    /// Joints travel as `f32`: half a unit in the last place at `q`.
    fn joint_position_resolution(&self, q: f64) -> f64 {
        f32_half_ulp(q)
    }
}

/// Half the spacing of `f32` values at `x`: how far a value rounded to `f32` can be off.
fn f32_half_ulp(x: f64) -> f64 {
    let f = (x as f32).abs();
    if !f.is_finite() {
        return 0.0;
    }
    let next = f32::from_bits(f.to_bits() + 1);
    0.5 * f64::from(next - f)
}

impl CartesianPositionActuator for MitsubishiH7 {
    fn set_cartesian_position(&mut self, pose: &Pose) -> Result<(), Error> {
        self.check_command(Mode::Pose, self.config.dof)?;
        // Keep the arm configuration (structure flags) the controller last reported.
        let (sflg1, sflg2) = match self.find_shape(DataShape::Pose, "") {
            Ok(DataView::Pose(p)) => (p.sflg1, p.sflg2),
            _ => (0, 0),
        };
        let data = PoseData {
            xyz_mm: pose.translation.to_array().map(|v| (v * 1000.0) as f32),
            abc_rad: euler::to_zyx(&pose.rotation).map(|v| v as f32),
            additional: [0.0; 2],
            sflg1,
            sflg2,
        };
        self.request.dat = Data::from_pose(&data);
        self.request.command = Command::Move;
        self.request.send_type = MxtType::Pose;
        Ok(())
    }
}

impl CartesianPositionSensor for MitsubishiH7 {
    fn cartesian_position(&self) -> Result<Pose, Error> {
        match self.find_shape(DataShape::Pose, "no pose data in the last reply")? {
            DataView::Pose(p) => Ok(Pose::new(
                euler::from_zyx(p.abc_rad.map(f64::from)),
                DVec3::from_array(p.xyz_mm.map(|v| f64::from(v) / 1000.0)),
            )),
            _ => Err(Error::protocol(
                Operation::Get,
                "H7 packet",
                &"no pose data in the last reply",
            )),
        }
    }
}

impl Gripper for MitsubishiH7 {
    fn halt(&mut self) -> Result<(), Error> {
        let g = self.config.gripper;
        self.set_output(g.bit_top, g.mask, g.halt)
    }

    fn release(&mut self) -> Result<(), Error> {
        let g = self.config.gripper;
        self.set_output(g.bit_top, g.mask, g.release)
    }

    fn shut(&mut self) -> Result<(), Error> {
        let g = self.config.gripper;
        self.set_output(g.bit_top, g.mask, g.shut)
    }
}

#[cfg(test)]
mod tests {
    use super::f32_half_ulp;

    #[test]
    fn the_resolution_covers_the_rounding_to_f32() {
        // kinova's joint limit, as a MELFA controller would report a joint standing on it.
        let limit = 0.331_612_557_879_f64;
        let reported = f64::from(limit as f32);
        assert_ne!(reported, limit);
        assert!((reported - limit).abs() <= f32_half_ulp(limit));
        assert!(f32_half_ulp(limit) < 2e-8);
        assert_eq!(f32_half_ulp(0.0), 0.5 * f64::from(f32::from_bits(1)));
        assert_eq!(f32_half_ulp(f64::NAN), 0.0);
    }
}
