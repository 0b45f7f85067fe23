//! `rl fake-robot ft | gripper | ur`: the fake devices around the arm (issue 30), each until Ctrl-C with one
//! status line per second.

use std::net::SocketAddr;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;

use clap::Args;

use super::every_second;
use crate::cli::output::outln;
use crate::cli::{CliError, CliResult};

/// Six comma-separated numbers.
fn six(text: &str) -> Result<[f64; 6], String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>().map_err(|e| format!("`{s}`: {e}")))
        .collect::<Result<_, _>>()?;
    let arr: [f64; 6] = v
        .try_into()
        .map_err(|v: Vec<f64>| format!("{} values, expected 6 (fx,fy,fz,tx,ty,tz)", v.len()))?;
    if arr.iter().all(|x| x.is_finite()) {
        Ok(arr)
    } else {
        Err("values must be finite".into())
    }
}

/// Arguments of `rl fake-robot ft`.
#[derive(Args, Debug)]
pub struct FtArgs {
    /// The RDT (UDP) address; the calibration (TCP) and web (HTTP) servers bind the same host.
    #[arg(long, default_value = "127.0.0.1:49152")]
    pub bind: SocketAddr,
    /// The calibration server's TCP port (READCALINFO).
    #[arg(long, default_value_t = rl_drivers::proto::netft::TCP_PORT)]
    pub tcp_port: u16,
    /// The web server's port (netftapi2.xml; the sensor's own is 80).
    #[arg(long, default_value_t = 8080)]
    pub http_port: u16,
    /// Records per second (1 to 7000).
    #[arg(long, default_value_t = 7000)]
    pub rate: u32,
    /// Counts per N and per N·m of the calibration.
    #[arg(long, default_value_t = 1_000_000)]
    pub counts: u32,
    /// The load on the sensor: fx,fy,fz,tx,ty,tz in N and N·m (sensor frame).
    #[arg(long, value_parser = six, allow_negative_numbers = true)]
    pub wrench: Option<[f64; 6]>,
    /// The unloaded sensor's reading (what a bias removes).
    #[arg(long, value_parser = six, allow_negative_numbers = true)]
    pub offset: Option<[f64; 6]>,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// Runs `rl fake-robot ft`.
pub fn run_ft(args: &FtArgs, stop: &AtomicBool) -> CliResult {
    use rl_drivers::fake::netft_sensor::{FakeNetFt, FakeNetFtConfig};
    use rl_drivers::proto::netft::Calibration;
    let config = FakeNetFtConfig {
        on_thread_start: Some(rl::devices::fake_process_thread_realtime),
        bind: args.bind.ip(),
        rdt_port: args.bind.port(),
        tcp_port: Some(args.tcp_port),
        http_port: Some(args.http_port),
        calibration: Calibration::si(args.counts, args.counts),
        rdt_rate_hz: args.rate,
        ..FakeNetFtConfig::loopback()
    };
    if args.counts == 0 {
        return Err(CliError::usage("--counts: must be positive"));
    }
    let fake = FakeNetFt::spawn(config).map_err(|e| {
        let code = if e.kind() == std::io::ErrorKind::InvalidInput {
            2
        } else {
            1
        };
        let msg = format!("fake Net F/T on {}: {e}", args.bind);
        if code == 2 {
            CliError::usage(msg)
        } else {
            CliError::failed(msg)
        }
    })?;
    if let Some(w) = args.wrench {
        fake.set_wrench(w);
    }
    if let Some(o) = args.offset {
        fake.set_offset(o);
    }
    let printed = outln!(
        "fake ATI Net F/T: RDT on {}, calibration on TCP {}, netftapi2.xml on HTTP {}; {} records/s, {} counts per N and per N·m; Ctrl-C to stop",
        fake.rdt_addr(),
        fake.tcp_addr().map_or("-".into(), |a| a.to_string()),
        fake.http_addr().map_or("-".into(), |a| a.to_string()),
        args.rate,
        args.counts
    );
    let mut last = 0;
    let printed = printed.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let s = fake.status();
            let rate = s.records - last;
            last = s.records;
            outln!(
                "t={t}s streaming_to={} records={} ({rate}/s) datagrams={} dropped={} reordered={} \
                 duplicated={} biases={} requests={} bad_requests={} calinfo={} http={} slips={} \
                 max_lateness_us={}",
                s.streaming_to.map_or("-".into(), |a| a.to_string()),
                s.records,
                s.datagrams,
                s.dropped,
                s.reordered,
                s.duplicated,
                s.biases,
                s.requests,
                s.bad_requests,
                s.calinfo_requests,
                s.http_requests,
                s.slips,
                s.max_lateness_us,
            )
        })
    });
    drop(fake);
    printed?;
    outln!("fake Net F/T stopped")?;
    Ok(ExitCode::SUCCESS)
}

