//! Universal Robots' real-time client interface (the "Matlab" interface): TCP port 30003
//! (which also takes URScript) and 30013 (read only). The controller sends its state to every
//! client on these ports each cycle, 500 Hz on e-Series and 125 Hz on CB3, unasked (RL's
//! `UniversalRobotsRealtime`).
//!
//! A message is a big-endian `i32` with the message's length in bytes (itself included), then
//! that many bytes less four of big-endian `f64`s. Every field is a double, integers and bit
//! sets included: the digital inputs' and outputs' bits arrive as the double of their value
//! (5.0: bits 0 and 2). The layout grew at the end over the controller's versions; the lengths
//! this codec reads are those of CB3 (PolyScope 3.0 and later) and e-Series (5.x), as UR's
//! client-interface tables ("RealTime 5.9", 5.10, 3.x) and RL's reader agree:
//!
//! | length | adds (in doubles after the length) | versions |
//! |---|---|---|
//! | 1044 | time (0), q/qd/qdd target (1, 7, 13), I and M target (19, 25), q/qd/I actual (31, 37, 43), I control (49), tool vector actual (55), TCP speed actual (61), TCP force (67), tool vector target (73), TCP speed target (79), digital input bits (85), motor temperatures (86), controller timer (92), test value (93), robot mode (94), joint modes (95), safety mode (101), 6 reserved, tool accelerometer (108), 6 reserved, speed scaling (117), linear momentum norm (118), 2 reserved, V main (121), V robot (122), I robot (123), V actual (124) | 3.0–3.1 |
//! | 1060 | digital outputs (130), program state (131) | 3.2–3.4 |
//! | 1108 | elbow position (132), elbow velocity (135) | 3.5–3.9 |
//! | 1116 | safety status (138) | 3.10– |
//! | 1140 | 3 reserved | 5.0– |
//! | 1220 | payload mass (142), payload centre of gravity (143), payload inertia (146) | 5.9– |
//!
//! A longer message of a future version is read up to 1220 bytes only if its length is one of
//! these: any other length is [`RealtimeError::UnknownLength`] (the stream cannot be read
//! further, as the controller gives no other framing). CB2's layouts (756, 764 and 812 bytes,
//! PolyScope 1.x) place the fields differently and are not read.
//!
//! Decoding never panics and allocates nothing; it returns a typed [`RealtimeError`] saying
//! what and where.

use core::fmt;

/// The real-time interface's port (takes URScript too).
pub const PORT: u16 = 30003;
/// The read-only real-time interface's port (PolyScope 5).
pub const READ_ONLY_PORT: u16 = 30013;
/// The lengths of the layouts read, bytes.
pub const LENGTHS: [usize; 6] = [1044, 1060, 1108, 1116, 1140, 1220];
/// The longest message, bytes.
pub const MAX_LEN: usize = 1220;
/// Doubles of the longest message.
const DOUBLES: usize = (MAX_LEN - 4) / 8;

/// Where each field starts, in doubles after the length.
mod at {
    pub const TIME: usize = 0;
    pub const Q_TARGET: usize = 1;
    pub const QD_TARGET: usize = 7;
    pub const QDD_TARGET: usize = 13;
    pub const I_TARGET: usize = 19;
    pub const M_TARGET: usize = 25;
    pub const Q_ACTUAL: usize = 31;
    pub const QD_ACTUAL: usize = 37;
    pub const I_ACTUAL: usize = 43;
    pub const I_CONTROL: usize = 49;
    pub const TOOL_VECTOR_ACTUAL: usize = 55;
    pub const TCP_SPEED_ACTUAL: usize = 61;
    pub const TCP_FORCE: usize = 67;
    pub const TOOL_VECTOR_TARGET: usize = 73;
    pub const TCP_SPEED_TARGET: usize = 79;
    pub const DIGITAL_INPUT_BITS: usize = 85;
    pub const MOTOR_TEMPERATURES: usize = 86;
    pub const CONTROLLER_TIMER: usize = 92;
    pub const TEST_VALUE: usize = 93;
    pub const ROBOT_MODE: usize = 94;
    pub const JOINT_MODES: usize = 95;
    pub const SAFETY_MODE: usize = 101;
    pub const TOOL_ACCELEROMETER: usize = 108;
    pub const SPEED_SCALING: usize = 117;
    pub const LINEAR_MOMENTUM_NORM: usize = 118;
    pub const V_MAIN: usize = 121;
    pub const V_ROBOT: usize = 122;
    pub const I_ROBOT: usize = 123;
    pub const V_ACTUAL: usize = 124;
    pub const DIGITAL_OUTPUTS: usize = 130;
    pub const PROGRAM_STATE: usize = 131;
    pub const ELBOW_POSITION: usize = 132;
    pub const ELBOW_VELOCITY: usize = 135;
    pub const SAFETY_STATUS: usize = 138;
    pub const PAYLOAD_MASS: usize = 142;
    pub const PAYLOAD_COG: usize = 143;
    pub const PAYLOAD_INERTIA: usize = 146;
}

