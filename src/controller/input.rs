//! Inputs to a running law from any other thread: targets (a position, with or without a
//! velocity, or a velocity) and one slot of the law's own type (e.g. obstacle spheres), typed
//! and `Copy`, through rl-rt's lock-free [`queue`].
//!
//! [`channel`] makes the two ends; a [`ControlRun`](super::ControlRun) makes one for its law and
//! hands out the sending end ([`ControlRun::inputs`](super::ControlRun::inputs)). The
//! [`InputSender`] checks every target before it goes (length, finite, inside the model's
//! position limits, within its speed limits) and refuses a bad one with a typed error naming
//! the joint; refused and dropped (queue full) inputs are counted. Senders can be cloned and
//! used from any number of threads: they serialise among themselves on a mutex that the
//! real-time thread never touches — it only pops the queue, wait-free.
//!
//! Each cycle, before the law runs, the loop takes what arrived (at most [`PER_CYCLE`]
//! inputs), hands each to [`ControlLaw::input`](super::ControlLaw::input) in order, and keeps
//! the newest accepted target and other input with their age in [`Inputs`], which the law
//! reads through its [`Context`](super::law::Context). With an input timeout
//! ([`RunOptions::input_timeout`](super::RunOptions::input_timeout)) the run asks the law to
//! bring the arm to rest once no input has been accepted for longer than the timeout
//! (counted from the loop's start until the first one), and ends at rest with
//! [`RunEnd::InputsStale`](super::RunEnd::InputsStale).

use core::fmt;
use core::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use rl_core::Model;
use rl_rt::MonoTime;
use rl_rt::exchange::{QueueReceiver, QueueSender, queue};

use super::plan::{UNKNOWN_SPEED, joint_name};

/// Inputs the loop takes per cycle at most (more wait for the next cycle), so a flood cannot
/// lengthen a cycle without bound.
pub const PER_CYCLE: usize = 64;

/// Inputs a run's queue holds by default.
pub const DEFAULT_CAPACITY: usize = 256;

/// Where the law should take the arm, for up to `J` joints (the first `dof` values are used).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target<const J: usize> {
    /// A position, rad or m, to reach with `velocity` (rad/s or m/s; `None`: at rest).
    Position {
        /// The position.
        position: [f64; J],
        /// The velocity to have there.
        velocity: Option<[f64; J]>,
    },
    /// A velocity to reach and keep, rad/s or m/s.
    Velocity {
        /// The velocity.
        velocity: [f64; J],
    },
}

/// One input to the loop: a target, or the law's own kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input<const J: usize, X> {
    /// A target.
    Target(Target<J>),
    /// An input of the law's own type.
    Other(X),
}

/// Why an input was not sent. Every one is counted in the run's report.
#[derive(Clone, Debug, PartialEq)]
pub enum InputError {
    /// A joint vector of the wrong length.
    Length {
        /// The model's joints.
        expected: usize,
        /// Given.
        got: usize,
    },
    /// A value that is not a number or infinite.
    NotFinite {
        /// `"position"` or `"velocity"`.
        quantity: &'static str,
        /// The joint's name.
        joint: String,
    },
    /// A position outside the joint's limits.
    OutsideLimits {
        /// The joint's name.
        joint: String,
        /// The value.
        value: f64,
        /// Lower limit.
        lower: f64,
        /// Upper limit.
        upper: f64,
    },
    /// A velocity beyond the joint's speed limit.
    TooFast {
        /// The joint's name.
        joint: String,
        /// The value.
        value: f64,
        /// The speed limit.
        limit: f64,
    },
    /// The queue was full (the loop takes at most [`PER_CYCLE`] per cycle): dropped.
    Full,
    /// The run is over: nobody takes inputs any more.
    Ended,
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Length { expected, got } => write!(
                f,
                "input refused: {got} joint values, the model has {expected} joints"
            ),
            Self::NotFinite { quantity, joint } => {
                write!(
                    f,
                    "input refused: the {quantity} of joint {joint} is not finite"
                )
            }
            Self::OutsideLimits {
                joint,
                value,
                lower,
                upper,
            } => write!(
                f,
                "target refused: joint {joint} at {value} is outside its limits [{lower}, {upper}]"
            ),
            Self::TooFast {
                joint,
                value,
                limit,
            } => write!(
                f,
                "target refused: joint {joint} at {value} is beyond its speed limit {limit}"
            ),
            Self::Full => f.write_str("input dropped: the run's input queue is full"),
            Self::Ended => f.write_str("input refused: the run is over"),
        }
    }
}

