//! Every variable the RTDE interface knows (the *RTDE Guide*'s tables, as PolyScope 5.x
//! serves them), with its type and direction: outputs the controller sends, inputs a client
//! writes, and the general-purpose registers, which are both (an input register can be read
//! back as an output).
//!
//! Register families are indexed: `output_int_register_0` to `_47`,
//! `output_double_register_0` to `_47`, `output_bit_register_64` to `_127` (bits 0 to 63 come
//! as `output_bit_registers0_to_31` and `…32_to_63`), and the same for `input_`. The lower
//! input registers (0 to 23) are meant for fieldbus adapters, the upper ones (24 to 47) for
//! RTDE clients.

use super::DataType;

/// Which way a variable goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    /// From the controller (an output recipe may name it).
    Output,
    /// To the controller (an input recipe may name it).
    Input,
    /// Both (the general-purpose input registers).
    Both,
}

impl Direction {
    /// Whether an output recipe may name it.
    pub const fn readable(self) -> bool {
        matches!(self, Self::Output | Self::Both)
    }

    /// Whether an input recipe may name it.
    pub const fn writable(self) -> bool {
        matches!(self, Self::Input | Self::Both)
    }
}

/// The variables with a name of their own.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[allow(missing_docs)]
pub enum Named {
    /// `timestamp`.
    Timestamp,
    /// `target_q`.
    TargetQ,
    /// `target_qd`.
    TargetQd,
    /// `target_qdd`.
    TargetQdd,
    /// `target_current`.
    TargetCurrent,
    /// `target_moment`.
    TargetMoment,
    /// `actual_q`.
    ActualQ,
    /// `actual_qd`.
    ActualQd,
    /// `actual_current`.
    ActualCurrent,
    /// `actual_current_window`.
    ActualCurrentWindow,
    /// `actual_current_as_torque`.
    ActualCurrentAsTorque,
    /// `joint_control_output`.
    JointControlOutput,
    /// `actual_TCP_pose`.
    ActualTcpPose,
    /// `actual_TCP_speed`.
    ActualTcpSpeed,
    /// `actual_TCP_force`.
    ActualTcpForce,
    /// `target_TCP_pose`.
    TargetTcpPose,
    /// `target_TCP_speed`.
    TargetTcpSpeed,
    /// `tcp_offset`.
    TcpOffset,
    /// `actual_TCP_acceleration`.
    ActualTcpAcceleration,
    /// `target_TCP_acceleration`.
    TargetTcpAcceleration,
    /// `actual_digital_input_bits`.
    ActualDigitalInputBits,
    /// `actual_configurable_digital_input_bits`.
    ActualConfigurableDigitalInputBits,
    /// `joint_temperatures`.
    JointTemperatures,
    /// `actual_execution_time`.
    ActualExecutionTime,
    /// `target_execution_time`.
    TargetExecutionTime,
    /// `robot_mode`.
    RobotMode,
    /// `joint_mode`.
    JointMode,
    /// `safety_mode`.
    SafetyMode,
    /// `safety_status`.
    SafetyStatus,
    /// `actual_tool_accelerometer`.
    ActualToolAccelerometer,
    /// `speed_scaling`.
    SpeedScaling,
    /// `target_speed_fraction`.
    TargetSpeedFraction,
    /// `actual_momentum`.
    ActualMomentum,
    /// `actual_main_voltage`.
    ActualMainVoltage,
    /// `actual_robot_voltage`.
    ActualRobotVoltage,
    /// `actual_robot_current`.
    ActualRobotCurrent,
    /// `actual_joint_voltage`.
    ActualJointVoltage,
    /// `actual_digital_output_bits`.
    ActualDigitalOutputBits,
    /// `actual_configurable_digital_output_bits`.
    ActualConfigurableDigitalOutputBits,
    /// `runtime_state`.
    RuntimeState,
    /// `elbow_position`.
    ElbowPosition,
    /// `elbow_velocity`.
    ElbowVelocity,
    /// `robot_status_bits`.
    RobotStatusBits,
    /// `safety_status_bits`.
    SafetyStatusBits,
    /// `analog_io_types`.
    AnalogIoTypes,
    /// `standard_analog_input0`.
    StandardAnalogInput0,
    /// `standard_analog_input1`.
    StandardAnalogInput1,
    /// `standard_analog_output0`.
    StandardAnalogOutput0,
    /// `standard_analog_output1`.
    StandardAnalogOutput1,
    /// `io_current`.
    IoCurrent,
    /// `output_bit_registers0_to_31`.
    OutputBitRegisters0To31,
    /// `output_bit_registers32_to_63`.
    OutputBitRegisters32To63,
    /// `actual_robot_energy_consumed`.
    ActualRobotEnergyConsumed,
    /// `actual_robot_braking_energy_dissipated`.
    ActualRobotBrakingEnergyDissipated,
    /// `encoder0_raw`.
    Encoder0Raw,
    /// `encoder1_raw`.
    Encoder1Raw,
    /// `euromap67_input_bits`.
    Euromap67InputBits,
    /// `euromap67_output_bits`.
    Euromap67OutputBits,
    /// `euromap67_24V_voltage`.
    Euromap67V24Voltage,
    /// `euromap67_24V_current`.
    Euromap67V24Current,
    /// `tool_mode`.
    ToolMode,
    /// `tool_analog_input_types`.
    ToolAnalogInputTypes,
    /// `tool_analog_input0`.
    ToolAnalogInput0,
    /// `tool_analog_input1`.
    ToolAnalogInput1,
    /// `tool_output_voltage`.
    ToolOutputVoltage,
    /// `tool_output_current`.
    ToolOutputCurrent,
    /// `tool_temperature`.
    ToolTemperature,
    /// `tool_output_mode`.
    ToolOutputMode,
    /// `tool_digital_output0_mode`.
    ToolDigitalOutput0Mode,
    /// `tool_digital_output1_mode`.
    ToolDigitalOutput1Mode,
    /// `tcp_force_scalar`.
    TcpForceScalar,
    /// `joint_position_deviation_ratio`.
    JointPositionDeviationRatio,
    /// `collision_detection_ratio`.
    CollisionDetectionRatio,
    /// `ft_raw_wrench`.
    FtRawWrench,
    /// `wrench_calc_from_currents`.
    WrenchCalcFromCurrents,
    /// `payload`.
    Payload,
    /// `payload_cog`.
    PayloadCog,
    /// `payload_inertia`.
    PayloadInertia,
    /// `script_control_line`.
    ScriptControlLine,
    /// `time_scale_source`.
    TimeScaleSource,
    /// `target_gravity`.
    TargetGravity,
    /// `target_base_acceleration`.
    TargetBaseAcceleration,
    /// `control_step`.
    ControlStep,
    /// `target_base_wrench`.
    TargetBaseWrench,
    /// `speed_slider_mask`.
    SpeedSliderMask,
    /// `speed_slider_fraction`.
    SpeedSliderFraction,
    /// `standard_digital_output_mask`.
    StandardDigitalOutputMask,
    /// `standard_digital_output`.
    StandardDigitalOutput,
    /// `configurable_digital_output_mask`.
    ConfigurableDigitalOutputMask,
    /// `configurable_digital_output`.
    ConfigurableDigitalOutput,
    /// `standard_analog_output_mask`.
    StandardAnalogOutputMask,
    /// `standard_analog_output_type`.
    StandardAnalogOutputType,
    /// `standard_analog_output_0`.
    StandardAnalogOutputInput0,
    /// `standard_analog_output_1`.
    StandardAnalogOutputInput1,
    /// `external_force_torque`.
    ExternalForceTorque,
    /// `tool_digital_output_mask`.
    ToolDigitalOutputMask,
    /// `tool_digital_output`.
    ToolDigitalOutput,
    /// `input_bit_registers0_to_31`.
    InputBitRegisters0To31,
    /// `input_bit_registers32_to_63`.
    InputBitRegisters32To63,
}

