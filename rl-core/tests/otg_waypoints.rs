//! Trajectories through waypoints (`otg::calculate_waypoints`): they pass every waypoint at the
//! time the sections say, keep every limit, reach the target, and are faster than stopping at
//! every waypoint whenever some axis keeps its direction through one (never slower: stopping
//! everywhere is one of the candidates).

use rl_core::traj::otg::{self, Input, Interface, Limits, OtgError, State, Waypoints};

mod otg_support;
use otg_support::Rng;

/// The duration when every waypoint is passed at rest (a chain of rest-to-rest moves).
fn stopping_everywhere<const N: usize>(input: &Input<N>) -> f64 {
    let mut points = vec![input.current.position];
    points.extend_from_slice(input.waypoints.as_slice());
    points.push(input.target.position);
    points
        .windows(2)
        .map(|w| {
            let mut i = *input;
            i.waypoints.clear();
            i.current = State::at_rest(w[0]);
            i.target = State::at_rest(w[1]);
            otg::calculate(&i).expect("rest to rest").duration()
        })
        .sum()
}

fn check<const N: usize>(rng: &mut Rng, count: usize) -> (f64, f64) {
    let mut limits = Limits::<N>::new(
        std::array::from_fn(|_| rng.uniform(0.5, 2.0)),
        std::array::from_fn(|_| rng.uniform(1.0, 6.0)),
        std::array::from_fn(|_| rng.uniform(5.0, 60.0)),
    );
    limits.min_velocity[0] = -0.7 * limits.max_velocity[0];
    let mut waypoints = Waypoints::new();
    // A path that mostly goes one way with some turns (as planned paths do).
    let mut p: [f64; N] = std::array::from_fn(|_| rng.uniform(-1.0, 1.0));
    let start = p;
    for _ in 0..count {
        for x in p.iter_mut() {
            *x += rng.uniform(-0.3, 0.8);
        }
        waypoints.push(p).expect("room for 8");
    }
    let target: [f64; N] = std::array::from_fn(|i| p[i] + rng.uniform(0.0, 0.8));
    let mut input = Input::new(State::at_rest(start), State::at_rest(target), limits);
    input.waypoints = waypoints;
    let t = otg::calculate_waypoints(&input).expect("through waypoints");
    assert!(
        t.limit_violation(&limits, 1e-9).is_none(),
        "{:?}",
        t.limit_violation(&limits, 1e-9)
    );
    // Passes each waypoint at the start of the next section, in the state it reports.
    for (k, (pass, start)) in t.passes().iter().zip(&t.section_starts()[1..]).enumerate() {
        let s = t.at_time(*start);
        for i in 0..N {
            assert!(
                (s.position[i] - input.waypoints.as_slice()[k][i]).abs() < 1e-8,
                "waypoint {k} axis {i}"
            );
            assert!((s.velocity[i] - pass.velocity[i]).abs() < 1e-8);
        }
    }
    // Continuous through the section borders (sampled on both sides of each border).
    for &b in &t.section_starts()[1..] {
        let (before, after) = (t.at_time(b - 1e-9), t.at_time(b + 1e-9));
        for i in 0..N {
            assert!((before.velocity[i] - after.velocity[i]).abs() < 1e-6);
            assert!((before.acceleration[i] - after.acceleration[i]).abs() < 1e-6);
        }
    }
    let end = t.at_time(t.duration());
    for ((p, v), goal) in end.position.iter().zip(&end.velocity).zip(&target) {
        assert!((p - goal).abs() < 1e-8 && v.abs() < 1e-8);
    }
    let stops = stopping_everywhere(&input);
    assert!(
        t.duration() <= stops * (1.0 + 1e-12),
        "{} vs {stops}",
        t.duration()
    );
    (t.duration(), stops)
}

#[test]
fn through_waypoints_within_limits_and_faster_than_stopping() {
    let mut rng = Rng(0x0123_4567_89ab_cdef);
    let (mut faster, mut total_ratio, mut n) = (0, 0.0, 0);
    for k in 0..60 {
        let count = 1 + k % 8;
        let (d, stops) = match k % 3 {
            0 => check::<3>(&mut rng, count),
            1 => check::<6>(&mut rng, count),
            _ => check::<7>(&mut rng, count),
        };
        if d < stops * 0.99 {
            faster += 1;
        }
        total_ratio += d / stops;
        n += 1;
    }
    eprintln!(
        "faster than stopping at every waypoint in {faster} of {n}; mean ratio {:.3}",
        total_ratio / n as f64
    );
    assert!(faster >= 50, "{faster} of {n}");
}

#[test]
fn waypoints_are_refused_where_they_do_not_apply() {
    let l = Limits::<2>::uniform(1.0, 2.0, 10.0).with_positions([-1.0; 2], [1.0; 2]);
    let mut input = Input::new(State::at_rest([0.0; 2]), State::at_rest([0.5; 2]), l);
    input.waypoints.push([0.2, 1.5]).expect("room");
    assert_eq!(
        otg::calculate_waypoints(&input).unwrap_err(),
        OtgError::TargetOutsidePositionLimits { axis: 1 }
    );
    input.waypoints.clear();
    input.waypoints.push([0.2, 0.3]).expect("room");
    assert_eq!(
        otg::calculate(&input).unwrap_err(),
        OtgError::WaypointsUnsupported
    );
    input.minimum_duration = Some(3.0);
    assert_eq!(
        otg::calculate_waypoints(&input).unwrap_err(),
        OtgError::WaypointsUnsupported
    );
    input.minimum_duration = None;
    input.interface = Interface::Velocity;
    assert_eq!(
        otg::calculate_waypoints(&input).unwrap_err(),
        OtgError::WaypointsUnsupported
    );
    let mut full = Waypoints::<2>::new();
    for _ in 0..otg::MAX_WAYPOINTS {
        full.push([0.0; 2]).expect("room");
    }
    assert_eq!(full.push([1.0, 1.0]), Err([1.0, 1.0]));
}
