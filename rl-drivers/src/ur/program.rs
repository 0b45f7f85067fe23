//! The URScript program the driver sends at `start`: it follows six double input registers
//! with `servoj` while an integer input register holds 1 ([`MODE_POSITION`]: joint positions)
//! and with `speedj` while it holds 2 ([`MODE_VELOCITY`]: joint speeds), and ends on anything
//! else (RL's `UniversalRobotsRtde` program, which follows positions only, with a handshake and
//! a stricter watchdog). The registers are RTDE's upper range by default (24 onwards), the
//! range the guide leaves to external clients.
//!
//! ```text
//! def rl_follow():
//!   write_output_integer_register(B, 1)                       # the handshake: running
//!   rtde_set_watchdog("input_int_register_B", W, "stop")       # no inputs for 1/W s: stop
//!   q = get_actual_joint_positions()
//!   mode = read_input_integer_register(B)
//!   while mode == 1 or mode == 2:
//!     q = [read_input_float_register(B), …, read_input_float_register(B + 5)]
//!     if mode == 1:
//!       servoj(q, 0, 0, T, L, G)                               # T: one step, L, G: smoothing
//!     else:
//!       speedj(q, A, T)                                        # A: the leading joint's rad/s²
//!     end
//!     mode = read_input_integer_register(B)
//!   end
//!   stopj(4.0)
//!   write_output_integer_register(B, 0)                       # the handshake: ended
//! end
//! ```
//!
//! `speedj` returns after `T` (one step), so each cycle's speeds replace the last; the
//! controller ramps to each at `A`.

use std::fmt::Write as _;

/// The program's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FollowerProgram {
    /// The first register: `input_int_register_B` (command), `input_double_register_B…B+5`
    /// (joints), `output_int_register_B` (handshake).
    pub register_base: u8,
    /// `servoj`'s time: one control period, s.
    pub servo_time: f64,
    /// `servoj`'s lookahead time, s (0.03 to 0.2).
    pub lookahead_time: f64,
    /// `servoj`'s gain (100 to 2000).
    pub gain: f64,
    /// The watchdog's minimum input frequency, Hz.
    pub watchdog_hz: f64,
    /// `speedj`'s acceleration, rad/s² of the leading joint.
    pub speed_acceleration: f64,
}

/// The command register's value for following joint positions (`servoj`).
pub const MODE_POSITION: i32 = 1;
/// The command register's value for following joint speeds (`speedj`).
pub const MODE_VELOCITY: i32 = 2;

impl FollowerProgram {
    /// The program's name.
    pub const NAME: &'static str = "rl_follow";

    /// The script.
    pub fn script(&self) -> String {
        let b = self.register_base;
        let mut s = String::new();
        let _ = writeln!(s, "def {}():", Self::NAME);
        let _ = writeln!(s, "  write_output_integer_register({b}, 1)");
        let _ = writeln!(
            s,
            "  rtde_set_watchdog(\"input_int_register_{b}\", {}, \"stop\")",
            self.watchdog_hz
        );
        let _ = writeln!(s, "  q = get_actual_joint_positions()");
        let _ = writeln!(s, "  mode = read_input_integer_register({b})");
        let _ = writeln!(
            s,
            "  while mode == {MODE_POSITION} or mode == {MODE_VELOCITY}:"
        );
        let regs: Vec<String> = (0..6)
            .map(|k| format!("read_input_float_register({})", u32::from(b) + k))
            .collect();
        let _ = writeln!(s, "    q = [{}]", regs.join(", "));
        let _ = writeln!(s, "    if mode == {MODE_POSITION}:");
        let _ = writeln!(
            s,
            "      servoj(q, 0, 0, {}, {}, {})",
            self.servo_time, self.lookahead_time, self.gain
        );
        let _ = writeln!(s, "    else:");
        let _ = writeln!(
            s,
            "      speedj(q, {}, {})",
            self.speed_acceleration, self.servo_time
        );
        let _ = writeln!(s, "    end");
        let _ = writeln!(s, "    mode = read_input_integer_register({b})");
        let _ = writeln!(s, "  end");
        let _ = writeln!(s, "  stopj(4.0)");
        let _ = writeln!(s, "  write_output_integer_register({b}, 0)");
        let _ = writeln!(s, "end");
        s
    }
}
