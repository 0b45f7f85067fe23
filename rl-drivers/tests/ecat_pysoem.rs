//! A master not written here against our fake segment: pysoem (PyPI `pysoem`, SOEM inside) on
//! the other end of a veth pair finds our devices with the names and identities of our SII
//! images, maps their PDOs, reaches OP with distributed clocks and exchanges process data with
//! the working counter it expects, and enables and moves our CiA 402 axes.
//!
//! pysoem comes from a virtual environment under `target/` that this test (or scripts/test)
//! creates with pip; needs root for the namespace. Without root, or when pip cannot install
//! pysoem, the test prints SKIPPED with the reason.

mod support;

use std::path::PathBuf;
use std::process::Command;

use rl_drivers::fake::ecat_segment::description::{FAKE_DRIVE_PRODUCT, FAKE_VENDOR_ID};
use rl_drivers::fake::ecat_segment::{FakeSegment, FakeSegmentConfig};
use support::netns::veth_or_skip;
use support::stall::{Canary, STALL, emulated, unless_stalled};

/// The pysoem version the checks were made with.
pub const PYSOEM: &str = "pysoem==1.1.13";

fn venv() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/pysoem-venv")
}

/// The venv's python with pysoem, installing it if needed; `Err` says why not.
pub fn python() -> Result<PathBuf, String> {
    let py = venv().join("bin/python");
    let has = |py: &PathBuf| {
        Command::new(py)
            .args(["-c", "import pysoem"])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if has(&py) {
        return Ok(py);
    }
    let run = |c: &mut Command| -> Result<(), String> {
        let o = c.output().map_err(|e| format!("{c:?}: {e}"))?;
        if o.status.success() {
            Ok(())
        } else {
            Err(format!(
                "{c:?}: {}",
                String::from_utf8_lossy(&o.stderr).trim()
            ))
        }
    };
    run(Command::new("python3").args(["-m", "venv"]).arg(venv()))?;
    run(Command::new(venv().join("bin/pip")).args(["install", "-q", PYSOEM]))?;
    if has(&py) {
        Ok(py)
    } else {
        Err("pysoem installed but does not import".into())
    }
}

#[test]
fn pysoem_configures_our_fake_segment_and_exchanges_process_data() {
    let Some(veth) = veth_or_skip("pysoem_configures_our_fake_segment") else {
        return;
    };
    let py = match python() {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: pysoem_configures_our_fake_segment: pysoem unavailable: {why}");
            return;
        }
    };
    unless_stalled("pysoem_configures_our_fake_segment", || {
        let mut c = FakeSegmentConfig::drives(&veth.b, 3);
        c.on_thread_start = Some(support::realtime_fake);
        let fake = veth.enter(|| FakeSegment::spawn(c)).expect("fake segment");
        let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/peers/pysoem_check.py");
        let canary = Canary::start();
        let out = veth
            .command(py.to_str().unwrap())
            .arg(&script)
            .arg(&veth.a)
            .args(["--dc", "--cycles", "600"])
            .output()
            .expect("run pysoem");
        let stalled = canary.worst();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "pysoem failed: {stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let r: serde_json::Value =
            serde_json::from_str(stdout.trim()).expect("JSON from the script");
        println!("pysoem: {r}");
        assert_eq!(r["found"], 3);
        for d in r["devices"].as_array().unwrap() {
            assert_eq!(d["name"], "rl-rs CiA 402 axis");
            assert_eq!(d["vendor"], FAKE_VENDOR_ID);
            assert_eq!(d["product"], FAKE_DRIVE_PRODUCT);
            assert_eq!(d["revision"], 1);
        }
        assert_eq!(r["dc"], true);
        assert_eq!(
            r["sizes"],
            serde_json::json!([[16, 16], [16, 16], [16, 16]])
        );
        assert_eq!(r["expected_wkc"], 9);
        assert_eq!(r["safeop"], true);
        assert_eq!(r["op"], true);
        // A frame that came back with a count other than SOEM's expected one is the fake's
        // fault whatever the machine did; a frame that did not come back within SOEM's 2 ms
        // (a count of 0 or less) is the fake's fault unless the machine stalled.
        let wrong = r["wkc_wrong"].as_array().unwrap();
        let miscounted: Vec<_> = wrong
            .iter()
            .filter(|w| w["wkc"].as_i64() > Some(0))
            .collect();
        assert!(
            miscounted.is_empty(),
            "wrong working counters: {miscounted:?}"
        );
        // Under an emulator the fake's code is translated as it first runs and its frames can
        // miss SOEM's 2 ms: counted and reported, not bounded (as ecat_units does).
        // (A clean-clone CI run under qemu-arm: one frame back after 7 ms, reported, then
        // failed by the bound below, which the emulated case had skipped only in intent.)
        if let Some(emulator) = emulated() {
            println!(
                "under {emulator}: {} of 600 frames not back within 2 ms: {wrong:?}",
                wrong.len()
            );
        } else {
            if !wrong.is_empty() && stalled >= STALL {
                return Err(format!(
                    "{} of 600 frames not back within 2 ms ({wrong:?}) while the machine \
                     stalled a thread {stalled:?}",
                    wrong.len()
                ));
            }
            assert_eq!(
                r["wkc_errors"], 0,
                "frames lost with no stall ({stalled:?}): {wrong:?}"
            );
        }
        for (k, sw) in r["statusword"].as_array().unwrap().iter().enumerate() {
            assert_eq!(
                sw.as_u64().unwrap() & 0x6F,
                0x27,
                "drive {k} operation enabled"
            );
        }
        for m in r["moved"].as_array().unwrap() {
            assert!(
                m.as_i64().unwrap() > 50_000,
                "the axes followed SOEM's targets: {m}"
            );
        }
        let st = fake.status();
        assert!(
            st.iter().all(|s| s.dc_mode),
            "SOEM's SYNC0 drove the axes: {st:?}"
        );
        Ok(())
    });
}
