//! The EtherCAT drives' `step()` and the getters and setters around it allocate nothing in
//! steady state, on the good path and on the error paths (a lost frame, a wrong working
//! counter, a device out of OP and its recovery). Runs on a veth pair in a namespace (root);
//! without root it prints SKIPPED.

mod support;

use std::time::{Duration, Instant};

use rl_drivers::ethercat::{EthercatConfig, EthercatDrives};
use rl_drivers::fake::ecat_segment::{FakeSegment, FakeSegmentConfig, Fault};
use rl_drivers::proto::ecat::al::AlStatusCode;
use rl_drivers::{
    CyclicDevice, Device, JointLimitSensor, JointPositionActuator, JointPositionSensor,
    JointTorqueFeedForward, JointVelocitySensor, LinkStatisticsSensor,
};
use rl_testkit::CountingAllocator;
use support::netns::veth_or_skip;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn the_counter_sees_allocations() {
    assert!(rl_testkit::allocations(|| drop(std::hint::black_box(vec![1u8; 64]))).0 >= 1);
}

#[test]
fn ethercat_steps_allocate_nothing() {
    let Some(veth) = veth_or_skip("ethercat_steps_allocate_nothing") else {
        return;
    };
    let mut c = FakeSegmentConfig::drives(&veth.b, 3);
    c.on_thread_start = Some(support::realtime_fake);
    support::realtime(70);
    let fake = veth.enter(|| FakeSegment::spawn(c)).expect("fake segment");
    let mut config = EthercatConfig::new(&veth.a);
    config.dc_static_frames = 100;
    config.frame_timeout = Duration::from_micros(900);
    config.max_consecutive_failures = 1000;
    let mut d = EthercatDrives::new(config).unwrap();
    veth.enter(|| d.open()).unwrap();
    d.start().unwrap();
    let (mut q, mut qd, mut tau, mut lim) = ([0.0; 3], [0.0; 3], [0.0; 3], [false; 3]);
    d.joint_position(&mut q).unwrap();
    let q0 = q;
    let mut cycle = |d: &mut EthercatDrives, k: usize| {
        q = q0;
        q[0] += 1e-4 * k as f64;
        d.set_joint_position(&q).unwrap();
        d.set_joint_torque_feed_forward(&tau).unwrap();
        let _ = d.step();
        let _ = d.joint_position(&mut q);
        let _ = d.joint_velocity(&mut qd);
        let _ = d.joint_limit_reached(&mut lim);
        let _ = d.link_statistics();
        tau[1] = 0.01;
    };
    let paced =
        |d: &mut EthercatDrives, n: usize, cycle: &mut dyn FnMut(&mut EthercatDrives, usize)| {
            let mut next = Instant::now();
            rl_testkit::allocations(|| {
                for k in 0..n {
                    cycle(d, k);
                    next += Duration::from_millis(1);
                    let now = Instant::now();
                    if next > now {
                        std::thread::sleep(next - now);
                    }
                }
            })
            .0
        };
    assert_eq!(
        paced(&mut d, 300, &mut cycle),
        0,
        "allocations in 300 good cycles"
    );
    fake.inject(Fault::LoseFrames { frames: 2 });
    fake.inject(Fault::WrongWorkingCounter { frames: 2 });
    std::thread::sleep(Duration::from_millis(5));
    assert_eq!(
        paced(&mut d, 20, &mut cycle),
        0,
        "allocations around lost frames and wrong working counters"
    );
    fake.inject(Fault::FallBackToSafeOp {
        device: 2,
        code: AlStatusCode::SM_WATCHDOG,
    });
    std::thread::sleep(Duration::from_millis(5));
    assert_eq!(
        paced(&mut d, 30, &mut cycle),
        0,
        "allocations while a device is recovered"
    );
    let c = d.process().unwrap().counters;
    assert!(
        c.wkc_errors >= 2 && c.recoveries >= 1,
        "the faults happened: {c:?}"
    );
    assert!(d.link_statistics().lost >= 2);
}
