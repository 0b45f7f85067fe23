//! The ROS 2 messages a cell exchanges, field for field as their `.msg` files in ROS 2 Jazzy
//! (common_interfaces, rcl_interfaces), with their type descriptions (for the RIHS01 hashes)
//! and CDR codecs.
//!
//! | message | direction | topic (relative to the cell's namespace) |
//! |---|---|---|
//! | `sensor_msgs/msg/JointState` | out | `joint_states` (measured), `joint_commands` (commanded) |
//! | `std_msgs/msg/String` | out | `run_state`, `fault`, `report` (JSON text) |
//! | `trajectory_msgs/msg/JointTrajectory` | in | `joint_trajectory` (streamed targets) |
//! | `geometry_msgs/msg/PoseStamped`, `PointStamped` | in | `obstacles/<name>` |
//! | `std_msgs/msg/String` | in | `stop` (`rest` or `now`) |

use super::cdr::{DecodeError, Reader, Writer};
use super::type_hash::{FieldType as T, TypeDescription, one, seq};

/// A message this crate reads and writes.
pub trait Message: Sized {
    /// Its type description.
    const TYPE: &'static TypeDescription;
    /// Appends its fields.
    fn write(&self, w: &mut Writer<'_>);
    /// Reads its fields.
    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError>;

    /// The whole CDR message (header included) into `buf`.
    fn encode(&self, buf: &mut Vec<u8>) {
        let mut w = Writer::new(buf);
        self.write(&mut w);
    }

    /// Reads a whole CDR message.
    fn decode(message: &[u8]) -> Result<Self, DecodeError> {
        let mut r = Reader::new(message)?;
        let m = Self::read(&mut r)?;
        r.finish()?;
        Ok(m)
    }
}

/// `builtin_interfaces/msg/Time`.
pub static TIME: TypeDescription = TypeDescription {
    name: "builtin_interfaces/msg/Time",
    fields: &[one("sec", T::I32), one("nanosec", T::U32)],
    nested: &[],
};

/// `builtin_interfaces/msg/Duration`.
pub static DURATION: TypeDescription = TypeDescription {
    name: "builtin_interfaces/msg/Duration",
    fields: &[one("sec", T::I32), one("nanosec", T::U32)],
    nested: &[],
};

/// `std_msgs/msg/Header`.
pub static HEADER: TypeDescription = TypeDescription {
    name: "std_msgs/msg/Header",
    fields: &[
        one("stamp", T::Nested("builtin_interfaces/msg/Time")),
        one("frame_id", T::String),
    ],
    nested: &[&TIME],
};

/// `std_msgs/msg/String`.
pub static STRING: TypeDescription = TypeDescription {
    name: "std_msgs/msg/String",
    fields: &[one("data", T::String)],
    nested: &[],
};

/// `sensor_msgs/msg/JointState`.
pub static JOINT_STATE: TypeDescription = TypeDescription {
    name: "sensor_msgs/msg/JointState",
    fields: &[
        one("header", T::Nested("std_msgs/msg/Header")),
        seq("name", T::String),
        seq("position", T::F64),
        seq("velocity", T::F64),
        seq("effort", T::F64),
    ],
    nested: &[&HEADER],
};

/// `trajectory_msgs/msg/JointTrajectoryPoint`.
pub static JOINT_TRAJECTORY_POINT: TypeDescription = TypeDescription {
    name: "trajectory_msgs/msg/JointTrajectoryPoint",
    fields: &[
        seq("positions", T::F64),
        seq("velocities", T::F64),
        seq("accelerations", T::F64),
        seq("effort", T::F64),
        one(
            "time_from_start",
            T::Nested("builtin_interfaces/msg/Duration"),
        ),
    ],
    nested: &[&DURATION],
};

/// `trajectory_msgs/msg/JointTrajectory`.
pub static JOINT_TRAJECTORY: TypeDescription = TypeDescription {
    name: "trajectory_msgs/msg/JointTrajectory",
    fields: &[
        one("header", T::Nested("std_msgs/msg/Header")),
        seq("joint_names", T::String),
        seq(
            "points",
            T::Nested("trajectory_msgs/msg/JointTrajectoryPoint"),
        ),
    ],
    nested: &[&HEADER, &JOINT_TRAJECTORY_POINT],
};

/// `geometry_msgs/msg/Point`.
pub static POINT: TypeDescription = TypeDescription {
    name: "geometry_msgs/msg/Point",
    fields: &[one("x", T::F64), one("y", T::F64), one("z", T::F64)],
    nested: &[],
};

/// `geometry_msgs/msg/Quaternion`.
pub static QUATERNION: TypeDescription = TypeDescription {
    name: "geometry_msgs/msg/Quaternion",
    fields: &[
        one("x", T::F64),
        one("y", T::F64),
        one("z", T::F64),
        one("w", T::F64),
    ],
    nested: &[],
};

/// `geometry_msgs/msg/Pose`.
pub static POSE: TypeDescription = TypeDescription {
    name: "geometry_msgs/msg/Pose",
    fields: &[
        one("position", T::Nested("geometry_msgs/msg/Point")),
        one("orientation", T::Nested("geometry_msgs/msg/Quaternion")),
    ],
    nested: &[&POINT, &QUATERNION],
};

/// `geometry_msgs/msg/PoseStamped`.
pub static POSE_STAMPED: TypeDescription = TypeDescription {
    name: "geometry_msgs/msg/PoseStamped",
    fields: &[
        one("header", T::Nested("std_msgs/msg/Header")),
        one("pose", T::Nested("geometry_msgs/msg/Pose")),
    ],
    nested: &[&HEADER, &POSE],
};

/// `geometry_msgs/msg/PointStamped`.
pub static POINT_STAMPED: TypeDescription = TypeDescription {
    name: "geometry_msgs/msg/PointStamped",
    fields: &[
        one("header", T::Nested("std_msgs/msg/Header")),
        one("point", T::Nested("geometry_msgs/msg/Point")),
    ],
    nested: &[&HEADER, &POINT],
};

/// `builtin_interfaces/msg/Time` (also the layout of `Duration`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, 0 to 999,999,999.
    pub nanosec: u32,
}