/// Name, variable, type, direction.
const NAMED: &[(&str, Named, DataType, Direction)] = &[
    (
        "timestamp",
        Named::Timestamp,
        DataType::Double,
        Direction::Output,
    ),
    (
        "target_q",
        Named::TargetQ,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "target_qd",
        Named::TargetQd,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "target_qdd",
        Named::TargetQdd,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "target_current",
        Named::TargetCurrent,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "target_moment",
        Named::TargetMoment,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_q",
        Named::ActualQ,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_qd",
        Named::ActualQd,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_current",
        Named::ActualCurrent,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_current_window",
        Named::ActualCurrentWindow,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_current_as_torque",
        Named::ActualCurrentAsTorque,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "joint_control_output",
        Named::JointControlOutput,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_TCP_pose",
        Named::ActualTcpPose,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_TCP_speed",
        Named::ActualTcpSpeed,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_TCP_force",
        Named::ActualTcpForce,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "target_TCP_pose",
        Named::TargetTcpPose,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "target_TCP_speed",
        Named::TargetTcpSpeed,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "tcp_offset",
        Named::TcpOffset,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_TCP_acceleration",
        Named::ActualTcpAcceleration,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "target_TCP_acceleration",
        Named::TargetTcpAcceleration,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_digital_input_bits",
        Named::ActualDigitalInputBits,
        DataType::Uint64,
        Direction::Output,
    ),
    (
        "actual_configurable_digital_input_bits",
        Named::ActualConfigurableDigitalInputBits,
        DataType::Uint64,
        Direction::Output,
    ),
    (
        "joint_temperatures",
        Named::JointTemperatures,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_execution_time",
        Named::ActualExecutionTime,
        DataType::Double,
        Direction::Output,
    ),
    (
        "target_execution_time",
        Named::TargetExecutionTime,
        DataType::Double,
        Direction::Output,
    ),
    (
        "robot_mode",
        Named::RobotMode,
        DataType::Int32,
        Direction::Output,
    ),
    (
        "joint_mode",
        Named::JointMode,
        DataType::Vector6Int32,
        Direction::Output,
    ),
    (
        "safety_mode",
        Named::SafetyMode,
        DataType::Int32,
        Direction::Output,
    ),
    (
        "safety_status",
        Named::SafetyStatus,
        DataType::Int32,
        Direction::Output,
    ),
    (
        "actual_tool_accelerometer",
        Named::ActualToolAccelerometer,
        DataType::Vector3d,
        Direction::Output,
    ),
    (
        "speed_scaling",
        Named::SpeedScaling,
        DataType::Double,
        Direction::Output,
    ),
    (
        "target_speed_fraction",
        Named::TargetSpeedFraction,
        DataType::Double,
        Direction::Output,
    ),
    (
        "actual_momentum",
        Named::ActualMomentum,
        DataType::Double,
        Direction::Output,
    ),
    (
        "actual_main_voltage",
        Named::ActualMainVoltage,
        DataType::Double,
        Direction::Output,
    ),
    (
        "actual_robot_voltage",
        Named::ActualRobotVoltage,
        DataType::Double,
        Direction::Output,
    ),
    (
        "actual_robot_current",
        Named::ActualRobotCurrent,
        DataType::Double,
        Direction::Output,
    ),
    (
        "actual_joint_voltage",
        Named::ActualJointVoltage,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "actual_digital_output_bits",
        Named::ActualDigitalOutputBits,
        DataType::Uint64,
        Direction::Output,
    ),
    (
        "actual_configurable_digital_output_bits",
        Named::ActualConfigurableDigitalOutputBits,
        DataType::Uint64,
        Direction::Output,
    ),
    (
        "runtime_state",
        Named::RuntimeState,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "elbow_position",
        Named::ElbowPosition,
        DataType::Vector3d,
        Direction::Output,
    ),
    (
        "elbow_velocity",
        Named::ElbowVelocity,
        DataType::Vector3d,
        Direction::Output,
    ),
    (
        "robot_status_bits",
        Named::RobotStatusBits,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "safety_status_bits",
        Named::SafetyStatusBits,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "analog_io_types",
        Named::AnalogIoTypes,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "standard_analog_input0",
        Named::StandardAnalogInput0,
        DataType::Double,
        Direction::Output,
    ),
    (
        "standard_analog_input1",
        Named::StandardAnalogInput1,
        DataType::Double,
        Direction::Output,
    ),
    (
        "standard_analog_output0",
        Named::StandardAnalogOutput0,
        DataType::Double,
        Direction::Output,
    ),
    (
        "standard_analog_output1",
        Named::StandardAnalogOutput1,
        DataType::Double,
        Direction::Output,
    ),
    (
        "io_current",
        Named::IoCurrent,
        DataType::Double,
        Direction::Output,
    ),
    (
        "output_bit_registers0_to_31",
        Named::OutputBitRegisters0To31,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "output_bit_registers32_to_63",
        Named::OutputBitRegisters32To63,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "actual_robot_energy_consumed",
        Named::ActualRobotEnergyConsumed,
        DataType::Double,
        Direction::Output,
    ),
    (
        "actual_robot_braking_energy_dissipated",
        Named::ActualRobotBrakingEnergyDissipated,
        DataType::Double,
        Direction::Output,
    ),
    (
        "encoder0_raw",
        Named::Encoder0Raw,
        DataType::Int32,
        Direction::Output,
    ),
    (
        "encoder1_raw",
        Named::Encoder1Raw,
        DataType::Int32,
        Direction::Output,
    ),
    (
        "euromap67_input_bits",
        Named::Euromap67InputBits,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "euromap67_output_bits",
        Named::Euromap67OutputBits,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "euromap67_24V_voltage",
        Named::Euromap67V24Voltage,
        DataType::Double,
        Direction::Output,
    ),
    (
        "euromap67_24V_current",
        Named::Euromap67V24Current,
        DataType::Double,
        Direction::Output,
    ),
    (
        "tool_mode",
        Named::ToolMode,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "tool_analog_input_types",
        Named::ToolAnalogInputTypes,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "tool_analog_input0",
        Named::ToolAnalogInput0,
        DataType::Double,
        Direction::Output,
    ),
    (
        "tool_analog_input1",
        Named::ToolAnalogInput1,
        DataType::Double,
        Direction::Output,
    ),
    (
        "tool_output_voltage",
        Named::ToolOutputVoltage,
        DataType::Int32,
        Direction::Output,
    ),
    (
        "tool_output_current",
        Named::ToolOutputCurrent,
        DataType::Double,
        Direction::Output,
    ),
    (
        "tool_temperature",
        Named::ToolTemperature,
        DataType::Double,
        Direction::Output,
    ),
    (
        "tool_output_mode",
        Named::ToolOutputMode,
        DataType::Uint8,
        Direction::Output,
    ),
    (
        "tool_digital_output0_mode",
        Named::ToolDigitalOutput0Mode,
        DataType::Uint8,
        Direction::Output,
    ),
    (
        "tool_digital_output1_mode",
        Named::ToolDigitalOutput1Mode,
        DataType::Uint8,
        Direction::Output,
    ),
    (
        "tcp_force_scalar",
        Named::TcpForceScalar,
        DataType::Double,
        Direction::Output,
    ),
    (
        "joint_position_deviation_ratio",
        Named::JointPositionDeviationRatio,
        DataType::Double,
        Direction::Output,
    ),
    (
        "collision_detection_ratio",
        Named::CollisionDetectionRatio,
        DataType::Double,
        Direction::Output,
    ),
    (
        "ft_raw_wrench",
        Named::FtRawWrench,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "wrench_calc_from_currents",
        Named::WrenchCalcFromCurrents,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "payload",
        Named::Payload,
        DataType::Double,
        Direction::Output,
    ),
    (
        "payload_cog",
        Named::PayloadCog,
        DataType::Vector3d,
        Direction::Output,
    ),
    (
        "payload_inertia",
        Named::PayloadInertia,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "script_control_line",
        Named::ScriptControlLine,
        DataType::Uint32,
        Direction::Output,
    ),
    (
        "time_scale_source",
        Named::TimeScaleSource,
        DataType::Int32,
        Direction::Output,
    ),
    (
        "target_gravity",
        Named::TargetGravity,
        DataType::Vector3d,
        Direction::Output,
    ),
    (
        "target_base_acceleration",
        Named::TargetBaseAcceleration,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "control_step",
        Named::ControlStep,
        DataType::Uint64,
        Direction::Output,
    ),
    (
        "target_base_wrench",
        Named::TargetBaseWrench,
        DataType::Vector6d,
        Direction::Output,
    ),
    (
        "speed_slider_mask",
        Named::SpeedSliderMask,
        DataType::Uint32,
        Direction::Input,
    ),
    (
        "speed_slider_fraction",
        Named::SpeedSliderFraction,
        DataType::Double,
        Direction::Input,
    ),
    (
        "standard_digital_output_mask",
        Named::StandardDigitalOutputMask,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "standard_digital_output",
        Named::StandardDigitalOutput,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "configurable_digital_output_mask",
        Named::ConfigurableDigitalOutputMask,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "configurable_digital_output",
        Named::ConfigurableDigitalOutput,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "standard_analog_output_mask",
        Named::StandardAnalogOutputMask,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "standard_analog_output_type",
        Named::StandardAnalogOutputType,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "standard_analog_output_0",
        Named::StandardAnalogOutputInput0,
        DataType::Double,
        Direction::Input,
    ),
    (
        "standard_analog_output_1",
        Named::StandardAnalogOutputInput1,
        DataType::Double,
        Direction::Input,
    ),
    (
        "external_force_torque",
        Named::ExternalForceTorque,
        DataType::Vector6d,
        Direction::Input,
    ),
    (
        "tool_digital_output_mask",
        Named::ToolDigitalOutputMask,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "tool_digital_output",
        Named::ToolDigitalOutput,
        DataType::Uint8,
        Direction::Input,
    ),
    (
        "input_bit_registers0_to_31",
        Named::InputBitRegisters0To31,
        DataType::Uint32,
        Direction::Both,
    ),
    (
        "input_bit_registers32_to_63",
        Named::InputBitRegisters32To63,
        DataType::Uint32,
        Direction::Both,
    ),
];

