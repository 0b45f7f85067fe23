//! Supervision: what every control cycle checks before it trusts the device, and the faults
//! that end a run.
//!
//! Each cycle the [`Supervisor`] looks at
//! - the feedback: a position that is not finite, outside the model's limits (beyond the
//!   device's own resolution), a jump larger than the joint can move between two replies, or
//!   a reply frozen while the command moves;
//! - the tracking error `commanded − measured` against a bound per joint;
//! - the commanded step against what the speed limit allows in one cycle;
//! - a limit the device reports (a clamped or refused command, a limit switch);
//! - the link: a lost connection, lost replies in a row (a short loss, then a dead link), the
//!   loss rate over a window;
//! - the loop: deadlines missed and overruns in a row.
//!
//! Any of these is a [`Fault`]. A fault that leaves a working link brings the arm to rest along
//! its path; one that does not ([`Fault::stops_at_once`]) ends the run at once. Either way the
//! device is then stopped (end of motion, power off) and the run fails with the reason.
//!
//! Lost replies in a row are two faults: [`Supervision::rest_after_lost`] of them (3) are a
//! short loss ([`Fault::LinkInterrupted`]): the arm is brought to rest along its path, the
//! commands going on every cycle, so a link that comes back finds the arm slowing down on the
//! path it was on; [`Supervision::max_consecutive_lost`] of them (10) are a dead link
//! ([`Fault::ConsecutiveLost`]): the run stops at once. A device that gives up on its own after
//! lost replies (its own bound) is a dead link too.
//!
//! Default bounds, per joint `k` with speed limit `v_k` (the model's, or the assumed speed),
//! control period `P` and device cycle `D`:
//! - tracking error: `tracking_cycles · v_k · max(P, D)` (4 cycles at full speed; the planned
//!   speed is a fraction of `v_k`, and a position-controlled drive lags a few cycles);
//! - commanded step: `v_k · min(P, D)` (the device executes a step within its own cycle);
//! - feedback jump between two replies `n` cycles apart: `jump_factor · v_k · max(P, D) · n`
//!   (twice the speed limit: the device samples on its own clock);
//! - frozen: `frozen_cycles` identical replies while the command moved more than the
//!   resolution.
//!
//! Nothing here allocates.

use core::fmt;

use rl_drivers::safety::{StopCategory, StopReason};
use rl_drivers::{DeviceError, Error as DeviceErrorValue, ErrorKind, LinkStatistics};

/// What the supervisor checks and its bounds. [`Supervision::default`] is on, with the bounds
/// in the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct Supervision {
    /// Whether faults end the run (off: nothing is checked; for bench set-ups only).
    pub enabled: bool,
    /// Tracking error bound per joint (rad or m); empty: derived from the speed limits.
    pub tracking_error: Vec<f64>,
    /// Cycles of full-speed motion the derived tracking bound allows.
    pub tracking_cycles: f64,
    /// Feedback jumps allowed, as a multiple of the speed limit.
    pub jump_factor: f64,
    /// Identical replies in a row, while the command moves, that count as a frozen device.
    pub frozen_cycles: u32,
    /// Lost replies in a row that are a short loss: the arm is brought to rest along its path.
    pub rest_after_lost: u32,
    /// Lost replies in a row that mean the link is dead: the run stops at once (at least
    /// [`rest_after_lost`](Self::rest_after_lost)).
    pub max_consecutive_lost: u32,
    /// Cycles over which the loss rate is measured (at most [`LOSS_WINDOW_MAX`]).
    pub loss_window: u32,
    /// Highest fraction of lost replies over the window.
    pub max_loss_rate: f64,
    /// Deadlines the loop may miss in a row.
    pub max_consecutive_missed_deadlines: u32,
    /// Cycles in a row that may overrun their period.
    pub max_consecutive_overruns: u32,
    /// Whether a limit the device reports is a fault.
    pub device_limits: bool,
}

/// The longest loss-rate window.
pub const LOSS_WINDOW_MAX: u32 = 256;

impl Default for Supervision {
    fn default() -> Self {
        Self {
            enabled: true,
            tracking_error: Vec::new(),
            tracking_cycles: 4.0,
            jump_factor: 2.0,
            frozen_cycles: 10,
            rest_after_lost: 3,
            max_consecutive_lost: 10,
            loss_window: 100,
            max_loss_rate: 0.1,
            max_consecutive_missed_deadlines: 3,
            max_consecutive_overruns: 5,
            device_limits: true,
        }
    }
}

