//! The generator in a control loop (`rl_core::traj::otg::Otg`) at 1 kHz: targets that jump to
//! random reachable states, stops from any state, and the guarantees a controller relies on —
//! continuity between cycles, every commanded sample within the limits, each target reached when
//! the trajectory says, no allocation, the same bits for the same input.

use std::time::Duration;

use rl_core::traj::otg::{self, Input, Interface, Limits, Otg, OtgError, State, Synchronization};
use rl_testkit::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

const DT: f64 = 0.001;

mod otg_support;
use otg_support::Rng;

fn limits() -> Limits<6> {
    let mut l = Limits::new(
        [1.0, 1.2, 1.5, 2.0, 2.5, 3.0],
        [2.0, 3.0, 4.0, 5.0, 6.0, 8.0],
        [20.0, 30.0, 40.0, 50.0, 60.0, 80.0],
    );
    // Asymmetric on two axes.
    l.min_velocity[1] = -0.8;
    l.min_acceleration[2] = -2.5;
    l
}

/// Every commanded sample within the limits (1e-9), and continuous between cycles: the
/// acceleration moves by at most one cycle of jerk, the velocity and position by what that
/// acceleration integrates to.
fn check_cycle<const N: usize>(prev: &State<N>, out: &otg::Output<N>, l: &Limits<N>, cycle: usize) {
    let s = &out.sample;
    let tol = 1e-9;
    for i in 0..N {
        assert!(
            s.velocity[i] <= l.max_velocity[i] + tol && s.velocity[i] >= l.min_velocity[i] - tol,
            "cycle {cycle} axis {i}: v {}",
            s.velocity[i]
        );
        assert!(
            s.acceleration[i] <= l.max_acceleration[i] + tol
                && s.acceleration[i] >= l.min_acceleration[i] - tol,
            "cycle {cycle} axis {i}: a {}",
            s.acceleration[i]
        );
        assert!(
            s.jerk[i].abs() <= l.max_jerk[i] + tol,
            "cycle {cycle} axis {i}: j {}",
            s.jerk[i]
        );
        let da = (s.acceleration[i] - prev.acceleration[i]).abs();
        assert!(
            da <= l.max_jerk[i] * DT * (1.0 + 1e-9) + 1e-12,
            "cycle {cycle} axis {i}: a jumps by {da}"
        );
        let dv = (s.velocity[i] - prev.velocity[i]).abs();
        let bound = DT * l.max_acceleration[i].max(-l.min_acceleration[i]);
        assert!(
            dv <= bound * (1.0 + 1e-9) + 1e-12,
            "cycle {cycle} axis {i}: v jumps by {dv}"
        );
    }
}

#[test]
fn jumping_targets_are_followed_within_limits() {
    let l = limits();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let start = State::at_rest([0.0; 6]);
    let mut generator = Otg::new(Duration::from_millis(1), start);
    let mut goal = Input::new(start, start, l);
    let mut prev = start;
    let (mut reached, mut switches) = (0, 0);
    // 200 targets at 1 kHz, a new one every 50 ms, or, one time in ten, after 2 s (long enough
    // to be reached).
    let mut cycle = 0;
    while switches < 200 {
        goal.target.position = std::array::from_fn(|_| rng.uniform(-1.5, 1.5));
        let moving = switches % 3 == 1;
        goal.target.velocity = std::array::from_fn(|i| {
            if moving {
                rng.uniform(l.min_velocity[i], l.max_velocity[i]) * 0.5
            } else {
                0.0
            }
        });
        goal.synchronization = if switches % 2 == 0 {
            Synchronization::Time
        } else {
            Synchronization::Phase
        };
        switches += 1;
        let hold = if switches % 10 == 0 { 2000 } else { 50 };
        let mut expected_end = None;
        for k in 0..hold {
            let out = generator.update(&goal).expect("reachable target");
            if k == 0 {
                assert!(out.recalculated, "a new target recalculates");
                expected_end = Some(generator.trajectory().duration());
            } else {
                assert!(!out.recalculated, "an unchanged goal does not recalculate");
            }
            check_cycle(&prev, &out, &l, cycle);
            prev = *generator.state();
            cycle += 1;
            let end = expected_end.expect("set");
            // Reached exactly when the trajectory said, within one cycle.
            if out.finished && out.time - DT < end {
                for i in 0..6 {
                    let s = &out.sample;
                    let drift = goal.target.velocity[i] * (out.time - end);
                    assert!(
                        (s.position[i] - goal.target.position[i] - drift).abs() < 1e-7,
                        "axis {i} p {} target {}",
                        s.position[i],
                        goal.target.position[i]
                    );
                    assert!((s.velocity[i] - goal.target.velocity[i]).abs() < 1e-7);
                }
                reached += 1;
            }
        }
    }
    assert!(switches > 100, "{switches} targets");
    assert!(
        reached >= 2,
        "targets held long enough were reached: {reached}"
    );
}

