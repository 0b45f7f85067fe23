//! How a cell's Zenoh session is set up: where it connects and listens, its ROS domain,
//! namespace and node name, how often it publishes, and what inbound samples must satisfy.
//!
//! The session is a Zenoh peer (as rmw_zenoh's are) with multicast scouting off: it talks to
//! the endpoints it is given and nothing else. It listens nowhere unless told, and a listen
//! endpoint given without a host binds to loopback (`7447` is `tcp/127.0.0.1:7447`). A connect
//! endpoint that does not answer yet is retried in the background (Zenoh's peer default): the
//! controller starts without its peers and joins them when they come.

use core::fmt;
use std::str::FromStr;
use std::time::Duration;

use zenoh::config::EndPoint;

use crate::inbound::Limits;
use crate::ros2::names::{self, NameError};

/// Why a cell could not be set up or opened.
#[derive(Debug)]
pub enum CellError {
    /// An endpoint, name or option is wrong.
    Config(String),
    /// Zenoh refused (opening the session, declaring a publisher, ...).
    Zenoh(String),
}

impl fmt::Display for CellError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Config(why) => f.write_str(why),
            Self::Zenoh(why) => write!(f, "zenoh: {why}"),
        }
    }
}

impl std::error::Error for CellError {}

impl From<NameError> for CellError {
    fn from(e: NameError) -> Self {
        Self::Config(e.to_string())
    }
}

/// Parses a Zenoh endpoint: `tcp/HOST:PORT` or `udp/HOST:PORT` (other Zenoh locators are
/// refused: this build has only TCP and UDP); `HOST:PORT` means TCP; a bare `PORT` means
/// `tcp/127.0.0.1:PORT`.
pub fn endpoint(text: &str) -> Result<String, CellError> {
    let t = text.trim();
    let full = if t.parse::<u16>().is_ok() {
        format!("tcp/127.0.0.1:{t}")
    } else if t.contains('/') {
        t.to_owned()
    } else {
        format!("tcp/{t}")
    };
    let ep = EndPoint::from_str(&full)
        .map_err(|e| CellError::Config(format!("endpoint `{text}`: {e}")))?;
    let protocol = ep.protocol();
    if !matches!(protocol.as_str(), "tcp" | "udp") {
        return Err(CellError::Config(format!(
            "endpoint `{text}`: protocol `{}` is not built in (tcp or udp)",
            protocol.as_str()
        )));
    }
    if !ep.address().as_str().contains(':') {
        return Err(CellError::Config(format!(
            "endpoint `{text}`: give HOST:PORT (e.g. tcp/127.0.0.1:7447)"
        )));
    }
    Ok(full)
}

/// A cell's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct CellConfig {
    /// Endpoints to connect to (`tcp/HOST:PORT`), retried until they answer.
    pub connect: Vec<String>,
    /// Endpoints to listen on (none by default).
    pub listen: Vec<String>,
    /// ROS domain (`ROS_DOMAIN_ID`), the first part of every key.
    pub domain: u32,
    /// ROS namespace of the controller's topics (`/` or `/arm1`).
    pub namespace: String,
    /// ROS node name the controller shows as.
    pub node: String,
    /// Publish the joint states of every `decimation`-th cycle (1: every cycle).
    pub decimation: u32,
    /// The loop's period (velocities are differences over it; stamps step by it).
    pub period: Duration,
    /// What inbound samples must satisfy.
    pub limits: Limits,
    /// Samples the bridge holds between the loop's side and the network (more are dropped
    /// and counted).
    pub capacity: usize,
    /// Wait up to this long in [`Cell::open`](crate::Cell::open) for a subscriber of the
    /// measured joint states (a recorder that must see the whole run); `None`: do not wait.
    pub wait_for_subscriber: Option<Duration>,
}

impl Default for CellConfig {
    fn default() -> Self {
        Self {
            connect: Vec::new(),
            listen: Vec::new(),
            domain: 0,
            namespace: "/".to_owned(),
            node: "rl".to_owned(),
            decimation: 1,
            period: Duration::from_millis(1),
            limits: Limits::default(),
            capacity: 1 << 14,
            wait_for_subscriber: None,
        }
    }
}

