//! A simulated joint robot in this process, for the controller's tests: it follows each
//! command with a lag of a few cycles (as a position-controlled drive does), clamps at its
//! joint limits and reports that, and misbehaves on demand — frozen or corrupted replies,
//! lost replies, a dropped connection — so every supervision case can be driven without a
//! network. It keeps RL's life cycle through the same `Lifecycle` every driver uses.
#![allow(clippy::needless_range_loop)] // per-joint arrays indexed alike

use std::sync::{Arc, Mutex};
use std::time::Duration;

use rl::drivers::{
    Error, JointDevice, JointLimitSensor, JointPositionActuator, JointPositionSensor, Lifecycle,
    LinkStatistics, LinkStatisticsSensor, Operation, State,
};

/// What the simulated robot does wrong, from which step on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Misbehaviour {
    /// Nothing.
    None,
    /// Repeats its last reply forever.
    Freeze,
    /// Reports joint `0` as NaN.
    NotANumber,
    /// Reports joint 0 jumped by this much.
    Jump(f64),
    /// Loses every `n`-th reply.
    LoseEvery(u64),
    /// Loses every reply (a silent peer).
    Silent,
    /// The connection drops.
    Disconnect,
    /// Joint `k` is blocked where it stands (a collision, a brake).
    Block(usize),
}

/// What the test can see of the simulated robot from outside.
#[derive(Clone, Debug, Default)]
pub struct SimStatus {
    /// Steps.
    pub steps: u64,
    /// Whether `stop()` ran (a safe state reached), and from which state.
    pub stopped_from: Option<State>,
    /// Whether power is on (between `start` and `stop`).
    pub powered: bool,
    /// Commands received, per joint, the last one.
    pub last_command: Vec<f64>,
    /// Largest step between two commands, per joint.
    pub largest_step: Vec<f64>,
}

/// The simulated robot.
pub struct SimRobot {
    lifecycle: Lifecycle,
    dof: usize,
    period: Duration,
    lag: usize,
    lower: Vec<f64>,
    upper: Vec<f64>,
    actual: Vec<f64>,
    reported: Vec<f64>,
    history: Vec<Vec<f64>>,
    command: Option<Vec<f64>>,
    clamped: Vec<bool>,
    link: LinkStatistics,
    misbehaviour: Misbehaviour,
    misbehave_from: u64,
    resolution: f64,
    status: Arc<Mutex<SimStatus>>,
}

impl SimRobot {
    /// A robot with `dof` joints standing at `start`, within `[lower, upper]`, stepping every
    /// `period` and following commands `lag` steps late.
    pub fn new(start: &[f64], lower: &[f64], upper: &[f64], period: Duration, lag: usize) -> Self {
        let dof = start.len();
        let inside: Vec<f64> = (0..dof)
            .map(|k| start[k].clamp(lower[k], upper[k]))
            .collect();
        Self {
            lifecycle: Lifecycle::with_failure_limit(50),
            dof,
            period,
            lag,
            lower: lower.to_vec(),
            upper: upper.to_vec(),
            actual: start.to_vec(),
            reported: start.to_vec(),
            history: vec![inside; lag + 1],
            command: None,
            clamped: vec![false; dof],
            link: LinkStatistics::default(),
            misbehaviour: Misbehaviour::None,
            misbehave_from: u64::MAX,
            resolution: 0.0,
            status: Arc::new(Mutex::new(SimStatus {
                last_command: start.to_vec(),
                largest_step: vec![0.0; dof],
                ..SimStatus::default()
            })),
        }
    }

    /// Misbehaves as `m` from step `from` on.
    pub fn misbehave(mut self, m: Misbehaviour, from: u64) -> Self {
        self.misbehaviour = m;
        self.misbehave_from = from;
        self
    }

    /// Reports positions with this resolution (rad).
    pub fn resolution(mut self, resolution: f64) -> Self {
        self.resolution = resolution;
        self
    }

    /// A handle on what the robot saw.
    pub fn status(&self) -> Arc<Mutex<SimStatus>> {
        self.status.clone()
    }

    fn active(&self, m: Misbehaviour) -> bool {
        self.misbehaviour == m && self.link.sent >= self.misbehave_from
    }

    fn exchange(&mut self) -> Result<(), Error> {
        self.link.sent += 1;
        let n = self.link.sent;
        if let Some(c) = self.command.take() {
            let mut st = self.status.lock().expect("status");
            for k in 0..self.dof {
                let step = (c[k] - st.last_command[k]).abs();
                st.largest_step[k] = st.largest_step[k].max(step);
            }
            st.last_command = c.clone();
            drop(st);
            self.history.push(c);
            if self.history.len() > self.lag + 1 {
                self.history.remove(0);
            }
        }
        let target = self.history[0].clone();
        for k in 0..self.dof {
            let blocked = matches!(self.misbehaviour, Misbehaviour::Block(j) if j == k)
                && n >= self.misbehave_from;
            if !blocked {
                let clamped = target[k].clamp(self.lower[k], self.upper[k]);
                self.clamped[k] = clamped != target[k];
                self.actual[k] = clamped;
            }
        }
        self.status.lock().expect("status").steps = n;
        if self.active(Misbehaviour::Disconnect) {
            return Err(Error::Disconnected {
                operation: Operation::Step,
            });
        }
        let lose = self.active(Misbehaviour::Silent)
            || matches!(self.misbehaviour, Misbehaviour::LoseEvery(e) if n >= self.misbehave_from && n % e == 0);
        if lose {
            self.link.lost += 1;
            return Err(Error::Timeout {
                operation: Operation::Step,
                waited: self.period,
            });
        }
        if !self.active(Misbehaviour::Freeze) {
            self.reported = self.actual.clone();
            if self.active(Misbehaviour::NotANumber) {
                self.reported[0] = f64::NAN;
            }
            if let Misbehaviour::Jump(d) = self.misbehaviour {
                if n >= self.misbehave_from {
                    self.reported[0] = self.actual[0] + d;
                }
            }
        }
        self.link.received += 1;
        Ok(())
    }
}

sim_device!(SimRobot);

impl JointDevice for SimRobot {
    fn dof(&self) -> usize {
        self.dof
    }

    fn joint_limit_sensor(&self) -> Option<&dyn JointLimitSensor<Error = Error>> {
        Some(self)
    }
}

impl JointPositionSensor for SimRobot {
    fn joint_position(&self, q: &mut [f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Get)?;
        Error::check_len("joint vector length", self.dof, q.len())?;
        q.copy_from_slice(&self.reported);
        Ok(())
    }

    fn joint_position_resolution(&self, _q: f64) -> f64 {
        self.resolution
    }
}

impl JointPositionActuator for SimRobot {
    fn set_joint_position(&mut self, q: &[f64]) -> Result<(), Error> {
        self.lifecycle.check(Operation::Set)?;
        Error::check_len("joint vector length", self.dof, q.len())?;
        self.command = Some(q.to_vec());
        Ok(())
    }
}

impl JointLimitSensor for SimRobot {
    fn joint_limit_reached(&self, reached: &mut [bool]) -> Result<(), Error> {
        reached.copy_from_slice(&self.clamped);
        Ok(())
    }
}

impl LinkStatisticsSensor for SimRobot {
    fn link_statistics(&self) -> LinkStatistics {
        self.link
    }
}
