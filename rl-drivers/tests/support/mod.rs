//! Helpers shared by the EtherCAT and CiA 402 tests: the real-hardware captures, read with the
//! pcap-file crate (not our code), the privileges some tests need, and drive units unlike any
//! default.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::time::Duration;

pub mod netns;
pub mod stall;

use rl_drivers::cia402::AxisUnits;

/// A 12-bit encoder behind a 121:1 gear, rated 0.64 N·m, position unit = encoder count: units
/// unlike any default.
pub const GEARED_121: AxisUnits = AxisUnits {
    counts_per_rev: 4096.0,
    gear_ratio: 121.0,
    feed: None,
    lead_m: None,
    rated_torque_nm: 0.64,
};

/// A 17-bit encoder behind a 50.5:1 gear, rated 2.4 N·m, scaled by the drive to millidegrees
/// (0x6092 = 360 000 per joint revolution).
pub const MILLIDEGREES: AxisUnits = AxisUnits {
    counts_per_rev: 131_072.0,
    gear_ratio: 50.5,
    feed: Some(360_000.0),
    lead_m: None,
    rated_torque_nm: 2.4,
};

/// The directory of the captures (`tests/data/ecat`).
pub fn capture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/ecat")
}

/// Every capture file, sorted by name.
pub fn captures() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(capture_dir())
        .expect("tests/data/ecat")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "pcapng"))
        .collect();
    v.sort();
    v
}

/// One captured packet: its time stamp and bytes.
pub struct Packet {
    /// Time stamp as the file gives it.
    pub time: Duration,
    /// The bytes (Ethernet frame without FCS).
    pub data: Vec<u8>,
}

/// The packets of a pcapng file, in order (frame number = index + 1).
pub fn read_pcapng(path: &Path) -> Vec<Packet> {
    use pcap_file::pcapng::blocks::interface_description::InterfaceDescriptionOption;
    use pcap_file::pcapng::{Block, PcapNgReader};
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = PcapNgReader::new(std::io::BufReader::new(file)).expect("pcapng header");
    let mut out = Vec::new();
    // The time stamp unit of each interface (if_tsresol; 10^-6 s when absent): pcap-file
    // returns the raw stamps as if they were nanoseconds.
    let mut resolutions: Vec<u8> = Vec::new();
    while let Some(block) = reader.next_block() {
        match block.unwrap_or_else(|e| panic!("{}: {e}", path.display())) {
            Block::InterfaceDescription(i) => resolutions.push(
                i.options
                    .iter()
                    .find_map(|o| match o {
                        InterfaceDescriptionOption::IfTsResol(r) => Some(*r),
                        _ => None,
                    })
                    .unwrap_or(6),
            ),
            Block::EnhancedPacket(p) => {
                let resol = resolutions
                    .get(p.interface_id as usize)
                    .copied()
                    .unwrap_or(6);
                let raw = p.timestamp.as_nanos();
                let ns = if resol & 0x80 == 0 {
                    let e = u32::from(resol);
                    if e <= 9 {
                        raw * 10u128.pow(9 - e)
                    } else {
                        raw / 10u128.pow(e - 9)
                    }
                } else {
                    // 2^-n s.
                    (raw * 1_000_000_000) >> u32::from(resol & 0x7F).min(127)
                };
                out.push(Packet {
                    time: Duration::from_nanos(ns as u64),
                    data: p.data.into_owned(),
                });
            }
            Block::SimplePacket(p) => out.push(Packet {
                time: Duration::ZERO,
                data: p.data.into_owned(),
            }),
            _ => {}
        }
    }
    out
}

/// Gives the calling thread SCHED_FIFO `priority` when the process may (root), so that the
/// 1 ms exchanges of a test are not delayed by other programs on a shared machine; without
/// the privilege it stays a normal thread.
pub fn realtime(priority: i32) {
    let _ = rl_rt::RtThreadBuilder::new("ecat-test")
        .policy(rl_rt::Policy::Fifo)
        .priority(priority)
        .best_effort(true)
        .apply_to_current();
}

/// [`realtime`] at 80, for the fake segment's thread.
pub fn realtime_fake() {
    realtime(80);
}

/// Whether the process runs as root (raw sockets and network namespaces need it).
pub fn is_root() -> bool {
    // SAFETY-free: geteuid through libc's safe wrapper in nix is not a dev-dependency, so ask
    // the kernel through /proc.
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("Uid:"))
                .and_then(|l| l.split_whitespace().nth(2).map(|u| u == "0"))
        })
        .unwrap_or(false)
}
