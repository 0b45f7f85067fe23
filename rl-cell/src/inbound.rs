//! What comes in from the cell, typed and checked before it goes anywhere near the loop.
//!
//! Each sample on an inbound topic is decoded (CDR, the rmw_zenoh attachment) and checked, in
//! this order, and refused with a [`Refusal`] (counted per reason in [`InboundCounts`]) at the
//! first check it fails:
//!
//! 1. it carries rmw_zenoh's attachment (sequence number, source timestamp, GID);
//! 2. it is not stale: no older than [`Limits::max_age`] by its source timestamp when it
//!    arrives, and not from further in the future than that either (the publisher's clock is
//!    off);
//! 3. it is newer than the last one from the same publisher (sequence number; a gap is counted
//!    as lost, a repeat or an older one is refused);
//! 4. its CDR decodes;
//! 5. what it says is within limits: a target names every joint of the model once, one point,
//!    finite values, positions within the joints' limits, speeds within their speed limits; an
//!    obstacle is in the expected frame, finite, inside the workspace bound, with a unit
//!    quaternion.
//!
//! What passes becomes a typed, `Copy` [`Target`] or [`Obstacle`] handed to an [`Inbound`]:
//! the small boundary the controller's input channel implements (which checks again and may
//! refuse in turn: counted as [`Refusal::Sink`]). Stop requests go straight to the run's
//! [`StopFlag`](rl_rt::StopFlag) and are never refused for their age (stopping is the safe
//! side).

use core::fmt;
use std::collections::HashMap;
use std::time::Duration;

use rl_rt::MonoTime;

use crate::ros2::attachment::Attachment;
use crate::ros2::cdr::DecodeError;
use crate::ros2::msg::{JointTrajectory, PointStamped, PoseStamped};

/// Most obstacles a cell tracks by name.
pub const MAX_OBSTACLES: usize = 16;

/// Where the law should take the arm, for up to `J` joints in the model's order (the first
/// `dof` values are used) — the shape of the controller's streamed targets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target<const J: usize> {
    /// A position, rad or m, to reach with `velocity` (rad/s or m/s; `None`: at rest).
    Position {
        /// The position.
        position: [f64; J],
        /// The velocity to have there.
        velocity: Option<[f64; J]>,
    },
    /// A velocity to reach and keep, rad/s or m/s.
    Velocity {
        /// The velocity.
        velocity: [f64; J],
    },
}

/// An obstacle's pose, m, in the cell's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obstacle {
    /// Which obstacle: the index of its name in the order names were first seen (at most
    /// [`MAX_OBSTACLES`]; [`crate::CellReport`] lists the names).
    pub id: u8,
    /// Position, m.
    pub position: [f64; 3],
    /// Orientation `[x, y, z, w]` (identity for a point).
    pub orientation: [f64; 4],
    /// The message's own stamp, ns since the UNIX epoch.
    pub stamp_ns: i64,
}

/// When and from whom an input came: the timestamps a latency measurement needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Arrival {
    /// When the bridge had decoded it (this host's monotonic clock): a loop that applies it
    /// later can tell how long it waited.
    pub received: MonoTime,
    /// When it arrived, ns since the UNIX epoch (this host's clock).
    pub received_unix_ns: i64,
    /// When it was published, ns since the UNIX epoch (the publisher's clock).
    pub source_unix_ns: i64,
    /// The publisher's sequence number.
    pub sequence: i64,
    /// The publisher's GID.
    pub gid: [u8; 16],
}

impl Arrival {
    /// Age on arrival (this host's clock minus the publisher's), ns; negative when the
    /// publisher's clock is ahead.
    pub fn age_ns(&self) -> i64 {
        self.received_unix_ns.saturating_sub(self.source_unix_ns)
    }
}

/// The boundary between the bridge and whatever takes the inputs — the controller's input
/// channel. Called on the bridge's (non-real-time) threads, one call at a time.
pub trait Inbound<const J: usize>: Send + 'static {
    /// A checked target; `Err` refuses it (with the reason, counted).
    fn target(&mut self, target: &Target<J>, arrival: &Arrival) -> Result<(), String>;
    /// A checked obstacle pose; `Err` refuses it.
    fn obstacle(&mut self, obstacle: &Obstacle, arrival: &Arrival) -> Result<(), String>;
}

