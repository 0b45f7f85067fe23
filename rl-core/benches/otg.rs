//! Online trajectory generation (`rl_core::traj::otg`), 7 axes: the calculation from a moving
//! start to a target at rest (the speed category), and the per-cycle step along a
//! trajectory. `scripts/bench-ruckig` runs this next to Ruckig's own reported C++ calculation
//! time in one go.
//!
//! With `RL_OTG_JOBS=jobs.jsonl` (the JSONL of `rl otg`) it instead times every job of the file
//! the way Ruckig reports its `calculation_duration` (input check, calculation and the first
//! sample of a fresh update; the best of `RL_OTG_REPEAT`, default 20, calls) and prints one line
//! per job: `index nanoseconds`. With `RL_OTG_STEPS=1` it times the per-cycle step the same
//! way (best of 200 batches of 1000 cycles).

// criterion_group! generates an undocumented public function.
#![allow(missing_docs)]

use std::hint::black_box;
use std::io::BufRead;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group};
use rl_core::traj::otg::{self, Input, Limits, Otg, OtgTrajectory, State};

#[path = "../tests/otg_support/mod.rs"]
mod otg_support;

/// Validation, calculation into a kept trajectory and the first sample (what Ruckig's
/// `calculation_duration` covers).
#[inline(never)]
fn update<const N: usize>(input: &Input<N>, trajectory: &mut OtgTrajectory<N>, dt: f64) -> bool {
    if otg::calculate_into(input, trajectory).is_err() {
        return false;
    }
    black_box(trajectory.at_time(dt));
    true
}

fn time_jobs(path: &str) {
    let repeat: usize = std::env::var("RL_OTG_REPEAT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let file = std::fs::File::open(path).expect("jobs file");
    for (index, line) in std::io::BufReader::new(file).lines().enumerate() {
        let job: serde_json::Value = serde_json::from_str(&line.expect("line")).expect("json");
        assert_eq!(job["vmax"].as_array().map(Vec::len), Some(7), "7-axis jobs");
        let input = otg_support::input::<7>(&job);
        let mut best = f64::INFINITY;
        let mut trajectory = OtgTrajectory::hold([0.0; 7], [0.0; 7], [0.0; 7]);
        for _ in 0..3 {
            black_box(update(black_box(&input), &mut trajectory, 0.001));
        }
        for _ in 0..repeat {
            let start = Instant::now();
            black_box(update(black_box(&input), &mut trajectory, 0.001));
            best = best.min(start.elapsed().as_nanos() as f64);
        }
        println!("{index} {best}");
    }
}

/// A fixed set of moving-start jobs (deterministic generator, the distributions of
/// scripts/otg-vs-ruckig.d/jobs.py: positions N(0,4), velocities and accelerations N(0,0.8),
/// limits U(0.08,16)).
fn moving_start_jobs() -> Vec<Input<7>> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut gauss = move |sigma: f64| {
        let (u, v) = (uniform().max(1e-300), uniform());
        sigma * (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    };
    (0..256)
        .map(|_| {
            let current = State {
                position: std::array::from_fn(|_| gauss(4.0)),
                velocity: std::array::from_fn(|_| gauss(0.8)),
                acceleration: std::array::from_fn(|_| gauss(0.8)),
            };
            let target = State::at_rest(std::array::from_fn(|_| gauss(4.0)));
            let lim = |g: &mut dyn FnMut(f64) -> f64| {
                std::array::from_fn(|_| 0.08 + 15.92 * (0.5 + 0.5 * g(0.5).tanh()))
            };
            let limits = Limits::new(lim(&mut gauss), lim(&mut gauss), lim(&mut gauss));
            Input::new(current, target, limits)
        })
        .collect()
}

fn calculation(c: &mut Criterion) {
    let jobs = moving_start_jobs();
    let mut k = 0;
    let mut trajectory = OtgTrajectory::hold([0.0; 7], [0.0; 7], [0.0; 7]);
    c.bench_function("otg/calculate_moving_start_7", |b| {
        b.iter(|| {
            k = (k + 1) % jobs.len();
            black_box(update(black_box(&jobs[k]), &mut trajectory, 0.001));
        })
    });
}

/// The per-cycle step of a control loop: the generator with an unchanged goal (the goal check
/// and one step), and the step alone. The trajectory is restarted when it ends, so the steps
/// run through every segment.
fn step(c: &mut Criterion) {
    let jobs = moving_start_jobs();
    let cycle = Duration::from_millis(1);
    let mut generator = Otg::new(cycle, jobs[0].current);
    generator.update(&jobs[0]).expect("goal");
    c.bench_function("otg/update_unchanged_7", |b| {
        b.iter(|| {
            if generator.is_finished() {
                generator.reset(jobs[0].current);
            }
            let out = generator.update(black_box(&jobs[0])).expect("goal");
            black_box(&out);
        })
    });
    let mut generator = Otg::new(cycle, jobs[0].current);
    generator.update(&jobs[0]).expect("goal");
    c.bench_function("otg/step_7", |b| {
        b.iter(|| {
            if generator.is_finished() {
                generator.reset(jobs[0].current);
                generator.update(&jobs[0]).expect("goal");
            }
            let out = generator.step();
            black_box(&out);
        })
    });
}

criterion_group!(benches, calculation, step);

/// The per-cycle step timed as the best of 200 batches of 1000 cycles (a shared machine
/// preempts; the best batch is the step's own cost): `step_ns` and `update_unchanged_ns`.
fn time_steps() {
    let jobs = moving_start_jobs();
    let cycle = Duration::from_millis(1);
    let best = |f: &mut dyn FnMut()| {
        let mut best = f64::INFINITY;
        for _ in 0..200 {
            let start = Instant::now();
            for _ in 0..1000 {
                f();
            }
            best = best.min(start.elapsed().as_nanos() as f64 / 1000.0);
        }
        best
    };
    let mut generator = Otg::new(cycle, jobs[0].current);
    generator.update(&jobs[0]).expect("goal");
    let step = best(&mut || {
        if generator.is_finished() {
            generator.reset(jobs[0].current);
            generator.update(&jobs[0]).expect("goal");
        }
        black_box(generator.step());
    });
    let mut generator = Otg::new(cycle, jobs[0].current);
    let update = best(&mut || {
        if generator.is_finished() {
            generator.reset(jobs[0].current);
        }
        black_box(generator.update(black_box(&jobs[0])).expect("goal"));
    });
    println!("step_ns {step:.1}\nupdate_unchanged_ns {update:.1}");
}

fn main() {
    if let Ok(path) = std::env::var("RL_OTG_JOBS") {
        time_jobs(&path);
        return;
    }
    if std::env::var_os("RL_OTG_STEPS").is_some() {
        time_steps();
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