/// Why bytes are not a real-time message.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RealtimeError {
    /// The length field names a layout this codec does not know.
    UnknownLength(u32),
    /// Fewer bytes than the length field says.
    Truncated {
        /// The message's length.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// A field that holds an integer (a mode, a bit set) holds something else.
    NotAnInteger {
        /// The field.
        field: &'static str,
        /// Its byte offset in the message.
        offset: usize,
        /// The value found.
        value: f64,
    },
    /// An encoder's buffer is shorter than the message.
    BufferTooSmall {
        /// The message's length.
        needed: usize,
        /// The buffer's.
        got: usize,
    },
}

impl fmt::Display for RealtimeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnknownLength(n) => write!(
                f,
                "UR real-time message of {n} bytes: no known layout (1044, 1060, 1108, 1116, 1140 or 1220 bytes; CB2's are not read)"
            ),
            Self::Truncated { expected, got } => write!(
                f,
                "UR real-time message truncated: {got} of its {expected} bytes"
            ),
            Self::NotAnInteger {
                field,
                offset,
                value,
            } => write!(
                f,
                "UR real-time message: {field} (byte {offset}) is {value}, not an integer in range"
            ),
            Self::BufferTooSmall { needed, got } => write!(
                f,
                "UR real-time message of {needed} bytes does not fit a buffer of {got}"
            ),
        }
    }
}

impl core::error::Error for RealtimeError {}

