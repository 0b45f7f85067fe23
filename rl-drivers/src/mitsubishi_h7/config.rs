//! The driver's settings (addresses, timeouts, the counter check, the gripper's I/O word) and its
//! counters.

use core::time::Duration;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};

use crate::capability::Delivery;
use crate::proto::h7::{CYCLE_US, MAX_AXES, Mode, MxtType};

/// The controller's cycle as the device's update period.
pub const UPDATE_PERIOD: Duration = Duration::from_micros(CYCLE_US);

/// The I/O word the gripper commands are written to (RL's defaults).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GripperIo {
    /// First output bit (RL: 900).
    pub bit_top: u16,
    /// Mask (RL: 0x00FF).
    pub mask: u16,
    /// Value for halt (RL: 0xAA).
    pub halt: u16,
    /// Value for release (RL: 0xA6).
    pub release: u16,
    /// Value for shut (RL: 0xA9).
    pub shut: u16,
}

impl Default for GripperIo {
    fn default() -> Self {
        Self {
            bit_top: 900,
            mask: 0x00FF,
            halt: 0x00AA,
            release: 0x00A6,
            shut: 0x00A9,
        }
    }
}

/// How a reply's packet counter (`cCount`) is checked against the packets sent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CounterCheck {
    /// The reply echoes the counter of the packet it answers (the fake does; RL's reference
    /// and Mitsubishi's header call it the transmission counter): the reply to the packet just
    /// sent must carry its counter.
    #[default]
    Echo,
    /// Only require that the counter differs from the last reply used (catches a frozen or
    /// replayed reply from a controller that counts its own transmissions).
    Advancing,
    /// No check.
    Off,
}

/// How to reach and drive the controller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MitsubishiH7Config {
    /// Axes the caller expects; `None` takes the count the controller reports (`JPOSF`) at
    /// `open`. When given, `open` fails if the controller reports another count, and it is the
    /// fallback when the controller does not answer `JPOSF`.
    pub axes: Option<usize>,
    /// Axes that are linear (mm in `JPOSF` and in the packets) rather than rotary (degrees in
    /// `JPOSF`, rad in the packets).
    pub linear_axes: [bool; MAX_AXES],
    /// The controller's real-time UDP address (port 10000 on a real controller).
    pub server: SocketAddr,
    /// The controller's R3 TCP address (port 10001).
    pub r3: SocketAddr,
    /// Local UDP address to bind. Default: 127.0.0.1:0 when the controller is on loopback,
    /// otherwise the wildcard, which `open` replaces by the local address of the route to the
    /// controller (the socket then hears only that interface).
    pub local: SocketAddr,
    /// Address written into the program's `ENET:` line (where the controller sends replies).
    /// Default: the bound local address.
    pub client_ip: Option<IpAddr>,
    /// What the client commands (the MXT program's mode).
    pub mode: Mode,
    /// The controller's low-pass filter time constant in ms (`MXT 1,<mode>,<filter>`).
    pub filter: u32,
    /// Reply types requested in `dat`, `dat1`, `dat2`, `dat3`. Default: encoder feedback of the
    /// joints, the controller's joint command (to see a clamped command: [`JointLimitSensor`](crate::JointLimitSensor)),
    /// encoder feedback of the pose, and current feedback. [`MitsubishiH7Config::RL_FEEDBACK`]
    /// is RL's.
    pub feedback: [MxtType; 4],
    /// How long a step waits for its reply: by default one period, so a step returns within
    /// the cycle; a reply that has not come by then is counted lost (RL waits
    /// (filter + 6) × 7.11 ms).
    pub reply_timeout: Duration,
    /// How reply counters are checked.
    pub counter_check: CounterCheck,
    /// Gripper I/O.
    pub gripper: GripperIo,
    /// Failed steps in a row (timeouts or bad replies) that fault the device.
    pub max_consecutive_failures: u32,
    /// Bound on each R3 exchange and on connecting.
    pub r3_timeout: Duration,
    /// Silence after the last byte that ends an R3 reply sent without a carriage return.
    pub r3_quiet: Duration,
    /// Bound on waiting for the servo to switch.
    pub servo_timeout: Duration,
    /// Robot number in R3 commands.
    pub robot: u8,
}

