//! A fake Robotiq 2F-85/140 gripper on the wire: a Modbus RTU server on a pseudo-terminal (a
//! client opens its path as a serial port) and, at the same time if asked, a Modbus TCP
//! server, answering [`RobotiqGripper`](crate::robotiq::RobotiqGripper) and PyPI `pymodbus`.
//!
//! It behaves like the gripper where the manual (*2F-85 & 2F-140 Instruction Manual*,
//! section 4) says how (`rl-drivers/NOTES.md` lists what is not simulated):
//! - **The register map.** Functions 0x03 and 0x04 read, 0x06 and 0x10 write, 0x17 writes then
//!   reads, within the robot output (0x03E8–0x03EF) or the robot input (0x07D0–0x07D7); an
//!   address outside them is answered with exception 2, a count out of range with 3, any other
//!   function with 1. A frame with a wrong CRC or for another unit is not answered (counted);
//!   unit 0 (broadcast) acts and does not answer.
//! - **Paced like the line.** An RTU answer leaves after the request's time on the wire at the
//!   configured baud rate (8N1), the gripper's turnaround, and the answer's own time on the
//!   wire; a frame ends at the request's length or after 3.5 characters of silence (1.75 ms
//!   above 19200 baud), and bytes that never make a frame are dropped and counted.
//! - **The mechanics.** A rising edge of `rACT` activates it (`gSTA` 1, then 3 after
//!   [`FakeGripperConfig::activation_time`], the fingers open); `rGTO` moves the fingers
//!   towards `rPR` at the speed `rSP` maps to over the model's range; an object between the
//!   fingers ([`FakeGripper::set_object`]) stops them closing (`gOBJ` 2), one around them
//!   ([`FakeGripper::set_inner_object`]) stops them opening (`gOBJ` 1); the current follows
//!   motion and grip force. `rACT = 0` resets (and clears faults).
//! - **Faults.** `rGTO` without `rACT` raises 0x07, during the activation 0x05 (the action
//!   runs when it completes); a second without any request raises 0x09 (cleared by the next);
//!   the automatic release (`rATR`) raises 0x0B and ends in 0x0F; [`FakeGripper::inject_fault`]
//!   raises any (a major one stops the fingers until a reset and a rising `rACT`).
//! - **Line faults to inject**: a silent gripper, answers with a wrong CRC, garbage answers,
//!   late answers, an unplugged line (the pseudo-terminal closed), a power cycle.

mod pty;
mod sim;

pub use pty::Pty;

use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use self::sim::Sim;
use crate::proto::modbus::rtu::{self, FrameLength};
use crate::proto::modbus::tcp::{self as mbtcp, MBAP_LEN, Mbap};
use crate::proto::modbus::{ExceptionCode, MAX_PDU, ModbusError, Registers, Request, Response};
use crate::proto::robotiq::{
    COMMAND_REGISTER, Command, DEFAULT_BAUD, DEFAULT_UNIT, Fault, MAP_REGISTERS, Model,
    STATUS_REGISTER, Status,
};

/// Configuration of the fake gripper.
#[derive(Clone, Debug)]
pub struct FakeGripperConfig {
    /// Which gripper.
    pub model: Model,
    /// Its Modbus unit.
    pub unit: u8,
    /// Serve Modbus RTU on a pseudo-terminal.
    pub serial: bool,
    /// A path to link to the pseudo-terminal (as `socat`'s `link=`), e.g. `/tmp/ttyGRIPPER`.
    pub serial_link: Option<PathBuf>,
    /// The line's baud rate the answers are paced at (8N1).
    pub baud: u32,
    /// Serve Modbus TCP at this address.
    pub tcp: Option<SocketAddr>,
    /// The gripper's time from a complete request to its answer.
    pub turnaround: Duration,
    /// How long an activation takes (the real gripper opens and closes to find its stroke:
    /// seconds).
    pub activation_time: Duration,
    /// Called first on the fake's thread (to give it a real-time priority: a gripper's
    /// firmware is not delayed by the host's other programs).
    pub on_thread_start: Option<fn()>,
}

