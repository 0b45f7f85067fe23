//! The Mitsubishi MELFA real-time external control packet (the H7 "MXT" packet): 196 bytes,
//! little-endian, exchanged over UDP once per 7.11 ms controller cycle.
//!
//! Layout and type codes from RL's `MitsubishiH7` driver, offsets checked with `offsetof` on a
//! build of it (see `shared/reference/mitsubishi-h7.md`):
//!
//! | off | field | off | field |
//! |---|---|---|---|
//! | 0 | command u16 | 58 | tCount u16 |
//! | 2 | sendType u16 | 60 | cCount u32 |
//! | 4 | recvType u16 | 64 | recvType1 u16, 66 reserve1 |
//! | 6 | reserve u16 | 68 | dat1 (40 bytes) |
//! | 8 | dat (40 bytes) | 108 | recvType2 u16, 110 reserve2 |
//! | 48 | sendIoType u16 | 112 | dat2 |
//! | 50 | recvIoType u16 | 152 | recvType3 u16, 154 reserve3 |
//! | 52, 54, 56 | bitTop, bitMask, ioData u16 | 156 | dat3 |

use core::fmt;

/// Size of one packet in bytes.
pub const PACKET_LEN: usize = 196;
/// Size of one data block (`dat`, `dat1`, `dat2`, `dat3`) in bytes.
pub const DATA_LEN: usize = 40;
/// Most axes a data block can carry (six robot axes and two additional axes).
pub const MAX_AXES: usize = 8;
/// The controller's cycle: 7.11 ms.
pub const CYCLE_US: u64 = 7110;

/// Byte offsets of the fields, from the reference table.
pub mod offset {
    /// `command`.
    pub const COMMAND: usize = 0;
    /// `sendType`.
    pub const SEND_TYPE: usize = 2;
    /// `recvType`.
    pub const RECV_TYPE: usize = 4;
    /// `reserve`.
    pub const RESERVE: usize = 6;
    /// `dat`.
    pub const DAT: usize = 8;
    /// `sendIoType`.
    pub const SEND_IO_TYPE: usize = 48;
    /// `recvIoType`.
    pub const RECV_IO_TYPE: usize = 50;
    /// `bitTop`.
    pub const BIT_TOP: usize = 52;
    /// `bitMask`.
    pub const BIT_MASK: usize = 54;
    /// `ioData`.
    pub const IO_DATA: usize = 56;
    /// `tCount`.
    pub const T_COUNT: usize = 58;
    /// `cCount`.
    pub const C_COUNT: usize = 60;
    /// `recvType1`.
    pub const RECV_TYPE1: usize = 64;
    /// `reserve1`.
    pub const RESERVE1: usize = 66;
    /// `dat1`.
    pub const DAT1: usize = 68;
    /// `recvType2`.
    pub const RECV_TYPE2: usize = 108;
    /// `reserve2`.
    pub const RESERVE2: usize = 110;
    /// `dat2`.
    pub const DAT2: usize = 112;
    /// `recvType3`.
    pub const RECV_TYPE3: usize = 152;
    /// `reserve3`.
    pub const RESERVE3: usize = 154;
    /// `dat3`.
    pub const DAT3: usize = 156;
}

/// What a packet asks the controller to do.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Command {
    /// 0: no command, only exchange state.
    #[default]
    Null,
    /// 1: move to the target in `dat`.
    Move,
    /// 255: end of the real-time session.
    End,
}

impl Command {
    /// The wire code.
    pub const fn code(self) -> u16 {
        match self {
            Command::Null => 0,
            Command::Move => 1,
            Command::End => 255,
        }
    }

    /// The command for a wire code.
    pub const fn from_code(code: u16) -> Option<Self> {
        match code {
            0 => Some(Command::Null),
            1 => Some(Command::Move),
            255 => Some(Command::End),
            _ => None,
        }
    }
}