impl std::error::Error for InputError {}

/// Limits a target is checked against, from the model.
#[derive(Debug)]
struct TargetLimits {
    names: Vec<String>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    speed: Vec<f64>,
}

impl TargetLimits {
    fn from_model<const B: usize>(model: &Model<B>) -> Self {
        let dof = model.dof();
        let mut t = Self {
            names: (0..dof).map(|k| joint_name(model, k)).collect(),
            lower: Vec::with_capacity(dof),
            upper: Vec::with_capacity(dof),
            speed: Vec::with_capacity(dof),
        };
        for k in 0..dof {
            let l = model.limits(k);
            let bounded = !l.wraparound;
            t.lower
                .push(if bounded { l.lower } else { f64::NEG_INFINITY });
            t.upper.push(if bounded { l.upper } else { f64::INFINITY });
            let v = l.velocity;
            t.speed.push(if v.is_finite() && v > 0.0 {
                v
            } else {
                UNKNOWN_SPEED
            });
        }
        t
    }

    fn dof(&self) -> usize {
        self.names.len()
    }

    fn check_length(&self, values: &[f64]) -> Result<(), InputError> {
        if values.len() == self.dof() {
            Ok(())
        } else {
            Err(InputError::Length {
                expected: self.dof(),
                got: values.len(),
            })
        }
    }

    fn check_position(&self, q: &[f64]) -> Result<(), InputError> {
        self.check_length(q)?;
        for (k, &v) in q.iter().enumerate() {
            if !v.is_finite() {
                return Err(InputError::NotFinite {
                    quantity: "position",
                    joint: self.names[k].clone(),
                });
            }
            if v < self.lower[k] || v > self.upper[k] {
                return Err(InputError::OutsideLimits {
                    joint: self.names[k].clone(),
                    value: v,
                    lower: self.lower[k],
                    upper: self.upper[k],
                });
            }
        }
        Ok(())
    }

    fn check_velocity(&self, qd: &[f64]) -> Result<(), InputError> {
        self.check_length(qd)?;
        for (k, &v) in qd.iter().enumerate() {
            if !v.is_finite() {
                return Err(InputError::NotFinite {
                    quantity: "velocity",
                    joint: self.names[k].clone(),
                });
            }
            if v.abs() > self.speed[k] {
                return Err(InputError::TooFast {
                    joint: self.names[k].clone(),
                    value: v,
                    limit: self.speed[k],
                });
            }
        }
        Ok(())
    }
}

/// What crosses the queue: an input and when it was sent.
#[derive(Clone, Copy, Debug)]
struct Message<const J: usize, X> {
    input: Input<J, X>,
    sent: MonoTime,
}

/// Counts kept by the senders, read by the report.
#[derive(Debug, Default)]
struct Counters {
    sent: AtomicU64,
    refused: AtomicU64,
    dropped: AtomicU64,
    ended: AtomicBool,
    first_refusal: Mutex<Option<String>>,
}

/// The sending end of an input [`channel`]: clone it for as many threads as send. Never used
/// on the real-time thread.
pub struct InputSender<const J: usize, X> {
    queue: Arc<Mutex<QueueSender<Message<J, X>>>>,
    limits: Arc<TargetLimits>,
    counters: Arc<Counters>,
}