impl CellConfig {
    /// Checks names and endpoints and returns them normalised.
    pub fn checked(mut self) -> Result<Self, CellError> {
        self.namespace = names::namespace(&self.namespace)?;
        self.node = names::node_name(&self.node)?;
        self.connect = self
            .connect
            .iter()
            .map(|e| endpoint(e))
            .collect::<Result<_, _>>()?;
        self.listen = self
            .listen
            .iter()
            .map(|e| endpoint(e))
            .collect::<Result<_, _>>()?;
        if self.decimation == 0 {
            return Err(CellError::Config("decimation must be at least 1".into()));
        }
        if self.period.is_zero() {
            return Err(CellError::Config("the loop period must be positive".into()));
        }
        if self.domain > 232 {
            return Err(CellError::Config(format!(
                "ROS domain {} is out of range (0 to 232)",
                self.domain
            )));
        }
        Ok(self)
    }

    /// The Zenoh configuration: a peer, multicast scouting off, these endpoints only.
    pub fn zenoh(&self) -> Result<zenoh::Config, CellError> {
        zenoh_config(&self.connect, &self.listen)
    }

    /// The fully qualified name of a topic of this cell.
    pub fn topic(&self, relative: &str) -> Result<String, CellError> {
        Ok(names::topic(&self.namespace, relative)?)
    }
}

/// Batches each link's data queue holds before a `Drop` publication is dropped (Zenoh's default
/// is 2, with 1 ms of waiting for a free one): 1 kHz joint states (two messages a cycle, each its
/// own batch as they are `express`) ride out a send thread kept off its CPU for ~8 ms, as on a
/// loaded 2-core controller. 16 is Zenoh's maximum (a larger value and no link opens). Memory:
/// 16 × the batch size (64 KiB) per link.
pub const TX_DATA_QUEUE_BATCHES: usize = 16;

/// A peer's Zenoh configuration for these endpoints (multicast scouting off, a data queue of
/// [`TX_DATA_QUEUE_BATCHES`], nothing else).
pub fn zenoh_config(connect: &[String], listen: &[String]) -> Result<zenoh::Config, CellError> {
    let list = |v: &[String]| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
    let json = format!(
        "{{mode: \"peer\", connect: {{endpoints: {}}}, listen: {{endpoints: {}}}, \
         scouting: {{multicast: {{enabled: false}}}}}}",
        list(connect),
        list(listen)
    );
    let mut config = zenoh::Config::from_json5(&json)
        .map_err(|e| CellError::Config(format!("zenoh config: {e}")))?;
    config
        .insert_json5(
            "transport/link/tx/queue/size/data",
            &TX_DATA_QUEUE_BATCHES.to_string(),
        )
        .map_err(|e| CellError::Config(format!("zenoh config: {e}")))?;
    Ok(config)
}

/// Nanoseconds since the UNIX epoch now (the clock ROS stamps use).
pub fn unix_now_ns() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoints_default_to_tcp_and_loopback() {
        assert_eq!(endpoint("7447").ok().as_deref(), Some("tcp/127.0.0.1:7447"));
        assert_eq!(
            endpoint("10.0.0.2:7447").ok().as_deref(),
            Some("tcp/10.0.0.2:7447")
        );
        assert_eq!(
            endpoint("udp/127.0.0.1:7447").ok().as_deref(),
            Some("udp/127.0.0.1:7447")
        );
        assert!(endpoint("quic/127.0.0.1:7447").is_err());
        assert!(endpoint("tcp/nohost").is_err());
        let c = CellConfig {
            namespace: "arm1".into(),
            connect: vec!["7447".into()],
            ..CellConfig::default()
        }
        .checked()
        .expect("valid");
        assert_eq!(c.namespace, "/arm1");
        assert_eq!(
            c.topic("joint_states").ok().as_deref(),
            Some("/arm1/joint_states")
        );
        assert!(c.zenoh().is_ok());
    }
}
