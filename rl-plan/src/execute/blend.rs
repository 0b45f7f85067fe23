//! A planned path executed without stopping at its interior waypoints: straight lines at
//! constant velocity joined by jerk-continuous blends, started and ended by jerk-limited speed
//! ramps, each line, blend and ramp timed so that
//! every joint stays within its velocity, acceleration and jerk limits, and the result checked
//! for collisions — blends leave the checked segments — with blends shrunk, or replaced by a
//! stop, where they collide.
//!
//! # Construction
//!
//! Craig's linear segments with blends (J. J. Craig, *Introduction to Robotics*, 3rd ed.,
//! §7.3, "linear function with parabolic blends" through via points; RL's `LinearParabolic`;
//! rl-core's [`linear_with_blends`](rl_core::traj::spline::linear_with_blends)), with three
//! changes: the blend at an interior waypoint is the sextic of rl-core's
//! [`BlendShape::Sextic`](rl_core::traj::BlendShape) (velocity `va + (vb − va)·σ(τ/tb)`,
//! `σ(s) = 10s³ − 15s⁴ + 6s⁵`, so acceleration and jerk are zero at both ends of a blend and
//! the trajectory is C³ through the corners); the blends from and to rest, which stay on the
//! first and last segment, are the time-optimal jerk-limited speed ramp (jerk, constant
//! acceleration, jerk: Biagiotti & Melchiorri, *Trajectory Planning for Automatic Machines and
//! Robots*, 2008, §3.4, applied to the fraction of the line's velocity, so C² with jerk steps
//! there, as rl-core's [`JerkLimited`] moves have); and every line and every blend gets its own
//! duration from the limits (rl-core's function takes one blend rule for all).
//!
//! For the waypoints `p_0 … p_m` of a *run* (a stretch between two stops), `d_i = p_{i+1} − p_i`
//! (`nq` numbers, circles unwrapped), line `i` has velocity `v_i = d_i / τ_i` and passes `p_i`
//! and `p_{i+1}` `τ_i` seconds apart; the blend at `p_j` lasts `b_j`, is centred on the instant
//! the lines pass `p_j` and takes the velocity from `v_{j−1}` to `v_j` (`v_{−1} = v_m = 0`: the
//! run starts and ends at rest, exactly at `p_0` and `p_m`). Per joint `k`, with
//! `Δ_k = |v_{j,k} − v_{j−1,k}|` and the limits `(V_k, A_k, J_k)`:
//!
//! - velocity: `τ_i ≥ max_k |d_{i,k}| / V_k` (a blend's velocity lies between its lines');
//! - acceleration: `b_j ≥ max_k 1.875·Δ_k / A_k` (`max σ' = 15/8`);
//! - jerk: `b_j ≥ max_k √(5.7735·Δ_k / J_k)` (`max |σ''| = 10/√3`);
//! - at the run's ends, the ramp to `v` with `A = min_k A_k/|v_k|`, `J = min_k J_k/|v_k|`:
//!   `b = 1/A + A/J` when `A²/J ≤ 1`, else `2/√J` (its speed profile is symmetric too, so it
//!   covers `b/2` times `v`, as a blend does);
//! - room: `τ_i ≥ (b_i + b_{i+1}) / 2` (neighbouring blends do not overlap).
//!
//! `b_j` is the smallest that meets its bounds; the lines start at their speed bound and a
//! line whose room is short is slowed (its `τ_i` raised, which lowers the velocity changes at
//! its ends) until every line has room: a monotone fixed-point iteration that ends because
//! every blend is bounded by the one for velocities at the limits. The run lasts
//! `Σ τ_i + (b_0 + b_m)/2`. A blend lies in the triangle of its two end points and the corner
//! (`σ` is increasing and symmetric), so per joint it stays between the waypoint and its
//! neighbours: within the bounds of the space.
//!
//! This is **not time-optimal**: lines keep one speed from blend to blend (a segment is not
//! sped up between two sharp corners, nor slowed only near a corner), and a corner's blend
//! duration is set by its largest velocity change. A run of one segment is rl-core's
//! time-optimal [`JerkLimited`] move, as the stop-at-every-waypoint execution
//! ([`Execution::trajectory`]) makes it, and a run whose blended timing is
//! not shorter than stopping at each of its waypoints stops at each of them. Time-optimal
//! path following (Kunz & Stilman, RSS 2012; TOPP-RA, Pham & Pham, IEEE T-RO 2018) handles
//! acceleration limits but not jerk.
//!
//! # Collision check
//!
//! Every segment of the result (lines and blends, and the moves of stopped runs) is sampled in
//! time so that consecutive samples are at most [`BlendOptions::check_step`] apart in the
//! space's metric (the step is derived from each segment's exact peak speed, and the distance
//! between consecutive samples is measured, the step halved until it holds), and every sample
//! is given to the [`Validity`] checker (circles wrapped into `[−π, π)`). Where a sample in a
//! blend is invalid, the speeds of the two lines at that waypoint are capped at half their
//! previous cap (a blend's deviation from the corner scales with `v²` when acceleration bounds
//! it and `v^1.5` when jerk does) and the run is timed and checked again, at most
//! [`BlendOptions::shrinks`] times; then the run stops at that waypoint and is split there (as
//! it does at once when a shrunk run is no longer faster than stopping at each of its
//! waypoints). An invalid sample on a line, a ramp or a move at rest lies on the path's own
//! straight segments: the
//! path is not valid for this checker at this resolution, and that is an error. No trajectory
//! is returned that was not checked.
//!
//! Capacity: a run of `m ≥ 2` segments gives at most `2m + 5` trajectory segments (`m` lines,
//! `m − 1` blends, two ramps of up to three pieces; lines with no room left are dropped), a
//! run of one segment one move, so a path of `n` segments needs at most `5n` (`2n + 5` when
//! nothing is stopped at). More is
//! [`PlanError::Unsupported`].
//!
//! Cost: `O(iterations · n · nq)` for the timing, one validity check per sample. Allocates
//! (it runs before the motion, not in the control loop); the trajectory it returns evaluates
//! without allocating.

