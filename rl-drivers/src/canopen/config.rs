//! How a [`Cia402`](super::Cia402) device is set up: the bus, the axes (node ids and units),
//! the mode, the cycle, the bounds on every wait, and the PDO layout that follows from them.

use std::sync::Arc;
use std::time::Duration;

use super::bus_load::BusLoad;
use crate::cia402::{Mode, UnitsOverride, object as obj};
use crate::proto::canopen::eds::Eds;
use crate::proto::canopen::pdo::Mapping;
use crate::transport::can::CanAddress;

/// Most axes one device drives.
pub const MAX_AXES: usize = 8;

/// One axis: a drive's node id and its units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisConfig {
    /// Node id (1..=127).
    pub node: u8,
    /// The units the user gives; the rest are read from the drive at `open` (0x608F, 0x6091,
    /// 0x6092, 0x6076), and a drive that cannot give them is refused before it is enabled.
    pub units: UnitsOverride,
    /// This node's heartbeat consumer time, if it differs from
    /// [`Cia402Config::heartbeat_timeout`].
    pub heartbeat_timeout: Option<Duration>,
}

/// The device's configuration.
#[derive(Clone, Debug)]
pub struct Cia402Config {
    /// The bus.
    pub bus: CanAddress,
    /// The axes, in joint order.
    pub axes: Vec<AxisConfig>,
    /// The mode of operation (CSP, CSV or CST).
    pub mode: Mode,
    /// The control period: one SYNC per step.
    pub period: Duration,
    /// The CAN bit rate, for the bus budget (1 Mbit/s).
    pub bitrate: u32,
    /// How long after its SYNC a step waits for the TPDOs (default: 80 % of the period).
    pub tpdo_timeout: Duration,
    /// Each node's heartbeat producer time written to 0x1017 (ms; 0: none).
    pub heartbeat_ms: u16,
    /// Heartbeat consumer time: a node is lost after this long without one (default 3 × the
    /// producer time); an axis may set its own ([`AxisConfig::heartbeat_timeout`]).
    pub heartbeat_timeout: Duration,
    /// Bound on one SDO answer.
    pub sdo_timeout: Duration,
    /// Bound on each power state transition in start and stop.
    pub transition_timeout: Duration,
    /// Bound on connecting.
    pub connect_timeout: Duration,
    /// Failed steps in a row that fault the device.
    pub max_consecutive_failures: u32,
    /// Map the torque offset (0x60B2) into the RPDO in CSP and CSV (feed-forward torque).
    pub torque_feed_forward: bool,
    /// Map the velocity actual value (0x606C) into a second TPDO.
    pub velocity_feedback: bool,
    /// Reset a drive's fault in `start` (rising edge of controlword bit 7).
    pub reset_faults_on_start: bool,
    /// The nodes' dictionary: every mapping and write is checked against it first.
    pub eds: Option<Arc<Eds>>,
}

impl Cia402Config {
    /// `nodes` in CSP at 2 ms on 1 Mbit/s with the units read from the drives, heartbeats
    /// every 50 ms, 20 ms SDO answers, 1 s transitions, torque feed-forward mapped.
    pub fn new(bus: CanAddress, nodes: &[u8]) -> Self {
        let period = Duration::from_millis(2);
        Self {
            bus,
            axes: nodes
                .iter()
                .map(|&node| AxisConfig {
                    node,
                    units: UnitsOverride::NONE,
                    heartbeat_timeout: None,
                })
                .collect(),
            mode: Mode::CyclicPosition,
            period,
            bitrate: 1_000_000,
            tpdo_timeout: period * 4 / 5,
            heartbeat_ms: 50,
            heartbeat_timeout: Duration::from_millis(150),
            sdo_timeout: Duration::from_millis(20),
            transition_timeout: Duration::from_secs(1),
            connect_timeout: Duration::from_secs(2),
            max_consecutive_failures: 10,
            torque_feed_forward: true,
            velocity_feedback: false,
            reset_faults_on_start: true,
            eds: None,
        }
    }

    /// Sets the period and the TPDO wait (80 % of it).
    pub fn with_period(mut self, period: Duration) -> Self {
        self.period = period;
        self.tpdo_timeout = period * 4 / 5;
        self
    }

    /// The RPDO1 mapping for the mode. (The layouts here hold at most 8 bytes by
    /// construction, so `Mapping::new` cannot refuse them.)
    pub fn rpdo_mapping(&self) -> Mapping {
        let target = match self.mode {
            Mode::CyclicVelocity => obj::TARGET_VELOCITY,
            Mode::CyclicTorque => obj::TARGET_TORQUE,
            _ => obj::TARGET_POSITION,
        };
        let mut entries = vec![obj::CONTROLWORD.entry(), target.entry()];
        if self.torque_feed_forward && self.mode != Mode::CyclicTorque {
            entries.push(obj::TORQUE_OFFSET.entry());
        }
        Mapping::new(&entries).unwrap_or_default()
    }

