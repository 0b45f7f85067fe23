//! The CiA 402 drive profile (IEC 61800-7-201), independent of the bus: the power state
//! machine decoded from the statusword and driven through the controlword ([`state`]), the
//! modes of operation ([`mode`]), the object table ([`object`]) and the conversion between
//! drive units and joint units ([`units`]). CANopen carries it in SDOs and PDOs; CANopen over
//! EtherCAT (CoE) carries the same objects, so both drivers use this module unchanged.
//!
//! `no_std`, allocation-free, no panics.

pub mod mode;
pub mod object;
pub mod state;
pub mod units;

pub use mode::Mode;
pub use state::{Command, Controlword, PowerState, Statusword};
pub use units::{AxisUnits, UnitsError, UnitsOverride};