use rl_core::traj::{JerkLimited, Piecewise, Polynomial, Segment, Trajectory};

use super::{Execution, ExecutionLimits, synchronized_move};
use crate::error::PlanError;
use crate::space::JointSpace;
use crate::validity::Validity;

/// `max σ'` of the sextic blend: its peak acceleration is `|Δv| / tb` times this.
pub const SEXTIC_PEAK_ACCELERATION: f64 = 1.875;
/// `max |σ''|` of the sextic blend (`10/√3`, at `s = (3 ± √3)/6`): its peak jerk is
/// `|Δv| / tb²` times this.
pub const SEXTIC_PEAK_JERK: f64 = 5.773_502_691_896_258;

/// Coefficients of `Σ(s) = ∫₀ˢ σ = 2.5s⁴ − 3s⁵ + s⁶` (powers 0 to 6).
const SEXTIC_INTEGRAL: [f64; 7] = [0.0, 0.0, 0.0, 0.0, 2.5, -3.0, 1.0];

/// Most iterations of the timing's fixed point (each raises a line's time by at least 1 %).
const MAX_TIMING_ITERATIONS: usize = 100_000;

/// Most samples of one trajectory segment (a finer step is refused, not attempted).
const MAX_SAMPLES_PER_SEGMENT: usize = 10_000_000;

/// How the blended execution is checked and shrunk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendOptions {
    /// Largest distance, in the space's metric, between consecutive checked samples: a tenth
    /// of the planner's collision resolution ([`BlendOptions::for_resolution`]).
    pub check_step: f64,
    /// How many times a colliding blend is shrunk (the speeds at its waypoint halved) before
    /// the trajectory stops at that waypoint instead.
    pub shrinks: u32,
}

impl BlendOptions {
    /// Samples a tenth of `resolution` (the planner's edge resolution) apart, three shrinks.
    pub fn for_resolution(resolution: f64) -> Self {
        Self {
            check_step: resolution / 10.0,
            shrinks: 3,
        }
    }
}

/// Why the trajectory stops at an interior waypoint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// Every blend tried there (the last after the allowed shrinks) was invalid.
    Collision,
    /// Blending the run was not faster than stopping at each of its waypoints.
    NotFaster,
}