impl Supervision {
    /// Supervision switched off.
    pub fn off() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }

    /// The bound to give the device on its own failed steps in a row: one above the dead-link
    /// bound, so that the supervisor names the loss first.
    pub fn device_failure_limit(&self) -> u32 {
        self.max_consecutive_lost.saturating_add(1)
    }

    /// Widens the derived tracking bound by a device's own lag: measured joints that follow
    /// the commands `lag` later (a first-order smoothing, as a UR's `servoj` lookahead) trail
    /// them by up to `v_k · lag`, on top of the [`tracking_cycles`](Self::tracking_cycles) of
    /// `cycle` (the slower of the control period and the device's cycle).
    pub fn allow_device_lag(&mut self, lag: core::time::Duration, cycle: core::time::Duration) {
        if !lag.is_zero() && !cycle.is_zero() {
            self.tracking_cycles += lag.as_secs_f64() / cycle.as_secs_f64();
        }
    }
}

/// What was wrong with a feedback value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FeedbackFault {
    /// NaN or infinite.
    NotFinite,
    /// Outside the model's limits by more than the device's resolution.
    OutsideLimits {
        /// The lower limit.
        lower: f64,
        /// The upper limit.
        upper: f64,
    },
    /// Moved more between two replies than the joint can.
    Jump {
        /// The change.
        jump: f64,
        /// The bound.
        bound: f64,
    },
}

/// Why a run was ended by the supervisor or the device.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// The tracking error of a joint exceeded its bound.
    TrackingError {
        /// Joint index.
        joint: usize,
        /// `commanded − measured`.
        error: f64,
        /// The bound.
        bound: f64,
    },
    /// A commanded step exceeded what the joint may move in one cycle.
    CommandStep {
        /// Joint index.
        joint: usize,
        /// The step.
        step: f64,
        /// The bound.
        bound: f64,
    },
    /// The device reported the joint at a limit (a clamped or refused command).
    DeviceLimit {
        /// Joint index.
        joint: usize,
    },
    /// A measured value cannot be trusted.
    Feedback {
        /// Joint index.
        joint: usize,
        /// The measured value.
        value: f64,
        /// What was wrong.
        fault: FeedbackFault,
    },
    /// The device repeated the same reply while the command moved.
    Frozen {
        /// Identical replies in a row.
        cycles: u32,
    },
    /// The connection to the device is gone.
    LinkLost {
        /// The error that showed it.
        error: DeviceErrorValue,
    },
    /// Replies lost in a row: a short loss; the arm is brought to rest along its path.
    LinkInterrupted {
        /// Lost in a row.
        count: u32,
        /// The bound ([`Supervision::rest_after_lost`]).
        bound: u32,
    },
    /// So many replies lost in a row that the link is dead ([`Supervision::max_consecutive_lost`]).
    ConsecutiveLost {
        /// Lost in a row.
        count: u32,
        /// The bound.
        bound: u32,
    },
    /// Too many replies lost over the window.
    LossRate {
        /// Lost in the window.
        lost: u32,
        /// The window, cycles.
        window: u32,
        /// The highest rate allowed.
        bound: f64,
    },
    /// The loop missed too many deadlines in a row.
    MissedDeadlines {
        /// Missed in a row.
        count: u64,
        /// The bound.
        bound: u32,
    },
    /// Too many cycles in a row overran their period.
    Overruns {
        /// Overruns in a row.
        count: u32,
        /// The bound.
        bound: u32,
    },
    /// The device faulted (it refuses to step).
    Device {
        /// Its reason.
        error: DeviceErrorValue,
    },
    /// The safety chain stopped the run (an e-stop opened, the enable was released, a pin
    /// failed): in category 0 at once, in category 1 brought to rest first.
    Safety {
        /// How.
        category: StopCategory,
        /// Why, with the pin.
        reason: StopReason,
    },
}

impl Fault {
    /// Whether the run must end at once: the link or the device can no longer carry a
    /// command, so there is no coming to rest along the path.
    pub fn stops_at_once(&self) -> bool {
        matches!(
            self,
            Fault::LinkLost { .. }
                | Fault::ConsecutiveLost { .. }
                | Fault::Device { .. }
                | Fault::Safety {
                    category: StopCategory::Zero,
                    ..
                }
        )
    }

    /// The fault that ends a run which `self` began: a short loss that became a dead link (or
    /// a lost connection) is one incident, ended by the later fault; any other first fault
    /// stays the run's reason.
    pub fn ended_by(self, later: Fault) -> Fault {
        match self {
            Fault::LinkInterrupted { .. } if later.stops_at_once() => later,
            first => first,
        }
    }

    /// The joint it concerns, if one.
    pub fn joint(&self) -> Option<usize> {
        match self {
            Fault::TrackingError { joint, .. }
            | Fault::CommandStep { joint, .. }
            | Fault::DeviceLimit { joint }
            | Fault::Feedback { joint, .. } => Some(*joint),
            _ => None,
        }
    }

