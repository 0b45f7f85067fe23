//! A trajectory retimed along its own path near time-optimally with bounded jerk: the same
//! configurations (so whatever was certified about them holds), a new timing within joint
//! velocity, acceleration and jerk limits.
//!
//! # Construction
//!
//! 1. **Runs.** The path is cut where it is at rest (`p' = 0` in its own time `τ`: its start,
//!    its end, and the waypoints it stops at, where it may turn a corner); each run is timed
//!    from rest to rest.
//! 2. **Arc length.** `τ` is a singular parameter at rest (after a jerk-limited start
//!    `p' ∝ τ²`, and a time-optimal timing of `τ` diverges there), so each run is
//!    parameterised by its arc length `σ` in joint space (`dσ/dτ = r = |p'|`, Gauss–Legendre
//!    quadrature): with `û = p'/r`, `P = p'' − û(û·p'')`,
//!    `q' = û`, `q'' = P/r²`, `q''' = (Ṗ/r² − 2P(û·p'')/r³)/r`,
//!    `Ṗ = p''' − (P/r)(û·p'') − û((P/r)·p'' + û·p''')`. Runs start and end on straight lines
//!    (the blends from and to rest stay on the first and last segment), where `P` is rounding:
//!    a `P` below 1e-9 of `|p''|` is taken as zero.
//! 3. **TOPP-RA** ([`topp_ra`]) on a uniform grid of `σ` gives the time-optimal `s(t)` under
//!    the velocity and acceleration limits; its `s̈` is constant per stage and steps between.
//! 4. **Bounded jerk.** `s̈` is averaged over a window `w` (a box filter: `s`, `ṡ`, `s̈` become
//!    their window averages, `s⃛ = (s̈(t + w/2) − s̈(t − w/2))/w`), which adds `w` to the
//!    run. On a straight line with `w = A/J` this is exactly the time-optimal jerk-limited
//!    profile (a trapezoid of acceleration whose ramps last `A/J`). Elsewhere the averaged
//!    timing may exceed a limit: on samples 0.25 ms apart each needs a uniform slow-down
//!    `ρ`, the worst of every joint's `|q̇|/V`, `(|q̈|/A)^½`, `(|q⃛|/J)^⅓`. The window is the
//!    one (of a few fractions of `max A/J`) whose uniform slow-down `k = max ρ` gives the
//!    fastest run; then, at most 16 rounds, the path speed over the stretch each exceeding
//!    sample's window averages is capped at `1/√ρ` of what it was and TOPP-RA runs again
//!    under the caps. The fastest round, slowed by its `k·(1 + margin)`, is kept: every
//!    sample within every limit.
//!
//! Jerk is `q⃛ = q'''ṡ³ + 3q''ṡs̈ + q's⃛`. The result is not proven time-optimal for jerk; it
//! is measured against TOPP-RA's velocity-and-acceleration optimum, a lower bound. Cost: one
//! TOPP-RA per run and one evaluation of the path per sample (a few ms for a path of seconds).
//! Evaluation finds `τ(σ)` by bisection and Newton steps: allocation-free, for use before or
//! in a loop.

use rl_core::traj::Trajectory;

use super::ExecutionLimits;
use super::topp::{Parameterization, ToppProblem, topp_ra};
use crate::error::PlanError;

/// Gauss–Legendre nodes and weights on [0, 1], 5 points (exact for degree 9).
const GAUSS: [(f64, f64); 5] = [
    (0.046_910_077_030_668, 0.118_463_442_528_095),
    (0.230_765_344_947_158, 0.239_314_335_249_683),
    (0.5, 0.284_444_444_444_444),
    (0.769_234_655_052_842, 0.239_314_335_249_683),
    (0.953_089_922_969_332, 0.118_463_442_528_095),
];
/// Samples per second of the result on which the slow-down is chosen.
const SAMPLES_PER_S: f64 = 4000.0;
/// Rounds of local slowing where the averaged timing exceeds a limit.
const REFINE: usize = 16;
/// Steps at most in finding the path's own time at an arc length.
const TAU_STEPS: usize = 48;
/// Averaging windows tried, as fractions of the limits' `max A/J`.
const WINDOWS: [f64; 6] = [0.5, 0.75, 1.0, 1.25, 1.5, 2.0];