/// What the trajectory does at one interior waypoint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WaypointOutcome {
    /// Passed through a blend, after `shrinks` shrinks (0: the full blend).
    Blended {
        /// Times the blend was shrunk before it passed the check.
        shrinks: u32,
    },
    /// Stopped at.
    Stopped(StopReason),
}

/// What the blended execution did.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendReport {
    /// One outcome per interior waypoint, in path order (repeated waypoints merged).
    pub waypoints: Vec<WaypointOutcome>,
    /// The trajectory's duration, s.
    pub duration_s: f64,
    /// The duration when stopping at every waypoint ([`Execution::trajectory`]), s.
    pub stop_duration_s: f64,
    /// Configurations given to the validity checker.
    pub checks: u64,
    /// The sampling step used, in the space's metric.
    pub check_step: f64,
}

impl BlendReport {
    /// Interior waypoints passed through a blend.
    pub fn blended(&self) -> usize {
        self.waypoints
            .iter()
            .filter(|w| matches!(w, WaypointOutcome::Blended { .. }))
            .count()
    }

    /// Of those, the blends that were shrunk to pass the check.
    pub fn shrunk(&self) -> usize {
        self.waypoints
            .iter()
            .filter(|w| matches!(w, WaypointOutcome::Blended { shrinks } if *shrinks > 0))
            .count()
    }

    /// Interior waypoints stopped at (for any reason).
    pub fn stopped(&self) -> usize {
        self.waypoints.len() - self.blended()
    }

    /// Interior waypoints stopped at because every blend there collided.
    pub fn stopped_for_collision(&self) -> usize {
        self.waypoints
            .iter()
            .filter(|w| **w == WaypointOutcome::Stopped(StopReason::Collision))
            .count()
    }
}

impl core::fmt::Display for BlendReport {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "blended through {} of {} interior waypoints ({} shrunk), stopped at {} ({} for \
             collision), {:.3} s (stopping at every waypoint: {:.3} s), {} configurations \
             checked {:.4} apart",
            self.blended(),
            self.waypoints.len(),
            self.shrunk(),
            self.stopped(),
            self.stopped_for_collision(),
            self.duration_s,
            self.stop_duration_s,
            self.checks,
            self.check_step
        )
    }
}

/// A blended trajectory and what was done to make it.
#[derive(Clone, Debug)]
pub struct Blended<const D: usize, const MAX: usize> {
    /// The trajectory (axes beyond the space's coordinates stay at 0), on the heap: at 8 axes
    /// and 165 segments it is about 233 KB, too big to pass around on a thread's stack.
    pub trajectory: Box<Piecewise<Segment<D>, MAX>>,
    /// Blended and stopped waypoints, durations, checks.
    pub report: BlendReport,
}

/// Where a piece of a run came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Origin {
    /// The blend at run waypoint `j`.
    Blend(usize),
    /// The line of run segment `i`, or a move at rest along it.
    Segment(usize),
}

