//! Names on the wire as rmw_zenoh (ROS 2's Zenoh middleware, Jazzy line 0.2.x and later)
//! writes them (its `docs/design.md` and `liveliness_utils.cpp`):
//!
//! - a topic's data key: `<domain_id>/<topic>/<dds type name>/<RIHS01 hash>`, the fully
//!   qualified topic name without its leading and trailing `/` (inner ones stay), e.g.
//!   `0/arm1/joint_states/sensor_msgs::msg::dds_::JointState_/RIHS01_a13e…`;
//! - liveliness tokens: `@ros2_lv/<domain_id>/<zid>/<nid>/<id>/<kind>/<enclave>/<namespace>/
//!   <node>[/<topic>/<type>/<hash>/<qos>]`, every `/` inside a part replaced by `%` (an empty
//!   namespace or enclave is `%`), kinds `NN` node, `MP` publisher, `MS` subscription;
//! - an entity's GID: the XXH3-128 of its liveliness key, low 64 bits then high 64 bits,
//!   little-endian.
//!
//! ROS names are checked here as ROS 2 checks them (`rcl`'s topic and node name rules, in
//! short): a name is `[A-Za-z0-9_/]`, no `//`, no part starting with a digit.

use core::fmt;

use super::type_hash::TypeDescription;

/// rmw_zenoh's liveliness admin space.
pub const LIVELINESS_SPACE: &str = "@ros2_lv";

/// A ROS name that cannot be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NameError {
    /// What was named (`namespace`, `node name`, `topic`).
    pub what: &'static str,
    /// The name.
    pub name: String,
    /// Why.
    pub why: &'static str,
}

impl fmt::Display for NameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} `{}`: {}", self.what, self.name, self.why)
    }
}

impl std::error::Error for NameError {}

fn check_parts(what: &'static str, name: &str, body: &str) -> Result<(), NameError> {
    let err = |why| {
        Err(NameError {
            what,
            name: name.to_owned(),
            why,
        })
    };
    if body.is_empty() {
        return Ok(());
    }
    for part in body.split('/') {
        if part.is_empty() {
            return err("empty part (`//`, or a trailing `/`)");
        }
        if part.starts_with(|c: char| c.is_ascii_digit()) {
            return err("a part starts with a digit");
        }
        if !part.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return err("only letters, digits, `_` and `/` are allowed");
        }
    }
    Ok(())
}

/// A namespace: `/` or `/a/b` (a leading `/` is added when missing).
pub fn namespace(ns: &str) -> Result<String, NameError> {
    let body = ns.trim_start_matches('/');
    check_parts("namespace", ns, body)?;
    Ok(format!("/{body}"))
}

/// A node name: one part.
pub fn node_name(name: &str) -> Result<String, NameError> {
    if name.is_empty() || name.contains('/') {
        return Err(NameError {
            what: "node name",
            name: name.to_owned(),
            why: "must be one non-empty part without `/`",
        });
    }
    check_parts("node name", name, name)?;
    Ok(name.to_owned())
}

/// The fully qualified name of `topic` (relative, or absolute with a leading `/`) in namespace
/// `ns` (as [`namespace`] returns it).
pub fn topic(ns: &str, topic: &str) -> Result<String, NameError> {
    if let Some(abs) = topic.strip_prefix('/') {
        check_parts("topic", topic, abs)?;
        return Ok(topic.to_owned());
    }
    if topic.is_empty() {
        return Err(NameError {
            what: "topic",
            name: String::new(),
            why: "empty",
        });
    }
    check_parts("topic", topic, topic)?;
    Ok(if ns == "/" {
        format!("/{topic}")
    } else {
        format!("{ns}/{topic}")
    })
}

/// The data key expression of a topic: `<domain>/<topic without outer slashes>/<type>/<hash>`.
pub fn topic_key(domain: u32, fq_topic: &str, ty: &TypeDescription) -> String {
    format!(
        "{domain}/{}/{}/{}",
        fq_topic.trim_start_matches('/').trim_end_matches('/'),
        ty.dds_name(),
        ty.rihs01()
    )
}

/// Replaces every `/` with `%` (rmw_zenoh's `mangle_name`); an empty name is `%`.
pub fn mangle(name: &str) -> String {
    if name.is_empty() {
        "%".to_owned()
    } else {
        name.replace('/', "%")
    }
}

/// The QoS part of a liveliness token for rmw_zenoh's default profile (reliable, volatile,
/// keep last) with history `depth`: `::,<depth>:,:,:,,` (a component equal to rmw_zenoh's
/// default is left empty; the default depth is 42).
pub fn qos_default_with_depth(depth: u32) -> String {
    if depth == 42 {
        "::,:,:,:,,".to_owned()
    } else {
        format!("::,{depth}:,:,:,,")
    }
}

/// What a liveliness token announces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EntityKind {
    /// A node (`NN`).
    Node,
    /// A publisher (`MP`).
    Publisher,
    /// A subscription (`MS`).
    Subscription,
}

impl EntityKind {
    /// The token's two letters.
    pub fn code(self) -> &'static str {
        match self {
            Self::Node => "NN",
            Self::Publisher => "MP",
            Self::Subscription => "MS",
        }
    }
}