impl<const J: usize, X> Clone for InputSender<J, X> {
    fn clone(&self) -> Self {
        Self {
            queue: Arc::clone(&self.queue),
            limits: Arc::clone(&self.limits),
            counters: Arc::clone(&self.counters),
        }
    }
}

impl<const J: usize, X> fmt::Debug for InputSender<J, X> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("InputSender")
            .field("dof", &self.limits.dof())
            .field("sent", &self.counters.sent.load(Ordering::Relaxed))
            .finish()
    }
}

impl<const J: usize, X: Copy + Send> InputSender<J, X> {
    /// Sends a position target (at rest there), `dof` values in rad or m.
    pub fn send_position(&self, position: &[f64]) -> Result<(), InputError> {
        self.refusing(|l| {
            l.check_position(position)?;
            Ok(Target::Position {
                position: to_array(position),
                velocity: None,
            })
        })
    }

    /// Sends a position target to pass with `velocity` (rad/s or m/s).
    pub fn send_position_velocity(
        &self,
        position: &[f64],
        velocity: &[f64],
    ) -> Result<(), InputError> {
        self.refusing(|l| {
            l.check_position(position)?;
            l.check_velocity(velocity)?;
            Ok(Target::Position {
                position: to_array(position),
                velocity: Some(to_array(velocity)),
            })
        })
    }

    /// Sends a velocity target (rad/s or m/s) to reach and keep.
    pub fn send_velocity(&self, velocity: &[f64]) -> Result<(), InputError> {
        self.refusing(|l| {
            l.check_velocity(velocity)?;
            Ok(Target::Velocity {
                velocity: to_array(velocity),
            })
        })
    }

    /// Sends a target, checked as the `send_*` methods check theirs.
    pub fn send_target(&self, target: Target<J>) -> Result<(), InputError> {
        let dof = self.limits.dof();
        self.refusing(|l| {
            if dof > J {
                return Err(InputError::Length {
                    expected: dof,
                    got: J,
                });
            }
            match &target {
                Target::Position { position, velocity } => {
                    l.check_position(&position[..dof])?;
                    if let Some(v) = velocity {
                        l.check_velocity(&v[..dof])?;
                    }
                }
                Target::Velocity { velocity } => l.check_velocity(&velocity[..dof])?,
            }
            Ok(target)
        })
    }

    /// Sends an input of the law's own type (the law checks it: [`ControlLaw::input`]).
    ///
    /// [`ControlLaw::input`]: super::ControlLaw::input
    pub fn send(&self, input: X) -> Result<(), InputError> {
        self.push(Input::Other(input))
    }

    /// Inputs queued so far.
    pub fn sent(&self) -> u64 {
        self.counters.sent.load(Ordering::Relaxed)
    }

    /// Inputs refused by the checks so far.
    pub fn refused(&self) -> u64 {
        self.counters.refused.load(Ordering::Relaxed)
    }

    /// Inputs dropped because the queue was full.
    pub fn dropped(&self) -> u64 {
        self.counters.dropped.load(Ordering::Relaxed)
    }

    /// Whether the run is over.
    pub fn is_ended(&self) -> bool {
        self.counters.ended.load(Ordering::Acquire)
    }

    fn refusing(
        &self,
        check: impl FnOnce(&TargetLimits) -> Result<Target<J>, InputError>,
    ) -> Result<(), InputError> {
        match check(&self.limits) {
            Ok(target) => self.push(Input::Target(target)),
            Err(e) => {
                self.counters.refused.fetch_add(1, Ordering::Relaxed);
                self.counters
                    .first_refusal
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .get_or_insert_with(|| e.to_string());
                Err(e)
            }
        }
    }

    fn push(&self, input: Input<J, X>) -> Result<(), InputError> {
        if self.is_ended() {
            return Err(InputError::Ended);
        }
        let message = Message {
            input,
            sent: MonoTime::now(),
        };
        let mut queue = self.queue.lock().unwrap_or_else(PoisonError::into_inner);
        match queue.try_send(message) {
            Ok(()) => {
                self.counters.sent.fetch_add(1, Ordering::Relaxed);
                Ok(())
            }
            Err(_) => {
                self.counters.dropped.fetch_add(1, Ordering::Relaxed);
                Err(InputError::Full)
            }
        }
    }
}