impl Execution {
    /// The trajectory that blends through the interior waypoints where that is valid and
    /// faster, checked with `validity` (see the module docs): `D ≥ nq` axes, at most `MAX`
    /// segments (`5·(waypoints − 1)` always suffice).
    pub fn blended<const D: usize, const MAX: usize>(
        &self,
        space: &JointSpace,
        validity: &mut dyn Validity,
        options: &BlendOptions,
    ) -> Result<Blended<D, MAX>, PlanError> {
        let n = self.limits.velocity.len();
        if n > D {
            return Err(PlanError::Unsupported(format!(
                "{n} joints in a trajectory of {D} axes"
            )));
        }
        if space.nq() != n {
            return Err(PlanError::setting(
                "space",
                format!("{} coordinates for {n} joints", space.nq()),
            ));
        }
        if !(options.check_step > 0.0 && options.check_step.is_finite()) {
            return Err(PlanError::setting(
                "check step",
                format!("{} is not a positive distance", options.check_step),
            ));
        }
        let checks_before = validity.checks();
        let mut points: Vec<&[f64]> = Vec::with_capacity(self.waypoints.len());
        for w in &self.waypoints {
            if points.last().is_none_or(|p| *p != &w[..]) {
                points.push(w);
            }
        }
        let segments = points.len().saturating_sub(1);
        let interior = segments.saturating_sub(1);
        let mut outcome = vec![WaypointOutcome::Blended { shrinks: 0 }; points.len()];
        let mut cap = vec![1.0f64; points.len()];
        let mut stop_duration = 0.0;
        let mut moves: Vec<Option<JerkLimited<D>>> = Vec::with_capacity(segments);
        for w in points.windows(2) {
            let m = synchronized_move::<D>(w[0], w[1], &self.limits)?;
            stop_duration += m.as_ref().map_or(0.0, |m| m.duration());
            moves.push(m);
        }
        let mut checker = Checker {
            space,
            validity,
            step: options.check_step,
            n,
            q: vec![0.0; n],
            prev: vec![0.0; n],
        };
        // Runs still to do (first and last waypoint), and the pieces of runs done.
        let mut todo = if segments > 0 {
            vec![(0, segments)]
        } else {
            vec![]
        };
        let mut done: Vec<(usize, Vec<Segment<D>>)> = Vec::new();
        while let Some((first, last)) = todo.pop() {
            let stops = || -> Vec<(usize, Vec<Segment<D>>)> {
                (first..last)
                    .map(|i| {
                        (
                            i,
                            moves[i].iter().map(|m| Segment::JerkLimited(*m)).collect(),
                        )
                    })
                    .collect()
            };
            if last - first == 1 {
                let pieces = stops();
                checker.check_run(&pieces[0].1, &[Origin::Segment(0)], first, 1)?;
                done.extend(pieces);
                continue;
            }
            loop {
                let run = &points[first..=last];
                let caps = &cap[first..=last];
                let (pieces, origins, duration) = blended_run::<D>(run, caps, &self.limits)?;
                let at_rest: f64 = moves[first..last]
                    .iter()
                    .flatten()
                    .map(|m| m.duration())
                    .sum();
                if duration >= at_rest {
                    // Slower than stopping: where a blend was shrunk for a collision, stop
                    // there instead and try the rest; otherwise stop at every waypoint.
                    let shrunk = (first + 1..last)
                        .filter(|&w| matches!(outcome[w], WaypointOutcome::Blended { shrinks } if shrinks > 0))
                        .max_by(|&a, &b| cap[b].total_cmp(&cap[a]));
                    if let Some(w) = shrunk {
                        outcome[w] = WaypointOutcome::Stopped(StopReason::Collision);
                        todo.push((first, w));
                        todo.push((w, last));
                        break;
                    }
                    for o in &mut outcome[first + 1..last] {
                        *o = WaypointOutcome::Stopped(StopReason::NotFaster);
                    }
                    for (i, p) in stops() {
                        checker.check_run(&p, &[Origin::Segment(0)], i, 1)?;
                        done.push((i, p));
                    }
                    break;
                }
                match checker.check_run(&pieces, &origins, first, last - first)? {
                    None => {
                        done.push((first, pieces));
                        break;
                    }
                    Some(j) => {
                        let w = first + j;
                        let shrinks = match outcome[w] {
                            WaypointOutcome::Blended { shrinks } => shrinks,
                            WaypointOutcome::Stopped(_) => options.shrinks,
                        };
                        if shrinks < options.shrinks {
                            cap[w] *= 0.5;
                            outcome[w] = WaypointOutcome::Blended {
                                shrinks: shrinks + 1,
                            };
                        } else {
                            outcome[w] = WaypointOutcome::Stopped(StopReason::Collision);
                            todo.push((first, w));
                            todo.push((w, last));
                            break;
                        }
                    }
                }
            }
        }
        done.sort_by_key(|(first, _)| *first);
        let mut trajectory = Box::new(Piecewise::new());
        for piece in done.into_iter().flat_map(|(_, p)| p) {
            trajectory.push(piece).map_err(|_| {
                PlanError::Unsupported(format!(
                    "a blended trajectory of more than {MAX} segments (a path of {segments} \
                     segments needs up to {}; simplify it or stop at every waypoint)",
                    5 * segments
                ))
            })?;
        }
        let report = BlendReport {
            waypoints: if interior > 0 {
                outcome[1..=interior].to_vec()
            } else {
                Vec::new()
            },
            duration_s: trajectory.duration(),
            stop_duration_s: stop_duration,
            checks: checker.validity.checks() - checks_before,
            check_step: options.check_step,
        };
        Ok(Blended { trajectory, report })
    }
}

