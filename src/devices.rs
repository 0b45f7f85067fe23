//! The device table: a text such as `fake-h7`, `h7://HOST` or `cannelloni+udp://HOST:PORT`
//! names a driver and where it is; [`DeviceSpec::build`] opens the device (and, for an
//! in-process fake, starts the fake) for a model, ready for [`crate::controller::ControlRun`].
//! `rl run --device`, the Python wheel and a user's own program share it:
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use std::time::Duration;
//! use rl::controller::{ControlRun, RunOptions, Supervision};
//! use rl::devices::DeviceSpec;
//! let loaded = rl::core::loader::load_file::<16>("tests/data/rlmdl/mitsubishi-rv6sl.xml")?;
//! let opened = DeviceSpec::parse("fake-h7")?.build(
//!     &loaded,
//!     None,
//!     None,
//!     Supervision::default().device_failure_limit(),
//!     false,
//! )?;
//! let _fake = opened.fake; // an in-process fake lives as long as this value
//! let options = RunOptions::default().duration(Duration::from_secs(2));
//! let run = ControlRun::<_, 16, 16>::start(opened.robot, loaded, options)?;
//! println!("{}", run.join());
//! # Ok(())
//! # }
//! ```
//!
//! This is the one place that names concrete drivers; the controller runtime only sees their
//! capabilities.

use std::net::{SocketAddr, ToSocketAddrs};
use std::time::Duration;

use crate::controller::{JointRobot, PeerLateness, RunError};
use rl_core::loader::LoadedModel;
use rl_drivers::Error as DeviceError;
use rl_drivers::EthercatDrives;
use rl_drivers::canopen::{Cia402, Cia402Config, DeviceAddress};
use rl_drivers::cia402::{AxisUnits, PowerState, UnitsOverride};
use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::ethercat::EthercatConfig;
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
use rl_drivers::fake::h7_controller::{self, FakeH7, FakeH7Config};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::proto::ecat::frame::ETHERTYPE;
use rl_drivers::transport::can::socketcan::{EAFNOSUPPORT, NO_AF_CAN};
use rl_drivers::transport::can::{CanAddress, default_local};
use rl_drivers::transport::{PacketLink, packet};

/// H7 real-time UDP port.
const H7_PORT: u16 = 10000;
/// H7 R3 TCP port.
const R3_PORT: u16 = 10001;

/// One form of device text [`DeviceSpec::parse`] accepts: a row of the device table, from
/// which `rl run --help`, the parse errors and the tests take the list of forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeviceForm {
    /// The form, e.g. `h7://HOST[:PORT][?r3=PORT]`.
    pub form: &'static str,
    /// What it drives, in a few words.
    pub what: &'static str,
    /// The control period it runs at unless `--rate` gives another, as the help says it.
    pub period: &'static str,
    /// Whether the device runs at its own fixed cycle, so that a rate is refused
    /// ([`DeviceSpec::fixed_period`]).
    pub fixed_period: bool,
    /// A text of this form that parses without a network or a device (for the tests).
    pub example: &'static str,
}