fn to_array<const J: usize>(values: &[f64]) -> [f64; J] {
    let mut a = [0.0; J];
    for (a, v) in a.iter_mut().zip(values) {
        *a = *v;
    }
    a
}

/// The receiving end of an input [`channel`], for the loop (the controller takes it:
/// [`Controller::attach_inputs`](super::Controller::attach_inputs)).
pub struct InputReceiver<const J: usize, X> {
    queue: QueueReceiver<Message<J, X>>,
    counters: Arc<Counters>,
}

impl<const J: usize, X> fmt::Debug for InputReceiver<J, X> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("InputReceiver")
            .field("waiting", &self.queue.len())
            .finish()
    }
}

impl<const J: usize, X> InputReceiver<J, X> {
    /// Tells the senders the run is over (they get [`InputError::Ended`] from now on).
    pub fn close(&mut self) {
        self.counters.ended.store(true, Ordering::Release);
    }
}

impl<const J: usize, X> Drop for InputReceiver<J, X> {
    fn drop(&mut self) {
        self.close();
    }
}

/// Makes an input channel for `model`'s joints holding up to `capacity` inputs.
pub fn channel<const B: usize, const J: usize, X: Copy + Send>(
    model: &Model<B>,
    capacity: usize,
) -> (InputSender<J, X>, InputReceiver<J, X>) {
    let (tx, rx) = queue(capacity.max(1));
    let counters = Arc::new(Counters::default());
    (
        InputSender {
            queue: Arc::new(Mutex::new(tx)),
            limits: Arc::new(TargetLimits::from_model(model)),
            counters: Arc::clone(&counters),
        },
        InputReceiver {
            queue: rx,
            counters,
        },
    )
}

/// The inputs the law sees: the newest accepted target and other input, how many came, and
/// how old they are at this cycle.
#[derive(Clone, Copy, Debug)]
pub struct Inputs<const J: usize, X> {
    target: Option<Target<J>>,
    target_sent: MonoTime,
    targets: u64,
    other: Option<X>,
    other_sent: MonoTime,
    others: u64,
    now: MonoTime,
    started: Option<MonoTime>,
    refused_by_law: u64,
    first_law_refusal: Option<&'static str>,
    max_age_ns: u64,
    stale_age_ns: Option<u64>,
}

impl<const J: usize, X> Default for Inputs<J, X> {
    fn default() -> Self {
        Self {
            target: None,
            target_sent: MonoTime::default(),
            targets: 0,
            other: None,
            other_sent: MonoTime::default(),
            others: 0,
            now: MonoTime::default(),
            started: None,
            refused_by_law: 0,
            first_law_refusal: None,
            max_age_ns: 0,
            stale_age_ns: None,
        }
    }
}

impl<const J: usize, X: Copy> Inputs<J, X> {
    /// The newest accepted target.
    pub fn target(&self) -> Option<&Target<J>> {
        self.target.as_ref()
    }

    /// Targets accepted so far (a new number means a new target).
    pub fn targets(&self) -> u64 {
        self.targets
    }

    /// Age of the newest target at this cycle, s.
    pub fn target_age_s(&self) -> Option<f64> {
        self.target
            .map(|_| self.now.nanos_since(self.target_sent) as f64 * 1e-9)
    }

    /// The newest accepted input of the law's own type.
    pub fn other(&self) -> Option<&X> {
        self.other.as_ref()
    }

    /// Inputs of the law's own type accepted so far.
    pub fn others(&self) -> u64 {
        self.others
    }

    /// Age of the newest input of the law's own type at this cycle, s.
    pub fn other_age_s(&self) -> Option<f64> {
        self.other
            .map(|_| self.now.nanos_since(self.other_sent) as f64 * 1e-9)
    }