/// The controller's state as one real-time message has it. Fields a shorter layout lacks
/// stay zero; [`length`](Self::length) says which layout it was.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RealtimeState {
    /// The message's length, bytes (one of [`LENGTHS`]).
    pub length: usize,
    /// Time since the controller started, s.
    pub time: f64,
    /// Target joint positions, rad.
    pub q_target: [f64; 6],
    /// Target joint velocities, rad/s.
    pub qd_target: [f64; 6],
    /// Target joint accelerations, rad/s².
    pub qdd_target: [f64; 6],
    /// Target joint currents, A.
    pub i_target: [f64; 6],
    /// Target joint torques, N·m.
    pub m_target: [f64; 6],
    /// Measured joint positions, rad.
    pub q_actual: [f64; 6],
    /// Measured joint velocities, rad/s.
    pub qd_actual: [f64; 6],
    /// Measured joint currents, A.
    pub i_actual: [f64; 6],
    /// Joint control currents, A.
    pub i_control: [f64; 6],
    /// The tool's pose: x, y, z (m) and a rotation vector (rad).
    pub tool_vector_actual: [f64; 6],
    /// The tool's measured speed (m/s, rad/s).
    pub tcp_speed_actual: [f64; 6],
    /// The generalised force at the tool (N, N·m).
    pub tcp_force: [f64; 6],
    /// The tool's target pose.
    pub tool_vector_target: [f64; 6],
    /// The tool's target speed.
    pub tcp_speed_target: [f64; 6],
    /// Digital inputs: standard 0–7, configurable 8–15, tool 16–17.
    pub digital_input_bits: u64,
    /// Joint temperatures, °C.
    pub motor_temperatures: [f64; 6],
    /// The controller's real-time thread's execution time, s.
    pub controller_timer: f64,
    /// UR's own test value.
    pub test_value: f64,
    /// The robot mode (−1 no controller … 7 running, 8 updating firmware).
    pub robot_mode: i32,
    /// The joints' control modes (253 running, 239 power off, 255 idle …).
    pub joint_modes: [i32; 6],
    /// The safety mode (1 normal, 3 protective stop, 7 robot emergency stop …).
    pub safety_mode: i32,
    /// The tool's accelerometer, m/s².
    pub tool_accelerometer: [f64; 3],
    /// The speed scaling in effect (the slider and the trajectory limiter), 0–1.
    pub speed_scaling: f64,
    /// The norm of the arm's linear momentum, kg·m/s.
    pub linear_momentum_norm: f64,
    /// The main voltage, V.
    pub v_main: f64,
    /// The robot voltage (48 V), V.
    pub v_robot: f64,
    /// The robot current, A.
    pub i_robot: f64,
    /// The joints' voltages, V.
    pub v_actual: [f64; 6],
    /// Digital outputs, numbered as the inputs (from 1060 bytes).
    pub digital_outputs: u64,
    /// The program state: 0 stopping, 1 stopped, 2 playing, 3 pausing, 4 paused, 5 resuming
    /// (from 1060 bytes).
    pub program_state: i32,
    /// The elbow's position, m (from 1108 bytes).
    pub elbow_position: [f64; 3],
    /// The elbow's velocity, m/s (from 1108 bytes).
    pub elbow_velocity: [f64; 3],
    /// The safety status, the safety mode's numbers and 12 (automatic-mode safeguard stop),
    /// 13 (three-position enabling stop) (from 1116 bytes).
    pub safety_status: i32,
    /// The payload's mass, kg (from 1220 bytes).
    pub payload_mass: f64,
    /// The payload's centre of gravity, m (from 1220 bytes).
    pub payload_cog: [f64; 3],
    /// The payload's inertia (Ixx, Iyy, Izz, Ixy, Ixz, Iyz), kg·m² (from 1220 bytes).
    pub payload_inertia: [f64; 6],
}

/// The length of the message at the start of `bytes`: `Ok(None)` until its four length
/// bytes are there; an unknown length is an error.
pub fn message_length(bytes: &[u8]) -> Result<Option<usize>, RealtimeError> {
    let Some(head) = bytes.get(..4) else {
        return Ok(None);
    };
    let n = u32::from_be_bytes([head[0], head[1], head[2], head[3]]);
    match usize::try_from(n) {
        Ok(len) if LENGTHS.contains(&len) => Ok(Some(len)),
        _ => Err(RealtimeError::UnknownLength(n)),
    }
}

/// The first complete message in `bytes` (the next starts after its length); `Ok(None)`
/// until it is all there.
pub fn split(bytes: &[u8]) -> Result<Option<&[u8]>, RealtimeError> {
    match message_length(bytes)? {
        Some(len) => Ok(bytes.get(..len)),
        None => Ok(None),
    }
}

fn six(d: &[f64; DOUBLES], at: usize) -> [f64; 6] {
    [d[at], d[at + 1], d[at + 2], d[at + 3], d[at + 4], d[at + 5]]
}

fn three(d: &[f64; DOUBLES], at: usize) -> [f64; 3] {
    [d[at], d[at + 1], d[at + 2]]
}

fn put(d: &mut [f64; DOUBLES], at: usize, values: &[f64]) {
    d[at..at + values.len()].copy_from_slice(values);
}

/// A double that holds an integer in `min..=max`.
fn integer(
    d: &[f64; DOUBLES],
    at: usize,
    field: &'static str,
    min: f64,
    max: f64,
) -> Result<f64, RealtimeError> {
    let value = d[at];
    // In range (so finite, and within i64's), a double is an integer when the truncating cast
    // gives it back (`f64::fract` is not in core).
    if (min..=max).contains(&value) && value as i64 as f64 == value {
        Ok(value)
    } else {
        Err(RealtimeError::NotAnInteger {
            field,
            offset: 4 + 8 * at,
            value,
        })
    }
}

fn mode(d: &[f64; DOUBLES], at: usize, field: &'static str) -> Result<i32, RealtimeError> {
    // Exact: every integer of i32's range is a double.
    integer(d, at, field, f64::from(i32::MIN), f64::from(i32::MAX)).map(|v| v as i32)
}