    /// The TPDO1 mapping: statusword, position and torque actual values.
    pub fn tpdo1_mapping(&self) -> Mapping {
        Mapping::new(&[
            obj::STATUSWORD.entry(),
            obj::POSITION_ACTUAL.entry(),
            obj::TORQUE_ACTUAL.entry(),
        ])
        .unwrap_or_default()
    }

    /// The TPDO2 mapping (velocity actual value), if configured.
    pub fn tpdo2_mapping(&self) -> Option<Mapping> {
        self.velocity_feedback
            .then(|| Mapping::new(&[obj::VELOCITY_ACTUAL.entry()]).unwrap_or_default())
    }

    /// The bus load of one cycle.
    pub fn bus_load(&self) -> BusLoad {
        let (r, t1) = (self.rpdo_mapping().len(), self.tpdo1_mapping().len());
        let t2 = self.tpdo2_mapping().map(|m| m.len());
        let per_axis = [Some(r), Some(t1), t2];
        BusLoad::of(
            self.axes
                .iter()
                .flat_map(|_| per_axis.iter().flatten().copied()),
            self.bitrate,
        )
    }
}

/// Parses a node list: a range `1-6`, a list `1,3,5`, or both (`1-3,7`); each id 1..=127,
/// none twice, at most [`MAX_AXES`].
pub fn parse_node_list(text: &str) -> Result<Vec<u8>, String> {
    let id = |t: &str| -> Result<u8, String> {
        t.trim()
            .parse::<u8>()
            .ok()
            .filter(|n| (1..=127).contains(n))
            .ok_or_else(|| format!("`{t}` is not a node id 1..=127"))
    };
    let mut nodes = Vec::new();
    for part in text.split(',') {
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (id(a)?, id(b)?);
                if a > b {
                    return Err(format!("range `{part}` runs backwards"));
                }
                nodes.extend(a..=b);
            }
            None => nodes.push(id(part)?),
        }
    }
    let mut sorted = nodes.clone();
    sorted.sort_unstable();
    sorted.dedup();
    if sorted.len() != nodes.len() {
        return Err("a node id appears twice".into());
    }
    if nodes.len() > MAX_AXES {
        return Err(format!("{} nodes; at most {MAX_AXES} axes", nodes.len()));
    }
    Ok(nodes)
}

/// A device address for the tool: a CAN bus address with an optional `nodes=` option, e.g.
/// `cannelloni+udp://127.0.0.1:20000?nodes=1-6` or `socketcan://can0?nodes=1,2`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeviceAddress {
    /// The bus.
    pub bus: CanAddress,
    /// The node ids, if given.
    pub nodes: Option<Vec<u8>>,
}

impl DeviceAddress {
    /// Parses the address (the `nodes=` option may stand with the bus's own options, joined
    /// by `&`).
    pub fn parse(text: &str) -> Result<Self, String> {
        let (base, query) = match text.split_once('?') {
            Some((b, q)) => (b, Some(q)),
            None => (text, None),
        };
        let mut nodes = None;
        let mut rest = Vec::new();
        for option in query.into_iter().flat_map(|q| q.split('&')) {
            match option.strip_prefix("nodes=") {
                Some(list) => {
                    nodes =
                        Some(parse_node_list(list).map_err(|e| format!("`{text}`: nodes: {e}"))?)
                }
                None => rest.push(option),
            }
        }
        let bus_text = if rest.is_empty() {
            base.to_owned()
        } else {
            format!("{base}?{}", rest.join("&"))
        };
        let bus = CanAddress::parse(&bus_text).map_err(|e| e.to_string())?;
        Ok(Self { bus, nodes })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_lists_and_device_addresses() {
        assert_eq!(parse_node_list("1-6").unwrap(), vec![1, 2, 3, 4, 5, 6]);
        assert_eq!(parse_node_list("1-3,7").unwrap(), vec![1, 2, 3, 7]);
        for bad in ["0", "128", "3-1", "1,1", "x", "1-", "", "1-9"] {
            assert!(parse_node_list(bad).is_err(), "{bad}");
        }
        let a = DeviceAddress::parse("cannelloni+tcp://127.0.0.1:9?listen&nodes=2-3").unwrap();
        assert_eq!(a.nodes, Some(vec![2, 3]));
        assert_eq!(
            a.bus,
            CanAddress::CannelloniTcp {
                addr: "127.0.0.1:9".parse().unwrap(),
                listen: true
            }
        );
        let a = DeviceAddress::parse("socketcan://can0").unwrap();
        assert_eq!(a.nodes, None);
        assert!(DeviceAddress::parse("socketcan://can0?nodes=0").is_err());
    }
}