    /// Time since the newest accepted input of either kind was sent (since the loop started
    /// while none has come), s.
    pub fn age_s(&self) -> f64 {
        self.age_ns() as f64 * 1e-9
    }

    fn last_sent(&self) -> Option<MonoTime> {
        match (
            self.target.map(|_| self.target_sent),
            self.other.map(|_| self.other_sent),
        ) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }

    pub(super) fn age_ns(&self) -> u64 {
        let since = self.last_sent().or(self.started).unwrap_or(self.now);
        self.now.nanos_since(since)
    }

    /// Whether the inputs are older than `timeout_ns`; the first time, the age is kept for
    /// the report.
    pub(super) fn went_stale(&mut self, timeout_ns: u64) -> bool {
        let age = self.age_ns();
        if age > timeout_ns && self.stale_age_ns.is_none() {
            self.stale_age_ns = Some(age);
            true
        } else {
            false
        }
    }

    /// Takes what arrived on `receiver` (at most [`PER_CYCLE`]) at `now`, handing each input
    /// to `accept` in order; accepted ones become the newest. Allocates nothing.
    pub(super) fn receive(
        &mut self,
        receiver: &mut InputReceiver<J, X>,
        now: MonoTime,
        mut accept: impl FnMut(&Input<J, X>) -> Result<(), super::law::Refused>,
    ) {
        self.now = now;
        self.started.get_or_insert(now);
        if self.last_sent().is_some() {
            self.max_age_ns = self.max_age_ns.max(self.age_ns());
        }
        for _ in 0..PER_CYCLE {
            let Some(m) = receiver.queue.try_recv() else {
                break;
            };
            match accept(&m.input) {
                Ok(()) => match m.input {
                    Input::Target(t) => {
                        self.target = Some(t);
                        self.target_sent = m.sent;
                        self.targets += 1;
                    }
                    Input::Other(x) => {
                        self.other = Some(x);
                        self.other_sent = m.sent;
                        self.others += 1;
                    }
                },
                Err(r) => {
                    self.refused_by_law += 1;
                    self.first_law_refusal.get_or_insert(r.0);
                }
            }
        }
    }

    /// The counts for the report, with the senders' from `receiver`.
    pub(super) fn report(
        &self,
        receiver: &InputReceiver<J, X>,
        timeout_s: Option<f64>,
    ) -> InputReport {
        let c = &receiver.counters;
        InputReport {
            sent: c.sent.load(Ordering::Relaxed),
            targets: self.targets,
            others: self.others,
            refused_invalid: c.refused.load(Ordering::Relaxed),
            first_invalid: c
                .first_refusal
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .clone(),
            refused_by_law: self.refused_by_law,
            first_law_refusal: self.first_law_refusal,
            dropped_full: c.dropped.load(Ordering::Relaxed),
            not_taken: receiver.queue.len() as u64,
            timeout_s,
            max_age_s: self.max_age_ns as f64 * 1e-9,
            stale: self.stale_age_ns.is_some(),
            stale_age_s: self.stale_age_ns.map(|ns| ns as f64 * 1e-9),
        }
    }
}

/// What became of the inputs of a run, for its report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InputReport {
    /// Inputs queued by the senders.
    pub sent: u64,
    /// Targets the law accepted.
    pub targets: u64,
    /// Inputs of the law's own type it accepted.
    pub others: u64,
    /// Inputs the senders' checks refused (length, not finite, outside the limits).
    pub refused_invalid: u64,
    /// The first of those, described.
    pub first_invalid: Option<String>,
    /// Inputs the law refused.
    pub refused_by_law: u64,
    /// The law's first reason.
    pub first_law_refusal: Option<&'static str>,
    /// Inputs dropped because the queue was full.
    pub dropped_full: u64,
    /// Inputs still queued when the loop ended.
    pub not_taken: u64,
    /// The input timeout, s.
    pub timeout_s: Option<f64>,
    /// The longest time between inputs the loop saw (after the first), s.
    pub max_age_s: f64,
    /// Whether inputs went stale (the run was brought to rest for it).
    pub stale: bool,
    /// How old the inputs were in the cycle that found them stale, s.
    pub stale_age_s: Option<f64>,
}