/// One run: a stretch of the path between two rests, its arc length table and timing.
#[derive(Clone, Debug)]
struct Run {
    /// The path's own time at the table's points (first and last: the rests).
    tau: Vec<f64>,
    /// Arc length at those points.
    sigma: Vec<f64>,
    timing: Parameterization,
    /// `∫ s dt` at each grid time.
    integral: Vec<f64>,
    window: f64,
    scale: f64,
    /// Where the run starts in the result, s.
    start: f64,
    /// The straight line's direction at the run's start and end (`q'` at rest).
    ends: [Vec<f64>; 2],
}

/// `path` retimed with bounded jerk (see the module docs). It keeps its path (`P`: the path
/// itself, a reference to it or a box), and is a [`Trajectory`] of the path's axes: evaluation
/// allocates nothing, for a real-time loop.
#[derive(Clone, Debug)]
pub struct JerkRetimed<P> {
    path: P,
    nq: usize,
    runs: Vec<Run>,
    duration: f64,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The path's first `nq` coordinates' derivatives of orders 1–3 at `tau`.
fn derivatives<const D: usize, T: Trajectory<D>>(path: &T, nq: usize, tau: f64) -> [[f64; D]; 3] {
    let mut d = [
        path.derivative(tau, 1),
        path.derivative(tau, 2),
        path.derivative(tau, 3),
    ];
    for row in &mut d {
        row[nq..].fill(0.0);
    }
    d
}

/// `r = |p'|` at `tau`.
fn speed<const D: usize, T: Trajectory<D>>(path: &T, nq: usize, tau: f64) -> f64 {
    let v = path.derivative(tau, 1);
    dot(&v[..nq], &v[..nq]).sqrt()
}

/// Arc length from `a` to `b` (5-point Gauss–Legendre).
fn arc<const D: usize, T: Trajectory<D>>(path: &T, nq: usize, a: f64, b: f64) -> f64 {
    GAUSS
        .iter()
        .map(|(x, w)| w * speed(path, nq, a + (b - a) * x))
        .sum::<f64>()
        * (b - a)
}

impl Run {
    /// The path's own time at arc length `s`: bisection on the table, then Newton steps on
    /// the arc length (`dσ/dτ = r`) kept inside a bracket that each step narrows; a step that
    /// would leave it (near a rest, where `r` → 0) bisects instead. At most [`TAU_STEPS`]
    /// steps: the table's intervals are short, so bisection alone reaches rounding in them.
    fn tau_at<const D: usize, T: Trajectory<D>>(&self, path: &T, nq: usize, s: f64) -> f64 {
        let n = self.sigma.len();
        let s = s.clamp(self.sigma[0], self.sigma[n - 1]);
        let i = self.sigma.partition_point(|x| *x <= s).clamp(1, n - 1) - 1;
        let (t0, t1) = (self.tau[i], self.tau[i + 1]);
        let (s0, s1) = (self.sigma[i], self.sigma[i + 1]);
        let mut t = if s1 > s0 {
            t0 + (t1 - t0) * (s - s0) / (s1 - s0)
        } else {
            t0
        };
        let (mut lo, mut hi) = (t0, t1);
        for _ in 0..TAU_STEPS {
            let err = s0 + arc(path, nq, t0, t) - s;
            if err.abs() <= 1e-13 * (1.0 + s.abs()) {
                break;
            }
            if err > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let r = speed(path, nq, t);
            let newton = t - err / r;
            t = if r > 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if hi - lo <= 4.0 * f64::EPSILON * hi.abs().max(1.0) {
                break;
            }
        }
        t
    }

