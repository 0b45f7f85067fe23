//! A fake Universal Robots controller (e-Series, PolyScope 5) on the wire: RTDE (TCP 30004),
//! the dashboard server (29999), the secondary interface's script port (30002: takes
//! URScript) and the real-time interface (30003: streams the state, takes URScript; 30013:
//! read only), each port configurable; answering [`UniversalRobot`](crate::ur::UniversalRobot),
//! [`UrRealtime`](crate::ur::UrRealtime), PyPI `ur-rtde` 1.6.5 (its receive and IO
//! interfaces), PyPI `urx` 0.11.0 (its real-time monitor) and anything else that speaks RTDE.
//!
//! It behaves like the controller where the RTDE guide, the dashboard server's and URScript's
//! manuals say how (`rl-drivers/NOTES.md` lists what is not simulated):
//! - **Its own 2 ms cycle.** One thread ticks at absolute 2 ms deadlines: it reads what came
//!   on every port, runs the program's share of the cycle, moves the arm, and sends each
//!   started RTDE client its output package when the client's frequency falls due (up to
//!   500 Hz: every cycle). A tick that wakes more than a cycle late does not catch up: its
//!   clock slips (counted, with the time it cost), and `timestamp` goes on in steps of 2 ms.
//! - **RTDE as the guide has it.** Protocol versions 1 and 2; the controller's version; output
//!   recipes of any known variables at 1 to 500 Hz (`NOT_FOUND` refuses the recipe), input
//!   recipes of writable variables (`IN_USE` when another client's recipe writes one),
//!   recipe ids per connection, start and pause, data packages checked against their recipe.
//!   Inputs take effect in the cycle they arrive: registers, digital outputs under their
//!   masks, the speed slider, analog outputs. Anything malformed is counted as a protocol
//!   error (the peer test asserts none).
//! - **The real-time interface.** Every client of 30003 and 30013 gets the state each cycle
//!   (500 Hz) as the real-time interface's message ([`crate::proto::ur_realtime`], 1220 bytes
//!   as PolyScope 5.9 and later send, or the length configured). The cycle never waits for a
//!   client: messages queue per client, and one that does not read loses what does not fit
//!   its queue (counted, `realtime_skipped`). Bytes sent to the read-only port are dropped
//!   (counted).
//! - **Programs.** A script on 30002 or 30003 is compiled (a subset of URScript, see the
//!   `script` module; outside it the program is refused as one that does not compile) and
//!   runs when the robot is running (powered, brakes released) and not stopped for safety;
//!   it replaces a running one. `servoj`, `speedj`, `movej`, `stopj`, `sync`, `sleep`,
//!   register reads and writes, `rtde_set_watchdog` (`ignore`, `pause`, `stop`), digital
//!   outputs. `servoj`'s lookahead smooths its commands (a first-order lag); a target that
//!   moves faster than a joint's speed limit is a protective stop.
//! - **Dashboard.** The commands of PolyScope 5's dashboard server and its answers (power,
//!   brakes, play/stop/pause of the loaded program, modes, protective stop, popups, version).
//! - **Faults to inject**: a protective stop, an emergency stop, a frozen controller (no
//!   packages), a closed RTDE connection.

mod arm;
pub(crate) mod script;

pub use arm::UrKinematics;

use std::collections::HashMap;
use std::io::{self, Read};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use self::arm::{Arm, DT};
use self::script::{Called, Cycle, Host, Runtime, Value};
use crate::fake::h7_controller::ForwardKinematics;
use crate::proto::rtde::types::{Reader, Writer};
use crate::proto::rtde::variables::{Named, REGISTERS, Var};
use crate::proto::rtde::{DataType, Message, split};

/// The dashboard server's port.
pub const DASHBOARD_PORT: u16 = 29999;
/// The secondary interface's port (takes URScript).
pub const SECONDARY_PORT: u16 = 30002;
/// The real-time interface's port (streams the state, takes URScript).
pub const REALTIME_PORT: u16 = crate::proto::ur_realtime::PORT;
/// The read-only real-time interface's port.
pub const REALTIME_READ_ONLY_PORT: u16 = crate::proto::ur_realtime::READ_ONLY_PORT;
/// Bytes a real-time client's queue holds (about 50 messages, 0.1 s) before messages are
/// skipped for it.
const REALTIME_QUEUE: usize = 64 * 1024;
/// A cycle.
pub const CYCLE: Duration = Duration::from_millis(2);

/// Robot modes (`robot_mode`).
pub mod robot_mode {
    /// No controller.
    pub const NO_CONTROLLER: i32 = -1;
    /// Powered off.
    pub const POWER_OFF: i32 = 3;
    /// Powering on.
    pub const POWER_ON: i32 = 4;
    /// Powered, brakes on.
    pub const IDLE: i32 = 5;
    /// Powered, brakes released.
    pub const RUNNING: i32 = 7;
}

/// Safety modes (`safety_mode`).
pub mod safety_mode {
    /// Normal.
    pub const NORMAL: i32 = 1;
    /// Protective stop.
    pub const PROTECTIVE_STOP: i32 = 3;
    /// Robot emergency stop (the arm's own button).
    pub const ROBOT_EMERGENCY_STOP: i32 = 7;
}

/// Runtime states (`runtime_state`).
pub mod runtime_state {
    /// Stopped.
    pub const STOPPED: u32 = 1;
    /// Playing.
    pub const PLAYING: u32 = 2;
    /// Paused.
    pub const PAUSED: u32 = 4;
}

/// Configuration of the fake controller.
#[derive(Clone, Debug)]
pub struct FakeUrConfig {
    /// The address every server binds (loopback by default).
    pub bind: IpAddr,
    /// RTDE's port (30004; 0: a free one).
    pub rtde_port: u16,
    /// The dashboard's port (29999; 0: free; `None`: none).
    pub dashboard_port: Option<u16>,
    /// Ports that take URScript only (30002, the secondary interface; 0: free).
    pub script_ports: Vec<u16>,
    /// The real-time interface's port (30003: streams the state, takes URScript; 0: free;
    /// `None`: none).
    pub realtime_port: Option<u16>,
    /// The read-only real-time interface's port (30013; 0: free; `None`: none).
    pub realtime_read_only_port: Option<u16>,
    /// The real-time message's length (one of [`crate::proto::ur_realtime::LENGTHS`]:
    /// 1220 as PolyScope 5.9 and later, 1116 as CB3's 3.10 and later …).
    pub realtime_length: usize,
    /// The arm's kinematics and speed limits.
    pub kinematics: UrKinematics,
    /// A model's forward kinematics for the tool pose instead.
    pub model: Option<ForwardKinematics>,
    /// The joints at power-up.
    pub initial_q: [f64; 6],
    /// Powered with the brakes released at start (as after an operator's start-up); else
    /// powered off, as after booting.
    pub running: bool,
    /// The version the controller reports (major, minor, bugfix, build).
    pub version: [u32; 4],
    /// Called first on the controller's thread (to give it a real-time priority).
    pub on_thread_start: Option<fn()>,
}

impl FakeUrConfig {
    /// A running UR5e on 127.0.0.1 at the controller's ports, PolyScope 5.11.
    pub fn loopback() -> Self {
        Self {
            bind: IpAddr::V4(Ipv4Addr::LOCALHOST),
            rtde_port: crate::proto::rtde::PORT,
            dashboard_port: Some(DASHBOARD_PORT),
            script_ports: vec![SECONDARY_PORT],
            realtime_port: Some(REALTIME_PORT),
            realtime_read_only_port: Some(REALTIME_READ_ONLY_PORT),
            realtime_length: crate::proto::ur_realtime::MAX_LEN,
            kinematics: UrKinematics::UR5E,
            model: None,
            initial_q: [0.0, -1.57, 1.57, -1.57, -1.57, 0.0],
            running: true,
            version: [5, 11, 0, 108_249],
            on_thread_start: None,
        }
    }

