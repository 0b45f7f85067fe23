//! The robot-state record the robot sends over UDP once a millisecond: 1377 bytes, packed, little
//! endian (libfranka-common `rbk_types.h` `RobotState`, whose arrays are `float` since its
//! "Reduce RobotState size" change; franky-sim 1.0.4 packs the same).
//!
//! | offset | field | type |
//! |---|---|---|
//! | 0 | `message_id` (the robot's millisecond) | u64 |
//! | 8 | `O_T_EE`, `O_T_EE_d`, `F_T_EE`, `EE_T_K`, `F_T_NE`, `NE_T_EE` | 6 × 16 f32, column-major |
//! | 392 | `m_ee`, `I_ee[9]`, `F_x_Cee[3]`, `m_load`, `I_load[9]`, `F_x_Cload[3]` | f32 |
//! | 496 | `elbow[2]`, `elbow_d[2]` | f32 |
//! | 512 | `tau_J`, `tau_J_d`, `dtau_J`, `q`, `q_d`, `dq`, `dq_d`, `ddq_d` | 8 × 7 f32 |
//! | 736 | `joint_contact[7]`, `cartesian_contact[6]`, `joint_collision[7]`, `cartesian_collision[6]` | f32 |
//! | 840 | `tau_ext_hat_filtered[7]`, `O_F_ext_hat_K[6]`, `K_F_ext_hat_K[6]` | f32 |
//! | 916 | `O_dP_EE_d[6]`, `O_ddP_O[3]`, `elbow_c`, `delbow_c`, `ddelbow_c` (2 each) | f32 |
//! | 976 | `O_T_EE_c[16]`, `O_dP_EE_c[6]`, `O_ddP_EE_c[6]` | f32 |
//! | 1088 | `theta[7]`, `dtheta[7]` | f32 |
//! | 1144 | `accelerometer_top`, `accelerometer_bottom` | 2 × 6 × 3 f32 |
//! | 1288 | `motion_generator_mode`, `controller_mode` | u8, u8 |
//! | 1290 | `errors[41]`, `reflex_reason[41]` | bool |
//! | 1372 | `robot_mode` | u8 |
//! | 1373 | `control_command_success_rate` | f32 |
//!
//! Decoded values are `f64` (an `f32` converts exactly). The model of the arm (mass matrix,
//! Coriolis, gravity) is not in the record: since version 10 the robot hands the client its
//! URDF (`GetRobotModel`) and the client computes the dynamics itself.

use core::fmt;

use super::DOF;
use super::errors::{ERROR_COUNT, ErrorSet};
use super::wire::{Reader, Writer};

/// Bytes of a state record.
pub const STATE_LEN: usize = 1377;

/// The identity as a column-major 4×4 matrix.
pub const IDENTITY: [f64; 16] = [
    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
];

/// The motion generator the robot runs (`rbk_types.h` `MotionGeneratorMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MotionGeneratorMode {
    /// 0: no motion.
    #[default]
    Idle,
    /// 1: the client's joint positions.
    JointPosition,
    /// 2: the client's joint velocities.
    JointVelocity,
    /// 3: the client's Cartesian pose.
    CartesianPosition,
    /// 4: the client's Cartesian velocity.
    CartesianVelocity,
    /// 5: none (pure torque control).
    None,
}

/// The controller the robot runs (`rbk_types.h` `ControllerMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ControllerMode {
    /// 0: joint impedance.
    JointImpedance,
    /// 1: Cartesian impedance.
    CartesianImpedance,
    /// 2: the client's torques.
    ExternalController,
    /// 3: another one (idle).
    #[default]
    Other,
}

/// The robot's mode (`rbk_types.h` `RobotMode`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RobotMode {
    /// 0: another mode (not ready for FCI: brakes closed, Desk in control).
    Other,
    /// 1: ready, no motion.
    #[default]
    Idle,
    /// 2: a motion runs.
    Move,
    /// 3: hand guiding.
    Guiding,
    /// 4: stopped by a reflex; errors must be recovered.
    Reflex,
    /// 5: the user stop is pressed.
    UserStopped,
    /// 6: recovering from errors.
    AutomaticErrorRecovery,
}