/// Arguments of `rl fake-robot gripper`.
#[derive(Args, Debug)]
pub struct GripperArgs {
    /// Serve Modbus RTU on a pseudo-terminal linked at PATH (open PATH as the serial port).
    #[arg(long, value_name = "PATH")]
    pub serial: Option<std::path::PathBuf>,
    /// Serve Modbus TCP at ADDR (e.g. 127.0.0.1:5020).
    #[arg(long, value_name = "ADDR")]
    pub modbus_tcp: Option<SocketAddr>,
    /// The gripper: 2f-85 or 2f-140.
    #[arg(long, default_value = "2f-85")]
    pub model: String,
    /// Its Modbus unit.
    #[arg(long, default_value_t = rl_drivers::proto::robotiq::DEFAULT_UNIT)]
    pub unit: u8,
    /// The serial line's baud rate (answers are paced at it, 8N1).
    #[arg(long, default_value_t = rl_drivers::proto::robotiq::DEFAULT_BAUD)]
    pub baud: u32,
    /// How long an activation takes.
    #[arg(long, default_value = "1.5s", value_parser = crate::cli::parse_duration)]
    pub activation_time: std::time::Duration,
    /// An object between the fingers, this wide (m): a closing grasp stops on it.
    #[arg(long)]
    pub object: Option<f64>,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// Runs `rl fake-robot gripper`.
pub fn run_gripper(args: &GripperArgs, stop: &AtomicBool) -> CliResult {
    use rl_drivers::fake::robotiq_gripper::{FakeGripper, FakeGripperConfig};
    use rl_drivers::proto::robotiq::Model;
    let model = match args.model.to_ascii_lowercase().as_str() {
        "2f-85" | "2f85" => Model::TwoF85,
        "2f-140" | "2f140" => Model::TwoF140,
        other => {
            return Err(CliError::usage(format!(
                "--model {other}: expected 2f-85 or 2f-140"
            )));
        }
    };
    if args.serial.is_none() && args.modbus_tcp.is_none() {
        return Err(CliError::usage(
            "give --serial PATH (Modbus RTU on a pseudo-terminal) or --modbus-tcp ADDR, or both",
        ));
    }
    if let Some(w) = args.object
        && !(w.is_finite() && (0.0..=model.stroke_m()).contains(&w))
    {
        return Err(CliError::usage(format!(
            "--object {w}: an opening from 0 to {} m",
            model.stroke_m()
        )));
    }
    let config = FakeGripperConfig {
        on_thread_start: Some(rl::devices::fake_process_thread_realtime),
        model,
        unit: args.unit,
        serial: args.serial.is_some(),
        serial_link: args.serial.clone(),
        baud: args.baud,
        tcp: args.modbus_tcp,
        activation_time: args.activation_time,
        ..FakeGripperConfig::serial()
    };
    let mut fake =
        FakeGripper::spawn(config).map_err(|e| CliError::failed(format!("fake gripper: {e}")))?;
    fake.set_object(args.object);
    let mut wires = Vec::new();
    if let (Some(link), Some(pty)) = (&args.serial, fake.serial_path()) {
        wires.push(format!(
            "Modbus RTU on {} -> {} at {} baud 8N1",
            link.display(),
            pty.display(),
            args.baud
        ));
    }
    if let Some(a) = fake.tcp_addr() {
        wires.push(format!("Modbus TCP on {a}"));
    }
    let printed = outln!(
        "fake Robotiq {} gripper, unit {}: {}; Ctrl-C to stop",
        model.name(),
        args.unit,
        wires.join(", ")
    );
    let printed = printed.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let s = fake.status();
            let g = s.status;
            outln!(
                "t={t}s requests={} answers={} exceptions={} crc_errors={} other_units={} garbage_bytes={} \
                 gACT={} gSTA={:?} gGTO={} gOBJ={:?} fault={} position={} opening_mm={:.1} current={} tcp_clients={}",
                s.requests,
                s.answers,
                s.exceptions,
                s.crc_errors,
                s.other_units,
                s.garbage_bytes,
                u8::from(g.activated),
                g.activation,
                u8::from(g.going),
                g.object,
                g.fault,
                g.position,
                s.opening_m * 1000.0,
                g.current,
                s.tcp_clients,
            )
        })
    });
    fake.shutdown();
    printed?;
    outln!("fake gripper stopped")?;
    Ok(ExitCode::SUCCESS)
}

