//! EtherCAT wire codecs (ETG.1000; facts in `shared/reference/ethercat.md`), one protocol
//! concept per file: [`frame`] (Ethernet II + EtherCAT header), [`datagram`]s and their
//! [`command`]s, ESC [`register`]s, the [`al`] state machine registers, [`sync_manager`]s and
//! [`fmmu`]s, the [`mailbox`] header, CANopen over EtherCAT ([`coe`], reusing the CANopen SDO
//! codec) and the [`sii`] EEPROM image.
//!
//! `no_std`, allocation-free; decoders return typed errors and never panic (fuzzed in
//! `rl-drivers/fuzz`, checked against Wireshark's dissector on every frame of the real-hardware
//! captures in `tests/ecat_captures.rs`).

pub mod al;
pub mod coe;
pub mod command;
pub mod datagram;
pub mod fmmu;
pub mod frame;
pub mod mailbox;
pub mod register;
pub mod sii;
pub mod sync_manager;

pub use al::{AlControl, AlState, AlStatus, AlStatusCode};
pub use command::Command;
pub use datagram::{Datagram, DatagramHeader};
pub use frame::{Frame, FrameBuilder, MacAddr};
