//! The cyclic device for a Robotiq 2F-85/140: [`RobotiqGripper`], over any [`ModbusMaster`].
//!
//! - `open`: reads the status once (a gripper that does not answer fails `open` with a
//!   timeout naming its line and unit).
//! - `start`: unless the gripper is activated already, resets it (`rACT = 0`) and activates it
//!   (`rACT = 1`), then reads its status until the activation completes (`gSTA = 3`), bounded
//!   by [`GripperConfig::activation_timeout`]; a major fault on the way fails `start`. The
//!   buffered command then holds the fingers where they are (`rGTO = 0`).
//! - `step`: one transaction in [`Exchange::ReadWrite`] (function 0x17: the command written,
//!   the status read), or in [`Exchange::Separate`] a write (0x10) when the command changed and
//!   a read (0x04). A major fault (undervoltage, internal, activation, overcurrent, automatic
//!   release) fails the step with the fault; so does a gripper that lost its activation (power
//!   cycled). Priority and minor faults are counted and shown in [`RobotiqGripper::status`].
//! - `stop`: halts the fingers (`rGTO = 0`), keeping the activation and the grip force.
//! - `close`: drops the line (the master).
//!
//! Positions, speeds and forces are set in the gripper's units (0 to 255) or in SI units
//! converted linearly over the model's ranges (the gripper's own mapping is close to linear;
//! see [`GripperConfig::open_count`]). `step` allocates nothing.

use core::time::Duration;
use std::time::Instant;

use super::master::{MasterError, ModbusMaster, check_answer};
use crate::capability::{Delivery, Gripper, LinkStatistics, LinkStatisticsSensor};
use crate::device::{
    DeviceError, Driver, Error, ErrorKind, Lifecycle, Operation, State, impl_cyclic_device,
};
use crate::proto::modbus::{ExceptionCode, MAX_PDU, Registers, Request, Response};
use crate::proto::robotiq::{
    ActivationStatus, COMMAND_REGISTER, Command, DEFAULT_UNIT, Fault, Model, STATUS_REGISTER,
    Severity, Status, USED_REGISTERS,
};

const SOURCE: &str = "Robotiq gripper";

/// How a step talks to the gripper.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Exchange {
    /// One transaction a step: read/write multiple registers (0x17).
    #[default]
    ReadWrite,
    /// Write multiple registers (0x10) when the command changed, then read input registers
    /// (0x04): what RL's `RobotiqModelC` does (with 0x03), for gateways without 0x17.
    Separate,
}

/// Configuration of a [`RobotiqGripper`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GripperConfig {
    /// The gripper's Modbus unit ([`DEFAULT_UNIT`]).
    pub unit: u8,
    /// Which gripper.
    pub model: Model,
    /// How a step talks to it.
    pub exchange: Exchange,
    /// The control period (the device's update period).
    pub period: Duration,
    /// Largest wait for one answer.
    pub response_timeout: Duration,
    /// Largest wait for the activation to complete.
    pub activation_timeout: Duration,
    /// Speed and force of the commands until set otherwise (0 to 255).
    pub speed: u8,
    /// See [`speed`](Self::speed).
    pub force: u8,
    /// The position count of the fully open gripper (its opening is the model's stroke).
    pub open_count: u8,
    /// The position count of the fully closed gripper (opening 0).
    pub closed_count: u8,
    /// Failed steps in a row that fault the device.
    pub max_failures: u32,
    /// Times a request of `open`, `start` or `stop` is sent again after no answer or a corrupt
    /// one (a frame lost on the line); a step is never repeated (its failure is counted and the
    /// next step is the retry).
    pub retries: u8,
}

impl GripperConfig {
    /// A 2F-85 at unit 9, one read/write a step every 10 ms.
    pub fn new(model: Model) -> Self {
        Self {
            unit: DEFAULT_UNIT,
            model,
            exchange: Exchange::ReadWrite,
            period: Duration::from_millis(10),
            response_timeout: Duration::from_millis(50),
            activation_timeout: Duration::from_secs(10),
            speed: 255,
            force: 128,
            open_count: 0,
            closed_count: 255,
            max_failures: 5,
            retries: 2,
        }
    }
}