impl FakeGripperConfig {
    /// A 2F-85 at unit 9 on a pseudo-terminal at 115200 baud, activating in 1.5 s.
    pub fn serial() -> Self {
        Self {
            model: Model::TwoF85,
            unit: DEFAULT_UNIT,
            serial: true,
            serial_link: None,
            baud: DEFAULT_BAUD,
            tcp: None,
            turnaround: Duration::from_millis(1),
            activation_time: Duration::from_millis(1500),
            on_thread_start: None,
        }
    }

    /// The same on Modbus TCP at `addr` only.
    pub fn tcp(addr: SocketAddr) -> Self {
        Self {
            serial: false,
            tcp: Some(addr),
            ..Self::serial()
        }
    }
}

/// What the fake has seen and where its fingers are.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FakeGripperStatus {
    /// Requests taken (framed and for this unit).
    pub requests: u64,
    /// Answers sent.
    pub answers: u64,
    /// Exception answers sent.
    pub exceptions: u64,
    /// Broadcast requests (acted on, not answered).
    pub broadcasts: u64,
    /// Frames with a wrong CRC (not answered).
    pub crc_errors: u64,
    /// Frames for another unit (not answered).
    pub other_units: u64,
    /// Bytes that never made a frame.
    pub garbage_bytes: u64,
    /// Requests left unanswered on purpose (silent gripper).
    pub unanswered: u64,
    /// Answers sent with a wrong CRC, as garbage, or late, on purpose.
    pub spoiled: u64,
    /// TCP clients accepted.
    pub tcp_clients: u64,
    /// The gripper's status registers.
    pub status: Status,
    /// The command it took last.
    pub command: Command,
    /// The fingers' opening, m.
    pub opening_m: f64,
    /// Activations completed.
    pub activations: u64,
    /// Whether the line was unplugged.
    pub unplugged: bool,
}

/// What a test injects.
#[derive(Clone, Debug, Default)]
struct Control {
    object: Option<Option<f64>>,
    inner: Option<Option<f64>>,
    fault: Option<Fault>,
    silent: bool,
    bad_crc: u32,
    garbage: u32,
    late: u32,
    late_by: Duration,
    unplug: bool,
    power_cycle: bool,
}

struct Shared {
    stop: AtomicBool,
    control: Mutex<Control>,
    status: Mutex<FakeGripperStatus>,
}

/// A running fake gripper; its thread stops when this is dropped.
pub struct FakeGripper {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    serial_path: Option<PathBuf>,
    link: Option<PathBuf>,
    tcp_addr: Option<SocketAddr>,
}

