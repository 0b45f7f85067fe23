//! `rl traj`: sample a trajectory through waypoints read from a CSV file, write position,
//! velocity, acceleration and jerk of every axis as CSV, and optionally plot them as SVG.
//!
//! Input: a header row, then one row per waypoint with a column per axis; a first column named
//! `t` gives the waypoints' times. Output header: `t,p0,v0,a0,j0,p1,...`, one row per sample
//! from the start to the exact end time, written as it is computed (a long trajectory takes
//! no memory). Output files are created before any work, so a bad path fails at once.
//!
//! Limits (`--vmax`, `--amax`, `--jmax`) are honoured by every profile that can: quintic and
//! jerk-limited are time-optimal under them; the splines (cubic-natural, cubic-clamped,
//! parabolic-blend) and quintic with a `t` column follow the given times and are slowed down
//! uniformly in time where a limit would be exceeded (a stretch by `k` divides velocities by
//! `k`, accelerations by `k²`, jerks by `k³`, and keeps the path); without a `t` column they
//! are timed by the limits (spaced by distance, then scaled until the tightest limit is
//! reached). `--jmax` with parabolic-blend is refused (its acceleration jumps: the jerk is
//! unbounded), and a `t` column with jerk-limited is refused (it plans its own timing).

use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, ValueEnum};
use plotters::prelude::*;
use rl_core::traj::{
    BlendShape, BlendTime, JerkLimited, Limits, Piecewise, Polynomial, Trajectory, TrajectoryError,
    spline,
};

use super::output::{Replacement, errln, write_error};
use super::{CliError, CliResult, parse_seconds, refuse_given};

/// Most axes a waypoint file may have.
pub const MAX_AXES: usize = 12;
/// Most waypoints a file may have.
pub const MAX_WAYPOINTS: usize = 128;
/// Most samples written (guards against a tiny `--dt`).
const MAX_SAMPLES: f64 = 1e7;
/// Most points per curve in the plot (samples are thinned evenly, the last one kept).
const PLOT_POINTS: usize = 2000;

/// Segment capacities for the largest file.
const SEGMENTS: usize = MAX_WAYPOINTS - 1;
const BLEND_SEGMENTS: usize = 2 * MAX_WAYPOINTS - 1;

/// Trajectory profile of `rl traj`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Profile {
    /// Quintic polynomials from rest to rest through every waypoint: time-optimal under
    /// --vmax/--amax/--jmax (any of them), or at the `t` column's times (slowed down where a
    /// limit would be exceeded).
    Quintic,
    /// Natural cubic spline through the waypoints, at the `t` column's times or timed by the
    /// limits.
    CubicNatural,
    /// Cubic spline starting and ending at rest, at the `t` column's times or timed by the
    /// limits.
    CubicClamped,
    /// Straight lines with parabolic blends (--blend of the neighbouring segments), at rest at
    /// both ends, at the `t` column's times or timed by --vmax/--amax (no --jmax: the
    /// acceleration jumps).
    ParabolicBlend,
    /// 7-segment jerk-limited moves from rest to rest through every waypoint, time-optimal
    /// under --vmax, --amax and --jmax (all required); no `t` column.
    JerkLimited,
}

impl Profile {
    /// The name on the command line.
    fn name(self) -> &'static str {
        match self {
            Self::Quintic => "quintic",
            Self::CubicNatural => "cubic-natural",
            Self::CubicClamped => "cubic-clamped",
            Self::ParabolicBlend => "parabolic-blend",
            Self::JerkLimited => "jerk-limited",
        }
    }
}

/// Arguments of `rl traj`.
#[derive(Args, Debug)]
pub struct TrajArgs {
    /// Waypoints: header row, then one row per waypoint (optional first column `t`, seconds).
    pub file: PathBuf,
    /// How to move through the waypoints.
    #[arg(long, value_enum)]
    pub profile: Profile,
    /// Velocity limit (unit/s): one value for all axes or a comma-separated value per axis.
    #[arg(long, allow_hyphen_values = true)]
    pub vmax: Option<String>,
    /// Acceleration limit (unit/s²): one value or one per axis.
    #[arg(long, allow_hyphen_values = true)]
    pub amax: Option<String>,
    /// Jerk limit (unit/s³): one value or one per axis.
    #[arg(long, allow_hyphen_values = true)]
    pub jmax: Option<String>,
    /// Sample period: a duration (e.g. 1ms, 0.5s) or a bare number of seconds, as `rl plan
    /// --dt` takes it.
    #[arg(long, value_name = "DURATION", default_value = "1ms", value_parser = parse_seconds)]
    pub dt: f64,
    /// Blend length for parabolic-blend, as a fraction (0, 1] of the neighbouring segments.
    #[arg(long, default_value_t = 0.2)]
    pub blend: f64,
    /// Write the samples here (default: standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Also draw position, velocity, acceleration and jerk over time as an SVG file.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// The unit of the waypoints' columns, for the plot's axis labels (e.g. rad, m, deg).
    #[arg(long, default_value = "rad")]
    pub unit: String,
}