/// Velocity of each line of a run, with the lines' times `tau`.
fn velocities(run: &[&[f64]], tau: &[f64], n: usize) -> Vec<Vec<f64>> {
    (0..tau.len())
        .map(|i| {
            (0..n)
                .map(|k| (run[i + 1][k] - run[i][k]) / tau[i])
                .collect()
        })
        .collect()
}

/// The shortest sextic blend from `va` to `vb` within the acceleration and jerk limits.
fn blend_time(va: Option<&[f64]>, vb: Option<&[f64]>, limits: &ExecutionLimits) -> f64 {
    let mut b: f64 = 0.0;
    for k in 0..limits.velocity.len() {
        let dv = (vb.map_or(0.0, |v| v[k]) - va.map_or(0.0, |v| v[k])).abs();
        b = b
            .max(SEXTIC_PEAK_ACCELERATION * dv / limits.acceleration[k])
            .max((SEXTIC_PEAK_JERK * dv / limits.jerk[k]).sqrt());
    }
    b
}

/// Times the lines and blends of one run (`caps`: the speed cap at each of its waypoints, a
/// fraction of the limits; its ends are ignored) and builds its pieces: blend, line, blend, …,
/// blend. Returns the pieces, where each came from, and the run's duration.
#[allow(clippy::type_complexity)]
fn blended_run<const D: usize>(
    run: &[&[f64]],
    caps: &[f64],
    limits: &ExecutionLimits,
) -> Result<(Vec<Segment<D>>, Vec<Origin>, f64), PlanError> {
    let n = limits.velocity.len();
    let m = run.len() - 1;
    let cap = |j: usize| if j == 0 || j == m { 1.0 } else { caps[j] };
    let mut tau: Vec<f64> = (0..m)
        .map(|i| {
            let c = cap(i).min(cap(i + 1));
            (0..n)
                .map(|k| (run[i + 1][k] - run[i][k]).abs() / (c * limits.velocity[k]))
                .fold(0.0, f64::max)
        })
        .collect();
    let mut b = vec![0.0; m + 1];
    let mut settled = false;
    for _ in 0..MAX_TIMING_ITERATIONS {
        let v = velocities(run, &tau, n);
        for j in 0..=m {
            let va = if j > 0 { Some(&v[j - 1][..]) } else { None };
            let vb = if j < m { Some(&v[j][..]) } else { None };
            b[j] = match (va, vb) {
                (Some(va), Some(vb)) => blend_time(Some(va), Some(vb), limits),
                (None, Some(v)) | (Some(v), None) => Ramp::new(v, limits).duration(),
                (None, None) => 0.0,
            };
        }
        settled = true;
        for i in 0..m {
            let need = 0.5 * (b[i] + b[i + 1]);
            if tau[i] < need * (1.0 - 1e-12) {
                tau[i] = (tau[i] * 1.01).max(need);
                settled = false;
            }
        }
        if settled {
            break;
        }
    }
    if !settled {
        return Err(PlanError::setting(
            "blended trajectory",
            format!("the timing did not settle in {MAX_TIMING_ITERATIONS} iterations"),
        ));
    }
    let v = velocities(run, &tau, n);
    let zero = vec![0.0; n];
    let mut pieces = Vec::with_capacity(2 * m + 1);
    let mut origins = Vec::with_capacity(2 * m + 1);
    let err = |e: rl_core::traj::TrajectoryError| PlanError::setting("trajectory", e.to_string());
    for j in 0..=m {
        let va = if j > 0 { &v[j - 1] } else { &zero };
        let vb = if j < m { &v[j] } else { &zero };
        if (j == 0 || j == m) && b[j] > 0.0 {
            // From or to rest along the line: the jerk-limited speed ramp, which also covers
            // b/2 times the line's velocity.
            let v = if j == 0 { vb } else { va };
            let ramp = Ramp::new(v, limits);
            let from = if j == 0 {
                run[0].to_vec()
            } else {
                (0..n).map(|k| run[m][k] - 0.5 * b[m] * v[k]).collect()
            };
            for piece in ramp.pieces::<D>(&from, v, j == 0)? {
                pieces.push(piece);
                origins.push(Origin::Blend(j));
            }
        } else if b[j] > 0.0 {
            // The blend starts on the incoming line, b/2 before it passes the waypoint:
            // p(t) = p0 + va·t + (vb − va)·b·Σ(t/b).
            let mut c = [[0.0; D]; 7];
            for k in 0..n {
                c[0][k] = run[j][k] - 0.5 * b[j] * va[k];
                c[1][k] = va[k];
            }
            let mut scale = 1.0; // b / b^power
            for (power, g) in SEXTIC_INTEGRAL.iter().enumerate().skip(2) {
                scale /= b[j];
                for k in 0..n {
                    c[power][k] = (vb[k] - va[k]) * g * scale;
                }
            }
            pieces.push(Segment::Polynomial(Polynomial::new(c, b[j]).map_err(err)?));
            origins.push(Origin::Blend(j));
        }
        if j < m {
            let line = tau[j] - 0.5 * (b[j] + b[j + 1]);
            if line > 0.0 {
                let mut c = [[0.0; D]; 7];
                for k in 0..n {
                    c[0][k] = run[j][k] + 0.5 * b[j] * vb[k];
                    c[1][k] = vb[k];
                }
                pieces.push(Segment::Polynomial(Polynomial::new(c, line).map_err(err)?));
                origins.push(Origin::Segment(j));
            }
        }
    }
    let duration = tau.iter().sum::<f64>() + 0.5 * (b[0] + b[m]);
    Ok((pieces, origins, duration))
}

