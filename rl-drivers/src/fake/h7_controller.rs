//! A fake Mitsubishi H7 controller: a UDP server answering every real-time packet from a
//! simulated arm, and an R3 TCP responder that accepts the program upload, switches the servo
//! and reports `DSTATE`. Faults can be injected to test a client's error handling.
//!
//! The simulated arm: each received packet advances it by one controller cycle. A joint command
//! is clamped to the joint limits (counted as limit hits) and becomes the target; the actual
//! joints follow the target through a first-order filter with a time constant of
//! `filter_cycles` cycles, each joint's motion per cycle clamped to its speed limit. The joint
//! and speed limits are plain data ([`FakeH7Config::with_limits`],
//! [`FakeH7Config::with_speed_limits`]) so they can come from a loaded robot model. Reply type
//! 2 (joint command) reports the clamped target; types 5 and 8 (after filter, encoder feedback)
//! report the simulated joints. The fake has no kinematic model: pose replies hold the last commanded
//! pose (followed through the same filter); pulses are joints × `pulses_per_rad`; currents are a
//! synthetic `1000 %/rad × (target − actual)` clamped to ±100 %.

use std::collections::HashMap;
use std::io::{self, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::proto::h7::{
    CYCLE_US, Command, Data, DataShape, IoType, MAX_AXES, MxtType, PACKET_LEN, Packet, PoseData,
};
use crate::proto::r3::{self, DState, Request, run_bits};

const POLL: Duration = Duration::from_millis(20);

/// A fault applied to every `every`-th reply (counting received packets from 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultPlan {
    /// Period in packets (1 = every reply).
    pub every: u32,
    /// What happens to that reply.
    pub fault: Fault,
}

/// What the fake does to a faulted reply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Sends nothing.
    Drop,
    /// Sends it after this delay.
    Delay(Duration),
    /// Writes an invalid data type code (0xFFFF) into `recvType`.
    Corrupt,
    /// Sends only the first 100 bytes.
    Truncate,
    /// Sends it from another UDP port.
    ForeignPort,
}

/// Configuration of the fake controller; joint limits are plain data so they can come from a
/// loaded robot model.
#[derive(Clone, Debug, PartialEq)]
pub struct FakeH7Config {
    /// UDP address for real-time packets (port 0: any free port).
    pub udp_bind: SocketAddr,
    /// TCP address of the R3 responder; `None` runs without it.
    pub r3_bind: Option<SocketAddr>,
    /// Number of joints simulated (at most 8).
    pub dof: usize,
    /// Lower joint limits in rad.
    pub lower_rad: [f64; MAX_AXES],
    /// Upper joint limits in rad.
    pub upper_rad: [f64; MAX_AXES],
    /// Joints at power-up in rad.
    pub initial_rad: [f64; MAX_AXES],
    /// Time constant of the controller's filter in cycles (0: the arm reaches the target at once).
    pub filter_cycles: u32,
    /// Joint speed limits in rad/s (infinite: none); the filtered motion is clamped to them.
    pub max_speed_rad_s: [f64; MAX_AXES],
    /// Motor pulses per rad, for pulse replies.
    pub pulses_per_rad: f64,
    /// DSTATE polls after `SRVON` before the servo reports on (exercises a client's polling).
    pub servo_on_polls: u32,
    /// Fault injection (can be changed while running with [`FakeH7::set_fault`]).
    pub fault: Option<FaultPlan>,
}

impl FakeH7Config {
    /// A `dof`-joint arm on 127.0.0.1 with free ports for UDP and R3, limits ±π, filter 2 cycles.
    pub fn loopback(dof: usize) -> Self {
        let any: SocketAddr = SocketAddr::from(([127, 0, 0, 1], 0));
        Self {
            udp_bind: any,
            r3_bind: Some(any),
            dof,
            lower_rad: [-core::f64::consts::PI; MAX_AXES],
            upper_rad: [core::f64::consts::PI; MAX_AXES],
            initial_rad: [0.0; MAX_AXES],
            filter_cycles: 2,
            max_speed_rad_s: [f64::INFINITY; MAX_AXES],
            pulses_per_rad: 2f64.powi(20) / core::f64::consts::TAU,
            servo_on_polls: 2,
            fault: None,
        }
    }

