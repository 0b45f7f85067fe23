//! `rl fake-robot`: run a fake robot controller on loopback until Ctrl-C, printing one status
//! line per second, so RL's programs or ours can be pointed at it without hardware.

use std::fmt::Write as _;
use std::net::SocketAddr;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use clap::{Args, Subcommand};
use nix::sys::signal::{SigSet, Signal};
use rl_drivers::fake::coach_server::{CoachServer, CoachServerConfig};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config, ForwardKinematics};

use super::capacity::WithModel;
use super::output::outln;
use super::{CliError, CliResult, refuse_given};

mod devices;

/// Which fake robot to run.
#[derive(Subcommand, Debug)]
pub enum FakeRobotCommand {
    /// A fake Mitsubishi H7 controller (UDP real-time packets + R3 over TCP).
    H7(H7Args),
    /// A Coach server (RL's visualisation protocol).
    Coach(CoachArgs),
    /// CiA 402 servo drives on a CAN bus (CANopen over cannelloni UDP/TCP or SocketCAN).
    Canopen(CanopenArgs),
    /// A fake EtherCAT segment of CiA 402 drives on a network interface (raw Ethernet; needs
    /// root or CAP_NET_RAW).
    Ethercat(EthercatArgs),
    /// A fake Franka FR3 speaking libfranka's protocol (FCI: TCP 1337 and 1 kHz UDP).
    Franka(FrankaArgs),
    /// A fake ATI Net F/T force/torque sensor (RDT over UDP, calibration over TCP and HTTP).
    Ft(devices::FtArgs),
    /// A fake Robotiq 2F-85/140 gripper (Modbus RTU on a pseudo-terminal, Modbus TCP).
    Gripper(devices::GripperArgs),
    /// A fake Universal Robots controller (RTDE 30004, dashboard 29999, URScript 30002/30003).
    Ur(devices::UrArgs),
}