macro_rules! codes {
    ($t:ty, $field:literal, $($variant:ident = $code:literal),+) => {
        impl $t {
            /// The mode's byte.
            pub const fn code(self) -> u8 {
                match self {
                    $(Self::$variant => $code),+
                }
            }

            /// The mode of a byte.
            pub const fn from_u8(code: u8) -> Option<Self> {
                match code {
                    $($code => Some(Self::$variant),)+
                    _ => None,
                }
            }

            const FIELD: &'static str = $field;
        }
    };
}

codes!(
    MotionGeneratorMode,
    "motion_generator_mode",
    Idle = 0,
    JointPosition = 1,
    JointVelocity = 2,
    CartesianPosition = 3,
    CartesianVelocity = 4,
    None = 5
);
codes!(
    ControllerMode,
    "controller_mode",
    JointImpedance = 0,
    CartesianImpedance = 1,
    ExternalController = 2,
    Other = 3
);
codes!(
    RobotMode,
    "robot_mode",
    Other = 0,
    Idle = 1,
    Move = 2,
    Guiding = 3,
    Reflex = 4,
    UserStopped = 5,
    AutomaticErrorRecovery = 6
);

impl fmt::Display for RobotMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Other => "other",
            Self::Idle => "idle",
            Self::Move => "move",
            Self::Guiding => "guiding",
            Self::Reflex => "reflex",
            Self::UserStopped => "user stopped",
            Self::AutomaticErrorRecovery => "automatic error recovery",
        })
    }
}

/// What is wrong with a state record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StateError {
    /// Not [`STATE_LEN`] bytes.
    Length {
        /// Bytes received.
        got: usize,
    },
    /// A mode byte outside its enumeration.
    BadMode {
        /// Which field.
        field: &'static str,
        /// Its offset.
        offset: usize,
        /// The value.
        value: u8,
    },
}

impl fmt::Display for StateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Length { got } => write!(f, "state of {got} bytes, expected {STATE_LEN}"),
            Self::BadMode {
                field,
                offset,
                value,
            } => write!(f, "{field} at byte {offset}: invalid value {value}"),
        }
    }
}

/// One robot state (libfranka's `franka::RobotState` before its conversions). Frames are
/// column-major 4×4 matrices; `O` is the base, `F` the flange, `NE` the nominal end effector,
/// `EE` the end effector, `K` the stiffness frame. Suffix `_d` is desired (what the robot's
/// controller aims at), `_c` commanded (what the client sent, as the robot took it).
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(non_snake_case, missing_docs)]
pub struct RobotState {
    /// The robot's millisecond counter; a command answers the state with its id.
    pub message_id: u64,
    /// Measured end-effector pose in the base frame.
    pub O_T_EE: [f64; 16],
    /// Last desired end-effector pose.
    pub O_T_EE_d: [f64; 16],
    /// End effector in the flange frame.
    pub F_T_EE: [f64; 16],
    /// Stiffness frame in the end-effector frame.
    pub EE_T_K: [f64; 16],
    /// Nominal end effector in the flange frame.
    pub F_T_NE: [f64; 16],
    /// End effector in the nominal end-effector frame.
    pub NE_T_EE: [f64; 16],
    /// End effector's mass, kg.
    pub m_ee: f64,
    /// End effector's inertia about its centre of mass, column-major.
    pub I_ee: [f64; 9],
    /// End effector's centre of mass in the flange frame.
    pub F_x_Cee: [f64; 3],
    /// Load's mass.
    pub m_load: f64,
    /// Load's inertia.
    pub I_load: [f64; 9],
    /// Load's centre of mass.
    pub F_x_Cload: [f64; 3],
    /// Elbow (joint 3's position, joint 4's sign).
    pub elbow: [f64; 2],
    /// Desired elbow.
    pub elbow_d: [f64; 2],
    /// Measured link-side joint torques, N·m.
    pub tau_J: [f64; DOF],
    /// Desired joint torques without gravity, N·m.
    pub tau_J_d: [f64; DOF],
    /// Derivative of the measured torques, N·m/s.
    pub dtau_J: [f64; DOF],
    /// Measured joint positions, rad.
    pub q: [f64; DOF],
    /// Desired joint positions.
    pub q_d: [f64; DOF],
    /// Measured joint velocities, rad/s.
    pub dq: [f64; DOF],
    /// Desired joint velocities.
    pub dq_d: [f64; DOF],
    /// Desired joint accelerations.
    pub ddq_d: [f64; DOF],
    pub joint_contact: [f64; DOF],
    pub cartesian_contact: [f64; 6],
    pub joint_collision: [f64; DOF],
    pub cartesian_collision: [f64; 6],
    /// Estimated external joint torques, filtered.
    pub tau_ext_hat_filtered: [f64; DOF],
    pub O_F_ext_hat_K: [f64; 6],
    pub K_F_ext_hat_K: [f64; 6],
    pub O_dP_EE_d: [f64; 6],
    pub O_ddP_O: [f64; 3],
    pub elbow_c: [f64; 2],
    pub delbow_c: [f64; 2],
    pub ddelbow_c: [f64; 2],
    pub O_T_EE_c: [f64; 16],
    pub O_dP_EE_c: [f64; 6],
    pub O_ddP_EE_c: [f64; 6],
    /// Motor positions (before the elastic transmission).
    pub theta: [f64; DOF],
    pub dtheta: [f64; DOF],
    pub accelerometer_top: [[f64; 3]; 6],
    pub accelerometer_bottom: [[f64; 3]; 6],
    pub motion_generator_mode: MotionGeneratorMode,
    pub controller_mode: ControllerMode,
    /// Errors active now.
    pub errors: ErrorSet,
    /// Why the last motion was stopped (libfranka's `last_motion_errors`).
    pub reflex_reason: ErrorSet,
    pub robot_mode: RobotMode,
    /// Fraction of the last 100 commands that reached the robot in time.
    pub control_command_success_rate: f64,
}

