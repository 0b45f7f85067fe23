//! The robot-command record the client answers each state with over UDP: 371 bytes, packed,
//! little endian (libfranka-common `rbk_types.h` `RobotCommand`), `f64` throughout.
//!
//! | offset | field | type |
//! |---|---|---|
//! | 0 | `message_id` (the id of the state it answers) | u64 |
//! | 8 | `q_c`, `dq_c` | 2 × 7 f64 |
//! | 120 | `O_T_EE_c` (column-major) | 16 f64 |
//! | 248 | `O_dP_EE_c` | 6 f64 |
//! | 296 | `elbow_c` | 2 f64 |
//! | 312 | `valid_elbow`, `motion_generation_finished` | bool, bool |
//! | 314 | `tau_J_d` (without gravity: the robot adds it) | 7 f64 |
//! | 370 | `torque_command_finished` | bool |

use super::DOF;
use super::wire::{Reader, Writer};

/// Bytes of a command record.
pub const COMMAND_LEN: usize = 371;

/// The motion generator's part of a command.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[allow(non_snake_case)]
pub struct MotionGeneratorCommand {
    /// Joint positions, rad (joint position generator).
    pub q_c: [f64; DOF],
    /// Joint velocities, rad/s (joint velocity generator).
    pub dq_c: [f64; DOF],
    /// End-effector pose, column-major (Cartesian pose generator).
    pub O_T_EE_c: [f64; 16],
    /// End-effector twist (Cartesian velocity generator).
    pub O_dP_EE_c: [f64; 6],
    /// Elbow (joint 3's position, joint 4's sign).
    pub elbow_c: [f64; 2],
    /// Whether `elbow_c` is given.
    pub valid_elbow: bool,
    /// The client ends the motion.
    pub motion_generation_finished: bool,
}

/// The controller's part of a command.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[allow(non_snake_case)]
pub struct ControllerCommand {
    /// Joint torques without gravity, N·m.
    pub tau_J_d: [f64; DOF],
    /// The client ends torque control.
    pub torque_command_finished: bool,
}

/// One command.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RobotCommand {
    /// The `message_id` of the state this command answers.
    pub message_id: u64,
    /// The motion generator's part.
    pub motion: MotionGeneratorCommand,
    /// The controller's part.
    pub control: ControllerCommand,
}

/// What is wrong with a command record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CommandLengthError {
    /// Bytes received.
    pub got: usize,
}

impl core::fmt::Display for CommandLengthError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "command of {} bytes, expected {COMMAND_LEN}", self.got)
    }
}

impl RobotCommand {
    /// Writes the record.
    pub fn encode(&self, out: &mut [u8; COMMAND_LEN]) {
        let mut w = Writer::new(out);
        w.u64(self.message_id);
        let m = &self.motion;
        w.f64s(&m.q_c);
        w.f64s(&m.dq_c);
        w.f64s(&m.O_T_EE_c);
        w.f64s(&m.O_dP_EE_c);
        w.f64s(&m.elbow_c);
        w.bool(m.valid_elbow);
        w.bool(m.motion_generation_finished);
        w.f64s(&self.control.tau_J_d);
        w.bool(self.control.torque_command_finished);
        debug_assert_eq!(w.position(), COMMAND_LEN);
    }

    /// Reads a record (what the robot does).
    pub fn decode(bytes: &[u8]) -> Result<Self, CommandLengthError> {
        if bytes.len() != COMMAND_LEN {
            return Err(CommandLengthError { got: bytes.len() });
        }
        let mut r = Reader::new(bytes);
        Ok(Self {
            message_id: r.u64(),
            motion: MotionGeneratorCommand {
                q_c: r.f64s(),
                dq_c: r.f64s(),
                O_T_EE_c: r.f64s(),
                O_dP_EE_c: r.f64s(),
                elbow_c: r.f64s(),
                valid_elbow: r.bool(),
                motion_generation_finished: r.bool(),
            },
            control: ControllerCommand {
                tau_J_d: r.f64s(),
                torque_command_finished: r.bool(),
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_command_round_trips_through_its_371_bytes() {
        let c = RobotCommand {
            message_id: 42,
            motion: MotionGeneratorCommand {
                q_c: [0.1, 0.2, 0.3, -1.4, 0.5, 1.6, 0.7],
                motion_generation_finished: true,
                ..Default::default()
            },
            control: ControllerCommand {
                tau_J_d: [1.5; 7],
                torque_command_finished: true,
            },
        };
        let mut buf = [0u8; COMMAND_LEN];
        c.encode(&mut buf);
        assert_eq!(RobotCommand::decode(&buf), Ok(c));
        assert_eq!(buf[313], 1, "motion_generation_finished");
        assert_eq!(&buf[314..322], &1.5f64.to_le_bytes(), "tau_J_d[0]");
        assert_eq!(buf[370], 1, "torque_command_finished");
        assert_eq!(
            RobotCommand::decode(&buf[..370]).unwrap_err().to_string(),
            "command of 370 bytes, expected 371"
        );
    }
}
