//! A recorded exchange between our master and the fake drives, written as a pcap with the
//! SocketCAN link type, decodes in Wireshark's CANopen dissector (tshark, a dissector not
//! written here) with the meanings our codec gives each frame: NMT commands, SDO requests and
//! responses with their objects, SYNC, PDOs, heartbeats with their NMT states, and an EMCY with
//! its error code. The same exchange is written as a candump log and read back. Without tshark
//! the dissector part prints SKIPPED and passes.

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use rl_drivers::canopen::{Cia402, Cia402Config};
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config, FakeFault};
use rl_drivers::proto::can::candump;
use rl_drivers::proto::canopen::emcy::Emergency;
use rl_drivers::proto::canopen::sdo::Request;
use rl_drivers::proto::canopen::{Function, heartbeat, nmt};
use rl_drivers::transport::can::CanAddress;
use rl_drivers::transport::can::bus::Bus;
use rl_drivers::transport::can::record::{CandumpLog, PcapLog, Recording};
use rl_drivers::{CyclicDevice, Device};

fn out_dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("canopen_pcap");
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Records a session: open, start, 30 cycles with heartbeats, a drive fault (EMCY), stop.
fn record() -> (PathBuf, PathBuf) {
    let dir = out_dir();
    let (pcap, log) = (dir.join("session.pcap"), dir.join("session.log"));
    let bus = Bus::new();
    let mut fc = FakeCia402Config::new(&[1, 2]).unwrap();
    fc.sync_loss_periods = 10;
    let fake = FakeCia402::on_transport(fc, Box::new(bus.endpoint())).unwrap();
    let link = Recording::new(
        bus.endpoint(),
        Some(PcapLog::create(&pcap).unwrap()),
        Some(CandumpLog::create(&log, "can0").unwrap()),
    );
    let mut config = Cia402Config::new(CanAddress::parse("socketcan://can0").unwrap(), &[1, 2])
        .with_period(Duration::from_millis(10));
    config.sdo_timeout = Duration::from_millis(200);
    config.heartbeat_ms = 20;
    let mut dev = Cia402::with_transport(config, Box::new(link)).unwrap();
    dev.open().unwrap();
    dev.start().unwrap();
    for k in 0..30 {
        if k == 20 {
            fake.inject(FakeFault::DriveFault {
                node: 2,
                code: 0x2310,
            });
        }
        let _ = dev.step();
        std::thread::sleep(Duration::from_millis(10));
    }
    let _ = dev.stop();
    dev.close().unwrap();
    drop(dev);
    (pcap, log)
}

/// What our codec says a frame is, in the words of Wireshark's column.
fn our_meaning(id: u16, data: &[u8]) -> String {
    match Function::from_cob_id(id) {
        Some(Function::Nmt) => match nmt::Command::decode(data) {
            Some((nmt::Command::Start, _)) => "NMT: Start remote node".into(),
            Some((nmt::Command::EnterPreOperational, _)) => {
                "NMT: Enter pre-operational state".into()
            }
            other => format!("NMT {other:?}"),
        },
        Some(Function::Sync) => "SYNC".into(),
        Some(Function::Emcy(_)) => "EMCY".into(),
        Some(Function::Tpdo(k, _)) => format!("PDO{k} (tx)"),
        Some(Function::Rpdo(k, _)) => format!("PDO{k} (rx)"),
        Some(Function::SdoRx(_)) => match Request::decode(data) {
            Ok(Request::UploadInitiate { .. }) => {
                "Default-SDO (rx): Initiate upload request".into()
            }
            Ok(Request::DownloadExpedited { .. } | Request::DownloadInitiate { .. }) => {
                "Default-SDO (rx): Initiate download request".into()
            }
            Ok(Request::UploadSegment { .. }) => "Default-SDO (rx): Upload segment request".into(),
            Ok(Request::DownloadSegment { .. }) => {
                "Default-SDO (rx): Download segment request".into()
            }
            other => format!("SDO {other:?}"),
        },
        Some(Function::SdoTx(_)) => "Default-SDO (tx)".into(),
        Some(Function::Heartbeat(_)) => match heartbeat::decode(data) {
            Some(nmt::State::BootUp) => "Boot-up".into(),
            Some(_) => "Heartbeat".into(),
            None => "heartbeat?".into(),
        },
        other => format!("{other:?}"),
    }
}

