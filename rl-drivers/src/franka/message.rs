//! The TCP command messages: a 12-byte header (`command: u32`, `command_id: u32`, `size: u32`,
//! the whole message's length) followed by the request's packed payload; the answer repeats the
//! command and its id and carries a one-byte status, then, for some commands, more (the
//! robot's version after `Connect`, the URDF after `GetRobotModel`).
//!
//! Payloads (libfranka-common `service_types.h`, `#pragma pack(1)`, little endian):
//!
//! | command | request payload | bytes |
//! |---|---|---|
//! | 0 `Connect` | version u16, udp_port u16 ([`super::connect`]) | 4 |
//! | 1 `Move` | controller mode u32, motion generator mode u32, path deviation 3 f64, goal deviation 3 f64, async bool, max velocity 7 f64 | 113 |
//! | 2 `StopMove` | — | 0 |
//! | 3 `SetCollisionBehavior` | 4 × 7 f64 torque thresholds, 4 × 6 f64 force thresholds | 416 |
//! | 4 `SetJointImpedance` | `K_theta` 7 f64 | 56 |
//! | 5 `SetCartesianImpedance` | `K_x` 6 f64 | 48 |
//! | 6 `SetGuidingMode` | 6 bool, nullspace bool | 7 |
//! | 7 `SetEEToK` | `EE_T_K` 16 f64 (column-major) | 128 |
//! | 8 `SetNEToEE` | `NE_T_EE` 16 f64 (column-major) | 128 |
//! | 9 `SetLoad` | mass f64, `F_x_Cload` 3 f64, `I_load` 9 f64 | 104 |
//! | 10 `AutomaticErrorRecovery` | — | 0 |
//! | 11 `GetRobotModel` | — | 0 |
//!
//! A `Move` request of 56 bytes (without the asynchronous motion generator's fields, as older
//! clients and franky-sim's parser have it) is accepted by [`Request::decode`].

use core::fmt;

use super::DOF;
use super::connect::ConnectRequest;
use super::wire::{Reader, Writer};

/// Bytes of a message header.
pub const HEADER_LEN: usize = 12;
/// Bytes of the longest request (`SetCollisionBehavior`), header included.
pub const MAX_REQUEST_LEN: usize = HEADER_LEN + 52 * 8;
/// Bytes of a `Move` request's payload with the asynchronous motion generator's fields.
pub const MOVE_PAYLOAD_LEN: usize = 113;
/// Bytes of a `Move` request's payload without them.
pub const MOVE_PAYLOAD_LEN_SHORT: usize = 56;

/// A command of the TCP interface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Command {
    /// 0: the handshake.
    Connect = 0,
    /// 1: start a motion.
    Move = 1,
    /// 2: stop the running motion.
    StopMove = 2,
    /// 3: contact and collision thresholds.
    SetCollisionBehavior = 3,
    /// 4: stiffness of the internal joint impedance controller.
    SetJointImpedance = 4,
    /// 5: stiffness of the internal Cartesian impedance controller.
    SetCartesianImpedance = 5,
    /// 6: which axes hand guiding may move.
    SetGuidingMode = 6,
    /// 7: the stiffness frame K relative to the end effector.
    SetEeToK = 7,
    /// 8: the end effector relative to the nominal end effector.
    SetNeToEe = 8,
    /// 9: the load's mass, centre of mass and inertia.
    SetLoad = 9,
    /// 10: clear the robot's errors (after a reflex).
    AutomaticErrorRecovery = 10,
    /// 11: the robot's model as URDF.
    GetRobotModel = 11,
}

impl Command {
    /// The command for a header's code.
    pub const fn from_u32(code: u32) -> Option<Self> {
        Some(match code {
            0 => Self::Connect,
            1 => Self::Move,
            2 => Self::StopMove,
            3 => Self::SetCollisionBehavior,
            4 => Self::SetJointImpedance,
            5 => Self::SetCartesianImpedance,
            6 => Self::SetGuidingMode,
            7 => Self::SetEeToK,
            8 => Self::SetNeToEe,
            9 => Self::SetLoad,
            10 => Self::AutomaticErrorRecovery,
            11 => Self::GetRobotModel,
            _ => return None,
        })
    }