/// Arguments of `rl fake-robot franka`.
#[derive(Args, Debug)]
pub struct FrankaArgs {
    /// Address of the command server and state sender (loopback by default; libfranka always
    /// connects to port 1337, so a second fake needs another address, e.g. 127.0.0.2).
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: std::net::IpAddr,
    /// The command server's port.
    #[arg(long, default_value_t = rl_drivers::franka::COMMAND_PORT)]
    pub port: u16,
    /// The arm's URDF (e.g. the FR3's): served to clients (`GetRobotModel`), its joint limits
    /// checked, and its dynamics integrated (rl-core's ABA) so torques move the arm. Without
    /// it the arm is kinematic with the FR3's limits.
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    /// With --model: serve it and take its limits, but keep the arm kinematic.
    #[arg(long)]
    pub kinematic: bool,
    /// With --model: the rotor inertia of each joint's drive reflected to the joint (kg·m²),
    /// which URDF has no field for, carried by the integrated arm: one value for all joints,
    /// or seven (franky-sim's FR3: 0.195,0.195,0.195,0.195,0.074,0.074,0.074) [default: 0].
    #[arg(long, value_name = "KG_M2[,…]", requires = "model", value_parser = crate::cli::parse_per_joint)]
    pub armature: Option<crate::cli::PerJointArg>,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// Arguments of `rl fake-robot ethercat`.
#[derive(Args, Debug)]
pub struct EthercatArgs {
    /// The network interface the segment answers on (e.g. one end of a veth pair).
    #[arg(long)]
    pub interface: String,
    /// Number of CiA 402 drives (taken from --model when one is given).
    #[arg(long, default_value_t = 6)]
    pub devices: usize,
    /// A robot model (URDF or RL XML): one drive per joint, its limits as the drives'
    /// software position limits.
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    /// Drives that run without distributed clocks (free run) instead of refusing SAFE-OP until
    /// SYNC0 is configured.
    #[arg(long)]
    pub free_run: bool,
    #[command(flatten)]
    pub units: DriveUnitsArgs,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// The units of the fake drives (`rl fake-robot canopen` and `ethercat`): what they report in
/// 0x608F, 0x6091 and 0x6092, and how their counts relate to the joint.
#[derive(Args, Debug)]
pub struct DriveUnitsArgs {
    /// Encoder counts per motor revolution, reported in 0x608F. The drives' position unit is
    /// the encoder count: 0x6092 (feed constant) = counts per revolution × gear.
    #[arg(long, value_name = "N", default_value_t = 1 << 20)]
    pub counts_per_rev: u32,
    /// Gear ratio, motor revolutions per joint revolution, reported in 0x6091 (up to six
    /// decimals: 50.5 is 0x6091 = 505000/10000).
    #[arg(long, value_name = "N", default_value_t = 100.0)]
    pub gear: f64,
    /// Drives without the factor-group objects 0x608F, 0x6091 and 0x6092: reading them is
    /// aborted with 0x06020000 "object does not exist", so a master must be given the units.
    #[arg(long)]
    pub no_unit_objects: bool,
}

impl DriveUnitsArgs {
    /// The drives' units, refused (exit 2) when the objects cannot hold them.
    fn units(&self) -> Result<rl_drivers::cia402::AxisUnits, CliError> {
        use rl_drivers::cia402::{AxisUnits, units::ratio};
        let u = AxisUnits {
            counts_per_rev: f64::from(self.counts_per_rev),
            gear_ratio: self.gear,
            ..AxisUnits::default()
        };
        if self.counts_per_rev == 0 || ratio(self.gear).is_none() {
            return Err(CliError::usage(format!(
                "--counts-per-rev {} --gear {}: give a positive count and a positive gear ratio \
                 with at most six decimals",
                self.counts_per_rev, self.gear
            )));
        }
        if ratio(u.units_per_rev()).is_none() {
            return Err(CliError::usage(format!(
                "--counts-per-rev {} --gear {}: {} counts per joint revolution do not fit the \
                 feed constant 0x6092 (32 bits)",
                self.counts_per_rev,
                self.gear,
                u.units_per_rev()
            )));
        }
        Ok(u)
    }

