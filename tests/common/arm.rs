//! A simulated arm with dynamics, for laws that command torques or velocities: each step it
//! applies the buffered command for one period and integrates the model's forward dynamics
//! (rl-core's ABA, gravity included) in sub-steps of semi-implicit Euler, like a drive in
//! cyclic synchronous torque (CST) or velocity (CSV) mode on a real arm. It refuses the kinds
//! of command its mode does not take (as a CiA 402 drive does), measures positions,
//! velocities and torques, and keeps RL's life cycle through rl-drivers' `Lifecycle`.
#![allow(dead_code, clippy::needless_range_loop)] // per-joint vectors indexed alike

use std::sync::{Arc, Mutex};
use std::time::Duration;

use rl::core::{Data, Model, algo};
use rl::drivers::{
    Error, JointDevice, JointPositionActuator, JointPositionSensor, JointTorqueActuator,
    JointTorqueSensor, JointVelocityActuator, JointVelocitySensor, Lifecycle, LinkStatistics,
    LinkStatisticsSensor, Operation, State,
};

/// What the simulated drives take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ArmMode {
    /// Joint torques (N·m): the arm moves by its dynamics.
    Torque,
    /// Joint velocities (rad/s), followed exactly (an ideal velocity loop).
    Velocity,
}

/// What the test sees of the arm from outside.
#[derive(Clone, Debug, Default)]
pub struct ArmStatus {
    /// Steps.
    pub steps: u64,
    /// Power on (between `start` and `stop`).
    pub powered: bool,
    /// Whether `stop()` ran (a safe state reached), and from which state.
    pub stopped_from: Option<State>,
    /// Joint positions now.
    pub q: Vec<f64>,
    /// Joint velocities now.
    pub qd: Vec<f64>,
    /// Commands refused because the mode does not take them.
    pub refused: u64,
    /// Commands taken.
    pub commands: u64,
}

/// The simulated arm.
pub struct SimArm {
    lifecycle: Lifecycle,
    model: Model<16>,
    data: Box<Data<16>>,
    mode: ArmMode,
    period: Duration,
    dof: usize,
    q: Vec<f64>,
    qd: Vec<f64>,
    tau: Vec<f64>,
    command: Vec<f64>,
    link: LinkStatistics,
    status: Arc<Mutex<ArmStatus>>,
    /// The count of measurements (periods of motion), reported where `numbered`.
    sample: u64,
    numbered: bool,
    /// Every `.0`-th exchange the arm moves `.1` periods (the states between lost: what a
    /// loop that woke late reads of a robot that kept its own clock).
    stall: Option<(u64, u32)>,
}

/// The simulated model refused a state (cannot happen for the vectors of its own length).
fn model_error<E>(_: E) -> Error {
    Error::InvalidArgument {
        what: "the simulated model",
        expected: 0,
        got: 1,
    }
}

/// Sub-steps of the integration per period.
const SUBSTEPS: u32 = 10;

impl SimArm {
    /// `model` standing still at `start`, stepping every `period`, taking `mode` commands.
    pub fn new(model: Model<16>, start: &[f64], mode: ArmMode, period: Duration) -> Self {
        let dof = model.dof();
        Self {
            lifecycle: Lifecycle::with_failure_limit(50),
            model,
            data: Box::new(Data::new()),
            mode,
            period,
            dof,
            q: start.to_vec(),
            qd: vec![0.0; dof],
            tau: vec![0.0; dof],
            command: vec![0.0; dof],
            link: LinkStatistics::default(),
            status: Arc::new(Mutex::new(ArmStatus {
                q: start.to_vec(),
                qd: vec![0.0; dof],
                ..ArmStatus::default()
            })),
            sample: 0,
            numbered: false,
            stall: None,
        }
    }

    /// Numbers its measurements ([`JointPositionSensor::joint_position_sample`]): one per
    /// period of motion.
    pub fn numbered(mut self) -> Self {
        self.numbered = true;
        self
    }

    /// Every `every`-th exchange moves the arm `periods` periods instead of one.
    pub fn stalling(mut self, every: u64, periods: u32) -> Self {
        self.stall = Some((every, periods));
        self
    }

    /// A handle on what the arm does.
    pub fn status(&self) -> Arc<Mutex<ArmStatus>> {
        self.status.clone()
    }

