//! `rl otg JOBS.jsonl [--samples DT] [--verify]`: online trajectory generation for scripts and
//! checks (rl-core's `traj::otg`), one job per input line, one JSON line out per job.
//!
//! A job: `{"current": {"p": [..], "v": [..], "a": [..]}, "target": {same}, "vmax": [..],
//! "amax": [..], "jmax": [..]}` with one entry per axis (1 to 12 axes), plus optionally `vmin`,
//! `amin` (default: the negated maxima), `pmin`, `pmax` (position limits), `sync` (`time`,
//! `time_if_necessary`, `phase`, `none`), `interface` (`position`, `velocity`), `waypoints`
//! (a list of positions to pass through, at most 8) and `min_duration` (seconds). Numbers may
//! be the strings `"inf"` and `"-inf"` (an unlimited derivative). Keys `ruckig` and `meta` are
//! ignored (the fixtures carry Ruckig's answer there); any other key is an error.
//!
//! Output per job: `{"result": "ok", "duration_s": s, "min_durations_s": [..]}` (with waypoints
//! `"sections_s": [..]`, the duration of each section, instead of `min_durations_s`), or
//! `{"result": "error", "error": KIND, "axis": i, "message": text}` for an input the generator
//! refuses (a typed error: what and which axis), or `{"result": "invalid", "message": text}`
//! for a line that is not a job. With `--samples DT`: `"samples": {"t": [..], "p": [[per axis],
//! ..], "v": .., "a": .., "j": ..}` at 0, DT, 2·DT, .. and the duration itself. With
//! `--verify`: `"violation": null` or the worst excess over a limit found by the exact
//! per-segment check (rl-core's `OtgTrajectory::limit_violation`, tolerance 1e-9 relative to
//! the limit or absolute below 1).
//!
//! Exit status 0 when every line was a job (refused or not), 1 when some line was invalid.

