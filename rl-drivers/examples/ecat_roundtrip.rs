//! The EtherCAT round trip on a veth pair, ours against pysoem's, alternating in one run: a fake
//! segment of 3 CiA 402 drives (in this process, real-time priority), then in each round our
//! master (`EthercatDrives::step`: one frame with the LRW of the image, the FRMW of the
//! reference clock and a BRD of AL status) and pysoem (`send_processdata` +
//! `receive_processdata`: the LRW and the FRMW) each run `CYCLES` cycles at 1 ms on the same
//! process image (the drives' own 16 + 16 byte mapping, distributed clocks on). Prints the
//! median and 99th percentile of each round trip, our step's CPU time, and the ratio.
//!
//! Needs root and an interface pair inside a namespace; `scripts/bench-ethercat` makes them and
//! runs this. Usage: ecat_roundtrip MASTER_IF SEGMENT_IF PYTHON [ROUNDS] [CYCLES]
//! (run inside the namespace).

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use nix::time::{ClockId, clock_gettime};
use rl_drivers::ethercat::{EthercatConfig, EthercatDrives};
use rl_drivers::fake::ecat_segment::{FakeSegment, FakeSegmentConfig};
use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};

fn realtime(priority: i32) {
    let _ = rl_rt::RtThreadBuilder::new("ecat-bench")
        .policy(rl_rt::Policy::Fifo)
        .priority(priority)
        .best_effort(true)
        .apply_to_current();
}

fn fake_thread() {
    realtime(80);
}

fn cpu_ns() -> u64 {
    clock_gettime(ClockId::CLOCK_THREAD_CPUTIME_ID).map_or(0, |t| {
        t.tv_sec() as u64 * 1_000_000_000 + t.tv_nsec() as u64
    })
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// Our master: open, start, `cycles` timed steps, stop, close. Returns round trips and CPU
/// times in µs.
fn ours(interface: &str, cycles: usize) -> (Vec<f64>, Vec<f64>, u64) {
    let mut c = EthercatConfig::new(interface);
    c.explicit_pdo = false; // the drives' own mapping, as SOEM uses it
    c.dc_static_frames = 200;
    c.frame_timeout = Duration::from_micros(900);
    let mut d = EthercatDrives::new(c).expect("config");
    d.open().expect("open");
    d.start().expect("start");
    let mut q = vec![0.0; 3];
    d.joint_position(&mut q).expect("position");
    let (mut rtt, mut cpu, mut failed) = (Vec::new(), Vec::new(), 0);
    let mut next = Instant::now();
    for _ in 0..cycles {
        d.set_joint_position(&q).expect("set");
        let (t0, c0) = (Instant::now(), cpu_ns());
        if d.step().is_err() {
            failed += 1;
        }
        let (c1, t1) = (cpu_ns(), Instant::now());
        rtt.push((t1 - t0).as_secs_f64() * 1e6);
        cpu.push((c1 - c0) as f64 / 1e3);
        next += Duration::from_millis(1);
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
    }
    d.stop().expect("stop");
    d.close().expect("close");
    (rtt, cpu, failed)
}

/// pysoem: the script's per-cycle round trips in µs.
fn pysoem(python: &str, interface: &str, cycles: usize) -> (Vec<f64>, u64) {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/peers/pysoem_check.py");
    let out = Command::new(python)
        .arg(script)
        .arg(interface)
        .args(["--dc", "--bench", &cycles.to_string()])
        .output()
        .expect("run pysoem");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "pysoem: {text} {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_str(text.trim()).expect("JSON");
    let rtt = v["rtt_us"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    (rtt, v["wkc_errors"].as_u64().unwrap())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (master_if, segment_if, python) = (&args[1], &args[2], &args[3]);
    let rounds: usize = args.get(4).map_or(5, |s| s.parse().unwrap());
    let cycles: usize = args.get(5).map_or(2000, |s| s.parse().unwrap());
    let mut c = FakeSegmentConfig::drives(segment_if, 3);
    c.on_thread_start = Some(fake_thread);
    let fake = FakeSegment::spawn(c).expect("fake segment");
    realtime(70);
    let (mut all_ours, mut all_cpu, mut all_py) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..rounds {
        let (mut rtt, mut cpu, failed) = ours(master_if, cycles);
        let (mut py, bad) = pysoem(python, master_if, cycles);
        println!(
            "round {r}: ours median {:.1} µs p99 {:.1} µs (step CPU median {:.2} µs, {failed} failed) | pysoem median {:.1} µs p99 {:.1} µs ({bad} wkc errors)",
            percentile(&mut rtt, 0.5),
            percentile(&mut rtt, 0.99),
            percentile(&mut cpu, 0.5),
            percentile(&mut py, 0.5),
            percentile(&mut py, 0.99),
        );
        all_ours.extend(rtt);
        all_cpu.extend(cpu);
        all_py.extend(py);
    }
    let (o, p) = (percentile(&mut all_ours, 0.5), percentile(&mut all_py, 0.5));
    println!(
        "all: ours median {o:.1} µs p99 {:.1} µs, step CPU median {:.2} µs; pysoem median {p:.1} µs p99 {:.1} µs; ratio ours/pysoem {:.2}",
        percentile(&mut all_ours, 0.99),
        percentile(&mut all_cpu, 0.5),
        percentile(&mut all_py, 0.99),
        o / p
    );
    println!("fake segment: {:?}", fake.counters());
    fake.shutdown().expect("fake segment");
}
