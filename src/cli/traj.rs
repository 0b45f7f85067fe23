//! `rl traj`: sample a trajectory through waypoints read from a CSV file, write position,
//! velocity, acceleration and jerk of every axis as CSV, and optionally plot them as SVG.
//!
//! Input: a header row, then one row per waypoint with a column per axis; profiles that need
//! times take them from a first column named `t`. Output header: `t,p0,v0,a0,j0,p1,...`, one row
//! per sample from the start to the exact end time.

use std::fs::File;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, ValueEnum};
use plotters::prelude::*;
use rl_core::traj::{
    BlendShape, BlendTime, JerkLimited, Limits, Piecewise, Polynomial, Trajectory, TrajectoryError,
    spline,
};

use super::{CliError, CliResult};

/// Most axes a waypoint file may have.
pub const MAX_AXES: usize = 12;
/// Most waypoints a file may have.
pub const MAX_WAYPOINTS: usize = 128;
/// Most samples written (guards against a tiny `--dt`).
const MAX_SAMPLES: f64 = 1e7;

/// Segment capacities for the largest file.
const SEGMENTS: usize = MAX_WAYPOINTS - 1;
const BLEND_SEGMENTS: usize = 2 * MAX_WAYPOINTS - 1;

/// Trajectory profile of `rl traj`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Profile {
    /// Quintic polynomials from rest to rest through every waypoint: time-optimal under
    /// --vmax/--amax/--jmax (any of them), else timed by the `t` column.
    Quintic,
    /// Natural cubic spline through the waypoints at the `t` column's times.
    CubicNatural,
    /// Cubic spline at the `t` column's times, starting and ending at rest.
    CubicClamped,
    /// Straight lines with parabolic blends (--blend of the neighbouring segments), at rest at
    /// both ends; needs the `t` column.
    ParabolicBlend,
    /// 7-segment jerk-limited moves from rest to rest through every waypoint, time-optimal
    /// under --vmax, --amax and --jmax (all required).
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
    /// Waypoints: header row, then one row per waypoint (optional first column `t`).
    pub file: PathBuf,
    /// How to move through the waypoints.
    #[arg(long, value_enum)]
    pub profile: Profile,
    /// Velocity limit: one value for all axes or a comma-separated value per axis.
    #[arg(long)]
    pub vmax: Option<String>,
    /// Acceleration limit: one value or one per axis.
    #[arg(long)]
    pub amax: Option<String>,
    /// Jerk limit: one value or one per axis.
    #[arg(long)]
    pub jmax: Option<String>,
    /// Sample period in seconds.
    #[arg(long, default_value_t = 0.001)]
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
}

/// Waypoints read from the CSV file.
#[derive(Debug)]
struct Waypoints {
    times: Option<Vec<f64>>,
    names: Vec<String>,
    points: Vec<Vec<f64>>,
}

/// Sampled trajectory: `rows[k] = [t, p0, v0, a0, j0, p1, ...]`.
#[derive(Debug)]
struct Samples {
    axes: usize,
    rows: Vec<Vec<f64>>,
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
    let waypoints = read_waypoints(&args.file)?;
    let samples = dispatch(&args, &waypoints)?;
    match &args.out {
        Some(path) => {
            let file = File::create(path)
                .map_err(|e| CliError::usage(format!("cannot create {}: {e}", path.display())))?;
            write_samples(io::BufWriter::new(file), &samples)
                .map_err(|e| CliError::failed(format!("writing {}: {e}", path.display())))?;
        }
        None => write_samples(io::stdout().lock(), &samples)
            .map_err(|e| CliError::failed(format!("writing samples: {e}")))?,
    }
    if let Some(path) = &args.plot {
        plot(path, &samples, &waypoints.names)
            .map_err(|e| CliError::failed(format!("drawing {}: {e}", path.display())))?;
    }
    Ok(ExitCode::SUCCESS)
}