/// The type of data in a data block (MELFA's `MXT_TYP_*`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MxtType {
    /// 0: no data.
    #[default]
    Null,
    /// 1: Cartesian pose (command).
    Pose,
    /// 2: joint positions (command).
    Joint,
    /// 3: motor pulses (command).
    Pulse,
    /// 4: pose after the controller's filter.
    PoseFiltered,
    /// 5: joints after the filter.
    JointFiltered,
    /// 6: pulses after the filter.
    PulseFiltered,
    /// 7: pose from encoder feedback.
    PoseFeedback,
    /// 8: joints from encoder feedback.
    JointFeedback,
    /// 9: pulses from encoder feedback.
    PulseFeedback,
    /// 10: current command in %.
    CurrentCommand,
    /// 11: current feedback in %.
    CurrentFeedback,
}

/// The shape of the data of one [`MxtType`] inside the 40-byte block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DataShape {
    /// Nothing.
    Null,
    /// 8×f32 pose + 2×u32 structure flags.
    Pose,
    /// 8×f32 joints.
    Joint,
    /// 8×i32 pulses.
    Pulse,
    /// 8×i32 currents in %.
    Current,
}

impl MxtType {
    /// All types in code order.
    pub const ALL: [MxtType; 12] = [
        MxtType::Null,
        MxtType::Pose,
        MxtType::Joint,
        MxtType::Pulse,
        MxtType::PoseFiltered,
        MxtType::JointFiltered,
        MxtType::PulseFiltered,
        MxtType::PoseFeedback,
        MxtType::JointFeedback,
        MxtType::PulseFeedback,
        MxtType::CurrentCommand,
        MxtType::CurrentFeedback,
    ];

    /// The wire code.
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// The type for a wire code.
    pub const fn from_code(code: u16) -> Option<Self> {
        if (code as usize) < Self::ALL.len() {
            Some(Self::ALL[code as usize])
        } else {
            None
        }
    }

    /// How the data block is laid out for this type.
    pub const fn shape(self) -> DataShape {
        match self {
            MxtType::Null => DataShape::Null,
            MxtType::Pose | MxtType::PoseFiltered | MxtType::PoseFeedback => DataShape::Pose,
            MxtType::Joint | MxtType::JointFiltered | MxtType::JointFeedback => DataShape::Joint,
            MxtType::Pulse | MxtType::PulseFiltered | MxtType::PulseFeedback => DataShape::Pulse,
            MxtType::CurrentCommand | MxtType::CurrentFeedback => DataShape::Current,
        }
    }
}

/// The I/O direction of a packet (`sendIoType`, `recvIoType`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum IoType {
    /// 0: no I/O.
    #[default]
    Null,
    /// 1: outputs.
    Output,
    /// 2: inputs.
    Input,
}

impl IoType {
    /// The wire code.
    pub const fn code(self) -> u16 {
        self as u16
    }

    /// The I/O type for a wire code.
    pub const fn from_code(code: u16) -> Option<Self> {
        match code {
            0 => Some(IoType::Null),
            1 => Some(IoType::Output),
            2 => Some(IoType::Input),
            _ => None,
        }
    }
}

/// The MXT program's mode argument: what the client commands.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Mode {
    /// 0: Cartesian poses.
    Pose,
    /// 1: joint positions.
    #[default]
    Joint,
    /// 2: motor pulses.
    Pulse,
}

impl Mode {
    /// The code written into `MXT 1,<mode>,<filter>`.
    pub const fn code(self) -> u8 {
        self as u8
    }
}

/// A pose as carried in a data block: mm and rad in f32, plus the structure flags.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseData {
    /// `x, y, z` in mm.
    pub xyz_mm: [f32; 3],
    /// `a, b, c` in rad (`R = Rz(c)·Ry(b)·Rx(a)`).
    pub abc_rad: [f32; 3],
    /// Additional axes `l1, l2`.
    pub additional: [f32; 2],
    /// Structure flag 1 (arm configuration).
    pub sflg1: u32,
    /// Structure flag 2 (multi-turn).
    pub sflg2: u32,
}