    /// The fault described with joints named from `joints`.
    pub fn describe(&self, joints: &[String]) -> String {
        let name = |k: &usize| joints.get(*k).map_or_else(|| format!("#{k}"), Clone::clone);
        match self {
            Fault::TrackingError {
                joint,
                error,
                bound,
            } => format!(
                "tracking error of joint {} is {:.4}, beyond its bound {:.4}",
                name(joint),
                error,
                bound
            ),
            Fault::CommandStep { joint, step, bound } => format!(
                "commanded step of joint {} is {:.4}, more than the {:.4} its speed limit allows \
                 in one cycle",
                name(joint),
                step,
                bound
            ),
            Fault::DeviceLimit { joint } => {
                format!("the device reports joint {} at a limit", name(joint))
            }
            Fault::Feedback {
                joint,
                value,
                fault,
            } => match fault {
                FeedbackFault::NotFinite => {
                    format!("the device reported joint {} as {value}", name(joint))
                }
                FeedbackFault::OutsideLimits { lower, upper } => format!(
                    "the device reported joint {} at {value}, outside its limits [{lower}, {upper}]",
                    name(joint)
                ),
                FeedbackFault::Jump { jump, bound } => format!(
                    "the device reported joint {} jumping by {jump:.4} between two replies \
                     (at most {bound:.4} is possible)",
                    name(joint)
                ),
            },
            other => other.to_string(),
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Fault::Frozen { cycles } => write!(
                f,
                "the device sent the same reply {cycles} times in a row while the command moved"
            ),
            Fault::LinkLost { error } => write!(f, "the link to the device is lost: {error}"),
            Fault::LinkInterrupted { count, bound } => write!(
                f,
                "{count} replies lost in a row ({bound} are a short loss): brought to rest along \
                 the path"
            ),
            Fault::ConsecutiveLost { count, bound } => write!(
                f,
                "{count} replies lost in a row (at most {bound} allowed): the link is dead"
            ),
            Fault::LossRate {
                lost,
                window,
                bound,
            } => write!(
                f,
                "{lost} of the last {window} replies lost, more than {:.0} % allowed",
                bound * 100.0
            ),
            Fault::MissedDeadlines { count, bound } => write!(
                f,
                "the loop missed {count} deadlines in a row (at most {bound} allowed)"
            ),
            Fault::Overruns { count, bound } => write!(
                f,
                "{count} cycles in a row overran their period (at most {bound} allowed)"
            ),
            Fault::Device { error } => write!(f, "the device faulted: {error}"),
            Fault::Safety { category, reason } => write!(
                f,
                "safety chain: {reason} (stop category {})",
                match category {
                    StopCategory::Zero => "0, at once",
                    StopCategory::One => "1, brought to rest",
                }
            ),
            other => f.write_str(&other.describe(&[])),
        }
    }
}

/// Per-joint limits the supervisor checks against, fixed before the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds<const J: usize> {
    /// Joints.
    pub dof: usize,
    /// Tracking error bound per joint.
    pub tracking: [f64; J],
    /// Commanded step bound per joint.
    pub step: [f64; J],
    /// Feedback jump bound per joint for replies one cycle apart.
    pub jump: [f64; J],
    /// Lower position limit per joint (`-inf` for continuous joints).
    pub lower: [f64; J],
    /// Upper position limit per joint (`+inf` for continuous joints).
    pub upper: [f64; J],
}

impl<const J: usize> Bounds<J> {
    /// Bounds from the speed limits `speed` (rad/s or m/s per joint), the position limits,
    /// the control period `period_s` and the device cycle `device_period_s`, with `config`'s
    /// factors and explicit tracking bounds.
    pub fn new(
        config: &Supervision,
        speed: &[f64],
        lower: &[f64],
        upper: &[f64],
        period_s: f64,
        device_period_s: f64,
    ) -> Self {
        #![allow(clippy::needless_range_loop)] // five arrays indexed alike
        let dof = speed.len().min(J);
        let slow = period_s.max(device_period_s);
        let fast = period_s.min(device_period_s);
        let mut b = Self {
            dof,
            tracking: [0.0; J],
            step: [0.0; J],
            jump: [0.0; J],
            lower: [f64::NEG_INFINITY; J],
            upper: [f64::INFINITY; J],
        };
        for k in 0..dof {
            b.tracking[k] = config
                .tracking_error
                .get(k)
                .copied()
                .unwrap_or(config.tracking_cycles * speed[k] * slow);
            b.step[k] = speed[k] * fast;
            b.jump[k] = config.jump_factor * speed[k] * slow;
            b.lower[k] = lower.get(k).copied().unwrap_or(f64::NEG_INFINITY);
            b.upper[k] = upper.get(k).copied().unwrap_or(f64::INFINITY);
        }
        b
    }
}

/// A ring of the last [`LOSS_WINDOW_MAX`] cycles' outcomes (lost or not), allocation-free.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct LossWindow {
    bits: [u64; (LOSS_WINDOW_MAX / 64) as usize],
    next: u32,
    filled: u32,
    lost: u32,
    window: u32,
}