impl Time {
    /// From nanoseconds (since the UNIX epoch for a stamp); saturates past 2038.
    pub fn from_nanos(ns: i64) -> Self {
        let sec = ns.div_euclid(1_000_000_000);
        Self {
            sec: i32::try_from(sec).unwrap_or(if sec < 0 { i32::MIN } else { i32::MAX }),
            nanosec: ns.rem_euclid(1_000_000_000) as u32,
        }
    }

    /// In nanoseconds.
    pub fn as_nanos(&self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    fn write(&self, w: &mut Writer<'_>) {
        w.i32(self.sec);
        w.u32(self.nanosec);
    }

    fn read(r: &mut Reader<'_>, field: &'static str) -> Result<Self, DecodeError> {
        Ok(Self {
            sec: r.i32(field)?,
            nanosec: r.u32(field)?,
        })
    }
}

/// `std_msgs/msg/Header`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Header {
    /// When the data was measured (or, for a trajectory, when it starts; zero: now).
    pub stamp: Time,
    /// The frame the data is in.
    pub frame_id: String,
}

impl Header {
    fn write(&self, w: &mut Writer<'_>) {
        self.stamp.write(w);
        w.string(&self.frame_id);
    }

    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError> {
        Ok(Self {
            stamp: Time::read(r, "header.stamp")?,
            frame_id: r.string("header.frame_id")?.to_owned(),
        })
    }
}

/// `std_msgs/msg/String`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Text {
    /// The text.
    pub data: String,
}

impl Message for Text {
    const TYPE: &'static TypeDescription = &STRING;
    fn write(&self, w: &mut Writer<'_>) {
        w.string(&self.data);
    }
    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError> {
        Ok(Self {
            data: r.string("data")?.to_owned(),
        })
    }
}