impl FakeGripper {
    /// Opens the pseudo-terminal and the TCP server and starts the gripper's thread.
    pub fn spawn(config: FakeGripperConfig) -> io::Result<Self> {
        if config.baud == 0 {
            return Err(io::Error::new(io::ErrorKind::InvalidInput, "baud rate 0"));
        }
        let pty = if config.serial {
            Some(Pty::open()?)
        } else {
            None
        };
        let serial_path = pty.as_ref().map(|p| p.path().to_path_buf());
        let mut link = None;
        if let (Some(path), Some(target)) = (&config.serial_link, &serial_path) {
            if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
                std::fs::remove_file(path)?;
            }
            std::os::unix::fs::symlink(target, path)?;
            link = Some(path.clone());
        }
        let listener = config.tcp.map(TcpListener::bind).transpose()?;
        if let Some(l) = &listener {
            l.set_nonblocking(true)?;
        }
        let tcp_addr = listener.as_ref().map(TcpListener::local_addr).transpose()?;
        if let Some(p) = &pty {
            set_nonblocking(&p.master)?;
        }
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            control: Mutex::new(Control::default()),
            status: Mutex::new(FakeGripperStatus::default()),
        });
        let now = Instant::now();
        let line = pty.map(|p| Line {
            master: std::fs::File::from(p.master),
            _slave: p.slave,
        });
        let mut server = Server {
            sim: Sim::new(config.model, config.activation_time, now),
            config,
            line,
            rx: Vec::new(),
            last_byte: now,
            listener,
            clients: Vec::new(),
            status: FakeGripperStatus::default(),
            control: Control::default(),
        };
        let s = shared.clone();
        let thread = std::thread::Builder::new()
            .name("fake-gripper".into())
            .spawn(move || {
                if let Some(f) = server.config.on_thread_start {
                    f();
                }
                server.run(&s);
            })?;
        Ok(Self {
            shared,
            thread: Some(thread),
            serial_path,
            link,
            tcp_addr,
        })
    }

    /// The pseudo-terminal's path (open it as the serial port).
    pub fn serial_path(&self) -> Option<&Path> {
        self.serial_path.as_deref()
    }

    /// The Modbus TCP server's address.
    pub fn tcp_addr(&self) -> Option<SocketAddr> {
        self.tcp_addr
    }

    /// What the fake has seen so far.
    pub fn status(&self) -> FakeGripperStatus {
        *self.shared.status.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn control(&self, f: impl FnOnce(&mut Control)) {
        f(&mut self
            .shared
            .control
            .lock()
            .unwrap_or_else(|p| p.into_inner()));
    }

    /// An object of this width (m) between the fingers (`None`: none).
    pub fn set_object(&self, width_m: Option<f64>) {
        self.control(|c| c.object = Some(width_m));
    }

    /// An object around the fingers that stops them opening at this opening (m).
    pub fn set_inner_object(&self, width_m: Option<f64>) {
        self.control(|c| c.inner = Some(width_m));
    }

    /// Raises a fault (a major one stops the fingers until reset and reactivation).
    pub fn inject_fault(&self, fault: Fault) {
        self.control(|c| c.fault = Some(fault));
    }

    /// Answers nothing while `silent` (an unpowered gripper).
    pub fn set_silent(&self, silent: bool) {
        self.control(|c| c.silent = silent);
    }

    /// Sends the next `n` answers with a wrong CRC (RTU) .
    pub fn corrupt_answers(&self, n: u32) {
        self.control(|c| c.bad_crc += n);
    }

    /// Sends garbage instead of the next `n` answers.
    pub fn garbage_answers(&self, n: u32) {
        self.control(|c| c.garbage += n);
    }

    /// Sends the next `n` answers `by` later than they are due.
    pub fn late_answers(&self, n: u32, by: Duration) {
        self.control(|c| {
            c.late += n;
            c.late_by = by;
        });
    }

    /// Unplugs the serial line (closes the pseudo-terminal) and drops the TCP clients.
    pub fn unplug(&self) {
        self.control(|c| c.unplug = true);
    }

    /// Power lost and back: the gripper must be activated again.
    pub fn power_cycle(&self) {
        self.control(|c| c.power_cycle = true);
    }

    /// Stops the thread and waits for it (also done on drop).
    pub fn shutdown(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        if let Some(l) = self.link.take() {
            let _ = std::fs::remove_file(l);
        }
    }
}

impl Drop for FakeGripper {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn set_nonblocking(fd: &OwnedFd) -> io::Result<()> {
    use nix::fcntl::{FcntlArg, OFlag, fcntl};
    let flags = OFlag::from_bits_truncate(fcntl(fd, FcntlArg::F_GETFL)?);
    fcntl(fd, FcntlArg::F_SETFL(flags | OFlag::O_NONBLOCK))?;
    Ok(())
}

/// The pseudo-terminal as the gripper's end holds it.
struct Line {
    master: std::fs::File,
    /// Kept open so the line stays up between clients.
    _slave: OwnedFd,
}

/// A TCP client being served.
struct Client {
    stream: TcpStream,
    rx: Vec<u8>,
}

/// The gripper: its thread's state.
struct Server {
    config: FakeGripperConfig,
    sim: Sim,
    line: Option<Line>,
    rx: Vec<u8>,
    last_byte: Instant,
    listener: Option<TcpListener>,
    clients: Vec<Client>,
    status: FakeGripperStatus,
    control: Control,
}

/// What a request's handling says to send.
enum Answer {
    /// This PDU.
    Pdu(usize),
    /// Nothing (broadcast).
    None,
}

impl Server {
    fn run(&mut self, shared: &Shared) {
        while !shared.stop.load(Ordering::Relaxed) {
            self.take_control(shared);
            self.wait_input();
            let now = Instant::now();
            self.sim.advance(now);
            self.serve_serial(now);
            self.serve_tcp();
            self.publish(shared);
        }
        self.publish(shared);
    }