/// Waypoints read from the CSV file.
#[derive(Debug)]
struct Waypoints {
    times: Option<Vec<f64>>,
    names: Vec<String>,
    points: Vec<Vec<f64>>,
}

/// What sampling produced besides the CSV: the waypoints' times (for the plot's markers), a
/// thinned copy of the samples for the plot, and notes for the user.
#[derive(Debug)]
struct Sampled {
    axes: usize,
    times: Vec<f64>,
    /// Thinned rows `[t, p0, v0, a0, j0, p1, ...]`.
    plot_rows: Vec<Vec<f64>>,
    /// Samples written.
    count: usize,
    notes: Vec<String>,
}

/// Runs `rl traj`.
pub fn run(args: TrajArgs) -> CliResult {
    // Fixed-capacity splines of up to 12 axes are large values and unoptimised builds keep
    // several copies of them on the stack, so the work runs on a thread with a roomy stack.
    std::thread::Builder::new()
        .name("rl-traj".into())
        .stack_size(64 << 20)
        .spawn(move || run_on_big_stack(args))
        .map_err(|e| CliError::failed(format!("cannot start the trajectory thread: {e}")))?
        .join()
        .map_err(|_| CliError::failed("the trajectory thread panicked"))?
}

fn run_on_big_stack(args: TrajArgs) -> CliResult {
    if !(args.dt > 0.0 && args.dt.is_finite()) {
        return Err(CliError::usage(format!(
            "--dt must be a positive number of seconds, got {}",
            args.dt
        )));
    }
    if !(args.blend > 0.0 && args.blend <= 1.0) {
        return Err(CliError::usage(format!(
            "--blend must be in (0, 1], got {}",
            args.blend
        )));
    }
    if args.profile != Profile::ParabolicBlend {
        refuse_given(
            &["blend"],
            &format!(
                "to --profile {}: it sets parabolic-blend's blends",
                args.profile.name()
            ),
        )?;
    }
    if args.plot.is_none() {
        refuse_given(&["unit"], "without --plot: it labels the plot's axes")?;
    }
    let waypoints = read_waypoints(&args.file)?;
    // Output files first: a path that cannot be written fails before any work. Each is
    // written beside its destination and moved over it only once complete, so a failed run
    // leaves an existing file as it was.
    let create = |flag: &str, path: &Path| {
        Replacement::create(path).map_err(|e| {
            CliError::usage(format!("--{flag}: cannot create {}: {e}", path.display()))
        })
    };
    let out_file = args.out.as_deref().map(|p| create("out", p)).transpose()?;
    let plot_file = args
        .plot
        .as_deref()
        .map(|p| create("plot", p))
        .transpose()?;
    let sampled = match out_file {
        Some(mut file) => {
            let path = args.out.as_deref().unwrap_or(Path::new(""));
            let sampled = dispatch(&args, &waypoints, &mut file).map_err(|e| in_file(e, path))?;
            file.commit()
                .map_err(|e| CliError::failed(format!("writing {}: {e}", path.display())))?;
            sampled
        }
        None => {
            let mut out = io::stdout().lock();
            let sampled = dispatch(&args, &waypoints, &mut out)?;
            out.flush().map_err(|e| write_error("standard output", e))?;
            sampled
        }
    };
    for note in &sampled.notes {
        errln!("rl traj: {note}");
    }
    if let (Some(path), Some(file)) = (&args.plot, plot_file) {
        let limits = PlotLimits::parse(&args, sampled.axes)?;
        plot(file.partial(), &sampled, &waypoints, &limits, &args.unit)
            .map_err(|e| e.to_string())
            .and_then(|()| file.commit().map_err(|e| e.to_string()))
            .map_err(|e| CliError::failed(format!("drawing {}: {e}", path.display())))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// A failure while sampling into the file at `path`: a write error names the file; bad
/// waypoints or limits stay bad arguments (exit 2) with their own message.
fn in_file(e: CliError, path: &Path) -> CliError {
    if e.is_closed_output() || e.exit_code() == 2 {
        e
    } else {
        CliError::failed(format!("writing {}: {e}", path.display()))
    }
}

fn read_waypoints(path: &Path) -> Result<Waypoints, CliError> {
    let shown = path.display();
    // Read within the loaders' size limit (a FIFO or a device is refused unread).
    let max = rl_core::loader::InputLimits::DEFAULT.max_bytes;
    let bytes = rl_core::loader::read_bytes(path, max)
        .map_err(|e| CliError::usage(format!("cannot read {e}")))?;
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(bytes.as_slice());
    let headers = reader
        .headers()
        .map_err(|e| CliError::usage(format!("{shown}:1: bad header row: {e}")))?
        .clone();
    if headers.is_empty() || headers.iter().all(str::is_empty) {
        return Err(CliError::usage(format!(
            "{shown}:1: the header row is empty"
        )));
    }
    let timed = headers.get(0) == Some("t");
    let names: Vec<String> = headers
        .iter()
        .skip(usize::from(timed))
        .map(str::to_owned)
        .collect();
    if names.is_empty() {
        return Err(CliError::usage(format!(
            "{shown}:1: no axis columns after `t`"
        )));
    }
    if names.len() > MAX_AXES {
        return Err(CliError::usage(format!(
            "{shown}:1: {} axes, at most {MAX_AXES} are supported",
            names.len()
        )));
    }
    let mut times = Vec::new();
    let mut points = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map(|p| p.line()).unwrap_or(0);
            CliError::usage(format!("{shown}:{line}: {e}"))
        })?;
        let line = record.position().map(|p| p.line()).unwrap_or(0);
        let mut values = Vec::with_capacity(record.len());
        for (column, field) in record.iter().enumerate() {
            let value: f64 = field
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| {
                    CliError::usage(format!(
                        "{shown}:{line}: column `{}`: `{field}` is not a finite number",
                        headers.get(column).unwrap_or("?")
                    ))
                })?;
            values.push(value);
        }
        if timed {
            let t = values.remove(0);
            if let Some(&before) = times.last() {
                if t <= before {
                    return Err(CliError::usage(format!(
                        "{shown}:{line}: time {t} is not after the previous time {before}"
                    )));
                }
            }
            times.push(t);
        }
        points.push(values);
    }
    if points.len() < 2 {
        return Err(CliError::usage(format!(
            "{shown}: needs at least 2 waypoints, found {}",
            points.len()
        )));
    }
    if points.len() > MAX_WAYPOINTS {
        return Err(CliError::usage(format!(
            "{shown}: {} waypoints, at most {MAX_WAYPOINTS} are supported",
            points.len()
        )));
    }
    Ok(Waypoints {
        times: timed.then_some(times),
        names,
        points,
    })
}