    /// libfranka's name of the command (`CommandTraits::kName`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Connect => "Connect",
            Self::Move => "Move",
            Self::StopMove => "Stop Move",
            Self::SetCollisionBehavior => "Set Collision Behavior",
            Self::SetJointImpedance => "Set Joint Impedance",
            Self::SetCartesianImpedance => "Set Cartesian Impedance",
            Self::SetGuidingMode => "Set Guiding Mode",
            Self::SetEeToK => "Set EE to K",
            Self::SetNeToEe => "Set NE to EE",
            Self::SetLoad => "Set Load",
            Self::AutomaticErrorRecovery => "Automatic Error Recovery",
            Self::GetRobotModel => "Get Robot Model",
        }
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// What is wrong with a message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MessageError {
    /// Fewer bytes than the part being read needs.
    TooShort {
        /// What was being read.
        what: &'static str,
        /// Bytes needed.
        needed: usize,
        /// Bytes there.
        got: usize,
    },
    /// The header's size is smaller than a header or larger than the receiver accepts.
    BadSize {
        /// The size in the header.
        size: u32,
        /// The largest accepted.
        max: usize,
    },
    /// The header names no known command.
    UnknownCommand {
        /// The code found.
        code: u32,
    },
    /// A mode or status byte outside its enumeration.
    BadValue {
        /// Which field.
        field: &'static str,
        /// The value found.
        value: u32,
    },
    /// The output buffer is too small for the message.
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
    },
}

impl fmt::Display for MessageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooShort { what, needed, got } => {
                write!(f, "{what}: {got} bytes, needs {needed}")
            }
            Self::BadSize { size, max } => {
                write!(f, "header size {size} outside {HEADER_LEN}..={max}")
            }
            Self::UnknownCommand { code } => write!(f, "unknown command {code}"),
            Self::BadValue { field, value } => write!(f, "{field}: invalid value {value}"),
            Self::BufferTooSmall { needed } => write!(f, "output buffer needs {needed} bytes"),
        }
    }
}

/// A message header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// The command.
    pub command: Command,
    /// The id the client chose; the answer repeats it.
    pub command_id: u32,
    /// The message's length, header included.
    pub size: u32,
}

impl Header {
    /// Writes the header into the first [`HEADER_LEN`] bytes of `out`.
    pub fn encode(&self, out: &mut [u8]) -> Result<(), MessageError> {
        if out.len() < HEADER_LEN {
            return Err(MessageError::BufferTooSmall { needed: HEADER_LEN });
        }
        let mut w = Writer::new(out);
        w.u32(self.command as u32);
        w.u32(self.command_id);
        w.u32(self.size);
        Ok(())
    }

    /// Reads a header; its size must lie between [`HEADER_LEN`] and `max_size`.
    pub fn decode(bytes: &[u8], max_size: usize) -> Result<Self, MessageError> {
        if bytes.len() < HEADER_LEN {
            return Err(MessageError::TooShort {
                what: "header",
                needed: HEADER_LEN,
                got: bytes.len(),
            });
        }
        let mut r = Reader::new(bytes);
        let code = r.u32();
        let command_id = r.u32();
        let size = r.u32();
        if (size as usize) < HEADER_LEN || size as usize > max_size {
            return Err(MessageError::BadSize {
                size,
                max: max_size,
            });
        }
        let command = Command::from_u32(code).ok_or(MessageError::UnknownCommand { code })?;
        Ok(Self {
            command,
            command_id,
            size,
        })
    }

    /// Bytes of payload after the header.
    pub fn payload_len(&self) -> usize {
        (self.size as usize).saturating_sub(HEADER_LEN)
    }
}

/// The controller a `Move` runs (its code on the wire is the `u32` of `Move::ControllerMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MoveControllerMode {
    /// 0: the robot's joint impedance controller tracks the motion generator.
    JointImpedance,
    /// 1: the robot's Cartesian impedance controller tracks it.
    CartesianImpedance,
    /// 2: the client commands joint torques (gravity is added by the robot).
    ExternalController,
}

impl MoveControllerMode {
    const fn code(self) -> u32 {
        match self {
            Self::JointImpedance => 0,
            Self::CartesianImpedance => 1,
            Self::ExternalController => 2,
        }
    }

    const fn from_code(code: u32) -> Option<Self> {
        Some(match code {
            0 => Self::JointImpedance,
            1 => Self::CartesianImpedance,
            2 => Self::ExternalController,
            _ => return None,
        })
    }
}

/// The motion generator a `Move` runs (`Move::MotionGeneratorMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MoveMotionGeneratorMode {
    /// 0: the client commands joint positions `q_c`.
    JointPosition,
    /// 1: joint velocities `dq_c`.
    JointVelocity,
    /// 2: the end effector's pose `O_T_EE_c`.
    CartesianPosition,
    /// 3: its twist `O_dP_EE_c`.
    CartesianVelocity,
    /// 4: none (torque control alone).
    None,
}