    /// The same on free ports (for tests).
    #[must_use]
    pub fn free_ports(mut self) -> Self {
        self.rtde_port = 0;
        self.dashboard_port = self.dashboard_port.map(|_| 0);
        self.script_ports = vec![0; self.script_ports.len()];
        self.realtime_port = self.realtime_port.map(|_| 0);
        self.realtime_read_only_port = self.realtime_read_only_port.map(|_| 0);
        self
    }
}

/// What the fake has seen and where its arm is.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FakeUrStatus {
    /// Cycles run.
    pub ticks: u64,
    /// Ticks that woke more than a cycle late (the fake's scheduling, not the controller's).
    pub slips: u64,
    /// The latest a tick woke after its deadline, µs.
    pub max_lateness_us: u64,
    /// The time the slips cost the fake's clock, µs: `timestamp` runs this much behind the
    /// wall clock (the sum of the slipped ticks' lateness).
    pub slipped_us: u64,
    /// RTDE connections accepted.
    pub rtde_clients: u64,
    /// RTDE packages received.
    pub rtde_packages: u64,
    /// Output packages sent.
    pub outputs_sent: u64,
    /// Real-time interface connections accepted (30003 and 30013).
    pub realtime_clients: u64,
    /// Real-time messages queued for sending.
    pub realtime_sent: u64,
    /// Real-time messages skipped for a client whose queue was full (it did not read).
    pub realtime_skipped: u64,
    /// Bytes sent to the read-only real-time port (dropped).
    pub read_only_ignored: u64,
    /// Input packages applied.
    pub inputs_applied: u64,
    /// Malformed or refused RTDE packages (unknown types, bad lengths, unknown recipes).
    pub protocol_errors: u64,
    /// The last protocol error.
    pub last_protocol_error: Option<String>,
    /// Recipes refused (`NOT_FOUND`, `IN_USE`).
    pub refused_recipes: u64,
    /// Dashboard commands answered.
    pub dashboard_commands: u64,
    /// Dashboard commands not understood.
    pub dashboard_unknown: u64,
    /// Programs received and started.
    pub programs_started: u64,
    /// Programs that did not compile, or could not start.
    pub programs_refused: u64,
    /// The last compile or runtime error.
    pub last_program_error: Option<String>,
    /// The running program's name.
    pub program: Option<String>,
    /// `servoj` calls.
    pub servoj_calls: u64,
    /// `speedj` calls.
    pub speedj_calls: u64,
    /// Watchdogs that fired.
    pub watchdog_triggers: u64,
    /// Protective stops.
    pub protective_stops: u64,
    /// Robot, safety and runtime state.
    pub robot_mode: i32,
    /// See [`safety_mode`].
    pub safety_mode: i32,
    /// See [`runtime_state`].
    pub runtime_state: u32,
    /// Measured joints.
    pub q: [f64; 6],
    /// Target joints.
    pub target_q: [f64; 6],
    /// Standard digital outputs (bits 0–7), configurable (8–15), tool (16–17).
    pub digital_outputs: u64,
    /// The speed slider.
    pub speed_slider: f64,
    /// Analog outputs (ratios as written).
    pub analog_outputs: [f64; 2],
    /// Input registers 0–47 (int and double).
    pub input_int: Vec<i32>,
    /// See [`input_int`](Self::input_int).
    pub input_double: Vec<f64>,
    /// Output registers 0–47.
    pub output_int: Vec<i32>,
}

/// What a test injects.
#[derive(Clone, Debug, Default)]
struct Control {
    protective_stop: bool,
    emergency_stop: bool,
    freeze: Option<Duration>,
    drop_rtde: bool,
    tcp_force: Option<[f64; 6]>,
    digital_inputs: Option<u64>,
}

struct Shared {
    stop: AtomicBool,
    control: Mutex<Control>,
    status: Mutex<FakeUrStatus>,
}

/// A running fake controller; its thread stops when this is dropped.
pub struct FakeUr {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    rtde: SocketAddr,
    dashboard: Option<SocketAddr>,
    scripts: Vec<SocketAddr>,
    realtime: Option<SocketAddr>,
    realtime_read_only: Option<SocketAddr>,
}

