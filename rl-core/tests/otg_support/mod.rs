//! Reading OTG jobs in the JSONL format of `rl otg` (with Ruckig's answer in a `ruckig` key, as
//! scripts/gen-otg-fixtures writes them) and running them through `rl_core::traj::otg`.

#![allow(dead_code)]

use rl_core::traj::otg::{
    self, Input, Interface, Limits, OtgError, OtgTrajectory, State, Synchronization,
};
use serde_json::Value;

/// A small deterministic generator for the tests (xorshift64), uniform in `[lo, hi)`.
pub struct Rng(pub u64);

impl Rng {
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// A number, or the strings "inf" / "-inf".
pub fn number(v: &Value) -> f64 {
    match v {
        Value::Number(n) => n.as_f64().expect("f64"),
        Value::String(s) => s.parse().expect("inf or -inf"),
        _ => panic!("not a number: {v}"),
    }
}

pub fn array<const N: usize>(v: &Value) -> [f64; N] {
    let a = v.as_array().expect("array");
    assert_eq!(a.len(), N, "length");
    core::array::from_fn(|i| number(&a[i]))
}

fn state<const N: usize>(v: &Value) -> State<N> {
    State {
        position: array(&v["p"]),
        velocity: array(&v["v"]),
        acceleration: array(&v["a"]),
    }
}

/// The input of a job with `N` axes.
pub fn input<const N: usize>(job: &Value) -> Input<N> {
    let mut limits = Limits::new(
        array(&job["vmax"]),
        array(&job["amax"]),
        array(&job["jmax"]),
    );
    if !job["vmin"].is_null() {
        limits.min_velocity = array(&job["vmin"]);
    }
    if !job["amin"].is_null() {
        limits.min_acceleration = array(&job["amin"]);
    }
    if !job["pmin"].is_null() {
        limits.min_position = array(&job["pmin"]);
    }
    if !job["pmax"].is_null() {
        limits.max_position = array(&job["pmax"]);
    }
    let mut input = Input::new(state(&job["current"]), state(&job["target"]), limits);
    input.synchronization = match job["sync"].as_str().unwrap_or("time") {
        "time" => Synchronization::Time,
        "time_if_necessary" => Synchronization::TimeIfNecessary,
        "phase" => Synchronization::Phase,
        "none" => Synchronization::None,
        other => panic!("sync {other}"),
    };
    if job["interface"].as_str() == Some("velocity") {
        input.interface = Interface::Velocity;
    }
    if let Some(d) = job["min_duration"].as_f64() {
        input.minimum_duration = Some(d);
    }
    if let Some(points) = job["waypoints"].as_array() {
        for p in points {
            input.waypoints.push(array(p)).expect("at most 8 waypoints");
        }
    }
    input
}

/// What one job gave: the duration, or the error; and the worst limit excess (relative).
pub struct Outcome {
    pub result: Result<f64, OtgError>,
    pub violation: Option<String>,
}

fn run_n<const N: usize>(job: &Value, tolerance: f64) -> Outcome {
    let input = input::<N>(job);
    match otg::calculate(&input) {
        Ok(t) => Outcome {
            result: Ok(t.duration()),
            violation: check(&input, &t, tolerance),
        },
        Err(e) => Outcome {
            result: Err(e),
            violation: None,
        },
    }
}

fn check<const N: usize>(input: &Input<N>, t: &OtgTrajectory<N>, tolerance: f64) -> Option<String> {
    let free = input.interface == Interface::Velocity;
    t.limit_violation(&input.limits, tolerance, free)
        .map(|v| format!("{v:?}"))
}

/// Runs a job of any number of axes from 1 to 8.
pub fn run(job: &Value, tolerance: f64) -> Outcome {
    match job["vmax"].as_array().expect("vmax").len() {
        1 => run_n::<1>(job, tolerance),
        2 => run_n::<2>(job, tolerance),
        3 => run_n::<3>(job, tolerance),
        4 => run_n::<4>(job, tolerance),
        5 => run_n::<5>(job, tolerance),
        6 => run_n::<6>(job, tolerance),
        7 => run_n::<7>(job, tolerance),
        8 => run_n::<8>(job, tolerance),
        n => panic!("{n} axes"),
    }
}