    fn take_control(&mut self, shared: &Shared) {
        let mut c = shared.control.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(o) = c.object.take() {
            self.sim.object_width = o;
        }
        if let Some(o) = c.inner.take() {
            self.sim.inner_width = o;
        }
        if let Some(f) = c.fault.take() {
            self.sim.inject(f);
        }
        if std::mem::take(&mut c.power_cycle) {
            self.sim.power_cycle(Instant::now());
        }
        if std::mem::take(&mut c.unplug) {
            self.line = None;
            self.clients.clear();
            self.listener = None;
            self.status.unplugged = true;
        }
        self.control.silent = c.silent;
        self.control.bad_crc += std::mem::take(&mut c.bad_crc);
        self.control.garbage += std::mem::take(&mut c.garbage);
        self.control.late += std::mem::take(&mut c.late);
        if !c.late_by.is_zero() {
            self.control.late_by = c.late_by;
        }
    }

    fn publish(&mut self, shared: &Shared) {
        let s = &mut self.status;
        s.status = self.sim.status();
        s.command =
            Command::from_registers([self.sim.output[0], self.sim.output[1], self.sim.output[2]]);
        s.opening_m = self.sim.opening(f64::from(s.status.position));
        s.activations = self.sim.activations;
        *shared.status.lock().unwrap_or_else(|p| p.into_inner()) = *s;
    }

    /// Waits up to 1 ms for a byte on the line (or a client).
    fn wait_input(&mut self) {
        match &self.line {
            Some(l) => {
                let mut fds = [PollFd::new(l.master.as_fd(), PollFlags::POLLIN)];
                let _ = poll(&mut fds, PollTimeout::from(1u8));
            }
            None => std::thread::sleep(Duration::from_millis(1)),
        }
    }

    fn gap(&self) -> Duration {
        rtu::frame_gap(self.config.baud, 10)
    }

    /// Reads what came on the line and answers each complete frame.
    fn serve_serial(&mut self, now: Instant) {
        let Some(line) = self.line.take() else {
            return;
        };
        let mut file = &line.master;
        let mut buf = [0u8; 512];
        loop {
            match file.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    self.rx.extend_from_slice(&buf[..n]);
                    self.last_byte = Instant::now();
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => break,
            }
        }
        while !self.rx.is_empty() {
            let silent_for = now.saturating_duration_since(self.last_byte);
            let len = match rtu::request_len(&self.rx) {
                FrameLength::Known(n) if self.rx.len() >= n => n,
                FrameLength::Known(n) if n > rtu::MAX_FRAME => {
                    self.status.garbage_bytes += self.rx.len() as u64;
                    self.rx.clear();
                    break;
                }
                // An unknown function: only the silence ends its frame.
                FrameLength::Unknown if silent_for >= self.gap() => self.rx.len(),
                // A frame cut short by silence is noise.
                _ if silent_for >= self.gap() => {
                    self.status.garbage_bytes += self.rx.len() as u64;
                    self.rx.clear();
                    break;
                }
                _ => break,
            };
            let frame: Vec<u8> = self.rx.drain(..len).collect();
            self.rtu_frame(&frame, &line.master);
        }
        self.line = Some(line);
    }

    fn rtu_frame(&mut self, frame: &[u8], mut line: &std::fs::File) {
        let (unit, pdu) = match rtu::decode(frame) {
            Ok(x) => x,
            Err(ModbusError::Crc { .. }) => {
                self.status.crc_errors += 1;
                return;
            }
            Err(_) => {
                self.status.garbage_bytes += frame.len() as u64;
                return;
            }
        };
        if unit != self.config.unit && unit != rtu::BROADCAST {
            self.status.other_units += 1;
            return;
        }
        let mut answer = [0u8; MAX_PDU];
        let Answer::Pdu(n) = self.request(pdu, unit == rtu::BROADCAST, &mut answer) else {
            return;
        };
        if self.control.silent {
            self.status.unanswered += 1;
            return;
        }
        let mut out = [0u8; rtu::MAX_FRAME];
        let Ok(mut len) = rtu::frame(unit, &answer[..n], &mut out) else {
            return;
        };
        let mut delay = rtu::wire_time(frame.len(), self.config.baud, 10)
            + self.config.turnaround
            + rtu::wire_time(len, self.config.baud, 10);
        if self.control.bad_crc > 0 {
            self.control.bad_crc -= 1;
            out[len - 1] ^= 0x5A;
            self.status.spoiled += 1;
        } else if self.control.garbage > 0 {
            self.control.garbage -= 1;
            // Bytes that look like nothing a master expects.
            out[..5].copy_from_slice(&[0xFF, 0x00, 0xAA, 0x55, 0x13]);
            len = 5;
            self.status.spoiled += 1;
        } else if self.control.late > 0 {
            self.control.late -= 1;
            delay += self.control.late_by;
            self.status.spoiled += 1;
        }
        std::thread::sleep(delay);
        if line.write_all(&out[..len]).is_ok() {
            self.status.answers += 1;
        }
    }