/// `sensor_msgs/msg/JointState`: one value per named joint; a quantity not known is an empty
/// sequence.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointState {
    /// Stamp and frame.
    pub header: Header,
    /// Joint names.
    pub name: Vec<String>,
    /// Positions, rad or m.
    pub position: Vec<f64>,
    /// Velocities, rad/s or m/s.
    pub velocity: Vec<f64>,
    /// Efforts, N·m or N.
    pub effort: Vec<f64>,
}

/// Writes a `JointState` from borrowed parts (the bridge's per-cycle path: no message is
/// built).
pub fn write_joint_state<S: AsRef<str>>(
    buf: &mut Vec<u8>,
    stamp: Time,
    frame_id: &str,
    name: &[S],
    position: &[f64],
    velocity: &[f64],
    effort: &[f64],
) {
    let mut w = Writer::new(buf);
    stamp.write(&mut w);
    w.string(frame_id);
    w.string_seq(name);
    w.f64_seq(position);
    w.f64_seq(velocity);
    w.f64_seq(effort);
}

impl Message for JointState {
    const TYPE: &'static TypeDescription = &JOINT_STATE;
    fn write(&self, w: &mut Writer<'_>) {
        self.header.write(w);
        w.string_seq(&self.name);
        w.f64_seq(&self.position);
        w.f64_seq(&self.velocity);
        w.f64_seq(&self.effort);
    }
    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError> {
        let header = Header::read(r)?;
        let name = r.string_seq("name")?;
        let mut m = Self {
            header,
            name,
            ..Self::default()
        };
        r.f64_seq("position", &mut m.position)?;
        r.f64_seq("velocity", &mut m.velocity)?;
        r.f64_seq("effort", &mut m.effort)?;
        Ok(m)
    }
}

/// `trajectory_msgs/msg/JointTrajectoryPoint`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointTrajectoryPoint {
    /// Positions, one per joint of the trajectory (or none).
    pub positions: Vec<f64>,
    /// Velocities (or none).
    pub velocities: Vec<f64>,
    /// Accelerations (or none).
    pub accelerations: Vec<f64>,
    /// Efforts (or none).
    pub effort: Vec<f64>,
    /// When to be there, from the trajectory's start.
    pub time_from_start: Time,
}

impl JointTrajectoryPoint {
    fn write(&self, w: &mut Writer<'_>) {
        w.f64_seq(&self.positions);
        w.f64_seq(&self.velocities);
        w.f64_seq(&self.accelerations);
        w.f64_seq(&self.effort);
        self.time_from_start.write(w);
    }

    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError> {
        let mut p = Self::default();
        r.f64_seq("points.positions", &mut p.positions)?;
        r.f64_seq("points.velocities", &mut p.velocities)?;
        r.f64_seq("points.accelerations", &mut p.accelerations)?;
        r.f64_seq("points.effort", &mut p.effort)?;
        p.time_from_start = Time::read(r, "points.time_from_start")?;
        Ok(p)
    }
}

/// `trajectory_msgs/msg/JointTrajectory`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointTrajectory {
    /// Stamp (when the trajectory starts; zero: now) and frame.
    pub header: Header,
    /// The joints, in the order of each point's values.
    pub joint_names: Vec<String>,
    /// The points.
    pub points: Vec<JointTrajectoryPoint>,
}

impl Message for JointTrajectory {
    const TYPE: &'static TypeDescription = &JOINT_TRAJECTORY;
    fn write(&self, w: &mut Writer<'_>) {
        self.header.write(w);
        w.string_seq(&self.joint_names);
        w.seq_len(self.points.len());
        for p in &self.points {
            p.write(w);
        }
    }
    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError> {
        let header = Header::read(r)?;
        let joint_names = r.string_seq("joint_names")?;
        // A point is at least four empty sequences and a duration: 24 bytes.
        let n = r.seq_len("points", 24)?;
        let points = (0..n)
            .map(|_| JointTrajectoryPoint::read(r))
            .collect::<Result<_, _>>()?;
        Ok(Self {
            header,
            joint_names,
            points,
        })
    }
}