/// One entity of a node: what its liveliness token says.
#[derive(Clone, Debug)]
pub struct Entity<'a> {
    /// ROS domain.
    pub domain: u32,
    /// The Zenoh session id as Zenoh prints it (lowercase hex).
    pub zid: &'a str,
    /// The node's id in the session.
    pub node_id: u32,
    /// This entity's id in the session (the node's own for the node).
    pub id: u32,
    /// Its kind.
    pub kind: EntityKind,
    /// The node's namespace (`/` or `/a/b`).
    pub namespace: &'a str,
    /// The node's name.
    pub node: &'a str,
    /// For a publisher or subscription: the fully qualified topic, its type and QoS depth.
    pub topic: Option<(&'a str, &'a TypeDescription, u32)>,
}

impl Entity<'_> {
    /// The liveliness key expression.
    pub fn liveliness_key(&self) -> String {
        // The enclave is not set: `%`. The namespace `/` mangles to `%`.
        let mut key = format!(
            "{LIVELINESS_SPACE}/{}/{}/{}/{}/{}/%/{}/{}",
            self.domain,
            self.zid,
            self.node_id,
            self.id,
            self.kind.code(),
            mangle(self.namespace),
            mangle(self.node)
        );
        if let Some((topic, ty, depth)) = self.topic {
            key.push('/');
            key.push_str(&mangle(topic));
            key.push('/');
            key.push_str(&mangle(&ty.dds_name()));
            key.push('/');
            key.push_str(&ty.rihs01());
            key.push('/');
            key.push_str(&qos_default_with_depth(depth));
        }
        key
    }

    /// The GID rmw_zenoh derives from the liveliness key (sent in every sample's attachment).
    pub fn gid(&self) -> [u8; 16] {
        gid_of(&self.liveliness_key())
    }
}

/// XXH3-128 of `key`: low 64 bits, then high 64 bits, each little-endian.
pub fn gid_of(key: &str) -> [u8; 16] {
    let h = xxhash_rust::xxh3::xxh3_128(key.as_bytes());
    let mut gid = [0u8; 16];
    gid[..8].copy_from_slice(&(h as u64).to_le_bytes());
    gid[8..].copy_from_slice(&((h >> 64) as u64).to_le_bytes());
    gid
}

/// A liveliness token read back: what `rl cell watch` shows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Token {
    /// Domain.
    pub domain: u32,
    /// Zenoh session id.
    pub zid: String,
    /// Kind (`NN`, `MP`, `MS`, `SS`, `SC`).
    pub kind: String,
    /// Namespace, demangled.
    pub namespace: String,
    /// Node name.
    pub node: String,
    /// Topic, demangled, for a publisher or subscription.
    pub topic: Option<String>,
    /// DDS type name.
    pub type_name: Option<String>,
}

/// Reads an rmw_zenoh liveliness key (`None` if it is not one).
pub fn parse_token(key: &str) -> Option<Token> {
    let parts: Vec<&str> = key.split('/').collect();
    if parts.len() < 9 || parts[0] != LIVELINESS_SPACE {
        return None;
    }
    let demangle = |s: &str| {
        if s == "%" {
            "/".to_owned()
        } else {
            s.replace('%', "/")
        }
    };
    Some(Token {
        domain: parts[1].parse().ok()?,
        zid: parts[2].to_owned(),
        kind: parts[5].to_owned(),
        namespace: demangle(parts[7]),
        node: parts[8].to_owned(),
        topic: parts.get(9).map(|t| demangle(t)),
        type_name: parts.get(10).map(|t| t.replace('%', "/")),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros2::msg::{JOINT_STATE, STRING};

    #[test]
    fn names_resolve_as_in_ros() {
        assert_eq!(namespace("").as_deref(), Ok("/"));
        assert_eq!(namespace("arm1").as_deref(), Ok("/arm1"));
        assert_eq!(namespace("/cell/arm1").as_deref(), Ok("/cell/arm1"));
        assert!(namespace("/a//b").is_err());
        assert!(namespace("/1arm").is_err());
        assert!(namespace("/arm-1").is_err());
        assert_eq!(topic("/", "joint_states").as_deref(), Ok("/joint_states"));
        assert_eq!(
            topic("/arm1", "joint_states").as_deref(),
            Ok("/arm1/joint_states")
        );
        assert_eq!(topic("/arm1", "/abs").as_deref(), Ok("/abs"));
        assert!(node_name("a/b").is_err());
    }

    #[test]
    fn keys_have_rmw_zenohs_shape() {
        assert_eq!(
            topic_key(0, "/chatter", &STRING),
            "0/chatter/std_msgs::msg::dds_::String_/\
             RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
        );
        let e = Entity {
            domain: 0,
            zid: "8b20917502ee955ac4476e0266340d5c",
            node_id: 0,
            id: 10,
            kind: EntityKind::Publisher,
            namespace: "/",
            node: "talker",
            topic: Some(("/chatter", &STRING, 7)),
        };
        // The publisher token of ROS 2's demo talker as rmw_zenoh's design document shows it.
        assert_eq!(
            e.liveliness_key(),
            "@ros2_lv/0/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/talker/%chatter/\
             std_msgs::msg::dds_::String_/\
             RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18/::,7:,:,:,,"
        );
        let t = parse_token(&e.liveliness_key()).expect("token");
        assert_eq!(t.topic.as_deref(), Some("/chatter"));
        assert_eq!(t.namespace, "/");
        let node = Entity {
            kind: EntityKind::Node,
            id: 0,
            topic: None,
            namespace: "/arm1",
            node: "rl",
            ..e
        };
        assert_eq!(
            node.liveliness_key(),
            "@ros2_lv/0/8b20917502ee955ac4476e0266340d5c/0/0/NN/%/%arm1/rl"
        );
        let _ = JOINT_STATE.rihs01();
    }
}