/// Parses `--name v` or `--name v0,v1,...` into one value per axis (`None`: unlimited).
fn parse_limit(name: &str, text: Option<&str>, axes: usize) -> Result<Vec<f64>, CliError> {
    let Some(text) = text else {
        return Ok(vec![f64::INFINITY; axes]);
    };
    let values = text
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| *v > 0.0 && v.is_finite())
                .ok_or_else(|| CliError::usage(format!("--{name}: `{s}` is not a positive number")))
        })
        .collect::<Result<Vec<f64>, _>>()?;
    match values.len() {
        1 => Ok(vec![values[0]; axes]),
        n if n == axes => Ok(values),
        n => Err(CliError::usage(format!(
            "--{name}: {n} values for {axes} axes (give 1 or {axes})"
        ))),
    }
}

fn dispatch(args: &TrajArgs, w: &Waypoints, out: &mut dyn Write) -> Result<Sampled, CliError> {
    macro_rules! by_axes {
        ($($d:literal)*) => {
            match w.names.len() {
                $($d => sample_profile::<$d>(args, w, out),)*
                n => Err(CliError::usage(format!("{n} axes are not supported (1 to {MAX_AXES})"))),
            }
        };
    }
    by_axes!(1 2 3 4 5 6 7 8 9 10 11 12)
}

fn to_arrays<const D: usize>(points: &[Vec<f64>]) -> Vec<[f64; D]> {
    points
        .iter()
        .map(|p| std::array::from_fn(|i| p[i]))
        .collect()
}

fn traj_error(profile: Profile, e: TrajectoryError) -> CliError {
    let what = match e {
        TrajectoryError::NonIncreasingTime { index } | TrajectoryError::NotFinite { index, .. } => {
            format!("{e} (waypoint row {})", index + 1)
        }
        _ => e.to_string(),
    };
    CliError::usage(format!("{} profile: {what}", profile.name()))
}

/// The limits of `args` for `D` axes and which of them were given.
fn limits<const D: usize>(args: &TrajArgs) -> Result<(Limits<D>, [bool; 3]), CliError> {
    Ok((
        Limits::<D> {
            velocity: array(parse_limit("vmax", args.vmax.as_deref(), D)?),
            acceleration: array(parse_limit("amax", args.amax.as_deref(), D)?),
            jerk: array(parse_limit("jmax", args.jmax.as_deref(), D)?),
        },
        [
            args.vmax.is_some(),
            args.amax.is_some(),
            args.jmax.is_some(),
        ],
    ))
}

/// Builds a piecewise-polynomial trajectory through the waypoints at given times.
type Build<'a, const D: usize, const C: usize, const M: usize> =
    &'a dyn Fn(&[f64]) -> Result<Box<Piecewise<Polynomial<D, C>, M>>, TrajectoryError>;

/// The smallest uniform time stretch `k` with `max|v|/k ≤ vmax`, `max|a|/k² ≤ amax` and
/// `max|j|/k³ ≤ jmax` on every axis (exact extrema of each piece).
fn stretch_for<const D: usize, const C: usize, const M: usize>(
    traj: &Piecewise<Polynomial<D, C>, M>,
    limits: &Limits<D>,
) -> f64 {
    let mut k: f64 = 0.0;
    for seg in traj.segments() {
        let (v, a, j) = (
            seg.max_abs_derivative(1),
            seg.max_abs_derivative(2),
            seg.max_abs_derivative(3),
        );
        for i in 0..D {
            k = k
                .max(v[i] / limits.velocity[i])
                .max((a[i] / limits.acceleration[i]).sqrt())
                .max((j[i] / limits.jerk[i]).cbrt());
        }
    }
    k
}