impl Default for RobotState {
    fn default() -> Self {
        Self {
            message_id: 0,
            O_T_EE: IDENTITY,
            O_T_EE_d: IDENTITY,
            F_T_EE: IDENTITY,
            EE_T_K: IDENTITY,
            F_T_NE: IDENTITY,
            NE_T_EE: IDENTITY,
            m_ee: 0.0,
            I_ee: [0.0; 9],
            F_x_Cee: [0.0; 3],
            m_load: 0.0,
            I_load: [0.0; 9],
            F_x_Cload: [0.0; 3],
            elbow: [0.0; 2],
            elbow_d: [0.0; 2],
            tau_J: [0.0; DOF],
            tau_J_d: [0.0; DOF],
            dtau_J: [0.0; DOF],
            q: [0.0; DOF],
            q_d: [0.0; DOF],
            dq: [0.0; DOF],
            dq_d: [0.0; DOF],
            ddq_d: [0.0; DOF],
            joint_contact: [0.0; DOF],
            cartesian_contact: [0.0; 6],
            joint_collision: [0.0; DOF],
            cartesian_collision: [0.0; 6],
            tau_ext_hat_filtered: [0.0; DOF],
            O_F_ext_hat_K: [0.0; 6],
            K_F_ext_hat_K: [0.0; 6],
            O_dP_EE_d: [0.0; 6],
            O_ddP_O: [0.0; 3],
            elbow_c: [0.0; 2],
            delbow_c: [0.0; 2],
            ddelbow_c: [0.0; 2],
            O_T_EE_c: IDENTITY,
            O_dP_EE_c: [0.0; 6],
            O_ddP_EE_c: [0.0; 6],
            theta: [0.0; DOF],
            dtheta: [0.0; DOF],
            accelerometer_top: [[0.0; 3]; 6],
            accelerometer_bottom: [[0.0; 3]; 6],
            motion_generator_mode: MotionGeneratorMode::Idle,
            controller_mode: ControllerMode::Other,
            errors: ErrorSet::EMPTY,
            reflex_reason: ErrorSet::EMPTY,
            robot_mode: RobotMode::Idle,
            control_command_success_rate: 0.0,
        }
    }
}

/// Offset of `motion_generator_mode`.
const MODES_OFFSET: usize = 1288;
/// Offset of `robot_mode`.
const ROBOT_MODE_OFFSET: usize = 1372;

