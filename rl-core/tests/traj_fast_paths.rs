//! The fast evaluation paths against straightforward formulas: the jerk-limited profile (stored
//! as its first half, evaluated mirrored) against a plain forward integration of all seven
//! phases, at every phase boundary and at random times.

mod traj_support;

use rl_core::traj::{JerkLimited, Limits, Trajectory};
use traj_support::Rng;

/// Jerk of the seven phases in units of the first phase's jerk.
const PATTERN: [f64; 7] = [1.0, 0.0, -1.0, 0.0, -1.0, 0.0, 1.0];

/// The profile the textbook way (Biagiotti & Melchiorri §3.4): seven phase durations per axis,
/// stretched to the slowest axis, integrated forward phase by phase; evaluation scans the
/// phases.
struct Reference<const D: usize> {
    /// Phase durations, `[axis][phase]`.
    durations: [[f64; 7]; D],
    /// Jerk of the first phase of each axis.
    jerk: [f64; D],
    /// Position, velocity and acceleration at each phase start, `[axis][phase]`.
    state: [[[f64; 3]; 7]; D],
}

fn phase_times(h: f64, v: f64, a: f64, j: f64) -> (f64, f64, f64) {
    if h == 0.0 {
        return (0.0, 0.0, 0.0);
    }
    // Eq. 3.32 and 3.33: velocity limit reached or not.
    let (mut tj, mut ta) = if v * j >= a * a {
        (a / j, a / j + v / a)
    } else {
        ((v / j).sqrt(), 2.0 * (v / j).sqrt())
    };
    let mut tv = h / v - ta;
    if tv < 0.0 {
        // No cruise: acceleration limit reached or not.
        tv = 0.0;
        if h >= 2.0 * a * a * a / (j * j) {
            tj = a / j;
            ta = 0.5 * tj + (0.25 * tj * tj + h / a).sqrt();
        } else {
            tj = (h / (2.0 * j)).cbrt();
            ta = 2.0 * tj;
        }
    }
    (tj, ta, tv)
}

impl<const D: usize> Reference<D> {
    fn new(start: [f64; D], goal: [f64; D], l: &Limits<D>) -> Self {
        let times: [(f64, f64, f64); D] = core::array::from_fn(|i| {
            phase_times(
                (goal[i] - start[i]).abs(),
                l.velocity[i],
                l.acceleration[i],
                l.jerk[i],
            )
        });
        let duration = times
            .iter()
            .map(|(_, ta, tv)| 2.0 * ta + tv)
            .fold(0.0, f64::max);
        let mut r = Self {
            durations: [[0.0; 7]; D],
            jerk: [0.0; D],
            state: [[[0.0; 3]; 7]; D],
        };
        for i in 0..D {
            let (tj, ta, tv) = times[i];
            let own = 2.0 * ta + tv;
            let k = own / duration;
            if k == 0.0 {
                r.state[i] = [[start[i], 0.0, 0.0]; 7];
                continue;
            }
            let (tj, tc, tv) = (tj / k, (ta - 2.0 * tj).max(0.0) / k, tv / k);
            r.durations[i] = [tj, tc, tj, tv, tj, tc, tj];
            r.jerk[i] = (goal[i] - start[i]).signum() * l.jerk[i] * k * k * k;
            let (mut x, mut v, mut a) = (start[i], 0.0, 0.0);
            for (p, sign) in PATTERN.iter().enumerate() {
                r.state[i][p] = [x, v, a];
                let (d, j) = (r.durations[i][p], sign * r.jerk[i]);
                x += v * d + a * d * d / 2.0 + j * d * d * d / 6.0;
                v += a * d + j * d * d / 2.0;
                a += j * d;
            }
        }
        r
    }

    /// Position, velocity and acceleration at `t` (continuous, so the phase chosen at a
    /// boundary does not matter).
    fn at(&self, t: f64) -> [[f64; 3]; D] {
        core::array::from_fn(|i| {
            let mut p = 0;
            let mut begin = 0.0;
            while p < 6 && t >= begin + self.durations[i][p] {
                begin += self.durations[i][p];
                p += 1;
            }
            let tau = t - begin;
            let [x, v, a] = self.state[i][p];
            let j = PATTERN[p] * self.jerk[i];
            [
                x + v * tau + a * tau * tau / 2.0 + j * tau * tau * tau / 6.0,
                v + a * tau + j * tau * tau / 2.0,
                a + j * tau,
            ]
        })
    }
}

