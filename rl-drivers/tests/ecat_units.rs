//! The EtherCAT master reads each drive's units over CoE — 0x608F, 0x6091, 0x6092, 0x6076 —
//! before it enables anything, and refuses a drive that cannot give them (naming the joint, the
//! device and the object) unless they are given; and the fake segment survives its link going
//! down and coming back, as a segment does. Our master against our fake segment on a veth pair
//! in a namespace made for each test (root; without it each test prints SKIPPED).

mod support;

use std::time::{Duration, Instant};

use rl_drivers::cia402::{AxisUnits, PowerState, UnitsOverride};
use rl_drivers::ethercat::{EthercatConfig, EthercatDrives};
use rl_drivers::fake::ecat_segment::description::Profile;
use rl_drivers::fake::ecat_segment::{FakeSegment, FakeSegmentConfig};
use rl_drivers::proto::ecat::al::AlState;
use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor, State};
use support::netns::{Veth, veth_or_skip};
use support::stall::{Canary, emulated, unless_stalled, within_bound_or_stall};
use support::{GEARED_121, MILLIDEGREES};

static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// Two drives with those units (the second without its unit objects if `hide`), standing at
/// 10 000 and -20 000 counts.
fn segment(veth: &Veth, hide: bool) -> FakeSegment {
    let mut c = FakeSegmentConfig::drives(&veth.b, 2);
    for (k, (d, u)) in c
        .devices
        .iter_mut()
        .zip([GEARED_121, MILLIDEGREES])
        .enumerate()
    {
        if let Profile::Cia402 {
            motor,
            initial_position,
            ..
        } = &mut d.profile
        {
            motor.units = u;
            motor.unit_objects = !(hide && k == 1);
            *initial_position = [10_000, -20_000][k];
        }
    }
    c.on_thread_start = Some(support::realtime_fake);
    support::realtime(70);
    veth.enter(|| FakeSegment::spawn(c)).expect("fake segment")
}

fn config(veth: &Veth, units: Vec<UnitsOverride>) -> EthercatDrives {
    let mut c = EthercatConfig::new(&veth.a);
    c.dc_static_frames = 200;
    c.frame_timeout = Duration::from_micros(900);
    c.units = units;
    EthercatDrives::new(c).unwrap()
}

/// Frames lost to scheduling are counted, at most 1 % of `n` cycles: `Err` (the session to run
/// again) when more went with a stall of the machine the `canary` saw, a failure when they went
/// without one; under an emulator ([`emulated`]) the count is reported, not bounded.
fn few_failures(failed: usize, n: usize, canary: Canary) -> Result<(), String> {
    if let Some(emulator) = emulated() {
        let _ = canary.worst();
        println!("under {emulator}: {failed} of {n} steps failed");
        return Ok(());
    }
    let within = within_bound_or_stall(failed, n, canary)?;
    assert!(
        within,
        "{failed} of {n} steps failed with the machine on time"
    );
    Ok(())
}