    fn exchange(&mut self) -> Result<(), Error> {
        self.link.sent += 1;
        let periods = match self.stall {
            Some((every, periods)) if self.link.sent % every == 0 => periods,
            _ => 1,
        };
        self.sample += u64::from(periods);
        let h = self.period.as_secs_f64() / f64::from(SUBSTEPS);
        for _ in 0..SUBSTEPS * periods {
            match self.mode {
                ArmMode::Torque => {
                    self.tau.copy_from_slice(&self.command);
                    let qdd = algo::aba(&self.model, &mut self.data, &self.q, &self.qd, &self.tau)
                        .map_err(model_error)?
                        .to_vec();
                    for k in 0..self.dof {
                        self.qd[k] += h * qdd[k];
                        self.q[k] += h * self.qd[k];
                    }
                }
                ArmMode::Velocity => {
                    for k in 0..self.dof {
                        self.qd[k] = self.command[k];
                        self.q[k] += h * self.qd[k];
                    }
                }
            }
        }
        if self.mode == ArmMode::Velocity {
            // The drives hold the arm against gravity: the torque they measure.
            let zero = vec![0.0; self.dof];
            self.tau = algo::rnea(&self.model, &mut self.data, &self.q, &self.qd, &zero)
                .map_err(model_error)?
                .to_vec();
        }
        let mut st = self.status.lock().expect("status");
        st.steps = self.link.sent;
        st.q.copy_from_slice(&self.q);
        st.qd.copy_from_slice(&self.qd);
        self.link.received += 1;
        Ok(())
    }

    fn refuse(&mut self) -> Result<(), Error> {
        self.status.lock().expect("status").refused += 1;
        Err(Error::InvalidArgument {
            what: "command kind does not match the configured mode",
            expected: 0,
            got: 1,
        })
    }

    fn read(&self, from: &[f64], to: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.dof, to.len())?;
        to.copy_from_slice(from);
        Ok(())
    }

    fn take(&mut self, values: &[f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        Error::check_len("joint vector length", self.dof, values.len())?;
        self.command.copy_from_slice(values);
        self.status.lock().expect("status").commands += 1;
        Ok(())
    }
}

sim_device!(SimArm);

impl JointDevice for SimArm {
    fn dof(&self) -> usize {
        self.dof
    }

    fn joint_velocity_actuator(&mut self) -> Option<&mut dyn JointVelocityActuator<Error = Error>> {
        (self.mode == ArmMode::Velocity).then_some(self as _)
    }

    fn joint_torque_actuator(&mut self) -> Option<&mut dyn JointTorqueActuator<Error = Error>> {
        (self.mode == ArmMode::Torque).then_some(self as _)
    }

    fn joint_velocity_sensor(&self) -> Option<&dyn JointVelocitySensor<Error = Error>> {
        Some(self)
    }

    fn joint_torque_sensor(&self) -> Option<&dyn JointTorqueSensor<Error = Error>> {
        Some(self)
    }
}

impl JointPositionSensor for SimArm {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.read(&self.q, q)
    }

    fn joint_position_sample(&self) -> Option<u64> {
        self.numbered.then_some(self.sample)
    }
}

impl JointVelocitySensor for SimArm {
    fn joint_velocity(&self, qd: &mut [f64]) -> Result<(), Error> {
        self.read(&self.qd, qd)
    }
}

impl JointTorqueSensor for SimArm {
    fn joint_torque(&self, tau: &mut [f64]) -> Result<(), Error> {
        self.read(&self.tau, tau)
    }
}

impl JointPositionActuator for SimArm {
    /// A drive in torque or velocity mode refuses position commands.
    fn set_joint_position(&mut self, _q: &[f64]) -> Result<(), Error> {
        self.refuse()
    }
}

impl JointVelocityActuator for SimArm {
    fn set_joint_velocity(&mut self, qd: &[f64]) -> Result<(), Error> {
        match self.mode {
            ArmMode::Velocity => self.take(qd),
            ArmMode::Torque => self.refuse(),
        }
    }
}

impl JointTorqueActuator for SimArm {
    fn set_joint_torque(&mut self, tau: &[f64]) -> Result<(), Error> {
        match self.mode {
            ArmMode::Torque => self.take(tau),
            ArmMode::Velocity => self.refuse(),
        }
    }
}

impl LinkStatisticsSensor for SimArm {
    fn link_statistics(&self) -> LinkStatistics {
        self.link
    }
}