impl MoveMotionGeneratorMode {
    const fn code(self) -> u32 {
        match self {
            Self::JointPosition => 0,
            Self::JointVelocity => 1,
            Self::CartesianPosition => 2,
            Self::CartesianVelocity => 3,
            Self::None => 4,
        }
    }

    const fn from_code(code: u32) -> Option<Self> {
        Some(match code {
            0 => Self::JointPosition,
            1 => Self::JointVelocity,
            2 => Self::CartesianPosition,
            3 => Self::CartesianVelocity,
            4 => Self::None,
            _ => return None,
        })
    }
}

/// How far the robot's internal motion may deviate (`Move::Deviation`): m, rad, rad.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Deviation {
    /// Translation in m.
    pub translation: f64,
    /// Rotation in rad.
    pub rotation: f64,
    /// Elbow in rad.
    pub elbow: f64,
}

impl Deviation {
    /// libfranka's default for its control loops (`kDefaultDeviation`): 10 m, 3.12 rad,
    /// 2π rad, i.e. not limiting.
    pub const DEFAULT: Self = Self {
        translation: 10.0,
        rotation: 3.12,
        elbow: 2.0 * core::f64::consts::PI,
    };
}

/// `Move`'s request.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveRequest {
    /// The controller.
    pub controller_mode: MoveControllerMode,
    /// The motion generator.
    pub motion_generator_mode: MoveMotionGeneratorMode,
    /// Largest deviation from the path.
    pub maximum_path_deviation: Deviation,
    /// Largest deviation from the goal pose.
    pub maximum_goal_pose_deviation: Deviation,
    /// The asynchronous (low-rate) motion generator's velocity limits, when it is used.
    pub async_maximum_velocity: Option<[f64; DOF]>,
}

/// `SetCollisionBehavior`'s thresholds: torques in N·m per joint, forces in N and N·m per
/// Cartesian axis, each a lower (contact) and upper (collision) bound, during acceleration and
/// at nominal speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollisionBehavior {
    /// Contact torque while accelerating.
    pub lower_torque_acceleration: [f64; DOF],
    /// Collision torque while accelerating.
    pub upper_torque_acceleration: [f64; DOF],
    /// Contact torque at nominal speed.
    pub lower_torque_nominal: [f64; DOF],
    /// Collision torque at nominal speed.
    pub upper_torque_nominal: [f64; DOF],
    /// Contact force while accelerating.
    pub lower_force_acceleration: [f64; 6],
    /// Collision force while accelerating.
    pub upper_force_acceleration: [f64; 6],
    /// Contact force at nominal speed.
    pub lower_force_nominal: [f64; 6],
    /// Collision force at nominal speed.
    pub upper_force_nominal: [f64; 6],
}

impl CollisionBehavior {
    /// The same torque and force thresholds everywhere (franky's `set_collision_behavior(t, f)`).
    pub const fn uniform(torque: f64, force: f64) -> Self {
        Self {
            lower_torque_acceleration: [torque; DOF],
            upper_torque_acceleration: [torque; DOF],
            lower_torque_nominal: [torque; DOF],
            upper_torque_nominal: [torque; DOF],
            lower_force_acceleration: [force; 6],
            upper_force_acceleration: [force; 6],
            lower_force_nominal: [force; 6],
            upper_force_nominal: [force; 6],
        }
    }

    /// The upper torque thresholds in effect (the larger of acceleration and nominal).
    pub fn collision_torque(&self) -> [f64; DOF] {
        core::array::from_fn(|i| {
            self.upper_torque_acceleration[i].max(self.upper_torque_nominal[i])
        })
    }
}

/// `SetLoad`'s request: the load on the flange.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Load {
    /// Mass in kg.
    pub mass: f64,
    /// Centre of mass in the flange frame, m.
    pub center_of_mass: [f64; 3],
    /// Inertia about the centre of mass, kg·m², column-major 3×3.
    pub inertia: [f64; 9],
}

