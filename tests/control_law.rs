//! Laws of one's own in the supervised runtime (`ControlRun::start_law`): a position law on the
//! fake H7 commands exactly what it computes and the fake follows; a computed-torque law and a
//! velocity law move a simulated arm with dynamics to targets streamed in while they run;
//! inputs are checked, refused and counted; inputs that stop coming bring the arm to rest;
//! stop requests, the duration and faults go through the law's braking, and a law that never
//! comes to rest is ended; the report and the telemetry say when a fault happened.

#![allow(clippy::needless_range_loop)] // per-joint arrays indexed alike

mod common;
mod late;

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use common::arm::{ArmMode, SimArm};
use common::sim::{Misbehaviour, SimRobot};
use rl::controller::input::Input;
use rl::controller::law::Refused;
use rl::controller::{
    BrakeReason, Command, CommandMode, Context, ControlLaw, ControlRun, CycleRecord, InputError,
    LawError, LawStatus, PlanError, RunEnd, RunError, RunOptions, RunReport, RunState, Start,
    Target, rv6sl,
};
use rl::core::algo::rnea;
use rl::core::loader::{UrdfOptions, load_urdf_str};
use rl::core::traj::{JerkLimited, Limits, Trajectory};
use rl::drivers::fake::franka_controller::{FakeFranka, fr3_shaped_urdf};

const PERIOD: Duration = Duration::from_millis(2);

fn options() -> RunOptions {
    RunOptions {
        lock_memory: false,
        priority: 50,
        telemetry: true,
        ..RunOptions::default()
    }
}

fn limits() -> (Vec<f64>, Vec<f64>) {
    let m = rv6sl().expect("embedded model").model;
    (
        (0..6).map(|k| m.limits(k).lower).collect(),
        (0..6).map(|k| m.limits(k).upper).collect(),
    )
}

/// A position-lagging simulated RV-6SL standing at zero.
fn sim_robot() -> SimRobot {
    let (lower, upper) = limits();
    SimRobot::new(&[0.0; 6], &lower, &upper, PERIOD, 2)
}

/// Runs to the end (bounded), collecting the telemetry.
fn finish<R, L>(mut run: ControlRun<R, 16, 8, L>) -> (RunReport, Vec<CycleRecord<8>>)
where
    R: rl::controller::JointRobot + Send + 'static,
    L: ControlLaw<16, 8> + 'static,
{
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut rows = Vec::new();
    while run.poll(Duration::from_millis(10)).is_some() {
        run.drain_telemetry(|r| rows.push(*r));
        assert!(Instant::now() < deadline, "the run did not end within 30 s");
    }
    let report = run.join_with(|r| rows.push(*r));
    (report, rows)
}

/// One run at a time: each runs a SCHED_FIFO loop, and several at once on two CPUs (the tests
/// run in parallel threads) take each other's cycles.
fn one_run_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static RUNS: std::sync::Mutex<()> = std::sync::Mutex::new(());
    RUNS.lock().unwrap_or_else(|p| p.into_inner())
}

/// Runs `attempt` (a whole run, from its start, one at a time) while it shows the machine
/// late ([`late::any_shortfall`]; see [`late::while_late`]).
fn on_time<T>(name: &str, attempt: impl FnMut() -> (RunReport, T)) -> Option<(RunReport, T)> {
    retried(name, attempt, |r, _| late::any_shortfall(r))
}

/// Runs `attempt` one at a time while `again` blames its outcome on the machine (see
/// [`late::while_late`]).
fn retried<T>(
    name: &str,
    mut attempt: impl FnMut() -> (RunReport, T),
    again: impl Fn(&RunReport, &T) -> Option<String>,
) -> Option<(RunReport, T)> {
    late::while_late(
        name,
        || {
            let _one = one_run_at_a_time();
            attempt()
        },
        |(report, rest)| again(report, rest),
    )
}

/// The arm's joints `q` within 1 mrad of `goal`, its velocities `qd` under 0.01 rad/s.
fn assert_at_rest_at(q: &[f64], qd: &[f64], goal: &[f64]) {
    for (k, g) in goal.iter().enumerate() {
        assert!(
            (q[k] - g).abs() < 1e-3,
            "joint {k} at {} instead of {g}",
            q[k]
        );
        assert!(qd[k].abs() < 1e-2, "joint {k} still moving: {}", qd[k]);
    }
}

/// The states of `rows`, each run of equal states once.
fn states(rows: &[CycleRecord<8>]) -> Vec<RunState> {
    let mut s: Vec<RunState> = rows.iter().map(|r| r.state).collect();
    s.dedup();
    s
}

