//! The fake gripper's mechanics and logic: activation, motion at the commanded speed, object
//! detection, faults, the automatic release, and the 1-second communication watchdog.

use std::time::{Duration, Instant};

use crate::proto::robotiq::{
    ActivationStatus, Command, Fault, Model, ObjectStatus, Severity, Status,
};

/// Where the fingers stop: fully open and fully closed, in position counts.
pub(super) const OPEN_COUNT: f64 = 3.0;
/// See [`OPEN_COUNT`].
pub(super) const CLOSED_COUNT: f64 = 230.0;
/// Silence after which the gripper reports fault 0x09.
const WATCHDOG: Duration = Duration::from_secs(1);
/// The automatic release's speed, a fraction of the slowest.
const RELEASE_SPEED: f64 = 0.5;

/// The gripper's state.
#[derive(Clone, Debug)]
pub(super) struct Sim {
    model: Model,
    activation_time: Duration,
    /// The robot output as written (8 registers).
    pub output: [u16; 8],
    command: Command,
    activated: bool,
    activation: ActivationStatus,
    activating_until: Option<Instant>,
    going: bool,
    /// Position, counts (0 open … 255 closed), continuous.
    position: f64,
    position_request: u8,
    object: ObjectStatus,
    fault: Fault,
    releasing: Option<f64>,
    last_comm: Instant,
    last_update: Instant,
    /// An object between the fingers: they stop closing at this opening, m.
    pub object_width: Option<f64>,
    /// An object around the fingers: they stop opening at this opening, m.
    pub inner_width: Option<f64>,
    /// Activations completed.
    pub activations: u64,
}

impl Sim {
    pub(super) fn new(model: Model, activation_time: Duration, now: Instant) -> Self {
        Self {
            model,
            activation_time,
            output: [0; 8],
            command: Command::default(),
            activated: false,
            activation: ActivationStatus::Reset,
            activating_until: None,
            going: false,
            position: OPEN_COUNT,
            position_request: 0,
            object: ObjectStatus::Moving,
            fault: Fault::None,
            releasing: None,
            last_comm: now,
            last_update: now,
            object_width: None,
            inner_width: None,
            activations: 0,
        }
    }

    /// The opening at a position count, m.
    pub(super) fn opening(&self, count: f64) -> f64 {
        let x = ((count - OPEN_COUNT) / (CLOSED_COUNT - OPEN_COUNT)).clamp(0.0, 1.0);
        self.model.stroke_m() * (1.0 - x)
    }

    fn count_at(&self, opening: f64) -> f64 {
        let x = 1.0 - (opening / self.model.stroke_m()).clamp(0.0, 1.0);
        OPEN_COUNT + x * (CLOSED_COUNT - OPEN_COUNT)
    }

    /// Counts per second at a speed request.
    fn speed(&self, request: u8) -> f64 {
        let (lo, hi) = self.model.speed_range();
        let v = lo + (hi - lo) * f64::from(request) / 255.0;
        v / self.model.stroke_m() * (CLOSED_COUNT - OPEN_COUNT)
    }

    fn major(&self) -> bool {
        self.fault.severity() == Severity::Major
    }

    /// A request came: the watchdog restarts (after this request's answer shows its fault).
    pub(super) fn communicated(&mut self, now: Instant) {
        self.last_comm = now;
        if self.fault == Fault::NoCommunication {
            self.fault = Fault::None;
        }
    }

    /// A fault injected from outside (a major one stops the fingers until a reset).
    pub(super) fn inject(&mut self, fault: Fault) {
        self.fault = fault;
        if self.major() {
            self.going = false;
            self.releasing = None;
        }
    }

    /// Power lost and back: the gripper forgets its activation and its command.
    pub(super) fn power_cycle(&mut self, now: Instant) {
        *self = Self {
            position: self.position,
            object_width: self.object_width,
            inner_width: self.inner_width,
            activations: self.activations,
            ..Self::new(self.model, self.activation_time, now)
        };
    }