/// A request of the TCP interface.
// A value built on the stack and encoded at once: boxing the large variant would allocate.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Request {
    /// The handshake.
    Connect(ConnectRequest),
    /// Start a motion.
    Move(MoveRequest),
    /// Stop the running motion.
    StopMove,
    /// Contact and collision thresholds.
    SetCollisionBehavior(CollisionBehavior),
    /// Joint stiffness `K_theta` in N·m/rad.
    SetJointImpedance([f64; DOF]),
    /// Cartesian stiffness `K_x`: N/m for x, y, z, N·m/rad for the rotations.
    SetCartesianImpedance([f64; 6]),
    /// Axes hand guiding may move, and whether the nullspace may.
    SetGuidingMode {
        /// x, y, z, roll, pitch, yaw.
        axes: [bool; 6],
        /// The elbow.
        nullspace: bool,
    },
    /// `EE_T_K`, column-major.
    SetEeToK([f64; 16]),
    /// `NE_T_EE`, column-major.
    SetNeToEe([f64; 16]),
    /// The load.
    SetLoad(Load),
    /// Clear the robot's errors.
    AutomaticErrorRecovery,
    /// Ask for the robot's URDF.
    GetRobotModel,
}

impl Request {
    /// The request's command.
    pub const fn command(&self) -> Command {
        match self {
            Self::Connect(_) => Command::Connect,
            Self::Move(_) => Command::Move,
            Self::StopMove => Command::StopMove,
            Self::SetCollisionBehavior(_) => Command::SetCollisionBehavior,
            Self::SetJointImpedance(_) => Command::SetJointImpedance,
            Self::SetCartesianImpedance(_) => Command::SetCartesianImpedance,
            Self::SetGuidingMode { .. } => Command::SetGuidingMode,
            Self::SetEeToK(_) => Command::SetEeToK,
            Self::SetNeToEe(_) => Command::SetNeToEe,
            Self::SetLoad(_) => Command::SetLoad,
            Self::AutomaticErrorRecovery => Command::AutomaticErrorRecovery,
            Self::GetRobotModel => Command::GetRobotModel,
        }
    }

    /// Bytes of the payload.
    pub const fn payload_len(&self) -> usize {
        match self {
            Self::Connect(_) => 4,
            Self::Move(_) => MOVE_PAYLOAD_LEN,
            Self::StopMove | Self::AutomaticErrorRecovery | Self::GetRobotModel => 0,
            Self::SetCollisionBehavior(_) => 52 * 8,
            Self::SetJointImpedance(_) => DOF * 8,
            Self::SetCartesianImpedance(_) => 6 * 8,
            Self::SetGuidingMode { .. } => 7,
            Self::SetEeToK(_) | Self::SetNeToEe(_) => 16 * 8,
            Self::SetLoad(_) => 13 * 8,
        }
    }

    /// Writes the message (header with `command_id`, then the payload) into `out`; returns its
    /// length.
    pub fn encode(&self, command_id: u32, out: &mut [u8]) -> Result<usize, MessageError> {
        let len = HEADER_LEN + self.payload_len();
        if out.len() < len {
            return Err(MessageError::BufferTooSmall { needed: len });
        }
        Header {
            command: self.command(),
            command_id,
            // At most MAX_REQUEST_LEN (428).
            size: len as u32,
        }
        .encode(out)?;
        let mut w = Writer::new(&mut out[HEADER_LEN..len]);
        match self {
            Self::Connect(c) => {
                w.u16(c.version);
                w.u16(c.udp_port);
            }
            Self::Move(m) => {
                w.u32(m.controller_mode.code());
                w.u32(m.motion_generator_mode.code());
                for d in [m.maximum_path_deviation, m.maximum_goal_pose_deviation] {
                    w.f64(d.translation);
                    w.f64(d.rotation);
                    w.f64(d.elbow);
                }
                w.bool(m.async_maximum_velocity.is_some());
                w.f64s(&m.async_maximum_velocity.unwrap_or([0.0; DOF]));
            }
            Self::StopMove | Self::AutomaticErrorRecovery | Self::GetRobotModel => {}
            Self::SetCollisionBehavior(c) => {
                w.f64s(&c.lower_torque_acceleration);
                w.f64s(&c.upper_torque_acceleration);
                w.f64s(&c.lower_torque_nominal);
                w.f64s(&c.upper_torque_nominal);
                w.f64s(&c.lower_force_acceleration);
                w.f64s(&c.upper_force_acceleration);
                w.f64s(&c.lower_force_nominal);
                w.f64s(&c.upper_force_nominal);
            }
            Self::SetJointImpedance(k) => w.f64s(k),
            Self::SetCartesianImpedance(k) => w.f64s(k),
            Self::SetGuidingMode { axes, nullspace } => {
                w.bools(axes);
                w.bool(*nullspace);
            }
            Self::SetEeToK(t) | Self::SetNeToEe(t) => w.f64s(t),
            Self::SetLoad(l) => {
                w.f64(l.mass);
                w.f64s(&l.center_of_mass);
                w.f64s(&l.inertia);
            }
        }
        Ok(len)
    }