impl MitsubishiH7Config {
    /// RL's reply types: joint, pose, pulse (commanded values) and current feedback.
    pub const RL_FEEDBACK: [MxtType; 4] = [
        MxtType::Joint,
        MxtType::Pose,
        MxtType::Pulse,
        MxtType::CurrentFeedback,
    ];

    /// A controller at `server` (UDP) and `r3` (TCP) whose axis count is read at `open`: joint
    /// mode, filter 0, a reply wait of one period, RL's gripper I/O, 10 failures to fault, 2 s
    /// R3 and 5 s servo bounds.
    pub fn at(server: SocketAddr, r3: SocketAddr) -> Self {
        Self {
            axes: None,
            linear_axes: [false; MAX_AXES],
            server,
            r3,
            local: if server.ip().is_loopback() {
                SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 0)
            } else if server.is_ipv6() {
                SocketAddr::new(IpAddr::V6(std::net::Ipv6Addr::UNSPECIFIED), 0)
            } else {
                SocketAddr::new(IpAddr::V4(Ipv4Addr::UNSPECIFIED), 0)
            },
            client_ip: None,
            mode: Mode::Joint,
            filter: 0,
            feedback: [
                MxtType::JointFeedback,
                MxtType::Joint,
                MxtType::PoseFeedback,
                MxtType::CurrentFeedback,
            ],
            reply_timeout: UPDATE_PERIOD,
            counter_check: CounterCheck::Echo,
            gripper: GripperIo::default(),
            max_consecutive_failures: 10,
            r3_timeout: Duration::from_secs(2),
            r3_quiet: Duration::from_millis(20),
            servo_timeout: Duration::from_secs(5),
            robot: 1,
        }
    }

    /// [`at`](Self::at), expecting exactly `axes` axes: `open` fails if the controller reports
    /// another number.
    pub fn new(axes: usize, server: SocketAddr, r3: SocketAddr) -> Self {
        Self {
            axes: Some(axes),
            ..Self::at(server, r3)
        }
    }

    /// RL's bound on waiting for one reply, (filter + 6) × 7.11 ms, for callers who want it
    /// as [`reply_timeout`](Self::reply_timeout).
    pub fn rl_reply_timeout(&self) -> Duration {
        UPDATE_PERIOD * (self.filter.saturating_add(6))
    }
}

/// What happened to the real-time exchange so far (over the life of the driver object: the
/// counts survive `close`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct H7Counters {
    /// Packets sent (including end packets).
    pub sent: u64,
    /// Valid replies used.
    pub replies: u64,
    /// Steps without their reply by the deadline (lost).
    pub timeouts: u64,
    /// Replies that arrived after their step had given up, dropped.
    pub late: u64,
    /// Datagrams from any other address than the controller's, dropped.
    pub foreign: u64,
    /// Replies of the wrong length.
    pub wrong_length: u64,
    /// Replies that did not decode or did not hold the requested types.
    pub corrupt: u64,
    /// Replies carrying the counter of a packet already answered or never sent (a frozen or
    /// replayed reply).
    pub replayed: u64,
    /// Bytes found on the R3 connection before a request (a reply to an earlier request that
    /// had timed out), dropped.
    pub r3_stale_bytes: u64,
    /// Current run of failed steps.
    pub consecutive_failures: u32,
    /// R3 connections opened again by `stop` after the controller dropped one.
    pub r3_reconnects: u64,
    /// Steps that sent nothing because the previous request was still unanswered: the
    /// controller was behind (one cycle, or several after a stall), and waiting for that reply
    /// lets its queue drain.
    pub held: u64,
    /// When replies reached this machine's kernel, against when the steps read them and
    /// against their steps' deadlines (kernel receive timestamps; empty where the kernel gives
    /// none).
    pub delivery: Delivery,
}
