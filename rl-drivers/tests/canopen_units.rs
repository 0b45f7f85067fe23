//! Units are read, never assumed: the CANopen master reads each drive's position encoder
//! resolution (0x608F), gear ratio (0x6091), feed constant (0x6092) and rated torque (0x6076)
//! at `open`, before anything is enabled, and converts with them; a drive that cannot give them
//! is refused before it is enabled, naming the node and the object, unless the units are given.
//!
//! The fake drives here have units that differ from every default (not 2^20 counts, not 1:1 or
//! 100:1, and one whose position unit is not the encoder count): a master that assumed units
//! would command them a multiple of the distance.

mod support;

use std::time::{Duration, Instant};

use rl_drivers::canopen::{Cia402, Cia402Config};
use rl_drivers::cia402::{AxisUnits, PowerState, UnitsOverride};
use rl_drivers::fake::cia402_drive::{FakeCia402, FakeCia402Config};
use rl_drivers::proto::canopen::nmt;
use rl_drivers::transport::can::CanAddress;
use rl_drivers::transport::can::bus::Bus;
use rl_drivers::{CyclicDevice, Device, JointPositionActuator, JointPositionSensor};
use support::{GEARED_121, MILLIDEGREES};

/// Fake drives 1 and 2 with those units (2 without its unit objects if `hide`), and a master
/// on the same in-process bus with the units `given` (20 ms cycle: behaviour, not timing).
fn setup(hide: bool, given: [UnitsOverride; 2]) -> (FakeCia402, Cia402) {
    let bus = Bus::new();
    let mut fc = FakeCia402Config::new(&[1, 2]).unwrap();
    fc.sync_loss_periods = 10;
    fc.axes[0].units = GEARED_121;
    fc.axes[1].units = MILLIDEGREES;
    fc.axes[1].unit_objects = !hide;
    fc.axes[0].initial = 0.25;
    fc.axes[1].initial = -0.5;
    let fake = FakeCia402::on_transport(fc, Box::new(bus.endpoint())).unwrap();
    let mut config = Cia402Config::new(CanAddress::parse("socketcan://unused").unwrap(), &[1, 2])
        .with_period(Duration::from_millis(20));
    config.sdo_timeout = Duration::from_millis(200);
    for (a, g) in config.axes.iter_mut().zip(given) {
        a.units = g;
    }
    let dev = Cia402::with_transport(config, Box::new(bus.endpoint())).unwrap();
    (fake, dev)
}

/// Enables, moves both joints by `delta` rad in 40 steps, holds 5 cycles, stops; returns where
/// the drives are by their own units, rad.
fn move_by(fake: &FakeCia402, dev: &mut Cia402, delta: [f64; 2]) -> ([f64; 2], [f64; 2]) {
    let mut start = [0.0; 2];
    dev.joint_position(&mut start).unwrap();
    dev.start().unwrap();
    let mut next = Instant::now();
    for k in 0..=45 {
        let s = (f64::from(k.min(40)) / 40.0).min(1.0);
        dev.set_joint_position(&[start[0] + s * delta[0], start[1] + s * delta[1]])
            .unwrap();
        dev.step().unwrap_or_else(|e| panic!("step {k}: {e}"));
        next += Duration::from_millis(20);
        std::thread::sleep(next.saturating_duration_since(Instant::now()));
    }
    let s = fake.status();
    dev.stop().unwrap();
    dev.close().unwrap();
    (start, [s.nodes[0].position, s.nodes[1].position])
}

#[test]
fn drives_with_their_own_units_move_exactly_the_commanded_distance() {
    let (fake, mut dev) = setup(false, [UnitsOverride::NONE; 2]);
    dev.open().unwrap();
    let read: Vec<AxisUnits> = dev.node_reports().map(|r| r.units).collect();
    assert_eq!(read[0].counts_per_rev, 4096.0);
    assert_eq!(read[0].gear_ratio, 121.0);
    assert_eq!(read[0].units_per_rev(), 4096.0 * 121.0);
    assert!((read[0].rated_torque_nm - 0.64).abs() < 1e-12);
    assert_eq!(read[1].gear_ratio, 50.5);
    assert_eq!(read[1].units_per_rev(), 360_000.0);
    let (start, end) = move_by(&fake, &mut dev, [0.3, -0.2]);
    // Where the drives stood at open, in joint units.
    assert!(
        (start[0] - 0.25).abs() <= GEARED_121.position_resolution(),
        "{start:?}"
    );
    assert!(
        (start[1] + 0.5).abs() <= MILLIDEGREES.position_resolution(),
        "{start:?}"
    );
    // Exactly the commanded distance, to the drives' own resolution.
    for (k, (d, u)) in [(0.3, GEARED_121), (-0.2, MILLIDEGREES)]
        .into_iter()
        .enumerate()
    {
        let moved = end[k] - start[k];
        assert!(
            (moved - d).abs() <= 2.0 * u.position_resolution(),
            "joint {k} moved {moved} rad for {d} commanded"
        );
    }
}

#[test]
fn a_drive_whose_units_cannot_be_read_is_refused_before_it_is_enabled() {
    let (fake, mut dev) = setup(true, [UnitsOverride::NONE; 2]);
    let e = dev.open().expect_err("refused").to_string();
    assert!(
        e.contains("node 2")
            && e.contains("0x608f:1")
            && e.contains("0x06020000")
            && e.contains("give the axis units"),
        "{e}"
    );
    // Nothing was enabled, nothing left pre-operational.
    std::thread::sleep(Duration::from_millis(50));
    for n in fake.status().nodes {
        assert_eq!(n.power, PowerState::SwitchOnDisabled, "{n:?}");
        assert_eq!(n.nmt, nmt::State::PreOperational, "{n:?}");
        assert_eq!(n.counters.syncs, 0, "{n:?}");
    }

    // Given, the drive runs with them (nothing of its factor group is read).
    let (fake, mut dev) = setup(
        true,
        [UnitsOverride::NONE, UnitsOverride::all(MILLIDEGREES)],
    );
    dev.open().unwrap();
    let (start, end) = move_by(&fake, &mut dev, [0.1, 0.2]);
    assert!((end[1] - start[1] - 0.2).abs() <= 2.0 * MILLIDEGREES.position_resolution());
}

#[test]
fn units_given_replace_what_the_drive_reports() {
    // The old assumption (2^20 counts, 100:1) given to a drive with a 12-bit encoder and a
    // 121:1 gear: its counts per joint revolution differ by 211.6×; the position read at open
    // shows it at once (a tenth of the true angle becomes hundreds of times smaller).
    let (fake, mut dev) = setup(false, [UnitsOverride::all(AxisUnits::GEARED_100); 2]);
    dev.open().unwrap();
    let mut q = [0.0; 2];
    dev.joint_position(&mut q).unwrap();
    let ratio = 0.25 / q[0];
    assert!(
        (ratio - 1_048_576.0 * 100.0 / (4096.0 * 121.0)).abs() < 0.01,
        "{q:?}"
    );
    dev.close().unwrap();
    drop(fake);
}