    fn describe(&self) -> String {
        if self.no_unit_objects {
            format!(
                "{} counts/rev, gear {}, without 0x608F/0x6091/0x6092",
                self.counts_per_rev, self.gear
            )
        } else {
            format!("{} counts/rev, gear {}", self.counts_per_rev, self.gear)
        }
    }
}

/// Arguments of `rl fake-robot h7`.
#[derive(Args, Debug)]
pub struct H7Args {
    /// UDP address for real-time packets.
    #[arg(long, default_value = "127.0.0.1:10000")]
    pub bind: SocketAddr,
    /// TCP address of the R3 command responder.
    #[arg(long, default_value = "127.0.0.1:10001")]
    pub r3_bind: SocketAddr,
    /// Number of simulated joints (1 to 8; taken from --model when one is given). Six without
    /// --model simulate the embedded RV-6SL that `rl run` drives; another number, plain ±π
    /// joints.
    #[arg(long, default_value_t = 6)]
    pub dof: usize,
    /// A robot model (URDF or RL XML) whose joint count, position and speed limits the
    /// simulated arm takes, and whose forward kinematics (to its last frame) the pose replies
    /// come from [default: the embedded Mitsubishi RV-6SL, as `rl run`].
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    /// Filter time constant in ms until a client's program sets its own (MXT's third argument).
    #[arg(long, default_value_t = 0)]
    pub filter_ms: u32,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// Arguments of `rl fake-robot coach`.
#[derive(Args, Debug)]
pub struct CoachArgs {
    /// TCP address to listen on.
    #[arg(long, default_value = "127.0.0.1:11235")]
    pub bind: SocketAddr,
    /// A robot model (URDF or RL XML) the viewer has loaded, as model 0 standing at its home
    /// position (or the neutral one): a client can ask where it stands (`6 0`) before sending
    /// anything, as `rl run --device coach://` does. Without it, a model becomes known from
    /// its first joint line.
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// Runs `rl fake-robot`.
pub fn run(cmd: FakeRobotCommand) -> CliResult {
    // Block SIGINT/SIGTERM before any thread starts (threads inherit the mask), and let one
    // thread wait for them synchronously: no signal handler, no unsafe code.
    let stop = interrupt_flag()?;
    match cmd {
        FakeRobotCommand::H7(args) => run_h7(&args, &stop),
        FakeRobotCommand::Coach(args) => run_coach(&args, &stop),
        FakeRobotCommand::Canopen(args) => run_canopen(&args, &stop),
        FakeRobotCommand::Ethercat(args) => run_ethercat(&args, &stop),
        FakeRobotCommand::Franka(args) => run_franka(&args, &stop),
        FakeRobotCommand::Ft(args) => devices::run_ft(&args, &stop),
        FakeRobotCommand::Gripper(args) => devices::run_gripper(&args, &stop),
        FakeRobotCommand::Ur(args) => devices::run_ur(&args, &stop),
    }
}

fn interrupt_flag() -> Result<Arc<AtomicBool>, CliError> {
    let mut set = SigSet::empty();
    set.add(Signal::SIGINT);
    set.add(Signal::SIGTERM);
    set.thread_block()
        .map_err(|e| CliError::failed(format!("cannot block SIGINT: {e}")))?;
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if set.wait().is_ok() {
                f.store(true, Ordering::Relaxed);
            }
        })
        .map_err(|e| CliError::failed(format!("cannot start the signal thread: {e}")))?;
    Ok(flag)
}

/// Calls `status` once per second until Ctrl-C, `duration` has passed or `status` fails
/// (standard output closed), and returns that failure.
fn every_second(
    stop: &AtomicBool,
    duration: Option<Duration>,
    mut status: impl FnMut(u64) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let start = Instant::now();
    let mut next = 1;
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(50));
        let elapsed = start.elapsed().as_secs();
        if elapsed >= next {
            status(elapsed)?;
            next = elapsed + 1;
        }
        if duration.is_some_and(|d| start.elapsed() >= d) {
            break;
        }
    }
    Ok(())
}

/// What the fake robots take from a model file: its joints' limits, whether they are all plain
/// (one coordinate per degree of freedom: no quaternion joints), and the forward kinematics to
/// its tool.
struct Arm {
    limits: Vec<rl_core::model::JointLimits>,
    /// Where it stands at first: its home position, else the neutral one.
    home: Vec<f64>,
    plain: bool,
    kinematics: Option<ForwardKinematics>,
}

impl Arm {
    /// Loads `path` (in the tool's capacity choice) for the fake named `what`, refusing quaternion
    /// joints.
    fn load(path: &std::path::Path, what: &str) -> Result<Self, CliError> {
        let arm = super::model::ModelFile::with_defaults(path.to_path_buf()).load(ArmJob)?;
        if !arm.plain {
            return Err(CliError::usage(format!(
                "--model {}: {what} plain joints; this model has quaternion joints",
                path.display()
            )));
        }
        Ok(arm)
    }
}

impl Arm {
    /// The embedded RV-6SL that `rl run` drives by default.
    fn embedded() -> Result<Self, CliError> {
        let loaded = rl::controller::rv6sl()
            .map_err(|e| CliError::failed(format!("the embedded RV-6SL: {e}")))?;
        ArmJob.run(Box::new(loaded))
    }

    /// `--model`'s arm, or the embedded RV-6SL when there is none and `count` (the joints,
    /// nodes or devices asked for) is its six; `None`: plain joints.
    fn for_fake(
        path: Option<&std::path::Path>,
        count: usize,
        what: &str,
    ) -> Result<Option<Self>, CliError> {
        match path {
            Some(p) => Self::load(p, what).map(Some),
            None if count == 6 => Self::embedded().map(Some),
            None => Ok(None),
        }
    }
}

