//! Shared set-up for the controller tests and the control-step benchmark: the embedded RV-6SL
//! on a started H7 device against an in-process fake, and the default tour.
#![allow(dead_code)]

/// `Device` and `CyclicDevice` for a simulated device in this process: RL's life cycle through
/// rl-drivers' `Lifecycle` (field `lifecycle`), power and the state it was stopped from recorded
/// in its status (field `status`: `powered`, `stopped_from`), one `exchange` per step, the link's
/// failures in a row (field `link`) and its `period`.
macro_rules! sim_device {
    ($device:ty) => {
        impl $device {
            fn lifecycle_of(s: &mut Self) -> &mut rl::drivers::Lifecycle {
                &mut s.lifecycle
            }
        }

        impl rl::drivers::Device for $device {
            type Error = rl::drivers::Error;

            fn open(&mut self) -> Result<(), Self::Error> {
                rl::drivers::Lifecycle::transition(
                    self,
                    rl::drivers::Operation::Open,
                    Self::lifecycle_of,
                    |_| Ok(()),
                )
            }

            fn start(&mut self) -> Result<(), Self::Error> {
                rl::drivers::Lifecycle::transition(
                    self,
                    rl::drivers::Operation::Start,
                    Self::lifecycle_of,
                    |s| {
                        s.status.lock().expect("status").powered = true;
                        Ok(())
                    },
                )
            }

            fn stop(&mut self) -> Result<(), Self::Error> {
                let from = self.lifecycle.state();
                rl::drivers::Lifecycle::transition(
                    self,
                    rl::drivers::Operation::Stop,
                    Self::lifecycle_of,
                    |s| {
                        let mut st = s.status.lock().expect("status");
                        st.powered = false;
                        st.stopped_from = Some(from);
                        Ok(())
                    },
                )
            }

            fn close(&mut self) -> Result<(), Self::Error> {
                rl::drivers::Lifecycle::transition(
                    self,
                    rl::drivers::Operation::Close,
                    Self::lifecycle_of,
                    |_| Ok(()),
                )
            }

            fn state(&self) -> rl::drivers::State {
                self.lifecycle.state()
            }

            fn fault(&self) -> Option<Self::Error> {
                self.lifecycle.fault()
            }

            fn stop_description(&self) -> &'static str {
                "simulated drives disabled"
            }
        }

        impl rl::drivers::CyclicDevice for $device {
            fn step(&mut self) -> Result<(), Self::Error> {
                let r = rl::drivers::Lifecycle::step(self, Self::lifecycle_of, Self::exchange);
                self.link.consecutive_failures = self.lifecycle.consecutive_failures();
                r
            }

            fn update_period(&self) -> std::time::Duration {
                self.period
            }
        }
    };
}

pub mod arm;
pub mod sim;

use std::time::Duration;

use rl::controller::{Controller, MotionLimits, Plan, default_waypoints, rv6sl};
use rl::drivers::fake::h7_controller::{FakeH7, FakeH7Config, Pacing};
use rl::drivers::mitsubishi_h7::{MitsubishiH7, MitsubishiH7Config};
use rl::drivers::{CyclicDevice, Device, JointPositionSensor};

/// A fake H7 with six axes on its 7.11 ms cycle, its thread at a real-time priority where the
/// process may (a real controller has its own CPU), and an H7 device for it: for runs of the
/// embedded RV-6SL's tour.
pub fn realtime_fake_h7() -> (FakeH7, MitsubishiH7) {
    let fake = FakeH7::spawn(FakeH7Config {
        on_thread_start: Some(rl::devices::fake_thread_realtime),
        ..FakeH7Config::loopback(6)
    })
    .expect("fake H7");
    let robot = MitsubishiH7::new(MitsubishiH7Config::new(6, fake.udp_addr(), fake.r3_addr()))
        .expect("device");
    (fake, robot)
}

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

/// [`started_h7`] and where it reports the arm.
pub fn started_h7_standing(fake: &FakeH7, dof: usize) -> (MitsubishiH7, Vec<f64>) {
    let robot = started_h7(fake, dof);
    let mut start = vec![0.0; dof];
    robot.joint_position(&mut start).expect("joints");
    (robot, start)
}

/// The default tour at 25 % of the model's speed limits, from where the arm stands, on a
/// started H7 against `fake`.
pub fn demo_controller(fake: &FakeH7) -> Controller<MitsubishiH7> {
    let model = rv6sl().expect("embedded model").model;
    let (robot, start) = started_h7_standing(fake, model.dof());
    let limits = MotionLimits::<8>::from_model(&model, 0.25).expect("limits");
    let plan =
        Plan::new(&model, &start, &default_waypoints(&model, &start), &limits).expect("plan");
    Controller::new(robot, model, plan, PERIOD).expect("controller")
}

/// A controller stepped by hand with `law` on a started H7 against `fake` (the RV-6SL standing
/// where it is), limits at 0.25 of the model's speeds, the law started, the inputs attached (a
/// queue of `capacity`, a 60 s input timeout): what the tests of laws that take inputs share.
pub fn law_on_h7<L: rl::controller::ControlLaw<16, 8>>(
    fake: &FakeH7,
    mut law: L,
    capacity: usize,
) -> LawOnH7<L> {
    use rl::controller::law::Start;
    use rl::controller::{Supervision, input};

    let model = rv6sl().expect("embedded model").model;
    let dof = model.dof();
    let (robot, start) = started_h7_standing(fake, dof);
    let limits = MotionLimits::<8>::from_model(&model, 0.25).expect("limits");
    let (tx, rx) = input::channel::<16, 8, L::Input>(&model, capacity);
    law.start(&Start {
        position: &start,
        model: &model,
        limits: &limits,
        period_s: PERIOD.as_secs_f64(),
        device_period_s: PERIOD.as_secs_f64(),
        device_adds_gravity: false,
    })
    .expect("law starts");
    let mut control = Box::new(
        Controller::with_law(
            robot,
            model,
            law,
            &start,
            &limits,
            PERIOD,
            &Supervision::default(),
        )
        .expect("controller"),
    );
    control.attach_inputs(rx);
    control.input_timeout(Duration::from_secs(60));
    LawOnH7 {
        control,
        tx,
        start,
        limits,
    }
}