fn bits(d: &[f64; DOUBLES], at: usize, field: &'static str) -> Result<u64, RealtimeError> {
    // Up to 2^53, where doubles stop holding every integer (UR's bit sets use 18 bits).
    integer(d, at, field, 0.0, 9_007_199_254_740_992.0).map(|v| v as u64)
}

impl RealtimeState {
    /// Decodes one whole message (its length field first).
    pub fn decode(message: &[u8]) -> Result<Self, RealtimeError> {
        let len = message_length(message)?.ok_or(RealtimeError::Truncated {
            expected: 4,
            got: message.len(),
        })?;
        if message.len() < len {
            return Err(RealtimeError::Truncated {
                expected: len,
                got: message.len(),
            });
        }
        let n = (len - 4) / 8;
        let mut d = [0.0f64; DOUBLES];
        for (k, chunk) in message[4..len].chunks_exact(8).enumerate() {
            let mut b = [0u8; 8];
            b.copy_from_slice(chunk);
            d[k] = f64::from_be_bytes(b);
        }
        let mut s = Self {
            length: len,
            time: d[at::TIME],
            q_target: six(&d, at::Q_TARGET),
            qd_target: six(&d, at::QD_TARGET),
            qdd_target: six(&d, at::QDD_TARGET),
            i_target: six(&d, at::I_TARGET),
            m_target: six(&d, at::M_TARGET),
            q_actual: six(&d, at::Q_ACTUAL),
            qd_actual: six(&d, at::QD_ACTUAL),
            i_actual: six(&d, at::I_ACTUAL),
            i_control: six(&d, at::I_CONTROL),
            tool_vector_actual: six(&d, at::TOOL_VECTOR_ACTUAL),
            tcp_speed_actual: six(&d, at::TCP_SPEED_ACTUAL),
            tcp_force: six(&d, at::TCP_FORCE),
            tool_vector_target: six(&d, at::TOOL_VECTOR_TARGET),
            tcp_speed_target: six(&d, at::TCP_SPEED_TARGET),
            digital_input_bits: bits(&d, at::DIGITAL_INPUT_BITS, "digital input bits")?,
            motor_temperatures: six(&d, at::MOTOR_TEMPERATURES),
            controller_timer: d[at::CONTROLLER_TIMER],
            test_value: d[at::TEST_VALUE],
            robot_mode: mode(&d, at::ROBOT_MODE, "robot mode")?,
            joint_modes: [0; 6],
            safety_mode: mode(&d, at::SAFETY_MODE, "safety mode")?,
            tool_accelerometer: three(&d, at::TOOL_ACCELEROMETER),
            speed_scaling: d[at::SPEED_SCALING],
            linear_momentum_norm: d[at::LINEAR_MOMENTUM_NORM],
            v_main: d[at::V_MAIN],
            v_robot: d[at::V_ROBOT],
            i_robot: d[at::I_ROBOT],
            v_actual: six(&d, at::V_ACTUAL),
            ..Self::default()
        };
        for (k, m) in s.joint_modes.iter_mut().enumerate() {
            *m = mode(&d, at::JOINT_MODES + k, "joint mode")?;
        }
        if n > at::PROGRAM_STATE {
            s.digital_outputs = bits(&d, at::DIGITAL_OUTPUTS, "digital outputs")?;
            s.program_state = mode(&d, at::PROGRAM_STATE, "program state")?;
        }
        if n > at::ELBOW_VELOCITY + 2 {
            s.elbow_position = three(&d, at::ELBOW_POSITION);
            s.elbow_velocity = three(&d, at::ELBOW_VELOCITY);
        }
        if n > at::SAFETY_STATUS {
            s.safety_status = mode(&d, at::SAFETY_STATUS, "safety status")?;
        }
        if n > at::PAYLOAD_INERTIA + 5 {
            s.payload_mass = d[at::PAYLOAD_MASS];
            s.payload_cog = three(&d, at::PAYLOAD_COG);
            s.payload_inertia = six(&d, at::PAYLOAD_INERTIA);
        }
        Ok(s)
    }