/// What the gripper has shown; kept across `close`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GripperCounters {
    /// Steps done.
    pub steps: u64,
    /// Commands written.
    pub writes: u64,
    /// Statuses read.
    pub reads: u64,
    /// Exception answers (the gripper refused a request).
    pub exceptions: u64,
    /// Activations done by `start`.
    pub activations: u32,
    /// Statuses that showed a priority fault (0x05, 0x07).
    pub priority_faults: u64,
    /// Statuses that showed a minor fault (0x08, 0x09).
    pub minor_faults: u64,
    /// Steps that ended on a major fault.
    pub major_faults: u64,
    /// Objects detected (a rising edge of a contact status).
    pub objects_detected: u64,
    /// Requests of `open`, `start` or `stop` sent again ([`GripperConfig::retries`]).
    pub retries: u64,
}

/// A Modbus master behind a box: RTU on any serial line, or TCP.
pub type BoxedMaster = Box<dyn ModbusMaster + Send>;

/// Makes the master when the device opens.
type Connect = Box<dyn FnMut() -> Result<BoxedMaster, Error> + Send>;

/// A Robotiq 2F-85 or 2F-140 over Modbus (RL's `RobotiqModelC`).
pub struct RobotiqGripper {
    config: GripperConfig,
    lifecycle: Lifecycle,
    open: Connect,
    master: Option<BoxedMaster>,
    command: Command,
    written: Option<Command>,
    status: Status,
    counters: GripperCounters,
    pdu: [u8; MAX_PDU],
}

impl core::fmt::Debug for RobotiqGripper {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("RobotiqGripper")
            .field("config", &self.config)
            .field("lifecycle", &self.lifecycle)
            .field("line", &self.master.as_ref().map(|m| m.describe()))
            .field("command", &self.command)
            .field("status", &self.status)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl RobotiqGripper {
    /// A gripper on the serial port at `path` (Modbus RTU, 8N1 at `baud`): a Pi's UART, a USB
    /// adapter. The port is opened by `open`.
    pub fn rtu(
        config: GripperConfig,
        path: impl Into<std::path::PathBuf>,
        baud: u32,
    ) -> Result<Self, Error> {
        let path = path.into();
        Self::new(config, move || {
            let port =
                super::SerialPort::open(&path, baud).map_err(|e| Error::io(Operation::Open, &e))?;
            Ok(Box::new(super::RtuMaster::new(
                port,
                baud,
                path.display().to_string(),
            )) as BoxedMaster)
        })
    }

    /// A gripper on an open serial line (any embedded-io port: a UART of a HAL, a
    /// pseudo-terminal); `name` names it in messages. The line is used by the first `open`
    /// only: a second `open` after `close` fails.
    pub fn rtu_on<S: super::SerialLine + Send + 'static>(
        config: GripperConfig,
        line: S,
        baud: u32,
        name: &str,
    ) -> Result<Self, Error> {
        let mut line = Some(line);
        let name = name.to_owned();
        Self::new(config, move || {
            let l = line.take().ok_or(Error::State {
                operation: Operation::Open,
                state: State::Closed,
            })?;
            Ok(Box::new(super::RtuMaster::new(l, baud, name.clone())) as BoxedMaster)
        })
    }

    /// A gripper behind a Modbus TCP server (a gateway, a gripper controller) at `server`.
    pub fn tcp(config: GripperConfig, server: std::net::SocketAddr) -> Result<Self, Error> {
        let timeout = config.response_timeout.max(Duration::from_secs(1));
        Self::new(config, move || {
            let m = super::TcpMaster::connect(server, timeout)
                .map_err(|e| Error::io(Operation::Open, &e))?;
            Ok(Box::new(m) as BoxedMaster)
        })
    }