/// A speed ramp along a line from rest to velocity `v` (or from `v` to rest): the time-optimal
/// jerk-limited profile of the fraction `ρ ∈ [0, 1]` of `v` (jerk `+J`, acceleration `A`,
/// jerk `−J`; Biagiotti & Melchiorri §3.4 for a velocity change), with `A = min_k A_k / |v_k|`
/// and `J = min_k J_k / |v_k|` so every joint keeps its own limits. `ρ` is symmetric about the
/// middle, so the ramp covers `T/2` times `v`, as the sextic blend does.
#[derive(Clone, Copy, Debug)]
struct Ramp {
    /// Jerk phases' length, s.
    t_jerk: f64,
    /// Constant-acceleration phase's length, s.
    t_accel: f64,
    /// Jerk of `ρ`, 1/s³.
    jerk: f64,
}

impl Ramp {
    fn new(v: &[f64], limits: &ExecutionLimits) -> Self {
        let (mut a, mut j) = (f64::INFINITY, f64::INFINITY);
        for (k, vk) in v.iter().enumerate() {
            if *vk != 0.0 {
                a = a.min(limits.acceleration[k] / vk.abs());
                j = j.min(limits.jerk[k] / vk.abs());
            }
        }
        if !a.is_finite() {
            return Self {
                t_jerk: 0.0,
                t_accel: 0.0,
                jerk: 0.0,
            };
        }
        if a * a / j <= 1.0 {
            Self {
                t_jerk: a / j,
                t_accel: 1.0 / a - a / j,
                jerk: j,
            }
        } else {
            Self {
                t_jerk: 1.0 / j.sqrt(),
                t_accel: 0.0,
                jerk: j,
            }
        }
    }

    fn duration(&self) -> f64 {
        2.0 * self.t_jerk + self.t_accel
    }