impl LossWindow {
    fn new(window: u32) -> Self {
        Self {
            bits: [0; (LOSS_WINDOW_MAX / 64) as usize],
            next: 0,
            filled: 0,
            lost: 0,
            window: window.clamp(1, LOSS_WINDOW_MAX),
        }
    }

    fn record(&mut self, lost: bool) {
        let (w, b) = ((self.next / 64) as usize, self.next % 64);
        let old = self.bits[w] >> b & 1 == 1;
        if self.filled == self.window && old {
            self.lost -= 1;
        }
        if lost {
            self.bits[w] |= 1 << b;
            self.lost += 1;
        } else {
            self.bits[w] &= !(1 << b);
        }
        self.next = (self.next + 1) % self.window;
        self.filled = (self.filled + 1).min(self.window);
    }
}

/// The per-cycle checks of a run, with the state they need (previous feedback, runs of
/// failures). `Copy`, allocation-free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supervisor<const J: usize> {
    enabled: bool,
    bounds: Bounds<J>,
    frozen_cycles: u32,
    device_limits: bool,
    rest_after_lost: u32,
    max_consecutive_lost: u32,
    max_loss_rate: f64,
    max_missed: u32,
    max_overruns: u32,
    previous: [f64; J],
    previous_command: [f64; J],
    have_previous: bool,
    cycles_since_fresh: u32,
    identical: u32,
    command_moved: [f64; J],
    window: LossWindow,
    consecutive_overruns: u32,
    last_lost: u64,
}

/// What one cycle gives the supervisor to look at.
#[derive(Clone, Copy, Debug)]
pub struct Observation<'a> {
    /// Whether `measured` is a fresh reply (the last step succeeded).
    pub fresh: bool,
    /// The measured positions.
    pub measured: &'a [f64],
    /// The resolution of each measured value (the device's representation).
    pub resolution: &'a [f64],
    /// What was commanded for this cycle (compared with `measured`).
    pub commanded: &'a [f64],
    /// The link's counts after the last step.
    pub link: LinkStatistics,
    /// Deadlines the loop skipped right before this cycle.
    pub skipped_deadlines: u64,
    /// Whether the previous cycle overran its period.
    pub overran: bool,
    /// The device's own count of its periods since the previous fresh measurement, where it
    /// numbers its measurements (`JointPositionSensor::joint_position_sample`).
    pub samples_between: Option<u64>,
}

/// Periods of motion between two fresh measurements `cycles` loop cycles apart: the device's
/// own count where it numbers its measurements (a robot that kept its clock while the loop
/// woke late sent states the loop never read), bounded by what the loop's clock allows — its
/// cycles, the deadlines it skipped, and one for a late wake-up — so a corrupt count cannot
/// widen a check further; else the loop's cycles.
pub fn measurement_gap(device: Option<u64>, cycles: u64, skipped_deadlines: u64) -> u64 {
    match device {
        Some(periods) => periods.clamp(1, cycles + skipped_deadlines + 1),
        None => cycles,
    }
}

impl<const J: usize> Supervisor<J> {
    /// A supervisor with `bounds` and `config`'s thresholds.
    pub fn new(config: &Supervision, bounds: Bounds<J>) -> Self {
        Self {
            enabled: config.enabled,
            bounds,
            frozen_cycles: config.frozen_cycles.max(2),
            device_limits: config.device_limits,
            rest_after_lost: config.rest_after_lost.max(1),
            max_consecutive_lost: config
                .max_consecutive_lost
                .max(config.rest_after_lost)
                .max(1),
            max_loss_rate: config.max_loss_rate,
            max_missed: config.max_consecutive_missed_deadlines,
            max_overruns: config.max_consecutive_overruns.max(1),
            previous: [0.0; J],
            previous_command: [0.0; J],
            have_previous: false,
            cycles_since_fresh: 0,
            identical: 0,
            command_moved: [0.0; J],
            window: LossWindow::new(config.loss_window),
            consecutive_overruns: 0,
            last_lost: 0,
        }
    }

    /// The bounds in force.
    pub fn bounds(&self) -> &Bounds<J> {
        &self.bounds
    }

    /// Whether faults are acted on.
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Checks one cycle's observation; the first fault found, if any.
    pub fn observe(&mut self, o: &Observation<'_>) -> Option<Fault> {
        let fault = self.link_and_timing(o).or_else(|| self.feedback(o));
        if self.enabled { fault } else { None }
    }