use std::fs::File;
use std::io::{self, BufRead, BufReader, BufWriter, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::Args;
use rl_core::traj::Sample;
use rl_core::traj::otg::{self, Input, Interface, Limits, OtgError, State, Synchronization};
use serde_json::{Map, Value, json};

use super::output::write_error;
use super::{CliError, CliResult};

/// Most axes a job may have.
pub const MAX_AXES: usize = 12;
/// Most samples per job (guards against a tiny `--samples`).
const MAX_SAMPLES: f64 = 1e6;
/// Limit tolerance of `--verify` (relative above 1).
const VERIFY_TOLERANCE: f64 = 1e-9;

/// Arguments of `rl otg`.
#[derive(Args, Debug)]
pub struct OtgArgs {
    /// Jobs, one JSON object per line (`-` for standard input).
    pub jobs: PathBuf,
    /// Add samples every DT seconds from 0 to the duration (inclusive).
    #[arg(long, value_name = "DT")]
    pub samples: Option<f64>,
    /// Add the worst limit excess of the trajectory (exact, per segment).
    #[arg(long)]
    pub verify: bool,
}

/// Runs `rl otg`.
pub fn run(args: OtgArgs) -> CliResult {
    if let Some(dt) = args.samples
        && !(dt > 0.0 && dt.is_finite())
    {
        return Err(CliError::usage(format!(
            "--samples {dt}: the sample period must be positive"
        )));
    }
    let reader: Box<dyn BufRead> = if args.jobs.as_os_str() == "-" {
        Box::new(BufReader::new(io::stdin().lock()))
    } else {
        let file = File::open(&args.jobs)
            .map_err(|e| CliError::usage(format!("{}: {e}", args.jobs.display())))?;
        Box::new(BufReader::new(file))
    };
    let mut out = BufWriter::new(io::stdout().lock());
    let mut invalid = 0usize;
    for (number, line) in reader.lines().enumerate() {
        let line = line.map_err(|e| {
            CliError::failed(format!("{}: line {}: {e}", args.jobs.display(), number + 1))
        })?;
        if line.trim().is_empty() {
            continue;
        }
        let answer = match serde_json::from_str::<Value>(&line)
            .map_err(|e| e.to_string())
            .and_then(|job| answer(&job, args.samples, args.verify))
        {
            Ok(answer) => answer,
            Err(message) => {
                invalid += 1;
                json!({"result": "invalid", "message": format!("line {}: {message}", number + 1)})
            }
        };
        let answer = rl::json::versioned("otg", 1, answer);
        serde_json::to_writer(&mut out, &answer)
            .map_err(|e| write_error("standard output", e.into()))?;
        out.write_all(b"\n")
            .map_err(|e| write_error("standard output", e))?;
    }
    out.flush().map_err(|e| write_error("standard output", e))?;
    Ok(if invalid == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The answer to one job, or why the line is not a job.
fn answer(job: &Value, samples: Option<f64>, verify: bool) -> Result<Value, String> {
    let object = job.as_object().ok_or("a job is a JSON object")?;
    for key in object.keys() {
        if !KEYS.contains(&key.as_str()) {
            return Err(format!("unknown key `{key}` (known: {})", KEYS.join(", ")));
        }
    }
    let n = job["vmax"]
        .as_array()
        .ok_or("`vmax` must be a list with one entry per axis")?
        .len();
    macro_rules! axes {
        ($($n:literal)*) => {
            match n {
                $($n => solve::<$n>(job, samples, verify),)*
                _ => Err(format!("{n} axes: 1 to {MAX_AXES} are supported")),
            }
        };
    }
    axes!(1 2 3 4 5 6 7 8 9 10 11 12)
}

/// The keys of a job.
const KEYS: [&str; 15] = [
    "current",
    "target",
    "vmax",
    "vmin",
    "amax",
    "amin",
    "jmax",
    "pmin",
    "pmax",
    "sync",
    "interface",
    "waypoints",
    "min_duration",
    "ruckig",
    "meta",
];

fn solve<const N: usize>(job: &Value, samples: Option<f64>, verify: bool) -> Result<Value, String> {
    let input = input::<N>(job)?;
    let mut answer = Map::new();
    answer.insert("result".into(), "ok".into());
    let (duration, violation, sampled) = if input.waypoints.is_empty() {
        let trajectory = match otg::calculate(&input) {
            Ok(t) => t,
            Err(e) => return Ok(error_answer(&e)),
        };
        answer.insert(
            "min_durations_s".into(),
            trajectory.min_durations().to_vec().into(),
        );
        let free = input.interface == Interface::Velocity;
        let violation = verify
            .then(|| trajectory.limit_violation(&input.limits, VERIFY_TOLERANCE, free))
            .flatten();
        let sampled = samples
            .map(|dt| sample(trajectory.duration(), dt, |t| trajectory.at_time(t)))
            .transpose()?;
        (trajectory.duration(), violation, sampled)
    } else {
        let trajectory = match otg::calculate_waypoints(&input) {
            Ok(t) => t,
            Err(e) => return Ok(error_answer(&e)),
        };
        let sections: Vec<f64> = trajectory.sections().iter().map(|s| s.duration()).collect();
        answer.insert("sections_s".into(), sections.into());
        let violation = verify
            .then(|| trajectory.limit_violation(&input.limits, VERIFY_TOLERANCE))
            .flatten();
        let sampled = samples
            .map(|dt| sample(trajectory.duration(), dt, |t| trajectory.at_time(t)))
            .transpose()?;
        (trajectory.duration(), violation, sampled)
    };
    answer.insert("duration_s".into(), duration.into());
    if verify {
        let violation = violation.map(|v| {
            json!({"axis": v.axis, "derivative": format!("{:?}", v.derivative).to_lowercase(),
                   "time_s": v.time, "value": v.value, "limit": v.limit})
        });
        answer.insert("violation".into(), violation.unwrap_or(Value::Null));
    }
    if let Some(samples) = sampled {
        answer.insert("samples".into(), samples);
    }
    Ok(Value::Object(answer))
}

/// `{"result": "error", ...}` for a refused input.
fn error_answer(e: &OtgError) -> Value {
    let kind = format!("{e:?}");
    let kind = kind
        .split(|c: char| !c.is_alphanumeric())
        .next()
        .unwrap_or("Error");
    let axis = match *e {
        OtgError::NotFinite { axis, .. }
        | OtgError::BadLimit { axis, .. }
        | OtgError::TargetOutsideLimits { axis, .. }
        | OtgError::ZeroLimits { axis }
        | OtgError::NoProfile { axis }
        | OtgError::NoSynchronization { axis, .. }
        | OtgError::CurrentOutsidePositionLimits { axis }
        | OtgError::TargetOutsidePositionLimits { axis }
        | OtgError::CannotStopBeforePositionLimit { axis }
        | OtgError::PositionLimitsUnreachable { axis } => Value::from(axis),
        _ => Value::Null,
    };
    json!({"result": "error", "error": kind, "axis": axis, "message": e.to_string()})
}

/// Samples at `0, dt, 2·dt, ...` and at the duration.
fn sample<const N: usize>(
    duration: f64,
    dt: f64,
    at: impl Fn(f64) -> Sample<N>,
) -> Result<Value, String> {
    let count = (duration / dt).floor();
    if count > MAX_SAMPLES {
        return Err(format!(
            "--samples {dt} gives {count} samples over {duration} s (at most {MAX_SAMPLES})"
        ));
    }
    let mut times: Vec<f64> = (0..=count as usize).map(|k| k as f64 * dt).collect();
    if times.last().is_none_or(|&t| t < duration) {
        times.push(duration);
    }
    let (mut p, mut v, mut a, mut j) = (vec![], vec![], vec![], vec![]);
    for &t in &times {
        let s = at(t);
        p.push(s.position.to_vec());
        v.push(s.velocity.to_vec());
        a.push(s.acceleration.to_vec());
        j.push(s.jerk.to_vec());
    }
    Ok(json!({"t": times, "p": p, "v": v, "a": a, "j": j}))
}

/// A number, or `"inf"` / `"-inf"`.
fn number(v: &Value, what: &str) -> Result<f64, String> {
    match v {
        Value::Number(n) => n.as_f64().ok_or_else(|| format!("{what}: not a number")),
        Value::String(s) => match s.as_str() {
            "inf" | "Infinity" => Ok(f64::INFINITY),
            "-inf" | "-Infinity" => Ok(f64::NEG_INFINITY),
            _ => Err(format!(
                "{what}: `{s}` is not a number (use \"inf\" or \"-inf\")"
            )),
        },
        _ => Err(format!("{what}: expected a number, got {v}")),
    }
}

/// A list of `N` numbers.
fn list<const N: usize>(v: &Value, what: &str) -> Result<[f64; N], String> {
    let items = v
        .as_array()
        .ok_or_else(|| format!("`{what}` must be a list of {N} numbers"))?;
    if items.len() != N {
        return Err(format!(
            "`{what}` has {} entries, the job has {N} axes",
            items.len()
        ));
    }
    let mut out = [0.0; N];
    for (i, item) in items.iter().enumerate() {
        out[i] = number(item, &format!("{what}[{i}]"))?;
    }
    Ok(out)
}

fn state<const N: usize>(v: &Value, what: &str) -> Result<State<N>, String> {
    if !v.is_object() {
        return Err(format!("`{what}` must be an object with p, v and a"));
    }
    let field = |key: &str| -> Result<[f64; N], String> {
        match &v[key] {
            Value::Null => Ok([0.0; N]),
            x => list(x, &format!("{what}.{key}")),
        }
    };
    Ok(State {
        position: field("p")?,
        velocity: field("v")?,
        acceleration: field("a")?,
    })
}

/// The generator's input of a job with `N` axes.
fn input<const N: usize>(job: &Value) -> Result<Input<N>, String> {
    let optional = |key: &str| -> Result<Option<[f64; N]>, String> {
        match &job[key] {
            Value::Null => Ok(None),
            v => list(v, key).map(Some),
        }
    };
    let mut limits = Limits::new(
        list(&job["vmax"], "vmax")?,
        list(&job["amax"], "amax")?,
        list(&job["jmax"], "jmax")?,
    );
    if let Some(v) = optional("vmin")? {
        limits.min_velocity = v;
    }
    if let Some(a) = optional("amin")? {
        limits.min_acceleration = a;
    }
    if let Some(p) = optional("pmin")? {
        limits.min_position = p;
    }
    if let Some(p) = optional("pmax")? {
        limits.max_position = p;
    }
    let mut input = Input::new(
        state(&job["current"], "current")?,
        state(&job["target"], "target")?,
        limits,
    );
    input.synchronization = match &job["sync"] {
        Value::Null => Synchronization::Time,
        Value::String(s) => match s.as_str() {
            "time" => Synchronization::Time,
            "time_if_necessary" => Synchronization::TimeIfNecessary,
            "phase" => Synchronization::Phase,
            "none" => Synchronization::None,
            other => {
                return Err(format!(
                    "sync `{other}`: use time, time_if_necessary, phase or none"
                ));
            }
        },
        other => return Err(format!("sync: expected a string, got {other}")),
    };
    input.interface = match &job["interface"] {
        Value::Null => Interface::Position,
        Value::String(s) if s == "position" => Interface::Position,
        Value::String(s) if s == "velocity" => Interface::Velocity,
        other => return Err(format!("interface {other}: use position or velocity")),
    };
    if !job["min_duration"].is_null() {
        input.minimum_duration = Some(number(&job["min_duration"], "min_duration")?);
    }
    if !job["waypoints"].is_null() {
        let points = job["waypoints"]
            .as_array()
            .ok_or("`waypoints` must be a list of positions")?;
        for (i, point) in points.iter().enumerate() {
            let p = list(point, &format!("waypoints[{i}]"))?;
            input.waypoints.push(p).map_err(|_| {
                format!(
                    "{} waypoints: at most {} are supported",
                    points.len(),
                    otg::MAX_WAYPOINTS
                )
            })?;
        }
    }
    Ok(input)
}
