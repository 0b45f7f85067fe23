//! The tool's device table: `--device` names a driver and where it is; each entry builds the
//! device (and, for an in-process fake, the fake) for a model. This is the one place the tool
//! names concrete drivers; the controller runtime only sees their capabilities.

use std::net::{SocketAddr, ToSocketAddrs};
use std::time::Duration;

use rl::controller::JointRobot;
use rl_core::loader::LoadedModel;
use rl_drivers::EthercatDrives;
use rl_drivers::canopen::{Cia402, Cia402Config, DeviceAddress};
use rl_drivers::cia402::{AxisUnits, PowerState};
use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::ethercat::EthercatConfig;
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::proto::ecat::frame::ETHERTYPE;
use rl_drivers::transport::can::{CanAddress, default_local};
use rl_drivers::transport::{PacketLink, packet};

use crate::cli::CliError;

/// H7 real-time UDP port.
const H7_PORT: u16 = 10000;
/// H7 R3 TCP port.
const R3_PORT: u16 = 10001;

/// The devices `--device` accepts, for messages.
pub const DEVICES: &str = "fake-h7, h7://HOST[:PORT][?r3=PORT], coach://HOST[:PORT], fake-cia402, \
     cannelloni+udp://HOST:PORT[?nodes=1-6], cannelloni+tcp://HOST:PORT[?listen][&nodes=…] or \
     socketcan://IFACE[?nodes=…], ethercat://IF, franka://HOST[:PORT] or \
     ur://HOST[:PORT][?power-on]";

/// The robot `rl run` drives.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceSpec {
    /// A fake H7 controller in this process on loopback.
    FakeH7,
    /// A MELFA controller: real-time UDP and R3 TCP addresses.
    H7 {
        /// UDP address (port 10000 by default).
        server: SocketAddr,
        /// R3 address (same host, port 10001 by default).
        r3: SocketAddr,
    },
    /// A Coach visualiser.
    Coach {
        /// TCP address (port 11235 by default).
        server: SocketAddr,
    },
    /// Fake CiA 402 drives in this process, on cannelloni UDP over loopback.
    FakeCia402,
    /// CiA 402 drives on a CAN bus (SocketCAN or cannelloni), nodes 1..=dof unless given.
    Cia402(DeviceAddress),
    /// CiA 402 drives on an EtherCAT segment on a network interface.
    Ethercat {
        /// The interface's name.
        interface: String,
    },
    /// A Franka arm (FCI, libfranka's protocol), in joint position mode.
    Franka {
        /// Its command server (port 1337 by default).
        server: SocketAddr,
    },
    /// A Universal Robots arm over RTDE (the follower program on its controller).
    Ur {
        /// RTDE's address (port 30004 by default; dashboard 29999 and script 30002 on the
        /// same host).
        server: SocketAddr,
        /// Power on and release the brakes through the dashboard at start.
        power_on: bool,
    },
}

/// A device built for a run: the driver behind the capabilities the controller needs, its name
/// for the report, and for an in-process fake what the fake saw.
pub struct Opened {
    /// The device (not yet opened: the controller runtime opens it).
    pub robot: Box<dyn JointRobot + Send>,
    /// How the report names it.
    pub name: String,
    /// The in-process fake, if the device talks to one.
    pub fake: Option<InProcessFake>,
}

/// An in-process fake the tool started, kept for the report.
pub enum InProcessFake {
    /// The fake H7 controller.
    H7(FakeH7),
    /// The fake CiA 402 drives.
    Cia402(FakeCia402),
}

/// What an in-process fake saw during a run.
pub struct FakeSeen {
    /// A line for the report.
    pub note: String,
    /// `Err` with the reason if the fake was not left in a safe state.
    pub safe: Result<(), String>,
    /// The same as JSON keys for the report (`fake_end_packets`, `fake_servo_on`, …).
    pub json: serde_json::Value,
}

