//! ATI force/torque sensors behind a Net F/T (or the Axia, NETrs and NETba boxes that speak
//! the same RDT protocol): the wrench streamed over UDP, up to 7000 records a second.
//!
//! - [`crate::proto::netft`]: the codec (RDT requests and records, the calibration query,
//!   units), `no_std`;
//! - `device` (this module, feature `std`): the cyclic device, [`AtiNetFt`];
//! - `mount`: where the sensor sits on the arm, from a model, to express its wrench in the
//!   flange's, the tool's or the base's frame.
//!
//! The session, as the sensor runs it:
//! 1. The calibration (counts per force and per torque unit, the units) is read at `open` over
//!    TCP 49151 (`READCALINFO`), or given in the configuration.
//! 2. `start` sends RDT command 2 (or 3, buffered) with a sample count of 0: the sensor streams
//!    records to the sender's address until told to stop.
//! 3. Each step takes every datagram that came, keeps the newest record, and counts what the
//!    sequence numbers show: gaps (records lost on the network), records older than the
//!    newest (reordered, dropped), repeats. A status word with bit 31 set is the sensor's
//!    error, and fails the step with [`ErrorKind::Device`](crate::ErrorKind::Device).
//! 4. `stop` sends command 0.

mod device;
mod mount;

pub use device::{AtiNetFt, NetFtConfig, NetFtCounters, StreamMode};
pub use mount::{MountError, SensorMount};