/// An [`Inbound`] from two closures.
pub struct FnInbound<F, G>(pub F, pub G);

impl<const J: usize, F, G> Inbound<J> for FnInbound<F, G>
where
    F: FnMut(&Target<J>, &Arrival) -> Result<(), String> + Send + 'static,
    G: FnMut(&Obstacle, &Arrival) -> Result<(), String> + Send + 'static,
{
    fn target(&mut self, target: &Target<J>, arrival: &Arrival) -> Result<(), String> {
        (self.0)(target, arrival)
    }
    fn obstacle(&mut self, obstacle: &Obstacle, arrival: &Arrival) -> Result<(), String> {
        (self.1)(obstacle, arrival)
    }
}

/// An [`Inbound`] that refuses everything with one reason: for a run whose loop takes no
/// inputs (yet).
#[derive(Clone, Debug)]
pub struct Refuse(pub &'static str);

impl<const J: usize> Inbound<J> for Refuse {
    fn target(&mut self, _: &Target<J>, _: &Arrival) -> Result<(), String> {
        Err(self.0.to_owned())
    }
    fn obstacle(&mut self, _: &Obstacle, _: &Arrival) -> Result<(), String> {
        Err(self.0.to_owned())
    }
}

/// Why an inbound sample was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum Refusal {
    /// No rmw_zenoh attachment, or a malformed one.
    NoAttachment,
    /// Older than the bound when it arrived.
    Stale {
        /// Its age, s.
        age_s: f64,
    },
    /// From further in the future than the bound (the publisher's clock is ahead).
    FromTheFuture {
        /// How far ahead, s.
        ahead_s: f64,
    },
    /// Not newer than the last sample from its publisher.
    OutOfOrder {
        /// Its sequence number.
        sequence: i64,
        /// The last one taken from that publisher.
        last: i64,
    },
    /// The CDR does not decode.
    Malformed(DecodeError),
    /// A target that does not name the model's joints (missing, unknown, repeated, or values
    /// of another length).
    Joints(String),
    /// A value outside a limit (position, speed, workspace, not finite).
    OutOfLimits(String),
    /// Something this bridge does not take (several points, accelerations, efforts, another
    /// frame, too many obstacles, an unknown stop word).
    Unsupported(String),
    /// Checked and passed, then refused by the [`Inbound`] (the controller's own checks).
    Sink(String),
}

impl Refusal {
    /// A short name for counting: `no_attachment`, `stale`, `from_the_future`,
    /// `out_of_order`, `malformed`, `joints`, `out_of_limits`, `unsupported`, `sink`.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::NoAttachment => "no_attachment",
            Self::Stale { .. } => "stale",
            Self::FromTheFuture { .. } => "from_the_future",
            Self::OutOfOrder { .. } => "out_of_order",
            Self::Malformed(_) => "malformed",
            Self::Joints(_) => "joints",
            Self::OutOfLimits(_) => "out_of_limits",
            Self::Unsupported(_) => "unsupported",
            Self::Sink(_) => "sink",
        }
    }
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoAttachment => f.write_str("no rmw_zenoh attachment (sequence, timestamp, GID)"),
            Self::Stale { age_s } => write!(f, "stale: {:.1} ms old on arrival", age_s * 1e3),
            Self::FromTheFuture { ahead_s } => write!(
                f,
                "stamped {:.1} ms in the future (the publisher's clock is ahead)",
                ahead_s * 1e3
            ),
            Self::OutOfOrder { sequence, last } => write!(
                f,
                "out of order: sequence {sequence} after {last} from the same publisher"
            ),
            Self::Malformed(e) => write!(f, "malformed: {e}"),
            Self::Joints(why) => write!(f, "joints: {why}"),
            Self::OutOfLimits(why) => write!(f, "out of limits: {why}"),
            Self::Unsupported(why) => write!(f, "not supported: {why}"),
            Self::Sink(why) => write!(f, "refused by the controller: {why}"),
        }
    }
}