    /// Reads the request of `header` from its `payload` (what the robot does).
    pub fn decode(header: &Header, payload: &[u8]) -> Result<Self, MessageError> {
        let need = |needed: usize| {
            if payload.len() < needed {
                Err(MessageError::TooShort {
                    what: header.command.name(),
                    needed,
                    got: payload.len(),
                })
            } else {
                Ok(())
            }
        };
        let mut r = Reader::new(payload);
        Ok(match header.command {
            Command::Connect => {
                need(4)?;
                Self::Connect(ConnectRequest {
                    version: r.u16(),
                    udp_port: r.u16(),
                })
            }
            Command::Move => {
                need(MOVE_PAYLOAD_LEN_SHORT)?;
                let c = r.u32();
                let controller_mode =
                    MoveControllerMode::from_code(c).ok_or(MessageError::BadValue {
                        field: "Move controller mode",
                        value: c,
                    })?;
                let g = r.u32();
                let motion_generator_mode =
                    MoveMotionGeneratorMode::from_code(g).ok_or(MessageError::BadValue {
                        field: "Move motion generator mode",
                        value: g,
                    })?;
                let mut dev = || Deviation {
                    translation: r.f64(),
                    rotation: r.f64(),
                    elbow: r.f64(),
                };
                let maximum_path_deviation = dev();
                let maximum_goal_pose_deviation = dev();
                let async_maximum_velocity = if payload.len() >= MOVE_PAYLOAD_LEN {
                    let on = r.bool();
                    let v = r.f64s::<DOF>();
                    on.then_some(v)
                } else {
                    None
                };
                Self::Move(MoveRequest {
                    controller_mode,
                    motion_generator_mode,
                    maximum_path_deviation,
                    maximum_goal_pose_deviation,
                    async_maximum_velocity,
                })
            }
            Command::StopMove => Self::StopMove,
            Command::AutomaticErrorRecovery => Self::AutomaticErrorRecovery,
            Command::GetRobotModel => Self::GetRobotModel,
            Command::SetCollisionBehavior => {
                need(52 * 8)?;
                Self::SetCollisionBehavior(CollisionBehavior {
                    lower_torque_acceleration: r.f64s(),
                    upper_torque_acceleration: r.f64s(),
                    lower_torque_nominal: r.f64s(),
                    upper_torque_nominal: r.f64s(),
                    lower_force_acceleration: r.f64s(),
                    upper_force_acceleration: r.f64s(),
                    lower_force_nominal: r.f64s(),
                    upper_force_nominal: r.f64s(),
                })
            }
            Command::SetJointImpedance => {
                need(DOF * 8)?;
                Self::SetJointImpedance(r.f64s())
            }
            Command::SetCartesianImpedance => {
                need(6 * 8)?;
                Self::SetCartesianImpedance(r.f64s())
            }
            Command::SetGuidingMode => {
                need(7)?;
                Self::SetGuidingMode {
                    axes: r.bools(),
                    nullspace: r.bool(),
                }
            }
            Command::SetEeToK => {
                need(16 * 8)?;
                Self::SetEeToK(r.f64s())
            }
            Command::SetNeToEe => {
                need(16 * 8)?;
                Self::SetNeToEe(r.f64s())
            }
            Command::SetLoad => {
                need(13 * 8)?;
                Self::SetLoad(Load {
                    mass: r.f64(),
                    center_of_mass: r.f64s(),
                    inertia: r.f64s(),
                })
            }
        })
    }
}

/// The status of an answer, typed by its command (each command has its own enumeration,
/// `kSuccess` = 0 in all of them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Status {
    /// `Connect::Status`.
    Connect(ConnectStatus),
    /// `Move::Status`.
    Move(MoveStatus),
    /// `StopMove::Status`.
    StopMove(StopMoveStatus),
    /// `GetterSetterCommandBase::Status`: the setters.
    Setter(SetterStatus),
    /// `AutomaticErrorRecovery::Status`.
    Recovery(RecoveryStatus),
    /// `CommandBase::Status`: `GetRobotModel`.
    Base(BaseStatus),
}