    /// Sets the joint speed limits (rad/s) from a slice of length `dof`.
    pub fn with_speed_limits(mut self, max_speed_rad_s: &[f64]) -> io::Result<Self> {
        if max_speed_rad_s.len() != self.dof {
            return Err(invalid(format!(
                "speed limits: expected {} values, got {}",
                self.dof,
                max_speed_rad_s.len()
            )));
        }
        if let Some((i, v)) = max_speed_rad_s
            .iter()
            .enumerate()
            .find(|(_, v)| v.is_nan() || **v <= 0.0)
        {
            return Err(invalid(format!(
                "joint {i}: speed limit {v} is not positive"
            )));
        }
        self.max_speed_rad_s[..self.dof].copy_from_slice(max_speed_rad_s);
        Ok(self)
    }

    /// Sets the joint limits from slices of length `dof`.
    pub fn with_limits(mut self, lower_rad: &[f64], upper_rad: &[f64]) -> io::Result<Self> {
        if lower_rad.len() != self.dof || upper_rad.len() != self.dof {
            return Err(invalid(format!(
                "joint limits: expected {} lower and upper values, got {} and {}",
                self.dof,
                lower_rad.len(),
                upper_rad.len()
            )));
        }
        for (i, (lo, hi)) in lower_rad.iter().zip(upper_rad).enumerate() {
            if lo > hi || lo.is_nan() || hi.is_nan() {
                return Err(invalid(format!(
                    "joint {i}: lower limit {lo} above upper {hi}"
                )));
            }
        }
        self.lower_rad[..self.dof].copy_from_slice(lower_rad);
        self.upper_rad[..self.dof].copy_from_slice(upper_rad);
        Ok(self)
    }
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// What the fake has seen and where its arm is (a snapshot).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FakeH7Status {
    /// Joints simulated.
    pub dof: usize,
    /// Real-time packets received (valid or not).
    pub packets: u64,
    /// Packets that did not decode.
    pub bad_packets: u64,
    /// Packets received while no MXT program was running (R3 responder only).
    pub packets_outside_program: u64,
    /// Replies sent (including faulted ones that were still sent).
    pub replies: u64,
    /// Move commands received.
    pub moves: u64,
    /// End packets (command 255) received.
    pub ends: u64,
    /// Faults injected.
    pub faults_injected: u64,
    /// Joint commands clamped to a limit.
    pub limit_hits: u64,
    /// `cCount` of the last packet.
    pub last_c_count: u32,
    /// The last commanded joints in rad (before clamping).
    pub commanded_rad: [f64; MAX_AXES],
    /// The simulated joints in rad.
    pub actual_rad: [f64; MAX_AXES],
    /// Output words written, by `bitTop`.
    pub outputs: HashMap<u16, u16>,
    /// Servo state as reported by DSTATE.
    pub servo_on: bool,
    /// Whether the uploaded program is running.
    pub program_running: bool,
    /// The uploaded program text (lines separated by `\v`).
    pub program: String,
    /// Name given with `LOAD=`.
    pub program_name: String,
    /// Every R3 request body in order (`STOP`, `NEW`, `LOAD=1432`, ...).
    pub r3_log: Vec<String>,
    /// The last address real-time packets came from.
    pub client: Option<SocketAddr>,
}

#[derive(Debug)]
struct Shared {
    config: FakeH7Config,
    status: FakeH7Status,
    target_rad: [f64; MAX_AXES],
    pose: PoseData,
    target_pose: PoseData,
    inputs: HashMap<u16, u16>,
    frozen: bool,
    reject: Option<String>,
    control: bool,
    servo_polls_left: Option<u32>,
}

/// A running fake H7 controller; stops its threads when dropped.
#[derive(Debug)]
pub struct FakeH7 {
    shared: Arc<Mutex<Shared>>,
    stop: Arc<AtomicBool>,
    udp_addr: SocketAddr,
    r3_addr: Option<SocketAddr>,
    threads: Vec<JoinHandle<()>>,
}

