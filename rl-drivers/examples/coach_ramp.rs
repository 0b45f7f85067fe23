//! Streams a joint ramp to a Coach server (RL's rlCoachMdl/rlCoachKin, or `rl fake-robot
//! coach`) for 2 s and reads the joints back each cycle.
//!
//! Without arguments it starts a Coach server in-process on loopback; with `ADDR` (for example
//! `127.0.0.1:11235`) it connects there. Options: `--model I` (default 0), `--dof N` (default 6).

use std::time::{Duration, Instant};

use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::coach_server::{CoachServer, CoachServerConfig};
use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let (mut addr, mut model, mut dof) = (None, 0u32, 6usize);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--model" => model = args.next().ok_or("--model needs a value")?.parse()?,
            "--dof" => dof = args.next().ok_or("--dof needs a value")?.parse()?,
            other => addr = Some(other.parse()?),
        }
    }
    let server = match addr {
        Some(_) => None,
        // The in-process viewer has the model loaded, standing at zero (the client asks where
        // it stands when it opens).
        None => Some(CoachServer::spawn(CoachServerConfig {
            models: vec![(model, vec![0.0; dof])],
            ..CoachServerConfig::loopback()
        })?),
    };
    let mut config = CoachConfig::new(dof);
    config.model = model;
    if let Some(a) = addr.or(server.as_ref().map(CoachServer::addr)) {
        config.server = a;
    }
    let mut coach = Coach::new(config)?;
    coach.open()?;
    coach.start()?;
    let period = coach.update_period();
    let cycles = (Duration::from_secs(2).as_micros() / period.as_micros()) as usize;
    let (mut q, mut back) = (vec![0.0; dof], vec![0.0; dof]);
    let mut next = Instant::now();
    for k in 0..cycles {
        q.iter_mut().for_each(|v| *v = 0.001 * k as f64);
        coach.set_joint_position(&q)?;
        coach.step()?;
        coach.joint_position(&mut back)?;
        next += period;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    coach.stop()?;
    coach.close()?;
    let c = coach.counters();
    println!(
        "{cycles} cycles: replies {}, timeouts {}, late {}, bad lines {}; last joints read back {:?}",
        c.replies, c.timeouts, c.late, c.bad_lines, back
    );
    Ok(())
}
