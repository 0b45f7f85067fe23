//! An EtherCAT master over raw Ethernet (`shared/reference/ethercat.md`), and CiA 402 servo
//! drives on it as one joint device ([`EthercatDrives`]). One concept per file: the [`link`]
//! (frames on an `AF_PACKET` socket, replies matched by index, losses counted), the [`master`]'s
//! acyclic services (scan, SII, registers, AL state machine), the [`mailbox`] with the CoE SDO
//! client, [`process`] data (image, sync managers, FMMUs, the cyclic exchange and its
//! recovery), distributed clocks ([`dc`]) and the [`drives`].
//!
//! No thread, no executor: every exchange happens in the caller's thread; the cyclic one in
//! [`CyclicDevice::step`](crate::CyclicDevice::step) allocates nothing and waits at most the
//! configured frame timeout.

pub mod dc;
pub mod drives;
pub mod error;
pub mod link;
pub mod mailbox;
pub mod master;
pub mod process;

pub use drives::{DriveFault, EthercatConfig, EthercatDrives, UnitsRefused};
pub use error::{DeviceRef, EcError};
pub use master::{Master, MasterConfig, SubDevice};
