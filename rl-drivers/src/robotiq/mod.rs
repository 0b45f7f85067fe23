//! Robotiq 2F-85 and 2F-140 adaptive grippers over Modbus RTU (a serial line through
//! embedded-io: a Raspberry Pi's UART, a USB adapter) or Modbus TCP, as RL's `RobotiqModelC`.
//!
//! - [`crate::proto::modbus`]: the Modbus codec (PDUs, RTU and TCP framing), `no_std`;
//! - [`crate::proto::robotiq`]: the gripper's register map (command, status, faults), `no_std`;
//! - [`serial`]: serial lines ([`SerialLine`]: embedded-io plus a bounded wait; [`SerialPort`]:
//!   a Linux tty at a baud rate);
//! - [`master`]: Modbus masters with bounded, counted transactions ([`RtuMaster`],
//!   [`TcpMaster`]);
//! - `device`: the cyclic device, [`RobotiqGripper`].
//!
//! A session: `open` (reads the status), `start` (activates: `rACT` 0 then 1, until
//! `gSTA = 3`), then one transaction a step (command written, status read), `stop` (the
//! fingers halt), `close`. [`RobotiqGripper::rtu`] opens a serial port,
//! [`RobotiqGripper::rtu_on`] takes any embedded-io line, [`RobotiqGripper::tcp`] connects to a
//! Modbus TCP server.

mod device;
pub mod master;
pub mod serial;

pub use device::{BoxedMaster, Exchange, GripperConfig, GripperCounters, RobotiqGripper};
pub use master::{MasterCounters, MasterError, ModbusMaster, RtuMaster, TcpMaster};
pub use serial::{SerialLine, SerialPort};
