//! The simulated motor of one fake drive, in drive units (counts, counts/s, ‰ of rated
//! torque): it follows its target per mode within the position, velocity and acceleration
//! limits, and decelerates on a quick stop.

use crate::cia402::Mode;

/// Limits and gains, in drive units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorLimits {
    /// Lowest position, counts.
    pub lower: f64,
    /// Highest position, counts.
    pub upper: f64,
    /// Highest speed, counts/s.
    pub max_velocity: f64,
    /// Highest acceleration (CSV, quick stop), counts/s².
    pub max_acceleration: f64,
    /// Acceleration per ‰ of rated torque (CST), counts/s² per ‰.
    pub acceleration_per_permille: f64,
    /// Torque reported per count of following error (CSP, CSV), ‰ per count.
    pub stiffness_permille_per_count: f64,
}

/// The motor's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motor {
    /// Position, counts.
    pub position: f64,
    /// Velocity, counts/s.
    pub velocity: f64,
    /// Torque, ‰.
    pub torque: f64,
    /// The target after clamping to the limits (CSP), counts.
    pub demand: f64,
    /// Whether the last target was clamped to a limit.
    pub at_limit: bool,
    /// The limits.
    pub limits: MotorLimits,
}

/// What the drive commands this interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Targets {
    /// 0x607A.
    pub position: i32,
    /// 0x60FF.
    pub velocity: i32,
    /// 0x6071.
    pub torque: i16,
    /// 0x60B2.
    pub torque_offset: i16,
    /// 0x6072.
    pub max_torque: u16,
}

/// How the power stage drives the motor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drive {
    /// Torque on: follow the targets.
    Enabled,
    /// Decelerate at the acceleration limit to standstill.
    QuickStop,
    /// Power off, brake on: stand still.
    Off,
}

impl Motor {
    /// A motor standing at `position`.
    pub fn new(position: f64, limits: MotorLimits) -> Self {
        Self {
            position,
            velocity: 0.0,
            torque: 0.0,
            demand: position,
            at_limit: false,
            limits,
        }
    }

    /// Advances `dt` seconds.
    pub fn advance(&mut self, dt: f64, drive: Drive, mode: Mode, t: Targets) {
        let l = self.limits;
        self.at_limit = false;
        let max_torque = f64::from(t.max_torque.max(1));
        match drive {
            Drive::Off => {
                self.velocity = 0.0;
                self.torque = 0.0;
                self.demand = self.position;
            }
            Drive::QuickStop => {
                let dv = (l.max_acceleration * dt).min(self.velocity.abs());
                let v0 = self.velocity;
                self.velocity -= dv * v0.signum();
                self.position += 0.5 * (v0 + self.velocity) * dt;
                self.torque = 0.0;
                self.demand = self.position;
            }
            Drive::Enabled => match mode {
                Mode::CyclicVelocity => {
                    let want = f64::from(t.velocity).clamp(-l.max_velocity, l.max_velocity);
                    let dv = (want - self.velocity)
                        .clamp(-l.max_acceleration * dt, l.max_acceleration * dt);
                    self.velocity += dv;
                    self.position += self.velocity * dt;
                    self.clamp_position();
                    self.demand = self.position;
                    self.torque = (f64::from(t.torque_offset)
                        + dv / dt.max(1e-9) / l.acceleration_per_permille.max(1e-9))
                    .clamp(-max_torque, max_torque);
                }
                Mode::CyclicTorque => {
                    let tau = (f64::from(t.torque) + f64::from(t.torque_offset))
                        .clamp(-max_torque, max_torque);
                    self.velocity = (self.velocity + tau * l.acceleration_per_permille * dt)
                        .clamp(-l.max_velocity, l.max_velocity);
                    self.position += self.velocity * dt;
                    self.clamp_position();
                    self.demand = self.position;
                    self.torque = tau;
                }
                _ => {
                    let target = f64::from(t.position);
                    self.demand = target.clamp(l.lower, l.upper);
                    self.at_limit = self.demand != target;
                    let step = (self.demand - self.position)
                        .clamp(-l.max_velocity * dt, l.max_velocity * dt);
                    self.position += step;
                    self.velocity = if dt > 0.0 { step / dt } else { 0.0 };
                    let error = self.demand - self.position;
                    self.torque = (f64::from(t.torque_offset)
                        + l.stiffness_permille_per_count * error)
                        .clamp(-max_torque, max_torque);
                }
            },
        }
    }

    fn clamp_position(&mut self) {
        let (lo, hi) = (self.limits.lower, self.limits.upper);
        if self.position < lo || self.position > hi {
            self.position = self.position.clamp(lo, hi);
            self.velocity = 0.0;
            self.at_limit = true;
        }
    }

    /// The following error (CSP), counts.
    pub fn following_error(&self) -> f64 {
        self.demand - self.position
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> MotorLimits {
        MotorLimits {
            lower: -1000.0,
            upper: 1000.0,
            max_velocity: 10_000.0,
            max_acceleration: 100_000.0,
            acceleration_per_permille: 100.0,
            stiffness_permille_per_count: 1.0,
        }
    }

    fn targets(position: i32) -> Targets {
        Targets {
            position,
            velocity: 0,
            torque: 0,
            torque_offset: 0,
            max_torque: 3000,
        }
    }

    #[test]
    fn csp_follows_within_the_speed_and_position_limits() {
        let mut m = Motor::new(0.0, limits());
        m.advance(0.002, Drive::Enabled, Mode::CyclicPosition, targets(15));
        assert_eq!(m.position, 15.0);
        m.advance(0.002, Drive::Enabled, Mode::CyclicPosition, targets(500));
        assert_eq!(m.position, 35.0, "10 000 counts/s for 2 ms");
        m.advance(0.002, Drive::Enabled, Mode::CyclicPosition, targets(5000));
        assert!(m.at_limit && m.demand == 1000.0);
        m.advance(0.002, Drive::Off, Mode::CyclicPosition, targets(0));
        assert_eq!(m.velocity, 0.0);
    }

    #[test]
    fn a_quick_stop_decelerates_to_standstill() {
        let mut m = Motor::new(0.0, limits());
        m.velocity = 1000.0;
        m.advance(0.005, Drive::QuickStop, Mode::CyclicPosition, targets(0));
        assert_eq!(m.velocity, 500.0);
        m.advance(0.01, Drive::QuickStop, Mode::CyclicPosition, targets(0));
        assert_eq!(m.velocity, 0.0);
    }
}