    /// The ramp's polynomial pieces from `from`: up (rest to `v`) or down (`v` to rest).
    fn pieces<const D: usize>(
        &self,
        from: &[f64],
        v: &[f64],
        up: bool,
    ) -> Result<Vec<Segment<D>>, PlanError> {
        let sign = if up { 1.0 } else { -1.0 };
        let phases = [
            (self.t_jerk, sign * self.jerk),
            (self.t_accel, 0.0),
            (self.t_jerk, -sign * self.jerk),
        ];
        // State of the path fraction: distance s (in units of v·s), speed ρ, acceleration.
        let (mut dist, mut rho, mut acc) = (0.0, if up { 0.0 } else { 1.0 }, 0.0);
        let mut out = Vec::with_capacity(3);
        for (length, jerk) in phases {
            if length <= 0.0 {
                continue;
            }
            let mut c = [[0.0; D]; 7];
            for k in 0..v.len() {
                c[0][k] = from[k] + v[k] * dist;
                c[1][k] = v[k] * rho;
                c[2][k] = v[k] * acc / 2.0;
                c[3][k] = v[k] * jerk / 6.0;
            }
            out.push(Segment::Polynomial(
                Polynomial::new(c, length)
                    .map_err(|e| PlanError::setting("trajectory", e.to_string()))?,
            ));
            dist += length * (rho + length * (acc / 2.0 + length * jerk / 6.0));
            rho += length * (acc + length * jerk / 2.0);
            acc += length * jerk;
        }
        Ok(out)
    }
}

/// Samples trajectory segments and asks the validity checker.
struct Checker<'a> {
    space: &'a JointSpace,
    validity: &'a mut dyn Validity,
    step: f64,
    n: usize,
    q: Vec<f64>,
    prev: Vec<f64>,
}