const NO_REASON: u8 = 0;

fn reason_code(r: BrakeReason) -> u8 {
    match r {
        BrakeReason::Requested => 1,
        BrakeReason::Duration => 2,
        BrakeReason::Fault => 3,
        BrakeReason::InputsStale => 4,
    }
}

/// Swings every joint by up to `2·amplitude` from where it stood (one swing in 2 s); braking
/// fades the swing out over half a second. Counts the brake calls and keeps the last reason.
struct Swing {
    home: [f64; 8],
    amplitude: f64,
    braking_s: Option<f64>,
    ignores_brake: bool,
    brakes: Arc<AtomicU64>,
    reason: Arc<AtomicU8>,
    refused: Arc<AtomicU64>,
}

impl Swing {
    fn new(amplitude: f64) -> Self {
        Self {
            home: [0.0; 8],
            amplitude,
            braking_s: None,
            ignores_brake: false,
            brakes: Arc::new(AtomicU64::new(0)),
            reason: Arc::new(AtomicU8::new(NO_REASON)),
            refused: Arc::new(AtomicU64::new(0)),
        }
    }

    /// What the law commands at `t` without braking.
    fn at(home: f64, amplitude: f64, t: f64) -> f64 {
        home + amplitude * (1.0 - (std::f64::consts::PI * t).cos())
    }
}

impl ControlLaw<16, 8> for Swing {
    /// Odd numbers are refused.
    type Input = u32;

    fn name(&self) -> &str {
        "swing"
    }

    fn start(&mut self, start: &Start<'_, 16, 8>) -> Result<(), LawError> {
        self.home[..start.position.len()].copy_from_slice(start.position);
        Ok(())
    }

    fn input(&mut self, input: &Input<8, u32>) -> Result<(), Refused> {
        match input {
            Input::Other(n) if n % 2 == 1 => {
                self.refused.fetch_add(1, Ordering::Relaxed);
                Err(Refused("odd"))
            }
            _ => Ok(()),
        }
    }

    fn cycle(&mut self, cx: &mut Context<'_, 16, 8, u32>, out: &mut Command<8>) -> LawStatus {
        let s = self.braking_s.map_or(0.0, |b| (b / 0.5).min(1.0));
        let fade = 0.5 * (1.0 + (std::f64::consts::PI * s).cos());
        for k in 0..cx.dof {
            out.position[k] = self.home[k] + fade * (Self::at(0.0, self.amplitude, cx.time_s));
        }
        match &mut self.braking_s {
            None => LawStatus::Running,
            Some(_) if s >= 1.0 => LawStatus::AtRest,
            Some(b) => {
                *b += cx.period_s;
                LawStatus::Braking
            }
        }
    }

    fn brake(&mut self, reason: BrakeReason) {
        self.brakes.fetch_add(1, Ordering::Relaxed);
        self.reason.store(reason_code(reason), Ordering::Relaxed);
        if !self.ignores_brake {
            self.braking_s.get_or_insert(0.0);
        }
    }
}

#[test]
fn a_position_law_of_ones_own_drives_the_fake_h7() {
    let Some((report, (rows, fake, brakes, reason))) = on_time("own position law", || {
        let (fake, robot) = common::realtime_fake_h7();
        let law = Swing::new(0.05);
        let (brakes, reason) = (law.brakes.clone(), law.reason.clone());
        let run = ControlRun::start_law(
            robot,
            rv6sl().expect("model"),
            options().duration(Duration::from_millis(1500)),
            law,
        )
        .expect("starts");
        let (report, rows) = finish(run);
        (report, (rows, fake, brakes, reason))
    }) else {
        return;
    };
    let period = report.period_s;
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    assert_eq!(report.trajectory_source, "swing");
    assert_eq!(brakes.load(Ordering::Relaxed), 1, "braked once");
    assert_eq!(
        reason.load(Ordering::Relaxed),
        reason_code(BrakeReason::Duration)
    );
    assert_eq!(
        states(&rows),
        [RunState::Running, RunState::Braking, RunState::Stopped]
    );
    assert_eq!(rows.len() as u64, report.stats.cycles());
    let home = rows[0].commanded;
    // Each record holds what the law commanded in the cycle before: exactly its formula.
    for (i, r) in rows.iter().enumerate().skip(1) {
        if r.state != RunState::Running {
            break;
        }
        let t = (i - 1) as f64 * period;
        for k in 0..6 {
            let expected = Swing::at(home[k], 0.05, t);
            assert!(
                (r.commanded[k] - expected).abs() < 1e-12,
                "cycle {i} joint {k}: {} vs {expected}",
                r.commanded[k]
            );
        }
    }
    // The fake followed: its replies (the measured joints) swung by the full 0.1 rad at
    // t = 1 s and came back to rest where they started.
    let peak = rows
        .iter()
        .map(|r| r.measured[0] - home[0])
        .fold(0.0, f64::max);
    assert!(peak > 0.095 && peak < 0.1 + 1e-6, "peak {peak}");
    let last = rows.last().expect("rows");
    for k in 0..6 {
        assert!(
            (last.measured[k] - home[k]).abs() < 1e-4,
            "joint {k} ends at {} (started at {})",
            last.measured[k],
            home[k]
        );
    }
    let status = fake.status();
    assert!(
        status.moves + 2 >= report.stats.cycles(),
        "{} moves in {} cycles",
        status.moves,
        report.stats.cycles()
    );
    // The end packet goes without waiting for an answer: give the fake's thread (bounded)
    // time to take it.
    let deadline = Instant::now() + Duration::from_secs(2);
    while fake.status().ends == 0 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(fake.status().ends, 1, "the device was stopped");
}

