//! Shared set-up for the controller tests and the control-step benchmark: the embedded RV-6SL
//! on a started H7 device against an in-process fake, and the default tour.
#![allow(dead_code)]

pub mod arm;
pub mod sim;

use std::time::Duration;

use rl::controller::{Controller, MotionLimits, Plan, default_waypoints, rv6sl};
use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config, Pacing};
use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl::drivers::{CyclicDevice, Device, JointPositionSensor};

/// A fake H7 with `dof` axes that answers at once instead of on its 7.11 ms cycle: for tests
/// that step the controller by hand (its logic, not its timing).
pub fn immediate_fake(dof: usize) -> FakeH7 {
    let mut config = FakeH7Config::loopback(dof);
    config.pacing = Pacing::Immediate;
    FakeH7::spawn(config).expect("fake H7")
}

/// The H7's control period.
pub const PERIOD: Duration = Duration::from_micros(7110);

/// An H7 device talking to `fake`, opened, started and past its first exchange.
pub fn started_h7(fake: &FakeH7, dof: usize) -> MitsubishiH7 {
    let config = MitsubishiH7Config::new(dof, fake.udp_addr(), fake.r3_addr());
    let mut robot = MitsubishiH7::new(config).expect("device");
    robot.open().expect("open");
    robot.start().expect("start");
    robot.step().expect("first exchange");
    robot
}

/// The default tour at 25 % of the model's speed limits, from where the arm stands, on a
/// started H7 against `fake`.
pub fn demo_controller(fake: &FakeH7) -> Controller<MitsubishiH7> {
    let model = rv6sl().expect("embedded model").model;
    let dof = model.dof();
    let robot = started_h7(fake, dof);
    let mut start = vec![0.0; dof];
    robot.joint_position(&mut start).expect("joints");
    let limits = MotionLimits::<8>::from_model(&model, 0.25).expect("limits");
    let plan =
        Plan::new(&model, &start, &default_waypoints(&model, &start), &limits).expect("plan");
    Controller::new(robot, model, plan, PERIOD).expect("controller")
}