/// The [`WithModel`] job behind [`Arm::load`].
struct ArmJob;

impl WithModel for ArmJob {
    type Output = Arm;

    fn run<const N: usize>(
        self,
        loaded: Box<rl_core::loader::LoadedModel<N>>,
    ) -> Result<Arm, CliError> {
        let m = &loaded.model;
        // A speed limit not given in the file is infinite (the loaders decide it).
        let limits = (0..m.dof()).map(|k| *m.limits(k)).collect();
        // The tool: the last frame (depth-first) on a moving body, else the last body.
        let tip = loaded
            .frames
            .iter()
            .rev()
            .find(|f| f.body != rl_core::model::ROOT)
            .map(|f| (f.body, f.placement))
            .or_else(|| {
                m.body_count()
                    .checked_sub(1)
                    .map(|b| (b, rl_core::spatial::PlueckerTransform::IDENTITY))
            });
        let kinematics =
            tip.map(|(body, placement)| ForwardKinematics::from_model(m.clone(), body, placement));
        Ok(Arm {
            limits,
            home: loaded.home_or_neutral(),
            plain: m.nq() == m.dof(),
            kinematics,
        })
    }
}

fn joints(q: &[f64]) -> String {
    let mut s = String::from("[");
    for (i, v) in q.iter().enumerate() {
        let _ = write!(s, "{}{v:.4}", if i > 0 { ", " } else { "" });
    }
    s.push(']');
    s
}

fn run_h7(args: &H7Args, stop: &AtomicBool) -> CliResult {
    let mut limits = None;
    let mut kinematics = None;
    if args.model.is_some() {
        refuse_given(&["dof"], "with --model: the model gives the joint count")?;
    }
    let mut dof = args.dof;
    let mut home = None;
    if let Some(arm) = Arm::for_fake(args.model.as_deref(), args.dof, "the fake H7 simulates")? {
        dof = arm.limits.len();
        home = Some(arm.home.clone());
        let limit = |f: fn(&rl_core::model::JointLimits) -> f64| -> Vec<f64> {
            arm.limits.iter().map(f).collect()
        };
        limits = Some((
            limit(|l| l.lower),
            limit(|l| l.upper),
            limit(|l| l.velocity),
        ));
        kinematics = arm.kinematics;
    }
    if dof == 0 || dof > 8 {
        return Err(CliError::usage(format!("--dof {dof}: must be 1 to 8")));
    }
    let mut config = FakeH7Config::loopback(dof);
    if let Some((lower, upper, speed)) = limits {
        let bad = |e: std::io::Error| CliError::usage(format!("--model: {e}"));
        config = config.with_limits(&lower, &upper).map_err(bad)?;
        config = config.with_speed_limits(&speed).map_err(bad)?;
    }
    config.udp_bind = args.bind;
    config.r3_bind = Some(args.r3_bind);
    config.filter_ms = args.filter_ms;
    // A real arm lags its command by its servo loop.
    config.servo_time_constant_s = rl_drivers::fake::h7_controller::SERVO_TIME_CONSTANT_S;
    config.kinematics = kinematics;
    if let Some(home) = &home {
        for (k, q) in home.iter().enumerate().take(dof) {
            config.initial_rad[k] = q.clamp(config.lower_rad[k], config.upper_rad[k]);
        }
    }
    // Real controllers and drives answer on their own CPUs: the fake's threads inherit this
    // thread's real-time priority (where the process may have one).
    rl::devices::fake_thread_realtime();
    let mut fake = FakeH7::spawn(config).map_err(|e| {
        CliError::failed(format!("fake H7 on {} / {}: {e}", args.bind, args.r3_bind))
    })?;
    let shown = outln!(
        "fake H7 controller ({} joints): real-time UDP on {}, R3 on {}; Ctrl-C to stop",
        dof,
        fake.udp_addr(),
        fake.r3_addr()
    );
    let mut last = 0;
    let shown = shown.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let s = fake.status();
            let rate = s.packets - last;
            last = s.packets;
            let program = match (s.program_running, s.program_info) {
                (true, Some(p)) => format!(
                    "running (mode {}, filter {} ms)",
                    p.mode.code(),
                    p.filter_ms
                ),
                (true, None) => "running".to_owned(),
                (false, _) => "stopped".to_owned(),
            };
            outln!(
                "t={t}s packets={} ({rate}/s) replies={} moves={} ends={} servo={} program={} \
             limit_hits={} speed_clamps={} rejected={} outside_program={} wrong_mode={} bad={} \
             dropped_frozen={} r3_clients={} r3_not_implemented={} commanded={} actual={}",
                s.packets,
                s.replies,
                s.moves,
                s.ends,
                if s.servo_on { "on" } else { "off" },
                program,
                s.limit_hits,
                s.speed_clamps,
                s.rejected,
                s.packets_outside_program,
                s.wrong_mode,
                s.bad_packets,
                s.dropped_frozen,
                s.r3_clients,
                s.r3_not_implemented,
                joints(&s.commanded_rad[..s.dof]),
                joints(&s.actual_rad[..s.dof]),
            )
        })
    });
    fake.shutdown();
    shown?;
    outln!("fake H7 controller stopped")?;
    Ok(ExitCode::SUCCESS)
}

