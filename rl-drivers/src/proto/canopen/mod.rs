//! CANopen (CiA 301) wire codecs, one protocol concept per file: the predefined connection
//! set of COB-IDs ([`cob`]), [`nmt`] commands and states, [`sync`], [`heartbeat`], emergency
//! messages ([`emcy`]), the [`sdo`] protocol, [`pdo`] mapping and packing, and the object
//! dictionary's data types ([`object`]); the SDO client's and server's transfer logic without
//! I/O ([`sdo_client`], [`sdo_server`]). `eds` reads CiA 306 EDS files (feature `std`).
//!
//! The SDO codec works on the 8-byte SDO payload, not on CAN frames, so CANopen over EtherCAT
//! (CoE), which carries the same bytes in a mailbox, reuses it unchanged.
//!
//! Facts: `shared/reference/canopen.md`, checked against CANopenNode, Lely and python-canopen.

pub mod cob;
#[cfg(feature = "std")]
pub mod eds;
pub mod emcy;
pub mod heartbeat;
pub mod nmt;
pub mod object;
pub mod pdo;
pub mod sdo;
pub mod sdo_client;
pub mod sdo_server;
pub mod sync;

pub use cob::{Function, NodeId};
