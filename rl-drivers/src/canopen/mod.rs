//! A CANopen master for CiA 402 drives: N axes (node ids) on one CAN bus driven as one cyclic
//! device, [`Cia402`], in cyclic synchronous position, velocity or torque mode.
//!
//! - [`config`]: the bus, the axes and their units, the mode, the cycle and the bounds on every
//!   wait; the PDO layout that follows from them.
//! - [`bus_load`]: the bits one cycle puts on the bus, and whether a period can carry them.
//! - [`error`]: the typed CANopen and CiA 402 failures, each naming its node.
//! - [`Cia402`] (in `drive.rs`): open (NMT pre-operational, device type, supported modes and
//!   positions by SDO), start (PDOs configured by SDO, NMT start, the power state machine to
//!   operation enabled), step (SYNC, RPDOs, TPDOs back within the cycle; EMCY, heartbeats,
//!   lost and late TPDOs counted), stop (quick stop, power stage off, NMT pre-operational).
//!
//! The protocol itself — frames, SDO transfers, PDO packing, the power state machine — is the
//! `no_std` code in [`proto::canopen`](crate::proto::canopen) and [`cia402`](crate::cia402);
//! this module adds the transport and the clock.

pub mod bus_load;
pub mod config;
mod drive;
pub mod error;

pub use bus_load::BusLoad;
pub use config::{AxisConfig, Cia402Config, DeviceAddress, MAX_AXES, parse_node_list};
pub use drive::{Cia402, Cia402Counters, NodeReport};
pub use error::CanopenError;