    fn link_and_timing(&mut self, o: &Observation<'_>) -> Option<Fault> {
        let lost_now = o.link.lost > self.last_lost;
        self.last_lost = o.link.lost;
        self.window.record(lost_now);
        if o.link.consecutive_failures >= self.max_consecutive_lost {
            return Some(Fault::ConsecutiveLost {
                count: o.link.consecutive_failures,
                bound: self.max_consecutive_lost,
            });
        }
        if o.link.consecutive_failures >= self.rest_after_lost {
            return Some(Fault::LinkInterrupted {
                count: o.link.consecutive_failures,
                bound: self.rest_after_lost,
            });
        }
        if self.window.filled == self.window.window
            && f64::from(self.window.lost) > self.max_loss_rate * f64::from(self.window.window)
        {
            return Some(Fault::LossRate {
                lost: self.window.lost,
                window: self.window.window,
                bound: self.max_loss_rate,
            });
        }
        if o.skipped_deadlines > u64::from(self.max_missed) {
            return Some(Fault::MissedDeadlines {
                count: o.skipped_deadlines,
                bound: self.max_missed,
            });
        }
        self.consecutive_overruns = if o.overran {
            self.consecutive_overruns + 1
        } else {
            0
        };
        if self.consecutive_overruns > self.max_overruns {
            return Some(Fault::Overruns {
                count: self.consecutive_overruns,
                bound: self.max_overruns,
            });
        }
        None
    }

    fn feedback(&mut self, o: &Observation<'_>) -> Option<Fault> {
        let b = &self.bounds;
        let dof = b.dof.min(o.measured.len());
        if !o.fresh {
            self.cycles_since_fresh = self.cycles_since_fresh.saturating_add(1);
            return None;
        }
        let gap = measurement_gap(
            o.samples_between,
            u64::from(self.cycles_since_fresh) + 1,
            o.skipped_deadlines,
        ) as f64;
        let mut all_identical = self.have_previous;
        for k in 0..dof {
            let q = o.measured[k];
            let res = o.resolution.get(k).copied().unwrap_or(0.0);
            if !q.is_finite() {
                return Some(Fault::Feedback {
                    joint: k,
                    value: q,
                    fault: FeedbackFault::NotFinite,
                });
            }
            if q < b.lower[k] - res || q > b.upper[k] + res {
                return Some(Fault::Feedback {
                    joint: k,
                    value: q,
                    fault: FeedbackFault::OutsideLimits {
                        lower: b.lower[k],
                        upper: b.upper[k],
                    },
                });
            }
            if self.have_previous {
                let jump = (q - self.previous[k]).abs();
                let bound = b.jump[k] * gap + 2.0 * res;
                if jump > bound {
                    return Some(Fault::Feedback {
                        joint: k,
                        value: q,
                        fault: FeedbackFault::Jump { jump, bound },
                    });
                }
                all_identical &= q.to_bits() == self.previous[k].to_bits();
            }
            let error = o.commanded[k] - q;
            if error.abs() > b.tracking[k] + res {
                return Some(Fault::TrackingError {
                    joint: k,
                    error,
                    bound: b.tracking[k],
                });
            }
        }
        // Frozen: identical replies while the command kept moving. Replies count from the
        // cycle the command had moved more than the resolution since the reply last changed:
        // a standing arm's identical replies before a motion starts do not count (a device
        // that answers a cycle or two later than the command would fault on every smooth
        // start from rest).
        if all_identical {
            let mut moved = false;
            for k in 0..dof {
                self.command_moved[k] += (o.commanded[k] - self.previous_command[k]).abs();
                let res = o.resolution.get(k).copied().unwrap_or(0.0);
                moved |= self.command_moved[k] > 4.0 * res.max(1e-9);
            }
            if moved {
                self.identical += 1;
            }
        } else {
            self.identical = 0;
            self.command_moved = [0.0; J];
        }
        self.previous[..dof].copy_from_slice(&o.measured[..dof]);
        self.previous_command[..dof].copy_from_slice(&o.commanded[..dof]);
        self.have_previous = true;
        self.cycles_since_fresh = 0;
        if self.identical + 1 >= self.frozen_cycles {
            return Some(Fault::Frozen {
                cycles: self.identical + 1,
            });
        }
        None
    }

    /// Checks a commanded step `to − from` per joint against the step bounds.
    pub fn check_step(&self, from: &[f64], to: &[f64]) -> Option<Fault> {
        if !self.enabled {
            return None;
        }
        let b = &self.bounds;
        for k in 0..b.dof.min(from.len()).min(to.len()) {
            let step = (to[k] - from[k]).abs();
            let bound = b.step[k] * (1.0 + 1e-6) + 1e-12;
            if step.is_nan() || step > bound {
                return Some(Fault::CommandStep {
                    joint: k,
                    step,
                    bound: b.step[k],
                });
            }
        }
        None
    }

    /// A fault for the first joint the device reports at a limit.
    pub fn check_device_limits(&self, reached: &[bool]) -> Option<Fault> {
        if !(self.enabled && self.device_limits) {
            return None;
        }
        reached
            .iter()
            .take(self.bounds.dof)
            .position(|&r| r)
            .map(|joint| Fault::DeviceLimit { joint })
    }

