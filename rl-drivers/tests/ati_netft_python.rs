//! Our fake Net F/T read by clients not written here: PyPI `pynetft` 2.1.3 (the calibration
//! from `netftapi2.xml` over HTTP, RDT streaming, its own counts of lost, repeated and
//! out-of-order records) and PyPI `netft` 2.0.1 (RDT counts). The wrench they read is the one
//! injected, in their units; the faults the fake injected are the ones pynetft counts; their
//! bias request reaches the fake. Without the venv of `scripts/test` it prints `SKIPPED`.

#[path = "devices/python.rs"]
mod python;

use std::io::{BufRead, BufReader, Write};
use std::net::{IpAddr, Ipv4Addr};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use rl_drivers::fake::netft_sensor::{FakeNetFt, FakeNetFtConfig};
use rl_drivers::proto::netft::{Calibration, ForceUnit, RDT_PORT, TorqueUnit};

/// A loopback address of this test's own, so `netft` (which always uses port 49152) finds the
/// fake there without colliding with anything else on 127.0.0.1.
const HOST: Ipv4Addr = Ipv4Addr::new(127, 0, 0, 93);

#[test]
fn pynetft_and_netft_read_our_fake_sensor() {
    let python = match python::python_with(&["pynetft", "NetFT"]) {
        Ok(p) => p,
        Err(why) => {
            println!("SKIPPED: pynetft_and_netft_read_our_fake_sensor: {why}");
            return;
        }
    };
    let calibration = Calibration {
        counts_per_force: 1_000_000,
        counts_per_torque: 1_000_000,
        force_unit: ForceUnit::Newton,
        torque_unit: TorqueUnit::NewtonMetre,
        scale_factors: [1; 6],
    };
    let config = FakeNetFtConfig {
        bind: IpAddr::V4(HOST),
        rdt_port: RDT_PORT,
        tcp_port: Some(0),
        http_port: Some(0),
        calibration,
        rdt_rate_hz: 1000,
        ..FakeNetFtConfig::loopback()
    };
    // Port 49152 on this address may be taken by an earlier run's leftover: then a free port
    // (the `netft` part is left out; pynetft takes any port).
    let fake = FakeNetFt::spawn(config.clone())
        .or_else(|_| {
            FakeNetFt::spawn(FakeNetFtConfig {
                rdt_port: 0,
                ..config
            })
        })
        .expect("fake sensor");
    let wrench = [1.5, -2.0, 10.0, 0.1, -0.2, 0.3];
    fake.set_wrench(wrench);
    let mut child = Command::new(&python)
        .arg(python::script("netft_check.py"))
        .arg(HOST.to_string())
        .arg(fake.rdt_addr().port().to_string())
        .arg(fake.http_addr().unwrap().port().to_string())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("python");
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut line = String::new();
    out.read_line(&mut line).unwrap();
    assert_eq!(line.trim(), "ready", "pynetft did not start streaming");
    // Faults while pynetft streams: 4 records lost, 2 pairs swapped, 3 repeated.
    let before = fake.status();
    fake.drop_records(4);
    fake.reorder_pairs(2);
    fake.duplicate_records(3);
    let end = Instant::now() + Duration::from_secs(3);
    loop {
        let s = fake.status();
        if s.dropped - before.dropped == 4
            && s.reordered - before.reordered == 2
            && s.duplicated - before.duplicated == 3
        {
            break;
        }
        assert!(Instant::now() < end, "the fake did not inject: {s:?}");
        std::thread::sleep(Duration::from_millis(5));
    }
    let mut stdin = child.stdin.take().unwrap();
    writeln!(stdin, "go").unwrap();
    line.clear();
    out.read_line(&mut line).unwrap();
    let v: serde_json::Value = serde_json::from_str(&line).expect("json");
    println!("{v:#}");
    // A new load for `netft`'s record: counts of (new load − the load biased away).
    let load = [0.0, 0.0, -5.0, 0.0, 0.25, 0.0];
    fake.set_wrench(load);
    std::thread::sleep(Duration::from_millis(20));
    writeln!(stdin, "go").unwrap();
    line.clear();
    out.read_line(&mut line).unwrap();
    assert!(child.wait().unwrap().success(), "netft_check.py failed");
    let n: serde_json::Value = serde_json::from_str(&line).expect("json");

    // The calibration, read by pynetft over HTTP.
    assert_eq!(v["calibration"]["counts_per_force"], 1_000_000.0);
    assert_eq!(v["calibration"]["counts_per_torque"], 1_000_000.0);
    assert_eq!(v["calibration"]["force_unit"], "N");
    assert_eq!(v["calibration"]["torque_unit"], "N-m");
    // The injected wrench, in N and N·m.
    for key in ["first_wrench", "loaded_wrench"] {
        let got: Vec<f64> = serde_json::from_value(v[key].clone()).unwrap();
        for (g, w) in got.iter().zip(wrench) {
            assert!((g - w).abs() < 1e-6, "{key}: {got:?}");
        }
    }
    // pynetft's bias request reached the fake, and zeroed what it read.
    assert_eq!(fake.status().biases, 1);
    let biased: Vec<f64> = serde_json::from_value(v["biased_wrench"].clone()).unwrap();
    assert!(biased.iter().all(|x| x.abs() < 1e-6), "{biased:?}");
    // What pynetft counted is what the fake injected.
    let h = &v["health"];
    assert_eq!(h["state"], "streaming");
    assert_eq!(h["fault_code"], "none");
    assert_eq!(h["malformed_count"], 0);
    assert_eq!(h["device_error_count"], 0);
    assert_eq!(h["duplicate_count"], 3, "{h}");
    assert_eq!(h["out_of_order_count"], 2, "{h}");
    // A swapped pair shows as a gap before the late record comes: pynetft counts the 4
    // dropped plus the 2 it saw late as lost, exactly as our driver does.
    assert_eq!(h["lost_count"], 4 + 2, "{h}");
    // `netft` (fixed port 49152): one record of counts (1e6 per N and per N·m).
    if fake.rdt_addr().port() == RDT_PORT {
        let counts: Vec<i64> = serde_json::from_value(n["counts"].clone()).unwrap();
        let expected: Vec<i64> = load
            .iter()
            .zip(wrench)
            .map(|(l, w)| ((l - w) * 1e6).round() as i64)
            .collect();
        assert_eq!(counts, expected);
    } else {
        println!("note: port {RDT_PORT} on {HOST} was taken; the `netft` part did not run");
    }
}
