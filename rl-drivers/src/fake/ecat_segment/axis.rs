//! A CiA 402 servo axis behind the fake drive's object dictionary: the power state machine of
//! the shared [`cia402`](crate::cia402) module driven by the controlword (0x6040), and a motor
//! that follows the cyclic synchronous targets of the mode in 0x6060:
//!
//! - CSP (8): the position reaches the target (0x607A) one cycle later, clamped to the
//!   software limits (0x607D, statusword bit 11 "internal limit") and to the maximum speed
//!   (0x607F); the torque is the torque offset (0x60B2) plus the inertia's share.
//! - CSV (9): the velocity is the target velocity (0x60FF) plus the offset (0x60B1).
//! - CST (10): the torque is the target torque (0x6071) plus the offset (0x60B2), limited to
//!   0x6072; the motor accelerates with `torque / inertia` against viscous friction.
//!
//! Positions are in the drive's position units ([`MotorParams::units`]: the feed constant per
//! joint revolution, encoder increments by default), torques thousandths of the motor's rated
//! torque (0x6076 mN·m) ahead of its gear, as a real drive reports them. The firmware calls [`Axis::update`] once per SYNC0 pulse in DC mode
//! (a drive in CSP waits for SYNC0) or once per new output buffer in free run.

use super::dictionary::Dictionary;
use crate::cia402::object as obj;
use crate::cia402::{AxisUnits, Mode, PowerState, Statusword};

/// The motor's physical parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorParams {
    /// Encoder, gear, feed constant and rated torque: what the drive reports in 0x608F, 0x6091,
    /// 0x6092 and 0x6076, and how its position units relate to the joint.
    pub units: AxisUnits,
    /// Whether the drive has the factor-group objects 0x608F, 0x6091, 0x6092 (`false`: an SDO
    /// upload of them is aborted with "object does not exist").
    pub unit_objects: bool,
    /// Inertia at the joint in kg·m².
    pub inertia: f64,
    /// Viscous friction at the joint in N·m·s/rad.
    pub damping: f64,
}

impl Default for MotorParams {
    fn default() -> Self {
        Self {
            units: AxisUnits::default(),
            unit_objects: true,
            inertia: 1e-3,
            damping: 1e-3,
        }
    }
}

impl MotorParams {
    /// Position units per joint radian.
    pub fn per_rad(&self) -> f64 {
        self.units.units_per_rev() / core::f64::consts::TAU
    }

    /// Joint torque per thousandth of the rated motor torque, N·m.
    fn joint_torque_per_permille(&self) -> f64 {
        self.units.rated_torque_nm * self.units.gear_ratio / 1000.0
    }
}

/// One axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Its parameters.
    pub motor: MotorParams,
    state: PowerState,
    previous_cw: u16,
    position: f64,
    velocity: f64,
    torque_permille: f64,
    error_code: u16,
    updates: u64,
}

impl Axis {
    /// An axis standing at `position` counts, switch on disabled.
    pub fn new(motor: MotorParams, position: i32) -> Self {
        Self {
            motor,
            state: PowerState::SwitchOnDisabled,
            previous_cw: 0,
            position: f64::from(position),
            velocity: 0.0,
            torque_permille: 0.0,
            error_code: 0,
            updates: 0,
        }
    }

    /// The power state.
    pub fn state(&self) -> PowerState {
        self.state
    }

    /// The position in counts.
    pub fn position(&self) -> f64 {
        self.position
    }

    /// Updates so far.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// A fault detected by the drive (`error_code` as in 0x603F): fault reaction, then fault.
    pub fn fault(&mut self, error_code: u16) {
        self.state = PowerState::Fault;
        self.error_code = error_code;
        self.velocity = 0.0;
        self.torque_permille = 0.0;
    }

    /// Applies the controlword in the dictionary (called once per new output buffer or SDO
    /// write, before [`update`](Self::update)).
    pub fn apply_controlword(&mut self, od: &Dictionary) {
        let cw = od.int(obj::CONTROLWORD.index, 0) as u16;
        let next = self.state.on_controlword(cw, self.previous_cw);
        if self.state == PowerState::Fault && next != PowerState::Fault {
            self.error_code = 0;
        }
        self.state = next;
        self.previous_cw = cw;
    }