    /// The fault for a failed step, if it is one: a lost connection or a faulted device (one
    /// that faulted on a lost reply gave up on the link: the link is lost).
    pub fn check_step_error(
        &self,
        error: &DeviceErrorValue,
        device_faulted: bool,
    ) -> Option<Fault> {
        if device_faulted {
            let kind = error.kind();
            Some(if kind.is_link_loss() || kind == ErrorKind::Timeout {
                Fault::LinkLost { error: *error }
            } else {
                Fault::Device { error: *error }
            })
        } else if error.kind().is_link_loss() {
            Some(Fault::LinkLost { error: *error })
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const P: f64 = 0.01;

    fn supervisor() -> Supervisor<4> {
        let config = Supervision::default();
        let bounds = Bounds::<4>::new(&config, &[1.0, 2.0], &[-1.0, -1.0], &[1.0, 1.0], P, P);
        Supervisor::new(&config, bounds)
    }

    fn obs<'a>(measured: &'a [f64], commanded: &'a [f64], link: LinkStatistics) -> Observation<'a> {
        Observation {
            fresh: true,
            measured,
            resolution: &[0.0, 0.0],
            commanded,
            link,
            skipped_deadlines: 0,
            overran: false,
            samples_between: None,
        }
    }

    #[test]
    fn derived_bounds_follow_the_speed_limits_and_periods() {
        let s = supervisor();
        let b = s.bounds();
        assert_eq!(b.tracking[..2], [4.0 * P, 8.0 * P]);
        assert_eq!(b.step[..2], [P, 2.0 * P]);
        assert_eq!(b.jump[..2], [2.0 * P, 4.0 * P]);
        // A slow control loop on a fast device: steps are bounded by the device's cycle.
        let b = Bounds::<4>::new(&Supervision::default(), &[1.0], &[-1.0], &[1.0], 0.5, P);
        assert_eq!((b.step[0], b.tracking[0]), (P, 4.0 * 0.5));
    }

    #[test]
    fn a_devices_lag_widens_the_derived_tracking_bound_only() {
        use core::time::Duration;
        // A UR's servoj lookahead of 0.1 s on its 2 ms cycle: 50 cycles more, at 1 rad/s.
        let mut config = Supervision::default();
        config.allow_device_lag(Duration::from_millis(100), Duration::from_millis(2));
        let b = Bounds::<4>::new(&config, &[1.0], &[-1.0], &[1.0], 0.002, 0.002);
        assert!(
            (b.tracking[0] - (0.1 + 4.0 * 0.002)).abs() < 1e-12,
            "{}",
            b.tracking[0]
        );
        assert!((b.step[0] - 0.002).abs() < 1e-15, "the step bound stays");
        // No lag, no change; an explicit bound wins.
        let mut plain = Supervision::default();
        plain.allow_device_lag(Duration::ZERO, Duration::from_millis(2));
        assert_eq!(plain, Supervision::default());
        config.tracking_error = vec![0.01];
        let b = Bounds::<4>::new(&config, &[1.0], &[-1.0], &[1.0], 0.002, 0.002);
        assert_eq!(b.tracking[0], 0.01);
    }

    #[test]
    fn bad_feedback_is_a_fault() {
        let link = LinkStatistics::default();
        let mut s = supervisor();
        assert_eq!(s.observe(&obs(&[0.0, 0.0], &[0.0, 0.0], link)), None);
        let f = s.observe(&obs(&[f64::NAN, 0.0], &[0.0, 0.0], link));
        assert!(matches!(
            f,
            Some(Fault::Feedback {
                joint: 0,
                fault: FeedbackFault::NotFinite,
                ..
            })
        ));
        let mut s = supervisor();
        let f = s.observe(&obs(&[0.0, 1.5], &[0.0, 0.0], link));
        assert!(
            matches!(
                f,
                Some(Fault::Feedback {
                    joint: 1,
                    fault: FeedbackFault::OutsideLimits { .. },
                    ..
                })
            ),
            "{f:?}"
        );
        let mut s = supervisor();
        assert_eq!(s.observe(&obs(&[0.0, 0.0], &[0.0, 0.0], link)), None);
        // Joint 0 may move 2·v·P = 0.02 between replies.
        assert_eq!(s.observe(&obs(&[0.019, 0.0], &[0.019, 0.0], link)), None);
        let f = s.observe(&obs(&[0.05, 0.0], &[0.05, 0.0], link));
        assert!(
            matches!(
                f,
                Some(Fault::Feedback {
                    joint: 0,
                    fault: FeedbackFault::Jump { .. },
                    ..
                })
            ),
            "{f:?}"
        );
    }

    #[test]
    fn a_jump_is_bounded_by_the_periods_the_device_counted_within_the_loops_clock() {
        let link = LinkStatistics::default();
        let numbered = |measured: &'static [f64], periods: u64, skipped: u64| Observation {
            samples_between: Some(periods),
            skipped_deadlines: skipped,
            ..obs(measured, measured, link)
        };
        // Two of the device's periods passed (a state between two readings was lost): joint 0
        // may move twice 0.02.
        let mut s = supervisor();
        assert_eq!(s.observe(&numbered(&[0.0, 0.0], 1, 0)), None);
        assert_eq!(s.observe(&numbered(&[0.039, 0.0], 2, 0)), None);
        // Unnumbered, the same motion is a jump.
        let mut s = supervisor();
        assert_eq!(s.observe(&obs(&[0.0, 0.0], &[0.0, 0.0], link)), None);
        assert!(
            s.observe(&obs(&[0.039, 0.0], &[0.039, 0.0], link))
                .is_some()
        );
        // A count beyond what the loop's clock allows (one cycle, no deadline skipped, one for a
        // late wake-up: two periods) does not widen the bound further.
        let mut s = supervisor();
        assert_eq!(s.observe(&numbered(&[0.0, 0.0], 1, 0)), None);
        assert!(s.observe(&numbered(&[0.059, 0.0], 1000, 0)).is_some());
        // ... unless the loop skipped deadlines meanwhile.
        let mut s = supervisor();
        assert_eq!(s.observe(&numbered(&[0.0, 0.0], 1, 0)), None);
        assert_eq!(s.observe(&numbered(&[0.059, 0.0], 3, 1)), None);
        assert_eq!(measurement_gap(None, 2, 5), 2);
        assert_eq!(measurement_gap(Some(0), 1, 0), 1);
    }

    #[test]
    fn the_resolution_is_tolerated_at_the_limits() {
        let link = LinkStatistics::default();
        let mut s = supervisor();
        let mut o = obs(&[1.0 + 1e-8, 0.0], &[1.0, 0.0], link);
        assert!(s.observe(&o).is_some());
        let mut s = supervisor();
        o.resolution = &[2e-8, 0.0];
        assert_eq!(s.observe(&o), None);
    }

    #[test]
    fn tracking_error_beyond_the_bound_is_a_fault() {
        let link = LinkStatistics::default();
        let mut s = supervisor();
        assert_eq!(s.observe(&obs(&[0.0, 0.0], &[0.039, 0.0], link)), None);
        let f = s.observe(&obs(&[0.0, 0.0], &[0.041, 0.0], link));
        assert!(
            matches!(f, Some(Fault::TrackingError { joint: 0, .. })),
            "{f:?}"
        );
    }

    #[test]
    fn a_frozen_reply_while_the_command_moves_is_a_fault() {
        let link = LinkStatistics::default();
        let mut s = supervisor();
        let mut found = None;
        for i in 0..20 {
            let c = [0.001 * f64::from(i), 0.0];
            if let Some(f) = s.observe(&obs(&[0.0, 0.0], &c, link)) {
                found = Some((i, f));
                break;
            }
        }
        assert!(
            matches!(found, Some((9, Fault::Frozen { cycles: 10 }))),
            "{found:?}"
        );
        // At rest, identical replies are what a standing robot sends.
        let mut s = supervisor();
        for _ in 0..50 {
            assert_eq!(s.observe(&obs(&[0.1, 0.2], &[0.1, 0.2], link)), None);
        }
        // A smooth start after a long rest, the replies two cycles behind the command: the
        // replies from before the motion do not count.
        let command = |i: u32| 0.1 + 1e-6 * f64::from(i.saturating_sub(50)).powi(3);
        for i in 50u32..80 {
            let reply = command(i.saturating_sub(2));
            assert_eq!(
                s.observe(&obs(&[reply, 0.2], &[command(i), 0.2], link)),
                None,
                "cycle {i}"
            );
        }
        // Once moving, replies that stop changing still fault after ten.
        let mut found = None;
        for i in 80u32..100 {
            if let Some(f) = s.observe(&obs(&[command(77), 0.2], &[command(i), 0.2], link)) {
                found = Some((i, f));
                break;
            }
        }
        assert!(
            matches!(found, Some((_, Fault::Frozen { cycles: 10 }))),
            "{found:?}"
        );
    }

    #[test]
    fn link_bounds() {
        // Two lost in a row: nothing; three: a short loss, come to rest; ten: a dead link.
        let lost = |n: u32| LinkStatistics {
            consecutive_failures: n,
            lost: u64::from(n),
            ..LinkStatistics::default()
        };
        let mut s = supervisor();
        let mut seen = Vec::new();
        for n in 1..=10 {
            seen.push(s.observe(&Observation {
                fresh: false,
                ..obs(&[0.0, 0.0], &[0.0, 0.0], lost(n))
            }));
        }
        assert_eq!(seen[..2], [None, None]);
        let short = seen[2].expect("a short loss");
        assert_eq!(short, Fault::LinkInterrupted { count: 3, bound: 3 });
        assert!(!short.stops_at_once());
        assert!(matches!(
            seen[8],
            Some(Fault::LinkInterrupted { count: 9, .. })
        ));
        let dead = seen[9].expect("a dead link");
        assert_eq!(
            dead,
            Fault::ConsecutiveLost {
                count: 10,
                bound: 10
            }
        );
        assert!(dead.stops_at_once());
        // The short loss that became a dead link ends the run as a dead link; another first
        // fault stays the reason.
        assert_eq!(short.ended_by(dead), dead);
        let tracking = Fault::TrackingError {
            joint: 0,
            error: 1.0,
            bound: 0.1,
        };
        assert_eq!(tracking.ended_by(dead), tracking);
        // The bounds are the caller's.
        let config = Supervision {
            rest_after_lost: 5,
            max_consecutive_lost: 6,
            ..Supervision::default()
        };
        let mut s = Supervisor::new(&config, *supervisor().bounds());
        let at = |s: &mut Supervisor<4>, n| {
            s.observe(&Observation {
                fresh: false,
                ..obs(&[0.0, 0.0], &[0.0, 0.0], lost(n))
            })
        };
        assert_eq!(at(&mut s, 4), None);
        assert_eq!(
            at(&mut s, 5),
            Some(Fault::LinkInterrupted { count: 5, bound: 5 })
        );
        assert_eq!(
            at(&mut s, 6),
            Some(Fault::ConsecutiveLost { count: 6, bound: 6 })
        );
        // A device that gave up on lost replies has lost the link.
        let timeout = DeviceErrorValue::Timeout {
            operation: rl_drivers::Operation::Step,
            waited: core::time::Duration::from_millis(7),
        };
        assert!(matches!(
            s.check_step_error(&timeout, true),
            Some(Fault::LinkLost { .. })
        ));
        assert_eq!(s.check_step_error(&timeout, false), None);

        // Every other reply lost: 50 % over the window of 100.
        let mut s = supervisor();
        let mut link = LinkStatistics::default();
        let mut fault = None;
        for i in 0..200u64 {
            if i % 2 == 0 {
                link.lost += 1;
                link.consecutive_failures = 1;
            } else {
                link.consecutive_failures = 0;
            }
            if let Some(f) = s.observe(&Observation {
                fresh: i % 2 == 1,
                ..obs(&[0.0, 0.0], &[0.0, 0.0], link)
            }) {
                fault = Some((i, f));
                break;
            }
        }
        assert!(
            matches!(
                fault,
                Some((
                    99,
                    Fault::LossRate {
                        lost: 50,
                        window: 100,
                        ..
                    }
                ))
            ),
            "{fault:?}"
        );
        assert!(!fault.is_some_and(|(_, f)| f.stops_at_once()));
    }

    #[test]
    fn loop_timing_bounds() {
        let link = LinkStatistics::default();
        let mut s = supervisor();
        let f = s.observe(&Observation {
            skipped_deadlines: 4,
            ..obs(&[0.0, 0.0], &[0.0, 0.0], link)
        });
        assert!(matches!(
            f,
            Some(Fault::MissedDeadlines { count: 4, bound: 3 })
        ));
        let mut s = supervisor();
        let mut found = None;
        for i in 0..10 {
            if let Some(f) = s.observe(&Observation {
                overran: true,
                ..obs(&[0.0, 0.0], &[0.0, 0.0], link)
            }) {
                found = Some((i, f));
                break;
            }
        }
        assert!(
            matches!(found, Some((5, Fault::Overruns { count: 6, bound: 5 }))),
            "{found:?}"
        );
    }

    #[test]
    fn steps_and_device_limits() {
        let s = supervisor();
        assert_eq!(s.check_step(&[0.0, 0.0], &[0.01, 0.02]), None);
        assert!(matches!(
            s.check_step(&[0.0, 0.0], &[0.0, 0.03]),
            Some(Fault::CommandStep { joint: 1, .. })
        ));
        assert_eq!(s.check_device_limits(&[false, false]), None);
        assert_eq!(
            s.check_device_limits(&[false, true]),
            Some(Fault::DeviceLimit { joint: 1 })
        );
        let off = Supervisor::<4>::new(&Supervision::off(), *s.bounds());
        assert_eq!(off.check_step(&[0.0, 0.0], &[1.0, 1.0]), None);
    }

    #[test]
    fn the_loss_window_counts_only_its_last_cycles() {
        let mut w = LossWindow::new(70);
        for i in 0..200 {
            w.record(i < 100);
        }
        assert_eq!((w.lost, w.filled), (0, 70));
        for _ in 0..65 {
            w.record(true);
        }
        assert_eq!(w.lost, 65);
    }
}