    /// `q'`, `q''`, `q'''` with respect to arc length at `tau`, into `out` (rows 0–2).
    fn arc_derivatives<const D: usize, T: Trajectory<D>>(
        &self,
        path: &T,
        nq: usize,
        tau: f64,
        out: &mut [[f64; D]; 3],
    ) {
        let [v, a, j] = derivatives(path, nq, tau);
        let r = dot(&v[..nq], &v[..nq]).sqrt();
        let an = dot(&a[..nq], &a[..nq]).sqrt();
        *out = [[0.0; D]; 3];
        if r <= 1e-12 * (1.0 + an) {
            // At rest: the run's end line's direction, no curvature.
            let end = if (tau - self.tau[0]).abs() <= (tau - self.tau[self.tau.len() - 1]).abs() {
                &self.ends[0]
            } else {
                &self.ends[1]
            };
            out[0][..nq].copy_from_slice(end);
            return;
        }
        let mut u = [0.0; D];
        for k in 0..nq {
            u[k] = v[k] / r;
        }
        let ua = dot(&u[..nq], &a[..nq]);
        let uj = dot(&u[..nq], &j[..nq]);
        let mut p = [0.0; D];
        for k in 0..nq {
            p[k] = a[k] - u[k] * ua;
        }
        // On a straight line P is the rounding of a − û(û·a).
        if dot(&p[..nq], &p[..nq]).sqrt() <= 1e-9 * an {
            p = [0.0; D];
        }
        // dû/dτ = P/r.
        let pa = dot(&p[..nq], &a[..nq]) / r;
        for k in 0..nq {
            let dp = j[k] - (p[k] / r) * ua - u[k] * (pa + uj);
            out[0][k] = u[k];
            out[1][k] = p[k] / (r * r);
            out[2][k] = (dp / (r * r) - 2.0 * p[k] * ua / (r * r * r)) / r;
        }
    }

    /// `(s, ṡ, s̈)` of TOPP-RA's timing at `t`, at rest before and after it.
    fn raw(&self, t: f64) -> (f64, f64, f64) {
        let p = &self.timing;
        if t <= 0.0 {
            (p.grid[0], 0.0, 0.0)
        } else if t >= p.duration() {
            (p.grid[p.grid.len() - 1], 0.0, 0.0)
        } else {
            p.eval(t)
        }
    }

    /// `∫₀^t s dt` of TOPP-RA's timing (`s` held before and after it).
    fn integral_at(&self, t: f64) -> f64 {
        let p = &self.timing;
        let n = p.t.len();
        if t <= 0.0 {
            return p.grid[0] * t;
        }
        if t >= p.duration() {
            return self.integral[n - 1] + p.grid[n - 1] * (t - p.duration());
        }
        let i = p.t.partition_point(|ti| *ti <= t).clamp(1, n - 1) - 1;
        let (v0, u) = stage(p, i);
        let tau = t - p.t[i];
        self.integral[i] + p.grid[i] * tau + v0 * tau * tau / 2.0 + u * tau * tau * tau / 6.0
    }

    fn duration(&self) -> f64 {
        (self.timing.duration() + self.window) * self.scale
    }

    /// `(s, ṡ, s̈, s⃛)` at `t` from the run's start.
    fn path_timing(&self, t: f64) -> [f64; 4] {
        let (w, k) = (self.window, self.scale);
        let c = (t / k).clamp(0.0, self.timing.duration() + w) - w / 2.0;
        let (a, b) = (c - w / 2.0, c + w / 2.0);
        let (ra, rb) = (self.raw(a), self.raw(b));
        [
            (self.integral_at(b) - self.integral_at(a)) / w,
            (rb.0 - ra.0) / w / k,
            (rb.1 - ra.1) / w / (k * k),
            (rb.2 - ra.2) / w / (k * k * k),
        ]
    }
}

/// `(ṡ, s̈)` at the start of stage `i`.
fn stage(p: &Parameterization, i: usize) -> (f64, f64) {
    let ds = p.grid[i + 1] - p.grid[i];
    (p.x[i].max(0.0).sqrt(), (p.x[i + 1] - p.x[i]) / (2.0 * ds))
}

impl<P> JerkRetimed<P> {
    /// The path retimed.
    pub fn path(&self) -> &P {
        &self.path
    }