impl InProcessFake {
    /// What the fake saw, for the report, and whether it was left in a safe state. Waits
    /// (bounded) for the end packet, which is sent without waiting for an answer.
    pub fn after_run(&self, device_stopped: bool) -> FakeSeen {
        match self {
            InProcessFake::H7(fake) => {
                let deadline = std::time::Instant::now() + Duration::from_millis(500);
                let mut s = fake.status();
                while device_stopped && s.ends == 0 && std::time::Instant::now() < deadline {
                    std::thread::sleep(Duration::from_millis(5));
                    s = fake.status();
                }
                FakeSeen {
                    note: format!(
                        "fake H7 saw {} end packet{}, servo {}, {} limit hits",
                        s.ends,
                        if s.ends == 1 { "" } else { "s" },
                        if s.servo_on { "on" } else { "off" },
                        s.limit_hits
                    ),
                    safe: if s.servo_on {
                        Err("the fake H7's servo is still on after the run".to_owned())
                    } else {
                        Ok(())
                    },
                    json: serde_json::json!({
                        "fake_end_packets": s.ends,
                        "fake_servo_on": s.servo_on,
                        "fake_limit_hits": s.limit_hits,
                        "fake_program_running": s.program_running,
                        "fake_packets": s.packets,
                        "fake_replies": s.replies,
                        "fake_cycles": s.cycles,
                        "fake_packets_outside_program": s.packets_outside_program,
                        "fake_overflowed": s.overflowed,
                    }),
                }
            }
            InProcessFake::Cia402(fake) => {
                let s = fake.status();
                let off =
                    |p: PowerState| matches!(p, PowerState::SwitchOnDisabled | PowerState::Fault);
                let powered: Vec<u8> = s
                    .nodes
                    .iter()
                    .filter(|n| !off(n.power))
                    .map(|n| n.node)
                    .collect();
                let note = format!(
                    "fake CiA 402 drives: {} of {} off, {} SYNCs and {} TPDOs on node 1, {} faults",
                    s.nodes.len() - powered.len(),
                    s.nodes.len(),
                    s.nodes.first().map_or(0, |n| n.counters.syncs),
                    s.nodes.first().map_or(0, |n| n.counters.tpdos),
                    s.nodes.iter().map(|n| n.counters.faults).sum::<u64>()
                );
                let safe = if powered.is_empty() {
                    Ok(())
                } else {
                    Err(format!(
                        "fake drives {powered:?} still powered after the run"
                    ))
                };
                let json = serde_json::json!({
                    "fake_drives": s.nodes.len(),
                    "fake_drives_powered": powered,
                    "fake_syncs": s.nodes.first().map_or(0, |n| n.counters.syncs),
                    "fake_tpdos": s.nodes.first().map_or(0, |n| n.counters.tpdos),
                    "fake_faults": s.nodes.iter().map(|n| n.counters.faults).sum::<u64>(),
                });
                FakeSeen { note, safe, json }
            }
        }
    }
}

impl DeviceSpec {
    /// Parses one of [`DEVICES`].
    pub fn parse(text: &str) -> Result<Self, CliError> {
        let bad = |why: String| CliError::usage(format!("--device {text}: {why} (use {DEVICES})"));
        if text == "fake-h7" {
            return Ok(Self::FakeH7);
        }
        if let Some(rest) = text.strip_prefix("h7://") {
            let (host, query) = match rest.split_once('?') {
                Some((h, q)) => (h, Some(q)),
                None => (rest, None),
            };
            let server = resolve(host, H7_PORT).map_err(bad)?;
            let r3_port = match query {
                None => R3_PORT,
                Some(q) => q
                    .strip_prefix("r3=")
                    .and_then(|p| p.parse::<u16>().ok())
                    .filter(|&p| p != 0)
                    .ok_or_else(|| bad(format!("`?{q}`: expected ?r3=PORT")))?,
            };
            return Ok(Self::H7 {
                server,
                r3: SocketAddr::new(server.ip(), r3_port),
            });
        }
        if text == "fake-cia402" {
            return Ok(Self::FakeCia402);
        }
        if ["socketcan://", "cannelloni+udp://", "cannelloni+tcp://"]
            .iter()
            .any(|p| text.starts_with(p))
        {
            return DeviceAddress::parse(text).map(Self::Cia402).map_err(bad);
        }
        if let Some(rest) = text.strip_prefix("coach://") {
            let server = resolve(rest, rl_drivers::coach::DEFAULT_PORT).map_err(bad)?;
            return Ok(Self::Coach { server });
        }
        if let Some(rest) = text.strip_prefix("franka://") {
            let server = resolve(rest, rl_drivers::franka::COMMAND_PORT).map_err(bad)?;
            return Ok(Self::Franka { server });
        }
        if let Some(rest) = text.strip_prefix("ur://") {
            let (host, power_on) = match rest.split_once('?') {
                None => (rest, false),
                Some((h, "power-on")) => (h, true),
                Some((_, q)) => return Err(bad(format!("`?{q}`: expected ?power-on"))),
            };
            let server = resolve(host, rl_drivers::proto::rtde::PORT).map_err(bad)?;
            return Ok(Self::Ur { server, power_on });
        }
        if let Some(interface) = text.strip_prefix("ethercat://") {
            if interface.is_empty() || interface.len() > 15 || interface.contains('/') {
                return Err(bad(
                    "expected a network interface name (1 to 15 bytes)".into()
                ));
            }
            return Ok(Self::Ethercat {
                interface: interface.into(),
            });
        }
        Err(bad("unknown device".into()))
    }