macro_rules! status_enum {
    ($(#[$meta:meta])* $name:ident { $($(#[$vmeta:meta])* $variant:ident = $code:literal => $text:literal),+ $(,)? }) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum $name {
            $($(#[$vmeta])* $variant = $code),+
        }

        impl $name {
            /// The status for its byte.
            pub const fn from_u8(code: u8) -> Option<Self> {
                match code {
                    $($code => Some(Self::$variant),)+
                    _ => None,
                }
            }

            /// Its byte.
            pub const fn code(self) -> u8 {
                self as u8
            }

            /// What it means, in libfranka's words.
            pub const fn text(self) -> &'static str {
                match self {
                    $(Self::$variant => $text),+
                }
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.text())
            }
        }
    };
}

status_enum! {
    /// `Connect::Status`.
    ConnectStatus {
        /// Connected.
        Success = 0 => "success",
        /// The robot speaks another version.
        IncompatibleLibraryVersion = 1 => "incompatible library version",
    }
}

status_enum! {
    /// `Move::Status`.
    MoveStatus {
        /// The motion ended as commanded.
        Success = 0 => "success",
        /// The motion started (the first answer).
        MotionStarted = 1 => "motion started",
        /// Another command ended it.
        Preempted = 2 => "preempted",
        /// A safety function ended it.
        PreemptedDueToActivatedSafetyFunctions = 3 => "preempted due to activated safety function",
        /// Refused: a safety function is active.
        CommandRejectedDueToActivatedSafetyFunctions = 4 => "rejected due to activated safety function",
        /// Refused: not possible now (a motion runs, the robot is in error or not in FCI mode).
        CommandNotPossibleRejected = 5 => "command not possible in the current mode",
        /// Refused: starting at a singular pose.
        StartAtSingularPoseRejected = 6 => "cannot start at singular pose",
        /// Refused: a deviation out of range.
        InvalidArgumentRejected = 7 => "maximum path deviation out of range",
        /// A reflex ended it.
        ReflexAborted = 8 => "motion aborted by reflex",
        /// The user stop ended it.
        EmergencyAborted = 9 => "User Stop pressed",
        /// Invalid input ended it.
        InputErrorAborted = 10 => "invalid input provided",
        /// Aborted.
        Aborted = 11 => "aborted",
    }
}

status_enum! {
    /// `StopMove::Status`.
    StopMoveStatus {
        /// Stopped.
        Success = 0 => "success",
        /// Not possible now.
        CommandNotPossibleRejected = 1 => "command not possible in the current mode",
        /// A safety function is active.
        CommandRejectedDueToActivatedSafetyFunctions = 2 => "rejected due to activated safety function",
        /// The user stop.
        EmergencyAborted = 3 => "User Stop pressed",
        /// A reflex.
        ReflexAborted = 4 => "motion aborted by reflex",
        /// Aborted.
        Aborted = 5 => "aborted",
    }
}

status_enum! {
    /// `GetterSetterCommandBase::Status`, the setters' answer.
    SetterStatus {
        /// Set.
        Success = 0 => "success",
        /// Not possible now (a motion runs).
        CommandNotPossibleRejected = 1 => "command not possible in the current mode",
        /// A value out of range.
        InvalidArgumentRejected = 2 => "invalid argument",
        /// A safety function is active.
        CommandRejectedDueToActivatedSafetyFunctions = 3 => "rejected due to activated safety function",
    }
}

status_enum! {
    /// `AutomaticErrorRecovery::Status`.
    RecoveryStatus {
        /// The errors are cleared.
        Success = 0 => "success",
        /// Not possible now.
        CommandNotPossibleRejected = 1 => "command not possible in the current mode",
        /// A safety function is active.
        CommandRejectedDueToActivatedSafetyFunctions = 2 => "rejected due to activated safety function",
        /// The error needs manual recovery (Desk).
        ManualErrorRecoveryRequiredRejected = 3 => "manual error recovery required",
        /// A reflex.
        ReflexAborted = 4 => "aborted by reflex",
        /// The user stop.
        EmergencyAborted = 5 => "User Stop pressed",
        /// Aborted.
        Aborted = 6 => "aborted",
    }
}

status_enum! {
    /// `CommandBase::Status`.
    BaseStatus {
        /// Done.
        Success = 0 => "success",
        /// Not possible now.
        CommandNotPossibleRejected = 1 => "command not possible in the current mode",
        /// A safety function is active.
        CommandRejectedDueToActivatedSafetyFunctions = 2 => "rejected due to activated safety function",
    }
}