    /// A closed device; `open` makes its master with `connect`.
    pub fn new(
        config: GripperConfig,
        connect: impl FnMut() -> Result<BoxedMaster, Error> + Send + 'static,
    ) -> Result<Self, Error> {
        if config.period.is_zero()
            || config.response_timeout.is_zero()
            || config.activation_timeout.is_zero()
        {
            return Err(Error::InvalidArgument {
                what: "gripper durations (period, timeouts) in µs",
                expected: 1,
                got: 0,
            });
        }
        if config.closed_count <= config.open_count {
            return Err(Error::InvalidArgument {
                what: "gripper closed_count (must exceed open_count)",
                expected: usize::from(config.open_count) + 1,
                got: usize::from(config.closed_count),
            });
        }
        Ok(Self {
            lifecycle: Lifecycle::with_failure_limit(config.max_failures),
            open: Box::new(connect),
            master: None,
            command: Command {
                speed: config.speed,
                force: config.force,
                ..Command::default()
            },
            written: None,
            status: Status::default(),
            counters: GripperCounters::default(),
            pdu: [0; MAX_PDU],
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &GripperConfig {
        &self.config
    }

    /// The last status read.
    pub fn status(&self) -> Status {
        self.status
    }

    /// The command buffered for the next step.
    pub fn command(&self) -> Command {
        self.command
    }

    /// The counts so far.
    pub fn counters(&self) -> GripperCounters {
        self.counters
    }

    /// The master's counts (requests, time-outs, CRC errors…).
    pub fn master_counters(&self) -> Option<super::MasterCounters> {
        self.master.as_ref().map(|m| m.counters())
    }

    /// The fingers' opening, m (linear between the configured counts).
    pub fn opening_m(&self) -> f64 {
        self.count_to_opening(self.status.position)
    }

    /// Whether the fingers stopped on an object.
    pub fn object_detected(&self) -> bool {
        self.status.going && self.status.object.holds_object()
    }

    /// Whether the last motion ended (at the position, or on an object).
    pub fn motion_done(&self) -> bool {
        self.status.going
            && self.status.position_request == self.command.position
            && !matches!(
                self.status.object,
                crate::proto::robotiq::ObjectStatus::Moving
            )
    }

    fn count_to_opening(&self, count: u8) -> f64 {
        let (o, c) = (
            f64::from(self.config.open_count),
            f64::from(self.config.closed_count),
        );
        let x = ((f64::from(count) - o) / (c - o)).clamp(0.0, 1.0);
        self.config.model.stroke_m() * (1.0 - x)
    }

    fn check_set(&self) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)
    }

    /// Moves the fingers to position `count` (0 open to 255 closed) at the next step.
    pub fn set_position_count(&mut self, count: u8) -> Result<(), Error> {
        self.check_set()?;
        self.command.position = count;
        self.command.go_to = true;
        Ok(())
    }

    /// Moves the fingers to an opening of `opening_m` (0 to the stroke).
    pub fn set_opening(&mut self, opening_m: f64) -> Result<(), Error> {
        let stroke = self.config.model.stroke_m();
        if !opening_m.is_finite() || !(0.0..=stroke).contains(&opening_m) {
            return Err(Error::InvalidArgument {
                what: "gripper opening in mm (0 to the stroke)",
                expected: (stroke * 1000.0) as usize,
                got: if opening_m.is_finite() {
                    (opening_m.abs() * 1000.0) as usize
                } else {
                    usize::MAX
                },
            });
        }
        let (o, c) = (
            f64::from(self.config.open_count),
            f64::from(self.config.closed_count),
        );
        let count = o + (1.0 - opening_m / stroke) * (c - o);
        self.set_position_count(count.round().clamp(0.0, 255.0) as u8)
    }

    /// The speed of the next motions (0 slowest to 255 fastest).
    pub fn set_speed_count(&mut self, count: u8) -> Result<(), Error> {
        self.check_set()?;
        self.command.speed = count;
        Ok(())
    }

    /// The speed in m/s, within the model's range.
    pub fn set_speed(&mut self, speed: f64) -> Result<(), Error> {
        let (lo, hi) = self.config.model.speed_range();
        let count = scale(speed, lo, hi, "gripper speed in mm/s")?;
        self.set_speed_count(count)
    }

    /// The grip force of the next motions (0 lowest to 255 highest).
    pub fn set_force_count(&mut self, count: u8) -> Result<(), Error> {
        self.check_set()?;
        self.command.force = count;
        Ok(())
    }

    /// The grip force in N, within the model's range.
    pub fn set_force(&mut self, force: f64) -> Result<(), Error> {
        let (lo, hi) = self.config.model.force_range();
        let count = scale(force, lo, hi, "gripper force in N")?;
        self.set_force_count(count)
    }

    fn link_error(&self, operation: Operation, e: MasterError) -> Error {
        match e {
            MasterError::Timeout => Error::Timeout {
                operation,
                waited: self.config.response_timeout,
            },
            MasterError::Disconnected => Error::Disconnected { operation },
            MasterError::Io(kind) => Error::Io {
                operation,
                kind,
                os_code: None,
            },
            e => Error::protocol(operation, "Modbus answer", &e),
        }
    }

    /// One transaction; an exception answer is a device error. Outside a step, a timeout or a
    /// corrupt answer is retried up to [`GripperConfig::retries`] times.
    fn transact(&mut self, operation: Operation, request: &Request<'_>) -> Result<(), Error> {
        let retries = if operation == Operation::Step {
            0
        } else {
            self.config.retries
        };
        let mut attempt = 0;
        loop {
            match self.transact_once(operation, request) {
                Err(e)
                    if attempt < retries
                        && matches!(e.kind(), ErrorKind::Timeout | ErrorKind::Protocol) =>
                {
                    attempt += 1;
                    self.counters.retries += 1;
                }
                result => return result,
            }
        }
    }

    fn transact_once(&mut self, operation: Operation, request: &Request<'_>) -> Result<(), Error> {
        let deadline = Instant::now() + self.config.response_timeout;
        let unit = self.config.unit;
        let master = self.master.as_mut().ok_or(Error::State {
            operation,
            state: State::Closed,
        })?;
        let n = match master.transact(unit, request, &mut self.pdu, deadline) {
            Ok(n) => n,
            Err(e) => return Err(self.link_error(operation, e)),
        };
        let response = check_answer(request, &self.pdu[..n])
            .map_err(|e| Error::protocol(operation, "Modbus answer", &e))?;
        match response {
            Response::Exception { code, .. } => {
                self.counters.exceptions += 1;
                Err(exception(operation, request, code))
            }
            Response::ReadInputRegisters(r)
            | Response::ReadHoldingRegisters(r)
            | Response::ReadWriteMultipleRegisters(r) => {
                let mut regs = [0u16; 3];
                r.copy_to(&mut regs);
                self.take_status(Status::from_registers(regs));
                Ok(())
            }
            Response::WriteMultipleRegisters { .. } | Response::WriteSingleRegister { .. } => {
                Ok(())
            }
        }
    }

    fn take_status(&mut self, s: Status) {
        let before = self.status;
        self.status = s;
        self.counters.reads += 1;
        match s.fault.severity() {
            Severity::Priority => self.counters.priority_faults += 1,
            Severity::Minor => self.counters.minor_faults += 1,
            _ => {}
        }
        if s.going && s.object.holds_object() && !(before.going && before.object.holds_object()) {
            self.counters.objects_detected += 1;
        }
    }

    fn write(&mut self, operation: Operation, command: Command) -> Result<(), Error> {
        let words = command.to_registers();
        self.transact(
            operation,
            &Request::WriteMultipleRegisters {
                address: COMMAND_REGISTER,
                values: Registers::Words(&words),
            },
        )?;
        self.counters.writes += 1;
        self.written = Some(command);
        Ok(())
    }

    fn read(&mut self, operation: Operation) -> Result<(), Error> {
        self.transact(
            operation,
            &Request::ReadInputRegisters {
                address: STATUS_REGISTER,
                count: USED_REGISTERS,
            },
        )
    }

    fn read_write(&mut self, operation: Operation, command: Command) -> Result<(), Error> {
        let words = command.to_registers();
        self.transact(
            operation,
            &Request::ReadWriteMultipleRegisters {
                read_address: STATUS_REGISTER,
                read_count: USED_REGISTERS,
                write_address: COMMAND_REGISTER,
                values: Registers::Words(&words),
            },
        )?;
        self.counters.writes += 1;
        self.written = Some(command);
        Ok(())
    }

    /// The status's fault as an error, if it stops the gripper.
    fn check_status(&mut self, operation: Operation) -> Result<(), Error> {
        let s = self.status;
        if s.fault.severity() == Severity::Major {
            self.counters.major_faults += 1;
            return Err(Error::device(operation, SOURCE, &s.fault));
        }
        if !s.is_ready() {
            return Err(Error::device(
                operation,
                SOURCE,
                &format_args!(
                    "not activated (gACT {}, gSTA {:?}): reset or power loss; stop and start again",
                    u8::from(s.activated),
                    s.activation
                ),
            ));
        }
        Ok(())
    }
}

fn scale(value: f64, lo: f64, hi: f64, what: &'static str) -> Result<u8, Error> {
    if !value.is_finite() || value < lo * (1.0 - 1e-9) || value > hi * (1.0 + 1e-9) {
        return Err(Error::InvalidArgument {
            what,
            expected: (hi * 1000.0) as usize,
            got: if value.is_finite() {
                (value.abs() * 1000.0) as usize
            } else {
                usize::MAX
            },
        });
    }
    Ok((255.0 * (value - lo) / (hi - lo)).round().clamp(0.0, 255.0) as u8)
}

fn exception(operation: Operation, request: &Request<'_>, code: ExceptionCode) -> Error {
    Error::device(
        operation,
        SOURCE,
        &format_args!(
            "refused function {:#04x}: {code}",
            request.function().code()
        ),
    )
}

impl Driver for RobotiqGripper {
    const STOP_DESCRIPTION: &'static str = "fingers halted (rGTO = 0), gripper activated";