    /// The robot wrote the output registers.
    pub(super) fn write(&mut self, output: [u16; 8], now: Instant) {
        self.advance(now);
        self.output = output;
        let cmd = Command::from_registers([output[0], output[1], output[2]]);
        let rising = cmd.activate && !self.command.activate;
        self.command = cmd;
        if !cmd.activate {
            // Reset: every fault cleared, the fingers stop.
            self.activated = false;
            self.activation = ActivationStatus::Reset;
            self.activating_until = None;
            self.going = false;
            self.releasing = None;
            // Reset clears every fault; a go-to without the activation bit is one.
            self.fault = if cmd.go_to {
                Fault::ActivationBitNotSet
            } else {
                Fault::None
            };
            return;
        }
        if rising {
            self.activated = true;
            self.activation = ActivationStatus::Activating;
            self.activating_until = Some(now + self.activation_time);
            self.going = false;
            self.fault = Fault::None;
        }
        if self.major() {
            return;
        }
        if cmd.automatic_release && self.activation == ActivationStatus::Activated {
            let target = if cmd.release_opening {
                OPEN_COUNT
            } else {
                CLOSED_COUNT
            };
            self.releasing = Some(target);
            self.going = false;
            self.fault = Fault::AutomaticReleaseInProgress;
            return;
        }
        if cmd.go_to {
            match self.activation {
                ActivationStatus::Activated => {
                    if self.fault.severity() == Severity::Priority {
                        self.fault = Fault::None;
                    }
                    if !self.going || self.position_request != cmd.position {
                        self.object = ObjectStatus::Moving;
                    }
                    self.going = true;
                    self.position_request = cmd.position;
                }
                ActivationStatus::Activating => self.fault = Fault::ActionDelayed,
                _ => self.fault = Fault::ActivationBitNotSet,
            }
        } else {
            self.going = false;
        }
    }

    /// Moves time on to `now`.
    pub(super) fn advance(&mut self, now: Instant) {
        let dt = now
            .saturating_duration_since(self.last_update)
            .as_secs_f64();
        self.last_update = now;
        if let Some(t) = self.activating_until
            && now >= t
        {
            self.activating_until = None;
            self.activation = ActivationStatus::Activated;
            self.activations += 1;
            self.position = OPEN_COUNT;
            if self.fault == Fault::ActionDelayed {
                self.fault = Fault::None;
                // The delayed action runs now.
                if self.command.go_to {
                    self.going = true;
                    self.position_request = self.command.position;
                    self.object = ObjectStatus::Moving;
                }
            }
        }
        if self.activated
            && self.fault == Fault::None
            && now.saturating_duration_since(self.last_comm) >= WATCHDOG
        {
            self.fault = Fault::NoCommunication;
        }
        if let Some(target) = self.releasing {
            let step = self.speed(0) * RELEASE_SPEED * dt;
            self.position = toward(self.position, target, step);
            if self.position == target {
                self.releasing = None;
                self.fault = Fault::AutomaticReleaseCompleted;
            }
            return;
        }
        if !self.going || self.major() || self.activation != ActivationStatus::Activated {
            return;
        }
        if self.object.holds_object() || self.object == ObjectStatus::AtPosition {
            return;
        }
        let target = f64::from(self.position_request).clamp(OPEN_COUNT, CLOSED_COUNT);
        let step = self.speed(self.command.speed) * dt;
        let next = toward(self.position, target, step);
        let closing = target > self.position;
        let contact = if closing {
            self.object_width.map(|w| self.count_at(w))
        } else {
            self.inner_width.map(|w| self.count_at(w))
        };
        match contact {
            Some(c) if closing && self.position <= c && next >= c && c < target => {
                self.position = c;
                self.object = ObjectStatus::ContactClosing;
            }
            Some(c) if !closing && self.position >= c && next <= c && c > target => {
                self.position = c;
                self.object = ObjectStatus::ContactOpening;
            }
            _ => {
                self.position = next;
                if next == target {
                    self.object = ObjectStatus::AtPosition;
                }
            }
        }
    }

    /// The status registers' meaning now.
    pub(super) fn status(&self) -> Status {
        let moving = self.going && self.object == ObjectStatus::Moving;
        let current = if moving || self.releasing.is_some() {
            0x10 + self.command.speed / 32
        } else if self.going && self.object.holds_object() {
            // Holding: a current that grows with the force request.
            8 + self.command.force / 8
        } else {
            0
        };
        Status {
            activated: self.activated,
            going: self.going,
            activation: self.activation,
            object: if self.going {
                self.object
            } else {
                ObjectStatus::Moving
            },
            fault: self.fault,
            controller_fault: 0,
            position_request: self.position_request,
            position: self.position.round().clamp(0.0, 255.0) as u8,
            current,
        }
    }

    /// The 8 input registers (bytes 6 to 15 reserved, zero).
    pub(super) fn input(&self) -> [u16; 8] {
        let s = self.status().to_registers();
        [s[0], s[1], s[2], 0, 0, 0, 0, 0]
    }
}

fn toward(x: f64, target: f64, step: f64) -> f64 {
    if (target - x).abs() <= step {
        target
    } else if target > x {
        x + step
    } else {
        x - step
    }
}