impl Status {
    /// The status byte of an answer to `command`.
    pub fn decode(command: Command, code: u8) -> Result<Self, MessageError> {
        let bad = MessageError::BadValue {
            field: "status",
            value: u32::from(code),
        };
        match command {
            Command::Connect => ConnectStatus::from_u8(code).map(Self::Connect),
            Command::Move => MoveStatus::from_u8(code).map(Self::Move),
            Command::StopMove => StopMoveStatus::from_u8(code).map(Self::StopMove),
            Command::SetCollisionBehavior
            | Command::SetJointImpedance
            | Command::SetCartesianImpedance
            | Command::SetGuidingMode
            | Command::SetEeToK
            | Command::SetNeToEe
            | Command::SetLoad => SetterStatus::from_u8(code).map(Self::Setter),
            Command::AutomaticErrorRecovery => RecoveryStatus::from_u8(code).map(Self::Recovery),
            Command::GetRobotModel => BaseStatus::from_u8(code).map(Self::Base),
        }
        .ok_or(bad)
    }

    /// The byte on the wire.
    pub const fn code(self) -> u8 {
        match self {
            Self::Connect(s) => s.code(),
            Self::Move(s) => s.code(),
            Self::StopMove(s) => s.code(),
            Self::Setter(s) => s.code(),
            Self::Recovery(s) => s.code(),
            Self::Base(s) => s.code(),
        }
    }

    /// Whether the command succeeded (for `Move`: started or ended as commanded).
    pub const fn is_success(self) -> bool {
        matches!(
            self,
            Self::Move(MoveStatus::MotionStarted | MoveStatus::Success)
        ) || self.code() == 0
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Connect(s) => s.fmt(f),
            Self::Move(s) => s.fmt(f),
            Self::StopMove(s) => s.fmt(f),
            Self::Setter(s) => s.fmt(f),
            Self::Recovery(s) => s.fmt(f),
            Self::Base(s) => s.fmt(f),
        }
    }
}

/// An answer: its header, status and what follows the status byte.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Response<'a> {
    /// The header (the command and id it answers).
    pub header: Header,
    /// The status.
    pub status: Status,
    /// The bytes after the status (the version after `Connect`, the URDF after
    /// `GetRobotModel`, padding otherwise).
    pub rest: &'a [u8],
}

impl<'a> Response<'a> {
    /// Reads an answer from a complete message (`bytes.len()` at least the header's size).
    pub fn decode(bytes: &'a [u8], max_size: usize) -> Result<Self, MessageError> {
        let header = Header::decode(bytes, max_size)?;
        let size = header.size as usize;
        if bytes.len() < size || size < HEADER_LEN + 1 {
            return Err(MessageError::TooShort {
                what: "answer",
                needed: size.max(HEADER_LEN + 1),
                got: bytes.len().min(size),
            });
        }
        let status = Status::decode(header.command, bytes[HEADER_LEN])?;
        Ok(Self {
            header,
            status,
            rest: &bytes[HEADER_LEN + 1..size],
        })
    }

