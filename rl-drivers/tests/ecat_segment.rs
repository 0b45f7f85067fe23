//! Our master against our fake segment on a veth pair in a network namespace made for each
//! test (root needed; without it every test prints SKIPPED and passes): open, enable, CSP motion
//! and disable on 6 axes; 10,000 cycles at 1 ms without a working-counter error; every injected
//! fault counted and typed; recovery to OP after a device drops to SAFE-OP; our own echo and
//! foreign frames dropped.

mod support;

use std::time::{Duration, Instant};

use rl_drivers::ethercat::{EthercatConfig, EthercatDrives};
use rl_drivers::fake::ecat_segment::{FakeSegment, FakeSegmentConfig, Fault};
use rl_drivers::proto::ecat::al::{AlState, AlStatusCode};
use rl_drivers::{
    CyclicDevice, Device, DeviceError, ErrorKind, JointDevice, JointLimitSensor,
    JointPositionActuator, JointPositionSensor, LinkStatisticsSensor, State,
};
use support::netns::{Veth, veth_or_skip};
use support::stall::{Canary, STALL, emulated, unless_stalled, within_bound_or_stall};

const COUNTS: f64 = (1u32 << 20) as f64;

/// One namespace test at a time: each runs a fake segment and a master at 1 ms on a 2-core
/// machine.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

/// Frames lost to scheduling (the reply later than the frame timeout) are counted, not hidden;
/// anything else is a failure.
fn only_timeouts(errors: &[rl_drivers::Error], cycles: usize) {
    assert!(
        errors.len() < cycles,
        "every cycle failed: {:?}",
        errors.first()
    );
    let other: Vec<_> = errors
        .iter()
        .filter(|e| e.kind() != ErrorKind::Timeout)
        .collect();
    assert!(other.is_empty(), "{other:?}");
    // The 1 % bound is this machine's scheduling; under an emulator it is reported, not
    // asserted.
    match emulated() {
        Some(emulator) if errors.len() * 100 > cycles => println!(
            "SKIPPED the 1 % timeout bound under {emulator}: {} of {cycles} cycles timed out",
            errors.len()
        ),
        _ => assert!(
            errors.len() * 100 <= cycles,
            "{} of {cycles} cycles timed out (more than 1 %)",
            errors.len()
        ),
    }
    println!("{} of {cycles} cycles timed out", errors.len());
}

fn segment(veth: &Veth, drives: usize) -> FakeSegment {
    let mut c = FakeSegmentConfig::drives(&veth.b, drives);
    c.on_thread_start = Some(support::realtime_fake);
    // The master's thread (this test's) runs at a real-time priority just below the fake's.
    support::realtime(70);
    veth.enter(|| FakeSegment::spawn(c)).expect("fake segment")
}

fn drives(veth: &Veth, config: impl FnOnce(&mut EthercatConfig)) -> EthercatDrives {
    let mut c = EthercatConfig::new(&veth.a);
    c.dc_static_frames = 200;
    c.frame_timeout = Duration::from_micros(900);
    config(&mut c);
    let mut d = EthercatDrives::new(c).unwrap();
    veth.enter(|| d.open()).expect("open");
    d
}

/// Runs `n` steps paced at the device's period; returns the errors.
fn run(
    d: &mut EthercatDrives,
    n: usize,
    each: impl FnMut(&mut EthercatDrives, usize),
) -> Vec<rl_drivers::Error> {
    run_timed(d, n, each).0
}

/// [`run`], also returning how late the loop woke at worst (after its deadline).
fn run_timed(
    d: &mut EthercatDrives,
    n: usize,
    mut each: impl FnMut(&mut EthercatDrives, usize),
) -> (Vec<rl_drivers::Error>, Duration) {
    let mut errors = Vec::new();
    let period = d.update_period();
    let mut next = Instant::now();
    let mut worst_late = Duration::ZERO;
    for k in 0..n {
        if d.state() == State::Faulted {
            break;
        }
        worst_late = worst_late.max(Instant::now().saturating_duration_since(next));
        each(d, k);
        if let Err(e) = d.step() {
            errors.push(e);
        }
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
    }
    (errors, worst_late)
}

#[test]
fn six_axes_open_enable_move_and_disable() {
    let _g = serial();
    let Some(veth) = veth_or_skip("six_axes_open_enable_move_and_disable") else {
        return;
    };
    unless_stalled("six_axes_open_enable_move_and_disable", || {
        six_axes_session(&veth)
    });
}