#[test]
fn a_recorded_session_decodes_in_wiresharks_canopen_dissector() {
    let (pcap, log) = record();
    // The candump log: every line parses, and says what the pcap says.
    let text = std::fs::read_to_string(&log).unwrap();
    let frames: Vec<_> = text
        .lines()
        .map(|l| candump::parse_line(l).unwrap().frame)
        .collect();
    assert!(frames.len() > 100, "{} frames", frames.len());
    let tshark = match Command::new("tshark").arg("--version").output() {
        Ok(o) if o.status.success() => "tshark",
        _ => {
            println!(
                "SKIPPED: no tshark (apt-get install tshark); the pcap is {}",
                pcap.display()
            );
            return;
        }
    };
    let out = Command::new(tshark)
        .arg("-r")
        .arg(&pcap)
        .args([
            "-d",
            "can.subdissector,canopen",
            "-T",
            "fields",
            "-E",
            "separator=|",
        ])
        .args([
            "-e",
            "can.id",
            "-e",
            "canopen.sdo.main_idx",
            "-e",
            "canopen.nmt_guard.state",
        ])
        .args(["-e", "canopen.em.err_code", "-e", "_ws.col.Info"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Vec<Vec<String>> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.split('|').map(str::to_owned).collect())
        .collect();
    assert_eq!(
        rows.len(),
        frames.len(),
        "the pcap and the candump log hold the same frames"
    );
    let mut seen = std::collections::BTreeSet::new();
    let mut emcy_codes = Vec::new();
    for (row, frame) in rows.iter().zip(&frames) {
        let id = frame.standard_id().unwrap();
        assert_eq!(row[0].parse::<u32>().unwrap(), u32::from(id), "{row:?}");
        let ours = our_meaning(id, frame.bytes());
        let info = &row[4];
        assert!(
            info.starts_with(&ours)
                || (ours == "Heartbeat" || ours == "Boot-up") && info.contains("NMT Error Control"),
            "frame {frame}: Wireshark says `{info}`, we say `{ours}`"
        );
        match Function::from_cob_id(id) {
            Some(Function::SdoRx(_))
                if !frame.bytes().is_empty()
                    && frame.bytes()[0] & 0xE0 != 0
                    && frame.bytes()[0] & 0xE0 != 0x60 =>
            {
                let index = u16::from_le_bytes([frame.bytes()[1], frame.bytes()[2]]);
                assert_eq!(row[1], format!("0x{index:04x}"), "SDO index of {frame}");
            }
            Some(Function::Heartbeat(_)) => {
                let state = u32::from(frame.bytes()[0] & 0x7F);
                assert_eq!(
                    row[2],
                    format!("0x{state:02x}"),
                    "heartbeat state of {frame}"
                );
            }
            Some(Function::Emcy(_)) => {
                let e = Emergency::decode(frame.bytes()).unwrap();
                assert_eq!(row[3], format!("0x{:04x}", e.code), "EMCY code of {frame}");
                emcy_codes.push(e.code);
            }
            _ => {}
        }
        seen.insert(
            ours.split(':')
                .next()
                .unwrap_or("")
                .split(' ')
                .next()
                .unwrap_or("")
                .to_owned(),
        );
    }
    for kind in ["NMT", "Default-SDO", "SYNC", "PDO1", "Heartbeat", "EMCY"] {
        assert!(seen.contains(kind), "no {kind} in the recording: {seen:?}");
    }
    assert!(
        emcy_codes.contains(&0x2310),
        "the injected fault's EMCY: {emcy_codes:x?}"
    );
}
