//! Wire codecs: pure, `no_std`, allocation-free, `#![forbid(unsafe_code)]`. Decoding returns a
//! typed error saying what and where, and never panics on any input (fuzzed under
//! `rl-drivers/fuzz` and property-tested in `tests/proto_properties.rs`).
#![forbid(unsafe_code)]

pub mod can;
pub mod canopen;
pub mod coach;
pub mod ecat;
pub mod h7;
pub mod modbus;
pub mod netft;
pub mod r3;
pub mod robotiq;
pub mod rtde;
pub mod ur_realtime;