/// Every form of device text, in the order the help lists them.
pub const DEVICE_FORMS: &[DeviceForm] = &[
    DeviceForm {
        form: "fake-h7",
        what: "a fake Mitsubishi H7 controller in this process on loopback",
        period: "its fixed 7.11 ms cycle",
        fixed_period: true,
        example: "fake-h7",
    },
    DeviceForm {
        form: "h7://HOST[:PORT][?r3=PORT]",
        what: "a MELFA controller (UDP 10000, R3 on TCP 10001 by default)",
        period: "its fixed 7.11 ms cycle",
        fixed_period: true,
        example: "h7://127.0.0.1?r3=10001",
    },
    DeviceForm {
        form: "coach://HOST[:PORT]",
        what: "an RL visualiser streamed the commanded joints (port 11235)",
        period: "10 ms",
        fixed_period: false,
        example: "coach://127.0.0.1",
    },
    DeviceForm {
        form: "fake-cia402",
        what: "fake CiA 402 drives in this process on cannelloni UDP loopback",
        period: "2 ms",
        fixed_period: false,
        example: "fake-cia402",
    },
    DeviceForm {
        form: "cannelloni+udp://HOST:PORT[?nodes=1-6][&units=…]",
        what: "CiA 402 drives over CANopen through a cannelloni UDP gateway",
        period: "2 ms",
        fixed_period: false,
        example: "cannelloni+udp://127.0.0.1:20000?nodes=1-6",
    },
    DeviceForm {
        form: "cannelloni+tcp://HOST:PORT[?listen][&nodes=…][&units=…]",
        what: "the same over cannelloni TCP",
        period: "2 ms",
        fixed_period: false,
        example: "cannelloni+tcp://127.0.0.1:20000",
    },
    DeviceForm {
        form: "socketcan://IFACE[?nodes=…][&units=…]",
        what: "CiA 402 drives over CANopen on a SocketCAN interface",
        period: "2 ms",
        fixed_period: false,
        example: "socketcan://can0?nodes=1-6",
    },
    DeviceForm {
        form: "ethercat://IF[?units=…]",
        what: "CiA 402 drives on an EtherCAT segment on interface IF (root or CAP_NET_RAW)",
        period: "1 ms",
        fixed_period: false,
        example: "ethercat://eth1",
    },
    DeviceForm {
        form: "franka://HOST[:PORT]",
        what: "a Franka FR3 or Panda over FCI, joint positions (port 1337)",
        period: "the robot's 1 ms",
        fixed_period: false,
        example: "franka://127.0.0.1",
    },
    DeviceForm {
        form: "ur://HOST[:PORT][?power-on]",
        what: "a Universal Robots arm over RTDE (port 30004)",
        period: "the controller's 2 ms",
        fixed_period: false,
        example: "ur://127.0.0.1?power-on",
    },
];

/// The control rates a device takes, Hz (lowest, highest); the device's own cycle may allow
/// less ([`DeviceSpec::period_for_rate`]).
pub const RATE_HZ: (f64, f64) = (0.1, 20_000.0);

/// The forms of [`DEVICE_FORMS`] in one line, for messages: `fake-h7, h7://…, … or ur://…`.
pub fn device_forms() -> String {
    let forms: Vec<&str> = DEVICE_FORMS.iter().map(|f| f.form).collect();
    match forms.split_last() {
        Some((last, [])) => (*last).to_owned(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// The table as the help of a `--device` flag: one line per form, what it drives and the
/// control period it runs at unless a rate is given.
pub fn device_help() -> String {
    let mut text = String::from("The robot [default: fake-h7]. One of:");
    for f in DEVICE_FORMS {
        text.push_str(&format!("\n  {}: {}; {}", f.form, f.what, f.period));
        if f.fixed_period {
            text.push_str(" (no --rate)");
        }
    }
    text
}

/// The form of `units=` (and `--units`), for messages.
pub const UNITS_FORM: &str = "cpr:N,gear:G[,feed:F][,torque:NM][,lead:M], each value one number \
     for every axis or one per axis joined by `/` (e.g. gear:100/100/80/50/50/50)";

/// Why a device text was refused or its device could not be opened: the message says what and
/// where; [`SpecError::is_input`] tells the caller's input (a wrong text, model or units) from a
/// device that failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SpecError {
    message: String,
    input: bool,
}

impl SpecError {
    /// The caller's input is wrong.
    pub fn usage(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            input: true,
        }
    }

    /// The device (or the fake) failed.
    pub fn failed(message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            input: false,
        }
    }

    /// Whether the caller's input was wrong (else the device failed).
    pub fn is_input(&self) -> bool {
        self.input
    }

    /// The message.
    pub fn message(&self) -> &str {
        &self.message
    }
}

impl std::fmt::Display for SpecError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for SpecError {}

/// Drive units the user gives (`?units=` or `--units`): they replace what the drives report in
/// 0x608F (`cpr`), 0x6091 (`gear`), 0x6092 (`feed`) and 0x6076 (`torque`); `lead` is the travel
/// of a linear axis per revolution. `cpr` and `gear` go together; without `feed` the position
/// unit is the encoder count (`feed = cpr × gear`); without `torque` the rated torque is read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct UnitsSpec {
    counts_per_rev: Vec<f64>,
    gear: Vec<f64>,
    feed: Vec<f64>,
    torque: Vec<f64>,
    lead: Vec<f64>,
}

