//! The library controller against the fake H7, cycle by cycle (no real-time loop): a stop
//! request brings the arm to rest along its path within the planned speed and (at most twice)
//! the planned acceleration, and a cycle limit ends at rest on its last cycle.

mod common;

use common::PERIOD;
use rl::controller::{Controller, RunEnd};
use rl::drivers::Device;
use rl::drivers::mitsubishi_h7::MitsubishiH7;

/// Commanded positions, one per cycle, until the run ends (bounded).
fn run(control: &mut Controller<MitsubishiH7>, halt_at: Option<u64>) -> Vec<[f64; 8]> {
    let mut commanded = Vec::new();
    for i in 0..20_000u64 {
        if Some(i) == halt_at {
            control.request_halt();
        }
        let out = control.cycle();
        commanded.push(out.record.commanded);
        if out.finished {
            return commanded;
        }
    }
    panic!("the run did not end within 20000 cycles");
}

#[test]
fn a_stop_request_brings_the_arm_to_rest_within_the_planned_limits() {
    let fake = common::immediate_fake(6);
    let mut control = common::demo_controller(&fake);
    let limits = *control.plan().limits();
    // Cycle 120 is mid-motion (the first move takes about 1.6 s = 230 cycles).
    let commanded = run(&mut control, Some(120));
    assert_eq!(control.end(), Some(RunEnd::Stopped));
    assert!(
        commanded.len() < 600,
        "stopped well before the end of the plan"
    );
    let t = PERIOD.as_secs_f64();
    let mut moving_at_request = false;
    for k in 0..6 {
        let v = limits.velocity[k];
        let a = limits.acceleration[k];
        for w in commanded.windows(3) {
            let d1 = w[1][k] - w[0][k];
            let d2 = w[2][k] - 2.0 * w[1][k] + w[0][k];
            assert!(
                d1.abs() <= v * t * (1.0 + 1e-9),
                "joint {k}: step {d1} above v·T"
            );
            assert!(
                d2.abs() <= 2.0 * a * t * t * (1.0 + 1e-6),
                "joint {k}: Δ² {d2}"
            );
        }
        moving_at_request |= (commanded[121][k] - commanded[120][k]).abs() > 0.1 * v * t;
        let n = commanded.len();
        // The rate ramps to exactly 0 on the last command, so the last step is the tail of
        // the half cosine: a tiny fraction of a full-speed step.
        let last = (commanded[n - 1][k] - commanded[n - 2][k]).abs();
        assert!(
            last < 1e-3 * v * t,
            "joint {k}: last step {last}, not at rest"
        );
    }
    assert!(moving_at_request, "the stop came while the arm moved");
    assert_eq!(control.failed_steps(), 0);
    let mut robot = control.into_robot();
    robot.stop().expect("stop");
    robot.close().expect("close");
    // The end packet is sent without waiting for an answer: give the fake's thread (bounded)
    // time to take it.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(2);
    while fake.status().ends == 0 && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert_eq!(fake.status().ends, 1, "end packet");
}

#[test]
fn a_cycle_limit_ends_at_rest_on_its_last_cycle() {
    let fake = common::immediate_fake(6);
    let mut control = common::demo_controller(&fake);
    control.limit_cycles(300);
    let commanded = run(&mut control, None);
    assert_eq!(commanded.len(), 300);
    assert_eq!(control.end(), Some(RunEnd::CycleLimit));
    let n = commanded.len();
    let v = control.plan().limits().velocity;
    for k in 0..6 {
        let last = (commanded[n - 1][k] - commanded[n - 2][k]).abs();
        assert!(
            last < 1e-3 * v[k] * PERIOD.as_secs_f64(),
            "joint {k}: last step {last}"
        );
    }
}