    /// Encodes the state as a message of `length` bytes (one of [`LENGTHS`]) into `out`;
    /// returns the length. Fields the layout lacks are left out, reserved ones are zero.
    pub fn encode(&self, length: usize, out: &mut [u8]) -> Result<usize, RealtimeError> {
        if !LENGTHS.contains(&length) {
            return Err(RealtimeError::UnknownLength(
                u32::try_from(length).unwrap_or(u32::MAX),
            ));
        }
        if out.len() < length {
            return Err(RealtimeError::BufferTooSmall {
                needed: length,
                got: out.len(),
            });
        }
        let mut d = [0.0f64; DOUBLES];
        d[at::TIME] = self.time;
        put(&mut d, at::Q_TARGET, &self.q_target);
        put(&mut d, at::QD_TARGET, &self.qd_target);
        put(&mut d, at::QDD_TARGET, &self.qdd_target);
        put(&mut d, at::I_TARGET, &self.i_target);
        put(&mut d, at::M_TARGET, &self.m_target);
        put(&mut d, at::Q_ACTUAL, &self.q_actual);
        put(&mut d, at::QD_ACTUAL, &self.qd_actual);
        put(&mut d, at::I_ACTUAL, &self.i_actual);
        put(&mut d, at::I_CONTROL, &self.i_control);
        put(&mut d, at::TOOL_VECTOR_ACTUAL, &self.tool_vector_actual);
        put(&mut d, at::TCP_SPEED_ACTUAL, &self.tcp_speed_actual);
        put(&mut d, at::TCP_FORCE, &self.tcp_force);
        put(&mut d, at::TOOL_VECTOR_TARGET, &self.tool_vector_target);
        put(&mut d, at::TCP_SPEED_TARGET, &self.tcp_speed_target);
        d[at::DIGITAL_INPUT_BITS] = self.digital_input_bits as f64;
        put(&mut d, at::MOTOR_TEMPERATURES, &self.motor_temperatures);
        d[at::CONTROLLER_TIMER] = self.controller_timer;
        d[at::TEST_VALUE] = self.test_value;
        d[at::ROBOT_MODE] = f64::from(self.robot_mode);
        for (k, m) in self.joint_modes.iter().enumerate() {
            d[at::JOINT_MODES + k] = f64::from(*m);
        }
        d[at::SAFETY_MODE] = f64::from(self.safety_mode);
        put(&mut d, at::TOOL_ACCELEROMETER, &self.tool_accelerometer);
        d[at::SPEED_SCALING] = self.speed_scaling;
        d[at::LINEAR_MOMENTUM_NORM] = self.linear_momentum_norm;
        d[at::V_MAIN] = self.v_main;
        d[at::V_ROBOT] = self.v_robot;
        d[at::I_ROBOT] = self.i_robot;
        put(&mut d, at::V_ACTUAL, &self.v_actual);
        d[at::DIGITAL_OUTPUTS] = self.digital_outputs as f64;
        d[at::PROGRAM_STATE] = f64::from(self.program_state);
        put(&mut d, at::ELBOW_POSITION, &self.elbow_position);
        put(&mut d, at::ELBOW_VELOCITY, &self.elbow_velocity);
        d[at::SAFETY_STATUS] = f64::from(self.safety_status);
        d[at::PAYLOAD_MASS] = self.payload_mass;
        put(&mut d, at::PAYLOAD_COG, &self.payload_cog);
        put(&mut d, at::PAYLOAD_INERTIA, &self.payload_inertia);
        // `length` is at most MAX_LEN: it fits u32.
        out[..4].copy_from_slice(&(length as u32).to_be_bytes());
        for (k, chunk) in out[4..length].chunks_exact_mut(8).enumerate() {
            chunk.copy_from_slice(&d[k].to_be_bytes());
        }
        Ok(length)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> RealtimeState {
        let mut s = RealtimeState {
            length: MAX_LEN,
            time: 12.5,
            digital_input_bits: 5,
            robot_mode: 7,
            joint_modes: [253; 6],
            safety_mode: 1,
            digital_outputs: 0x2_0001,
            program_state: 2,
            safety_status: 1,
            payload_mass: 1.5,
            ..RealtimeState::default()
        };
        for k in 0..6 {
            s.q_actual[k] = 0.1 * k as f64 - 1.0;
            s.tcp_force[k] = 2.0 * k as f64;
            s.payload_inertia[k] = 0.01 * k as f64;
        }
        s
    }

    #[test]
    fn every_layout_round_trips_what_it_carries() {
        let s = sample();
        let mut buf = [0u8; MAX_LEN];
        for len in LENGTHS {
            assert_eq!(s.encode(len, &mut buf), Ok(len));
            let d = RealtimeState::decode(&buf[..len]).unwrap();
            assert_eq!(d.length, len);
            assert_eq!(d.q_actual, s.q_actual);
            assert_eq!(d.tcp_force, s.tcp_force);
            assert_eq!(d.digital_input_bits, 5);
            assert_eq!(d.joint_modes, [253; 6]);
            assert_eq!(d.digital_outputs, if len >= 1060 { 0x2_0001 } else { 0 });
            assert_eq!(d.safety_status, if len >= 1116 { 1 } else { 0 });
            assert_eq!(d.payload_mass, if len >= 1220 { 1.5 } else { 0.0 });
            assert_eq!(d.payload_inertia[5], if len >= 1220 { 0.05 } else { 0.0 });
        }
        assert_eq!(RealtimeState::decode(&buf).unwrap(), s);
    }

    #[test]
    fn fields_sit_where_the_tables_put_them() {
        let mut buf = [0u8; MAX_LEN];
        sample().encode(MAX_LEN, &mut buf).unwrap();
        let at = |byte: usize| f64::from_be_bytes(buf[byte..byte + 8].try_into().unwrap());
        // Gnuplot columns of UR's table are 1-based doubles after the length.
        assert_eq!(at(4), 12.5); // time, column 1
        assert_eq!(at(4 + 8 * 31), -1.0); // q actual, columns 32–37
        assert_eq!(at(4 + 8 * 68), 2.0); // TCP force, columns 68–73 (second value)
        assert_eq!(at(4 + 8 * 85), 5.0); // digital input bits, column 86: the value as a double
        assert_eq!(at(4 + 8 * 94), 7.0); // robot mode, column 95
        assert_eq!(u32::from_be_bytes(buf[..4].try_into().unwrap()), 1220);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let mut buf = [0u8; MAX_LEN];
        sample().encode(1116, &mut buf).unwrap();
        assert_eq!(
            RealtimeState::decode(&buf[..1000]),
            Err(RealtimeError::Truncated {
                expected: 1116,
                got: 1000
            })
        );
        assert_eq!(split(&buf[..3]), Ok(None));
        assert_eq!(split(&buf[..1115]), Ok(None));
        assert_eq!(split(&buf[..1200]).unwrap().map(<[u8]>::len), Some(1116));
        buf[..4].copy_from_slice(&1000u32.to_be_bytes());
        assert_eq!(split(&buf), Err(RealtimeError::UnknownLength(1000)));
        buf[..4].copy_from_slice(&1116u32.to_be_bytes());
        buf[4 + 8 * 94..4 + 8 * 95].copy_from_slice(&7.5f64.to_be_bytes());
        let e = RealtimeState::decode(&buf).unwrap_err();
        assert_eq!(
            e,
            RealtimeError::NotAnInteger {
                field: "robot mode",
                offset: 756,
                value: 7.5
            }
        );
        let mut text = heapless::String::<128>::new();
        core::fmt::write(&mut text, format_args!("{e}")).unwrap();
        assert!(text.contains("robot mode (byte 756) is 7.5"), "{text}");
        buf[4 + 8 * 94..4 + 8 * 95].copy_from_slice(&f64::NAN.to_be_bytes());
        assert!(RealtimeState::decode(&buf).is_err());
        assert_eq!(
            sample().encode(1220, &mut [0u8; 100]),
            Err(RealtimeError::BufferTooSmall {
                needed: 1220,
                got: 100
            })
        );
        assert_eq!(
            sample().encode(1000, &mut buf),
            Err(RealtimeError::UnknownLength(1000))
        );
    }
}