/// The model's joints as targets are checked against.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLimits {
    /// Names, in the model's order.
    pub names: Vec<String>,
    /// Lower position limits, rad or m (`-inf` for none).
    pub lower: Vec<f64>,
    /// Upper position limits.
    pub upper: Vec<f64>,
    /// Speed limits, rad/s or m/s (`inf` for none).
    pub speed: Vec<f64>,
}

impl JointLimits {
    /// Joints without limits.
    pub fn unlimited(names: Vec<String>) -> Self {
        let n = names.len();
        Self {
            names,
            lower: vec![f64::NEG_INFINITY; n],
            upper: vec![f64::INFINITY; n],
            speed: vec![f64::INFINITY; n],
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.names.len()
    }
}

/// The bounds inbound samples are checked against.
#[derive(Clone, Debug, PartialEq)]
pub struct Limits {
    /// Oldest a sample may be on arrival (and furthest in the future).
    pub max_age: Duration,
    /// The frame obstacles must be given in.
    pub frame: String,
    /// Obstacles farther than this from the frame's origin are refused, m.
    pub workspace_radius: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_age: Duration::from_millis(100),
            frame: "world".to_owned(),
            workspace_radius: 10.0,
        }
    }
}

/// Counts of one inbound topic kind.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TopicCounts {
    /// Samples received.
    pub received: u64,
    /// Handed on (accepted by the [`Inbound`], or applied for a stop).
    pub accepted: u64,
    /// Refused, per [`Refusal::kind`].
    pub refused: Vec<(&'static str, u64)>,
    /// The first refusal, described.
    pub first_refusal: Option<String>,
    /// Samples a publisher's sequence numbers skipped (lost on the way).
    pub lost: u64,
    /// Largest age on arrival of an accepted sample, s.
    pub max_age_s: f64,
}

impl TopicCounts {
    /// All refusals.
    pub fn refused_total(&self) -> u64 {
        self.refused.iter().map(|(_, n)| n).sum()
    }

    fn refuse(&mut self, r: &Refusal) {
        match self.refused.iter_mut().find(|(k, _)| *k == r.kind()) {
            Some((_, n)) => *n += 1,
            None => self.refused.push((r.kind(), 1)),
        }
        self.first_refusal.get_or_insert_with(|| r.to_string());
    }
}

/// Counts of everything inbound.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InboundCounts {
    /// Targets (`joint_trajectory`).
    pub targets: TopicCounts,
    /// Obstacles (`obstacles/<name>`).
    pub obstacles: TopicCounts,
    /// Stop requests (`stop`).
    pub stops: TopicCounts,
    /// Obstacle names in the order first seen (their [`Obstacle::id`]).
    pub obstacle_names: Vec<String>,
}

/// Which inbound topic.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Targets.
    Target,
    /// Obstacles.
    Obstacle,
    /// Stop requests.
    Stop,
}

/// The checks of steps 1 to 3 (attachment, order, age), with per-publisher state.
#[derive(Debug, Default)]
pub struct Gate {
    last: HashMap<([u8; 16], u8), i64>,
    lost: [u64; 3],
}

impl Gate {
    /// Checks a sample's attachment, its order among its publisher's samples of `kind`, and
    /// its age at `now_unix_ns` against `max_age`. A sample whose sequence number skips some
    /// adds them to [`lost`](Self::lost) (whether it is then refused for its age or not).
    pub fn admit(
        &mut self,
        kind: Kind,
        attachment: Option<&[u8]>,
        now_unix_ns: i64,
        max_age: Duration,
    ) -> Result<Arrival, Refusal> {
        let a = attachment
            .and_then(|b| Attachment::from_bytes(b).ok())
            .ok_or(Refusal::NoAttachment)?;
        let slot = self.last.entry((a.source_gid, kind as u8)).or_insert(0);
        if a.sequence_number <= *slot {
            return Err(Refusal::OutOfOrder {
                sequence: a.sequence_number,
                last: *slot,
            });
        }
        if *slot != 0 {
            self.lost[kind as usize] += (a.sequence_number - *slot - 1) as u64;
        }
        *slot = a.sequence_number;
        let arrival = Arrival {
            received: MonoTime::now(),
            received_unix_ns: now_unix_ns,
            source_unix_ns: a.source_timestamp,
            sequence: a.sequence_number,
            gid: a.source_gid,
        };
        let age = arrival.age_ns();
        let bound = i64::try_from(max_age.as_nanos()).unwrap_or(i64::MAX);
        // Stop requests pass whatever their age: stopping is the safe side.
        if kind != Kind::Stop {
            if age > bound {
                return Err(Refusal::Stale {
                    age_s: age as f64 * 1e-9,
                });
            }
            if age < -bound {
                return Err(Refusal::FromTheFuture {
                    ahead_s: -age as f64 * 1e-9,
                });
            }
        }
        Ok(arrival)
    }