/// Registers of each indexed family.
pub const REGISTERS: u8 = 48;
/// The first bit register with a name of its own (below it, bits come in 32-bit words).
pub const FIRST_BIT_REGISTER: u8 = 64;
/// The last bit register.
pub const LAST_BIT_REGISTER: u8 = 127;

/// A variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Var {
    /// A variable with a name of its own.
    Named(Named),
    /// `output_int_register_N`.
    OutputIntRegister(u8),
    /// `output_double_register_N`.
    OutputDoubleRegister(u8),
    /// `output_bit_register_N` (64 to 127).
    OutputBitRegister(u8),
    /// `input_int_register_N`.
    InputIntRegister(u8),
    /// `input_double_register_N`.
    InputDoubleRegister(u8),
    /// `input_bit_register_N` (64 to 127).
    InputBitRegister(u8),
}

fn index(name: &str, prefix: &str, range: core::ops::RangeInclusive<u8>) -> Option<u8> {
    let digits = name.strip_prefix(prefix)?;
    if digits.is_empty() || digits.len() > 3 || (digits.len() > 1 && digits.starts_with('0')) {
        return None;
    }
    let n: u8 = digits.parse().ok()?;
    range.contains(&n).then_some(n)
}

impl Var {
    /// The variable of a name (`None`: the controller answers `NOT_FOUND`).
    pub fn parse(name: &str) -> Option<Self> {
        if let Some((_, v, _, _)) = NAMED.iter().find(|(n, ..)| *n == name) {
            return Some(Self::Named(*v));
        }
        let regs = 0..=REGISTERS - 1;
        let bits = FIRST_BIT_REGISTER..=LAST_BIT_REGISTER;
        index(name, "output_int_register_", regs.clone())
            .map(Self::OutputIntRegister)
            .or_else(|| {
                index(name, "output_double_register_", regs.clone()).map(Self::OutputDoubleRegister)
            })
            .or_else(|| {
                index(name, "output_bit_register_", bits.clone()).map(Self::OutputBitRegister)
            })
            .or_else(|| {
                index(name, "input_int_register_", regs.clone()).map(Self::InputIntRegister)
            })
            .or_else(|| {
                index(name, "input_double_register_", regs.clone()).map(Self::InputDoubleRegister)
            })
            .or_else(|| {
                index(name, "input_bit_register_", bits.clone()).map(Self::InputBitRegister)
            })
    }