impl UnitsSpec {
    /// Parses [`UNITS_FORM`].
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = |why: String| format!("units `{text}`: {why} (give {UNITS_FORM})");
        let mut spec = Self::default();
        for part in text.split(',') {
            let (key, values) = part
                .split_once(':')
                .ok_or_else(|| bad(format!("`{part}` is not KEY:VALUE")))?;
            let slot = match key.trim() {
                "cpr" => &mut spec.counts_per_rev,
                "gear" => &mut spec.gear,
                "feed" => &mut spec.feed,
                "torque" => &mut spec.torque,
                "lead" => &mut spec.lead,
                other => return Err(bad(format!("unknown key `{other}`"))),
            };
            if !slot.is_empty() {
                return Err(bad(format!("`{key}` given twice")));
            }
            for v in values.split('/') {
                let x: f64 = v
                    .trim()
                    .parse()
                    .map_err(|_| bad(format!("`{v}` of `{key}` is not a number")))?;
                if !(x.is_finite() && x > 0.0) {
                    return Err(bad(format!("`{key}` must be positive, got {v}")));
                }
                slot.push(x);
            }
        }
        if spec.counts_per_rev.is_empty() != spec.gear.is_empty() {
            return Err(bad("`cpr` and `gear` go together".into()));
        }
        if !spec.feed.is_empty() && spec.gear.is_empty() {
            return Err(bad("`feed` needs `cpr` and `gear`".into()));
        }
        Ok(spec)
    }

    /// The override of each of `axes` axes.
    pub fn for_axes(&self, axes: usize) -> Result<Vec<UnitsOverride>, String> {
        let pick = |values: &[f64], key: &str, k: usize| -> Result<Option<f64>, String> {
            match values.len() {
                0 => Ok(None),
                1 => Ok(Some(values[0])),
                n if n == axes => Ok(Some(values[k])),
                n => Err(format!(
                    "units: {n} values of `{key}` for {axes} axes (give one, or one per axis)"
                )),
            }
        };
        (0..axes)
            .map(|k| {
                let counts_per_rev = pick(&self.counts_per_rev, "cpr", k)?;
                let gear_ratio = pick(&self.gear, "gear", k)?;
                let feed = match (pick(&self.feed, "feed", k)?, counts_per_rev, gear_ratio) {
                    (Some(f), _, _) => Some(f),
                    // Position unit = encoder count.
                    (None, Some(c), Some(g)) => Some(c * g),
                    _ => None,
                };
                Ok(UnitsOverride {
                    counts_per_rev,
                    gear_ratio,
                    feed,
                    rated_torque_nm: pick(&self.torque, "torque", k)?,
                    lead_m: pick(&self.lead, "lead", k)?,
                })
            })
            .collect()
    }
}

/// Splits `units=…` off a device address's query: the address without it, and its value.
fn take_units(text: &str) -> (String, Option<&str>) {
    let Some((base, query)) = text.split_once('?') else {
        return (text.to_owned(), None);
    };
    let mut units = None;
    let rest: Vec<&str> = query
        .split('&')
        .filter(|o| match o.strip_prefix("units=") {
            Some(u) => {
                units = Some(u);
                false
            }
            None => true,
        })
        .collect();
    let address = if rest.is_empty() {
        base.to_owned()
    } else {
        format!("{base}?{}", rest.join("&"))
    };
    (address, units)
}