    /// Samples of `kind` that publishers' sequence numbers skipped.
    pub fn lost(&self, kind: Kind) -> u64 {
        self.lost[kind as usize]
    }
}

/// Step 5 for a target: the one point of `msg` as a [`Target`] in the model's joint order.
pub fn target_from<const J: usize>(
    msg: &JointTrajectory,
    joints: &JointLimits,
) -> Result<Target<J>, Refusal> {
    let dof = joints.dof();
    if dof > J {
        return Err(Refusal::Joints(format!(
            "the model has {dof} joints, the bridge was built for {J}"
        )));
    }
    let [point] = msg.points.as_slice() else {
        return Err(Refusal::Unsupported(format!(
            "{} points: a streamed target is one point",
            msg.points.len()
        )));
    };
    if msg.joint_names.len() != dof {
        return Err(Refusal::Joints(format!(
            "{} joint names, the model has {dof} joints ({})",
            msg.joint_names.len(),
            joints.names.join(", ")
        )));
    }
    // Where each named joint sits in the model.
    let mut index = [usize::MAX; J];
    for (k, name) in msg.joint_names.iter().enumerate() {
        let Some(m) = joints.names.iter().position(|n| n == name) else {
            return Err(Refusal::Joints(format!(
                "unknown joint `{name}` (the model's: {})",
                joints.names.join(", ")
            )));
        };
        if index[..k].contains(&m) {
            return Err(Refusal::Joints(format!("joint `{name}` named twice")));
        }
        index[k] = m;
    }
    for (what, values) in [
        ("accelerations", &point.accelerations),
        ("effort", &point.effort),
    ] {
        if values.iter().any(|v| *v != 0.0) {
            return Err(Refusal::Unsupported(format!(
                "{what}: a target is a position (with a velocity) or a velocity"
            )));
        }
    }
    let reorder = |values: &[f64], what: &str| -> Result<[f64; J], Refusal> {
        if values.len() != dof {
            return Err(Refusal::Joints(format!(
                "{} {what} for {dof} joint names",
                values.len()
            )));
        }
        let mut out = [0.0; J];
        for (k, v) in values.iter().enumerate() {
            if !v.is_finite() {
                return Err(Refusal::OutOfLimits(format!(
                    "{what} of joint {} is not finite",
                    msg.joint_names[k]
                )));
            }
            out[index[k]] = *v;
        }
        Ok(out)
    };
    let velocity = if point.velocities.is_empty() {
        None
    } else {
        let v = reorder(&point.velocities, "velocities")?;
        for ((v, speed), name) in v.iter().zip(&joints.speed).zip(&joints.names).take(dof) {
            if v.abs() > *speed {
                return Err(Refusal::OutOfLimits(format!(
                    "joint {name} at {v} is beyond its speed limit {speed}"
                )));
            }
        }
        Some(v)
    };
    if point.positions.is_empty() {
        return match velocity {
            Some(velocity) => Ok(Target::Velocity { velocity }),
            None => Err(Refusal::Unsupported(
                "a point without positions or velocities".into(),
            )),
        };
    }
    let position = reorder(&point.positions, "positions")?;
    let bounds = joints.lower.iter().zip(&joints.upper).zip(&joints.names);
    for (q, ((lower, upper), name)) in position.iter().zip(bounds).take(dof) {
        if q < lower || q > upper {
            return Err(Refusal::OutOfLimits(format!(
                "joint {name} at {q} is outside its limits [{lower}, {upper}]"
            )));
        }
    }
    Ok(Target::Position { position, velocity })
}