impl Checker<'_> {
    /// Checks the pieces of a run of `m` segments whose first path segment is `first`, blends
    /// first (they are the ones that leave the path). `Ok(Some(j))`: the blend at the run's
    /// interior waypoint `j` is invalid. An invalid line, end blend or move lies on the path's
    /// own segments: an error.
    fn check_run<const D: usize>(
        &mut self,
        pieces: &[Segment<D>],
        origins: &[Origin],
        first: usize,
        m: usize,
    ) -> Result<Option<usize>, PlanError> {
        let is_blend = |i: &usize| matches!(origins[*i], Origin::Blend(_));
        let order = (0..pieces.len())
            .filter(is_blend)
            .chain((0..pieces.len()).filter(|i| !is_blend(i)));
        for i in order {
            if let Some(t) = self.invalid_at(&pieces[i])? {
                return match origins[i] {
                    Origin::Blend(j) if j > 0 && j < m => Ok(Some(j)),
                    Origin::Blend(j) => Err(self.on_path(first + j.min(m - 1), t)),
                    Origin::Segment(s) => Err(self.on_path(first + s, t)),
                };
            }
        }
        Ok(None)
    }

    fn on_path(&self, segment: usize, t: f64) -> PlanError {
        PlanError::setting(
            "trajectory",
            format!(
                "the path itself is invalid for this checker near segment {segment} (a sample \
                 {t:.4} s into its motion, checked every {} in the space's metric): plan with \
                 a finer resolution",
                self.step
            ),
        )
    }

    /// The local time of the first invalid sample of `piece`, if any.
    fn invalid_at<const D: usize>(&mut self, piece: &Segment<D>) -> Result<Option<f64>, PlanError> {
        let duration = piece.duration();
        let peak = match piece {
            Segment::Polynomial(p) => p.max_abs_derivative(1),
            Segment::JerkLimited(m) => m.sample(0.5 * duration).velocity.map(f64::abs),
        };
        let speed = self
            .space
            .coordinates()
            .iter()
            .zip(&peak)
            .map(|(c, v)| (c.weight * v) * (c.weight * v))
            .sum::<f64>()
            .sqrt();
        let mut count = ((duration * speed / self.step).ceil() as usize).max(1);
        'refine: loop {
            if count > MAX_SAMPLES_PER_SEGMENT {
                return Err(PlanError::setting(
                    "check step",
                    format!(
                        "{} would need more than {MAX_SAMPLES_PER_SEGMENT} samples in one \
                         trajectory segment",
                        self.step
                    ),
                ));
            }
            let samples = count;
            for i in 0..=samples {
                let t = duration * i as f64 / samples as f64;
                let p = piece.position(t);
                self.q.copy_from_slice(&p[..self.n]);
                self.space.normalize(&mut self.q);
                if i > 0 && self.space.distance(&self.prev, &self.q) > self.step {
                    // The bound from the peak speed was not enough (weights, wrapping):
                    // twice as many samples.
                    count *= 2;
                    continue 'refine;
                }
                if !self.validity.is_valid(&self.q) {
                    return Ok(Some(t));
                }
                std::mem::swap(&mut self.q, &mut self.prev);
            }
            return Ok(None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::Path;
    use crate::space::Topology;
    use crate::validity::AlwaysValid;

    fn plane() -> JointSpace {
        let i = Topology::Interval {
            lower: -5.0,
            upper: 5.0,
        };
        JointSpace::new(vec![("x".into(), i), ("y".into(), i)]).unwrap()
    }

    fn limits() -> ExecutionLimits {
        ExecutionLimits {
            velocity: vec![1.0, 1.0],
            acceleration: vec![2.0, 2.0],
            jerk: vec![100.0, 100.0],
        }
    }

    /// `path` in `space` under [`limits`], blended with nothing in the way (resolution 0.1).
    fn blend_in_plane(space: &JointSpace, path: &Path) -> Blended<2, 16> {
        Execution::new(space, path, limits())
            .unwrap()
            .blended::<2, 16>(
                space,
                &mut AlwaysValid::new(space.clone()),
                &BlendOptions::for_resolution(0.1),
            )
            .unwrap()
    }

    /// A right-angle corner with long legs: the blend at the corner lasts `1.875 · 1 / 2` s
    /// (acceleration-bound: the velocity of each joint changes by 1), the ramps from and to
    /// rest `1/A + A/J = 0.52` s, the lines run at the speed limit, and the run lasts
    /// `Σ τ + 0.52` with `τ = 2 s` per leg. Continuous in acceleration everywhere, in jerk
    /// across the corner.
    #[test]
    fn a_right_angle_corner_by_hand() {
        let space = plane();
        let path = Path::from_points(2, &[vec![0.0, 0.0], vec![2.0, 0.0], vec![2.0, 2.0]]);
        let b = blend_in_plane(&space, &path);
        let tb = 1.875 * 1.0 / 2.0;
        assert!(
            (b.report.duration_s - (2.0 + 2.0 + 0.52)).abs() < 1e-12,
            "{}",
            b.report
        );
        // Ramp (3 pieces), line, corner blend, line, ramp (3).
        assert_eq!(b.trajectory.len(), 9);
        assert_eq!(
            b.report.waypoints,
            vec![WaypointOutcome::Blended { shrinks: 0 }]
        );
        b.trajectory.check_continuity(2, 1e-9).unwrap();
        let corner = &b.trajectory.segments()[3..6];
        for pair in corner.windows(2) {
            let (l, r) = (
                pair[0].derivative(pair[0].duration(), 3),
                pair[1].derivative(0.0, 3),
            );
            assert!((l[0] - r[0]).abs() < 1e-9 && (l[1] - r[1]).abs() < 1e-9);
        }
        // Halfway through the corner blend, the widest point: the corner plus
        // Δv·tb·Σ(½) = (−1, 1)·tb·5/64; the lines pass the corner 0.26 + 2 s in.
        let mid = b.trajectory.position(0.26 + 2.0);
        let off = tb * 5.0 / 64.0;
        assert!((mid[0] - (2.0 - off)).abs() < 1e-12 && (mid[1] - off).abs() < 1e-12);
    }

    /// Collinear waypoints: the blend only changes the speed, so the trajectory stays on the
    /// line and does not stop.
    #[test]
    fn collinear_waypoints_are_passed_on_the_line() {
        let space = plane();
        let path = Path::from_points(
            2,
            &[
                vec![0.0, 0.0],
                vec![0.1, 0.05],
                vec![3.0, 1.5],
                vec![3.2, 1.6],
            ],
        );
        let b = blend_in_plane(&space, &path);
        assert_eq!(b.report.blended(), 2, "{}", b.report);
        assert!(b.report.duration_s < b.report.stop_duration_s);
        let mut t = 0.0;
        while t < b.trajectory.duration() {
            let s = b.trajectory.sample(t);
            assert!(
                (s.position[1] - 0.5 * s.position[0]).abs() < 1e-12,
                "off the line"
            );
            if t > 0.1 && t < b.trajectory.duration() - 0.1 {
                assert!(s.velocity[0] > 0.0, "stopped at t={t}");
            }
            t += 1e-3;
        }
    }
}