/// The robot `rl run` drives.
#[derive(Clone, Debug, PartialEq)]
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
    /// CiA 402 drives on a CAN bus (SocketCAN or cannelloni), nodes 1..=dof unless given; the
    /// units given (else read from the drives).
    Cia402(DeviceAddress, Option<UnitsSpec>),
    /// CiA 402 drives on an EtherCAT segment on a network interface.
    Ethercat {
        /// The interface's name.
        interface: String,
        /// The units given (else read from the drives).
        units: Option<UnitsSpec>,
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
    /// How much later than the commands the measured joints follow by the device's own
    /// smoothing (a UR's `servoj` lookahead); zero for devices that execute a position within
    /// their cycle. The supervisor's tracking bound allows it
    /// ([`Supervision::allow_device_lag`](crate::controller::Supervision::allow_device_lag)).
    pub lag: Duration,
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
    /// How late the fake's own thread ran against its cycle (for the report's
    /// [`peer_lateness`](crate::controller::RunReport::peer_lateness)); `None` where the fake
    /// has no measure that tells a starved thread from a healthy one.
    pub lateness: Option<PeerLateness>,
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
                        "fake_late_ticks": s.late_ticks,
                        "fake_max_tick_lateness_ms": s.max_tick_lateness.as_secs_f64() * 1e3,
                    }),
                    lateness: Some(PeerLateness {
                        who: "the fake H7".to_owned(),
                        cycle: Some(h7_controller::CYCLE),
                        max: s.max_tick_lateness,
                        late: Some(s.late_ticks),
                        cycles: Some(s.cycles),
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
                    "fake_max_lateness_ms": s.max_lateness.as_secs_f64() * 1e3,
                });
                // The drives' `max_lateness` mixes a frame's wait in the socket with the
                // thread's poll timeouts and reads about 1 ms in a healthy 2 ms run: set against
                // the cycle it would blame the drives for every timing failure. It stays in the
                // JSON (`fake_max_lateness_ms`); the likely cause rests on the loop and the
                // delivery until the drives measure their own SYNC-to-answer lateness.
                let lateness = None;
                FakeSeen {
                    note,
                    safe,
                    json,
                    lateness,
                }
            }
        }
    }
}