fn lock(shared: &Mutex<Shared>) -> MutexGuard<'_, Shared> {
    shared
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl FakeH7 {
    /// Binds the sockets and starts the server threads.
    pub fn spawn(config: FakeH7Config) -> io::Result<FakeH7> {
        if config.dof == 0 || config.dof > MAX_AXES {
            return Err(invalid(format!(
                "dof {} outside 1..={MAX_AXES}",
                config.dof
            )));
        }
        let udp = UdpSocket::bind(config.udp_bind)?;
        udp.set_read_timeout(Some(POLL))?;
        let udp_addr = udp.local_addr()?;
        // A second socket on the same address, for replies "from another port".
        let foreign = UdpSocket::bind(SocketAddr::new(udp_addr.ip(), 0))?;
        let listener = config.r3_bind.map(TcpListener::bind).transpose()?;
        let r3_addr = listener.as_ref().map(TcpListener::local_addr).transpose()?;
        let mut status = FakeH7Status {
            dof: config.dof,
            ..FakeH7Status::default()
        };
        status.actual_rad = config.initial_rad;
        status.commanded_rad = config.initial_rad;
        let shared = Arc::new(Mutex::new(Shared {
            target_rad: config.initial_rad,
            config,
            status,
            pose: PoseData::default(),
            target_pose: PoseData::default(),
            inputs: HashMap::new(),
            frozen: false,
            reject: None,
            control: false,
            servo_polls_left: None,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let mut threads = Vec::new();
        let (s, st) = (shared.clone(), stop.clone());
        threads.push(
            std::thread::Builder::new()
                .name("fake-h7-udp".into())
                .spawn(move || serve_udp(&udp, &foreign, &s, &st))?,
        );
        if let Some(listener) = listener {
            listener.set_nonblocking(true)?;
            let (s, st) = (shared.clone(), stop.clone());
            threads.push(
                std::thread::Builder::new()
                    .name("fake-h7-r3".into())
                    .spawn(move || serve_r3(&listener, &s, &st))?,
            );
        }
        Ok(FakeH7 {
            shared,
            stop,
            udp_addr,
            r3_addr,
            threads,
        })
    }

    /// Where real-time packets go.
    pub fn udp_addr(&self) -> SocketAddr {
        self.udp_addr
    }

    /// Where the R3 responder listens (`None` if disabled); defaults to the UDP address's IP
    /// with port 0 when disabled, so callers can still build a client configuration.
    pub fn r3_addr(&self) -> SocketAddr {
        self.r3_addr
            .unwrap_or(SocketAddr::new(self.udp_addr.ip(), 0))
    }

    /// A snapshot of what the fake has seen.
    pub fn status(&self) -> FakeH7Status {
        lock(&self.shared).status.clone()
    }

    /// Changes fault injection.
    pub fn set_fault(&self, fault: Option<FaultPlan>) {
        lock(&self.shared).config.fault = fault;
    }

    /// Freezes the controller: while frozen it receives but answers nothing, neither real-time
    /// packets nor R3 requests (a hung controller; sockets stay open).
    pub fn set_frozen(&self, frozen: bool) {
        lock(&self.shared).frozen = frozen;
    }

    /// Makes the R3 responder answer `QeR4100` to every request with this command name (such as
    /// `SRVON`), as a controller in an error state would; `None` accepts everything again.
    pub fn set_r3_rejection(&self, command: Option<&str>) {
        lock(&self.shared).reject = command.map(str::to_owned);
    }

    /// Sets the input word at `bit_top` that the fake reports when asked for inputs.
    pub fn set_input(&self, bit_top: u16, value: u16) {
        lock(&self.shared).inputs.insert(bit_top, value);
    }

    /// Stops the server threads and waits for them (also done on drop).
    pub fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

impl Drop for FakeH7 {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn serve_udp(udp: &UdpSocket, foreign: &UdpSocket, shared: &Mutex<Shared>, stop: &AtomicBool) {
    let mut buf = [0u8; 1024];
    while !stop.load(Ordering::Relaxed) {
        let (n, from) = match udp.recv_from(&mut buf) {
            Ok(x) => x,
            Err(_) => continue, // timeout (to check `stop`) or a transient error
        };
        let (reply, fault) = {
            let mut s = lock(shared);
            s.status.packets += 1;
            s.status.client = Some(from);
            if s.frozen {
                continue;
            }
            match Packet::decode(&buf[..n]) {
                Ok(p) => {
                    let reply = s.handle(&p);
                    let count = s.status.packets;
                    let fault = s
                        .config
                        .fault
                        .filter(|f| f.every > 0 && count % u64::from(f.every) == 0);
                    if fault.is_some() {
                        s.status.faults_injected += 1;
                    }
                    (reply, fault)
                }
                Err(_) => {
                    s.status.bad_packets += 1;
                    (None, None)
                }
            }
        };
        let Some(reply) = reply else { continue };
        let mut bytes = reply.to_bytes();
        let mut len = PACKET_LEN;
        let mut socket = udp;
        match fault.map(|f| f.fault) {
            None => {}
            Some(Fault::Drop) => continue,
            Some(Fault::Delay(d)) => std::thread::sleep(d),
            Some(Fault::Corrupt) => bytes[4..6].copy_from_slice(&0xFFFFu16.to_le_bytes()),
            Some(Fault::Truncate) => len = 100,
            Some(Fault::ForeignPort) => socket = foreign,
        }
        if socket.send_to(&bytes[..len], from).is_ok() {
            lock(shared).status.replies += 1;
        }
    }
}

impl Shared {
    /// Applies one packet to the arm and builds the reply (`None` for an end packet).
    fn handle(&mut self, p: &Packet) -> Option<Packet> {
        let dof = self.config.dof;
        self.status.last_c_count = p.c_count;
        if self.config.r3_bind.is_some() && !self.status.program_running {
            self.status.packets_outside_program += 1;
        }
        match p.command {
            Command::End => {
                self.status.ends += 1;
                self.status.program_running = false;
                return None;
            }
            Command::Move => {
                self.status.moves += 1;
                match p.send_type.shape() {
                    DataShape::Joint => {
                        for (i, j) in p.dat.joints().into_iter().enumerate().take(dof) {
                            self.command_joint(i, f64::from(j));
                        }
                    }
                    DataShape::Pulse => {
                        let per_rad = self.config.pulses_per_rad;
                        for (i, pl) in p.dat.i32s().into_iter().enumerate().take(dof) {
                            self.command_joint(i, f64::from(pl) / per_rad);
                        }
                    }
                    DataShape::Pose => self.target_pose = p.dat.pose(),
                    DataShape::Null | DataShape::Current => {}
                }
            }
            Command::Null => {}
        }
        if p.send_io_type == IoType::Output {
            let old = self.status.outputs.get(&p.bit_top).copied().unwrap_or(0);
            let new = (old & !p.bit_mask) | (p.io_data & p.bit_mask);
            self.status.outputs.insert(p.bit_top, new);
        }
        self.advance();
        let mut reply = Packet {
            command: p.command,
            send_type: p.send_type,
            recv_io_type: p.recv_io_type,
            bit_top: p.bit_top,
            c_count: p.c_count,
            ..Packet::default()
        };
        reply.io_data = match p.recv_io_type {
            IoType::Input => self.inputs.get(&p.bit_top).copied().unwrap_or(0),
            IoType::Output => self.status.outputs.get(&p.bit_top).copied().unwrap_or(0),
            IoType::Null => 0,
        };
        let wanted = [p.recv_type, p.recv_type1, p.recv_type2, p.recv_type3];
        for ((ty, data), want) in reply.blocks_mut().into_iter().zip(wanted) {
            *ty = want;
            *data = self.data_for(want);
        }
        Some(reply)
    }

    fn command_joint(&mut self, i: usize, q: f64) {
        self.status.commanded_rad[i] = q;
        let (lo, hi) = (self.config.lower_rad[i], self.config.upper_rad[i]);
        if !(lo..=hi).contains(&q) {
            self.status.limit_hits += 1;
        }
        self.target_rad[i] = if q.is_nan() {
            self.target_rad[i]
        } else {
            q.clamp(lo, hi)
        };
    }

    fn advance(&mut self) {
        let alpha = 1.0 / (1.0 + f64::from(self.config.filter_cycles));
        let cycle_s = CYCLE_US as f64 * 1e-6;
        for i in 0..self.config.dof {
            let a = &mut self.status.actual_rad[i];
            let max_step = self.config.max_speed_rad_s[i] * cycle_s;
            *a += (alpha * (self.target_rad[i] - *a)).clamp(-max_step, max_step);
        }
        let f = |a: &mut f32, t: f32| *a += (alpha as f32) * (t - *a);
        let t = self.target_pose;
        for k in 0..3 {
            f(&mut self.pose.xyz_mm[k], t.xyz_mm[k]);
            f(&mut self.pose.abc_rad[k], t.abc_rad[k]);
        }
        for k in 0..2 {
            f(&mut self.pose.additional[k], t.additional[k]);
        }
        self.pose.sflg1 = t.sflg1;
        self.pose.sflg2 = t.sflg2;
    }

    fn data_for(&self, ty: MxtType) -> Data {
        let dof = self.config.dof;
        let pick = |v: &[f64; MAX_AXES]| -> [f32; MAX_AXES] {
            core::array::from_fn(|i| if i < dof { v[i] as f32 } else { 0.0 })
        };
        let pulses = |v: &[f64; MAX_AXES]| -> [i32; MAX_AXES] {
            core::array::from_fn(|i| {
                if i < dof {
                    (v[i] * self.config.pulses_per_rad).round() as i32
                } else {
                    0
                }
            })
        };
        match ty {
            MxtType::Null => Data::ZERO,
            MxtType::Joint => Data::from_joints(&pick(&self.target_rad)),
            MxtType::JointFiltered | MxtType::JointFeedback => {
                Data::from_joints(&pick(&self.status.actual_rad))
            }
            MxtType::Pose => Data::from_pose(&self.target_pose),
            MxtType::PoseFiltered | MxtType::PoseFeedback => Data::from_pose(&self.pose),
            MxtType::Pulse => Data::from_i32s(&pulses(&self.target_rad)),
            MxtType::PulseFiltered | MxtType::PulseFeedback => {
                Data::from_i32s(&pulses(&self.status.actual_rad))
            }
            MxtType::CurrentCommand | MxtType::CurrentFeedback => {
                Data::from_i32s(&core::array::from_fn(|i| {
                    if i < dof {
                        let e = self.target_rad[i] - self.status.actual_rad[i];
                        (1000.0 * e).clamp(-100.0, 100.0).round() as i32
                    } else {
                        0
                    }
                }))
            }
        }
    }

    /// Answers one R3 request body.
    fn r3(&mut self, req: &Request<'_>) -> String {
        self.status.r3_log.push(req.body.to_string());
        if self.reject.as_deref() == Some(req.name()) {
            return "QeR4100".into();
        }
        let args = req.args();
        match req.name() {
            "STOP" => {
                self.status.program_running = false;
                "QoK".into()
            }
            "NEW" => "QoK".into(),
            "LOAD" => {
                self.status.program_name = args.trim_start_matches('=').to_string();
                "QoK".into()
            }
            "ECLR" => {
                self.status.program.clear();
                "QoK".into()
            }
            "EMDAT" => {
                if !self.status.program.is_empty() {
                    self.status.program.push(r3::LINE_SEPARATOR);
                }
                self.status.program.push_str(args);
                "QoK".into()
            }
            "CNTLON" => {
                self.control = true;
                "QoK".into()
            }
            "CNTLOFF" => {
                self.control = false;
                "QoK".into()
            }
            "SRVON" if !self.control => "QeR4000".into(),
            "SRVON" => {
                self.servo_polls_left = Some(self.config.servo_on_polls);
                "QoK".into()
            }
            "SRVOFF" => {
                self.status.servo_on = false;
                self.servo_polls_left = None;
                "QoK".into()
            }
            "RUN" => {
                let name = args.split(';').next().unwrap_or("");
                if !self.control || !self.status.servo_on || name != self.status.program_name {
                    "QeR4001".into()
                } else {
                    self.status.program_running = true;
                    "QoK".into()
                }
            }
            "DSTATE" => {
                if let Some(left) = self.servo_polls_left {
                    if left <= 1 {
                        self.status.servo_on = true;
                        self.servo_polls_left = None;
                    } else {
                        self.servo_polls_left = Some(left - 1);
                    }
                }
                let mut run = run_bits::OPERATION_ENABLED;
                if self.status.servo_on {
                    run |= run_bits::SERVO_ON;
                }
                if self.status.program_running {
                    run |= run_bits::RUN;
                }
                let state = DState {
                    run,
                    stop: 0,
                    error_no: 0,
                    step_no: 0,
                    mech_no: 1,
                };
                let mut buf = [0u8; 64];
                match state.encode(&mut buf) {
                    Ok(n) => format!("QoK{}", String::from_utf8_lossy(&buf[..n])),
                    Err(_) => "QeR9999".into(),
                }
            }
            "ERRORMES" => format!("QoKfake controller error {args}"),
            "" => "QeR9998".into(),
            _ => "QoK".into(),
        }
    }
}

fn serve_r3(listener: &TcpListener, shared: &Mutex<Shared>, stop: &AtomicBool) {
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, _)) => serve_r3_client(stream, shared, stop),
            Err(_) => std::thread::sleep(POLL),
        }
    }
}

/// One R3 client: every receive is one request (the protocol has no terminator; clients wait
/// for each reply before the next request, as RL does).
fn serve_r3_client(mut stream: TcpStream, shared: &Mutex<Shared>, stop: &AtomicBool) {
    if stream.set_nonblocking(false).is_err() || stream.set_read_timeout(Some(POLL)).is_err() {
        return;
    }
    let _ = stream.set_nodelay(true);
    let mut buf = [0u8; 1024];
    while !stop.load(Ordering::Relaxed) {
        let n = match stream.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                continue;
            }
            Err(_) => return,
        };
        let mut s = lock(shared);
        if s.frozen {
            continue;
        }
        let reply = match Request::parse(&buf[..n]) {
            Ok(req) => s.r3(&req),
            Err(_) => "QeR9997".into(),
        };
        drop(s);
        if stream.write_all(reply.as_bytes()).is_err() {
            return;
        }
    }
}