fn read_waypoints(path: &Path) -> Result<Waypoints, CliError> {
    let shown = path.display();
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .map_err(|e| CliError::usage(format!("cannot read {shown}: {e}")))?;
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

fn dispatch(args: &TrajArgs, w: &Waypoints) -> Result<Samples, CliError> {
    macro_rules! by_axes {
        ($($d:literal)*) => {
            match w.names.len() {
                $($d => sample_profile::<$d>(args, w),)*
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

fn sample_profile<const D: usize>(args: &TrajArgs, w: &Waypoints) -> Result<Samples, CliError> {
    let points = to_arrays::<D>(&w.points);
    let limits = Limits::<D> {
        velocity: array(parse_limit("vmax", args.vmax.as_deref(), D)?),
        acceleration: array(parse_limit("amax", args.amax.as_deref(), D)?),
        jerk: array(parse_limit("jmax", args.jmax.as_deref(), D)?),
    };
    let any_limit = [
        args.vmax.is_some(),
        args.amax.is_some(),
        args.jmax.is_some(),
    ];
    let err = |e| traj_error(args.profile, e);
    let need_times = || {
        w.times.as_deref().ok_or_else(|| {
            CliError::usage(format!(
                "{} profile needs times: make the first column `t`",
                args.profile.name()
            ))
        })
    };
    let t0 = w.times.as_ref().map_or(0.0, |t| t[0]);
    match args.profile {
        Profile::Quintic => {
            if any_limit.iter().any(|&x| x) {
                let s: Box<Piecewise<Polynomial<D, 6>, SEGMENTS>> =
                    Box::new(spline::at_rest_through(&points, &limits).map_err(err)?);
                sample(s.as_ref(), t0, args.dt)
            } else {
                let times = w.times.as_deref().ok_or_else(|| {
                    CliError::usage(
                        "quintic profile needs limits (--vmax/--amax/--jmax) or a `t` column",
                    )
                })?;
                let mut s: Box<Piecewise<Polynomial<D, 6>, SEGMENTS>> = Box::default();
                let zero = [0.0; D];
                for (k, pair) in points.windows(2).enumerate() {
                    let q = Polynomial::quintic(
                        pair[0],
                        pair[1],
                        zero,
                        zero,
                        zero,
                        zero,
                        times[k + 1] - times[k],
                    )
                    .map_err(err)?;
                    s.push(q).map_err(err)?;
                }
                sample(s.as_ref(), t0, args.dt)
            }
        }
        Profile::CubicNatural => {
            let s: Box<Piecewise<Polynomial<D, 4>, SEGMENTS>> =
                Box::new(spline::natural_cubic(need_times()?, &points).map_err(err)?);
            sample(s.as_ref(), t0, args.dt)
        }
        Profile::CubicClamped => {
            let s: Box<Piecewise<Polynomial<D, 4>, SEGMENTS>> = Box::new(
                spline::clamped_cubic(need_times()?, &points, [0.0; D], [0.0; D]).map_err(err)?,
            );
            sample(s.as_ref(), t0, args.dt)
        }
        Profile::ParabolicBlend => {
            if !(args.blend > 0.0 && args.blend <= 1.0) {
                return Err(CliError::usage(format!(
                    "--blend must be in (0, 1], got {}",
                    args.blend
                )));
            }
            let s: Box<Piecewise<Polynomial<D, 7>, BLEND_SEGMENTS>> = Box::new(
                spline::linear_with_blends(
                    need_times()?,
                    &points,
                    BlendShape::Parabolic,
                    BlendTime::Fraction(args.blend),
                )
                .map_err(err)?,
            );
            sample(s.as_ref(), t0, args.dt)
        }
        Profile::JerkLimited => {
            for (name, given) in ["vmax", "amax", "jmax"].iter().zip(any_limit) {
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
            sample(&moves, t0, args.dt)
        }
    }
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

/// Samples every `dt` from 0 and once more at the exact end time.
fn sample<const D: usize, T: Trajectory<D>>(
    traj: &T,
    t0: f64,
    dt: f64,
) -> Result<Samples, CliError> {
    let end = traj.duration();
    if end / dt > MAX_SAMPLES {
        return Err(CliError::usage(format!(
            "--dt {dt} gives more than {MAX_SAMPLES} samples over {end} s"
        )));
    }
    let steps = (end / dt + 1e-9).floor() as usize;
    let mut times: Vec<f64> = (0..=steps).map(|k| k as f64 * dt).collect();
    if let Some(&last) = times.last() {
        if end - last > 1e-9 * dt {
            times.push(end);
        } else if let Some(l) = times.last_mut() {
            *l = end;
        }
    }
    let rows = times
        .into_iter()
        .map(|t| {
            let s = traj.sample(t);
            let mut row = Vec::with_capacity(1 + 4 * D);
            row.push(t0 + t);
            for i in 0..D {
                row.extend([s.position[i], s.velocity[i], s.acceleration[i], s.jerk[i]]);
            }
            row
        })
        .collect();
    Ok(Samples { axes: D, rows })
}

fn write_samples(out: impl Write, samples: &Samples) -> io::Result<()> {
    let mut w = csv::Writer::from_writer(out);
    let mut header = vec!["t".to_owned()];
    for i in 0..samples.axes {
        header.extend([
            format!("p{i}"),
            format!("v{i}"),
            format!("a{i}"),
            format!("j{i}"),
        ]);
    }
    w.write_record(&header)?;
    for row in &samples.rows {
        // Shortest round-trip formatting (ryu), exponents for tiny values.
        w.serialize(row).map_err(io::Error::other)?;
    }
    w.flush()
}

fn plot(
    path: &Path,
    samples: &Samples,
    names: &[String],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (1000, 1000)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((4, 1));
    let t_min = samples.rows.first().map_or(0.0, |r| r[0]);
    let t_max = samples.rows.last().map_or(1.0, |r| r[0]).max(t_min + 1e-9);
    let titles = ["position", "velocity", "acceleration", "jerk"];
    for (q, panel) in panels.iter().enumerate() {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for row in &samples.rows {
            for i in 0..samples.axes {
                lo = lo.min(row[1 + 4 * i + q]);
                hi = hi.max(row[1 + 4 * i + q]);
            }
        }
        let pad = ((hi - lo) * 0.05).max(1e-9);
        let mut chart = ChartBuilder::on(panel)
            .caption(titles[q], ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(28)
            .y_label_area_size(60)
            .build_cartesian_2d(t_min..t_max, (lo - pad)..(hi + pad))?;
        chart.configure_mesh().x_desc("t [s]").draw()?;
        for i in 0..samples.axes {
            let color = Palette99::pick(i).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    samples.rows.iter().map(|r| (r[0], r[1 + 4 * i + q])),
                    color,
                ))?
                .label(names.get(i).cloned().unwrap_or_else(|| format!("axis {i}")))
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
        }
        if q == 0 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
    }
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
        }
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
        let mut out = Vec::new();
        let s = dispatch(&args(path.clone(), Profile::CubicNatural), &w).unwrap();
        write_samples(&mut out, &s).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("t,p0,v0,a0,j0,p1,v1,a1,j1\n"));
        assert_eq!(text.lines().count(), s.rows.len() + 1);
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
}