    fn named(v: Named) -> &'static (&'static str, Named, DataType, Direction) {
        // Every variant is in the table (a unit test checks it).
        NAMED.iter().find(|(_, n, ..)| *n == v).unwrap_or(&NAMED[0])
    }

    /// Its type.
    pub fn data_type(self) -> DataType {
        match self {
            Self::Named(v) => Self::named(v).2,
            Self::OutputIntRegister(_) | Self::InputIntRegister(_) => DataType::Int32,
            Self::OutputDoubleRegister(_) | Self::InputDoubleRegister(_) => DataType::Double,
            Self::OutputBitRegister(_) | Self::InputBitRegister(_) => DataType::Bool,
        }
    }

    /// Its direction.
    pub fn direction(self) -> Direction {
        match self {
            Self::Named(v) => Self::named(v).3,
            Self::OutputIntRegister(_)
            | Self::OutputDoubleRegister(_)
            | Self::OutputBitRegister(_) => Direction::Output,
            Self::InputIntRegister(_)
            | Self::InputDoubleRegister(_)
            | Self::InputBitRegister(_) => Direction::Both,
        }
    }

    /// The name of a variable with a name of its own.
    pub fn name_of(v: Named) -> &'static str {
        Self::named(v).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_with_their_types() {
        for (name, v, t, _) in NAMED {
            assert_eq!(Var::parse(name), Some(Var::Named(*v)), "{name}");
            assert_eq!(Var::parse(name).unwrap().data_type(), *t);
            assert_eq!(Var::name_of(*v), *name);
        }
        assert_eq!(
            Var::parse("actual_q").unwrap().data_type(),
            DataType::Vector6d
        );
        assert_eq!(
            Var::parse("joint_mode").unwrap().data_type(),
            DataType::Vector6Int32
        );
        assert_eq!(
            Var::parse("output_int_register_47"),
            Some(Var::OutputIntRegister(47))
        );
        assert_eq!(Var::parse("output_int_register_48"), None);
        assert_eq!(Var::parse("output_int_register_07"), None);
        assert_eq!(
            Var::parse("input_bit_register_64"),
            Some(Var::InputBitRegister(64))
        );
        assert_eq!(Var::parse("input_bit_register_63"), None);
        assert_eq!(
            Var::parse("input_double_register_24").unwrap().direction(),
            Direction::Both
        );
        assert!(!Var::parse("actual_q").unwrap().direction().writable());
        assert!(
            Var::parse("standard_digital_output")
                .unwrap()
                .direction()
                .writable()
        );
        assert_eq!(Var::parse("no_such_thing"), None);
        assert_eq!(Var::parse(""), None);
    }
}