/// One 40-byte data block, kept as raw bytes so any block round-trips bit for bit; the typed
/// views read it in one of the four shapes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Data(pub [u8; DATA_LEN]);

impl Default for Data {
    fn default() -> Self {
        Self::ZERO
    }
}

impl Data {
    /// All zero.
    pub const ZERO: Data = Data([0; DATA_LEN]);

    fn word(&self, i: usize) -> [u8; 4] {
        let o = i * 4;
        [self.0[o], self.0[o + 1], self.0[o + 2], self.0[o + 3]]
    }

    fn set_word(&mut self, i: usize, w: [u8; 4]) {
        self.0[i * 4..i * 4 + 4].copy_from_slice(&w);
    }

    /// A block holding joints (rad, or mm for linear axes); the last 8 bytes stay zero.
    pub fn from_joints(joints: &[f32; MAX_AXES]) -> Self {
        let mut d = Self::ZERO;
        for (i, j) in joints.iter().enumerate() {
            d.set_word(i, j.to_le_bytes());
        }
        d
    }

    /// The block read as joints.
    pub fn joints(&self) -> [f32; MAX_AXES] {
        core::array::from_fn(|i| f32::from_le_bytes(self.word(i)))
    }

    /// A block holding a pose.
    pub fn from_pose(pose: &PoseData) -> Self {
        let mut d = Self::ZERO;
        let w = [
            pose.xyz_mm[0],
            pose.xyz_mm[1],
            pose.xyz_mm[2],
            pose.abc_rad[0],
            pose.abc_rad[1],
            pose.abc_rad[2],
            pose.additional[0],
            pose.additional[1],
        ];
        for (i, v) in w.iter().enumerate() {
            d.set_word(i, v.to_le_bytes());
        }
        d.set_word(8, pose.sflg1.to_le_bytes());
        d.set_word(9, pose.sflg2.to_le_bytes());
        d
    }

    /// The block read as a pose.
    pub fn pose(&self) -> PoseData {
        let f = |i| f32::from_le_bytes(self.word(i));
        PoseData {
            xyz_mm: [f(0), f(1), f(2)],
            abc_rad: [f(3), f(4), f(5)],
            additional: [f(6), f(7)],
            sflg1: u32::from_le_bytes(self.word(8)),
            sflg2: u32::from_le_bytes(self.word(9)),
        }
    }

    /// A block holding 8 signed integers: motor pulses or currents in %.
    pub fn from_i32s(values: &[i32; MAX_AXES]) -> Self {
        let mut d = Self::ZERO;
        for (i, v) in values.iter().enumerate() {
            d.set_word(i, v.to_le_bytes());
        }
        d
    }

    /// The block read as 8 signed integers (pulses, or currents in %).
    pub fn i32s(&self) -> [i32; MAX_AXES] {
        core::array::from_fn(|i| i32::from_le_bytes(self.word(i)))
    }

    /// The block read in the shape of `ty`.
    pub fn view(&self, ty: MxtType) -> DataView {
        match ty.shape() {
            DataShape::Null => DataView::Null,
            DataShape::Pose => DataView::Pose(self.pose()),
            DataShape::Joint => DataView::Joint(self.joints()),
            DataShape::Pulse => DataView::Pulse(self.i32s()),
            DataShape::Current => DataView::Current(self.i32s()),
        }
    }
}

/// A data block read in the shape of its type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DataView {
    /// No data.
    Null,
    /// A pose.
    Pose(PoseData),
    /// Joints.
    Joint([f32; MAX_AXES]),
    /// Motor pulses.
    Pulse([i32; MAX_AXES]),
    /// Currents in %.
    Current([i32; MAX_AXES]),
}