    /// Whether the device runs at its own fixed cycle (`--rate` is refused).
    pub fn fixed_period(&self) -> bool {
        matches!(self, Self::H7 { .. } | Self::FakeH7)
    }

    /// Builds the device for `loaded`; `period` is the control period asked for, if any. An
    /// in-process fake stands at `home` (the start of a planned motion), else at the model's
    /// home position.
    pub fn build<const B: usize>(
        &self,
        loaded: &LoadedModel<B>,
        period: Option<Duration>,
        home: Option<&[f64]>,
    ) -> Result<Opened, CliError> {
        let model = &loaded.model;
        let home = home.map_or_else(|| loaded.home_or_neutral(), <[f64]>::to_vec);
        match self {
            Self::FakeH7 => {
                let config = fake_h7_config(loaded, &home)?;
                let fake = spawn_fake("fake-h7-0", move || FakeH7::spawn(config))
                    .map_err(|e| CliError::failed(format!("cannot start the fake H7: {e}")))?;
                let robot =
                    MitsubishiH7::new(MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr()))
                        .map_err(|e| CliError::failed(format!("H7 device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!(
                        "fake H7 in-process on {} (R3 {})",
                        fake.udp_addr(),
                        fake.r3_addr()
                    ),
                    fake: Some(InProcessFake::H7(fake)),
                })
            }
            Self::H7 { server, r3 } => {
                // The controller reports its axes (JPOSF) when the device opens; the run then
                // refuses a model with another joint count.
                let robot = MitsubishiH7::new(MitsubishiH7Config::at(*server, *r3))
                    .map_err(|e| CliError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("H7 at {server} (R3 {r3})"),
                    fake: None,
                })
            }
            Self::FakeCia402 => {
                let units = AxisUnits::GEARED_100;
                let config = FakeCia402Config::for_model(model, &home, units)
                    .map_err(|e| CliError::usage(format!("fake CiA 402 drives: {e}")))?;
                let loopback = CanAddress::parse("cannelloni+udp://127.0.0.1:0")
                    .map_err(|e| CliError::failed(e.to_string()))?;
                let fake = spawn_fake("fake-cia402-0", move || {
                    FakeCia402::serve(config, &loopback)
                })
                .map_err(|e| CliError::failed(format!("cannot start the fake drives: {e}")))?;
                let addr = fake
                    .local_addr()
                    .ok_or_else(|| CliError::failed("the fake drives have no address"))?;
                let bus = CanAddress::CannelloniUdp {
                    remote: addr,
                    local: default_local(addr),
                };
                let nodes: Vec<u8> = (1..=model.dof() as u8).collect();
                let robot = cia402(bus, &nodes, units, period)?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!(
                        "fake CiA 402 drives in-process on cannelloni+udp://{addr}, nodes 1-{}",
                        nodes.len()
                    ),
                    fake: Some(InProcessFake::Cia402(fake)),
                })
            }
            Self::Cia402(address) => {
                let nodes = address
                    .nodes
                    .clone()
                    .unwrap_or_else(|| (1..=model.dof() as u8).collect());
                if nodes.len() != model.dof() {
                    return Err(CliError::usage(format!(
                        "--device {}: {} nodes for a model with {} joints",
                        address.bus,
                        nodes.len(),
                        model.dof()
                    )));
                }
                let robot = cia402(address.bus.clone(), &nodes, AxisUnits::GEARED_100, period)?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("CiA 402 drives {nodes:?} on {}", address.bus),
                    fake: None,
                })
            }
            Self::Ethercat { interface } => {
                // Say what raw sockets need before anything else fails on it.
                if let Err(e) = PacketLink::open(interface, ETHERTYPE) {
                    let fix = if packet::is_permission_error(&e) {
                        format!("; {}", packet::PERMISSION_REMEDY)
                    } else {
                        String::new()
                    };
                    return Err(CliError::failed(format!(
                        "--device ethercat://{interface}: {e}{fix}"
                    )));
                }
                let mut config = EthercatConfig::new(interface);
                if let Some(p) = period {
                    config.period = p;
                }
                let robot = EthercatDrives::new(config)
                    .map_err(|e| CliError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("EtherCAT CiA 402 drives on {interface}"),
                    fake: None,
                })
            }
            Self::Franka { server } => {
                let mut config = rl_drivers::franka::FrankaConfig::new(server.ip());
                config.command_port = server.port();
                let robot = rl_drivers::FrankaArm::new(config)
                    .map_err(|e| CliError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("Franka arm at {server} (FCI, joint positions at 1 kHz)"),
                    fake: None,
                })
            }
            Self::Ur { server, power_on } => {
                if model.dof() != rl_drivers::ur::DOF {
                    return Err(CliError::usage(format!(
                        "--device ur://{server}: the model has {} joints; a UR arm has 6",
                        model.dof()
                    )));
                }
                let mut config = rl_drivers::ur::UrConfig::new(server.ip());
                config.rtde_port = server.port();
                config.power_on = *power_on;
                let robot = rl_drivers::UniversalRobot::new(config)
                    .map_err(|e| CliError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("UR at {server} (RTDE, joint positions at 500 Hz)"),
                    fake: None,
                })
            }
            Self::Coach { server } => {
                let mut config = CoachConfig::new(model.dof());
                config.server = *server;
                if let Some(p) = period {
                    config.update_period = p;
                }
                let robot =
                    Coach::new(config).map_err(|e| CliError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("Coach at {server}"),
                    fake: None,
                })
            }
        }
    }
}