impl FakeUr {
    /// Binds the servers and starts the controller's thread.
    pub fn spawn(config: FakeUrConfig) -> io::Result<Self> {
        let listen = |port: u16| -> io::Result<TcpListener> {
            let l = TcpListener::bind((config.bind, port))?;
            l.set_nonblocking(true)?;
            Ok(l)
        };
        let rtde = listen(config.rtde_port)?;
        let dashboard = config.dashboard_port.map(listen).transpose()?;
        let scripts = config
            .script_ports
            .iter()
            .map(|p| listen(*p))
            .collect::<io::Result<Vec<_>>>()?;
        let rtde_addr = rtde.local_addr()?;
        let dashboard_addr = dashboard
            .as_ref()
            .map(TcpListener::local_addr)
            .transpose()?;
        let script_addrs = scripts
            .iter()
            .map(TcpListener::local_addr)
            .collect::<io::Result<Vec<_>>>()?;
        if !crate::proto::ur_realtime::LENGTHS.contains(&config.realtime_length) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                crate::proto::ur_realtime::RealtimeError::UnknownLength(
                    u32::try_from(config.realtime_length).unwrap_or(u32::MAX),
                ),
            ));
        }
        let realtime = config.realtime_port.map(listen).transpose()?;
        let realtime_ro = config.realtime_read_only_port.map(listen).transpose()?;
        let realtime_addr = realtime.as_ref().map(TcpListener::local_addr).transpose()?;
        let realtime_ro_addr = realtime_ro
            .as_ref()
            .map(TcpListener::local_addr)
            .transpose()?;
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            control: Mutex::new(Control::default()),
            status: Mutex::new(FakeUrStatus::default()),
        });
        let mut c = Controller::new(config, rtde, dashboard, scripts);
        c.realtime = [(realtime, false), (realtime_ro, true)]
            .into_iter()
            .filter_map(|(l, ro)| l.map(|l| (l, ro)))
            .collect();
        c.publish(&shared);
        let s = shared.clone();
        let thread = std::thread::Builder::new()
            .name("fake-ur".into())
            .spawn(move || {
                if let Some(f) = c.config.on_thread_start {
                    f();
                }
                c.run(&s);
            })?;
        Ok(Self {
            shared,
            thread: Some(thread),
            rtde: rtde_addr,
            dashboard: dashboard_addr,
            scripts: script_addrs,
            realtime: realtime_addr,
            realtime_read_only: realtime_ro_addr,
        })
    }

    /// RTDE's address.
    pub fn rtde_addr(&self) -> SocketAddr {
        self.rtde
    }

    /// The dashboard's address.
    pub fn dashboard_addr(&self) -> Option<SocketAddr> {
        self.dashboard
    }

    /// The script-only ports' addresses (the secondary interface's).
    pub fn script_addrs(&self) -> &[SocketAddr] {
        &self.scripts
    }

    /// The real-time interface's address (streams the state, takes URScript).
    pub fn realtime_addr(&self) -> Option<SocketAddr> {
        self.realtime
    }

    /// The read-only real-time interface's address.
    pub fn realtime_read_only_addr(&self) -> Option<SocketAddr> {
        self.realtime_read_only
    }

    /// What the fake has seen so far.
    pub fn status(&self) -> FakeUrStatus {
        self.shared
            .status
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone()
    }

    fn control(&self, f: impl FnOnce(&mut Control)) {
        f(&mut self
            .shared
            .control
            .lock()
            .unwrap_or_else(|p| p.into_inner()));
    }

    /// A protective stop, as a collision would raise (the program stops; the dashboard's
    /// `unlock protective stop` clears it).
    pub fn protective_stop(&self) {
        self.control(|c| c.protective_stop = true);
    }

    /// The arm's emergency stop button.
    pub fn emergency_stop(&self) {
        self.control(|c| c.emergency_stop = true);
    }

    /// The controller sends nothing for `duration` (its cycle goes on).
    pub fn freeze(&self, duration: Duration) {
        self.control(|c| c.freeze = Some(duration));
    }

    /// Closes every RTDE connection.
    pub fn drop_rtde_clients(&self) {
        self.control(|c| c.drop_rtde = true);
    }

    /// The force and torque at the tool from now on (N, N·m; `actual_TCP_force` in RTDE,
    /// "TCP force" in the real-time interface), as a contact would cause.
    pub fn set_tcp_force(&self, wrench: [f64; 6]) {
        self.control(|c| c.tcp_force = Some(wrench));
    }

    /// The digital inputs from now on (standard 0–7, configurable 8–15, tool 16–17), as the
    /// cell's wiring would set them.
    pub fn set_digital_inputs(&self, bits: u64) {
        self.control(|c| c.digital_inputs = Some(bits & 0x3_FFFF));
    }

    /// Stops the thread and waits for it (also done on drop).
    pub fn shutdown(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for FakeUr {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// An output recipe.
#[derive(Clone, Debug)]
struct Outputs {
    vars: Vec<Var>,
    every: u64,
}

/// One RTDE connection.
struct Session {
    stream: TcpStream,
    rx: Vec<u8>,
    version: u16,
    outputs: Option<Outputs>,
    /// Input recipes by id − 1 (`None`: refused).
    inputs: Vec<Option<Vec<Var>>>,
    started: bool,
    closed: bool,
}

/// A line-based client (dashboard), a script sender, or a real-time interface client.
struct TextClient {
    stream: TcpStream,
    rx: Vec<u8>,
    closed: bool,
    /// A real-time interface client: the messages queued for it.
    realtime: Option<Vec<u8>>,
    /// The read-only real-time port: what it sends is dropped.
    read_only: bool,
}

impl TextClient {
    fn new(stream: TcpStream) -> Self {
        Self {
            stream,
            rx: Vec::new(),
            closed: false,
            realtime: None,
            read_only: false,
        }
    }
}

/// A watchdog set by the program.
#[derive(Clone, Copy, Debug)]
struct Watchdog {
    var: Var,
    period_ticks: u64,
    action: WatchdogAction,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum WatchdogAction {
    Ignore,
    Pause,
    Stop,
}

/// The controller: its thread's state.
struct Controller {
    config: FakeUrConfig,
    rtde: Option<TcpListener>,
    dashboard: Option<TcpListener>,
    scripts: Vec<TcpListener>,
    /// The real-time interface's listeners (read only or not).
    realtime: Vec<(TcpListener, bool)>,
    sessions: Vec<Session>,
    dash_clients: Vec<TextClient>,
    script_clients: Vec<TextClient>,
    arm: Arm,
    robot_mode: i32,
    safety_mode: i32,
    runtime_state: u32,
    program: Option<Runtime>,
    /// The last program received (the dashboard's "loaded program").
    loaded: Option<script::Program>,
    watchdogs: Vec<Watchdog>,
    /// The tick each input variable was last written.
    updated: HashMap<Var, u64>,
    input_int: [i32; REGISTERS as usize],
    input_double: [f64; REGISTERS as usize],
    input_bits: u128,
    output_int: [i32; REGISTERS as usize],
    output_double: [f64; REGISTERS as usize],
    output_bits: u128,
    digital_out: u64,
    speed_slider: f64,
    analog_out: [f64; 2],
    analog_types: u32,
    tcp_force: [f64; 6],
    digital_in: u64,
    tick: u64,
    frozen_until: Option<Instant>,
    popup: bool,
    status: FakeUrStatus,
}

impl Controller {
    fn new(
        config: FakeUrConfig,
        rtde: TcpListener,
        dashboard: Option<TcpListener>,
        scripts: Vec<TcpListener>,
    ) -> Self {
        let arm = Arm::new(config.kinematics, config.model.clone(), config.initial_q);
        let robot_mode = if config.running {
            robot_mode::RUNNING
        } else {
            robot_mode::POWER_OFF
        };
        Self {
            config,
            rtde: Some(rtde),
            dashboard,
            scripts,
            realtime: Vec::new(),
            sessions: Vec::new(),
            dash_clients: Vec::new(),
            script_clients: Vec::new(),
            arm,
            robot_mode,
            safety_mode: safety_mode::NORMAL,
            runtime_state: runtime_state::STOPPED,
            program: None,
            loaded: None,
            watchdogs: Vec::new(),
            updated: HashMap::new(),
            input_int: [0; REGISTERS as usize],
            input_double: [0.0; REGISTERS as usize],
            input_bits: 0,
            output_int: [0; REGISTERS as usize],
            output_double: [0.0; REGISTERS as usize],
            output_bits: 0,
            digital_out: 0,
            speed_slider: 1.0,
            analog_out: [0.0; 2],
            analog_types: 0,
            tcp_force: [0.0; 6],
            digital_in: 0,
            tick: 0,
            frozen_until: None,
            popup: false,
            status: FakeUrStatus::default(),
        }
    }

    fn run(&mut self, shared: &Shared) {
        let mut next = Instant::now() + CYCLE;
        while !shared.stop.load(Ordering::Relaxed) {
            let now = Instant::now();
            if next > now {
                std::thread::sleep(next - now);
            }
            let woke = Instant::now();
            let late = woke.saturating_duration_since(next);
            self.status.max_lateness_us = self
                .status
                .max_lateness_us
                .max(u64::try_from(late.as_micros()).unwrap_or(u64::MAX));
            next += CYCLE;
            if late > CYCLE {
                next = woke + CYCLE;
                self.status.slips += 1;
                self.status.slipped_us = self
                    .status
                    .slipped_us
                    .saturating_add(u64::try_from(late.as_micros()).unwrap_or(u64::MAX));
            }
            self.take_control(shared);
            self.cycle(woke);
            self.publish(shared);
        }
        self.publish(shared);
    }

    fn take_control(&mut self, shared: &Shared) {
        let mut c = shared.control.lock().unwrap_or_else(|p| p.into_inner());
        if std::mem::take(&mut c.protective_stop) {
            self.protective_stop("injected");
        }
        if std::mem::take(&mut c.emergency_stop) {
            self.safety_mode = safety_mode::ROBOT_EMERGENCY_STOP;
            self.end_program();
            self.arm.halt();
        }
        if let Some(d) = c.freeze.take() {
            self.frozen_until = Some(Instant::now() + d);
        }
        if std::mem::take(&mut c.drop_rtde) {
            self.sessions.clear();
        }
        if let Some(w) = c.tcp_force.take() {
            self.tcp_force = w;
        }
        if let Some(b) = c.digital_inputs.take() {
            self.digital_in = b;
        }
    }

    fn publish(&mut self, shared: &Shared) {
        let s = &mut self.status;
        s.robot_mode = self.robot_mode;
        s.safety_mode = self.safety_mode;
        s.runtime_state = self.runtime_state;
        s.q = self.arm.q;
        s.target_q = self.arm.target_q;
        s.digital_outputs = self.digital_out;
        s.speed_slider = self.speed_slider;
        s.analog_outputs = self.analog_out;
        s.input_int = self.input_int.to_vec();
        s.input_double = self.input_double.to_vec();
        s.output_int = self.output_int.to_vec();
        s.program = self.program.as_ref().map(|p| p.program.name.clone());
        *shared.status.lock().unwrap_or_else(|p| p.into_inner()) = s.clone();
    }

    /// One 2 ms cycle.
    fn cycle(&mut self, now: Instant) {
        self.status.ticks += 1;
        self.accept();
        self.serve_rtde();
        self.serve_dashboard();
        self.serve_scripts();
        self.run_program();
        self.check_watchdogs();
        if let Err(j) = self.arm.advance(self.speed_slider) {
            self.protective_stop(&format!("joint {j} speed limit"));
        }
        self.tick += 1;
        let frozen = self.frozen_until.is_some_and(|t| now < t);
        if !frozen {
            self.frozen_until = None;
            self.send_outputs();
            self.send_realtime();
        }
        self.flush_realtime();
    }

    fn accept(&mut self) {
        if let Some(l) = &self.rtde {
            while let Ok((stream, _)) = l.accept() {
                if stream.set_nonblocking(true).is_ok() {
                    let _ = stream.set_nodelay(true);
                    self.status.rtde_clients += 1;
                    self.sessions.push(Session {
                        stream,
                        rx: Vec::new(),
                        version: 1,
                        outputs: None,
                        inputs: Vec::new(),
                        started: false,
                        closed: false,
                    });
                }
            }
        }
        if let Some(l) = &self.dashboard {
            while let Ok((mut stream, _)) = l.accept() {
                if stream.set_nonblocking(true).is_ok() {
                    let _ = stream.set_nodelay(true);
                    let _ = write_all(
                        &mut stream,
                        b"Connected: Universal Robots Dashboard Server\n",
                    );
                    self.dash_clients.push(TextClient::new(stream));
                }
            }
        }
        for l in &self.scripts {
            while let Ok((stream, _)) = l.accept() {
                if stream.set_nonblocking(true).is_ok() {
                    self.script_clients.push(TextClient::new(stream));
                }
            }
        }
        for (l, read_only) in &self.realtime {
            while let Ok((stream, _)) = l.accept() {
                if stream.set_nonblocking(true).is_ok() {
                    let _ = stream.set_nodelay(true);
                    // The kernel's share of a client's backlog stays near the fake's own
                    // queue (autotuned, it would grow to megabytes: seconds of the stream).
                    let _ = socket2::SockRef::from(&stream).set_send_buffer_size(REALTIME_QUEUE);
                    self.status.realtime_clients += 1;
                    self.script_clients.push(TextClient {
                        realtime: Some(Vec::new()),
                        read_only: *read_only,
                        ..TextClient::new(stream)
                    });
                }
            }
        }
    }

    fn protocol_error(&mut self, why: String) {
        self.status.protocol_errors += 1;
        self.status.last_protocol_error = Some(why);
    }

    fn serve_rtde(&mut self) {
        let mut sessions = std::mem::take(&mut self.sessions);
        for i in 0..sessions.len() {
            let s = &mut sessions[i];
            if !read_into(&mut s.stream, &mut s.rx) {
                s.closed = true;
            }
            // What the other clients' input recipes write (for `IN_USE`).
            let others: Vec<Var> = sessions
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .flat_map(|(_, s)| s.inputs.iter().flatten().flatten().copied())
                .collect();
            let s = &mut sessions[i];
            loop {
                let size = match split(&s.rx) {
                    Ok(Some((h, _, _))) => usize::from(h.size),
                    Ok(None) => break,
                    Err(e) => {
                        // The stream cannot be resynchronised.
                        self.protocol_error(format!("RTDE: {e}"));
                        s.closed = true;
                        break;
                    }
                };
                let bytes: Vec<u8> = s.rx.drain(..size).collect();
                self.status.rtde_packages += 1;
                let Ok(Some((header, payload, _))) = split(&bytes) else {
                    continue;
                };
                match Message::decode_request(header, payload, s.version) {
                    Ok(m) => self.rtde_request(s, m, &others),
                    Err(e) => self.protocol_error(format!("RTDE {:?}: {e}", header.kind as char)),
                }
            }
        }
        sessions.retain(|s| !s.closed);
        self.sessions = sessions;
    }

    /// Answers one request of session `s`.
    fn rtde_request(&mut self, s: &mut Session, m: Message<'_>, others: &[Var]) {
        let mut out = [0u8; 4096];
        let answer = match m {
            Message::RequestProtocolVersion(v) => {
                let ok = v == 1 || v == 2;
                if ok {
                    s.version = v;
                }
                Message::ProtocolVersionAccepted(ok)
            }
            Message::GetUrcontrolVersion => {
                let [major, minor, bugfix, build] = self.config.version;
                Message::UrcontrolVersion {
                    major,
                    minor,
                    bugfix,
                    build,
                }
            }
            Message::SetupOutputs { frequency, names } => {
                let mut types = String::new();
                let mut vars = Vec::new();
                let mut ok = !s.started;
                for name in names.split(',').filter(|n| !n.is_empty()) {
                    if !types.is_empty() {
                        types.push(',');
                    }
                    match Var::parse(name).filter(|v| v.direction().readable()) {
                        Some(v) => {
                            types.push_str(v.data_type().name());
                            vars.push(v);
                        }
                        None => {
                            types.push_str("NOT_FOUND");
                            ok = false;
                        }
                    }
                }
                let f = frequency.unwrap_or(500.0);
                if !(f > 0.0 && f <= 500.0) || vars.is_empty() {
                    ok = false;
                }
                if ok {
                    s.outputs = Some(Outputs {
                        vars,
                        every: (500.0 / f).round().max(1.0) as u64,
                    });
                } else {
                    self.status.refused_recipes += 1;
                }
                let answer = Message::OutputsRecipe {
                    id: (s.version >= 2).then_some(u8::from(ok)),
                    types: &types,
                };
                self.send(s, &answer, &mut out);
                return;
            }
            Message::SetupInputs { names } => {
                let mut types = String::new();
                let mut vars = Vec::new();
                let mut ok = true;
                for name in names.split(',').filter(|n| !n.is_empty()) {
                    if !types.is_empty() {
                        types.push(',');
                    }
                    match Var::parse(name).filter(|v| v.direction().writable()) {
                        Some(v) if others.contains(&v) => {
                            types.push_str("IN_USE");
                            ok = false;
                        }
                        Some(v) => {
                            types.push_str(v.data_type().name());
                            vars.push(v);
                        }
                        None => {
                            types.push_str("NOT_FOUND");
                            ok = false;
                        }
                    }
                }
                let id = if ok && !vars.is_empty() && s.inputs.len() < 255 {
                    s.inputs.push(Some(vars));
                    s.inputs.len() as u8
                } else {
                    self.status.refused_recipes += 1;
                    0
                };
                let answer = Message::InputsRecipe { id, types: &types };
                self.send(s, &answer, &mut out);
                return;
            }
            Message::Start => {
                s.started = s.outputs.is_some();
                Message::StartAccepted(s.started)
            }
            Message::Pause => {
                s.started = false;
                Message::PauseAccepted(true)
            }
            Message::Data { recipe, payload } => {
                let id = usize::from(recipe.unwrap_or(0));
                let vars = id
                    .checked_sub(1)
                    .and_then(|k| s.inputs.get(k))
                    .and_then(|r| r.as_ref());
                match vars {
                    Some(vars) => {
                        let vars = vars.clone();
                        if let Err(e) = self.apply_inputs(&vars, payload) {
                            self.protocol_error(format!("RTDE data package of recipe {id}: {e}"));
                        }
                    }
                    None => {
                        self.protocol_error(format!("RTDE data package of unknown recipe {id}"))
                    }
                }
                return;
            }
            Message::Text { .. } => return,
            other => {
                self.protocol_error(format!("RTDE: {:?} is not a request", other.package_type()));
                return;
            }
        };
        self.send(s, &answer, &mut out);
    }

    fn send(&mut self, s: &mut Session, m: &Message<'_>, out: &mut [u8]) {
        match m.encode(s.version, out) {
            Ok(n) => {
                if write_all(&mut s.stream, &out[..n]).is_err() {
                    s.closed = true;
                }
            }
            Err(e) => self.protocol_error(format!("RTDE answer: {e}")),
        }
    }

    /// Applies an input package (registers, masked outputs, slider, analog outputs).
    fn apply_inputs(&mut self, vars: &[Var], payload: &[u8]) -> Result<(), String> {
        let size: usize = vars.iter().map(|v| v.data_type().size()).sum();
        if payload.len() != size {
            return Err(format!("{} bytes, the recipe has {size}", payload.len()));
        }
        let mut r = Reader::new(payload);
        let e = |e: crate::proto::rtde::RtdeError| e.to_string();
        let mut masked: HashMap<Named, u64> = HashMap::new();
        let mut doubles: HashMap<Named, f64> = HashMap::new();
        for v in vars {
            match *v {
                Var::InputIntRegister(n) => {
                    self.input_int[usize::from(n)] = r.u32("int").map_err(e)? as i32
                }
                Var::InputDoubleRegister(n) => {
                    self.input_double[usize::from(n)] = r.f64("double").map_err(e)?
                }
                Var::InputBitRegister(n) => {
                    let b = r.u8("bool").map_err(e)? != 0;
                    self.input_bits = (self.input_bits & !(1u128 << n)) | (u128::from(b) << n);
                }
                Var::Named(n) => match v.data_type() {
                    DataType::Uint8 => {
                        masked.insert(n, u64::from(r.u8("uint8").map_err(e)?));
                    }
                    DataType::Uint32 => {
                        let x = r.u32("uint32").map_err(e)?;
                        match n {
                            Named::InputBitRegisters0To31 => {
                                self.input_bits = (self.input_bits & !0xFFFF_FFFF) | u128::from(x);
                            }
                            Named::InputBitRegisters32To63 => {
                                self.input_bits = (self.input_bits & !(0xFFFF_FFFF << 32))
                                    | (u128::from(x) << 32);
                            }
                            _ => {
                                masked.insert(n, u64::from(x));
                            }
                        }
                    }
                    DataType::Double => {
                        doubles.insert(n, r.f64("double").map_err(e)?);
                    }
                    t => {
                        r.take(t.size(), "input").map_err(e)?;
                    }
                },
                _ => return Err("an output in an input recipe".into()),
            }
            self.updated.insert(*v, self.tick);
        }
        let get = |m: &HashMap<Named, u64>, k| m.get(&k).copied();
        if let (Some(mask), Some(value)) = (
            get(&masked, Named::StandardDigitalOutputMask),
            get(&masked, Named::StandardDigitalOutput),
        ) {
            self.digital_out = (self.digital_out & !mask) | (value & mask);
        }
        if let (Some(mask), Some(value)) = (
            get(&masked, Named::ConfigurableDigitalOutputMask),
            get(&masked, Named::ConfigurableDigitalOutput),
        ) {
            self.digital_out = (self.digital_out & !(mask << 8)) | ((value & mask) << 8);
        }
        if let (Some(mask), Some(value)) = (
            get(&masked, Named::ToolDigitalOutputMask),
            get(&masked, Named::ToolDigitalOutput),
        ) {
            let (mask, value) = (mask & 3, value & 3);
            self.digital_out = (self.digital_out & !(mask << 16)) | ((value & mask) << 16);
        }
        if get(&masked, Named::SpeedSliderMask).is_some_and(|m| m & 1 != 0)
            && let Some(f) = doubles.get(&Named::SpeedSliderFraction)
        {
            self.speed_slider = f.clamp(0.0, 1.0);
        }
        if let Some(mask) = get(&masked, Named::StandardAnalogOutputMask) {
            let types = get(&masked, Named::StandardAnalogOutputType).unwrap_or(0);
            for (k, name) in [
                Named::StandardAnalogOutputInput0,
                Named::StandardAnalogOutputInput1,
            ]
            .into_iter()
            .enumerate()
            {
                if mask & (1 << k) != 0 {
                    if let Some(v) = doubles.get(&name) {
                        self.analog_out[k] = v.clamp(0.0, 1.0);
                    }
                    self.analog_types = (self.analog_types & !(1 << k)) | (types as u32 & (1 << k));
                }
            }
        }
        self.status.inputs_applied += 1;
        Ok(())
    }

    /// Sends each started session its output package when its frequency falls due.
    fn send_outputs(&mut self) {
        let mut sessions = std::mem::take(&mut self.sessions);
        let mut out = vec![0u8; 4096];
        for s in &mut sessions {
            let Some(o) = &s.outputs else { continue };
            if !s.started || self.tick % o.every != 0 {
                continue;
            }
            let mut payload = vec![0u8; 4000];
            let mut w = Writer::new(&mut payload);
            let mut ok = true;
            for v in &o.vars {
                ok &= self.write_var(*v, &mut w).is_ok();
            }
            let n = w.len();
            if !ok {
                continue;
            }
            let m = Message::Data {
                recipe: (s.version >= 2).then_some(1),
                payload: &payload[..n],
            };
            if let Ok(len) = m.encode(s.version, &mut out) {
                if write_all(&mut s.stream, &out[..len]).is_err() {
                    s.closed = true;
                } else {
                    self.status.outputs_sent += 1;
                }
            }
        }
        sessions.retain(|s| !s.closed);
        self.sessions = sessions;
    }

    /// The joints' mode: 253 running, 239 powered off, 255 idle.
    fn joint_mode(&self) -> i32 {
        if self.robot_mode == robot_mode::RUNNING {
            253
        } else if self.robot_mode == robot_mode::POWER_OFF {
            239
        } else {
            255
        }
    }

    /// The state as the real-time interface sends it. Currents, torques and speeds of the
    /// tool are not simulated (zero), as in RTDE.
    fn realtime_state(&self) -> crate::proto::ur_realtime::RealtimeState {
        let arm = &self.arm;
        let powered = self.robot_mode >= robot_mode::POWER_ON;
        crate::proto::ur_realtime::RealtimeState {
            length: self.config.realtime_length,
            time: self.tick as f64 * DT,
            q_target: arm.target_q,
            qd_target: arm.target_qd,
            qdd_target: arm.target_qdd,
            q_actual: arm.q,
            qd_actual: arm.qd,
            tool_vector_actual: arm.tcp_pose(&arm.q),
            tcp_force: self.tcp_force,
            tool_vector_target: arm.tcp_pose(&arm.target_q),
            digital_input_bits: self.digital_in,
            motor_temperatures: [32.0; 6],
            robot_mode: self.robot_mode,
            joint_modes: [self.joint_mode(); 6],
            safety_mode: self.safety_mode,
            speed_scaling: self.speed_slider,
            v_main: if powered { 48.0 } else { 0.0 },
            v_robot: if powered { 48.0 } else { 0.0 },
            digital_outputs: self.digital_out,
            program_state: self.runtime_state as i32,
            safety_status: self.safety_mode,
            ..Default::default()
        }
    }

    /// Queues this cycle's real-time message for every real-time client (a full queue skips
    /// it for that client).
    fn send_realtime(&mut self) {
        if !self.script_clients.iter().any(|c| c.realtime.is_some()) {
            return;
        }
        let mut message = [0u8; crate::proto::ur_realtime::MAX_LEN];
        let Ok(n) = self
            .realtime_state()
            .encode(self.config.realtime_length, &mut message)
        else {
            return;
        };
        for c in &mut self.script_clients {
            let Some(queue) = c.realtime.as_mut() else {
                continue;
            };
            if queue.len() + n > REALTIME_QUEUE {
                self.status.realtime_skipped += 1;
            } else {
                queue.extend_from_slice(&message[..n]);
                self.status.realtime_sent += 1;
            }
        }
    }

    /// Writes what the real-time clients' queues hold, as far as their sockets take it now.
    fn flush_realtime(&mut self) {
        for c in &mut self.script_clients {
            let Some(queue) = c.realtime.as_mut() else {
                continue;
            };
            while !queue.is_empty() {
                match io::Write::write(&mut c.stream, queue) {
                    Ok(0) => {
                        c.closed = true;
                        break;
                    }
                    Ok(k) => {
                        queue.drain(..k);
                    }
                    Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(_) => {
                        c.closed = true;
                        break;
                    }
                }
            }
        }
        self.script_clients.retain(|c| !c.closed);
    }

    fn robot_status_bits(&self) -> u32 {
        let powered = matches!(
            self.robot_mode,
            robot_mode::POWER_ON | robot_mode::IDLE | robot_mode::RUNNING
        );
        u32::from(powered) | (u32::from(self.runtime_state == runtime_state::PLAYING) << 1)
    }

    fn safety_status_bits(&self) -> u32 {
        match self.safety_mode {
            safety_mode::NORMAL => 1,
            safety_mode::PROTECTIVE_STOP => 1 << 2,
            safety_mode::ROBOT_EMERGENCY_STOP => (1 << 6) | (1 << 7),
            _ => 0,
        }
    }

    /// Writes one output variable's value now.
    fn write_var(&self, v: Var, w: &mut Writer<'_>) -> Result<(), crate::proto::rtde::RtdeError> {
        let six = |w: &mut Writer<'_>, x: [f64; 6]| -> Result<(), crate::proto::rtde::RtdeError> {
            for v in x {
                w.f64(v)?;
            }
            Ok(())
        };
        let arm = &self.arm;
        match v {
            Var::OutputIntRegister(n) => w.i32(self.output_int[usize::from(n)]),
            Var::OutputDoubleRegister(n) => w.f64(self.output_double[usize::from(n)]),
            Var::OutputBitRegister(n) => w.u8(u8::from(self.output_bits & (1u128 << n) != 0)),
            Var::InputIntRegister(n) => w.i32(self.input_int[usize::from(n)]),
            Var::InputDoubleRegister(n) => w.f64(self.input_double[usize::from(n)]),
            Var::InputBitRegister(n) => w.u8(u8::from(self.input_bits & (1u128 << n) != 0)),
            Var::Named(n) => {
                match n {
                    Named::Timestamp => w.f64(self.tick as f64 * DT),
                    Named::TargetQ => six(w, arm.target_q),
                    Named::TargetQd => six(w, arm.target_qd),
                    Named::TargetQdd => six(w, arm.target_qdd),
                    Named::ActualQ => six(w, arm.q),
                    Named::ActualTcpForce => six(w, self.tcp_force),
                    Named::ActualDigitalInputBits => w.u64(self.digital_in),
                    Named::ActualQd => six(w, arm.qd),
                    Named::ActualTcpPose => six(w, arm.tcp_pose(&arm.q)),
                    Named::TargetTcpPose => six(w, arm.tcp_pose(&arm.target_q)),
                    Named::JointTemperatures => six(w, [32.0; 6]),
                    Named::RobotMode => w.i32(self.robot_mode),
                    Named::JointMode => {
                        let m = self.joint_mode();
                        (0..6).try_for_each(|_| w.i32(m))
                    }
                    Named::SafetyMode | Named::SafetyStatus => w.i32(self.safety_mode),
                    Named::SpeedScaling | Named::TargetSpeedFraction => w.f64(self.speed_slider),
                    Named::ActualMainVoltage | Named::ActualRobotVoltage => {
                        w.f64(if self.robot_mode >= robot_mode::POWER_ON {
                            48.0
                        } else {
                            0.0
                        })
                    }
                    Named::ActualDigitalOutputBits => w.u64(self.digital_out),
                    Named::ActualConfigurableDigitalOutputBits => {
                        w.u64(self.digital_out >> 8 & 0xFF)
                    }
                    Named::RuntimeState => w.u32(self.runtime_state),
                    Named::RobotStatusBits => w.u32(self.robot_status_bits()),
                    Named::SafetyStatusBits => w.u32(self.safety_status_bits()),
                    Named::AnalogIoTypes => w.u32(self.analog_types << 2),
                    Named::StandardAnalogOutput0 => {
                        w.f64(analog(self.analog_out[0], self.analog_types & 1 != 0))
                    }
                    Named::StandardAnalogOutput1 => {
                        w.f64(analog(self.analog_out[1], self.analog_types & 2 != 0))
                    }
                    Named::OutputBitRegisters0To31 => w.u32(self.output_bits as u32),
                    Named::OutputBitRegisters32To63 => w.u32((self.output_bits >> 32) as u32),
                    Named::InputBitRegisters0To31 => w.u32(self.input_bits as u32),
                    Named::InputBitRegisters32To63 => w.u32((self.input_bits >> 32) as u32),
                    Named::ToolOutputVoltage => w.i32(24),
                    Named::ControlStep => w.u64(self.tick),
                    Named::ActualExecutionTime => w.f64(0.1),
                    Named::TargetExecutionTime => w.f64(0.1),
                    Named::ToolTemperature => w.f64(35.0),
                    Named::Payload => w.f64(0.0),
                    Named::TargetGravity => {
                        w.f64(0.0)?;
                        w.f64(0.0)?;
                        w.f64(-9.82)
                    }
                    _ => {
                        // Everything else the fake does not simulate: zero of its type.
                        let size = Var::Named(n).data_type().size();
                        w.put(&[0u8; 48][..size])
                    }
                }
            }
        }
    }
}

/// An analog output's value from its ratio: 0–10 V, or 0–20 mA.
fn analog(ratio: f64, voltage: bool) -> f64 {
    if voltage { 10.0 * ratio } else { 0.020 * ratio }
}

impl Controller {
    fn protective_stop(&mut self, why: &str) {
        if self.safety_mode == safety_mode::NORMAL {
            self.safety_mode = safety_mode::PROTECTIVE_STOP;
            self.status.protective_stops += 1;
            self.status.last_program_error = Some(format!("protective stop: {why}"));
        }
        self.end_program();
        self.arm.halt();
    }

    fn end_program(&mut self) {
        self.program = None;
        self.watchdogs.clear();
        self.runtime_state = runtime_state::STOPPED;
    }

    fn can_run(&self) -> bool {
        self.robot_mode == robot_mode::RUNNING && self.safety_mode == safety_mode::NORMAL
    }

    fn start_program(&mut self, program: script::Program) {
        self.loaded = Some(program.clone());
        if !self.can_run() {
            self.status.programs_refused += 1;
            self.status.last_program_error = Some(format!(
                "program {} not started: robot mode {}, safety mode {}",
                program.name, self.robot_mode, self.safety_mode
            ));
            return;
        }
        self.watchdogs.clear();
        self.arm.halt();
        self.program = Some(Runtime::new(program));
        self.runtime_state = runtime_state::PLAYING;
        self.status.programs_started += 1;
    }

    fn run_program(&mut self) {
        if self.runtime_state != runtime_state::PLAYING {
            return;
        }
        let Some(mut rt) = self.program.take() else {
            self.runtime_state = runtime_state::STOPPED;
            return;
        };
        match rt.cycle(self) {
            Cycle::Running => {
                if self.runtime_state == runtime_state::PLAYING
                    || self.runtime_state == runtime_state::PAUSED
                {
                    self.program = Some(rt);
                }
            }
            Cycle::Finished => {
                self.end_program();
                self.arm.halt();
            }
            Cycle::Failed(line, why) => {
                self.status.last_program_error =
                    Some(format!("runtime error on line {line}: {why}"));
                self.end_program();
                self.arm.halt();
            }
        }
    }

    fn check_watchdogs(&mut self) {
        if self.runtime_state != runtime_state::PLAYING {
            return;
        }
        for w in self.watchdogs.clone() {
            let last = self.updated.get(&w.var).copied().unwrap_or(0);
            if self.tick.saturating_sub(last) > w.period_ticks {
                self.status.watchdog_triggers += 1;
                match w.action {
                    WatchdogAction::Ignore => {
                        self.updated.insert(w.var, self.tick);
                    }
                    WatchdogAction::Pause => {
                        self.runtime_state = runtime_state::PAUSED;
                        self.arm.stop(4.0);
                        return;
                    }
                    WatchdogAction::Stop => {
                        self.end_program();
                        self.arm.stop(4.0);
                        return;
                    }
                }
            }
        }
    }

    fn serve_dashboard(&mut self) {
        let mut clients = std::mem::take(&mut self.dash_clients);
        for c in &mut clients {
            if !read_into(&mut c.stream, &mut c.rx) {
                c.closed = true;
            }
            while let Some(end) = c.rx.iter().position(|b| *b == b'\n') {
                let line: Vec<u8> = c.rx.drain(..=end).collect();
                let command = String::from_utf8_lossy(&line).trim().to_owned();
                let (answer, quit) = self.dashboard(&command);
                self.status.dashboard_commands += 1;
                if write_all(&mut c.stream, format!("{answer}\n").as_bytes()).is_err() || quit {
                    c.closed = true;
                    break;
                }
            }
        }
        clients.retain(|c| !c.closed);
        self.dash_clients = clients;
    }

    /// PolyScope 5's dashboard server: one command, one answer.
    fn dashboard(&mut self, command: &str) -> (String, bool) {
        let mode_name = |m: i32| match m {
            robot_mode::POWER_OFF => "POWER_OFF",
            robot_mode::POWER_ON => "POWER_ON",
            robot_mode::IDLE => "IDLE",
            robot_mode::RUNNING => "RUNNING",
            _ => "NO_CONTROLLER",
        };
        let safety_name = |m: i32| match m {
            safety_mode::NORMAL => "NORMAL",
            safety_mode::PROTECTIVE_STOP => "PROTECTIVE_STOP",
            safety_mode::ROBOT_EMERGENCY_STOP => "ROBOT_EMERGENCY_STOP",
            _ => "FAULT",
        };
        let name = self
            .loaded
            .as_ref()
            .map_or_else(String::new, |p| format!("{}.urp", p.name));
        let lower = command.to_ascii_lowercase();
        let a = match lower.as_str() {
            "quit" => return ("Disconnected".into(), true),
            "power on" => {
                if self.robot_mode == robot_mode::POWER_OFF {
                    self.robot_mode = robot_mode::IDLE;
                }
                "Powering on".into()
            }
            "power off" => {
                self.end_program();
                self.arm.halt();
                self.robot_mode = robot_mode::POWER_OFF;
                "Powering off".into()
            }
            "brake release" => {
                if self.robot_mode == robot_mode::IDLE {
                    self.robot_mode = robot_mode::RUNNING;
                }
                "Brake releasing".into()
            }
            "play" => match self.loaded.clone() {
                Some(p) if self.can_run() && self.runtime_state != runtime_state::PLAYING => {
                    if self.runtime_state == runtime_state::PAUSED && self.program.is_some() {
                        self.runtime_state = runtime_state::PLAYING;
                    } else {
                        self.start_program(p);
                    }
                    "Starting program".into()
                }
                _ => "Failed to execute: play".into(),
            },
            "stop" => {
                if self.runtime_state == runtime_state::STOPPED {
                    "Failed to execute: stop".into()
                } else {
                    self.end_program();
                    self.arm.stop(4.0);
                    "Stopped".into()
                }
            }
            "pause" => {
                if self.runtime_state == runtime_state::PLAYING {
                    self.runtime_state = runtime_state::PAUSED;
                    self.arm.stop(4.0);
                    "Pausing program".into()
                } else {
                    "Failed to execute: pause".into()
                }
            }
            "running" => format!(
                "Program running: {}",
                self.runtime_state == runtime_state::PLAYING
            ),
            "robotmode" => format!("Robotmode: {}", mode_name(self.robot_mode)),
            "safetymode" => format!("Safetymode: {}", safety_name(self.safety_mode)),
            "safetystatus" => format!("Safetystatus: {}", safety_name(self.safety_mode)),
            "programstate" => {
                let state = match self.runtime_state {
                    runtime_state::PLAYING => "PLAYING",
                    runtime_state::PAUSED => "PAUSED",
                    _ => "STOPPED",
                };
                format!("{state} {name}")
            }
            "get loaded program" => {
                if name.is_empty() {
                    "No program loaded".into()
                } else {
                    format!("Loaded program: /programs/{name}")
                }
            }
            "unlock protective stop" => {
                if self.safety_mode == safety_mode::PROTECTIVE_STOP {
                    self.safety_mode = safety_mode::NORMAL;
                    "Protective stop releasing".into()
                } else {
                    "Cannot unlock protective stop until 5s after occurrence. Always inspect cause of protective stop before unlocking".into()
                }
            }
            "close safety popup" => "closing safety popup".into(),
            "close popup" => {
                self.popup = false;
                "closing popup".into()
            }
            "restart safety" => {
                self.safety_mode = safety_mode::NORMAL;
                self.robot_mode = robot_mode::POWER_OFF;
                "Restarting safety".into()
            }
            "is in remote control" => "true".into(),
            "isprogramsaved" => format!("true {name}"),
            "polyscopeversion" => {
                let [a, b, c, d] = self.config.version;
                format!("URSoftware {a}.{b}.{c}.{d} (fake)")
            }
            "version" => {
                let [a, b, c, d] = self.config.version;
                format!("{a}.{b}.{c}.{d}")
            }
            "get robot model" => self.config.kinematics.name.trim_end_matches('e').to_owned(),
            "get serial number" => "20000000000".into(),
            "shutdown" => "Shutting down".into(),
            _ if lower.starts_with("load ") => format!("File not found: {}", &command[5..]),
            _ if lower.starts_with("popup ") => {
                self.popup = true;
                "showing popup".into()
            }
            _ if lower.starts_with("addtolog ") => "Added log message".into(),
            _ => {
                self.status.dashboard_unknown += 1;
                format!("could not understand: '{command}'")
            }
        };
        (a, false)
    }

    fn serve_scripts(&mut self) {
        let mut clients = std::mem::take(&mut self.script_clients);
        let mut programs = Vec::new();
        for c in &mut clients {
            if !read_into(&mut c.stream, &mut c.rx) {
                c.closed = true;
            }
            if c.read_only {
                self.status.read_only_ignored += c.rx.len() as u64;
                c.rx.clear();
                continue;
            }
            if c.rx.is_empty() || !(c.rx.ends_with(b"\n") || c.closed) {
                continue;
            }
            let text = String::from_utf8_lossy(&c.rx).into_owned();
            match script::compile(&text, &|n| known_function(n)) {
                Ok(p) => {
                    programs.push(p);
                    c.rx.clear();
                }
                // An open block: more text is on its way (or never comes: dropped at close).
                Err(e) if e.message.ends_with("has no `end`") && !c.closed => {}
                Err(e) => {
                    self.status.programs_refused += 1;
                    self.status.last_program_error = Some(e.to_string());
                    c.rx.clear();
                }
            }
        }
        clients.retain(|c| !c.closed);
        self.script_clients = clients;
        for p in programs {
            self.start_program(p);
        }
    }
}

/// The functions the fake's URScript knows.
fn known_function(name: &str) -> bool {
    matches!(
        name,
        "servoj"
            | "speedj"
            | "movej"
            | "stopj"
            | "sync"
            | "sleep"
            | "textmsg"
            | "popup"
            | "get_actual_joint_positions"
            | "get_target_joint_positions"
            | "get_actual_joint_speeds"
            | "get_actual_tcp_pose"
            | "get_target_tcp_pose"
            | "read_input_float_register"
            | "read_input_integer_register"
            | "read_input_boolean_register"
            | "write_output_float_register"
            | "write_output_integer_register"
            | "write_output_boolean_register"
            | "rtde_set_watchdog"
            | "set_standard_digital_out"
            | "get_standard_digital_out"
            | "get_standard_digital_in"
    )
}

/// An argument: the `k`th positional one or the one named `name`, else `default`.
fn arg<'v>(
    args: &'v [Value],
    named: &'v [(String, Value)],
    k: usize,
    name: &str,
) -> Option<&'v Value> {
    named
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| v)
        .or_else(|| args.get(k))
}

