//! What a cell publishes, as a peer sees it: every sample under a ROS domain and namespace,
//! decoded by the type named in its key, and the rmw_zenoh liveliness tokens coming and going
//! (nodes, publishers, subscriptions). `rl cell watch` prints these.

use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

use zenoh::Wait;
use zenoh::pubsub::Subscriber;
use zenoh::sample::{Sample, SampleKind};

use crate::config::{CellError, unix_now_ns, zenoh_config};
use crate::ros2::attachment::Attachment;
use crate::ros2::cdr::DecodeError;
use crate::ros2::msg::{
    JOINT_STATE, JOINT_TRAJECTORY, JointState, JointTrajectory, Message, POINT_STAMPED,
    POSE_STAMPED, PointStamped, PoseStamped, STRING, Text,
};
use crate::ros2::names::{self, LIVELINESS_SPACE, Token};

/// A decoded message body.
#[derive(Clone, Debug, PartialEq)]
pub enum Body {
    /// `sensor_msgs/JointState`.
    JointState(JointState),
    /// `std_msgs/String`.
    Text(String),
    /// `trajectory_msgs/JointTrajectory`.
    Trajectory(JointTrajectory),
    /// `geometry_msgs/PoseStamped`.
    Pose(PoseStamped),
    /// `geometry_msgs/PointStamped`.
    Point(PointStamped),
    /// A type this crate does not decode.
    Other {
        /// Its size, bytes.
        bytes: usize,
    },
    /// A known type that does not decode.
    Malformed(DecodeError),
}

/// What the watcher saw.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A liveliness token appeared (an entity joined).
    Joined(Token),
    /// A liveliness token went (an entity left, or its session was lost).
    Left(Token),
    /// A sample.
    Message {
        /// The ROS topic (fully qualified).
        topic: String,
        /// The DDS type name from the key.
        type_name: String,
        /// rmw_zenoh's attachment, if it came with one.
        attachment: Option<Attachment>,
        /// When it arrived, ns since the UNIX epoch.
        received_unix_ns: i64,
        /// The decoded body.
        body: Body,
    },
}

/// Splits a data key `<domain>/<topic...>/<type>/<hash>` into topic and type.
fn split_key(key: &str) -> Option<(String, String)> {
    let mut parts: Vec<&str> = key.split('/').collect();
    if parts.len() < 4 {
        return None;
    }
    let _hash = parts.pop()?;
    let ty = parts.pop()?.to_owned();
    Some((format!("/{}", parts[1..].join("/")), ty))
}

fn decode(type_name: &str, payload: &[u8]) -> Body {
    let wrap = |r: Result<Body, DecodeError>| r.unwrap_or_else(Body::Malformed);
    if type_name == JOINT_STATE.dds_name() {
        wrap(JointState::decode(payload).map(Body::JointState))
    } else if type_name == STRING.dds_name() {
        wrap(Text::decode(payload).map(|t| Body::Text(t.data)))
    } else if type_name == JOINT_TRAJECTORY.dds_name() {
        wrap(JointTrajectory::decode(payload).map(Body::Trajectory))
    } else if type_name == POSE_STAMPED.dds_name() {
        wrap(PoseStamped::decode(payload).map(Body::Pose))
    } else if type_name == POINT_STAMPED.dds_name() {
        wrap(PointStamped::decode(payload).map(Body::Point))
    } else {
        Body::Other {
            bytes: payload.len(),
        }
    }
}

/// A watcher: a Zenoh session subscribed to a domain's (and namespace's) samples and tokens.
pub struct Watch {
    rx: Receiver<Event>,
    _subscribers: Vec<Subscriber<()>>,
    session: zenoh::Session,
}

impl Watch {
    /// Connects to (or listens on) the endpoints and watches `namespace` (`/` for all) in
    /// `domain`. Endpoints are taken as [`crate::config::endpoint`] reads them.
    pub fn open(
        connect: &[String],
        listen: &[String],
        domain: u32,
        namespace: &str,
    ) -> Result<Self, CellError> {
        let connect = connect
            .iter()
            .map(|e| crate::config::endpoint(e))
            .collect::<Result<Vec<_>, _>>()?;
        let listen = listen
            .iter()
            .map(|e| crate::config::endpoint(e))
            .collect::<Result<Vec<_>, _>>()?;
        let ns = names::namespace(namespace)?;
        let session = zenoh::open(zenoh_config(&connect, &listen)?)
            .wait()
            .map_err(|e| CellError::Zenoh(format!("cannot open the session: {e}")))?;
        let (tx, rx) = channel();
        let data_key = if ns == "/" {
            format!("{domain}/**")
        } else {
            format!("{domain}/{}/**", ns.trim_start_matches('/'))
        };
        let data_tx = tx.clone();
        let data = session
            .declare_subscriber(data_key)
            .callback(move |s: Sample| {
                let Some((topic, type_name)) = split_key(s.key_expr().as_str()) else {
                    return;
                };
                let attachment = s
                    .attachment()
                    .and_then(|a| Attachment::from_bytes(&a.to_bytes()).ok());
                let body = decode(&type_name, &s.payload().to_bytes());
                let _ = data_tx.send(Event::Message {
                    topic,
                    type_name,
                    attachment,
                    received_unix_ns: unix_now_ns(),
                    body,
                });
            })
            .wait()
            .map_err(|e| CellError::Zenoh(format!("cannot subscribe: {e}")))?;
        let ns_filter = ns.clone();
        let tokens = session
            .liveliness()
            .declare_subscriber(format!("{LIVELINESS_SPACE}/{domain}/**"))
            .history(true)
            .callback(move |s: Sample| {
                let Some(token) = names::parse_token(s.key_expr().as_str()) else {
                    return;
                };
                if ns_filter != "/"
                    && token.namespace != ns_filter
                    && !token.namespace.starts_with(&format!("{ns_filter}/"))
                {
                    return;
                }
                let _ = tx.send(match s.kind() {
                    SampleKind::Put => Event::Joined(token),
                    SampleKind::Delete => Event::Left(token),
                });
            })
            .wait()
            .map_err(|e| CellError::Zenoh(format!("cannot watch liveliness: {e}")))?;
        Ok(Self {
            rx,
            _subscribers: vec![data, tokens],
            session,
        })
    }

    /// The next event, waiting up to `timeout`.
    pub fn next(&self, timeout: Duration) -> Option<Event> {
        // Timed out, or the session's callbacks are gone.
        self.rx.recv_timeout(timeout).ok()
    }

    /// The Zenoh session id.
    pub fn zid(&self) -> String {
        self.session.zid().to_string()
    }
}

impl Drop for Watch {
    fn drop(&mut self) {
        self._subscribers.clear();
        let _ = self.session.close().wait();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_split_into_topic_and_type() {
        assert_eq!(
            split_key("0/arm1/joint_states/sensor_msgs::msg::dds_::JointState_/RIHS01_x"),
            Some((
                "/arm1/joint_states".to_owned(),
                "sensor_msgs::msg::dds_::JointState_".to_owned()
            ))
        );
        assert_eq!(split_key("0/x"), None);
    }
}