    /// Handles one request PDU; writes the answer's PDU into `out`.
    fn request(&mut self, pdu: &[u8], broadcast: bool, out: &mut [u8; MAX_PDU]) -> Answer {
        let now = Instant::now();
        self.status.requests += 1;
        if broadcast {
            self.status.broadcasts += 1;
        }
        self.sim.advance(now);
        let response = self.respond(pdu, now);
        self.sim.communicated(now);
        if broadcast {
            return Answer::None;
        }
        let mut regs = [0u16; MAP_REGISTERS as usize];
        let r = match response {
            Ok(Reply::Read(values, n)) => {
                regs[..n].copy_from_slice(&values[..n]);
                match pdu[0] {
                    0x03 => Response::ReadHoldingRegisters(Registers::Words(&regs[..n])),
                    0x04 => Response::ReadInputRegisters(Registers::Words(&regs[..n])),
                    _ => Response::ReadWriteMultipleRegisters(Registers::Words(&regs[..n])),
                }
            }
            Ok(Reply::WroteOne(address, value)) => Response::WriteSingleRegister { address, value },
            Ok(Reply::WroteMany(address, count)) => {
                Response::WriteMultipleRegisters { address, count }
            }
            Err((function, code)) => {
                self.status.exceptions += 1;
                Response::Exception { function, code }
            }
        };
        match r.encode(out) {
            Ok(n) => Answer::Pdu(n),
            Err(_) => Answer::None,
        }
    }

    /// What the gripper does with a request.
    fn respond(&mut self, pdu: &[u8], now: Instant) -> Result<Reply, (u8, ExceptionCode)> {
        let function = pdu.first().copied().unwrap_or(0);
        let request = Request::decode(pdu).map_err(|e| match e {
            ModbusError::UnsupportedFunction(f) => (f, ExceptionCode::IllegalFunction),
            _ => (function, ExceptionCode::IllegalDataValue),
        })?;
        let bad_address = (function, ExceptionCode::IllegalDataAddress);
        match request {
            Request::ReadHoldingRegisters { address, count }
            | Request::ReadInputRegisters { address, count } => {
                self.read(address, count).ok_or(bad_address)
            }
            Request::WriteSingleRegister { address, value } => {
                self.write(address, Registers::Words(&[value]), now)
                    .ok_or(bad_address)?;
                Ok(Reply::WroteOne(address, value))
            }
            Request::WriteMultipleRegisters { address, values } => {
                self.write(address, values, now).ok_or(bad_address)?;
                Ok(Reply::WroteMany(address, values.len() as u16))
            }
            Request::ReadWriteMultipleRegisters {
                read_address,
                read_count,
                write_address,
                values,
            } => {
                // Both ranges are checked before anything is written.
                self.read(read_address, read_count).ok_or(bad_address)?;
                self.write(write_address, values, now).ok_or(bad_address)?;
                // "Executes the write, one cycle of motion, updates the output, then answers."
                self.sim.advance(now);
                self.read(read_address, read_count).ok_or(bad_address)
            }
        }
    }

    /// The registers at `address` (in one of the two maps).
    fn read(&self, address: u16, count: u16) -> Option<Reply> {
        let (base, map) = if in_map(address, count, STATUS_REGISTER) {
            (STATUS_REGISTER, self.sim.input())
        } else if in_map(address, count, COMMAND_REGISTER) {
            (COMMAND_REGISTER, self.sim.output)
        } else {
            return None;
        };
        let from = usize::from(address - base);
        let mut values = [0u16; MAP_REGISTERS as usize];
        let n = usize::from(count);
        values[..n].copy_from_slice(&map[from..from + n]);
        Some(Reply::Read(values, n))
    }