    /// Writes an answer to `command_id` of `status`'s command with `rest` after the status byte
    /// (what the robot does); returns its length.
    pub fn encode(
        command_id: u32,
        command: Command,
        status: Status,
        rest: &[u8],
        out: &mut [u8],
    ) -> Result<usize, MessageError> {
        let len = HEADER_LEN + 1 + rest.len();
        if out.len() < len {
            return Err(MessageError::BufferTooSmall { needed: len });
        }
        Header {
            command,
            command_id,
            size: u32::try_from(len).map_err(|_| MessageError::BufferTooSmall { needed: len })?,
        }
        .encode(out)?;
        out[HEADER_LEN] = status.code();
        out[HEADER_LEN + 1..len].copy_from_slice(rest);
        Ok(len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_round_trip_and_have_the_packed_lengths() {
        let requests = [
            Request::Move(MoveRequest {
                controller_mode: MoveControllerMode::ExternalController,
                motion_generator_mode: MoveMotionGeneratorMode::None,
                maximum_path_deviation: Deviation::DEFAULT,
                maximum_goal_pose_deviation: Deviation::DEFAULT,
                async_maximum_velocity: None,
            }),
            Request::StopMove,
            Request::SetCollisionBehavior(CollisionBehavior::uniform(20.0, 30.0)),
            Request::SetJointImpedance([3000.0; 7]),
            Request::SetCartesianImpedance([3000.0, 3000.0, 3000.0, 300.0, 300.0, 300.0]),
            Request::SetGuidingMode {
                axes: [true, false, true, false, true, false],
                nullspace: true,
            },
            Request::SetEeToK([1.0; 16]),
            Request::SetNeToEe([2.0; 16]),
            Request::SetLoad(Load {
                mass: 0.5,
                center_of_mass: [0.0, 0.0, 0.1],
                inertia: [0.01, 0.0, 0.0, 0.0, 0.01, 0.0, 0.0, 0.0, 0.01],
            }),
            Request::AutomaticErrorRecovery,
            Request::GetRobotModel,
        ];
        let lens = [125, 12, 428, 68, 60, 19, 140, 140, 116, 12, 12];
        for (req, len) in requests.iter().zip(lens) {
            let mut buf = [0u8; MAX_REQUEST_LEN];
            let n = req.encode(7, &mut buf).unwrap();
            assert_eq!(n, len, "{:?}", req.command());
            let h = Header::decode(&buf, MAX_REQUEST_LEN).unwrap();
            assert_eq!(
                (h.command, h.command_id, h.size as usize),
                (req.command(), 7, n)
            );
            assert_eq!(Request::decode(&h, &buf[HEADER_LEN..n]).unwrap(), *req);
        }
    }

    #[test]
    fn a_short_move_without_the_async_fields_decodes() {
        // franky-sim's parser reads `<II ddd ddd>`: the 56-byte form.
        let mut payload = [0u8; MOVE_PAYLOAD_LEN_SHORT];
        payload[0..4].copy_from_slice(&0u32.to_le_bytes());
        payload[4..8].copy_from_slice(&1u32.to_le_bytes());
        let h = Header {
            command: Command::Move,
            command_id: 3,
            size: (HEADER_LEN + payload.len()) as u32,
        };
        let Request::Move(m) = Request::decode(&h, &payload).unwrap() else {
            panic!("not a move")
        };
        assert_eq!(
            m.motion_generator_mode,
            MoveMotionGeneratorMode::JointVelocity
        );
        assert_eq!(m.async_maximum_velocity, None);
        // Shorter still is an error that says what was short.
        let e = Request::decode(&h, &payload[..40]).unwrap_err();
        assert_eq!(e.to_string(), "Move: 40 bytes, needs 56");
    }

    #[test]
    fn bad_headers_modes_and_statuses_are_typed_errors() {
        let mut buf = [0u8; 16];
        buf[0..4].copy_from_slice(&99u32.to_le_bytes());
        buf[8..12].copy_from_slice(&16u32.to_le_bytes());
        assert_eq!(
            Header::decode(&buf, 64),
            Err(MessageError::UnknownCommand { code: 99 })
        );
        buf[8..12].copy_from_slice(&5u32.to_le_bytes());
        assert!(matches!(
            Header::decode(&buf, 64),
            Err(MessageError::BadSize { size: 5, .. })
        ));
        assert_eq!(
            Status::decode(Command::Move, 12),
            Err(MessageError::BadValue {
                field: "status",
                value: 12
            })
        );
        assert_eq!(
            Status::decode(Command::SetLoad, 2),
            Ok(Status::Setter(SetterStatus::InvalidArgumentRejected))
        );
        let h = Header {
            command: Command::Move,
            command_id: 0,
            size: 68,
        };
        let mut p = [0u8; 56];
        p[0..4].copy_from_slice(&3u32.to_le_bytes());
        assert_eq!(
            Request::decode(&h, &p),
            Err(MessageError::BadValue {
                field: "Move controller mode",
                value: 3
            })
        );
    }

    #[test]
    fn answers_round_trip() {
        let mut buf = [0u8; 64];
        let n = Response::encode(
            5,
            Command::Move,
            Status::Move(MoveStatus::ReflexAborted),
            &[],
            &mut buf,
        )
        .unwrap();
        assert_eq!(n, 13);
        let r = Response::decode(&buf[..n], 64).unwrap();
        assert_eq!(r.header.command_id, 5);
        assert_eq!(r.status, Status::Move(MoveStatus::ReflexAborted));
        assert!(!r.status.is_success());
        assert!(Status::Move(MoveStatus::MotionStarted).is_success());
        let n = Response::encode(
            6,
            Command::GetRobotModel,
            Status::Base(BaseStatus::Success),
            b"<robot/>",
            &mut buf,
        )
        .unwrap();
        assert_eq!(Response::decode(&buf[..n], 64).unwrap().rest, b"<robot/>");
    }
}