#[test]
fn stops_from_any_state_time_optimally() {
    let l = limits();
    let mut rng = Rng(7);
    for _ in 0..500 {
        let state = State {
            position: std::array::from_fn(|_| rng.uniform(-1.0, 1.0)),
            velocity: std::array::from_fn(|i| rng.uniform(l.min_velocity[i], l.max_velocity[i])),
            acceleration: std::array::from_fn(|i| {
                rng.uniform(l.min_acceleration[i], l.max_acceleration[i]) * 0.5
            }),
        };
        for sync in [
            Synchronization::None,
            Synchronization::Time,
            Synchronization::Phase,
        ] {
            let stop = otg::braking(&state, &l, sync).expect("a stop is always possible");
            let end = stop.at_time(stop.duration());
            for i in 0..6 {
                assert!(end.velocity[i].abs() < 1e-8 && end.acceleration[i].abs() < 1e-10);
            }
            assert!(stop.limit_violation(&l, 1e-9, true).is_none());
            // Synchronised or not, the stop takes the slowest axis' own shortest time.
            let slowest = stop.min_durations().iter().fold(0.0f64, |m, &t| m.max(t));
            assert!(
                (stop.duration() - slowest).abs() <= 1e-12 * slowest.max(1.0),
                "{sync:?}"
            );
        }
    }
    // In a loop: brake, step to rest.
    let mut generator = Otg::new(Duration::from_millis(1), State::at_rest([0.0; 6]));
    let mut goal = Input::new(*generator.state(), State::at_rest([1.0; 6]), l);
    goal.interface = Interface::Position;
    for _ in 0..300 {
        generator.update(&goal).expect("goal");
    }
    generator.brake(&l, Synchronization::None).expect("stop");
    let mut prev = *generator.state();
    for cycle in 0..5000 {
        let out = generator.step();
        check_cycle(&prev, &out, &l, cycle);
        prev = *generator.state();
    }
    assert!(generator.is_finished());
    assert!(generator.state().velocity.iter().all(|v| v.abs() < 1e-9));
}

#[test]
fn control_loop_allocates_nothing() {
    let l = limits();
    let start = State::at_rest([0.0; 6]);
    let mut generator = Otg::new(Duration::from_millis(1), start);
    let mut goal = Input::new(start, State::at_rest([0.5; 6]), l);
    generator.update(&goal).expect("warm up");
    let (n, _) = allocations(|| {
        for k in 0..2000 {
            if k % 100 == 0 {
                goal.target.position = [0.5 - 0.001 * k as f64; 6];
            }
            let out = generator.update(&goal).expect("goal");
            std::hint::black_box(&out);
        }
        generator.brake(&l, Synchronization::Time).expect("stop");
        for _ in 0..1000 {
            std::hint::black_box(generator.step());
        }
        std::hint::black_box(
            otg::braking(generator.state(), &l, Synchronization::None).expect("stop"),
        );
    });
    assert_eq!(n, 0, "allocations in the control loop");
}

#[test]
fn same_input_same_bits() {
    let l = limits();
    let current = State {
        position: [0.1, -0.2, 0.3, -0.4, 0.5, -0.6],
        velocity: [0.5, -0.3, 0.2, 1.0, -1.5, 0.7],
        acceleration: [1.0, -0.5, 0.3, -2.0, 3.0, 0.0],
    };
    let target = State {
        position: [1.0, 0.5, -0.7, 0.2, 0.0, -1.0],
        velocity: [0.0, 0.2, 0.0, -0.3, 0.0, 0.0],
        acceleration: [0.0; 6],
    };
    let input = Input::new(current, target, l);
    let a = otg::calculate(&input).expect("trajectory");
    // Something else in between (other code paths warm, other state in caches).
    let _ = otg::calculate(&Input::new(target, current, l));
    let b = otg::calculate(&input).expect("trajectory");
    assert_eq!(a.duration().to_bits(), b.duration().to_bits());
    for k in 0..=200 {
        let t = a.duration() * k as f64 / 200.0;
        let (sa, sb) = (a.at_time(t), b.at_time(t));
        for i in 0..6 {
            assert_eq!(sa.position[i].to_bits(), sb.position[i].to_bits());
            assert_eq!(sa.jerk[i].to_bits(), sb.jerk[i].to_bits());
        }
    }
}

