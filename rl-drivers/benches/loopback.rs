//! Round trip of one `step()` against the loopback fakes (H7 over UDP, Coach over TCP): the
//! communication cost a control cycle pays on this machine, without the 7.11 ms pacing.
#![allow(missing_docs)] // criterion_group! generates an undocumented function

use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use rl_drivers::coach::{Coach, CoachConfig};
use rl_drivers::fake::coach_server::{CoachServer, CoachServerConfig};
use rl_drivers::fake::h7_controller::{FakeH7, FakeH7Config, Pacing};
use rl_drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl_drivers::{CyclicDevice, Device, JointPositionActuator};

fn h7_step(c: &mut Criterion) {
    // Unpaced: the communication cost itself, not the controller's cycle.
    let fake = FakeH7::spawn(FakeH7Config {
        pacing: Pacing::Immediate,
        ..FakeH7Config::loopback(6)
    })
    .expect("fake H7");
    let mut robot =
        MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr())).unwrap();
    robot.open().unwrap();
    robot.start().unwrap();
    let mut k = 0.0;
    c.bench_function("h7 step round trip (loopback)", |b| {
        b.iter(|| {
            k += 1e-4;
            robot.set_joint_position(&[k; 6]).unwrap();
            robot.step().unwrap();
        })
    });
    robot.stop().unwrap();
}

fn coach_step(c: &mut Criterion) {
    let server = CoachServer::spawn(CoachServerConfig {
        models: vec![(0, vec![0.0; 6])],
        ..CoachServerConfig::loopback()
    })
    .expect("Coach server");
    let mut config = CoachConfig::new(6);
    config.server = server.addr();
    config.reply_timeout = Duration::from_secs(1);
    let mut coach = Coach::new(config).unwrap();
    coach.open().unwrap();
    coach.start().unwrap();
    let mut k = 0.0;
    c.bench_function("coach step round trip (loopback)", |b| {
        b.iter(|| {
            k += 1e-4;
            coach.set_joint_position(&[k; 6]).unwrap();
            coach.step().unwrap();
        })
    });
}

criterion_group!(benches, h7_step, coach_step);
criterion_main!(benches);
