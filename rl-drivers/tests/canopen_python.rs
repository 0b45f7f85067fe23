//! Independent checks against a CANopen stack not written here: python-canopen (PyPI
//! `canopen`) with python-can and the PyPI interface `can-cannelloni` (a cannelloni TCP
//! client), talking to our cannelloni TCP endpoints.
//!
//! (a) python-canopen as master reads our fake drive's identity and objects by SDO, configures
//! a PDO, and brings it to operation enabled through its `BaseNode402`;
//! (b) our master configures and exchanges PDOs with python-canopen's `LocalNode` loaded from
//! our EDS;
//! (c) python-canopen reads the units our fake drives report (0x608F, 0x6091, 0x6092, 0x6076),
//! and the abort of a drive without them.
//!
//! The Python environment: `RL_CAN_PYTHON` (a python with canopen, python-can and
//! can-cannelloni), else `target/can-peers/bin/python` (what `scripts/test` installs). Without
//! either the tests print SKIPPED and pass.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use rl_drivers::canopen::{Cia402, Cia402Config};
use rl_drivers::cia402::{AxisUnits, PowerState};
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
use rl_drivers::transport::can::CanAddress;
use rl_drivers::{
    CyclicDevice, Device, JointPositionActuator, JointPositionSensor, LinkStatisticsSensor,
};
use serde_json::Value;

fn manifest() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The python with the peers installed, or why there is none.
fn python() -> Result<PathBuf, String> {
    let candidate = match std::env::var_os("RL_CAN_PYTHON") {
        Some(p) => PathBuf::from(p),
        None => manifest().join("../target/can-peers/bin/python"),
    };
    if !candidate.exists() {
        return Err(format!(
            "no python with python-canopen at {} (scripts/test installs it; or set RL_CAN_PYTHON)",
            candidate.display()
        ));
    }
    let ok = Command::new(&candidate)
        .args(["-c", "import canopen, can, can_cannelloni"])
        .status()
        .map_err(|e| format!("{}: {e}", candidate.display()))?;
    if !ok.success() {
        return Err(format!(
            "{} lacks canopen, python-can or can-cannelloni",
            candidate.display()
        ));
    }
    Ok(candidate)
}

fn eds() -> PathBuf {
    manifest().join("data/rl-fake-cia402.eds")
}

fn script(name: &str) -> PathBuf {
    manifest().join("tests/canopen_python").join(name)
}

fn json_of(out: &std::process::Output) -> Value {
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "python failed: {}\nstdout: {stdout}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(stdout.lines().last().unwrap_or(""))
        .unwrap_or_else(|e| panic!("{e}: {stdout}"))
}

#[test]
fn python_canopen_as_master_enables_our_fake_drive() {
    let python = match python() {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: {why}");
            return;
        }
    };
    let mut config = FakeCia402Config::new(&[3]).unwrap();
    config.axes[0].initial = 0.25;
    let fake = FakeCia402::serve(
        config,
        &CanAddress::parse("cannelloni+tcp://127.0.0.1:0").unwrap(),
    )
    .unwrap();
    let addr = fake.local_addr().unwrap();
    let out = Command::new(&python)
        .arg(script("master_402.py"))
        .arg(addr.to_string())
        .arg("3")
        .arg(eds())
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let v = json_of(&out);
    assert_eq!(v["device_type"], 0x0002_0192);
    assert_eq!(v["vendor_id"], 0x0E1D);
    assert_eq!(v["product_code"], 0x0402);
    assert_eq!(v["serial"], 0x5252_0003, "$NODEID in the EDS default");
    assert_eq!(v["device_name"], "rl-rs fake CiA 402 drive");
    assert_eq!(v["supported_modes"], 0x380);
    assert_eq!(v["following_window"], 123_456);
    assert_eq!(v["abort"], 0x0602_0000, "object does not exist");
    assert_eq!(
        v["read_only_abort"], 0x0601_0002,
        "attempt to write a read-only object"
    );
    assert_eq!(
        v["tpdo1_mapping"],
        serde_json::json!([2, 0x6041_0010, 0x6064_0020])
    );
    assert_eq!(v["tpdo1_cob_id"].as_u64().unwrap() & 0x7FF, 0x183);
    assert_eq!(v["state_before"], "SWITCH ON DISABLED");
    assert_eq!(v["state_enabled"], "OPERATION ENABLED");
    assert_eq!(v["statusword_sdo"].as_u64().unwrap() & 0x6F, 0x27);
    assert_eq!(v["state_after"], "SWITCH ON DISABLED");
    let s = fake.status();
    let n = &s.nodes[0];
    assert!(n.counters.syncs > 5 && n.counters.tpdos > 5, "{s:?}");
    assert_eq!(n.power, PowerState::SwitchOnDisabled);
    assert!(
        (n.position - 0.25).abs() < 1e-5,
        "the drive held its position: {}",
        n.position
    );
}