/// Steps `n` cycles at 1 ms, commanding `q(k)`; returns the failed steps.
fn run(d: &mut EthercatDrives, n: usize, q: impl Fn(usize) -> [f64; 2]) -> usize {
    let mut next = Instant::now();
    let mut failed = 0;
    for k in 0..n {
        if d.state() == State::Faulted {
            return failed + n - k;
        }
        d.set_joint_position(&q(k)).unwrap();
        if d.step().is_err() {
            failed += 1;
        }
        next += Duration::from_millis(1);
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    failed
}

/// The drives' positions in their own counts.
fn counts(fake: &FakeSegment) -> [f64; 2] {
    let s = fake.status();
    [s[0].position.unwrap(), s[1].position.unwrap()]
}

#[test]
fn drives_with_their_own_units_move_exactly_the_commanded_distance() {
    let _g = serial();
    let Some(veth) = veth_or_skip("drives_with_their_own_units_move_exactly") else {
        return;
    };
    unless_stalled("drives_with_their_own_units_move_exactly", || {
        units_session(&veth)
    });
}

/// One session of [`drives_with_their_own_units_move_exactly_the_commanded_distance`]; `Err`
/// with the numbers when frames lost beyond the bound went with a stall of the machine.
fn units_session(veth: &Veth) -> Result<(), String> {
    let fake = segment(veth, false);
    let mut d = config(veth, Vec::new());
    veth.enter(|| d.open()).expect("open");
    let units = d.units();
    assert_eq!(
        (
            units[0].counts_per_rev,
            units[0].gear_ratio,
            units[0].units_per_rev()
        ),
        (4096.0, 121.0, 4096.0 * 121.0)
    );
    assert_eq!(
        (units[1].gear_ratio, units[1].units_per_rev()),
        (50.5, 360_000.0)
    );
    assert!((units[1].rated_torque_nm - 2.4).abs() < 1e-12);
    let mut q0 = [0.0; 2];
    d.joint_position(&mut q0).unwrap();
    let rad = |c: f64, u: &AxisUnits| c / u.units_per_rev() * std::f64::consts::TAU;
    assert!((q0[0] - rad(10_000.0, &GEARED_121)).abs() < 1e-12, "{q0:?}");
    assert!(
        (q0[1] - rad(-20_000.0, &MILLIDEGREES)).abs() < 1e-12,
        "{q0:?}"
    );
    let before = counts(&fake);
    d.start().unwrap();
    let delta = [0.3, -0.2];
    let canary = Canary::start();
    let failed = run(&mut d, 600, |k| {
        let s = (k as f64 / 500.0).min(1.0);
        [q0[0] + s * delta[0], q0[1] + s * delta[1]]
    });
    let within = few_failures(failed, 600, canary);
    let after = counts(&fake);
    d.stop().unwrap();
    d.close().unwrap();
    within?;
    for (k, u) in [GEARED_121, MILLIDEGREES].iter().enumerate() {
        let moved = rad(after[k] - before[k], u);
        assert!(
            (moved - delta[k]).abs() <= 2.0 * u.position_resolution(),
            "joint {k} moved {moved} rad for {} commanded",
            delta[k]
        );
    }
    Ok(())
}

#[test]
fn a_drive_whose_units_cannot_be_read_is_refused_before_it_is_enabled() {
    let _g = serial();
    let Some(veth) = veth_or_skip("a_drive_whose_units_cannot_be_read_is_refused") else {
        return;
    };
    let fake = segment(&veth, true);
    let mut d = config(&veth, Vec::new());
    let e = veth.enter(|| d.open()).expect_err("refused").to_string();
    assert!(
        e.contains("joint 1") && e.contains("0x608f:1") && e.contains("0x06020000"),
        "{e}"
    );
    let s = fake.status();
    assert!(
        s.iter()
            .all(|d| d.state != AlState::Op && d.power == Some(PowerState::SwitchOnDisabled)),
        "{s:?}"
    );
    // Given, the drive runs with them.
    let mut d = config(
        &veth,
        vec![UnitsOverride::NONE, UnitsOverride::all(MILLIDEGREES)],
    );
    veth.enter(|| d.open()).expect("open with the units given");
    assert_eq!(d.units()[1].units_per_rev(), 360_000.0);
    d.close().unwrap();
}

#[test]
fn the_fake_segment_survives_its_link_going_down_and_coming_back() {
    let _g = serial();
    let Some(veth) = veth_or_skip("the_fake_segment_survives_its_link") else {
        return;
    };
    unless_stalled("the_fake_segment_survives_its_link", || link_session(&veth));
}

/// One enabled session of 200 cycles on `fake`: the drives left in OP; `Err` when frames lost
/// beyond the bound went with a stall of the machine.
fn op_session(veth: &Veth, fake: &FakeSegment) -> Result<EthercatDrives, String> {
    let mut d = config(veth, Vec::new());
    veth.enter(|| d.open()).expect("open");
    d.start().unwrap();
    let mut q = [0.0; 2];
    d.joint_position(&mut q).unwrap();
    let canary = Canary::start();
    let failed = run(&mut d, 200, |_| q);
    if let Err(stall) = few_failures(failed, 200, canary) {
        let _ = d.stop();
        let _ = d.close();
        return Err(stall);
    }
    assert!(fake.status().iter().all(|s| s.state == AlState::Op));
    Ok(d)
}

/// One run of [`the_fake_segment_survives_its_link_going_down_and_coming_back`].
fn link_session(veth: &Veth) -> Result<(), String> {
    let fake = segment(veth, false);
    let mut d = op_session(veth, &fake)?;
    // The segment's end of the cable is pulled: frames go nowhere, the master loses the link.
    veth.set_link(&veth.b, false).unwrap();
    let q = [0.0; 2];
    let lost = run(&mut d, 100, |_| q);
    assert!(lost >= 90, "{lost} of 100 steps failed with the link down");
    let _ = d.stop();
    let _ = d.close();
    std::thread::sleep(Duration::from_millis(200));
    veth.set_link(&veth.b, true).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    // Plugged back: the same fake answers a new session.
    let mut d = op_session(veth, &fake)?;
    d.stop().unwrap();
    d.close().unwrap();
    let c = fake.counters();
    assert!(c.link_down >= 1, "{c:?}");
    println!("{c:?}");
    fake.shutdown()
        .expect("the segment's thread ran to the end without an error");
    Ok(())
}
