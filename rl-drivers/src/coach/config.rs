//! How to reach the Coach server, the buffers' sizes, and the link's counters.

use core::time::Duration;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};

/// The port RL's visualisers listen on.
pub const DEFAULT_PORT: u16 = 11235;
/// Bytes of commands one step can carry: position, velocity and torque lines of
/// [`MAX_VALUES`](crate::proto::coach::MAX_VALUES) joints at 14 bytes a value (`-1.23457e+308 `) and the request.
pub const OUTPUT_CAPACITY: usize = 16384;
/// Bytes of received lines buffered for reassembly: two replies of [`MAX_VALUES`](crate::proto::coach::MAX_VALUES) joints.
pub const INPUT_CAPACITY: usize = 8192;

/// How to reach the Coach server.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoachConfig {
    /// Server address (RL: localhost:11235).
    pub server: SocketAddr,
    /// Model index `i` in the lines.
    pub model: u32,
    /// Joints of the model (at most [`MAX_VALUES`](crate::proto::coach::MAX_VALUES)).
    pub dof: usize,
    /// The period the caller steps at.
    pub update_period: Duration,
    /// Bound on a step: draining, sending, and waiting for the `6 <i>` reply. Default: the
    /// update period.
    pub reply_timeout: Duration,
    /// Failed steps in a row that fault the device.
    pub max_consecutive_failures: u32,
    /// Ask for joint positions each step (`6 <i>`); off for rlSimulator, which does not answer.
    pub request_joints: bool,
    /// Bound on connecting, and on the first joint reply at open (when `request_joints`).
    pub connect_timeout: Duration,
}

impl CoachConfig {
    /// Model 0 at 127.0.0.1:11235, 10 ms period, a reply bound of one period, 10 failed steps
    /// in a row to fault, joints requested.
    pub fn new(dof: usize) -> Self {
        Self {
            server: SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), DEFAULT_PORT),
            model: 0,
            dof,
            update_period: Duration::from_millis(10),
            reply_timeout: Duration::from_millis(10),
            max_consecutive_failures: crate::device::DEFAULT_MAX_CONSECUTIVE_FAILURES,
            request_joints: true,
            connect_timeout: Duration::from_secs(2),
        }
    }
}

/// What the line exchange has seen.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CoachCounters {
    /// Steps that sent their lines.
    pub sent: u64,
    /// Joint replies used.
    pub replies: u64,
    /// Steps whose reply did not arrive in time.
    pub timeouts: u64,
    /// Replies to earlier requests found at the start of a step (after a timeout), dropped.
    pub late: u64,
    /// Lines that did not parse or did not fit the buffer (dropped up to their newline).
    pub bad_lines: u64,
    /// Well-formed lines that were not a reply for our model (such as rlSimulator's empty lines).
    pub other_lines: u64,
    /// Requests sent whose reply has not come yet.
    pub outstanding: u32,
    /// Requests taken as never answered: a step's wait saw a reply it took for an earlier
    /// request and then nothing until its deadline, so the server had skipped requests (the
    /// count of outstanding requests starts again from there). A reply that turns up after all
    /// moves from here to `late` (and, from a server that is merely very slow, one stale
    /// reply may be taken for a current one). Always
    /// `sent == replies + late + outstanding + unanswered`.
    pub unanswered: u64,
}