#[test]
fn our_master_drives_python_canopen_s_local_node() {
    let python = match python() {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: {why}");
            return;
        }
    };
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let child = Command::new(&python)
        .arg(script("slave_402.py"))
        .arg(format!("127.0.0.1:{port}"))
        .arg("2")
        .arg(eds())
        .arg("6")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let bus = CanAddress::parse(&format!("cannelloni+tcp://127.0.0.1:{port}?listen")).unwrap();
    // Python answers in its own time: a 50 ms cycle, 500 ms SDO answers, 100 ms heartbeats.
    let mut config = Cia402Config::new(bus, &[2]).with_period(Duration::from_millis(50));
    config.sdo_timeout = Duration::from_millis(500);
    config.connect_timeout = Duration::from_secs(20);
    config.heartbeat_ms = 100;
    config.heartbeat_timeout = Duration::from_millis(400);
    let eds_text = std::fs::read_to_string(eds()).unwrap();
    config.eds = Some(std::sync::Arc::new(
        rl_drivers::proto::canopen::eds::Eds::parse(&eds_text).unwrap(),
    ));
    let mut dev = Cia402::new(config).unwrap();
    dev.open().unwrap_or_else(|e| panic!("open: {e}"));
    let mut q = [0.0];
    dev.joint_position(&mut q).unwrap();
    let per_count = core::f64::consts::TAU / f64::from(1u32 << 20);
    assert!(
        (q[0] - 1234.0 * per_count).abs() < 1e-12,
        "position read by SDO at open: {q:?}"
    );
    dev.start().unwrap_or_else(|e| panic!("start: {e}"));
    let lost_at_start = dev.link_statistics().lost;
    let mut failures = Vec::new();
    for k in 0..40 {
        dev.set_joint_position(&[q[0] + 1000.0 * per_count * f64::from(k)])
            .unwrap();
        if let Err(e) = dev.step() {
            failures.push(e.to_string());
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let mut now = [0.0];
    dev.joint_position(&mut now).unwrap();
    dev.stop().unwrap_or_else(|e| panic!("stop: {e}"));
    dev.close().unwrap();
    let v = json_of(&child.wait_with_output().unwrap());
    assert!(failures.is_empty(), "{failures:?}");
    assert_eq!(dev.link_statistics().lost, lost_at_start);
    assert_eq!(
        v["tpdo1_mapping"],
        serde_json::json!([3, 0x6041_0010, 0x6064_0020, 0x6077_0010])
    );
    assert_eq!(
        v["rpdo1_mapping"],
        serde_json::json!([3, 0x6040_0010, 0x607A_0020, 0x60B2_0010])
    );
    assert_eq!(v["heartbeat_ms"], 100);
    assert_eq!(v["mode"], 8);
    // The power state machine: ready, switched on, enabled; then quick stop and off.
    assert_eq!(
        v["states"],
        serde_json::json!([0x21, 0x23, 0x27, 0x07, 0x40])
    );
    // The drive followed the targets: the last (k = 39) was applied at the next SYNC. What we
    // read after step 39 is two cycles behind (k = 37): an RPDO applies at the SYNC after it,
    // and the TPDO of the SYNC after that reports it.
    let followed = v["position"].as_i64().unwrap();
    assert_eq!(followed, 1234 + 39_000, "{v}");
    assert!(
        (now[0] - (1234.0 + 37_000.0) * per_count).abs() < 1e-12,
        "{now:?}"
    );
    assert!(v["syncs"].as_u64().unwrap() >= 40 && v["rpdos"].as_u64().unwrap() >= 40);
}

#[test]
fn python_canopen_reads_the_units_our_fake_drives_report() {
    let python = match python() {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: {why}");
            return;
        }
    };
    // Node 3: a 12-bit encoder behind a 50.5:1 gear, rated 0.64 N·m, position unit = count;
    // node 4: the same drive without the factor-group objects.
    let mut config = FakeCia402Config::new(&[3, 4]).unwrap();
    for a in &mut config.axes {
        a.units = AxisUnits {
            counts_per_rev: 4096.0,
            gear_ratio: 50.5,
            feed: None,
            lead_m: None,
            rated_torque_nm: 0.64,
        };
    }
    config.axes[1].unit_objects = false;
    let fake = FakeCia402::serve(
        config,
        &CanAddress::parse("cannelloni+tcp://127.0.0.1:0").unwrap(),
    )
    .unwrap();
    let out = Command::new(&python)
        .arg(script("units_402.py"))
        .arg(fake.local_addr().unwrap().to_string())
        .arg(eds())
        .args(["3", "4"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let v = json_of(&out);
    // 50.5 = 505 / 10; 4096 × 50.5 = 206 848 counts per joint revolution.
    assert_eq!(
        v["3"],
        serde_json::json!({
            "0x608f": [4096, 1],
            "0x6091": [505, 10],
            "0x6092": [206_848, 1],
            "0x6076": [640],
        }),
        "{v}"
    );
    assert_eq!(
        v["4"],
        serde_json::json!({
            "0x608f": 0x0602_0000,
            "0x6091": 0x0602_0000,
            "0x6092": 0x0602_0000,
            "0x6076": [640],
        }),
        "object does not exist: {v}"
    );
}