/// A trajectory timed by [`timed`]: the trajectory, the waypoints' times and the first one.
struct Timed<const D: usize, const C: usize, const M: usize> {
    traj: Box<Piecewise<Polynomial<D, C>, M>>,
    times: Vec<f64>,
    t0: f64,
}

/// A profile that follows times: at the `t` column's times, slowed down where a limit would be
/// exceeded; without a `t` column, spaced by distance and scaled to the tightest limit.
#[allow(clippy::too_many_arguments)]
fn timed<const D: usize, const C: usize, const M: usize>(
    profile: Profile,
    w: &Waypoints,
    points: &[[f64; D]],
    limits: &Limits<D>,
    any_limit: bool,
    build: Build<'_, D, C, M>,
    notes: &mut Vec<String>,
) -> Result<Timed<D, C, M>, CliError> {
    let err = |e| traj_error(profile, e);
    let given = w.times.as_deref();
    let times: Vec<f64> = match given {
        Some(t) => t.to_vec(),
        None if any_limit => {
            // Spaced by the largest axis move (at least 1 ms, so a repeated waypoint pauses).
            let mut t = vec![0.0];
            for pair in points.windows(2) {
                let d = (0..D).fold(0.0_f64, |m, i| m.max((pair[1][i] - pair[0][i]).abs()));
                t.push(t[t.len() - 1] + d.max(1e-3));
            }
            t
        }
        None => {
            return Err(CliError::usage(format!(
                "{} profile needs times: make the first column `t`, or give --vmax/--amax/--jmax \
                 to time it by the limits",
                profile.name()
            )));
        }
    };
    let t0 = times[0];
    let first = build(&times).map_err(err)?;
    let k = if any_limit {
        stretch_for(&first, limits)
    } else {
        1.0
    };
    if !any_limit || (given.is_some() && k <= 1.0) {
        return Ok(Timed {
            traj: first,
            times,
            t0,
        });
    }
    let scaled: Vec<f64> = times.iter().map(|t| t0 + (t - t0) * k).collect();
    let traj = build(&scaled).map_err(err)?;
    if given.is_some() {
        notes.push(format!(
            "the `t` column's times exceed a limit: stretched {k:.4}× ({:.6} s → {:.6} s)",
            times[times.len() - 1] - t0,
            scaled[scaled.len() - 1] - t0
        ));
    } else {
        notes.push(format!(
            "timed by the limits: {:.6} s",
            scaled[scaled.len() - 1] - t0
        ));
    }
    Ok(Timed {
        traj,
        times: scaled,
        t0,
    })
}

fn sample_profile<const D: usize>(
    args: &TrajArgs,
    w: &Waypoints,
    out: &mut dyn Write,
) -> Result<Sampled, CliError> {
    let points = to_arrays::<D>(&w.points);
    let (limits, given) = limits::<D>(args)?;
    let any_limit = given.iter().any(|&x| x);
    let err = |e| traj_error(args.profile, e);
    let mut notes = Vec::new();
    let zero = [0.0; D];
    // A spline profile: timed by the `t` column or the limits ([`timed`]), then sampled.
    macro_rules! timed_and_sampled {
        ($build:expr) => {{
            let t = timed(
                args.profile,
                w,
                &points,
                &limits,
                any_limit,
                &$build,
                &mut notes,
            )?;
            sample(t.traj.as_ref(), t.t0, args.dt, t.times, out, notes)
        }};
    }
    match args.profile {
        Profile::Quintic if w.times.is_none() && any_limit => {
            let s: Box<Piecewise<Polynomial<D, 6>, SEGMENTS>> =
                Box::new(spline::at_rest_through(&points, &limits).map_err(err)?);
            let times = starts_and_end(s.starts(), s.duration());
            sample(s.as_ref(), 0.0, args.dt, times, out, notes)
        }
        Profile::Quintic => {
            let build = |times: &[f64]| {
                let mut s: Box<Piecewise<Polynomial<D, 6>, SEGMENTS>> = Box::default();
                for (k, pair) in points.windows(2).enumerate() {
                    let q = Polynomial::quintic(
                        pair[0],
                        pair[1],
                        zero,
                        zero,
                        zero,
                        zero,
                        times[k + 1] - times[k],
                    )?;
                    s.push(q)?;
                }
                Ok(s)
            };
            timed_and_sampled!(build)
        }
        Profile::CubicNatural => {
            let build = |times: &[f64]| {
                Ok(Box::new(spline::natural_cubic::<D, SEGMENTS>(
                    times, &points,
                )?))
            };
            timed_and_sampled!(build)
        }
        Profile::CubicClamped => {
            let build = |times: &[f64]| {
                Ok(Box::new(spline::clamped_cubic::<D, SEGMENTS>(
                    times, &points, zero, zero,
                )?))
            };
            timed_and_sampled!(build)
        }
        Profile::ParabolicBlend => {
            if given[2] {
                return Err(CliError::usage(
                    "parabolic-blend profile: --jmax cannot be honoured (the acceleration jumps \
                     at every blend, so the jerk is unbounded); drop --jmax, or use quintic, \
                     cubic-natural, cubic-clamped or jerk-limited",
                ));
            }
            let build = |times: &[f64]| {
                Ok(Box::new(spline::linear_with_blends::<D, BLEND_SEGMENTS>(
                    times,
                    &points,
                    BlendShape::Parabolic,
                    BlendTime::Fraction(args.blend),
                )?))
            };
            timed_and_sampled!(build)
        }
        Profile::JerkLimited => {
            if w.times.is_some() {
                return Err(CliError::usage(
                    "jerk-limited profile plans its own (time-optimal) timing from --vmax, \
                     --amax and --jmax: remove the `t` column, or use a profile that follows \
                     times (quintic, cubic-natural, cubic-clamped, parabolic-blend)",
                ));
            }
            for (name, given) in ["vmax", "amax", "jmax"].iter().zip(given) {
                if !given {
                    return Err(CliError::usage(format!(
                        "jerk-limited profile needs --{name}"
                    )));
                }
            }
            // Moves of 12 axes are large; keep them on the heap (rl-core's
            // `spline::jerk_limited_through` is the fixed-capacity equivalent).
            let mut moves = Moves::default();
            for pair in points.windows(2) {
                moves.push(JerkLimited::new(pair[0], pair[1], &limits).map_err(err)?);
            }
            let times = starts_and_end(&moves.starts, moves.duration);
            sample(&moves, 0.0, args.dt, times, out, notes)
        }
    }
}