    fn open_sequence(&mut self) -> Result<(), Error> {
        let master = (self.open)()?;
        self.master = Some(master);
        self.written = None;
        if let Err(e) = self.read(Operation::Open) {
            self.master = None;
            return Err(e);
        }
        Ok(())
    }

    fn start_sequence(&mut self) -> Result<(), Error> {
        let op = Operation::Start;
        self.read(op)?;
        if !self.status.is_ready() || self.status.fault.severity() == Severity::Major {
            // A rising edge of rACT: reset, then activate.
            let reset = Command {
                speed: self.command.speed,
                force: self.command.force,
                ..Command::default()
            };
            self.write(op, reset)?;
            let activate = Command {
                activate: true,
                ..reset
            };
            self.write(op, activate)?;
            self.counters.activations += 1;
            let deadline = Instant::now() + self.config.activation_timeout;
            loop {
                std::thread::sleep(self.config.period);
                self.read(op)?;
                if self.status.fault.severity() == Severity::Major {
                    self.counters.major_faults += 1;
                    return Err(Error::device(op, SOURCE, &self.status.fault));
                }
                if self.status.is_ready() {
                    break;
                }
                if Instant::now() >= deadline {
                    return Err(Error::Timeout {
                        operation: op,
                        waited: self.config.activation_timeout,
                    });
                }
            }
        }
        // Hold where the fingers are.
        self.command = Command {
            activate: true,
            go_to: false,
            automatic_release: false,
            release_opening: false,
            position: self.status.position,
            speed: self.command.speed,
            force: self.command.force,
        };
        self.write(op, self.command)?;
        Ok(())
    }