/// Arguments of `rl fake-robot ur`.
#[derive(Args, Debug)]
pub struct UrArgs {
    /// The address every server binds (loopback by default).
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: std::net::IpAddr,
    /// RTDE's port.
    #[arg(long, default_value_t = rl_drivers::proto::rtde::PORT)]
    pub rtde_port: u16,
    /// The dashboard server's port.
    #[arg(long, default_value_t = rl_drivers::fake::ur_controller::DASHBOARD_PORT)]
    pub dashboard_port: u16,
    /// The ports that take URScript only (the secondary interface).
    #[arg(long, value_delimiter = ',', default_value = "30002")]
    pub script_ports: Vec<u16>,
    /// The real-time interface's port: streams the state at 500 Hz, takes URScript.
    #[arg(long, default_value_t = rl_drivers::fake::ur_controller::REALTIME_PORT)]
    pub realtime_port: u16,
    /// The read-only real-time interface's port.
    #[arg(long, default_value_t = rl_drivers::fake::ur_controller::REALTIME_READ_ONLY_PORT)]
    pub realtime_read_only_port: u16,
    /// The arm: ur5e or ur10e (kinematics and joint speed limits).
    #[arg(long, default_value = "ur5e")]
    pub arm: String,
    /// A robot model (URDF or RL XML, six joints): its home position is where the arm stands
    /// and its forward kinematics give the tool pose.
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    /// Start powered off with the brakes on, as after booting (a client powers it on through
    /// the dashboard); by default it is running, as after an operator's start-up.
    #[arg(long)]
    pub power_off: bool,
    /// Stop after this long instead of waiting for Ctrl-C: e.g. 30s, 500ms, 2m (a bare number
    /// is seconds).
    #[arg(long, alias = "seconds", value_parser = crate::cli::parse_duration)]
    pub duration: Option<std::time::Duration>,
}

/// Runs `rl fake-robot ur`.
pub fn run_ur(args: &UrArgs, stop: &AtomicBool) -> CliResult {
    use rl_drivers::fake::ur_controller::{FakeUr, FakeUrConfig, UrKinematics};
    let kinematics = match args.arm.to_ascii_lowercase().as_str() {
        "ur5e" => UrKinematics::UR5E,
        "ur10e" => UrKinematics::UR10E,
        other => {
            return Err(CliError::usage(format!(
                "--arm {other}: expected ur5e or ur10e"
            )));
        }
    };
    let mut config = FakeUrConfig {
        bind: args.bind,
        rtde_port: args.rtde_port,
        dashboard_port: Some(args.dashboard_port),
        script_ports: args.script_ports.clone(),
        realtime_port: Some(args.realtime_port),
        realtime_read_only_port: Some(args.realtime_read_only_port),
        kinematics,
        running: !args.power_off,
        on_thread_start: Some(rl::devices::fake_process_thread_realtime),
        ..FakeUrConfig::loopback()
    };
    if let Some(path) = &args.model {
        let arm = super::Arm::load(path, "the fake UR moves")?;
        if arm.limits.len() != 6 {
            return Err(CliError::usage(format!(
                "--model {}: {} joints; a UR arm has 6",
                path.display(),
                arm.limits.len()
            )));
        }
        for (q, h) in config.initial_q.iter_mut().zip(&arm.home) {
            *q = *h;
        }
        config.model = arm.kinematics;
    }
    let fake = FakeUr::spawn(config)
        .map_err(|e| CliError::failed(format!("fake UR controller on {}: {e}", args.bind)))?;
    let scripts: Vec<String> = fake
        .script_addrs()
        .iter()
        .map(ToString::to_string)
        .collect();
    let printed = outln!(
        "fake UR controller ({}{}): RTDE on {}, dashboard on {}, URScript on {}, real-time interface on {} (read only {}); Ctrl-C to stop",
        kinematics.name,
        if args.power_off { ", powered off" } else { "" },
        fake.rtde_addr(),
        fake.dashboard_addr().map_or("-".into(), |a| a.to_string()),
        scripts.join(", "),
        fake.realtime_addr().map_or("-".into(), |a| a.to_string()),
        fake.realtime_read_only_addr()
            .map_or("-".into(), |a| a.to_string()),
    );
    let mut last = 0;
    let printed = printed.and_then(|()| {
        every_second(stop, args.duration, |t| {
            let s = fake.status();
            let rate = s.outputs_sent - last;
            last = s.outputs_sent;
            outln!(
                "t={t}s robot_mode={} safety_mode={} runtime_state={} program={} outputs={} ({rate}/s) \
                 inputs={} rtde_clients={} protocol_errors={} servoj={} watchdogs={} protective_stops={} \
                 dashboard={} realtime_clients={} realtime_skipped={} slips={} max_lateness_us={} q=[{}]{}",
                s.robot_mode,
                s.safety_mode,
                s.runtime_state,
                s.program.as_deref().unwrap_or("-"),
                s.outputs_sent,
                s.inputs_applied,
                s.rtde_clients,
                s.protocol_errors,
                s.servoj_calls,
                s.watchdog_triggers,
                s.protective_stops,
                s.dashboard_commands,
                s.realtime_clients,
                s.realtime_skipped,
                s.slips,
                s.max_lateness_us,
                s.q.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(", "),
                s.last_program_error
                    .as_ref()
                    .map_or(String::new(), |e| format!(" last_error=\"{e}\"")),
            )
        })
    });
    drop(fake);
    printed?;
    outln!("fake UR controller stopped")?;
    Ok(ExitCode::SUCCESS)
}