/// Why bytes are not a valid packet. Offsets are byte offsets into the packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DecodeError {
    /// The datagram is not 196 bytes long.
    Length {
        /// Bytes received.
        got: usize,
    },
    /// `command` is not 0, 1 or 255.
    UnknownCommand {
        /// The value found.
        value: u16,
    },
    /// A type field holds no MxtType code (0..=11).
    UnknownType {
        /// Where.
        offset: usize,
        /// The value found.
        value: u16,
    },
    /// An I/O type field is not 0, 1 or 2.
    UnknownIoType {
        /// Where.
        offset: usize,
        /// The value found.
        value: u16,
    },
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::Length { got } => {
                write!(f, "length {got} bytes, expected {PACKET_LEN}")
            }
            DecodeError::UnknownCommand { value } => {
                write!(
                    f,
                    "unknown command {value} at offset 0 (expected 0, 1 or 255)"
                )
            }
            DecodeError::UnknownType { offset, value } => {
                write!(
                    f,
                    "unknown data type {value} at offset {offset} (expected 0..=11)"
                )
            }
            DecodeError::UnknownIoType { offset, value } => {
                write!(
                    f,
                    "unknown I/O type {value} at offset {offset} (expected 0, 1 or 2)"
                )
            }
        }
    }
}

/// One real-time packet, field for field (RL's `MitsubishiH7::Command`). The same layout goes
/// both ways; in a reply, `recv_type*` say what the controller put into each data block.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Packet {
    /// What to do.
    pub command: Command,
    /// Type of `dat` when commanding.
    pub send_type: MxtType,
    /// Type wanted back (or, in a reply, held) in `dat`.
    pub recv_type: MxtType,
    /// Reserved.
    pub reserve: u16,
    /// Data block 0: the command target, or a reply.
    pub dat: Data,
    /// I/O command direction.
    pub send_io_type: IoType,
    /// I/O monitor direction.
    pub recv_io_type: IoType,
    /// First I/O bit number.
    pub bit_top: u16,
    /// I/O mask (when commanding).
    pub bit_mask: u16,
    /// I/O value (command or monitor).
    pub io_data: u16,
    /// Timeout counter.
    pub t_count: u16,
    /// Packet counter.
    pub c_count: u32,
    /// Type wanted back in `dat1`.
    pub recv_type1: MxtType,
    /// Reserved.
    pub reserve1: u16,
    /// Data block 1.
    pub dat1: Data,
    /// Type wanted back in `dat2`.
    pub recv_type2: MxtType,
    /// Reserved.
    pub reserve2: u16,
    /// Data block 2.
    pub dat2: Data,
    /// Type wanted back in `dat3`.
    pub recv_type3: MxtType,
    /// Reserved.
    pub reserve3: u16,
    /// Data block 3.
    pub dat3: Data,
}

fn get_u16(b: &[u8; PACKET_LEN], o: usize) -> u16 {
    u16::from_le_bytes([b[o], b[o + 1]])
}