    fn stop_sequence(&mut self) -> Result<(), Error> {
        let halt = Command {
            go_to: false,
            ..self.command
        };
        self.command = halt;
        self.write(Operation::Stop, halt)
    }

    fn close_sequence(&mut self) -> Result<(), Error> {
        self.master = None;
        Ok(())
    }

    fn period(&self) -> Duration {
        self.config.period
    }

    fn exchange(&mut self) -> Result<(), Error> {
        let op = Operation::Step;
        self.counters.steps += 1;
        let command = self.command;
        match self.config.exchange {
            Exchange::ReadWrite => self.read_write(op, command)?,
            Exchange::Separate => {
                if self.written != Some(command) {
                    self.write(op, command)?;
                }
                self.read(op)?;
            }
        }
        self.check_status(op)
    }
}

impl_cyclic_device!(RobotiqGripper, lifecycle);

impl Gripper for RobotiqGripper {
    /// Stops the fingers where they are (the position request becomes the current position).
    fn halt(&mut self) -> Result<(), Error> {
        self.check_set()?;
        self.command.position = self.status.position;
        self.command.go_to = true;
        Ok(())
    }

    /// Opens fully.
    fn release(&mut self) -> Result<(), Error> {
        self.set_position_count(0)
    }

    /// Closes fully (on an object, the fingers stop there with the set force).
    fn shut(&mut self) -> Result<(), Error> {
        self.set_position_count(255)
    }
}

impl LinkStatisticsSensor for RobotiqGripper {
    fn link_statistics(&self) -> LinkStatistics {
        let m = self.master_counters().unwrap_or_default();
        LinkStatistics {
            sent: m.requests,
            received: m.responses,
            lost: m.timeouts,
            late: m.stale_bytes,
            rejected: m.exceptions,
            corrupt: m.crc_errors + m.garbage,
            consecutive_failures: self.lifecycle.consecutive_failures(),
            delivery: Delivery::default(),
        }
    }
}

impl RobotiqGripper {
    /// Whether the gripper is activated (after `start`).
    pub fn is_activated(&self) -> bool {
        self.status.is_ready() && self.status.activation == ActivationStatus::Activated
    }

    /// The gripper's fault in the last status.
    pub fn gripper_fault(&self) -> Fault {
        self.status.fault
    }
}