impl DeviceSpec {
    /// Parses one of [`DEVICE_FORMS`].
    pub fn parse(text: &str) -> Result<Self, SpecError> {
        let bad = |why: String| {
            SpecError::usage(format!("--device {text}: {why} (use {})", device_forms()))
        };
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
        let (text_without_units, units) = take_units(text);
        let units = units.map(UnitsSpec::parse).transpose().map_err(bad)?;
        if units.is_some()
            && !text.starts_with("ethercat://")
            && !text.starts_with("socketcan://")
            && !text.starts_with("cannelloni+")
        {
            return Err(bad(
                "units= applies to CiA 402 drives (CANopen, EtherCAT)".into()
            ));
        }
        let text = text_without_units.as_str();
        if ["socketcan://", "cannelloni+udp://", "cannelloni+tcp://"]
            .iter()
            .any(|p| text.starts_with(p))
        {
            return DeviceAddress::parse(text)
                .map(|a| Self::Cia402(a, units))
                .map_err(bad);
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
                units,
            });
        }
        Err(bad("unknown device".into()))
    }

    /// Whether the device runs at its own fixed cycle (`--rate` is refused).
    pub fn fixed_period(&self) -> bool {
        matches!(self, Self::H7 { .. } | Self::FakeH7)
    }

    /// The control period of a rate of `hz` asked for this device: [`RATE_HZ`] holds the rates
    /// taken; a device on its fixed cycle ([`DeviceSpec::fixed_period`]) refuses any. The
    /// message names neither the flag nor the keyword: the caller puts its own before it.
    pub fn period_for_rate(&self, hz: f64) -> Result<Duration, SpecError> {
        let (low, high) = RATE_HZ;
        if !(hz.is_finite() && (low..=high).contains(&hz)) {
            return Err(SpecError::usage(format!(
                "{hz}: give a control rate in Hz between {low} and {high}"
            )));
        }
        if self.fixed_period() {
            return Err(SpecError::usage(format!(
                "{hz}: an H7 controller (and the fake one) runs at its own 7.11 ms cycle; a \
                 rate applies to the other devices"
            )));
        }
        Ok(Duration::from_secs_f64(1.0 / hz))
    }

    /// Gives the drives' units (`--units`); refused for a device that has none, or when the
    /// address gives them too.
    pub fn set_units(&mut self, spec: UnitsSpec) -> Result<(), SpecError> {
        match self {
            Self::Cia402(_, units @ None)
            | Self::Ethercat {
                units: units @ None,
                ..
            } => {
                *units = Some(spec);
                Ok(())
            }
            Self::Cia402(..) | Self::Ethercat { .. } => Err(SpecError::usage(
                "--units and the device's units= give the units twice: give them once",
            )),
            _ => Err(SpecError::usage(
                "--units: only CiA 402 drives (CANopen, EtherCAT) have drive units; this device \
                 reports joints",
            )),
        }
    }

    /// Builds the device for `loaded`; `period` is the control period asked for, if any;
    /// `failure_limit` failed steps in a row fault the device. An in-process fake stands at
    /// `home` (the start of a planned motion), else at the model's home position. `torque`:
    /// the run's law commands joint torques, and a device that has several command modes is
    /// opened in its torque mode (a Franka arm); the others are opened as always (and a run
    /// refuses a torque law on a device that takes no torques).
    pub fn build<const B: usize>(
        &self,
        loaded: &LoadedModel<B>,
        period: Option<Duration>,
        home: Option<&[f64]>,
        failure_limit: u32,
        torque: bool,
    ) -> Result<Opened, SpecError> {
        let model = &loaded.model;
        let home = home.map_or_else(|| loaded.home_or_neutral(), <[f64]>::to_vec);
        match self {
            Self::FakeH7 => {
                let config = fake_h7_config(loaded, &home)?;
                let fake = spawn_fake("fake-h7-0", move || FakeH7::spawn(config))
                    .map_err(|e| SpecError::failed(format!("cannot start the fake H7: {e}")))?;
                let mut config = MitsubishiH7Config::at(fake.udp_addr(), fake.r3_addr());
                config.max_consecutive_failures = failure_limit;
                let robot = MitsubishiH7::new(config)
                    .map_err(|e| SpecError::failed(format!("H7 device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!(
                        "fake H7 in-process on {} (R3 {})",
                        fake.udp_addr(),
                        fake.r3_addr()
                    ),
                    fake: Some(InProcessFake::H7(fake)),
                    lag: Duration::ZERO,
                })
            }
            Self::H7 { server, r3 } => {
                // The controller reports its axes (JPOSF) when the device opens; the run then
                // refuses a model with another joint count.
                let mut config = MitsubishiH7Config::at(*server, *r3);
                config.max_consecutive_failures = failure_limit;
                let robot = MitsubishiH7::new(config)
                    .map_err(|e| SpecError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("H7 at {server} (R3 {r3})"),
                    fake: None,
                    lag: Duration::ZERO,
                })
            }
            Self::FakeCia402 => {
                // The fake drives' own units (a 100:1 gear carries the inverse-dynamics
                // torques); the master reads them from the drives like any other.
                let config = FakeCia402Config::for_model(model, &home, AxisUnits::GEARED_100)
                    .map_err(|e| SpecError::usage(format!("fake CiA 402 drives: {e}")))?;
                let loopback = CanAddress::parse("cannelloni+udp://127.0.0.1:0")
                    .map_err(|e| SpecError::failed(e.to_string()))?;
                let fake = spawn_fake("fake-cia402-0", move || {
                    FakeCia402::serve(config, &loopback)
                })
                .map_err(|e| SpecError::failed(format!("cannot start the fake drives: {e}")))?;
                let addr = fake
                    .local_addr()
                    .ok_or_else(|| SpecError::failed("the fake drives have no address"))?;
                let bus = CanAddress::CannelloniUdp {
                    remote: addr,
                    local: default_local(addr),
                };
                let nodes: Vec<u8> = (1..=model.dof() as u8).collect();
                let units = vec![UnitsOverride::NONE; nodes.len()];
                let robot = cia402(bus, &nodes, &units, period, failure_limit)?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!(
                        "fake CiA 402 drives in-process on cannelloni+udp://{addr}, nodes 1-{}",
                        nodes.len()
                    ),
                    fake: Some(InProcessFake::Cia402(fake)),
                    lag: Duration::ZERO,
                })
            }
            Self::Cia402(address, units) => {
                let nodes = address
                    .nodes
                    .clone()
                    .unwrap_or_else(|| (1..=model.dof() as u8).collect());
                if nodes.len() != model.dof() {
                    return Err(SpecError::usage(format!(
                        "--device {}: {} nodes for a model with {} joints",
                        address.bus,
                        nodes.len(),
                        model.dof()
                    )));
                }
                let units = given_units(units.as_ref(), nodes.len())?;
                let robot = cia402(address.bus.clone(), &nodes, &units, period, failure_limit)?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("CiA 402 drives {nodes:?} on {}", address.bus),
                    fake: None,
                    lag: Duration::ZERO,
                })
            }
            Self::Ethercat { interface, units } => {
                // Say what raw sockets need before anything else fails on it.
                if let Err(e) = PacketLink::open(interface, ETHERTYPE) {
                    let fix = if packet::is_permission_error(&e) {
                        format!("; {}", packet::PERMISSION_REMEDY)
                    } else {
                        String::new()
                    };
                    return Err(SpecError::failed(format!(
                        "--device ethercat://{interface}: {e}{fix}"
                    )));
                }
                let mut config = EthercatConfig::new(interface);
                if let Some(p) = period {
                    config.period = p;
                }
                // Drives are found by the scan: the model's joint count is what must match.
                config.units = given_units(units.as_ref(), model.dof())?;
                config.max_consecutive_failures = failure_limit;
                let robot = EthercatDrives::new(config)
                    .map_err(|e| SpecError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("EtherCAT CiA 402 drives on {interface}"),
                    fake: None,
                    lag: Duration::ZERO,
                })
            }
            Self::Franka { server } => {
                let (mode, what) = if torque {
                    (
                        rl_drivers::franka::ControlMode::JointTorque,
                        "joint torques",
                    )
                } else {
                    (
                        rl_drivers::franka::ControlMode::JointPosition,
                        "joint positions",
                    )
                };
                let mut config = rl_drivers::franka::FrankaConfig::new(server.ip()).with_mode(mode);
                config.command_port = server.port();
                let robot = rl_drivers::FrankaArm::new(config)
                    .map_err(|e| SpecError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("Franka arm at {server} (FCI, {what} at 1 kHz)"),
                    fake: None,
                    lag: Duration::ZERO,
                })
            }
            Self::Ur { server, power_on } => {
                if model.dof() != rl_drivers::ur::DOF {
                    return Err(SpecError::usage(format!(
                        "--device ur://{server}: the model has {} joints; a UR arm has 6",
                        model.dof()
                    )));
                }
                let mut config = rl_drivers::ur::UrConfig::new(server.ip());
                config.rtde_port = server.port();
                config.power_on = *power_on;
                // The measured joints trail `servoj`'s commands by its lookahead.
                let lag = Duration::from_secs_f64(config.lookahead_time);
                let robot = rl_drivers::UniversalRobot::new(config)
                    .map_err(|e| SpecError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("UR at {server} (RTDE, joint positions at 500 Hz)"),
                    fake: None,
                    lag,
                })
            }
            Self::Coach { server } => {
                let mut config = CoachConfig::new(model.dof());
                config.server = *server;
                config.max_consecutive_failures = failure_limit;
                if let Some(p) = period {
                    config.update_period = p;
                }
                let robot =
                    Coach::new(config).map_err(|e| SpecError::usage(format!("--device: {e}")))?;
                Ok(Opened {
                    robot: Box::new(robot),
                    name: format!("Coach at {server}"),
                    fake: None,
                    lag: Duration::ZERO,
                })
            }
        }
    }
}

