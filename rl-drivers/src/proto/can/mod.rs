//! CAN frames and the byte forms they take on the way: the Linux SocketCAN structures, the
//! candump log line of can-utils, and the cannelloni CAN-over-UDP/TCP encoding.
//!
//! - [`frame`]: [`Frame`], one classic (CAN 2.0A/B) or CAN FD frame with the Linux `canid_t`
//!   flags, implementing [`embedded_can::Frame`]; the 16-byte `struct can_frame`.
//! - [`fd`]: CAN FD lengths and flags and the 72-byte `struct canfd_frame`.
//! - [`candump`]: the `(sec.usec) iface ID#DATA` log line, read and written.
//! - [`cannelloni`]: the cannelloni frame encoding, its version 2 UDP datagram and its version 1
//!   TCP stream.
//! - [`timing`]: bits on the wire per frame, for the bus-load arithmetic.
//!
//! All `no_std`, allocation-free; decoding never panics (fuzzed in `rl-drivers/fuzz`).

pub mod candump;
pub mod cannelloni;
pub mod fd;
pub mod frame;
pub mod timing;

pub use frame::{DecodeError, Frame, IdOrder};