impl InputReport {
    /// Whether anything was sent or a timeout was set (otherwise the report leaves it out).
    pub fn is_used(&self) -> bool {
        self.sent + self.refused_invalid + self.dropped_full > 0 || self.timeout_s.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Model<16> {
        super::super::rv6sl().expect("embedded model").model
    }

    #[test]
    fn targets_are_checked_before_they_go() {
        let m = model();
        let (tx, _rx) = channel::<16, 8, ()>(&m, 4);
        assert_eq!(tx.send_position(&[0.0; 6]), Ok(()));
        assert!(matches!(
            tx.send_position(&[0.0; 5]),
            Err(InputError::Length {
                expected: 6,
                got: 5
            })
        ));
        let mut q = [0.0; 6];
        q[1] = 3.0; // joint1 is limited to [-92°, 135°]
        let e = tx.send_position(&q).expect_err("outside");
        assert!(
            matches!(&e, InputError::OutsideLimits { joint, value, .. } if joint == "joint1" && *value == 3.0),
            "{e}"
        );
        q[1] = f64::NAN;
        assert!(matches!(
            tx.send_position(&q),
            Err(InputError::NotFinite {
                quantity: "position",
                ..
            })
        ));
        let mut v = [0.0; 6];
        v[0] = 100.0;
        assert!(matches!(
            tx.send_velocity(&v),
            Err(InputError::TooFast { ref joint, .. }) if joint == "joint0"
        ));
        assert_eq!((tx.sent(), tx.refused(), tx.dropped()), (1, 4, 0));
    }

    #[test]
    fn a_full_queue_drops_and_counts_and_an_ended_run_refuses() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, u32>(&m, 2);
        assert_eq!(tx.send(1), Ok(()));
        assert_eq!(tx.send(2), Ok(()));
        assert_eq!(tx.send(3), Err(InputError::Full));
        assert_eq!(tx.dropped(), 1);
        let mut inputs = Inputs::<8, u32>::default();
        let mut seen = Vec::new();
        inputs.receive(&mut rx, MonoTime::now(), |i| {
            seen.push(*i);
            if matches!(i, Input::Other(2)) {
                Err(super::super::law::Refused("even"))
            } else {
                Ok(())
            }
        });
        assert_eq!(seen, [Input::Other(1), Input::Other(2)]);
        assert_eq!((inputs.others(), inputs.other()), (1, Some(&1)));
        let report = inputs.report(&rx, None);
        assert_eq!(
            (report.sent, report.refused_by_law, report.dropped_full),
            (2, 1, 1)
        );
        assert_eq!(report.first_law_refusal, Some("even"));
        drop(rx);
        assert_eq!(tx.send(4), Err(InputError::Ended));
    }

    #[test]
    fn ages_count_from_the_newest_input_or_the_start() {
        let m = model();
        let (tx, mut rx) = channel::<16, 8, ()>(&m, 4);
        let mut inputs = Inputs::<8, ()>::default();
        let t0 = MonoTime::now();
        inputs.receive(&mut rx, t0, |_| Ok(()));
        assert_eq!(inputs.age_ns(), 0);
        let later = MonoTime::from_nanos(t0.as_nanos() + 50_000_000);
        inputs.receive(&mut rx, later, |_| Ok(()));
        assert_eq!(
            inputs.age_ns(),
            50_000_000,
            "since the start while none came"
        );
        tx.send_position(&[0.0; 6]).expect("sent");
        let now = MonoTime::now();
        inputs.receive(&mut rx, now, |_| Ok(()));
        assert!(inputs.target().is_some());
        assert!(inputs.age_s() < 1.0);
        assert_eq!(inputs.targets(), 1);
    }
}