    /// Advances the motor by `dt` seconds and writes the measurements into the dictionary.
    pub fn update(&mut self, od: &mut Dictionary, dt: f64) {
        self.updates += 1;
        let mode = Mode::from_code(od.int(obj::MODES_OF_OPERATION.index, 0) as i8);
        let per_rad = self.motor.per_rad();
        let mut limit = false;
        let mut following_error = false;
        let previous = self.position;
        match (self.state, mode) {
            (PowerState::OperationEnabled, Some(Mode::CyclicPosition)) => {
                let mut target = od.int(obj::TARGET_POSITION.index, 0) as f64;
                let (lo, hi) = (
                    od.int(obj::SOFTWARE_LIMIT_MIN.index, 1) as f64,
                    od.int(obj::SOFTWARE_LIMIT_MAX.index, 2) as f64,
                );
                if lo < hi && (target < lo || target > hi) {
                    target = target.clamp(lo, hi);
                    limit = true;
                }
                let vmax = od.int(obj::MAX_PROFILE_VELOCITY.index, 0) as f64;
                let step = target - self.position;
                if vmax > 0.0 && dt > 0.0 && step.abs() > vmax * dt {
                    self.position += step.signum() * vmax * dt;
                    limit = true;
                } else {
                    self.position = target;
                }
                let window = od.int(obj::FOLLOWING_ERROR_WINDOW.index, 0) as f64;
                following_error = window > 0.0 && (target - self.position).abs() > window;
                let v = if dt > 0.0 {
                    (self.position - previous) / dt
                } else {
                    0.0
                };
                let acc = if dt > 0.0 {
                    (v - self.velocity) / dt
                } else {
                    0.0
                };
                self.velocity = v;
                let offset = od.int(obj::TORQUE_OFFSET.index, 0) as f64;
                let inertial =
                    self.motor.inertia * acc / per_rad / self.motor.joint_torque_per_permille();
                self.torque_permille = offset + inertial;
            }
            (PowerState::OperationEnabled, Some(Mode::CyclicVelocity)) => {
                self.velocity = (od.int(obj::TARGET_VELOCITY.index, 0)
                    + od.int(obj::VELOCITY_OFFSET.index, 0)) as f64;
                self.position += self.velocity * dt;
                self.torque_permille = od.int(obj::TORQUE_OFFSET.index, 0) as f64;
            }
            (PowerState::OperationEnabled, Some(Mode::CyclicTorque)) => {
                let max = od.int(obj::MAX_TORQUE.index, 0) as f64;
                let mut t = (od.int(obj::TARGET_TORQUE.index, 0)
                    + od.int(obj::TORQUE_OFFSET.index, 0)) as f64;
                if max > 0.0 && t.abs() > max {
                    t = t.signum() * max;
                    limit = true;
                }
                self.torque_permille = t;
                let tau = t * self.motor.joint_torque_per_permille();
                let w = self.velocity / per_rad;
                let acc = (tau - self.motor.damping * w) / self.motor.inertia;
                let w2 = w + acc * dt;
                self.position += 0.5 * (w + w2) * dt * per_rad;
                self.velocity = w2 * per_rad;
            }
            (PowerState::QuickStopActive, _) => {
                // Decelerate at 10 joint revolutions/s² to standstill.
                let dec = 10.0 * self.motor.units.units_per_rev() * dt;
                let v = self.velocity;
                self.velocity = if v.abs() <= dec {
                    0.0
                } else {
                    v - v.signum() * dec
                };
                self.position += self.velocity * dt;
                self.torque_permille = 0.0;
            }
            _ => {
                self.velocity = 0.0;
                self.torque_permille = 0.0;
            }
        }
        self.write_measurements(od, mode, limit, following_error);
    }

    /// Writes the statusword and actual values into the dictionary without moving.
    pub fn write_measurements(
        &self,
        od: &mut Dictionary,
        mode: Option<Mode>,
        limit: bool,
        following_error: bool,
    ) {
        let mut sw = self.state.statusword_bits() | Statusword::REMOTE;
        if !matches!(
            self.state,
            PowerState::NotReadyToSwitchOn | PowerState::SwitchOnDisabled | PowerState::Fault
        ) {
            sw |= Statusword::VOLTAGE_ENABLED;
        }
        let cyclic = matches!(
            mode,
            Some(Mode::CyclicPosition | Mode::CyclicVelocity | Mode::CyclicTorque)
        );
        if self.state == PowerState::OperationEnabled && cyclic {
            sw |= Statusword::FOLLOWS_TARGET | Statusword::TARGET_REACHED;
        }
        if limit {
            sw |= Statusword::INTERNAL_LIMIT;
        }
        if following_error {
            sw |= Statusword::FOLLOWING_ERROR;
        }
        od.set_int(obj::STATUSWORD.index, 0, i64::from(sw));
        od.set_int(
            obj::MODES_DISPLAY.index,
            0,
            mode.map_or(0, |m| i64::from(m.code())),
        );
        od.set_int(obj::POSITION_ACTUAL.index, 0, self.position.round() as i64);
        od.set_int(obj::VELOCITY_ACTUAL.index, 0, self.velocity.round() as i64);
        od.set_int(
            obj::TORQUE_ACTUAL.index,
            0,
            self.torque_permille.round() as i64,
        );
        od.set_int(
            obj::FOLLOWING_ERROR_ACTUAL.index,
            0,
            (od.int(obj::TARGET_POSITION.index, 0) as f64 - self.position).round() as i64,
        );
        od.set_int(obj::ERROR_CODE.index, 0, i64::from(self.error_code));
    }
}