    /// The path back, its timing dropped.
    pub fn into_path(self) -> P {
        self.path
    }

    /// The duration.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The runs (rest to rest) the path was cut into.
    pub fn runs(&self) -> usize {
        self.runs.len()
    }

    /// The runs' uniform slow-downs `k` (1: the averaged TOPP-RA timing kept every limit).
    pub fn scales(&self) -> impl Iterator<Item = f64> + '_ {
        self.runs.iter().map(|r| r.scale)
    }

    /// The path's own time at `t` (the configuration is the path's there).
    pub fn path_time<const D: usize>(&self, t: f64) -> f64
    where
        P: Trajectory<D>,
    {
        let (run, t) = self.locate(t);
        let [s, ..] = run.path_timing(t);
        run.tau_at(&self.path, self.nq, s)
    }

    fn locate(&self, t: f64) -> (&Run, f64) {
        let i = self
            .runs
            .partition_point(|r| r.start <= t)
            .clamp(1, self.runs.len())
            - 1;
        let r = &self.runs[i];
        (r, t - r.start)
    }

    /// Position, velocity, acceleration and jerk of the joints at `t`.
    pub fn sample<const D: usize>(&self, t: f64) -> [[f64; D]; 4]
    where
        P: Trajectory<D>,
    {
        let (run, t) = self.locate(t.clamp(0.0, self.duration));
        let [s, sd, sdd, sddd] = run.path_timing(t);
        let tau = run.tau_at(&self.path, self.nq, s);
        let mut d = [[0.0; D]; 3];
        run.arc_derivatives(&self.path, self.nq, tau, &mut d);
        let q = self.path.derivative(tau, 0);
        let (mut v, mut a, mut j) = ([0.0; D], [0.0; D], [0.0; D]);
        for m in 0..self.nq {
            v[m] = d[0][m] * sd;
            a[m] = d[0][m] * sdd + d[1][m] * sd * sd;
            j[m] = d[0][m] * sddd + 3.0 * d[1][m] * sd * sdd + d[2][m] * sd * sd * sd;
        }
        [q, v, a, j]
    }
}

impl<const D: usize, P: Trajectory<D>> Trajectory<D> for JerkRetimed<P> {
    fn duration(&self) -> f64 {
        self.duration
    }

    fn derivative(&self, t: f64, order: usize) -> [f64; D] {
        match order {
            0..=3 => self.sample(t)[order],
            _ => [0.0; D],
        }
    }

    fn sample(&self, t: f64) -> rl_core::traj::Sample<D> {
        let [position, velocity, acceleration, jerk] = JerkRetimed::sample(self, t);
        rl_core::traj::Sample {
            position,
            velocity,
            acceleration,
            jerk,
        }
    }
}