impl RobotState {
    /// Reads a record into `self` (in place: the caller's buffer, no copy of 3 KiB on the
    /// stack per cycle). On an error `self` is left as it was.
    pub fn decode_into(&mut self, bytes: &[u8]) -> Result<(), StateError> {
        if bytes.len() != STATE_LEN {
            return Err(StateError::Length { got: bytes.len() });
        }
        let mode = |offset: usize| bytes[offset];
        let mg = MotionGeneratorMode::from_u8(mode(MODES_OFFSET)).ok_or(StateError::BadMode {
            field: MotionGeneratorMode::FIELD,
            offset: MODES_OFFSET,
            value: mode(MODES_OFFSET),
        })?;
        let cm = ControllerMode::from_u8(mode(MODES_OFFSET + 1)).ok_or(StateError::BadMode {
            field: ControllerMode::FIELD,
            offset: MODES_OFFSET + 1,
            value: mode(MODES_OFFSET + 1),
        })?;
        let rm = RobotMode::from_u8(mode(ROBOT_MODE_OFFSET)).ok_or(StateError::BadMode {
            field: RobotMode::FIELD,
            offset: ROBOT_MODE_OFFSET,
            value: mode(ROBOT_MODE_OFFSET),
        })?;
        let mut r = Reader::new(bytes);
        self.message_id = r.u64();
        self.O_T_EE = r.f32s();
        self.O_T_EE_d = r.f32s();
        self.F_T_EE = r.f32s();
        self.EE_T_K = r.f32s();
        self.F_T_NE = r.f32s();
        self.NE_T_EE = r.f32s();
        self.m_ee = r.f32();
        self.I_ee = r.f32s();
        self.F_x_Cee = r.f32s();
        self.m_load = r.f32();
        self.I_load = r.f32s();
        self.F_x_Cload = r.f32s();
        self.elbow = r.f32s();
        self.elbow_d = r.f32s();
        self.tau_J = r.f32s();
        self.tau_J_d = r.f32s();
        self.dtau_J = r.f32s();
        self.q = r.f32s();
        self.q_d = r.f32s();
        self.dq = r.f32s();
        self.dq_d = r.f32s();
        self.ddq_d = r.f32s();
        self.joint_contact = r.f32s();
        self.cartesian_contact = r.f32s();
        self.joint_collision = r.f32s();
        self.cartesian_collision = r.f32s();
        self.tau_ext_hat_filtered = r.f32s();
        self.O_F_ext_hat_K = r.f32s();
        self.K_F_ext_hat_K = r.f32s();
        self.O_dP_EE_d = r.f32s();
        self.O_ddP_O = r.f32s();
        self.elbow_c = r.f32s();
        self.delbow_c = r.f32s();
        self.ddelbow_c = r.f32s();
        self.O_T_EE_c = r.f32s();
        self.O_dP_EE_c = r.f32s();
        self.O_ddP_EE_c = r.f32s();
        self.theta = r.f32s();
        self.dtheta = r.f32s();
        self.accelerometer_top = core::array::from_fn(|_| r.f32s());
        self.accelerometer_bottom = core::array::from_fn(|_| r.f32s());
        debug_assert_eq!(r.position(), MODES_OFFSET);
        r.u8();
        r.u8();
        self.motion_generator_mode = mg;
        self.controller_mode = cm;
        self.errors = ErrorSet::from_flags(&r.bools::<ERROR_COUNT>());
        self.reflex_reason = ErrorSet::from_flags(&r.bools::<ERROR_COUNT>());
        r.u8();
        self.robot_mode = rm;
        self.control_command_success_rate = r.f32();
        Ok(())
    }

