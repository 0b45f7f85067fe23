//! Everything `rl run` does, from a program of your own: a supervised, real-time joint
//! controller driving the embedded Mitsubishi RV-6SL on a fake H7 controller on loopback.
//! Ctrl-C brings the arm to rest along its path; twice stops at once.
//!
//! `cargo run --release --example controller [seconds]`

use std::time::Duration;

use rl::controller::{ControlRun, RunOptions, rv6sl};
use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seconds: f64 = std::env::args().nth(1).map_or(Ok(3.0), |s| s.parse())?;
    let options = RunOptions::default().duration(Duration::from_secs_f64(seconds));
    options.stop.raise_on_termination_signals()?;
    let fake = FakeH7::spawn(FakeH7Config::loopback(6))?;
    let robot = MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr()))?;
    let mut run = ControlRun::<_, 16, 8>::start(robot, rv6sl()?, options)?;
    while let Some(p) = run.poll(Duration::from_millis(500)) {
        eprintln!(
            "t {:5.2} s  tracking error {:.4} rad",
            p.time_s, p.error_max_rad
        );
    }
    let report = run.join();
    println!("{report}");
    std::process::exit(report.exit_code());
}