/// Starts an in-process fake. Real controllers and drives do not share the controller's CPU
/// time: where the process may, the fake's threads run SCHED_FIFO (they inherit the policy of
/// the thread that starts them), one priority below the loop's default; else as they are.
fn spawn_fake<T: Send + 'static, E: std::fmt::Display>(
    name: &str,
    start: impl FnOnce() -> Result<T, E> + Clone + Send + 'static,
) -> Result<T, String> {
    let rt = rl_rt::RtThreadBuilder::new(name)
        .policy(rl_rt::Policy::Fifo)
        .priority(79)
        .spawn({
            let start = start.clone();
            move || start().map_err(|e| e.to_string())
        });
    match rt {
        Ok(thread) => thread
            .join()
            .map_err(|_| "its start-up thread panicked".to_owned())?,
        // No right to SCHED_FIFO: start it here, as this thread runs.
        Err(_) => start().map_err(|e| e.to_string()),
    }
}

/// The in-process fake H7 for a model: its limits and speed limits, standing at `home`.
fn fake_h7_config<const B: usize>(
    loaded: &LoadedModel<B>,
    home: &[f64],
) -> Result<FakeH7Config, CliError> {
    FakeH7Config::for_model(&loaded.model, home)
        .map_err(|e| CliError::usage(format!("--model: the fake H7 cannot simulate it: {e}")))
}