/// What [`law_on_h7`] makes.
pub struct LawOnH7<L: rl::controller::ControlLaw<16, 8>> {
    /// The controller, stepped by hand.
    pub control: Box<Controller<MitsubishiH7, 16, 8, L>>,
    /// Its inputs' sender.
    pub tx: rl::controller::InputSender<8, L::Input>,
    /// Where the arm stands.
    pub start: Vec<f64>,
    /// The limits it runs with.
    pub limits: MotionLimits<8>,
}

/// The tour's waypoints from `start` as a planned path (no obstacles) blended through its two
/// interior corners, as `rl run --plan` builds it — and with `retime`, then retimed with bounded
/// jerk (its default).
#[cfg(feature = "plan")]
pub fn tour_as_planned_path<const N: usize>(
    model: &rl::core::Model<N>,
    start: &[f64],
    limits: &MotionLimits<8>,
    retime: bool,
) -> rl::controller::PlanTrajectory<8> {
    use rl::controller::PlanTrajectory;
    use rl::controller::plan::BLENDED_SEGMENTS;
    use rl_plan::execute::{BlendOptions, Execution, ExecutionLimits, jerk_limited, rests_of};
    use rl_plan::validity::AlwaysValid;
    use rl_plan::{JointSpace, Path};

    let dof = model.dof();
    let mut points = vec![start.to_vec()];
    points.extend(default_waypoints(model, start));
    let space = JointSpace::from_model(model).expect("space");
    let execution = Execution::new(
        &space,
        &Path::from_points(dof, &points),
        ExecutionLimits {
            velocity: limits.velocity[..dof].to_vec(),
            acceleration: limits.acceleration[..dof].to_vec(),
            jerk: limits.jerk[..dof].to_vec(),
        },
    )
    .expect("execution");
    let blended = execution
        .blended::<8, BLENDED_SEGMENTS>(
            &space,
            &mut AlwaysValid::new(space.clone()),
            &BlendOptions::for_resolution(0.05),
        )
        .expect("blended");
    assert_eq!(blended.report.blended(), 2, "{}", blended.report);
    let path = blended.trajectory;
    if !retime {
        return PlanTrajectory::Blended(path);
    }
    let rests = rests_of::<8, _, BLENDED_SEGMENTS>(&*path, dof);
    let retimed = jerk_limited(path, &rests, execution.limits(), 1000, 1e-3).expect("retimed");
    PlanTrajectory::Retimed(Box::new(retimed))
}

/// The fake FR3 on loopback with the arm's dynamics integrated from `urdf` (its robot thread
/// at a real-time priority where allowed), and a Franka device for it in joint torque mode (not
/// opened).
pub fn fake_franka_in_torque_mode(
    urdf: &str,
) -> (
    rl::drivers::fake::franka_controller::FakeFranka,
    rl::drivers::franka::FrankaArm,
) {
    use rl::drivers::fake::franka_controller::{FakeFranka, FakeFrankaConfig};
    use rl::drivers::franka::{ControlMode, FrankaArm, FrankaConfig};
    use std::net::{IpAddr, Ipv4Addr};
    let fake = FakeFranka::spawn(FakeFrankaConfig {
        command_port: 0,
        on_thread_start: Some(rl::devices::fake_process_thread_realtime),
        ..FakeFrankaConfig::loopback().with_urdf(urdf.to_owned())
    })
    .expect("fake FR3");
    let mut config =
        FrankaConfig::new(IpAddr::V4(Ipv4Addr::LOCALHOST)).with_mode(ControlMode::JointTorque);
    config.command_port = fake.addr().port();
    (fake, FrankaArm::new(config).expect("device"))
}

/// A run on the fake FR3 that fell short on timing (the loop overran or missed deadlines, or
/// states or commands were lost) while the loop or the fake was measured late (the loop's
/// wake-ups, the fake's clock slipping or waking a quarter cycle late): the reason, for
/// `late::while_late` — whether the run failed or not, as `late::json_late` rules for runs
/// of the tool: what these tests measure of a law (how closely it tracks, how smoothly its
/// torques change) is the law's only on a machine that kept the time. A shortfall with both
/// on time, or a failure without one, is the run's own (`None`).
pub fn franka_run_late(
    r: &rl::controller::RunReport,
    fake: &rl::drivers::fake::franka_controller::FakeFranka,
) -> Option<String> {
    use rl::controller::lateness::Culprit;
    let f = fake.status();
    let shortfall = r.stats.overruns > 0 || r.stats.missed_deadlines > 0 || r.lost_packets > 0;
    let late = r.lateness().culprit() != Culprit::Nobody || f.slips > 0 || f.max_lateness_us > 250;
    (shortfall && late).then(|| {
        format!(
            "{r}\nthe fake: {} slips, {} µs late at most",
            f.slips, f.max_lateness_us
        )
    })
}
