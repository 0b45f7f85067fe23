//! The fast paths against straightforward formulas: the jerk-limited profile (stored as its
//! first half, evaluated mirrored) against a plain forward integration of all seven phases, and
//! the cubic splines (Thomas algorithm) against the textbook linear system solved densely, at
//! every boundary and at random times.

mod traj_support;

#[path = "support/waypoints.rs"]
mod waypoints;
use rl_core::traj::{JerkLimited, Limits, Piecewise, Polynomial, Trajectory, spline};
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

/// Coefficients `[segment][a, b, c, d]` of `a + b τ + c τ² + d τ³` (local time `τ`) of the cubic
/// spline of one axis, from the 4(n-1) interpolation, continuity and end conditions solved by
/// dense Gaussian elimination. `ends` = `None` for natural, `Some((v0, v1))` for clamped.
fn textbook_spline(times: &[f64], y: &[f64], ends: Option<(f64, f64)>) -> Vec<[f64; 4]> {
    let segments = times.len() - 1;
    let n = 4 * segments;
    let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
    let row = |entries: &[(usize, f64)], rhs: f64| {
        let mut r = vec![0.0; n];
        for &(col, value) in entries {
            r[col] = value;
        }
        (r, rhs)
    };
    for i in 0..segments {
        let (h, k) = (times[i + 1] - times[i], 4 * i);
        rows.push(row(&[(k, 1.0)], y[i]));
        rows.push(row(
            &[(k, 1.0), (k + 1, h), (k + 2, h * h), (k + 3, h * h * h)],
            y[i + 1],
        ));
        if i + 1 < segments {
            // First and second derivative continuous at the next waypoint.
            rows.push(row(
                &[
                    (k + 1, 1.0),
                    (k + 2, 2.0 * h),
                    (k + 3, 3.0 * h * h),
                    (k + 5, -1.0),
                ],
                0.0,
            ));
            rows.push(row(&[(k + 2, 2.0), (k + 3, 6.0 * h), (k + 6, -2.0)], 0.0));
        }
    }
    let (h_last, k_last) = (times[segments] - times[segments - 1], 4 * (segments - 1));
    match ends {
        None => {
            rows.push(row(&[(2, 2.0)], 0.0));
            rows.push(row(&[(k_last + 2, 2.0), (k_last + 3, 6.0 * h_last)], 0.0));
        }
        Some((v0, v1)) => {
            rows.push(row(&[(1, 1.0)], v0));
            rows.push(row(
                &[
                    (k_last + 1, 1.0),
                    (k_last + 2, 2.0 * h_last),
                    (k_last + 3, 3.0 * h_last * h_last),
                ],
                v1,
            ));
        }
    }
    // Gaussian elimination with partial pivoting.
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&a, &b| rows[a].0[col].abs().total_cmp(&rows[b].0[col].abs()))
            .unwrap();
        rows.swap(col, pivot);
        for r in col + 1..n {
            let f = rows[r].0[col] / rows[col].0[col];
            if f != 0.0 {
                for c in col..n {
                    rows[r].0[c] -= f * rows[col].0[c];
                }
                rows[r].1 -= f * rows[col].1;
            }
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|c| rows[r].0[c] * x[c]).sum();
        x[r] = (rows[r].1 - s) / rows[r].0[r];
    }
    x.chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect()
}

fn check_spline<const D: usize>(
    s: &Piecewise<Polynomial<D, 4>, 8>,
    times: &[f64],
    points: &[[f64; D]],
    ends: Option<([f64; D], [f64; D])>,
    rng: &mut Rng,
) {
    let reference: Vec<Vec<[f64; 4]>> = (0..D)
        .map(|axis| {
            let y: Vec<f64> = points.iter().map(|p| p[axis]).collect();
            textbook_spline(times, &y, ends.map(|(v0, v1)| (v0[axis], v1[axis])))
        })
        .collect();
    let t0 = times[0];
    let mut at: Vec<f64> = times.to_vec();
    at.extend(times.iter().map(|t| t * (1.0 - 1e-15) + 1e-300));
    at.extend(times.iter().map(|t| t * (1.0 + 1e-15)));
    at.extend((0..100).map(|_| rng.range(t0, times[times.len() - 1])));
    // The scale of each quantity: its largest magnitude at the waypoints and in between.
    let eval = |t: f64| -> [[f64; D]; 4] {
        let i = (times.partition_point(|&k| k <= t).max(1) - 1).min(times.len() - 2);
        let tau = t - times[i];
        core::array::from_fn(|q| {
            core::array::from_fn(|axis| {
                let [a, b, c, d] = reference[axis][i];
                [
                    a + tau * (b + tau * (c + tau * d)),
                    b + tau * (2.0 * c + 3.0 * tau * d),
                    2.0 * c + 6.0 * tau * d,
                    6.0 * d,
                ][q]
            })
        })
    };
    let mut scale = [0.0f64; 4];
    for &t in &at {
        let r = eval(t);
        for q in 0..4 {
            scale[q] = r[q].iter().fold(scale[q], |m, x| m.max(x.abs()));
        }
    }
    for &t in &at {
        // Away from the waypoints the jerk is that of the segment; at a waypoint it may be
        // either neighbour's (jerk jumps there), so it is compared only inside segments.
        let inside = times.iter().all(|k| (t - k).abs() > 1e-9);
        let got = s.sample(t - t0);
        let want = eval(t);
        for (q, got) in [got.position, got.velocity, got.acceleration, got.jerk]
            .into_iter()
            .enumerate()
        {
            if q == 3 && !inside {
                continue;
            }
            for axis in 0..D {
                assert!(
                    (got[axis] - want[q][axis]).abs() <= 1e-10 * (1.0 + scale[q]),
                    "order {q} axis {axis} at t={t}: {} vs {}",
                    got[axis],
                    want[q][axis]
                );
            }
        }
    }
}

#[test]
fn cubic_splines_match_the_textbook_system() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let (times, points) = (waypoints::TIMES, waypoints::POINTS);
    for n in 2..=6 {
        let natural: Piecewise<Polynomial<7, 4>, 8> =
            spline::natural_cubic(&times[..n], &points[..n]).unwrap();
        check_spline(&natural, &times[..n], &points[..n], None, &mut rng);
        let (v0, v1) = ([0.3; 7], [-0.2; 7]);
        let clamped: Piecewise<Polynomial<7, 4>, 8> =
            spline::clamped_cubic(&times[..n], &points[..n], v0, v1).unwrap();
        check_spline(
            &clamped,
            &times[..n],
            &points[..n],
            Some((v0, v1)),
            &mut rng,
        );
    }
    for _ in 0..100 {
        let n = 2 + (rng.next_f64() * 7.0) as usize;
        let mut times = vec![rng.range(-1.0, 1.0)];
        for _ in 1..n {
            times.push(times[times.len() - 1] + rng.range(0.2, 2.0));
        }
        let points: Vec<[f64; 3]> = (0..n)
            .map(|_| core::array::from_fn(|_| rng.range(-2.0, 2.0)))
            .collect();
        let natural: Piecewise<Polynomial<3, 4>, 8> =
            spline::natural_cubic(&times, &points).unwrap();
        check_spline(&natural, &times, &points, None, &mut rng);
        let v0 = core::array::from_fn(|_| rng.range(-1.0, 1.0));
        let v1 = core::array::from_fn(|_| rng.range(-1.0, 1.0));
        let clamped: Piecewise<Polynomial<3, 4>, 8> =
            spline::clamped_cubic(&times, &points, v0, v1).unwrap();
        check_spline(&clamped, &times, &points, Some((v0, v1)), &mut rng);
    }
}