fn get_u32(b: &[u8; PACKET_LEN], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

fn get_data(b: &[u8; PACKET_LEN], o: usize) -> Data {
    let mut d = [0; DATA_LEN];
    d.copy_from_slice(&b[o..o + DATA_LEN]);
    Data(d)
}

fn get_type(b: &[u8; PACKET_LEN], offset: usize) -> Result<MxtType, DecodeError> {
    let value = get_u16(b, offset);
    MxtType::from_code(value).ok_or(DecodeError::UnknownType { offset, value })
}

fn get_io_type(b: &[u8; PACKET_LEN], offset: usize) -> Result<IoType, DecodeError> {
    let value = get_u16(b, offset);
    IoType::from_code(value).ok_or(DecodeError::UnknownIoType { offset, value })
}

impl Packet {
    /// The four data blocks with the types they hold (in a reply) or ask for (in a request).
    pub fn blocks(&self) -> [(MxtType, &Data); 4] {
        [
            (self.recv_type, &self.dat),
            (self.recv_type1, &self.dat1),
            (self.recv_type2, &self.dat2),
            (self.recv_type3, &self.dat3),
        ]
    }

    /// Mutable access to the data blocks with their type fields.
    pub fn blocks_mut(&mut self) -> [(&mut MxtType, &mut Data); 4] {
        [
            (&mut self.recv_type, &mut self.dat),
            (&mut self.recv_type1, &mut self.dat1),
            (&mut self.recv_type2, &mut self.dat2),
            (&mut self.recv_type3, &mut self.dat3),
        ]
    }

    /// The first data block holding `ty`, read in its shape.
    pub fn find(&self, ty: MxtType) -> Option<DataView> {
        self.blocks()
            .iter()
            .find(|(t, _)| *t == ty && ty != MxtType::Null)
            .map(|(t, d)| d.view(*t))
    }

    /// Writes the packet into `out`.
    pub fn encode(&self, out: &mut [u8; PACKET_LEN]) {
        use offset::*;
        let mut put16 = |o: usize, v: u16| out[o..o + 2].copy_from_slice(&v.to_le_bytes());
        put16(COMMAND, self.command.code());
        put16(SEND_TYPE, self.send_type.code());
        put16(RECV_TYPE, self.recv_type.code());
        put16(RESERVE, self.reserve);
        put16(SEND_IO_TYPE, self.send_io_type.code());
        put16(RECV_IO_TYPE, self.recv_io_type.code());
        put16(BIT_TOP, self.bit_top);
        put16(BIT_MASK, self.bit_mask);
        put16(IO_DATA, self.io_data);
        put16(T_COUNT, self.t_count);
        put16(RECV_TYPE1, self.recv_type1.code());
        put16(RESERVE1, self.reserve1);
        put16(RECV_TYPE2, self.recv_type2.code());
        put16(RESERVE2, self.reserve2);
        put16(RECV_TYPE3, self.recv_type3.code());
        put16(RESERVE3, self.reserve3);
        out[C_COUNT..C_COUNT + 4].copy_from_slice(&self.c_count.to_le_bytes());
        for (o, d) in [
            (DAT, &self.dat),
            (DAT1, &self.dat1),
            (DAT2, &self.dat2),
            (DAT3, &self.dat3),
        ] {
            out[o..o + DATA_LEN].copy_from_slice(&d.0);
        }
    }

    /// The packet as a byte array.
    pub fn to_bytes(&self) -> [u8; PACKET_LEN] {
        let mut out = [0; PACKET_LEN];
        self.encode(&mut out);
        out
    }

    /// Decodes a datagram. Any input gives a packet or a [`DecodeError`]; it never panics.
    pub fn decode(bytes: &[u8]) -> Result<Packet, DecodeError> {
        use offset::*;
        let b: &[u8; PACKET_LEN] = bytes
            .try_into()
            .map_err(|_| DecodeError::Length { got: bytes.len() })?;
        let value = get_u16(b, COMMAND);
        let command = Command::from_code(value).ok_or(DecodeError::UnknownCommand { value })?;
        Ok(Packet {
            command,
            send_type: get_type(b, SEND_TYPE)?,
            recv_type: get_type(b, RECV_TYPE)?,
            reserve: get_u16(b, RESERVE),
            dat: get_data(b, DAT),
            send_io_type: get_io_type(b, SEND_IO_TYPE)?,
            recv_io_type: get_io_type(b, RECV_IO_TYPE)?,
            bit_top: get_u16(b, BIT_TOP),
            bit_mask: get_u16(b, BIT_MASK),
            io_data: get_u16(b, IO_DATA),
            t_count: get_u16(b, T_COUNT),
            c_count: get_u32(b, C_COUNT),
            recv_type1: get_type(b, RECV_TYPE1)?,
            reserve1: get_u16(b, RESERVE1),
            dat1: get_data(b, DAT1),
            recv_type2: get_type(b, RECV_TYPE2)?,
            reserve2: get_u16(b, RESERVE2),
            dat2: get_data(b, DAT2),
            recv_type3: get_type(b, RECV_TYPE3)?,
            reserve3: get_u16(b, RESERVE3),
            dat3: get_data(b, DAT3),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hand-built RL step request (reference, "step() repeats every cycle"): joint command
    /// with the four recv types RL asks for, cCount 7.
    #[test]
    fn fields_land_at_the_reference_offsets() {
        let p = Packet {
            command: Command::Move,
            send_type: MxtType::Joint,
            recv_type: MxtType::Joint,
            dat: Data::from_joints(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -2.0]),
            send_io_type: IoType::Output,
            recv_io_type: IoType::Input,
            bit_top: 900,
            bit_mask: 0x00FF,
            io_data: 0xAA,
            c_count: 7,
            recv_type1: MxtType::Pose,
            recv_type2: MxtType::Pulse,
            recv_type3: MxtType::CurrentFeedback,
            ..Packet::default()
        };
        let b = p.to_bytes();
        assert_eq!(&b[0..8], &[1, 0, 2, 0, 2, 0, 0, 0]);
        assert_eq!(&b[8..12], &1.0f32.to_le_bytes());
        assert_eq!(&b[36..40], &(-2.0f32).to_le_bytes());
        assert_eq!(
            &b[48..60],
            &[1, 0, 2, 0, 0x84, 0x03, 0xFF, 0, 0xAA, 0, 0, 0]
        );
        assert_eq!(&b[60..64], &[7, 0, 0, 0]);
        assert_eq!(&b[64..66], &[1, 0]);
        assert_eq!(&b[108..110], &[3, 0]);
        assert_eq!(&b[152..154], &[11, 0]);
        assert_eq!(Packet::decode(&b), Ok(p));
    }

    #[test]
    fn an_end_packet_is_code_255() {
        let b = Packet {
            command: Command::End,
            ..Packet::default()
        }
        .to_bytes();
        assert_eq!(&b[0..2], &[255, 0]);
        assert!(b[2..].iter().all(|&x| x == 0));
    }

    #[test]
    fn bad_input_names_what_and_where() {
        assert_eq!(
            Packet::decode(&[0; 195]),
            Err(DecodeError::Length { got: 195 })
        );
        let mut b = Packet::default().to_bytes();
        b[0] = 2;
        assert_eq!(
            Packet::decode(&b),
            Err(DecodeError::UnknownCommand { value: 2 })
        );
        let mut b = Packet::default().to_bytes();
        b[108] = 12;
        assert_eq!(
            Packet::decode(&b),
            Err(DecodeError::UnknownType {
                offset: 108,
                value: 12
            })
        );
        let mut b = Packet::default().to_bytes();
        b[50] = 3;
        assert_eq!(
            Packet::decode(&b),
            Err(DecodeError::UnknownIoType {
                offset: 50,
                value: 3
            })
        );
    }

    #[test]
    fn data_shapes_round_trip() {
        let pose = PoseData {
            xyz_mm: [1.5, -2.0, 300.25],
            abc_rad: [0.1, 0.2, -3.1],
            additional: [4.0, 5.0],
            sflg1: 7,
            sflg2: 0x00F0_0000,
        };
        assert_eq!(Data::from_pose(&pose).pose(), pose);
        assert_eq!(
            Data::from_pose(&pose).view(MxtType::PoseFeedback),
            DataView::Pose(pose)
        );
        let pulses = [1, -2, 3, i32::MAX, i32::MIN, 0, 5, 6];
        assert_eq!(
            Data::from_i32s(&pulses).view(MxtType::Pulse),
            DataView::Pulse(pulses)
        );
        assert_eq!(
            Data::from_i32s(&pulses).view(MxtType::CurrentFeedback),
            DataView::Current(pulses)
        );
        let j = [0.5; 8];
        assert_eq!(&Data::from_joints(&j).0[32..], &[0; 8]);
        assert_eq!(
            Data::from_joints(&j).view(MxtType::JointFiltered),
            DataView::Joint(j)
        );
    }
}