fn number(v: Option<&Value>, default: f64, what: &str) -> Result<f64, String> {
    match v {
        None => Ok(default),
        Some(v) => v
            .as_f64()
            .ok_or_else(|| format!("{what}: {v} is not a number")),
    }
}

fn register(v: Option<&Value>, lo: i64, hi: i64) -> Result<usize, String> {
    let n = v
        .and_then(Value::as_i64)
        .ok_or_else(|| "a register number is needed".to_owned())?;
    if !(lo..=hi).contains(&n) {
        return Err(format!("register {n} outside {lo} to {hi}"));
    }
    Ok(n as usize)
}

fn joints(v: Option<&Value>, what: &str) -> Result<[f64; 6], String> {
    v.and_then(Value::as_six)
        .ok_or_else(|| format!("{what}: six numbers are needed"))
}

/// Cycles a time takes (at least one).
fn cycles(t: f64) -> u32 {
    ((t / DT).round() as u32).max(1)
}

impl Host for Controller {
    fn call(
        &mut self,
        name: &str,
        args: &[Value],
        named: &[(String, Value)],
    ) -> Result<Called, String> {
        let a = |k, n| arg(args, named, k, n);
        Ok(match name {
            "servoj" => {
                let q = joints(a(0, "q"), "servoj")?;
                let t = number(a(3, "t"), 0.002, "servoj t")?;
                let lookahead = number(a(4, "lookahead_time"), 0.1, "servoj lookahead_time")?;
                self.status.servoj_calls += 1;
                self.arm.servo(q, lookahead);
                Called::Cycles(cycles(t))
            }
            "speedj" => {
                let qd = joints(a(0, "qd"), "speedj")?;
                let acc = number(a(1, "a"), 1.4, "speedj a")?;
                let t = number(a(2, "t"), 0.002, "speedj t")?;
                self.status.speedj_calls += 1;
                self.arm.speed(qd, acc);
                Called::Cycles(cycles(t))
            }
            "movej" => {
                let q = joints(a(0, "q"), "movej")?;
                let v = number(a(2, "v"), 1.05, "movej v")?;
                self.arm.move_to(q, v);
                Called::Motion
            }
            "stopj" => {
                let acc = number(a(0, "a"), 1.4, "stopj a")?;
                self.arm.stop(acc);
                Called::Motion
            }
            "sync" => Called::Cycles(1),
            "sleep" => Called::Cycles(cycles(number(a(0, "t"), 0.0, "sleep")?)),
            "textmsg" | "popup" => Called::Value(Value::Bool(true)),
            "get_actual_joint_positions" => Called::Value(Value::six(self.arm.q)),
            "get_target_joint_positions" => Called::Value(Value::six(self.arm.target_q)),
            "get_actual_joint_speeds" => Called::Value(Value::six(self.arm.qd)),
            "get_actual_tcp_pose" => Called::Value(Value::six(self.arm.tcp_pose(&self.arm.q))),
            "get_target_tcp_pose" => {
                Called::Value(Value::six(self.arm.tcp_pose(&self.arm.target_q)))
            }
            "read_input_float_register" => Called::Value(Value::Float(
                self.input_double[register(a(0, "address"), 0, 47)?],
            )),
            "read_input_integer_register" => Called::Value(Value::Int(i64::from(
                self.input_int[register(a(0, "address"), 0, 47)?],
            ))),
            "read_input_boolean_register" => {
                let n = register(a(0, "address"), 0, 127)?;
                Called::Value(Value::Bool(self.input_bits & (1u128 << n) != 0))
            }
            "write_output_float_register" => {
                let n = register(a(0, "address"), 0, 47)?;
                self.output_double[n] = number(a(1, "value"), 0.0, "value")?;
                Called::Value(Value::Bool(true))
            }
            "write_output_integer_register" => {
                let n = register(a(0, "address"), 0, 47)?;
                let v = a(1, "value")
                    .and_then(Value::as_i64)
                    .ok_or_else(|| "an integer value is needed".to_owned())?;
                self.output_int[n] =
                    i32::try_from(v).map_err(|_| format!("{v} is not a 32-bit integer"))?;
                Called::Value(Value::Bool(true))
            }
            "write_output_boolean_register" => {
                let n = register(a(0, "address"), 0, 127)?;
                let b = a(1, "value")
                    .ok_or_else(|| "a value is needed".to_owned())?
                    .truthy()?;
                self.output_bits = (self.output_bits & !(1u128 << n)) | (u128::from(b) << n);
                Called::Value(Value::Bool(true))
            }
            "set_standard_digital_out" => {
                let n = register(a(0, "n"), 0, 7)?;
                let b = a(1, "b")
                    .ok_or_else(|| "a value is needed".to_owned())?
                    .truthy()?;
                self.digital_out = (self.digital_out & !(1 << n)) | (u64::from(b) << n);
                Called::Value(Value::Bool(true))
            }
            "get_standard_digital_out" => {
                let n = register(a(0, "n"), 0, 7)?;
                Called::Value(Value::Bool(self.digital_out & (1 << n) != 0))
            }
            "get_standard_digital_in" => Called::Value(Value::Bool(false)),
            "rtde_set_watchdog" => {
                let Some(Value::Str(var)) = a(0, "variable_name") else {
                    return Err("rtde_set_watchdog: a variable name is needed".into());
                };
                let var = Var::parse(var)
                    .filter(|v| v.direction().writable())
                    .ok_or_else(|| format!("rtde_set_watchdog: {var} is not an RTDE input"))?;
                let f = number(a(1, "min_frequency"), 1.0, "min_frequency")?;
                if f <= 0.0 {
                    return Err("rtde_set_watchdog: min_frequency must be positive".into());
                }
                let action = match a(2, "action") {
                    None => WatchdogAction::Pause,
                    Some(Value::Str(s)) if s == "ignore" => WatchdogAction::Ignore,
                    Some(Value::Str(s)) if s == "pause" => WatchdogAction::Pause,
                    Some(Value::Str(s)) if s == "stop" => WatchdogAction::Stop,
                    Some(other) => return Err(format!("rtde_set_watchdog: action {other}")),
                };
                self.watchdogs.retain(|w| w.var != var);
                self.watchdogs.push(Watchdog {
                    var,
                    period_ticks: ((1.0 / f) / DT).ceil() as u64,
                    action,
                });
                // The watchdog counts from now.
                self.updated.insert(var, self.tick);
                Called::Value(Value::Bool(true))
            }
            other => return Err(format!("name '{other}' is not defined")),
        })
    }

    fn motion_done(&self) -> bool {
        self.arm.motion_done()
    }
}

/// Reads what a non-blocking stream has into `rx`; `false` when it closed.
fn read_into(stream: &mut TcpStream, rx: &mut Vec<u8>) -> bool {
    let mut buf = [0u8; 4096];
    loop {
        match stream.read(&mut buf) {
            Ok(0) => return false,
            Ok(n) => {
                rx.extend_from_slice(&buf[..n]);
                if rx.len() > 1 << 20 {
                    return false;
                }
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => return true,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(_) => return false,
        }
    }
}

fn write_all(stream: &mut TcpStream, bytes: &[u8]) -> io::Result<()> {
    super::tcp_server::write_all_within(stream, bytes, Duration::from_millis(100))
}