    /// Writes the record (what the robot sends); values are rounded to `f32`.
    pub fn encode(&self, out: &mut [u8; STATE_LEN]) {
        let mut w = Writer::new(out);
        w.u64(self.message_id);
        for m in [
            &self.O_T_EE,
            &self.O_T_EE_d,
            &self.F_T_EE,
            &self.EE_T_K,
            &self.F_T_NE,
            &self.NE_T_EE,
        ] {
            w.f32s(m);
        }
        w.f32(self.m_ee);
        w.f32s(&self.I_ee);
        w.f32s(&self.F_x_Cee);
        w.f32(self.m_load);
        w.f32s(&self.I_load);
        w.f32s(&self.F_x_Cload);
        w.f32s(&self.elbow);
        w.f32s(&self.elbow_d);
        for v in [
            &self.tau_J,
            &self.tau_J_d,
            &self.dtau_J,
            &self.q,
            &self.q_d,
            &self.dq,
            &self.dq_d,
            &self.ddq_d,
            &self.joint_contact,
        ] {
            w.f32s(v);
        }
        w.f32s(&self.cartesian_contact);
        w.f32s(&self.joint_collision);
        w.f32s(&self.cartesian_collision);
        w.f32s(&self.tau_ext_hat_filtered);
        w.f32s(&self.O_F_ext_hat_K);
        w.f32s(&self.K_F_ext_hat_K);
        w.f32s(&self.O_dP_EE_d);
        w.f32s(&self.O_ddP_O);
        w.f32s(&self.elbow_c);
        w.f32s(&self.delbow_c);
        w.f32s(&self.ddelbow_c);
        w.f32s(&self.O_T_EE_c);
        w.f32s(&self.O_dP_EE_c);
        w.f32s(&self.O_ddP_EE_c);
        w.f32s(&self.theta);
        w.f32s(&self.dtheta);
        for a in self
            .accelerometer_top
            .iter()
            .chain(self.accelerometer_bottom.iter())
        {
            w.f32s(a);
        }
        debug_assert_eq!(w.position(), MODES_OFFSET);
        w.u8(self.motion_generator_mode.code());
        w.u8(self.controller_mode.code());
        w.bools(&self.errors.to_flags());
        w.bools(&self.reflex_reason.to_flags());
        w.u8(self.robot_mode.code());
        w.f32(self.control_command_success_rate);
        debug_assert_eq!(w.position(), STATE_LEN);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::franka::errors::RobotError;

    #[test]
    fn a_state_round_trips_through_its_1377_bytes() {
        let mut s = RobotState {
            message_id: 123_456_789,
            q: [0.1, -0.2, 0.3, -1.5, 0.5, 1.6, 0.7],
            dq: [0.01; 7],
            tau_J: [1.0, -30.0, 2.0, 22.0, 0.8, 2.1, 0.0],
            motion_generator_mode: MotionGeneratorMode::JointPosition,
            controller_mode: ControllerMode::JointImpedance,
            robot_mode: RobotMode::Reflex,
            errors: ErrorSet::EMPTY.with(RobotError::JointMotionGeneratorVelocityDiscontinuity),
            reflex_reason: ErrorSet::EMPTY.with(RobotError::CommunicationConstraintsViolation),
            control_command_success_rate: 0.96,
            ..RobotState::default()
        };
        s.accelerometer_bottom[5] = [0.5, -9.75, 0.25];
        let mut buf = [0u8; STATE_LEN];
        s.encode(&mut buf);
        let mut d = RobotState::default();
        d.decode_into(&buf).unwrap();
        // Every value is an f32 on the wire.
        let mut expected = s;
        expected.q = s.q.map(|x| f64::from(x as f32));
        expected.dq = s.dq.map(|x| f64::from(x as f32));
        expected.tau_J = s.tau_J.map(|x| f64::from(x as f32));
        expected.control_command_success_rate = f64::from(0.96f32);
        assert_eq!(d, expected);
        // The offsets of the table in the module documentation.
        assert_eq!(&buf[0..8], &123_456_789u64.to_le_bytes());
        assert_eq!(buf[1288], 1, "motion generator mode");
        assert_eq!(buf[1289], 0, "controller mode");
        assert_eq!(buf[1290 + 14], 1, "errors[14]");
        assert_eq!(buf[1331 + 25], 1, "reflex_reason[25]");
        assert_eq!(buf[1372], 4, "robot mode");
        assert_eq!(&buf[512 + 3 * 28..512 + 3 * 28 + 4], &0.1f32.to_le_bytes());
    }

    #[test]
    fn wrong_lengths_and_modes_are_refused_without_touching_the_state() {
        let mut d = RobotState::default();
        assert_eq!(
            d.decode_into(&[0u8; 100]),
            Err(StateError::Length { got: 100 })
        );
        let mut buf = [0u8; STATE_LEN];
        RobotState::default().encode(&mut buf);
        buf[1372] = 9;
        let e = d.decode_into(&buf).unwrap_err();
        assert_eq!(e.to_string(), "robot_mode at byte 1372: invalid value 9");
        assert_eq!(d, RobotState::default());
    }
}