impl DeviceSpec {
    /// What a user reads when the run could not start: the error, and for the errors a user
    /// meets first — no CAN sockets, nothing listening at the address, nobody on the bus or
    /// the segment — what they mean and what to do.
    pub fn explain(&self, error: &RunError) -> String {
        let text = error.to_string();
        let RunError::Device {
            stage: "open",
            error,
        } = error
        else {
            return text;
        };
        let refused = matches!(
            error,
            DeviceError::Io {
                kind: std::io::ErrorKind::ConnectionRefused,
                ..
            }
        );
        let hint = match self {
            Self::Cia402(address, _) => match (&address.bus, error) {
                (
                    CanAddress::SocketCan { .. },
                    DeviceError::Io {
                        kind: std::io::ErrorKind::Unsupported,
                        ..
                    }
                    | DeviceError::Io {
                        os_code: Some(EAFNOSUPPORT),
                        ..
                    },
                ) => Some(NO_AF_CAN.to_owned()),
                (
                    CanAddress::SocketCan { interface },
                    DeviceError::Io {
                        kind: std::io::ErrorKind::NotFound,
                        ..
                    },
                ) => Some(format!(
                    "there is no network interface `{interface}` (see `ip link`)"
                )),
                (bus, e)
                    if matches!(e, DeviceError::Timeout { .. })
                        || text.contains("no SDO answer in time") =>
                {
                    Some(format!(
                        "no drive answers on {bus}: is the bus powered and the gateway there? \
                         For fake drives start `rl fake-robot canopen --bus {bus}`"
                    ))
                }
                (bus, _) if refused => Some(format!(
                    "nothing listens at {bus}; for fake drives start `rl fake-robot canopen \
                     --bus {bus}`"
                )),
                _ => None,
            },
            Self::H7 { server, r3 } if refused => Some(format!(
                "no H7 controller listens at {r3} (R3, TCP; real-time UDP {server}): check the \
                 address and that the controller's R3 server is on, or start a fake with `rl \
                 fake-robot h7 --bind {server} --r3-bind {r3}`"
            )),
            Self::Coach { server } if refused => Some(format!(
                "no Coach server listens at {server}: start RL's rlCoachMdl with the model, or \
                 `rl fake-robot coach --bind {server} --model FILE`"
            )),
            _ => None,
        };
        match hint {
            Some(h) => format!("{text}: {h}"),
            None => text,
        }
    }
}

