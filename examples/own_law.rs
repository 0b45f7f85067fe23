//! A control law of your own in the supervised runtime: the embedded Mitsubishi RV-6SL on a
//! fake H7 controller on loopback, every joint swung by a law of twenty lines, with the
//! runtime's start-up checks, supervision, two-level stop, telemetry and report around it.
//! Ctrl-C (or the end of the duration) has the law fade the swing out to rest; twice stops at
//! once.
//!
//! `cargo run --release --example own_law [seconds]`

use std::f64::consts::PI;
use std::time::Duration;

use rl::controller::{
    BrakeReason, Command, Context, ControlLaw, ControlRun, LawError, LawStatus, RunOptions, Start,
    rv6sl,
};
use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};

/// Swings every joint by up to 0.1 rad from where it stood, one swing in 2 s; braking fades the
/// swing out over half a second.
#[derive(Default)]
struct Swing {
    home: [f64; 8],
    braking_s: Option<f64>,
}

impl ControlLaw<16, 8> for Swing {
    type Input = ();

    fn start(&mut self, start: &Start<'_, 16, 8>) -> Result<(), LawError> {
        self.home[..start.position.len()].copy_from_slice(start.position);
        Ok(())
    }

    fn cycle(&mut self, cx: &mut Context<'_, 16, 8, ()>, out: &mut Command<8>) -> LawStatus {
        let s = self.braking_s.map_or(0.0, |b| (b / 0.5).min(1.0));
        let fade = 0.5 * (1.0 + (PI * s).cos());
        for k in 0..cx.dof {
            out.position[k] = self.home[k] + fade * 0.05 * (1.0 - (PI * cx.time_s).cos());
        }
        match &mut self.braking_s {
            None => LawStatus::Running,
            Some(_) if s >= 1.0 => LawStatus::AtRest,
            Some(b) => {
                *b += cx.period_s;
                LawStatus::Braking
            }
        }
    }

    fn brake(&mut self, _reason: BrakeReason) {
        self.braking_s.get_or_insert(0.0);
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seconds: f64 = std::env::args().nth(1).map_or(Ok(3.0), |s| s.parse())?;
    let options = RunOptions {
        model_name: "Mitsubishi RV-6SL (embedded)".into(),
        device_name: "fake H7 on loopback".into(),
        ..RunOptions::default().duration(Duration::from_secs_f64(seconds))
    };
    options.stop.raise_on_termination_signals()?;
    let fake = FakeH7::spawn(FakeH7Config::loopback(6))?;
    let robot = MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr()))?;
    let mut run = ControlRun::start_law(robot, rv6sl()?, options, Swing::default())?;
    while let Some(p) = run.poll(Duration::from_millis(500)) {
        eprintln!(
            "t {:5.2} s  tracking error {:.4} rad{}",
            p.time_s,
            p.error_max_rad,
            if p.halting { "  (coming to rest)" } else { "" }
        );
    }
    let report = run.join();
    println!("{report}");
    std::process::exit(report.exit_code());
}