fn run_coach(args: &CoachArgs, stop: &AtomicBool) -> CliResult {
    let mut models = Vec::new();
    if let Some(path) = &args.model {
        models.push((0, Arm::load(path, "the viewer shows")?.home));
    }
    let config = CoachServerConfig {
        bind: args.bind,
        models,
        ..CoachServerConfig::loopback()
    };
    let mut server = CoachServer::spawn(config)
        .map_err(|e| CliError::failed(format!("Coach server on {}: {e}", args.bind)))?;
    let shown = outln!("Coach server on {}; Ctrl-C to stop", server.addr());
    let shown = shown.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let s = server.status();
            let mut models: Vec<_> = s.joints.iter().collect();
            models.sort_by_key(|(m, _)| **m);
            let mut line = format!(
                "t={t}s clients={} lines={} requests={} bad={} overlong={} ignored={} bodies={} shapes={}",
                s.clients,
                s.lines,
                s.requests,
                s.bad_lines,
                s.overlong_lines,
                s.ignored_lines,
                s.bodies.len(),
                s.shapes.len()
            );
            if let Some(e) = &s.last_error {
                let _ = write!(line, " last_error=\"{e}\"");
            }
            for (m, q) in models {
                let _ = write!(line, " model{m}={}", joints(q));
            }
            outln!("{line}")
        })
    });
    server.shutdown();
    shown?;
    outln!("Coach server stopped")?;
    Ok(ExitCode::SUCCESS)
}