#[test]
fn a_stop_request_goes_through_the_law_and_a_second_stops_at_once() {
    let Some((report, (rows, reason))) = on_time("stop through the law", || {
        let law = Swing::new(0.05);
        let reason = law.reason.clone();
        let run = ControlRun::start_law(sim_robot(), rv6sl().expect("model"), options(), law)
            .expect("starts");
        std::thread::sleep(Duration::from_millis(300));
        run.stop_flag().request_stop();
        let (report, rows) = finish(run);
        (report, (rows, reason))
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::Stopped), "{report}");
    assert_eq!(report.exit_code(), 130);
    assert_eq!(
        reason.load(Ordering::Relaxed),
        reason_code(BrakeReason::Requested)
    );
    assert_eq!(
        states(&rows),
        [RunState::Running, RunState::Braking, RunState::Stopped]
    );
    // Braking took the law's half second (at 2 ms per cycle), not longer.
    let braking = rows.iter().filter(|r| r.state == RunState::Braking).count();
    assert!((249..=252).contains(&braking), "{braking} braking cycles");

    // A law that ignores the request: the second request ends the run at once.
    let Some((report, _)) = on_time("a second stop request", || {
        let mut law = Swing::new(0.05);
        law.ignores_brake = true;
        let run = ControlRun::start_law(sim_robot(), rv6sl().expect("model"), options(), law)
            .expect("starts");
        std::thread::sleep(Duration::from_millis(100));
        run.stop_flag().request_stop();
        std::thread::sleep(Duration::from_millis(100));
        run.stop_flag().request_stop();
        finish(run)
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::Aborted), "{report}");
}

#[test]
fn a_law_that_never_comes_to_rest_is_ended_at_once() {
    let Some((report, rows)) = on_time("a law never at rest", || {
        let mut law = Swing::new(0.05);
        law.ignores_brake = true;
        let options = RunOptions {
            max_braking: Duration::from_millis(200),
            ..options().duration(Duration::from_millis(300))
        };
        finish(
            ControlRun::start_law(sim_robot(), rv6sl().expect("model"), options, law)
                .expect("starts"),
        )
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::BrakeTimeout), "{report}");
    assert_eq!(report.exit_code(), 1, "{report}");
    assert!(report.failure.is_some());
    let braking = rows.iter().filter(|r| r.state == RunState::Braking).count();
    assert_eq!(braking, 101, "200 ms of braking at 2 ms, then ended");
    assert!(report.shutdown.stopped, "{report}");
}