/// Calls `each(a, b, ρ)` for every sample of `run` 0.25 ms apart, with `ρ` the worst of
/// `|q̇|/V`, `(|q̈|/A)^½`, `(|q⃛|/J)^⅓` over the joints (the uniform slow-down the sample
/// needs) and `[a, b]` the TOPP-RA times its window averages; returns the worst `ρ`.
fn ratios<const D: usize, P: Trajectory<D>>(
    retimed: &JerkRetimed<P>,
    run: &Run,
    limits: &ExecutionLimits,
    mut each: impl FnMut(f64, f64, f64),
) -> f64 {
    let n = (run.duration() * SAMPLES_PER_S).ceil().max(1.0) as usize;
    let mut worst = 0.0f64;
    let mut d = [[0.0; D]; 3];
    for i in 0..=n {
        let t = run.duration() * i as f64 / n as f64;
        let [s, sd, sdd, sddd] = run.path_timing(t);
        let tau = run.tau_at(&retimed.path, retimed.nq, s);
        run.arc_derivatives(&retimed.path, retimed.nq, tau, &mut d);
        let mut rho = 0.0f64;
        for m in 0..retimed.nq {
            let v = d[0][m] * sd;
            let a = d[0][m] * sdd + d[1][m] * sd * sd;
            let j = d[0][m] * sddd + 3.0 * d[1][m] * sd * sdd + d[2][m] * sd * sd * sd;
            rho = rho
                .max(v.abs() / limits.velocity[m])
                .max((a.abs() / limits.acceleration[m]).sqrt())
                .max((j.abs() / limits.jerk[m]).cbrt());
        }
        let c = (t / run.scale).clamp(0.0, run.timing.duration() + run.window) - run.window / 2.0;
        each(c - run.window / 2.0, c + run.window / 2.0, rho);
        worst = worst.max(rho);
    }
    worst
}