/// Arguments of `rl fake-robot canopen`.
#[derive(Args, Debug)]
pub struct CanopenArgs {
    /// The bus: cannelloni+udp://HOST:PORT (bound here; answers whoever sends),
    /// cannelloni+tcp://HOST:PORT (listens) or socketcan://IFACE.
    #[arg(long, default_value = "cannelloni+udp://127.0.0.1:20000")]
    pub bus: String,
    /// Node ids: a range `1-6`, a list `1,3,5`, or both (`1-3,7`). Default: 1 to the model's
    /// joint count, or 1-6.
    #[arg(long)]
    pub nodes: Option<String>,
    /// A robot model (URDF or RL XML) whose joint position and speed limits the simulated
    /// motors take (one node per joint), standing at its home position [default: six nodes
    /// simulate the embedded RV-6SL that `rl run` drives; another number, plain ±π axes].
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    #[command(flatten)]
    pub units: DriveUnitsArgs,
    /// An EDS to give every node (default: the one shipped for this fake).
    #[arg(long)]
    pub eds: Option<std::path::PathBuf>,
    /// Delay between a SYNC and the TPDOs it triggers.
    #[arg(long, default_value = "100us", value_parser = super::parse_duration)]
    pub tpdo_delay: Duration,
    /// Record every frame to this pcap file (SocketCAN link type, for Wireshark).
    #[arg(long)]
    pub pcap: Option<std::path::PathBuf>,
    /// Record every frame to this candump log (for can-utils).
    #[arg(long)]
    pub candump: Option<std::path::PathBuf>,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// `1-6`, `1,3,5`, `1-3,7` to node ids (each 1..=127, no repeats, at most 8).
fn parse_nodes(text: &str) -> Result<Vec<u8>, CliError> {
    rl_drivers::canopen::parse_node_list(text)
        .map_err(|e| CliError::usage(format!("--nodes {text}: {e}")))
}

fn run_canopen(args: &CanopenArgs, stop: &AtomicBool) -> CliResult {
    use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
    use rl_drivers::proto::canopen::eds::Eds;
    use rl_drivers::transport::can::CanAddress;

    let address =
        CanAddress::parse(&args.bus).map_err(|e| CliError::usage(format!("--bus: {e}")))?;
    let units = args.units.units()?;
    let mut nodes = match &args.nodes {
        Some(text) => Some(parse_nodes(text)?),
        None => None,
    };
    let count = nodes.as_ref().map_or(6, Vec::len);
    let arm = Arm::for_fake(args.model.as_deref(), count, "the fake drives simulate")?;
    let nodes = match (nodes.take(), &arm) {
        (Some(n), _) => n,
        (None, Some(a)) => (1..=a.limits.len() as u8).collect(),
        (None, None) => (1..=6).collect(),
    };
    if nodes.is_empty() || nodes.len() > rl_drivers::canopen::MAX_AXES {
        return Err(CliError::usage(format!(
            "--nodes: {} nodes; 1 to {} are simulated",
            nodes.len(),
            rl_drivers::canopen::MAX_AXES
        )));
    }
    let mut config = FakeCia402Config::new(&nodes).map_err(|e| CliError::failed(e.to_string()))?;
    for a in &mut config.axes {
        a.units = units;
        a.unit_objects = !args.units.no_unit_objects;
    }
    if let Some(arm) = &arm {
        if arm.limits.len() != nodes.len() {
            return Err(CliError::usage(format!(
                "--model has {} joints but --nodes names {} nodes",
                arm.limits.len(),
                nodes.len()
            )));
        }
        for ((a, j), home) in config.axes.iter_mut().zip(&arm.limits).zip(&arm.home) {
            if !j.wraparound {
                a.lower = j.lower;
                a.upper = j.upper;
            }
            // An unknown speed limit (infinite, or RL's 0) keeps the fake's default.
            if j.velocity.is_finite() && j.velocity > 0.0 {
                a.max_velocity = j.velocity;
            }
            a.initial = home.clamp(a.lower, a.upper);
        }
    }
    if let Some(path) = &args.eds {
        let eds = Eds::load(path).map_err(|e| CliError::usage(format!("--eds: {e}")))?;
        config.eds = std::sync::Arc::new(eds);
    }
    config.tpdo_delay = args.tpdo_delay;
    config.pcap = args.pcap.clone();
    config.candump = args.candump.clone();
    // Real controllers and drives answer on their own CPUs: the fake's threads inherit this
    // thread's real-time priority (where the process may have one).
    rl::devices::fake_thread_realtime();
    let mut fake = FakeCia402::serve(config, &address)
        .map_err(|e| CliError::failed(format!("fake CiA 402 drives on {}: {e}", args.bus)))?;
    let shown = match (&address, fake.local_addr()) {
        (CanAddress::CannelloniUdp { .. }, Some(a)) => format!("cannelloni+udp://{a}"),
        (CanAddress::CannelloniTcp { .. }, Some(a)) => format!("cannelloni+tcp://{a}"),
        _ => address.to_string(),
    };
    let printed = outln!(
        "fake CiA 402 drives, nodes {nodes:?}, on {shown}; {}; {}; TPDOs {} µs after SYNC; Ctrl-C \
         to stop",
        match (&args.model, &arm) {
            (Some(p), _) => format!("limits of {}", p.display()),
            (None, Some(_)) => "limits of the embedded RV-6SL".to_owned(),
            (None, None) => "±π axes".to_owned(),
        },
        args.units.describe(),
        args.tpdo_delay.as_micros()
    );
    let mut last = 0;
    let printed = printed.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let s = fake.status();
            let rate = s.frames_received - last;
            last = s.frames_received;
            let mut line = format!(
                "t={t}s frames in={} ({rate}/s) out={}",
                s.frames_received, s.frames_sent
            );
            for n in &s.nodes {
                let _ = write!(
                    line,
                    " | {}: {} {} q={:.4}",
                    n.node, n.nmt, n.power, n.position
                );
            }
            if let Some(e) = &s.last_error {
                let _ = write!(line, " | last error: {e}");
            }
            outln!("{line}")
        })
    });
    fake.shutdown();
    printed?;
    outln!("fake CiA 402 drives stopped")?;
    Ok(ExitCode::SUCCESS)
}