#[test]
fn bad_input_is_a_typed_error_naming_the_axis() {
    use otg::{Limit, Quantity};
    let l = Limits::<3>::uniform(1.0, 2.0, 10.0);
    let ok = Input::new(State::at_rest([0.0; 3]), State::at_rest([1.0; 3]), l);
    assert!(otg::calculate(&ok).is_ok());

    let mut nan = ok;
    nan.current.velocity[1] = f64::NAN;
    assert_eq!(
        otg::calculate(&nan).unwrap_err(),
        OtgError::NotFinite {
            quantity: Quantity::CurrentVelocity,
            axis: 1
        }
    );

    let mut inf = ok;
    inf.target.position[2] = f64::INFINITY;
    assert_eq!(
        otg::calculate(&inf).unwrap_err(),
        OtgError::NotFinite {
            quantity: Quantity::TargetPosition,
            axis: 2
        }
    );

    let mut negative = ok;
    negative.limits.max_jerk[0] = -1.0;
    assert_eq!(
        otg::calculate(&negative).unwrap_err(),
        OtgError::BadLimit {
            limit: Limit::MaxJerk,
            axis: 0
        }
    );

    let mut wrong_sign = ok;
    wrong_sign.limits.min_acceleration[2] = 0.5;
    assert_eq!(
        otg::calculate(&wrong_sign).unwrap_err(),
        OtgError::BadLimit {
            limit: Limit::MinAcceleration,
            axis: 2
        }
    );

    let mut too_fast = ok;
    too_fast.target.velocity[1] = 1.5;
    assert_eq!(
        otg::calculate(&too_fast).unwrap_err(),
        OtgError::TargetOutsideLimits {
            quantity: Quantity::TargetVelocity,
            axis: 1
        }
    );

    // Arriving at full velocity while still accelerating would have exceeded the limit.
    let mut unapproachable = ok;
    unapproachable.target.velocity[0] = 1.0;
    unapproachable.target.acceleration[0] = -1.0;
    assert_eq!(
        otg::calculate(&unapproachable).unwrap_err(),
        OtgError::TargetOutsideLimits {
            quantity: Quantity::TargetAcceleration,
            axis: 0
        }
    );

    // A zero jerk limit keeps the current (zero) acceleration: a moving target is unreachable.
    let mut zero = ok;
    zero.limits.max_jerk[2] = 0.0;
    assert_eq!(
        otg::calculate(&zero).unwrap_err(),
        OtgError::ZeroLimits { axis: 2 }
    );

    // The generator keeps its trajectory when a new goal fails.
    let mut generator = Otg::new(Duration::from_millis(1), State::at_rest([0.0; 3]));
    generator.update(&ok).expect("goal");
    let before = generator.trajectory().duration();
    assert!(generator.update(&too_fast).is_err());
    assert_eq!(generator.trajectory().duration(), before);
}

/// A goal the generator cannot reach leaves the motion under way as it was: the cycles after
/// the refused update are, bit for bit, those of a generator that never saw it. The refused
/// goal fails late in the calculation (its position limits: arriving at the edge moving back
/// in needs a turn beyond it), after the synchronised profiles were written, and a refused
/// stop the same way.
#[test]
fn a_refused_goal_leaves_the_motion_under_way() {
    let mut l = Limits::<3>::uniform(1.0, 2.0, 10.0);
    l.min_position = [-1.0; 3];
    l.max_position = [1.0; 3];
    let start = State::at_rest([0.0; 3]);
    let goal = Input::new(start, State::at_rest([0.5, -0.3, 0.2]), l);
    let mut refused = goal;
    refused.target.position[0] = 1.0 - 1e-3;
    refused.target.velocity[0] = -0.9;
    let mut a = Otg::new(Duration::from_secs_f64(DT), start);
    let mut b = Otg::new(Duration::from_secs_f64(DT), start);
    for _ in 0..100 {
        assert_eq!(a.update(&goal).unwrap(), b.update(&goal).unwrap());
    }
    let err = a.update(&refused).unwrap_err();
    assert!(
        matches!(
            err,
            OtgError::PositionLimitsUnreachable { axis: 0 }
                | OtgError::CannotStopBeforePositionLimit { axis: 0 }
        ),
        "{err:?}"
    );
    let mut bad_limits = l;
    bad_limits.max_jerk[1] = -1.0;
    assert!(b.brake(&bad_limits, Synchronization::None).is_err());
    loop {
        let (x, y) = (a.update(&goal).unwrap(), b.update(&goal).unwrap());
        assert_eq!(x, y);
        assert!(!x.recalculated);
        if x.finished {
            for (p, goal) in x.sample.position.iter().zip([0.5, -0.3, 0.2]) {
                assert!((p - goal).abs() < 1e-12, "{p} for {goal}");
            }
            break;
        }
    }
}
