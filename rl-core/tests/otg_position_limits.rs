//! Position limits: random moving starts and moving targets inside random limits. Every
//! trajectory returned stays inside (exact per-segment extremes), ends in the target state and
//! is never faster than without limits (and equal to it when that one stays inside); every
//! refusal is justified independently: `CannotStopBeforePositionLimit` only when the
//! time-optimal stop of that axis alone crosses the limit, `PositionLimitsUnreachable` only
//! when the target state, run backwards to rest, comes from beyond a limit.

use rl_core::traj::otg::{self, Input, Interface, Limits, OtgError, State, Synchronization};

mod otg_support;
use otg_support::Rng;

/// Whether the time-optimal stop of one axis alone from `(p, v, a)` leaves its position limits.
fn stop_leaves(p: f64, v: f64, a: f64, l: &Limits<3>, axis: usize) -> bool {
    let one = Limits::<1> {
        max_velocity: [l.max_velocity[axis]],
        min_velocity: [l.min_velocity[axis]],
        max_acceleration: [l.max_acceleration[axis]],
        min_acceleration: [l.min_acceleration[axis]],
        max_jerk: [l.max_jerk[axis]],
        min_position: [f64::NEG_INFINITY],
        max_position: [f64::INFINITY],
    };
    let state = State {
        position: [p],
        velocity: [v],
        acceleration: [a],
    };
    let stop = otg::braking(&state, &one, Synchronization::None).expect("a stop");
    let [[min, max, ..]] = stop.position_extrema();
    min < l.min_position[axis] || max > l.max_position[axis]
}

#[test]
fn trajectories_stay_inside_and_refusals_are_justified() {
    let mut rng = Rng(0x5eed_0f0f_f5e7);
    let (mut inside, mut detoured, mut cannot_stop, mut unreachable) = (0, 0, 0, 0);
    for k in 0..4000 {
        let mut l = Limits::<3>::new(
            [
                rng.uniform(0.5, 2.0),
                rng.uniform(0.5, 2.0),
                rng.uniform(0.5, 2.0),
            ],
            [
                rng.uniform(1.0, 5.0),
                rng.uniform(1.0, 5.0),
                rng.uniform(1.0, 5.0),
            ],
            [
                rng.uniform(5.0, 50.0),
                rng.uniform(5.0, 50.0),
                rng.uniform(5.0, 50.0),
            ],
        );
        l.min_position = [-1.0, rng.uniform(-2.0, -0.5), -0.3];
        l.max_position = [1.0, rng.uniform(0.5, 2.0), 0.8];
        let current = State {
            position: std::array::from_fn(|i| rng.uniform(l.min_position[i], l.max_position[i])),
            velocity: std::array::from_fn(|i| rng.uniform(l.min_velocity[i], l.max_velocity[i])),
            acceleration: std::array::from_fn(|i| {
                0.3 * rng.uniform(l.min_acceleration[i], l.max_acceleration[i])
            }),
        };
        let moving = k % 2 == 0;
        let target = State {
            position: std::array::from_fn(|i| rng.uniform(l.min_position[i], l.max_position[i])),
            velocity: std::array::from_fn(|i| {
                if moving {
                    0.6 * rng.uniform(l.min_velocity[i], l.max_velocity[i])
                } else {
                    0.0
                }
            }),
            acceleration: [0.0; 3],
        };
        let mut input = Input::new(current, target, l);
        input.synchronization = [
            Synchronization::Time,
            Synchronization::Phase,
            Synchronization::None,
        ][k % 3];
        let mut free = input;
        free.limits.min_position = [f64::NEG_INFINITY; 3];
        free.limits.max_position = [f64::INFINITY; 3];
        let unlimited = otg::calculate(&free).expect("reachable without position limits");
        match otg::calculate(&input) {
            Ok(t) => {
                assert!(
                    t.limit_violation(&l, 1e-9, false).is_none(),
                    "{input:?}: {:?}",
                    t.limit_violation(&l, 1e-9, false)
                );
                // Each axis at the end of its own profile (without synchronisation they end
                // at different times; a moving target keeps moving after).
                for i in 0..3 {
                    let axis = t.axis(i).expect("axis");
                    let [p, v, ..] = axis.at(axis.duration());
                    assert!((p - target.position[i]).abs() < 1e-7, "{input:?}");
                    assert!((v - target.velocity[i]).abs() < 1e-7, "{input:?}");
                }
                assert!(
                    t.duration() >= unlimited.duration() * (1.0 - 1e-12),
                    "{input:?}"
                );
                if unlimited.limit_violation(&l, 1e-9, false).is_none() {
                    assert_eq!(
                        t.duration(),
                        unlimited.duration(),
                        "inside anyway: {input:?}"
                    );
                    inside += 1;
                } else {
                    detoured += 1;
                }
            }
            Err(OtgError::CannotStopBeforePositionLimit { axis }) => {
                let (p, v, a) = (
                    current.position[axis],
                    current.velocity[axis],
                    current.acceleration[axis],
                );
                assert!(
                    stop_leaves(p, v, a, &l, axis),
                    "stop stays inside: {input:?}"
                );
                cannot_stop += 1;
            }
            Err(OtgError::PositionLimitsUnreachable { axis }) => {
                // Backwards in time the target state moves with velocity −vf, acceleration af.
                let (p, v, a) = (
                    target.position[axis],
                    -target.velocity[axis],
                    target.acceleration[axis],
                );
                assert!(
                    stop_leaves(p, v, a, &l, axis),
                    "target approachable: {input:?}"
                );
                unreachable += 1;
            }
            Err(e) => panic!("{e:?} for {input:?}"),
        }
    }
    eprintln!(
        "inside {inside}, detoured {detoured}, cannot stop {cannot_stop}, target unreachable {unreachable}"
    );
    assert!(inside > 500 && detoured > 100 && cannot_stop > 50 && unreachable > 20);
}

#[test]
fn targets_and_starts_outside_are_refused() {
    let l = Limits::<2>::uniform(1.0, 2.0, 10.0).with_positions([-1.0, -1.0], [1.0, 1.0]);
    let out = Input::new(State::at_rest([0.0, 0.0]), State::at_rest([0.0, 1.5]), l);
    assert_eq!(
        otg::calculate(&out).unwrap_err(),
        OtgError::TargetOutsidePositionLimits { axis: 1 }
    );
    let out = Input::new(State::at_rest([-1.2, 0.0]), State::at_rest([0.0, 0.0]), l);
    assert_eq!(
        otg::calculate(&out).unwrap_err(),
        OtgError::CurrentOutsidePositionLimits { axis: 0 }
    );
    // The velocity interface running into a limit within the trajectory.
    let mut run = Input::new(
        State {
            position: [0.9, 0.0],
            velocity: [1.0, 0.0],
            acceleration: [0.0; 2],
        },
        State {
            position: [0.0; 2],
            velocity: [1.0, 0.0],
            acceleration: [0.0; 2],
        },
        l,
    );
    run.interface = Interface::Velocity;
    run.minimum_duration = Some(1.0);
    assert_eq!(
        otg::calculate(&run).unwrap_err(),
        OtgError::CannotStopBeforePositionLimit { axis: 0 }
    );
}