/// A CiA 402 device on `bus` for `nodes` with `units`, at `period` (2 ms by default); a cycle
/// the bus cannot carry is refused with the arithmetic.
fn cia402(
    bus: CanAddress,
    nodes: &[u8],
    units: AxisUnits,
    period: Option<Duration>,
) -> Result<Cia402, CliError> {
    let mut config = Cia402Config::new(bus, nodes);
    if let Some(p) = period {
        config = config.with_period(p);
    }
    for a in &mut config.axes {
        a.units = units;
    }
    let load = config.bus_load();
    if !load.fits(config.period) {
        return Err(CliError::usage(format!(
            "--rate: a {} µs cycle cannot carry {} CiA 402 axes: {load}",
            config.period.as_micros(),
            nodes.len()
        )));
    }
    Cia402::new(config).map_err(|e| CliError::usage(format!("--device: {e}")))
}

/// `HOST[:PORT]` to an address (the first the resolver gives).
fn resolve(host: &str, default_port: u16) -> Result<SocketAddr, String> {
    if host.is_empty() {
        return Err("no host".into());
    }
    if let Ok(addr) = host.parse::<SocketAddr>() {
        return Ok(addr);
    }
    let with_port = match host.rsplit_once(':') {
        Some((_, port)) if !host.ends_with(']') && port.parse::<u16>().is_ok() => {
            host.to_socket_addrs()
        }
        _ => (
            host.trim_start_matches('[').trim_end_matches(']'),
            default_port,
        )
            .to_socket_addrs(),
    };
    with_port
        .map_err(|e| format!("cannot resolve `{host}`: {e}"))?
        .next()
        .ok_or_else(|| format!("`{host}` has no address"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_parse_with_default_ports() {
        assert_eq!(DeviceSpec::parse("fake-h7").ok(), Some(DeviceSpec::FakeH7));
        assert_eq!(
            DeviceSpec::parse("h7://127.0.0.1").ok(),
            Some(DeviceSpec::H7 {
                server: "127.0.0.1:10000".parse().expect("addr"),
                r3: "127.0.0.1:10001".parse().expect("addr"),
            })
        );
        assert_eq!(
            DeviceSpec::parse("h7://10.0.0.2:2000?r3=2001").ok(),
            Some(DeviceSpec::H7 {
                server: "10.0.0.2:2000".parse().expect("addr"),
                r3: "10.0.0.2:2001".parse().expect("addr"),
            })
        );
        assert_eq!(
            DeviceSpec::parse("coach://127.0.0.1").ok(),
            Some(DeviceSpec::Coach {
                server: "127.0.0.1:11235".parse().expect("addr"),
            })
        );
        assert_eq!(
            DeviceSpec::parse("fake-cia402").ok(),
            Some(DeviceSpec::FakeCia402)
        );
        assert!(matches!(
            DeviceSpec::parse("cannelloni+udp://127.0.0.1:20000?nodes=1-6"),
            Ok(DeviceSpec::Cia402(a)) if a.nodes == Some(vec![1, 2, 3, 4, 5, 6])
        ));
        assert!(matches!(
            DeviceSpec::parse("socketcan://can0"),
            Ok(DeviceSpec::Cia402(_))
        ));
        assert_eq!(
            DeviceSpec::parse("franka://127.0.0.2").ok(),
            Some(DeviceSpec::Franka {
                server: "127.0.0.2:1337".parse().expect("addr"),
            })
        );
        assert_eq!(
            DeviceSpec::parse("ur://127.0.0.3?power-on").ok(),
            Some(DeviceSpec::Ur {
                server: "127.0.0.3:30004".parse().expect("addr"),
                power_on: true,
            })
        );
        assert_eq!(
            DeviceSpec::parse("ethercat://eth1").ok(),
            Some(DeviceSpec::Ethercat {
                interface: "eth1".into()
            })
        );
        for bad in [
            "ethercat://",
            "ethercat://a-name-far-too-long",
            "socketcan://",
            "cannelloni+udp://127.0.0.1:1?nodes=0",
            "cannelloni+tcp://nohost",
            "h7",
            "h7://",
            "h7://1.2.3.4?r3=x",
            "tcp://1.2.3.4",
            "coach://",
            "franka://",
            "ur://",
            "ur://1.2.3.4?fast",
        ] {
            let e = DeviceSpec::parse(bad).expect_err(bad);
            assert_eq!(e.exit_code(), 2, "{bad}");
        }
    }
}