fn read_xyz(r: &mut Reader<'_>, field: &'static str) -> Result<[f64; 3], DecodeError> {
    Ok([r.f64(field)?, r.f64(field)?, r.f64(field)?])
}

/// `geometry_msgs/msg/PoseStamped`: a position (m) and a unit quaternion `[x, y, z, w]` in a
/// frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// Position, m.
    pub position: [f64; 3],
    /// Orientation `[x, y, z, w]`.
    pub orientation: [f64; 4],
}

impl Message for PoseStamped {
    const TYPE: &'static TypeDescription = &POSE_STAMPED;
    fn write(&self, w: &mut Writer<'_>) {
        self.header.write(w);
        for v in self.position.iter().chain(&self.orientation) {
            w.f64(*v);
        }
    }
    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError> {
        let header = Header::read(r)?;
        let position = read_xyz(r, "pose.position")?;
        let f = "pose.orientation";
        let orientation = [r.f64(f)?, r.f64(f)?, r.f64(f)?, r.f64(f)?];
        Ok(Self {
            header,
            position,
            orientation,
        })
    }
}

/// `geometry_msgs/msg/PointStamped`: a position (m) in a frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointStamped {
    /// Stamp and frame.
    pub header: Header,
    /// Position, m.
    pub point: [f64; 3],
}

impl Message for PointStamped {
    const TYPE: &'static TypeDescription = &POINT_STAMPED;
    fn write(&self, w: &mut Writer<'_>) {
        self.header.write(w);
        for v in &self.point {
            w.f64(*v);
        }
    }
    fn read(r: &mut Reader<'_>) -> Result<Self, DecodeError> {
        Ok(Self {
            header: Header::read(r)?,
            point: read_xyz(r, "point")?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dds_names_are_rmw_zenohs() {
        assert_eq!(
            JOINT_STATE.dds_name(),
            "sensor_msgs::msg::dds_::JointState_"
        );
        assert_eq!(STRING.dds_name(), "std_msgs::msg::dds_::String_");
    }

    #[test]
    fn stamps_split_into_seconds_and_nanoseconds() {
        let t = Time::from_nanos(1_700_000_000_123_456_789);
        assert_eq!((t.sec, t.nanosec), (1_700_000_000, 123_456_789));
        assert_eq!(t.as_nanos(), 1_700_000_000_123_456_789);
        assert_eq!(
            Time::from_nanos(-1),
            Time {
                sec: -1,
                nanosec: 999_999_999
            }
        );
    }

    #[test]
    fn messages_round_trip() {
        let js = JointState {
            header: Header {
                stamp: Time { sec: 1, nanosec: 2 },
                frame_id: "base".into(),
            },
            name: vec!["j1".into(), "j2".into()],
            position: vec![0.5, -1.0],
            velocity: vec![],
            effort: vec![3.0, 4.0],
        };
        let mut buf = Vec::new();
        js.encode(&mut buf);
        assert_eq!(JointState::decode(&buf), Ok(js));
        let jt = JointTrajectory {
            header: Header::default(),
            joint_names: vec!["a".into()],
            points: vec![JointTrajectoryPoint {
                positions: vec![0.25],
                velocities: vec![0.0],
                time_from_start: Time { sec: 0, nanosec: 5 },
                ..Default::default()
            }],
        };
        jt.encode(&mut buf);
        assert_eq!(JointTrajectory::decode(&buf), Ok(jt));
        // One byte short anywhere is an error, never a panic.
        for n in 0..buf.len() {
            assert!(JointTrajectory::decode(&buf[..n]).is_err(), "{n} bytes");
        }
    }
}