/// The waypoints' times from the segment starts and the end.
fn starts_and_end(starts: &[f64], end: f64) -> Vec<f64> {
    let mut t = starts.to_vec();
    t.push(end);
    t
}

/// Moves played one after another, on the heap.
struct Moves<F> {
    starts: Vec<f64>,
    moves: Vec<F>,
    duration: f64,
}

impl<F> Default for Moves<F> {
    fn default() -> Self {
        Self {
            starts: Vec::new(),
            moves: Vec::new(),
            duration: 0.0,
        }
    }
}

impl<F> Moves<F> {
    fn push<const D: usize>(&mut self, f: F)
    where
        F: Trajectory<D>,
    {
        self.starts.push(self.duration);
        self.duration += f.duration();
        self.moves.push(f);
    }
}

impl<const D: usize, F: Trajectory<D>> Trajectory<D> for Moves<F> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        let i = self.starts.partition_point(|&s| s <= t).saturating_sub(1);
        self.moves
            .get(i)
            .map_or([0.0; D], |m| m.derivative(t - self.starts[i], order))
    }

    fn sample(&self, t: f64) -> rl_core::traj::Sample<D> {
        let i = self.starts.partition_point(|&s| s <= t).saturating_sub(1);
        match self.moves.get(i) {
            Some(m) => m.sample(t - self.starts[i]),
            None => rl_core::traj::Sample {
                position: [0.0; D],
                velocity: [0.0; D],
                acceleration: [0.0; D],
                jerk: [0.0; D],
            },
        }
    }
}

fn array<const D: usize>(v: Vec<f64>) -> [f64; D] {
    std::array::from_fn(|i| v[i])
}

/// Samples every `dt` from 0 and once more at the exact end time, writing each row as it is
/// computed and keeping a thinned copy for the plot. `times` are the waypoints' times relative
/// to the trajectory's start, shifted by `t0` in the output.
fn sample<const D: usize, T: Trajectory<D> + ?Sized>(
    traj: &T,
    t0: f64,
    dt: f64,
    times: Vec<f64>,
    out: &mut dyn Write,
    notes: Vec<String>,
) -> Result<Sampled, CliError> {
    let end = traj.duration();
    if end / dt > MAX_SAMPLES {
        return Err(CliError::usage(format!(
            "--dt {dt} gives more than {MAX_SAMPLES} samples over {end} s"
        )));
    }
    let steps = (end / dt + 1e-9).floor() as usize;
    let last_on_grid = end - steps as f64 * dt <= 1e-9 * dt;
    let count = if last_on_grid { steps + 1 } else { steps + 2 };
    let stride = count.div_ceil(PLOT_POINTS).max(1);
    let shift = times.first().copied().unwrap_or(0.0);
    let mut w = csv::Writer::from_writer(out);
    let mut header = vec!["t".to_owned()];
    for i in 0..D {
        header.extend([
            format!("p{i}"),
            format!("v{i}"),
            format!("a{i}"),
            format!("j{i}"),
        ]);
    }
    let written = |e: csv::Error| match e.into_kind() {
        csv::ErrorKind::Io(e) => write_error("the samples' output", e),
        e => CliError::failed(format!("writing samples: {e:?}")),
    };
    w.write_record(&header).map_err(written)?;
    let mut plot_rows = Vec::with_capacity(count / stride + 2);
    let mut row = Vec::with_capacity(1 + 4 * D);
    for k in 0..count {
        let t = if k + 1 == count { end } else { k as f64 * dt };
        let s = traj.sample(t);
        row.clear();
        row.push(t0 + t);
        for i in 0..D {
            row.extend([s.position[i], s.velocity[i], s.acceleration[i], s.jerk[i]]);
        }
        // Shortest round-trip formatting (ryu), exponents for tiny values.
        w.serialize(&row).map_err(written)?;
        if k % stride == 0 || k + 1 == count {
            plot_rows.push(row.clone());
        }
    }
    w.flush()
        .map_err(|e| write_error("the samples' output", e))?;
    Ok(Sampled {
        axes: D,
        times: times.iter().map(|t| t0 + t - shift).collect(),
        plot_rows,
        count,
        notes,
    })
}