/// Starts an in-process fake. Real controllers and drives do not share the controller's CPU
/// time: where the process may, the fake's threads run SCHED_FIFO (they inherit the policy of
/// the thread that starts them), one priority below the loop's default; else as they are.
/// The priority of an in-process fake's threads: one below `rl run`'s loop (80), above any
/// test's loop.
pub const FAKE_PRIORITY: i32 = 79;

/// Gives the calling thread [`FAKE_PRIORITY`] under SCHED_FIFO where the process may (else it
/// runs as it is): real controllers and drives answer on their own CPUs, unhindered by the
/// machine's other programs, and a fake's pacing thread should not be either. For a fake's
/// `on_thread_start` hook (`FakeH7Config`, `FakeSegmentConfig`, …).
pub fn fake_thread_realtime() {
    fake_thread_at(FAKE_PRIORITY);
}

/// The priority of the threads of a fake in a process of its own (`rl fake-robot …`) and of
/// the 1 kHz fakes (Franka, EtherCAT) beside a test's loop: above `rl run`'s loop (80), as a
/// device's own CPU would be.
pub const FAKE_PROCESS_PRIORITY: i32 = 85;

/// Gives the calling thread [`FAKE_PROCESS_PRIORITY`] under SCHED_FIFO where the process may
/// (else it runs as it is); see [`fake_thread_realtime`].
pub fn fake_process_thread_realtime() {
    fake_thread_at(FAKE_PROCESS_PRIORITY);
}

/// The calling thread at SCHED_FIFO `priority` where the process may; else unchanged.
fn fake_thread_at(priority: i32) {
    let _ = rl_rt::RtThreadBuilder::new("fake")
        .policy(rl_rt::Policy::Fifo)
        .priority(priority)
        .best_effort(true)
        .apply_to_current();
}

fn spawn_fake<T: Send + 'static, E: std::fmt::Display>(
    name: &str,
    start: impl FnOnce() -> Result<T, E> + Clone + Send + 'static,
) -> Result<T, String> {
    let rt = rl_rt::RtThreadBuilder::new(name)
        .policy(rl_rt::Policy::Fifo)
        .priority(FAKE_PRIORITY)
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
) -> Result<FakeH7Config, SpecError> {
    FakeH7Config::for_model(&loaded.model, home)
        .map_err(|e| SpecError::usage(format!("--model: the fake H7 cannot simulate it: {e}")))
}

/// The units given for `axes` axes (nothing given: every unit is read from the drives).
fn given_units(spec: Option<&UnitsSpec>, axes: usize) -> Result<Vec<UnitsOverride>, SpecError> {
    match spec {
        None => Ok(vec![UnitsOverride::NONE; axes]),
        Some(s) => s.for_axes(axes).map_err(SpecError::usage),
    }
}