fn run_ethercat(args: &EthercatArgs, stop: &AtomicBool) -> CliResult {
    use rl_drivers::fake::ecat_segment::description::Profile;
    use rl_drivers::fake::ecat_segment::{FakeSegment, FakeSegmentConfig};
    let units = args.units.units()?;
    if args.model.is_some() {
        refuse_given(
            &["devices"],
            "with --model: one drive per joint of the model",
        )?;
    }
    let arm = Arm::for_fake(args.model.as_deref(), args.devices, "the fake drives move")?;
    let devices = arm.as_ref().map_or(args.devices, |a| a.limits.len());
    if devices == 0 || devices > 64 {
        return Err(CliError::usage(format!(
            "--devices {devices}: must be 1 to 64"
        )));
    }
    let mut config = FakeSegmentConfig::drives(&args.interface, devices);
    for (k, d) in config.devices.iter_mut().enumerate() {
        if let Profile::Cia402 {
            motor,
            limits: l,
            requires_dc,
            initial_position,
        } = &mut d.profile
        {
            *requires_dc = !args.free_run;
            motor.units = units;
            motor.unit_objects = !args.units.no_unit_objects;
            if let Some(arm) = &arm {
                let per_rad = motor.per_rad();
                let j = &arm.limits[k];
                if !j.wraparound && j.lower.is_finite() && j.upper.is_finite() && j.lower < j.upper
                {
                    *l = ((j.lower * per_rad) as i32, (j.upper * per_rad) as i32);
                }
                // Standing at the model's home, inside the limits.
                let home = (arm.home[k] * per_rad).round() as i32;
                *initial_position = if l.0 < l.1 {
                    home.clamp(l.0, l.1)
                } else {
                    home
                };
            }
        }
    }
    // Hardware answers without being delayed by other programs: the segment's thread runs at a
    // real-time priority when the process may (root), like the controller's.
    config.on_thread_start = Some(rl::devices::fake_process_thread_realtime);
    let fake = FakeSegment::spawn(config).map_err(|e| {
        let mut msg = format!("fake EtherCAT segment on {}: {e}", args.interface);
        if rl_drivers::transport::packet::is_permission_error(&e) {
            msg.push_str("; ");
            msg.push_str(rl_drivers::transport::packet::PERMISSION_REMEDY);
        }
        CliError::failed(msg)
    })?;
    let printed = outln!(
        "fake EtherCAT segment: {devices} CiA 402 drives on {}, {}{}; Ctrl-C to stop",
        args.interface,
        args.units.describe(),
        if args.free_run {
            " (free run)"
        } else {
            " (DC SYNC0 required)"
        }
    );
    let mut last = 0;
    let printed = printed.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let c = fake.counters();
            let rate = c.frames - last;
            last = c.frames;
            let mut line = format!(
                "t={t}s frames={} ({rate}/s) lost={} falsified={} malformed={} slips={} \
                 max_lateness_us={}",
                c.frames, c.dropped, c.falsified, c.malformed, c.slips, c.max_lateness_us
            );
            for d in fake.status() {
                let _ = write!(
                    line,
                    " [{:#06x} {}{}{}]",
                    d.station,
                    d.state,
                    d.error.map(|e| format!(" error {e}")).unwrap_or_default(),
                    d.power.map(|p| format!(" {p}")).unwrap_or_default()
                );
            }
            outln!("{line}")
        })
    });
    let c = fake.counters();
    fake.shutdown()
        .map_err(|e| CliError::failed(format!("fake EtherCAT segment: {e}")))?;
    printed?;
    outln!("fake EtherCAT segment stopped after {} frames", c.frames)?;
    Ok(ExitCode::SUCCESS)
}