/// Frames lost beyond the 1 % bound while the `canary` saw the machine stall a thread for a
/// frame timeout or more: `Err` with the numbers, the session to run again. Beyond the bound
/// with no stall seen fails here ([`only_timeouts`]).
fn timeouts_or_stall(
    errors: &[rl_drivers::Error],
    cycles: usize,
    canary: Canary,
) -> Result<(), String> {
    within_bound_or_stall(errors.len(), cycles, canary)?;
    only_timeouts(errors, cycles);
    Ok(())
}

/// One session of [`six_axes_open_enable_move_and_disable`]; `Err` with the numbers when the
/// frames lost beyond the bound went with a stall of the machine.
fn six_axes_session(veth: &Veth) -> Result<(), String> {
    let fake = segment(veth, 6);
    let mut d = drives(veth, |_| {});
    // After open, before any drive is enabled: the true axis count and where the arm is.
    assert_eq!(d.dof(), 6);
    assert_eq!(d.device_names().len(), 6);
    assert!(d.device_names().iter().all(|n| n == "rl-rs CiA 402 axis"));
    let mut q0 = [0.0; 6];
    d.joint_position(&mut q0).unwrap();
    for (k, q) in q0.iter().enumerate() {
        let expected = (k as f64 * ((1 << 20) / 10) as f64) / COUNTS * std::f64::consts::TAU;
        assert!((q - expected).abs() < 1e-5, "joint {k}: {q} vs {expected}");
    }
    let dc = d.dc().expect("distributed clocks");
    assert_eq!(
        dc.delays,
        vec![0, 500, 1000, 1500, 2000, 2500],
        "hop delay 500 ns"
    );
    assert!(
        fake.status()
            .iter()
            .all(|s| s.state == AlState::SafeOp && s.dc_mode)
    );
    d.start().unwrap();
    assert!(fake.status().iter().all(|s| s.state == AlState::Op));
    // 1 s of CSP motion: a sine of 0.2 rad on every joint.
    let canary = Canary::start();
    let errors = run(&mut d, 1000, |d, k| {
        let t = k as f64 * 1e-3;
        let q: Vec<f64> = q0
            .iter()
            .map(|q| q + 0.2 * (std::f64::consts::TAU * t).sin())
            .collect();
        d.set_joint_position(&q).unwrap();
    });
    if let Err(stall) = timeouts_or_stall(&errors, 1000, canary) {
        let _ = d.stop();
        let _ = d.close();
        return Err(stall);
    }
    assert_eq!(d.state(), State::Running, "{:?}", d.fault());
    let mut q = [0.0; 6];
    d.joint_position(&mut q).unwrap();
    // The last command was sin(2π·0.999) ≈ -0.00628 rad; the drives follow within a cycle.
    for k in 0..6 {
        assert!(
            (q[k] - q0[k]).abs() < 0.02,
            "joint {k} at {} after the sine, started at {}",
            q[k],
            q0[k]
        );
    }
    let status = fake.status();
    assert!(
        status.iter().all(|s| s.updates > 900),
        "the drives moved on SYNC0: {status:?}"
    );
    let mut limits = [true; 6];
    d.joint_limit_reached(&mut limits).unwrap();
    assert_eq!(limits, [false; 6]);
    d.stop().unwrap();
    let status = fake.status();
    assert!(
        status.iter().all(|s| s.state == AlState::PreOp),
        "{status:?}"
    );
    assert!(
        status
            .iter()
            .all(|s| s.power == Some(rl_drivers::cia402::PowerState::SwitchOnDisabled))
    );
    d.close().unwrap();
    assert_eq!(d.state(), State::Closed);
    assert!(fake.status().iter().all(|s| s.state == AlState::Init));
    Ok(())
}