/// A CiA 402 device on `bus` for `nodes` with the units given per axis (the rest read from the
/// drives), at `period` (2 ms by default); a cycle the bus cannot carry is refused with the
/// arithmetic.
fn cia402(
    bus: CanAddress,
    nodes: &[u8],
    units: &[UnitsOverride],
    period: Option<Duration>,
    failure_limit: u32,
) -> Result<Cia402, SpecError> {
    let mut config = Cia402Config::new(bus, nodes);
    if let Some(p) = period {
        config = config.with_period(p);
    }
    config.max_consecutive_failures = failure_limit;
    for (a, u) in config.axes.iter_mut().zip(units) {
        a.units = *u;
    }
    let load = config.bus_load();
    if !load.fits(config.period) {
        return Err(SpecError::usage(format!(
            "--rate: a {} µs cycle cannot carry {} CiA 402 axes: {load}",
            config.period.as_micros(),
            nodes.len()
        )));
    }
    Cia402::new(config).map_err(|e| SpecError::usage(format!("--device: {e}")))
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
    fn every_form_of_the_table_parses_and_says_whether_it_takes_a_rate() {
        for f in DEVICE_FORMS {
            let spec = DeviceSpec::parse(f.example)
                .unwrap_or_else(|e| panic!("{} ({}): {e}", f.form, f.example));
            assert_eq!(spec.fixed_period(), f.fixed_period, "{}", f.form);
            assert_eq!(
                spec.period_for_rate(100.0).is_ok(),
                !f.fixed_period,
                "{}",
                f.form
            );
            assert!(device_forms().contains(f.form) && device_help().contains(f.form));
        }
        let e = DeviceSpec::parse("tcp://1.2.3.4").unwrap_err();
        assert!(e.message().contains(&device_forms()), "{e}");
        let coach = DeviceSpec::parse("coach://127.0.0.1").unwrap();
        assert_eq!(coach.period_for_rate(200.0), Ok(Duration::from_millis(5)));
        for hz in [0.0, -5.0, f64::NAN, 20_001.0] {
            assert!(coach.period_for_rate(hz).is_err(), "{hz}");
        }
    }

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
            Ok(DeviceSpec::Cia402(a, None)) if a.nodes == Some(vec![1, 2, 3, 4, 5, 6])
        ));
        assert!(matches!(
            DeviceSpec::parse("socketcan://can0"),
            Ok(DeviceSpec::Cia402(_, None))
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
                interface: "eth1".into(),
                units: None,
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
            "franka://127.0.0.1?units=cpr:1,gear:1",
            "cannelloni+udp://127.0.0.1:1?units=gear:100",
            "cannelloni+udp://127.0.0.1:1?units=cpr:0,gear:100",
            "cannelloni+udp://127.0.0.1:1?units=cpr:4096,gear:x",
            "cannelloni+udp://127.0.0.1:1?units=cpr:4096,gear:1,speed:3",
            "ethercat://eth0?units=feed:1000",
            "h7://1.2.3.4?units=cpr:1,gear:1",
        ] {
            let e = DeviceSpec::parse(bad).expect_err(bad);
            assert!(e.is_input(), "{bad}");
        }
    }

    #[test]
    fn units_are_given_per_axis_or_for_all() {
        let Ok(DeviceSpec::Cia402(a, Some(spec))) = DeviceSpec::parse(
            "cannelloni+udp://127.0.0.1:20000?units=cpr:4096,gear:121/101/80,torque:0.5&nodes=1-3",
        ) else {
            panic!("parses");
        };
        assert_eq!(a.nodes, Some(vec![1, 2, 3]));
        let u = spec.for_axes(3).expect("three axes");
        assert_eq!(u[1].gear_ratio, Some(101.0));
        assert_eq!(u[2].counts_per_rev, Some(4096.0));
        // Without `feed:` the position unit is the encoder count.
        assert_eq!(u[0].feed, Some(4096.0 * 121.0));
        assert_eq!(u[0].rated_torque_nm, Some(0.5));
        assert!(spec.for_axes(2).is_err(), "three gears for two axes");
        // Only the rated torque given: the position scaling is read.
        let t = UnitsSpec::parse("torque:2")
            .expect("torque only")
            .for_axes(6)
            .expect("six");
        assert_eq!(
            (t[5].gear_ratio, t[5].feed, t[5].rated_torque_nm),
            (None, None, Some(2.0))
        );
        let mut d = DeviceSpec::parse("ethercat://eth1").expect("ethercat");
        d.set_units(UnitsSpec::parse("cpr:1,gear:1").expect("units"))
            .expect("given once");
        assert!(d.set_units(UnitsSpec::default()).is_err(), "given twice");
        assert!(DeviceSpec::FakeH7.set_units(UnitsSpec::default()).is_err());
    }
}