#[test]
fn inputs_are_checked_counted_and_dropped_when_the_queue_is_full() {
    let Some((report, (tx, refused_by_law))) = on_time("inputs counted", || {
        let law = Swing::new(0.02);
        let refused_by_law = law.refused.clone();
        let options = RunOptions {
            input_capacity: 4,
            ..options().duration(Duration::from_millis(600))
        };
        let run = ControlRun::start_law(sim_robot(), rv6sl().expect("model"), options, law)
            .expect("starts");
        let tx = run.inputs();
        // A burst far faster than one cycle: the queue of 4 overflows; every input is either
        // queued or counted as dropped.
        let mut full = 0;
        for n in 0..100u32 {
            match tx.send(n) {
                Ok(()) => {}
                Err(InputError::Full) => full += 1,
                Err(e) => panic!("{e}"),
            }
        }
        assert!(full > 0, "a burst of 100 overflows a queue of 4");
        assert_eq!(tx.sent() + tx.dropped(), 100);
        // Targets are checked before they go, and refused with the joint named.
        let mut q = [0.0; 6];
        q[1] = 3.0;
        let e = tx.send_position(&q).expect_err("outside the limits");
        assert!(
            matches!(&e, InputError::OutsideLimits { joint, .. } if joint == "joint1"),
            "{e}"
        );
        assert!(matches!(
            tx.send_velocity(&[0.0; 5]),
            Err(InputError::Length {
                expected: 6,
                got: 5
            })
        ));
        // Once the loop has taken the burst (a few cycles), another thread's input gets through.
        std::thread::sleep(Duration::from_millis(50));
        let other = tx.clone();
        std::thread::spawn(move || other.send(2).expect("from another thread"))
            .join()
            .expect("sender thread");
        let (report, _) = finish(run);
        (report, (tx, refused_by_law))
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    let i = report.inputs.clone().expect("inputs reported");
    assert_eq!(i.sent, tx.sent());
    assert_eq!(i.dropped_full, tx.dropped());
    assert_eq!(i.refused_invalid, 2);
    assert!(
        i.first_invalid
            .as_deref()
            .is_some_and(|w| w.contains("joint1")),
        "{i:?}"
    );
    assert_eq!(i.refused_by_law, refused_by_law.load(Ordering::Relaxed));
    assert!(i.refused_by_law > 0);
    assert_eq!(i.first_law_refusal, Some("odd"));
    assert_eq!(i.others + i.refused_by_law + i.not_taken, i.sent);
    let json = report.to_json();
    assert_eq!(json["inputs"]["dropped_full"], tx.dropped());
    assert!(report.to_string().contains("inputs: "), "{report}");
    assert_eq!(tx.send(4), Err(InputError::Ended), "the run is over");
}

/// Takes the arm to a position target along a jerk-limited reference with computed torques,
/// `τ = RNEA(q, q̇, r̈ + Kp·(r − q) + Kd·(ṙ − q̇))`, less the gravity torque `RNEA(q, 0, 0)` for
/// a device that compensates gravity itself (a Franka arm); takes a new target only at rest.
/// Braking holds the reference where it is and ends once the arm is still.
struct ComputedTorque {
    reference: [f64; 8],
    limits: Limits<8>,
    pending: Option<[f64; 8]>,
    moving: Option<(JerkLimited<8>, f64)>,
    braking: bool,
    gravity_by_device: bool,
}

impl ComputedTorque {
    const KP: f64 = 400.0;
    const KD: f64 = 40.0;

    fn new() -> Self {
        Self {
            reference: [0.0; 8],
            limits: Limits::uniform(1.0, 1.0, 1.0),
            pending: None,
            moving: None,
            braking: false,
            gravity_by_device: false,
        }
    }

    /// The same for a device that adds the gravity torque to what it is given.
    fn gravity_compensated() -> Self {
        Self {
            gravity_by_device: true,
            ..Self::new()
        }
    }

    /// Subtracts the gravity torque at `cx.measured.position` from `out.torque`.
    fn less_gravity(cx: &mut Context<'_, 16, 8, ()>, out: &mut Command<8>) {
        let zero = [0.0; 8];
        let dof = cx.dof;
        if let Ok(g) = rnea(
            cx.model,
            cx.data,
            cx.measured.position,
            &zero[..dof],
            &zero[..dof],
        ) {
            for k in 0..dof {
                out.torque[k] -= g[k];
            }
        }
    }
}

impl ControlLaw<16, 8> for ComputedTorque {
    type Input = ();

    fn mode(&self) -> CommandMode {
        CommandMode::Torque
    }

    fn name(&self) -> &str {
        "computed torque"
    }

    fn start(&mut self, start: &Start<'_, 16, 8>) -> Result<(), LawError> {
        self.reference[..start.position.len()].copy_from_slice(start.position);
        let l = start.limits;
        self.limits = Limits {
            velocity: l.velocity,
            acceleration: l.acceleration,
            jerk: l.jerk,
        };
        Ok(())
    }

    fn input(&mut self, input: &Input<8, ()>) -> Result<(), Refused> {
        match input {
            Input::Target(Target::Position { position, .. }) => {
                if self.pending.is_some() || self.moving.is_some() || self.braking {
                    return Err(Refused("moving: a new target is taken at rest"));
                }
                self.pending = Some(*position);
                Ok(())
            }
            _ => Err(Refused("only position targets")),
        }
    }

    fn cycle(&mut self, cx: &mut Context<'_, 16, 8, ()>, out: &mut Command<8>) -> LawStatus {
        let dof = cx.dof;
        if let (Some(goal), false) = (self.pending.take(), self.braking) {
            if let Ok(m) = JerkLimited::new(self.reference, goal, &self.limits) {
                self.moving = Some((m, cx.time_s));
            }
        }
        let (mut r, mut rd, mut rdd) = (self.reference, [0.0; 8], [0.0; 8]);
        if let Some((m, t0)) = &self.moving {
            let s = m.sample(cx.time_s - t0);
            (r, rd, rdd) = (s.position, s.velocity, s.acceleration);
            if cx.time_s - t0 >= m.duration() || self.braking {
                self.moving = None;
            }
        }
        self.reference = r;
        let q = cx.measured.position;
        let Some(qd) = cx.measured.velocity else {
            return LawStatus::AtRest;
        };
        let mut qdd = [0.0; 8];
        for k in 0..dof {
            qdd[k] = rdd[k] + Self::KP * (r[k] - q[k]) + Self::KD * (rd[k] - qd[k]);
        }
        if let Ok(tau) = rnea(cx.model, cx.data, q, qd, &qdd[..dof]) {
            out.torque[..dof].copy_from_slice(tau);
        }
        if self.gravity_by_device {
            Self::less_gravity(cx, out);
        }
        out.position = r;
        out.velocity = rd;
        if !self.braking {
            LawStatus::Running
        } else if qd.iter().all(|v| v.abs() < 1e-3) {
            LawStatus::AtRest
        } else {
            LawStatus::Braking
        }
    }

    /// The gravity torque where the arm stands, unless the device compensates it.
    fn hold(&mut self, cx: &mut Context<'_, 16, 8, ()>, out: &mut Command<8>) {
        if self.gravity_by_device {
            return;
        }
        let zero = [0.0; 8];
        let dof = cx.dof;
        if let Ok(tau) = rnea(
            cx.model,
            cx.data,
            cx.measured.position,
            &zero[..dof],
            &zero[..dof],
        ) {
            out.torque[..dof].copy_from_slice(tau);
        }
    }

    fn brake(&mut self, _reason: BrakeReason) {
        self.braking = true;
    }
}

#[test]
fn a_computed_torque_law_takes_a_simulated_arm_to_a_streamed_target() {
    let start = [0.0, 0.3, 0.6, 0.0, 0.4, 0.0];
    let goal = [0.3, 0.1, 0.9, -0.2, 0.2, 0.5];
    let Some((report, (rows, status))) = on_time("computed torque", || {
        let model = rv6sl().expect("model");
        let arm = SimArm::new(model.model.clone(), &start, ArmMode::Torque, PERIOD);
        let status = arm.status();
        let run = ControlRun::start_law(
            arm,
            model,
            options().duration(Duration::from_millis(2500)),
            ComputedTorque::new(),
        )
        .expect("starts");
        let tx = run.inputs();
        tx.send_position(&goal).expect("the target");
        // Sent at once after it: refused by the law (not at rest), counted.
        tx.send_position(&start).expect("queued");
        tx.send_velocity(&[0.1; 6]).expect("queued");
        let (report, rows) = finish(run);
        (report, (rows, status))
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    // The first exchange held the arm against gravity (the law's hold): it did not sag.
    for k in 0..6 {
        assert!(
            (rows[0].measured[k] - start[k]).abs() < 1e-9,
            "joint {k} moved to {} in the first exchange",
            rows[0].measured[k]
        );
    }
    let i = report.inputs.clone().expect("inputs");
    assert_eq!((i.targets, i.refused_by_law), (1, 2), "{i:?}");
    let st = status.lock().expect("status");
    assert_eq!(st.refused, 0, "only torque commands were sent");
    assert!(st.commands as usize >= rows.len() - 1);
    assert_at_rest_at(&st.q, &st.qd, &goal);
    // The reference tracked within the supervisor's bound all along, and the torques are the
    // law's (the gravity torque of a joint that carries the arm is far from zero).
    assert!(report.tracking_error_max < 1e-2, "{report}");
    assert!(report.peak_feed_forward[1] > 1.0, "{report}");
    assert!(st.stopped_from.is_some() && !st.powered);
}

/// The computed-torque law on the fake FR3 in torque mode at its 1 kHz (FCI on loopback, the
/// arm's dynamics integrated by the fake from the same URDF, gravity added by the robot): the
/// law's torques reach the robot through the driver's torque capability, and a streamed target
/// is reached and held; the robot raised no reflex (its torque-rate and limit checks, and
/// lost commands: the loop answers every state before the next tick, which needs the phase
/// lock's jump out of a start one state behind).
#[test]
fn a_torque_law_takes_the_fake_franka_to_a_streamed_target() {
    let urdf = fr3_shaped_urdf();
    let goal = [0.2, -0.6, 0.1, -2.2, 0.1, 1.8, 0.6];
    // Its checks do not depend on the run's timing: a late run that ended well is checked; one
    // that failed with the loop or the fake late (its clock slipped or woke a quarter cycle
    // late) is tried again. Lost commands with both on time fail the test.
    let failed_late = |r: &RunReport, (_, fake): &(Vec<CycleRecord<8>>, FakeFranka)| {
        common::franka_run_late(r, fake)
    };
    let attempt = || {
        let (fake, robot) = common::fake_franka_in_torque_mode(&urdf);
        let model = load_urdf_str::<16>(&urdf, &UrdfOptions::default()).expect("model");
        let run = ControlRun::start_law(
            robot,
            model,
            options().duration(Duration::from_millis(2500)),
            ComputedTorque::gravity_compensated(),
        )
        .expect("starts");
        run.inputs().send_position(&goal).expect("the target");
        let (report, rows) = finish(run);
        (report, (rows, fake))
    };
    let Some((report, (rows, fake))) = retried("torque law on the fake FR3", attempt, failed_late)
    else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::CycleLimit), "{report}");
    assert_eq!(report.exit_code(), 0, "{report}");
    assert!((report.period_s - 0.001).abs() < 1e-9, "{report}");
    // At rest at the target when the duration ends: the law's braking is over at once.
    let s = states(&rows);
    assert_eq!(s.first(), Some(&RunState::Running), "{s:?}");
    assert_eq!(s.last(), Some(&RunState::Stopped), "{s:?}");
    assert!(!s.contains(&RunState::Fault), "{s:?}");
    let i = report.inputs.clone().expect("inputs");
    assert_eq!((i.targets, i.refused_by_law), (1, 0), "{i:?}");
    let status = fake.status();
    assert!(
        status.raised.is_empty(),
        "the robot raised {:?}",
        status.raised
    );
    // At the target and still (the robot's own state: it moves by the law's torques alone, as
    // it compensates gravity itself), within the tracking bound all along.
    assert_at_rest_at(&status.q, &status.dq, &goal);
    assert!(report.tracking_error_max < 1e-2, "{report}");
    assert!(
        report.peak_feed_forward.iter().any(|t| *t > 0.1),
        "{report}"
    );
}

/// Velocity commands toward a target with a speed and acceleration limit; the reference
/// position integrates them. Braking decelerates to zero.
struct VelocityServo {
    reference: [f64; 8],
    velocity: [f64; 8],
    braking: bool,
    /// Its top speed (rad/s).
    speed: f64,
}

impl VelocityServo {
    const GAIN: f64 = 10.0;
    const ACCEL: f64 = 4.0;

    fn new(speed: f64) -> Self {
        Self {
            reference: [0.0; 8],
            velocity: [0.0; 8],
            braking: false,
            speed,
        }
    }
}

impl ControlLaw<16, 8> for VelocityServo {
    type Input = ();

    fn mode(&self) -> CommandMode {
        CommandMode::Velocity
    }

    fn start(&mut self, start: &Start<'_, 16, 8>) -> Result<(), LawError> {
        self.reference[..start.position.len()].copy_from_slice(start.position);
        Ok(())
    }

    fn cycle(&mut self, cx: &mut Context<'_, 16, 8, ()>, out: &mut Command<8>) -> LawStatus {
        // At rest once zero was commanded (the last command stays with the drives).
        if self.braking && self.velocity.iter().all(|v| *v == 0.0) {
            return LawStatus::AtRest;
        }
        let target = match (cx.inputs.target(), self.braking) {
            (Some(Target::Position { position, .. }), false) => Some(*position),
            _ => None,
        };
        let dv = Self::ACCEL * cx.period_s;
        for k in 0..cx.dof {
            let want = target.map_or(0.0, |t| {
                (Self::GAIN * (t[k] - self.reference[k])).clamp(-self.speed, self.speed)
            });
            self.velocity[k] += (want - self.velocity[k]).clamp(-dv, dv);
            self.reference[k] += self.velocity[k] * cx.period_s;
        }
        out.velocity = self.velocity;
        out.position = self.reference;
        if self.braking {
            LawStatus::Braking
        } else {
            LawStatus::Running
        }
    }

    fn brake(&mut self, _reason: BrakeReason) {
        self.braking = true;
    }
}

#[test]
fn inputs_that_stop_coming_bring_the_arm_to_rest() {
    let timeout = Duration::from_millis(300);
    let Some((report, (rows, status))) = on_time("stale inputs", || {
        let model = rv6sl().expect("model");
        let arm = SimArm::new(model.model.clone(), &[0.0; 6], ArmMode::Velocity, PERIOD);
        let status = arm.status();
        let run = ControlRun::start_law(
            arm,
            model,
            options().input_timeout(timeout),
            VelocityServo::new(0.5),
        )
        .expect("starts");
        // A target that moves every 20 ms for 0.6 s, then nothing: the arm follows (still
        // creeping towards the last target when the inputs go stale), then is brought to rest
        // once 300 ms pass without one.
        let tx = run.inputs();
        let sender = std::thread::spawn(move || {
            for i in 0..30 {
                let x = 0.01 * f64::from(i);
                tx.send_position(&[x, -x, x, 0.0, x, 0.0]).expect("sent");
                std::thread::sleep(Duration::from_millis(20));
            }
        });
        let (report, rows) = finish(run);
        sender.join().expect("sender");
        (report, (rows, status))
    }) else {
        return;
    };
    assert_eq!(report.end, Some(RunEnd::InputsStale), "{report}");
    assert_eq!(report.exit_code(), 1, "{report}");
    let i = report.inputs.clone().expect("inputs");
    assert!(i.stale, "{i:?}");
    assert_eq!(i.targets, 30, "{i:?}");
    assert!(i.timeout_s.is_some_and(|t| (t - 0.3).abs() < 1e-9), "{i:?}");
    // The loop saw the inputs go stale in the first cycle past the timeout (a cycle is 2 ms;
    // a late wake-up of the loop may add a few).
    let age = i.stale_age_s.expect("the age when it went stale");
    assert!(age > 0.3 && age < 0.3 + 0.02, "stale at age {age} s");
    assert_eq!(
        states(&rows),
        [RunState::Running, RunState::Braking, RunState::Stopped]
    );
    // At rest where the last target was (it had time to get there), and only velocity
    // commands were sent.
    let st = status.lock().expect("status");
    assert_eq!(st.refused, 0);
    assert!(st.qd.iter().all(|v| *v == 0.0), "{:?}", st.qd);
    for (k, goal) in [0.29, -0.29, 0.29, 0.0, 0.29, 0.0].iter().enumerate() {
        assert!((st.q[k] - goal).abs() < 5e-3, "{:?}", st.q);
    }
}

/// The speed check of the measured motion divides by the time between two measurements: a
/// device that numbers its measurements (the Franka's `message_id`) and moved several of its
/// periods between two readings (the states between lost, as a loop that woke late finds a
/// robot that kept its own clock) is not taken for one that went several times too fast; for
/// a device that does not number them the same motion counts as too fast (nothing tells the
/// loop it lasted longer).
#[test]
fn the_speed_check_counts_the_periods_between_numbered_measurements() {
    let run = |numbered: bool, stall: u32| {
        let _one = one_run_at_a_time();
        let model = rv6sl().expect("model");
        let mut arm = SimArm::new(model.model.clone(), &[0.0; 6], ArmMode::Velocity, PERIOD)
            .stalling(350, stall);
        if numbered {
            arm = arm.numbered();
        }
        let run = ControlRun::start_law(
            arm,
            model,
            options().duration(Duration::from_millis(800)),
            VelocityServo::new(3.0),
        )
        .expect("starts");
        run.inputs()
            .send_position(&[2.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            .expect("the target");
        finish(run).0
    };
    // Two periods of motion of joint 0 at 2.8 rad/s (its limit: 4.4 rad/s) between two
    // readings, at the 350th exchange.
    let numbered = run(true, 2);
    assert_eq!(numbered.exit_code(), 0, "{numbered}");
    assert_eq!(numbered.limit_violations, 0, "{numbered}");
    let unnumbered = run(false, 2);
    assert_eq!(unnumbered.exit_code(), 0, "{unnumbered}");
    assert_eq!(unnumbered.limit_violations, 1, "{unnumbered}");
    let v = unnumbered.first_violation.expect("the first");
    assert_eq!((v.quantity, v.joint), ("speed", 0), "{v:?}");
    assert!(v.value > 5.5, "{v:?}");
}

#[test]
fn a_device_that_takes_no_torque_is_refused_before_anything_moves() {
    let sim = sim_robot();
    let status = sim.status();
    let e = ControlRun::start_law(
        sim,
        rv6sl().expect("model"),
        options(),
        ComputedTorque::new(),
    )
    .err()
    .expect("refused");
    assert!(
        matches!(
            e,
            RunError::Plan(PlanError::CommandMode {
                mode: CommandMode::Torque
            })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("torque"), "{e}");
    let st = status.lock().expect("status");
    assert!(!st.powered && st.steps == 0, "nothing was started");
}

#[test]
fn the_report_and_the_telemetry_say_when_the_fault_happened() {
    let Some((report, rows)) = on_time("fault time", || {
        // The tour, joint 1 blocked from step 150 on (0.3 s): the tracking bound is crossed a
        // few cycles later, and the arm is then brought to rest, which takes longer.
        let sim = sim_robot().misbehave(Misbehaviour::Block(1), 150);
        let run = ControlRun::<_, 16, 8>::start(
            sim,
            rv6sl().expect("model"),
            RunOptions {
                speed: 0.5,
                ..options()
            },
        )
        .expect("starts");
        finish(run)
    }) else {
        return;
    };
    let at = report.fault_at.expect("fault time reported");
    assert!(
        matches!(report.end, Some(RunEnd::Fault(f)) if f.joint() == Some(1)),
        "{report}"
    );
    assert!((150..200).contains(&at.cycle), "{at:?}");
    let first = rows
        .iter()
        .position(|r| r.state == RunState::Fault)
        .expect("a fault row");
    assert_eq!(rows[first].cycle, at.cycle);
    assert_eq!(rows[first].time_s, at.time_s);
    assert!(rows[..first].iter().all(|r| r.state == RunState::Running));
    assert_eq!(
        states(&rows),
        [RunState::Running, RunState::Fault, RunState::Stopped]
    );
    assert!(
        at.time_s + 0.05 < report.trajectory_time_s,
        "the fault at {} s, the end at {} s",
        at.time_s,
        report.trajectory_time_s
    );
    let json = report.to_json();
    assert_eq!(json["fault_cycle"], at.cycle);
    assert_eq!(json["fault_time_s"], at.time_s);
    let text = report.to_string();
    assert!(
        text.contains(&format!(
            "fault found at cycle {}, t = {:.3} s",
            at.cycle, at.time_s
        )),
        "{text}"
    );
}

/// A target the limits cannot reach (at the edge of joint 0's range, moving back in at 0.9 of
/// its speed: arriving there so needs a turn beyond the limit) is not taken: counted as
/// unreachable with the generator's reason, the motion to the target before it goes on and
/// reaches it, and the position limits are never left.
#[test]
fn a_target_the_limits_cannot_reach_is_counted_and_not_taken() {
    let fake = common::immediate_fake(6);
    let common::LawOnH7 {
        mut control,
        tx,
        start,
        limits,
    } = common::law_on_h7(&fake, rl::controller::TargetFollower::<8>::new(), 16);
    let dof = start.len();
    let upper = control.model().limits(0).upper;
    let mut reachable = start.clone();
    reachable[1] += 0.05;
    tx.send_position(&reachable).expect("a reachable target");
    for _ in 0..5 {
        assert!(!control.cycle().finished);
    }
    let mut edge = start.clone();
    edge[0] = upper - 1e-3;
    let mut inwards = vec![0.0; dof];
    inwards[0] = -0.9 * limits.velocity[0];
    tx.send_position_velocity(&edge, &inwards)
        .expect("the channel takes it: within the limits, the speed allowed");
    let mut q = [0.0; 8];
    for _ in 0..2000 {
        let cycle = control.cycle();
        assert!(!cycle.finished);
        q = cycle.record.commanded;
        assert!(
            q[0] <= upper,
            "joint 0 commanded at {} beyond {upper}",
            q[0]
        );
    }
    let counts = *control.law().counts();
    assert_eq!(counts.targets, 1, "{counts:?}");
    assert_eq!(counts.unreachable, 1, "{counts:?}");
    assert!(counts.first_unreachable.is_some(), "{counts:?}");
    assert!(
        counts.last_reach_s.is_some(),
        "the first target was reached: {counts:?}"
    );
    for (k, (q, goal)) in q[..dof].iter().zip(&reachable).enumerate() {
        assert!((q - goal).abs() < 1e-9, "joint {k} at {q}, not at {goal}");
    }
    let mut robot = control.into_robot();
    rl::drivers::Device::stop(&mut robot).expect("stop");
    rl::drivers::Device::close(&mut robot).expect("close");
}