#[test]
fn ten_thousand_cycles_at_1_ms_without_a_working_counter_error() {
    let _g = serial();
    let Some(veth) = veth_or_skip("ten_thousand_cycles") else {
        return;
    };
    // Frames lost in a row fault the drives, as on a real segment. Where this test's own loop
    // woke a period or more late, or the canary thread saw the machine stall a thread for a
    // frame timeout or more, or under an emulator, the machine stalled it: a session that
    // faulted, lost frames beyond the 1 % bound or saw a working-counter error then is run
    // again, up to three times, then SKIPPED with the measurements. Any of these with the
    // machine on time fails the test. Under an emulator every session stalls, and runs slower
    // than real time (10 000 cycles can take minutes): one session, then SKIPPED.
    let emulated = emulated().is_some();
    let mut stalls = Vec::new();
    let (fake, mut d, errors) = loop {
        let fake = segment(&veth, 6);
        let mut d = drives(&veth, |_| {});
        d.start().unwrap();
        let mut q = [0.0; 6];
        d.joint_position(&mut q).unwrap();
        let q0 = q;
        let canary = Canary::start();
        let (errors, late) = run_timed(&mut d, 10_000, |d, k| {
            for (j, v) in q.iter_mut().enumerate() {
                *v = q0[j] + 0.1 * (k as f64 * 1e-3).sin();
            }
            d.set_joint_position(&q).unwrap();
        });
        let canary = canary.worst();
        println!(
            "{:?}; the canary saw a stall of {canary:?}",
            d.master().unwrap().link.counters()
        );
        let faulted = d.state() == State::Faulted;
        let wkc_errors = d.process().map_or(0, |p| p.counters.wkc_errors);
        // Under an emulator the fake's threads stall as this loop does.
        let stalled = late >= d.update_period() || canary >= Duration::from_micros(900) || emulated;
        let short = faulted || wkc_errors > 0 || errors.len() * 100 > 10_000;
        if !short || !stalled {
            only_timeouts(&errors, 10_000);
            assert_eq!(
                d.state(),
                State::Running,
                "{:?} (the loop was at most {late:?} late)",
                d.fault()
            );
            break (fake, d, errors);
        }
        println!(
            "attempt {}: {:?} after {} lost frames, {wkc_errors} working-counter errors; the \
             loop woke {late:?} late at worst, the canary {canary:?}",
            stalls.len() + 1,
            d.fault(),
            errors.len()
        );
        stalls.push(late);
        let _ = d.stop();
        let _ = d.close();
        drop(fake);
        if stalls.len() == 3 || emulated {
            println!(
                "SKIPPED ten_thousand_cycles: the drives faulted on lost frames in {} session(s) \
                 while this machine stalled the 1 ms loop (worst lateness {stalls:?}{})",
                stalls.len(),
                if emulated { ", under an emulator" } else { "" }
            );
            return;
        }
    };
    let p = d.process().unwrap();
    assert_eq!(p.counters.wkc_errors, 0);
    assert_eq!(p.counters.state_errors, 0);
    let s = d.link_statistics();
    println!("{s:?}; fake {:?}", fake.counters());
    assert_eq!(s.lost, errors.len() as u64);
    assert_eq!(s.corrupt, 0);
    // The devices' clocks stayed on the reference's.
    for st in fake.status() {
        assert!(
            st.dc_difference.abs() < 1_000,
            "DC difference {} ns",
            st.dc_difference
        );
    }
    d.stop().unwrap();
    d.close().unwrap();
}