/// Step 5 for an obstacle named `name` (the last part of its topic): its pose, checked.
pub fn obstacle_from(
    name: &str,
    pose: ObstacleMsg<'_>,
    limits: &Limits,
    names: &mut Vec<String>,
) -> Result<Obstacle, Refusal> {
    let (header, position, orientation) = match pose {
        ObstacleMsg::Pose(p) => (&p.header, p.position, p.orientation),
        ObstacleMsg::Point(p) => (&p.header, p.point, [0.0, 0.0, 0.0, 1.0]),
    };
    if header.frame_id != limits.frame {
        return Err(Refusal::Unsupported(format!(
            "obstacle `{name}` in frame `{}`, the cell takes frame `{}`",
            header.frame_id, limits.frame
        )));
    }
    if position.iter().chain(&orientation).any(|v| !v.is_finite()) {
        return Err(Refusal::OutOfLimits(format!(
            "obstacle `{name}`: a value is not finite"
        )));
    }
    let distance = position.iter().map(|v| v * v).sum::<f64>().sqrt();
    if distance > limits.workspace_radius {
        return Err(Refusal::OutOfLimits(format!(
            "obstacle `{name}` {distance:.3} m from the origin, beyond the workspace bound {} m",
            limits.workspace_radius
        )));
    }
    let norm = orientation.iter().map(|v| v * v).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-3 {
        return Err(Refusal::OutOfLimits(format!(
            "obstacle `{name}`: orientation is not a unit quaternion (norm {norm:.6})"
        )));
    }
    let id = match names.iter().position(|n| n == name) {
        Some(id) => id,
        None if names.len() < MAX_OBSTACLES => {
            names.push(name.to_owned());
            names.len() - 1
        }
        None => {
            return Err(Refusal::Unsupported(format!(
                "obstacle `{name}`: the cell tracks at most {MAX_OBSTACLES} obstacles"
            )));
        }
    };
    Ok(Obstacle {
        id: id as u8,
        position,
        orientation,
        stamp_ns: header.stamp.as_nanos(),
    })
}

