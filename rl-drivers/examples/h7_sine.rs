//! Drives a Mitsubishi H7 controller with a joint sine for 5 s at the real 7.11 ms period.
//!
//! Without arguments it starts a fake controller in-process on loopback (no hardware needed).
//! With `UDP_ADDR R3_ADDR` (for example `127.0.0.1:10000 127.0.0.1:10001` against
//! `rl fake-robot h7`, or a real controller's address) it talks to that controller instead.
//! A real robot will MOVE: only point this at hardware with the work cell cleared.
//!
//! The controller runs its own 7.11 ms cycle and answers at its ticks
//! ([`CyclicDevice::runs_own_cycle`]): a command sent just after a tick waits almost a period
//! for its reply, at the edge of the step's budget. So the loop wakes half a period after each
//! reply — its command then reaches the controller half a period before the next tick. (`rl
//! run` keeps the same phase with a phase-locked real-time loop.)

use std::time::{Duration, Instant};

use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};

const DOF: usize = 6;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (_fake, udp, r3) = match args.as_slice() {
        [] => {
            let fake = FakeH7::spawn(FakeH7Config::loopback(DOF))?;
            let (u, r) = (fake.udp_addr(), fake.r3_addr());
            (Some(fake), u, r)
        }
        [u, r] => (None, u.parse()?, r.parse()?),
        _ => return Err("usage: h7_sine [UDP_ADDR R3_ADDR]".into()),
    };
    let mut robot = MitsubishiH7::new(MitsubishiH7Config::new(DOF, udp, r3))?;
    robot.open()?;
    robot.start()?;
    robot.step()?; // the first step only polls the state
    let mut q0 = [0.0; DOF];
    robot.joint_position(&mut q0)?;
    let period = robot.update_period();
    let cycles = (Duration::from_secs(5).as_micros() / period.as_micros()) as usize;
    let (mut q, mut measured, mut worst) = ([0.0; DOF], [0.0; DOF], 0.0f64);
    let start = Instant::now();
    let mut next = start;
    let mut failed = 0;
    for k in 0..cycles {
        let t = k as f64 * period.as_secs_f64();
        for (i, qi) in q.iter_mut().enumerate() {
            *qi = q0[i] + 0.05 * (std::f64::consts::TAU * 0.5 * t).sin();
        }
        robot.set_joint_position(&q)?;
        match robot.step() {
            // The reply came at a tick: the next is a period later.
            Ok(()) if robot.runs_own_cycle() => next = Instant::now() + period / 2,
            Ok(()) => next += period,
            Err(e) => {
                failed += 1;
                eprintln!("cycle {k}: {e}");
                next += period;
            }
        }
        robot.joint_position(&mut measured)?;
        worst = worst.max((measured[0] - q[0]).abs());
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    robot.stop()?;
    robot.close()?;
    let c = robot.counters();
    println!(
        "{cycles} cycles in {:.2} s: {failed} failed steps; replies {}, timeouts {}, late {}, foreign {}, corrupt {}, wrong length {}",
        start.elapsed().as_secs_f64(),
        c.replies,
        c.timeouts,
        c.late,
        c.foreign,
        c.corrupt,
        c.wrong_length
    );
    println!("largest |measured - commanded| on joint 1: {worst:.5} rad (filter lag)");
    Ok(())
}