#[test]
fn injected_faults_are_counted_and_typed_and_a_device_recovers_to_op() {
    let _g = serial();
    let Some(veth) = veth_or_skip("injected_faults") else {
        return;
    };
    let fake = segment(&veth, 3);
    let mut d = drives(&veth, |c| c.max_consecutive_failures = 20);
    d.start().unwrap();
    let hold = |d: &mut EthercatDrives, _k: usize| {
        let mut q = [0.0; 3];
        if d.joint_position(&mut q).is_ok() {
            d.set_joint_position(&q).unwrap();
        }
    };
    assert!(
        run(&mut d, 50, hold)
            .iter()
            .all(|e| e.kind() == ErrorKind::Timeout)
    );
    let before = d.link_statistics();

    // Lost frames: timeouts, counted as lost.
    fake.inject(Fault::LoseFrames { frames: 3 });
    let errors = run(&mut d, 20, hold);
    let lost = d.link_statistics().lost - before.lost;
    assert!(lost >= 3, "lost {lost}");
    assert!(
        errors.len() >= 3 && errors.iter().all(|e| e.kind() == ErrorKind::Timeout),
        "{errors:?}"
    );

    // A wrong working counter: a protocol error naming expected and received. A falsified
    // frame that comes back after the frame timeout is a timeout instead: when the machine
    // stalled, the two go again (at most three times, then SKIPPED with the numbers). Under an
    // emulator the fake's and the master's threads stall as the canary's do not (the
    // qemu-aarch64 run of a clean-clone CI: a falsified frame back after 900 µs with the canary
    // 582 µs late): every such session counts as stalled, as run_timed's caller does.
    let emulated = emulated().is_some();
    let mut stalls = Vec::new();
    while stalls.len() < 3 {
        let wkc_before = d.process().unwrap().counters.wkc_errors;
        let canary = Canary::start();
        fake.inject(Fault::WrongWorkingCounter { frames: 2 });
        let errors = run(&mut d, 20, hold);
        let stalled = canary.worst();
        let wkc: Vec<_> = errors
            .iter()
            .filter(|e| e.kind() == ErrorKind::Protocol)
            .collect();
        let timeouts = errors
            .iter()
            .filter(|e| e.kind() == ErrorKind::Timeout)
            .count();
        assert_eq!(wkc.len() + timeouts, errors.len(), "{errors:?}");
        assert_eq!(
            d.process().unwrap().counters.wkc_errors - wkc_before,
            wkc.len() as u64
        );
        if let Some(first) = wkc.first() {
            assert_eq!(
                first.to_string(),
                "step: EtherCAT datagram: LRW 0x00000000: working counter 8, expected 9"
            );
        }
        if wkc.len() == 2 {
            break;
        }
        assert!(
            wkc.len() < 2 && wkc.len() + timeouts >= 2 && (stalled >= STALL || emulated),
            "{} wrong working counters of 2 falsified frames, {timeouts} timeouts, the \
             machine stalled {stalled:?}: {errors:?}",
            wkc.len()
        );
        stalls.push(format!(
            "{} of 2 falsified frames in time, {timeouts} timeouts, a stall of {stalled:?}",
            wkc.len()
        ));
        println!(
            "injected_faults: wrong working counter: {}",
            stalls.last().unwrap()
        );
    }
    if stalls.len() == 3 {
        println!(
            "SKIPPED injected_faults' wrong working counter: this machine stalled in three \
             tries: {}",
            stalls.join("; ")
        );
    }

    // A device falls back to SAFE-OP with "sync manager watchdog": named, then recovered.
    fake.inject(Fault::FallBackToSafeOp {
        device: 1,
        code: AlStatusCode::SM_WATCHDOG,
    });
    let errors = run(&mut d, 10, hold);
    assert!(d.state() == State::Running, "{:?}", d.fault());
    let named = errors
        .iter()
        .find(|e| e.to_string().contains("sync manager watchdog"))
        .unwrap_or_else(|| panic!("no error names the AL status code: {errors:?}"));
    assert_eq!(named.kind(), ErrorKind::Device);
    assert!(named.to_string().contains("device 1 (0x1002)"), "{named}");
    assert!(
        fake.status()
            .iter()
            .all(|s| s.state == AlState::Op && s.error.is_none()),
        "{:?}",
        fake.status()
    );
    let c = d.process().unwrap().counters;
    assert_eq!((c.recoveries, c.recovered), (1, 1));
    // The drive faulted when its outputs stopped: a device error naming the joint, until the
    // failures in a row fault the whole device.
    let drive = errors
        .iter()
        .find(|e| e.to_string().contains("CiA 402"))
        .expect("the drive's fault");
    assert!(drive.to_string().contains("joint 1"), "{drive}");
    let errors = run(&mut d, 30, hold);
    assert_eq!(d.state(), State::Faulted, "{errors:?}");
    // stop from the faulted state brings everything down, every step bounded.
    d.stop().unwrap();
    assert!(fake.status().iter().all(|s| s.state == AlState::PreOp));
    d.close().unwrap();
}

#[test]
fn our_own_echo_and_foreign_frames_are_dropped_and_counted() {
    let _g = serial();
    let Some(veth) = veth_or_skip("echo") else {
        return;
    };
    unless_stalled("echo", || echo_session(&veth));
}

/// One session of [`our_own_echo_and_foreign_frames_are_dropped_and_counted`].
fn echo_session(veth: &Veth) -> Result<(), String> {
    use rl_drivers::proto::ecat::command::Command;
    use rl_drivers::proto::ecat::datagram::{DatagramHeader, physical};
    use rl_drivers::proto::ecat::frame::{FrameBuilder, MacAddr};
    use rl_drivers::transport::PacketLink;
    let fake = segment(veth, 1);
    let mut d = drives(veth, |_| {});
    // Another sender on the segment's side: a frame with our own source (as a hub would
    // return our echo) and one from a stranger.
    let mut other = veth.enter(|| PacketLink::open(&veth.b, 0x88A4)).unwrap();
    for src in [MacAddr::MASTER, MacAddr([0x02, 0, 0, 0, 0, 7])] {
        let mut buf = [0u8; 64];
        let mut b = FrameBuilder::new(&mut buf, src).unwrap();
        let mut h = DatagramHeader::new(Command::Brd, physical(0, 0), 2);
        h.index = 0xEE;
        b.push_zeroed(h, 2).unwrap();
        let n = b.finish();
        other.send(&buf[..n]).unwrap();
    }
    d.start().unwrap();
    let canary = Canary::start();
    let errors = run(&mut d, 20, |_, _| {});
    if let Err(stall) = timeouts_or_stall(&errors, 20, canary) {
        let _ = d.stop();
        let _ = d.close();
        return Err(stall);
    }
    let s = d.master().unwrap().link.counters();
    assert_eq!((s.echo, s.foreign), (1, 1), "{s:?}");
    assert_eq!(d.link_statistics().rejected, 2);
    // The fake ignored our echo of its own frames and the stranger's frame was answered by
    // nobody we count.
    assert!(fake.counters().ignored <= 1);
    d.stop().unwrap();
    d.close().unwrap();
    Ok(())
}
