//! A second master not written here against our fake segment: the ethercrab crate (0.7.1, built
//! as its own small program in tests/peers/ethercrab-check, outside the main build) scans our
//! devices, reads their SII identities, sets up distributed clocks and SYNC0, reaches OP,
//! exchanges process data with the working counter it expects, and enables and moves our
//! CiA 402 axes. Needs root for the namespace and cargo to build the program (crates.io);
//! without either it prints SKIPPED with the reason.

mod support;

use std::collections::HashMap;
use std::path::PathBuf;
use std::process::Command;

use rl_drivers::fake::ecat_segment::description::{FAKE_DRIVE_PRODUCT, FAKE_VENDOR_ID};
use rl_drivers::fake::ecat_segment::{FakeSegment, FakeSegmentConfig};
use support::netns::veth_or_skip;

fn build() -> Result<PathBuf, String> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let manifest = dir.join("tests/peers/ethercrab-check/Cargo.toml");
    let target = dir.join("../target/ethercrab-check");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["build", "--release", "--locked", "--manifest-path"])
        .arg(&manifest)
        .arg("--target-dir")
        .arg(&target)
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "building ethercrab-check failed: {}",
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("")
        ));
    }
    Ok(target.join("release/ethercrab-check"))
}

#[test]
fn ethercrab_configures_our_fake_segment_and_exchanges_process_data() {
    let Some(veth) = veth_or_skip("ethercrab_configures_our_fake_segment") else {
        return;
    };
    let bin = match build() {
        Ok(b) => b,
        Err(why) => {
            println!("SKIPPED: ethercrab_configures_our_fake_segment: {why}");
            return;
        }
    };
    let mut c = FakeSegmentConfig::drives(&veth.b, 3);
    c.on_thread_start = Some(support::realtime_fake);
    let fake = veth.enter(|| FakeSegment::spawn(c)).expect("fake segment");
    let out = veth
        .command(bin.to_str().unwrap())
        .arg(&veth.a)
        .arg("600")
        .output()
        .expect("run ethercrab-check");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    println!("ethercrab:\n{stdout}");
    assert!(
        out.status.success(),
        "ethercrab failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut kv: HashMap<&str, Vec<&str>> = HashMap::new();
    for line in stdout.lines() {
        if let Some((k, v)) = line.split_once('=') {
            kv.entry(k).or_default().push(v);
        }
    }
    assert_eq!(kv["found"], ["3"]);
    let devices = &kv["device"];
    assert_eq!(devices.len(), 3);
    for (k, d) in devices.iter().enumerate() {
        // ethercrab names a device by the SII general category's order string (ETG.2010
        // table 7's OrderIdx), SOEM by its name string; our SII has both.
        assert!(d.contains("name=RL-AXIS-1"), "{d}");
        assert!(d.contains(&format!("vendor={FAKE_VENDOR_ID} ")), "{d}");
        assert!(d.contains(&format!("product={FAKE_DRIVE_PRODUCT} ")), "{d}");
        assert!(d.contains(&format!("serial={} ", 1000 + k)), "{d}");
        assert!(d.contains("dc=Bits64"), "{d}");
    }
    assert_eq!(kv["safeop"], ["true"]);
    assert_eq!(kv["op"], ["true"]);
    assert_eq!(kv["sizes"], ["16,16"; 3]);
    assert_eq!(kv["expected_wkc"], ["9"]);
    assert_eq!(kv["wkc_errors"], ["0"]);
    for d in &kv["drive"] {
        assert!(d.contains("statusword=0x1637"), "operation enabled: {d}");
        let moved: i64 = d.rsplit("moved=").next().unwrap().parse().unwrap();
        assert!(moved > 50_000, "{d}");
    }
    assert_eq!(kv["done"], ["true"]);
    assert!(fake.status().iter().all(|s| s.dc_mode));
}