    /// Writes the robot output; `None` if outside it.
    fn write(&mut self, address: u16, values: Registers<'_>, now: Instant) -> Option<()> {
        let count = u16::try_from(values.len()).ok()?;
        if !in_map(address, count, COMMAND_REGISTER) {
            return None;
        }
        let mut output = self.sim.output;
        let from = usize::from(address - COMMAND_REGISTER);
        for (k, v) in values.iter().enumerate() {
            output[from + k] = v;
        }
        self.sim.write(output, now);
        Some(())
    }

    /// Accepts TCP clients and answers their requests (after the turnaround).
    fn serve_tcp(&mut self) {
        if let Some(listener) = &self.listener {
            while let Ok((stream, _)) = listener.accept() {
                if stream.set_nonblocking(true).is_ok() {
                    let _ = stream.set_nodelay(true);
                    self.status.tcp_clients += 1;
                    self.clients.push(Client {
                        stream,
                        rx: Vec::new(),
                    });
                }
            }
        }
        let mut clients = std::mem::take(&mut self.clients);
        clients.retain_mut(|c| self.serve_client(c));
        if self.listener.is_some() {
            self.clients = clients;
        }
    }

    fn serve_client(&mut self, c: &mut Client) -> bool {
        let mut buf = [0u8; 512];
        loop {
            match c.stream.read(&mut buf) {
                Ok(0) => return false,
                Ok(n) => c.rx.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(_) => return false,
            }
        }
        while c.rx.len() >= MBAP_LEN {
            let h = match Mbap::decode(&c.rx) {
                Ok(h) => h,
                Err(_) => {
                    // The stream cannot be resynchronised.
                    self.status.garbage_bytes += c.rx.len() as u64;
                    return false;
                }
            };
            if c.rx.len() < h.frame_len() {
                break;
            }
            let frame: Vec<u8> = c.rx.drain(..h.frame_len()).collect();
            let mut answer = [0u8; MAX_PDU];
            let n = if h.unit == self.config.unit {
                match self.request(&frame[MBAP_LEN..], false, &mut answer) {
                    Answer::Pdu(n) => n,
                    Answer::None => continue,
                }
            } else {
                // As a gateway answers for a unit that is not there.
                self.status.other_units += 1;
                let e = Response::Exception {
                    function: frame[MBAP_LEN] & 0x7F,
                    code: ExceptionCode::GatewayTargetFailedToRespond,
                };
                e.encode(&mut answer).unwrap_or(0)
            };
            if self.control.silent {
                self.status.unanswered += 1;
                continue;
            }
            let mut out = [0u8; mbtcp::MAX_FRAME];
            let Ok(mut len) = mbtcp::frame(h.transaction, h.unit, &answer[..n], &mut out) else {
                continue;
            };
            let mut delay = self.config.turnaround;
            if self.control.garbage > 0 {
                self.control.garbage -= 1;
                out[2] = 0x77; // a protocol identifier that is not 0
                len = len.min(MBAP_LEN + 1);
                self.status.spoiled += 1;
            } else if self.control.late > 0 {
                self.control.late -= 1;
                delay += self.control.late_by;
                self.status.spoiled += 1;
            }
            std::thread::sleep(delay);
            if write_all(&mut c.stream, &out[..len]).is_err() {
                return false;
            }
            self.status.answers += 1;
        }
        true
    }
}

/// What a request produced.
enum Reply {
    Read([u16; MAP_REGISTERS as usize], usize),
    WroteOne(u16, u16),
    WroteMany(u16, u16),
}

/// Whether `count` registers from `address` lie within the map at `base`.
fn in_map(address: u16, count: u16, base: u16) -> bool {
    address >= base && u32::from(address) + u32::from(count) <= u32::from(base + MAP_REGISTERS)
}

fn write_all(stream: &mut TcpStream, bytes: &[u8]) -> io::Result<()> {
    super::tcp_server::write_all_within(stream, bytes, Duration::from_secs(1))
}