/// Compares the profile with the reference at `t` to 1e-12 of each quantity's scale, and the
/// jerk by the convention that at a boundary the phase starting there counts.
#[track_caller]
fn compare<const D: usize>(p: &JerkLimited<D>, r: &Reference<D>, scale: &[[f64; D]; 3], t: f64) {
    let s = p.sample(t);
    let expected = r.at(t);
    for q in 0..3 {
        let got = [s.position, s.velocity, s.acceleration][q];
        for i in 0..D {
            let want = expected[i][q];
            assert!(
                (got[i] - want).abs() <= 1e-12 * (1.0 + scale[q][i]),
                "order {q} axis {i} at t={t}: {} vs {want}",
                got[i]
            );
        }
    }
    for i in 0..D {
        // Phase by the profile's own boundaries: the number of phase ends at or before t.
        let ends = p.phase_ends(i).unwrap();
        let phase = ends[..6].iter().filter(|&&e| e <= t).count();
        let want = PATTERN[phase] * r.jerk[i];
        assert!(
            (s.jerk[i] - want).abs() <= 1e-12 * (1.0 + want.abs()),
            "jerk axis {i} at t={t} (phase {phase}): {} vs {want}",
            s.jerk[i]
        );
    }
    // `derivative` agrees with `sample`.
    for (order, got) in [s.position, s.velocity, s.acceleration, s.jerk]
        .into_iter()
        .enumerate()
    {
        assert_eq!(p.derivative(t, order), got, "order {order} at t={t}");
    }
}

fn check<const D: usize>(start: [f64; D], goal: [f64; D], l: &Limits<D>, rng: &mut Rng) {
    let p = JerkLimited::new(start, goal, l).unwrap();
    let r = Reference::new(start, goal, l);
    let t_end = p.duration();
    // The size of each quantity plus what a time error of 1e-12 · T changes it by (the two
    // sum phase times in different orders).
    let scale = [
        core::array::from_fn(|i| start[i].abs().max(goal[i].abs()) + l.velocity[i] * t_end),
        core::array::from_fn(|i| l.velocity[i] + l.acceleration[i] * t_end),
        core::array::from_fn(|i| l.acceleration[i] + l.jerk[i] * t_end),
    ];
    let mut times = vec![0.0, t_end, 0.5 * t_end];
    for i in 0..D {
        let ends = p.phase_ends(i).unwrap();
        times.extend(ends);
        // Just before and after each boundary too.
        times.extend(ends.iter().map(|e| e * (1.0 - 1e-15)));
        times.extend(ends.iter().map(|e| e * (1.0 + 1e-15)));
    }
    times.extend((0..200).map(|_| rng.range(0.0, t_end)));
    for t in times {
        compare(&p, &r, &scale, t);
    }
}

#[test]
fn jerk_limited_matches_forward_integration_of_seven_phases() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    // Every case of the phase times: cruise or not, acceleration limit reached or not, short
    // moves; axes that stay put; negative moves.
    let l = Limits::uniform(5.0, 10.0, 30.0);
    check([0.0], [10.0], &l, &mut rng);
    check([1.0], [0.998], &l, &mut rng);
    check([0.0], [-3.0], &l, &mut rng);
    check(
        [0.5, 0.5],
        [0.5, -1.0],
        &Limits::uniform(5.0, 10.0, 30.0),
        &mut rng,
    );
    let l7 = Limits::<7>::uniform(1.0, 2.0, 10.0);
    check(
        [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
        [0.5, -0.1, 0.0, 0.8, 0.1, 0.0, -0.6],
        &l7,
        &mut rng,
    );
    for _ in 0..300 {
        let l = Limits {
            velocity: core::array::from_fn(|_| rng.range(0.05, 5.0)),
            acceleration: core::array::from_fn(|_| rng.range(0.05, 20.0)),
            jerk: core::array::from_fn(|_| rng.range(0.05, 500.0)),
        };
        let a: [f64; 7] = core::array::from_fn(|_| rng.range(-3.0, 3.0));
        let mut b: [f64; 7] = core::array::from_fn(|_| rng.range(-3.0, 3.0));
        if rng.next_f64() < 0.3 {
            b[3] = a[3];
        }
        check(a, b, &l, &mut rng);
    }
}