/// The limits drawn in the plot: per panel (velocity, acceleration, jerk), one value per axis
/// when given.
struct PlotLimits {
    panels: [Option<Vec<f64>>; 3],
}

impl PlotLimits {
    fn parse(args: &TrajArgs, axes: usize) -> Result<Self, CliError> {
        let one = |name: &str, text: Option<&str>| -> Result<Option<Vec<f64>>, CliError> {
            text.map(|t| parse_limit(name, Some(t), axes)).transpose()
        };
        Ok(Self {
            panels: [
                one("vmax", args.vmax.as_deref())?,
                one("amax", args.amax.as_deref())?,
                one("jmax", args.jmax.as_deref())?,
            ],
        })
    }
}

/// Twelve colours told apart on white and by most colour-blind readers: Tableau 10, black and
/// a dark gold.
const COLOURS: [(u8, u8, u8); MAX_AXES] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
    (0, 0, 0),
    (166, 118, 29),
];

fn colour(i: usize) -> RGBColor {
    let (r, g, b) = COLOURS[i % MAX_AXES];
    RGBColor(r, g, b)
}

/// Position, velocity, acceleration and jerk over time, one panel each, with units; the limits
/// as dashed lines; the waypoints as circles; the legend to the right of the panels, clear of
/// the curves.
fn plot(
    path: &Path,
    s: &Sampled,
    w: &Waypoints,
    limits: &PlotLimits,
    unit: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (1200, 1100)).into_drawing_area();
    root.fill(&WHITE)?;
    let (charts, legend) = root.split_horizontally(1020);
    let panels = charts.split_evenly((4, 1));
    let rows = &s.plot_rows;
    let t_min = rows.first().map_or(0.0, |r| r[0]);
    let t_max = rows.last().map_or(1.0, |r| r[0]).max(t_min + 1e-9);
    let titles = [
        ("position", unit.to_string()),
        ("velocity", format!("{unit}/s")),
        ("acceleration", format!("{unit}/s²")),
        ("jerk", format!("{unit}/s³")),
    ];
    for (q, panel) in panels.iter().enumerate() {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for row in rows {
            for i in 0..s.axes {
                lo = lo.min(row[1 + 4 * i + q]);
                hi = hi.max(row[1 + 4 * i + q]);
            }
        }
        // The limits stay in view.
        if let Some(l) = q.checked_sub(1).and_then(|k| limits.panels[k].as_ref()) {
            let m = l.iter().copied().fold(0.0, f64::max);
            lo = lo.min(-m);
            hi = hi.max(m);
        }
        if !(lo.is_finite() && hi.is_finite()) {
            (lo, hi) = (-1.0, 1.0);
        }
        let pad = ((hi - lo) * 0.06).max(1e-9);
        let (name, unit) = &titles[q];
        let mut chart = ChartBuilder::on(panel)
            .caption(name, ("sans-serif", 18))
            .margin(8)
            .margin_right(16)
            .x_label_area_size(36)
            .y_label_area_size(78)
            .build_cartesian_2d(t_min..t_max, (lo - pad)..(hi + pad))?;
        chart
            .configure_mesh()
            .x_desc("t [s]")
            .y_desc(format!("{name} [{unit}]"))
            .light_line_style(WHITE.mix(0.0))
            .draw()?;
        for i in 0..s.axes {
            chart.draw_series(LineSeries::new(
                rows.iter().map(|r| (r[0], r[1 + 4 * i + q])),
                colour(i).stroke_width(2),
            ))?;
        }
        if q == 0 {
            for (k, t) in s.times.iter().enumerate() {
                for i in 0..s.axes {
                    let y = w.points.get(k).and_then(|p| p.get(i)).copied();
                    if let Some(y) = y {
                        chart.draw_series(std::iter::once(Circle::new(
                            (*t, y),
                            4,
                            colour(i).stroke_width(2),
                        )))?;
                    }
                }
            }
        }
        if let Some(l) = q.checked_sub(1).and_then(|k| limits.panels[k].as_ref()) {
            let uniform = l.iter().all(|x| *x == l[0]);
            for (i, x) in l.iter().enumerate() {
                if uniform && i > 0 {
                    break;
                }
                let style = if uniform {
                    BLACK.mix(0.7).stroke_width(1)
                } else {
                    colour(i).mix(0.9).stroke_width(1)
                };
                for y in [*x, -*x] {
                    chart.draw_series(DashedLineSeries::new(
                        [(t_min, y), (t_max, y)],
                        8,
                        5,
                        style,
                    ))?;
                }
            }
        }
    }
    // The legend: one line per axis, then the markers' meaning.
    let font = ("sans-serif", 15).into_font();
    let mut y = 40;
    legend.draw(&Text::new(
        "axes",
        (10, y - 24),
        font.clone().style(FontStyle::Bold),
    ))?;
    for i in 0..s.axes {
        let name = w
            .names
            .get(i)
            .cloned()
            .unwrap_or_else(|| format!("axis {i}"));
        legend.draw(&PathElement::new(
            vec![(10, y), (40, y)],
            colour(i).stroke_width(3),
        ))?;
        legend.draw(&Text::new(name, (48, y - 8), font.clone()))?;
        y += 24;
    }
    y += 16;
    legend.draw(&Circle::new((25, y), 4, BLACK.stroke_width(2)))?;
    legend.draw(&Text::new("waypoint", (48, y - 8), font.clone()))?;
    if limits.panels.iter().any(Option::is_some) {
        y += 24;
        legend.draw(&PathElement::new(
            vec![(10, y), (20, y)],
            BLACK.mix(0.7).stroke_width(1),
        ))?;
        legend.draw(&PathElement::new(
            vec![(28, y), (38, y)],
            BLACK.mix(0.7).stroke_width(1),
        ))?;
        legend.draw(&Text::new("± limit", (48, y - 8), font.clone()))?;
    }
    y += 32;
    legend.draw(&Text::new(
        format!("{} samples", s.count),
        (10, y),
        font.clone(),
    ))?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("rl-traj-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    fn args(file: PathBuf, profile: Profile) -> TrajArgs {
        TrajArgs {
            file,
            profile,
            vmax: None,
            amax: None,
            jmax: None,
            dt: 0.01,
            blend: 0.2,
            out: None,
            plot: None,
            unit: "rad".into(),
        }
    }

    /// Every row written, parsed back, and the text.
    #[derive(Debug)]
    struct Rows {
        rows: Vec<Vec<f64>>,
        text: String,
    }

    fn dispatch(a: &TrajArgs, w: &Waypoints) -> Result<Rows, CliError> {
        let mut out = Vec::new();
        super::dispatch(a, w, &mut out)?;
        let text = String::from_utf8(out).unwrap();
        let rows = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        Ok(Rows { rows, text })
    }

    #[test]
    fn malformed_rows_name_the_line() {
        let path = write("bad.csv", "t,a,b\n0,0,0\n1,1,x\n");
        let e = read_waypoints(&path).unwrap_err().to_string();
        assert!(e.contains("bad.csv:3") && e.contains("column `b`"), "{e}");
        let path = write("short.csv", "t,a\n0,0\n1\n2,3\n");
        let e = read_waypoints(&path).unwrap_err().to_string();
        assert!(e.contains("short.csv:3"), "{e}");
        let path = write("time.csv", "t,a\n0,0\n1,1\n1,2\n");
        let e = read_waypoints(&path).unwrap_err().to_string();
        assert!(e.contains("time.csv:4") && e.contains("not after"), "{e}");
        let path = write("one.csv", "a\n1\n");
        assert!(
            read_waypoints(&path)
                .unwrap_err()
                .to_string()
                .contains("at least 2")
        );
    }

    #[test]
    fn samples_run_from_start_to_exact_end_with_the_header() {
        let path = write("wp.csv", "t,x,y\n0.5,0,1\n1.0,1,0\n1.73,0,0\n");
        let w = read_waypoints(&path).unwrap();
        for profile in [
            Profile::CubicNatural,
            Profile::CubicClamped,
            Profile::ParabolicBlend,
            Profile::Quintic,
        ] {
            let s = dispatch(&args(path.clone(), profile), &w).unwrap();
            assert_eq!(s.rows[0][0], 0.5);
            assert!(
                (s.rows.last().unwrap()[0] - 1.73).abs() < 1e-12,
                "{profile:?}"
            );
            assert_eq!(s.rows[0].len(), 9);
            // Passes through (or, for blends, ends at) the last waypoint.
            assert!(s.rows.last().unwrap()[1].abs() < 1e-12);
        }
        let s = dispatch(&args(path.clone(), Profile::CubicNatural), &w).unwrap();
        assert!(s.text.starts_with("t,p0,v0,a0,j0,p1,v1,a1,j1\n"));
        assert_eq!(s.text.lines().count(), s.rows.len() + 1);
    }

    #[test]
    fn at_rest_profiles_need_their_limits_and_respect_them() {
        let path = write("rest.csv", "a,b\n0,0\n1,-2\n0.5,0.5\n");
        let w = read_waypoints(&path).unwrap();
        let mut a = args(path.clone(), Profile::JerkLimited);
        a.vmax = Some("1".into());
        assert!(dispatch(&a, &w).unwrap_err().to_string().contains("--amax"));
        a.amax = Some("2,3".into());
        a.jmax = Some("10".into());
        let s = dispatch(&a, &w).unwrap();
        for row in &s.rows {
            assert!(row[2].abs() <= 1.0 + 1e-9 && row[6].abs() <= 1.0 + 1e-9);
            assert!(row[3].abs() <= 2.0 + 1e-9 && row[7].abs() <= 3.0 + 1e-9);
        }
        let last = s.rows.last().unwrap();
        assert!((last[1] - 0.5).abs() < 1e-9 && last[2].abs() < 1e-9);
        a.vmax = Some("-1".into());
        assert!(dispatch(&a, &w).unwrap_err().to_string().contains("--vmax"));
        let q = args(path, Profile::Quintic);
        assert!(dispatch(&q, &w).unwrap_err().to_string().contains("limits"));
    }

    /// Largest |column| over the rows.
    fn peak(rows: &[Vec<f64>], col: usize) -> f64 {
        rows.iter().map(|r| r[col].abs()).fold(0.0, f64::max)
    }

    #[test]
    fn spline_profiles_are_slowed_down_to_their_limits() {
        // Times far too short for vmax 1, amax 2, jmax 20.
        let path = write(
            "fast.csv",
            "t,x,y\n0,0,0\n0.1,1,-2\n0.2,0.5,0.5\n0.35,0,0\n",
        );
        let w = read_waypoints(&path).unwrap();
        for profile in [
            Profile::CubicNatural,
            Profile::CubicClamped,
            Profile::ParabolicBlend,
            Profile::Quintic,
        ] {
            let mut a = args(path.clone(), profile);
            a.dt = 0.0005;
            let free = dispatch(&a, &w).unwrap();
            assert!(
                peak(&free.rows, 2) > 5.0,
                "{profile:?}: the test needs fast times"
            );
            a.vmax = Some("1".into());
            a.amax = Some("2,3".into());
            if profile != Profile::ParabolicBlend {
                a.jmax = Some("20".into());
            }
            let s = dispatch(&a, &w).unwrap();
            let (vp, ap, jp) = (
                peak(&s.rows, 2).max(peak(&s.rows, 6)),
                peak(&s.rows, 3),
                peak(&s.rows, 7),
            );
            assert!(vp <= 1.0 + 1e-9, "{profile:?}: |v| {vp}");
            assert!(
                ap <= 2.0 + 1e-9 && jp <= 3.0 + 1e-9,
                "{profile:?}: |a| {ap}, {jp}"
            );
            if profile != Profile::ParabolicBlend {
                let j = peak(&s.rows, 4).max(peak(&s.rows, 8));
                assert!(j <= 20.0 + 1e-9, "{profile:?}: |j| {j}");
            }
            // The tightest limit is reached (to the sampling), not undershot by far.
            let reached = [vp / 1.0, ap / 2.0, jp / 3.0]
                .into_iter()
                .fold(0.0, f64::max);
            assert!(reached > 0.9, "{profile:?}: {reached}");
            // Same path: starts at the first waypoint, ends at the last, later.
            let last = s.rows.last().unwrap();
            assert!(last[0] > 0.35 && last[1].abs() < 1e-9 && last[5].abs() < 1e-9);
        }
    }

    #[test]
    fn slow_times_are_kept_and_missing_times_come_from_the_limits() {
        let path = write("slow.csv", "t,x\n0,0\n10,1\n20,0\n");
        let w = read_waypoints(&path).unwrap();
        let mut a = args(path.clone(), Profile::CubicClamped);
        a.vmax = Some("1".into());
        let s = dispatch(&a, &w).unwrap();
        assert!(
            (s.rows.last().unwrap()[0] - 20.0).abs() < 1e-12,
            "times kept"
        );
        // No `t` column: timed by the limits, the velocity limit reached.
        let path = write("untimed.csv", "x\n0\n1\n0\n");
        let w = read_waypoints(&path).unwrap();
        let mut a = args(path, Profile::CubicNatural);
        a.dt = 0.001;
        assert!(
            dispatch(&a, &w)
                .unwrap_err()
                .to_string()
                .contains("needs times")
        );
        a.vmax = Some("0.5".into());
        let s = dispatch(&a, &w).unwrap();
        let vp = peak(&s.rows, 2);
        assert!(vp <= 0.5 + 1e-9 && vp > 0.49, "{vp}");
    }

    #[test]
    fn what_a_profile_cannot_honour_is_refused() {
        let timed = write("timed.csv", "t,x\n0,0\n1,1\n");
        let w = read_waypoints(&timed).unwrap();
        let mut a = args(timed.clone(), Profile::JerkLimited);
        a.vmax = Some("1".into());
        a.amax = Some("1".into());
        a.jmax = Some("1".into());
        let e = dispatch(&a, &w).unwrap_err().to_string();
        assert!(e.contains("remove the `t` column"), "{e}");
        let mut a = args(timed, Profile::ParabolicBlend);
        a.jmax = Some("1".into());
        let e = dispatch(&a, &w).unwrap_err().to_string();
        assert!(e.contains("--jmax cannot be honoured"), "{e}");
    }
}