/// An obstacle message of either kind.
#[derive(Clone, Copy, Debug)]
pub enum ObstacleMsg<'a> {
    /// A pose.
    Pose(&'a PoseStamped),
    /// A point.
    Point(&'a PointStamped),
}

/// Counts one sample's outcome.
pub(crate) fn count(counts: &mut TopicCounts, result: &Result<Arrival, Refusal>) {
    counts.received += 1;
    match result {
        Ok(arrival) => {
            counts.accepted += 1;
            counts.max_age_s = counts.max_age_s.max(arrival.age_ns() as f64 * 1e-9);
        }
        Err(r) => counts.refuse(r),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros2::msg::{Header, JointTrajectoryPoint};

    fn joints() -> JointLimits {
        JointLimits {
            names: vec!["a".into(), "b".into()],
            lower: vec![-1.0, -2.0],
            upper: vec![1.0, 2.0],
            speed: vec![0.5, 0.5],
        }
    }

    fn traj(names: &[&str], positions: &[f64], velocities: &[f64]) -> JointTrajectory {
        JointTrajectory {
            header: Header::default(),
            joint_names: names.iter().map(|s| s.to_string()).collect(),
            points: vec![JointTrajectoryPoint {
                positions: positions.to_vec(),
                velocities: velocities.to_vec(),
                ..Default::default()
            }],
        }
    }

    #[test]
    fn targets_are_put_in_the_models_order_and_checked() {
        let j = joints();
        assert_eq!(
            target_from::<4>(&traj(&["b", "a"], &[1.5, 0.5], &[]), &j),
            Ok(Target::Position {
                position: [0.5, 1.5, 0.0, 0.0],
                velocity: None
            })
        );
        assert_eq!(
            target_from::<2>(&traj(&["a", "b"], &[], &[0.1, -0.2]), &j),
            Ok(Target::Velocity {
                velocity: [0.1, -0.2]
            })
        );
        let refused = |t: JointTrajectory| target_from::<2>(&t, &j).expect_err("refused").kind();
        assert_eq!(
            refused(traj(&["a", "b"], &[1.5, 0.0], &[])),
            "out_of_limits"
        );
        assert_eq!(
            refused(traj(&["a", "b"], &[0.0, 0.0], &[0.6, 0.0])),
            "out_of_limits"
        );
        assert_eq!(
            refused(traj(&["a", "b"], &[f64::NAN, 0.0], &[])),
            "out_of_limits"
        );
        assert_eq!(refused(traj(&["a", "c"], &[0.0, 0.0], &[])), "joints");
        assert_eq!(refused(traj(&["a", "a"], &[0.0, 0.0], &[])), "joints");
        assert_eq!(refused(traj(&["a"], &[0.0], &[])), "joints");
        assert_eq!(refused(traj(&["a", "b"], &[0.0], &[])), "joints");
        let mut two = traj(&["a", "b"], &[0.0, 0.0], &[]);
        two.points.push(two.points[0].clone());
        assert_eq!(refused(two), "unsupported");
    }

    #[test]
    fn the_gate_refuses_stale_future_and_old_samples() {
        let mut g = Gate::default();
        let att = |seq, ts| {
            Attachment {
                sequence_number: seq,
                source_timestamp: ts,
                source_gid: [1; 16],
            }
            .to_bytes()
        };
        let max = Duration::from_millis(100);
        let now = 1_000_000_000_000;
        assert_eq!(
            g.admit(Kind::Target, None, now, max).err(),
            Some(Refusal::NoAttachment)
        );
        let ok = g.admit(Kind::Target, Some(&att(1, now - 1_000_000)), now, max);
        assert_eq!(ok.map(|a| a.age_ns()), Ok(1_000_000));
        let stale = g.admit(Kind::Target, Some(&att(2, now - 200_000_000)), now, max);
        assert_eq!(stale.err().map(|r| r.kind()), Some("stale"));
        let future = g.admit(Kind::Target, Some(&att(3, now + 200_000_000)), now, max);
        assert_eq!(future.err().map(|r| r.kind()), Some("from_the_future"));
        assert_eq!(g.lost(Kind::Target), 0, "refused is not lost");
        // 4 never came: lost.
        assert!(g.admit(Kind::Target, Some(&att(5, now)), now, max).is_ok());
        assert_eq!(g.lost(Kind::Target), 1);
        let old = g.admit(Kind::Target, Some(&att(4, now)), now, max);
        assert_eq!(
            old.err(),
            Some(Refusal::OutOfOrder {
                sequence: 4,
                last: 5
            })
        );
        // A stop request is taken however old it is.
        assert!(g.admit(Kind::Stop, Some(&att(1, 0)), now, max).is_ok());
    }

    #[test]
    fn obstacles_are_checked_and_named() {
        let limits = Limits::default();
        let mut names = Vec::new();
        let mut p = PoseStamped {
            header: Header {
                frame_id: "world".into(),
                ..Header::default()
            },
            position: [0.5, 0.0, 0.2],
            orientation: [0.0, 0.0, 0.0, 1.0],
        };
        let o = obstacle_from("ball", ObstacleMsg::Pose(&p), &limits, &mut names).expect("ok");
        assert_eq!((o.id, o.position), (0, [0.5, 0.0, 0.2]));
        let q = obstacle_from("hand", ObstacleMsg::Pose(&p), &limits, &mut names).expect("ok");
        assert_eq!(q.id, 1);
        p.orientation = [0.0, 0.0, 0.0, 2.0];
        let e = obstacle_from("ball", ObstacleMsg::Pose(&p), &limits, &mut names);
        assert_eq!(e.err().map(|r| r.kind()), Some("out_of_limits"));
        p.orientation = [0.0, 0.0, 0.0, 1.0];
        p.position = [20.0, 0.0, 0.0];
        let e = obstacle_from("ball", ObstacleMsg::Pose(&p), &limits, &mut names);
        assert_eq!(e.err().map(|r| r.kind()), Some("out_of_limits"));
        p.position = [0.0; 3];
        p.header.frame_id = "camera".into();
        let e = obstacle_from("ball", ObstacleMsg::Pose(&p), &limits, &mut names);
        assert_eq!(e.err().map(|r| r.kind()), Some("unsupported"));
    }
}