fn run_franka(args: &FrankaArgs, stop: &AtomicBool) -> CliResult {
    use rl_drivers::fake::franka_controller::{FakeFranka, FakeFrankaConfig};
    let mut config = FakeFrankaConfig::loopback();
    config.bind = args.bind;
    config.command_port = args.port;
    if let Some(path) = &args.model {
        let urdf = std::fs::read_to_string(path)
            .map_err(|e| CliError::usage(format!("--model {}: {e}", path.display())))?;
        config = config.with_urdf(urdf);
        config.dynamics = !args.kinematic;
    }
    if let Some(a) = &args.armature {
        let values = a
            .per_dof("--armature", config.armature.len())
            .map_err(CliError::usage)?;
        config.armature.copy_from_slice(&values);
    }
    // The robot's cycle runs at a real-time priority where the process may (root).
    config.on_thread_start = Some(rl::devices::fake_process_thread_realtime);
    let fake = FakeFranka::spawn(config).map_err(|e| {
        CliError::failed(format!("fake Franka on {}:{}: {e}", args.bind, args.port))
    })?;
    let dynamics = fake.status().dynamics;
    let printed = outln!(
        "fake Franka FR3 (FCI v{}) on {}, {}; Ctrl-C to stop",
        rl_drivers::franka::connect::VERSION,
        fake.addr(),
        if dynamics {
            "dynamics from --model"
        } else {
            "kinematic arm"
        }
    );
    let mut last = 0;
    let printed = printed.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let s = fake.status();
            let rate = s.states - last;
            last = s.states;
            outln!(
                "t={t}s mode={} states={} ({rate}/s) commands={} lost={} max_lost_in_a_row={} \
                 late={} motions={} finished={} reflexes={} errors={} recoveries={} refused={} \
                 slips={} max_lateness_us={} q={}",
                s.robot_mode,
                s.states,
                s.commands,
                s.lost,
                s.max_lost_in_a_row,
                s.late,
                s.motions,
                s.finished,
                s.reflexes,
                s.errors,
                s.recoveries,
                s.refused_requests,
                s.slips,
                s.max_lateness_us,
                joints(&s.q),
            )
        })
    });
    drop(fake);
    printed?;
    outln!("fake Franka stopped")?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::parse_nodes;

    #[test]
    fn node_lists_and_ranges() {
        assert_eq!(parse_nodes("1-6").unwrap(), vec![1, 2, 3, 4, 5, 6]);
        assert_eq!(parse_nodes("1-3,7").unwrap(), vec![1, 2, 3, 7]);
        assert_eq!(parse_nodes("5").unwrap(), vec![5]);
        for bad in ["0", "128", "3-1", "1,1", "x", "1-", ""] {
            assert_eq!(parse_nodes(bad).unwrap_err().exit_code(), 2, "{bad}");
        }
    }
}
