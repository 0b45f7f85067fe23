//! The URScript program the driver sends at `start`: it follows six double input registers
//! with `servoj` while an integer input register holds 1 (RL's `UniversalRobotsRtde` program,
//! with a handshake and a stricter watchdog). The registers are RTDE's upper range by default
//! (24 onwards), the range the guide leaves to external clients.
//!
//! ```text
//! def rl_follow():
//!   write_output_integer_register(B, 1)                       # the handshake: running
//!   rtde_set_watchdog("input_int_register_B", W, "stop")       # no inputs for 1/W s: stop
//!   q = get_actual_joint_positions()
//!   while read_input_integer_register(B) == 1:
//!     q = [read_input_float_register(B), …, read_input_float_register(B + 5)]
//!     servoj(q, 0, 0, T, L, G)                                 # T: one step, L, G: smoothing
//!   end
//!   stopj(4.0)
//!   write_output_integer_register(B, 0)                       # the handshake: ended
//! end
//! ```

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
}

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
        let _ = writeln!(s, "  while read_input_integer_register({b}) == 1:");
        let regs: Vec<String> = (0..6)
            .map(|k| format!("read_input_float_register({})", u32::from(b) + k))
            .collect();
        let _ = writeln!(s, "    q = [{}]", regs.join(", "));
        let _ = writeln!(
            s,
            "    servoj(q, 0, 0, {}, {}, {})",
            self.servo_time, self.lookahead_time, self.gain
        );
        let _ = writeln!(s, "  end");
        let _ = writeln!(s, "  stopj(4.0)");
        let _ = writeln!(s, "  write_output_integer_register({b}, 0)");
        let _ = writeln!(s, "end");
        s
    }
}