/// `path` retimed with bounded jerk along its own configurations (see the module docs):
/// `rests` are the path's own times where it is at rest (its start and end included, in
/// order; [`rests_of`] finds them), `stages` TOPP-RA stages per run, `margin` added to the
/// slow-down.
pub fn jerk_limited<const D: usize, P: Trajectory<D>>(
    path: P,
    rests: &[f64],
    limits: &ExecutionLimits,
    stages: usize,
    margin: f64,
) -> Result<JerkRetimed<P>, PlanError> {
    let nq = limits.velocity.len();
    if nq > D || stages == 0 || rests.len() < 2 {
        return Err(PlanError::setting(
            "retiming",
            format!(
                "{nq} joints of {D} axes, {stages} stages, {} rests",
                rests.len()
            ),
        ));
    }
    if limits.jerk.len() != nq || limits.acceleration.len() != nq {
        return Err(PlanError::setting(
            "retiming",
            format!(
                "{nq} velocity, {} acceleration and {} jerk limits",
                limits.acceleration.len(),
                limits.jerk.len()
            ),
        ));
    }
    let rise = (0..nq)
        .map(|m| limits.acceleration[m] / limits.jerk[m])
        .fold(0.0f64, f64::max);
    let mut out = JerkRetimed {
        path,
        nq,
        runs: Vec::new(),
        duration: 0.0,
    };
    for w in rests.windows(2) {
        let (ta, tb) = (w[0], w[1]);
        if tb.is_nan() || ta.is_nan() || tb <= ta {
            continue;
        }
        let path = &out.path;
        // The arc length table: 8 points per stage.
        let m = 8 * stages;
        let tau: Vec<f64> = (0..=m)
            .map(|i| ta + (tb - ta) * i as f64 / m as f64)
            .collect();
        let mut sigma = vec![0.0; m + 1];
        for i in 1..=m {
            sigma[i] = sigma[i - 1] + arc(path, nq, tau[i - 1], tau[i]);
        }
        let length = sigma[m];
        if length <= 0.0 {
            continue;
        }
        let direction = |t: f64, h: f64| -> Vec<f64> {
            let (p0, p1) = (path.position(t), path.position(t + h));
            let d: Vec<f64> = (0..nq).map(|k| p1[k] - p0[k]).collect();
            let n = dot(&d, &d).sqrt();
            d.iter().map(|x| x / n).collect()
        };
        let h = (tb - ta) * 1e-4;
        let ends = [direction(ta, h), direction(tb - h, h)];
        let mut run = Run {
            tau,
            sigma,
            timing: Parameterization {
                grid: vec![],
                x: vec![],
                t: vec![],
            },
            integral: vec![],
            window: 0.0,
            scale: 1.0,
            start: 0.0,
            ends,
        };
        let grid: Vec<f64> = (0..=stages)
            .map(|i| length * i as f64 / stages as f64)
            .collect();
        let mut dq = Vec::with_capacity(grid.len() * nq);
        let mut ddq = Vec::with_capacity(grid.len() * nq);
        let mut d = [[0.0; D]; 3];
        for &s in &grid {
            let t = run.tau_at(path, nq, s);
            run.arc_derivatives(path, nq, t, &mut d);
            dq.extend_from_slice(&d[0][..nq]);
            ddq.extend_from_slice(&d[1][..nq]);
        }
        // TOPP-RA, averaged; where a sample needs slowing by ρ, the path speed over the
        // stretch its window averages is capped at 1/√ρ of what it was, and again.
        let mut caps = vec![f64::INFINITY; grid.len()];
        let mut best: Option<Run> = None;
        for round in 0..=REFINE {
            run.timing = topp_ra(&ToppProblem::rest_to_rest(&grid, &dq, &ddq, limits, &caps))?;
            let p = &run.timing;
            let mut integral = vec![0.0; p.t.len()];
            for i in 1..p.t.len() {
                let (v0, u) = stage(p, i - 1);
                let tau = p.t[i] - p.t[i - 1];
                integral[i] = integral[i - 1]
                    + p.grid[i - 1] * tau
                    + v0 * tau * tau / 2.0
                    + u * tau * tau * tau / 6.0;
            }
            run.integral = integral;
            if round == 0 {
                // The window: the one whose uniform slow-down gives the fastest run.
                for fraction in WINDOWS {
                    let mut r = run.clone();
                    r.window = fraction * rise;
                    r.scale = 1.0;
                    let k = ratios(&out, &r, limits, |_, _, _| {});
                    r.scale = k.max(1.0) * (1.0 + margin);
                    if best.as_ref().is_none_or(|b| r.duration() < b.duration()) {
                        best = Some(r);
                    }
                }
                run.window = best.as_ref().map_or(rise, |b| b.window);
            }
            run.scale = 1.0;
            let speeds: Vec<f64> = run.timing.speeds().collect();
            let mut next = caps.clone();
            let times = &run.timing.t;
            let k = ratios(&out, &run, limits, |a, b, rho| {
                if rho > 1.0 {
                    let i0 = times.partition_point(|t| *t < a).saturating_sub(1);
                    let i1 = times.partition_point(|t| *t <= b).min(times.len() - 1);
                    for i in i0..=i1 {
                        next[i] = next[i].min(speeds[i] / rho.sqrt());
                    }
                }
            });
            run.scale = k.max(1.0) * (1.0 + margin);
            if best.as_ref().is_none_or(|b| run.duration() < b.duration()) {
                best = Some(run.clone());
            }
            if k <= 1.0 {
                break;
            }
            caps = next;
        }
        let Some(mut best) = best else { continue };
        best.start = out.duration;
        out.duration += best.duration();
        out.runs.push(best);
    }
    if out.runs.is_empty() {
        return Err(PlanError::setting("retiming", "the path does not move"));
    }
    Ok(out)
}

/// The times where a piecewise trajectory is at rest: its start, its end, and the segment
/// boundaries where its first `nq` velocities are all zero (to 1e-12 of its largest speed).
pub fn rests_of<const D: usize, S, const MAX: usize>(
    path: &rl_core::traj::Piecewise<S, MAX>,
    nq: usize,
) -> Vec<f64>
where
    rl_core::traj::Piecewise<S, MAX>: Trajectory<D>,
{
    let duration = path.duration();
    let peak = (0..=1000)
        .map(|i| speed(path, nq, duration * i as f64 / 1000.0))
        .fold(0.0f64, f64::max);
    let mut rests = vec![0.0];
    for &t in path.starts().iter().skip(1) {
        if t < duration && speed(path, nq, t) <= 1e-12 * peak {
            rests.push(t);
        }
    }
    rests.push(duration);
    rests
}
