//! Time-optimal path parameterisation by reachability analysis (TOPP-RA): the fastest timing
//! `s(t)` of a geometric path `q(s)` under per-joint velocity and acceleration limits.
//!
//! # Formulation
//!
//! H. Pham and Q.-C. Pham, "A New Approach to Time-Optimal Path Parameterization Based on
//! Reachability Analysis", IEEE T-RO 34(3), 2018. Along a path `q(s)`, `s ∈ [0, L]`, with
//! `x = ṡ²` and `u = s̈`, the joint velocity and acceleration are `q̇ = q'(s)·ṡ` and
//! `q̈ = q'(s)·u + q''(s)·x`, so the limits `|q̇_k| ≤ V_k`, `|q̈_k| ≤ A_k` are
//!
//! - `x ≤ (V_k / q'_k)²` (a bound on `x` alone), and
//! - `−A_k ≤ q'_k·u + q''_k·x ≤ A_k` (linear in `(x, u)`),
//!
//! for every joint `k`. On the grid `0 = s_0 < … < s_N = L` with `Δ_i = s_{i+1} − s_i` and `u`
//! constant on each interval, `x_{i+1} = x_i + 2Δ_i·u_i`. The acceleration constraints of stage
//! `i` hold at `s_i` and, in the *interpolation* scheme (TOPP-RA's and PyPI `toppra`'s default
//! for joint accelerations), also at `s_{i+1}` with `x_{i+1}` written in `(x_i, u_i)`; in the
//! *collocation* scheme at `s_i` only.
//!
//! 1. Backward pass: the controllable sets `K_N = {x_N}` and `K_i` = the `x` of stage `i` from
//!    which some admissible `u` reaches `K_{i+1}`. Each is an interval, the projection onto `x`
//!    of a polygon in `(x, u)`: solved exactly by pairing every lower bound on `u` with every
//!    upper bound (each pair is a bound on `x`), `O(m²)` for `m` constraints.
//! 2. Forward pass: from `x_0`, the greatest admissible `u_i` that keeps `x_{i+1}` in
//!    `K_{i+1}` (a bound per constraint, `O(m)`).
//!
//! The result is time-optimal for the discretised problem (the greedy forward pass over
//! controllable sets is, Pham & Pham's Theorem 2); the timing between grid points has
//! constant `s̈`, so `t_{i+1} − t_i = 2Δ_i / (ṡ_i + ṡ_{i+1})`. Between grid points the limits
//! hold to `O(Δ)` (the interpolation scheme's error is of second order, the paper's §V).
//!
//! Dimensions: `grid` has `N + 1` points; `dq`, `ddq` hold `N + 1` rows of `nq` numbers
//! (`q'(s_i)`, `q''(s_i)`), row-major. Cost: `O(N·nq²)` time, `O(N)` memory. Deterministic: no
//! iteration count depends on the input beyond `N`. Jerk is not bounded here (TOPP-RA's
//! profile is bang-bang in `s̈`).

use crate::error::PlanError;

/// Where the acceleration constraints of a stage hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Discretization {
    /// At the stage's grid point only.
    Collocation,
    /// At the stage's grid point and the next (TOPP-RA's and `toppra`'s default).
    #[default]
    Interpolation,
}

/// The limits and the path's end speeds.
#[derive(Clone, Debug, PartialEq)]
pub struct ToppProblem<'a> {
    /// The grid `s_0 < … < s_N`.
    pub grid: &'a [f64],
    /// `q'(s_i)`, `N + 1` rows of `nq`.
    pub dq: &'a [f64],
    /// `q''(s_i)`, `N + 1` rows of `nq`.
    pub ddq: &'a [f64],
    /// Velocity limit per joint (positive; infinite: none).
    pub velocity: &'a [f64],
    /// Acceleration limit per joint (positive; infinite: none).
    pub acceleration: &'a [f64],
    /// `ṡ` at the start and at the end (0: at rest).
    pub start_speed: f64,
    /// See [`start_speed`](Self::start_speed).
    pub end_speed: f64,
    /// Where the acceleration constraints hold.
    pub discretization: Discretization,
    /// Caps on `ṡ` per grid point (empty: none), on top of the velocity limits.
    pub speed_cap: &'a [f64],
}

/// The time-optimal timing of the grid: `ṡ` at each grid point and the time it is reached.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameterization {
    pub(super) grid: Vec<f64>,
    /// `ṡ²` at each grid point.
    pub(super) x: Vec<f64>,
    /// The time at each grid point.
    pub(super) t: Vec<f64>,
}

/// One linear constraint `alpha·x + beta·u ≤ gamma` of a stage.
#[derive(Clone, Copy, Debug)]
struct Half {
    alpha: f64,
    beta: f64,
    gamma: f64,
}

/// Slack for rounding: a bound this far violated counts as met.
const EPS: f64 = 1e-10;

impl Parameterization {
    /// The path's duration.
    pub fn duration(&self) -> f64 {
        self.t.last().copied().unwrap_or(0.0)
    }

    /// The grid.
    pub fn grid(&self) -> &[f64] {
        &self.grid
    }

    /// `ṡ` at each grid point.
    pub fn speeds(&self) -> impl Iterator<Item = f64> + '_ {
        self.x.iter().map(|x| x.max(0.0).sqrt())
    }

    /// The time at each grid point.
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// `(s, ṡ, s̈)` at time `t` (clamped to `[0, duration]`).
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        let n = self.t.len();
        if n < 2 {
            return (self.grid.first().copied().unwrap_or(0.0), 0.0, 0.0);
        }
        let t = t.clamp(0.0, self.duration());
        // The interval whose start is the last grid time not after t.
        let i = self.t.partition_point(|ti| *ti <= t).clamp(1, n - 1) - 1;
        let ds = self.grid[i + 1] - self.grid[i];
        let u = if ds > 0.0 {
            (self.x[i + 1] - self.x[i]) / (2.0 * ds)
        } else {
            0.0
        };
        let v0 = self.x[i].max(0.0).sqrt();
        let tau = t - self.t[i];
        let s = (self.grid[i] + v0 * tau + 0.5 * u * tau * tau).min(self.grid[i + 1]);
        ((s), (v0 + u * tau).max(0.0), u)
    }
}

impl<'a> ToppProblem<'a> {
    /// Rest to rest under `limits`' velocity and acceleration, interpolation scheme, speeds
    /// capped by `speed_cap` (empty: none).
    pub fn rest_to_rest(
        grid: &'a [f64],
        dq: &'a [f64],
        ddq: &'a [f64],
        limits: &'a super::ExecutionLimits,
        speed_cap: &'a [f64],
    ) -> Self {
        Self {
            grid,
            dq,
            ddq,
            velocity: &limits.velocity,
            acceleration: &limits.acceleration,
            start_speed: 0.0,
            end_speed: 0.0,
            discretization: Discretization::Interpolation,
            speed_cap,
        }
    }
}

impl ToppProblem<'_> {
    fn nq(&self) -> usize {
        self.velocity.len()
    }

    fn check(&self) -> Result<(), PlanError> {
        let (n, nq) = (self.grid.len(), self.nq());
        let bad = |what: &str, why: String| Err(PlanError::setting(what, why));
        if n < 2 {
            return bad("TOPP grid", format!("{n} points; at least 2"));
        }
        if self
            .grid
            .windows(2)
            .any(|w| w[1].partial_cmp(&w[0]) != Some(core::cmp::Ordering::Greater))
            || !self.grid[0].is_finite()
        {
            return bad("TOPP grid", "not finite and strictly increasing".into());
        }
        if self.acceleration.len() != nq || nq == 0 {
            return bad(
                "TOPP limits",
                format!(
                    "{nq} velocity and {} acceleration limits",
                    self.acceleration.len()
                ),
            );
        }
        for (what, rows) in [("q'", self.dq), ("q''", self.ddq)] {
            if rows.len() != n * nq {
                return bad(
                    "TOPP path derivatives",
                    format!("{what}: {} numbers for {n} points of {nq}", rows.len()),
                );
            }
            if let Some(k) = rows.iter().position(|v| !v.is_finite()) {
                return bad(
                    "TOPP path derivatives",
                    format!(
                        "{what} of joint {} at grid point {} is not finite",
                        k % nq,
                        k / nq
                    ),
                );
            }
        }
        for (what, lim) in [
            ("velocity", self.velocity),
            ("acceleration", self.acceleration),
        ] {
            if let Some(k) = lim.iter().position(|v| v.is_nan() || *v <= 0.0) {
                return bad(
                    "TOPP limits",
                    format!("{what} limit of joint {k} is {}: positive", lim[k]),
                );
            }
        }
        if !self.speed_cap.is_empty() && self.speed_cap.len() != n {
            return bad(
                "TOPP speed caps",
                format!("{} caps for {n} points", self.speed_cap.len()),
            );
        }
        if let Some(i) = self.speed_cap.iter().position(|c| c.is_nan() || *c < 0.0) {
            return bad(
                "TOPP speed caps",
                format!("cap {i} is {}", self.speed_cap[i]),
            );
        }
        for (what, v) in [("start", self.start_speed), ("end", self.end_speed)] {
            if !(v >= 0.0 && v.is_finite()) {
                return bad("TOPP path speed", format!("{what} speed {v}"));
            }
        }
        Ok(())
    }

    /// The bound on `x` at grid point `i` from the velocity limits.
    fn x_max(&self, i: usize) -> f64 {
        let nq = self.nq();
        let row = &self.dq[i * nq..(i + 1) * nq];
        let cap = self.speed_cap.get(i).map_or(f64::INFINITY, |c| c * c);
        row.iter()
            .zip(self.velocity)
            .filter(|(d, _)| d.abs() > 0.0)
            .map(|(d, v)| (v / d) * (v / d))
            .fold(cap, f64::min)
    }

    /// Stage `i`'s acceleration constraints, into `out`.
    fn stage(&self, i: usize, out: &mut Vec<Half>) {
        out.clear();
        let nq = self.nq();
        let n = self.grid.len();
        // The stage's length (the last point's: the stage before it).
        let d = self.grid[(i + 1).min(n - 1)] - self.grid[i.min(n - 2)];
        let mut push = |a: f64, b: f64, lim: f64| {
            // −lim ≤ a·u + b·x ≤ lim. Where q' vanishes (the path at rest in its own time), a
            // is rounding noise: a·u changes x's bound by less than 1e-12 of b·Δx (Δx = 2d·u)
            // and, kept, divides the rounding of lim − b·x by ~1e-17.
            let a = if a.abs() <= 1e-12 * b.abs() * 2.0 * d {
                0.0
            } else {
                a
            };
            if lim.is_finite() {
                out.push(Half {
                    alpha: b,
                    beta: a,
                    gamma: lim,
                });
                out.push(Half {
                    alpha: -b,
                    beta: -a,
                    gamma: lim,
                });
            }
        };
        for k in 0..nq {
            push(
                self.dq[i * nq + k],
                self.ddq[i * nq + k],
                self.acceleration[k],
            );
        }
        if self.discretization == Discretization::Interpolation && i + 1 < n {
            let j = i + 1;
            for k in 0..nq {
                let (a, b) = (self.dq[j * nq + k], self.ddq[j * nq + k]);
                // a·u + b·(x + 2d·u). Where the two terms cancel (to 1e-9 of their size) the
                // coefficient is their rounding: zero.
                let beta = a + 2.0 * d * b;
                let beta = if beta.abs() <= 1e-9 * (a.abs() + 2.0 * d * b.abs()) {
                    0.0
                } else {
                    beta
                };
                push(beta, b, self.acceleration[k]);
            }
        }
    }
}

/// The range of `x` of the polygon `halves` ∩ `lo ≤ x + 2d·u ≤ hi` ∩ `0 ≤ x ≤ x_max`, or
/// `None` when empty.
fn project(halves: &[Half], d: f64, lo: f64, hi: f64, x_max: f64) -> Option<(f64, f64)> {
    let reach = [
        Half {
            alpha: 1.0,
            beta: 2.0 * d,
            gamma: hi,
        },
        Half {
            alpha: -1.0,
            beta: -2.0 * d,
            gamma: -lo,
        },
    ];
    let all = || halves.iter().chain(reach.iter());
    let (mut x_lo, mut x_hi) = (0.0f64, x_max);
    // Constraints on x alone.
    for h in all().filter(|h| h.beta == 0.0) {
        if h.alpha > 0.0 {
            x_hi = x_hi.min(h.gamma / h.alpha);
        } else if h.alpha < 0.0 {
            x_lo = x_lo.max(h.gamma / h.alpha);
        } else if h.gamma < -EPS {
            return None;
        }
    }
    // Every lower bound on u below every upper bound: u ≥ (γj − αj x)/βj (βj < 0) and
    // u ≤ (γl − αl x)/βl (βl > 0) meet where c0 + c1·x ≥ 0.
    for l in all().filter(|h| h.beta > 0.0) {
        for j in all().filter(|h| h.beta < 0.0) {
            let c0 = l.gamma / l.beta - j.gamma / j.beta;
            let c1 = j.alpha / j.beta - l.alpha / l.beta;
            if c1 < 0.0 {
                x_hi = x_hi.min(-c0 / c1);
            } else if c1 > 0.0 {
                x_lo = x_lo.max(-c0 / c1);
            } else if c0 < -EPS {
                return None;
            }
        }
    }
    (x_lo <= x_hi + EPS * (1.0 + x_hi.abs())).then_some((x_lo, x_hi.max(x_lo)))
}

/// The greatest `u` with `halves` at `x` and `lo ≤ x + 2d·u ≤ hi`.
fn greatest_u(halves: &[Half], x: f64, d: f64, lo: f64, hi: f64) -> Option<f64> {
    let (mut u_lo, mut u_hi) = ((lo - x) / (2.0 * d), (hi - x) / (2.0 * d));
    for h in halves {
        let r = h.gamma - h.alpha * x;
        if h.beta > 0.0 {
            u_hi = u_hi.min(r / h.beta);
        } else if h.beta < 0.0 {
            u_lo = u_lo.max(r / h.beta);
        }
    }
    (u_lo <= u_hi + EPS * (1.0 + u_hi.abs())).then_some(u_hi.max(u_lo))
}

/// TOPP-RA: the time-optimal timing of the grid of `problem`. An error says what was wrong
/// with the input, or at which grid point the path cannot be followed (its end speed is not
/// reachable, or its start speed is too high to stop in time).
pub fn topp_ra(problem: &ToppProblem<'_>) -> Result<Parameterization, PlanError> {
    problem.check()?;
    let n = problem.grid.len();
    let mut halves = Vec::with_capacity(4 * problem.nq());
    // Backward pass: the controllable sets.
    let mut k_lo = vec![0.0; n];
    let mut k_hi = vec![0.0; n];
    let end = problem.end_speed * problem.end_speed;
    if end > problem.x_max(n - 1) * (1.0 + EPS) {
        return Err(PlanError::setting(
            "TOPP end speed",
            format!("{} is above the velocity limits there", problem.end_speed),
        ));
    }
    (k_lo[n - 1], k_hi[n - 1]) = (end, end);
    for i in (0..n - 1).rev() {
        problem.stage(i, &mut halves);
        let d = problem.grid[i + 1] - problem.grid[i];
        let (lo, hi) =
            project(&halves, d, k_lo[i + 1], k_hi[i + 1], problem.x_max(i)).ok_or_else(|| {
                PlanError::setting(
                    "TOPP path",
                    format!(
                        "no speed at s = {} reaches the end at speed {}",
                        problem.grid[i], problem.end_speed
                    ),
                )
            })?;
        (k_lo[i], k_hi[i]) = (lo, hi);
    }
    let start = problem.start_speed * problem.start_speed;
    if start > k_hi[0] * (1.0 + EPS) + EPS || start < k_lo[0] * (1.0 - EPS) - EPS {
        return Err(PlanError::setting(
            "TOPP start speed",
            format!(
                "{} is outside the controllable speeds [{}, {}] at the start",
                problem.start_speed,
                k_lo[0].max(0.0).sqrt(),
                k_hi[0].max(0.0).sqrt()
            ),
        ));
    }
    // Forward pass: the greatest admissible acceleration at each stage.
    let mut x = vec![0.0; n];
    let mut t = vec![0.0; n];
    x[0] = start.clamp(k_lo[0], k_hi[0]);
    for i in 0..n - 1 {
        problem.stage(i, &mut halves);
        let d = problem.grid[i + 1] - problem.grid[i];
        let u = greatest_u(&halves, x[i], d, k_lo[i + 1], k_hi[i + 1]).ok_or_else(|| {
            PlanError::setting(
                "TOPP path",
                format!(
                    "numerically infeasible at s = {} (x = {})",
                    problem.grid[i], x[i]
                ),
            )
        })?;
        x[i + 1] = (x[i] + 2.0 * d * u)
            .clamp(k_lo[i + 1], k_hi[i + 1])
            .max(0.0);
        let speeds = x[i].sqrt() + x[i + 1].sqrt();
        if speeds.is_nan() || speeds <= 0.0 {
            return Err(PlanError::setting(
                "TOPP path",
                format!("the path stops at s = {}", problem.grid[i]),
            ));
        }
        t[i + 1] = t[i] + 2.0 * d / speeds;
    }
    Ok(Parameterization {
        grid: problem.grid.to_vec(),
        x,
        t,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight line of length `len` in one joint: the limits' trapezoid (or triangle),
    /// approached from above as the grid is refined (the switches between accelerating,
    /// cruising and braking fall between grid points, and a stage's `u` is constant).
    #[test]
    fn a_straight_line_converges_to_the_limits_trapezoid() {
        for (len, v, a) in [(1.0f64, 0.5f64, 2.0f64), (0.1, 2.0, 1.0)] {
            let want = if len >= v * v / a {
                len / v + v / a
            } else {
                2.0 * (len / a).sqrt()
            };
            let mut last = f64::INFINITY;
            for n in [11, 101, 1001] {
                let grid: Vec<f64> = (0..n).map(|i| i as f64 / (n - 1) as f64).collect();
                let dq = vec![len; n];
                let ddq = vec![0.0; n];
                let p = ToppProblem {
                    grid: &grid,
                    dq: &dq,
                    ddq: &ddq,
                    velocity: &[v],
                    acceleration: &[a],
                    start_speed: 0.0,
                    end_speed: 0.0,
                    discretization: Discretization::Interpolation,
                    speed_cap: &[],
                };
                let r = topp_ra(&p).unwrap();
                let err = (r.duration() - want) / want;
                // Second order in the grid step (a switch inside a stage costs O(Δ²)).
                assert!(
                    err > -1e-12 && err < 10.0 / (n * n) as f64,
                    "N = {n}: {err}"
                );
                assert!(
                    err < last * 0.2 || err < 1e-12,
                    "N = {n}: {err} after {last}"
                );
                last = err;
                // Halfway in time, about halfway along (the profile is symmetric).
                let (s, _, _) = r.eval(0.5 * r.duration());
                assert!((s - 0.5).abs() < 2.0 / n as f64, "N = {n}: {s}");
            }
        }
    }

    #[test]
    fn bad_input_says_what() {
        let grid = [0.0, 0.5, 0.4];
        let p = ToppProblem {
            grid: &grid,
            dq: &[1.0; 3],
            ddq: &[0.0; 3],
            velocity: &[1.0],
            acceleration: &[1.0],
            start_speed: 0.0,
            end_speed: 0.0,
            discretization: Discretization::Collocation,
            speed_cap: &[],
        };
        assert!(topp_ra(&p).unwrap_err().to_string().contains("increasing"));
        let grid = [0.0, 0.5, 1.0];
        let p = ToppProblem {
            grid: &grid,
            acceleration: &[0.0],
            ..p
        };
        let e = topp_ra(&p).unwrap_err().to_string();
        assert!(e.contains("acceleration limit of joint 0 is 0"), "{e}");
        // Too fast at the start to stop within the path.
        let p = ToppProblem {
            acceleration: &[1.0],
            velocity: &[10.0],
            start_speed: 5.0,
            ..p
        };
        let e = topp_ra(&p).unwrap_err().to_string();
        assert!(e.contains("start speed: 5 is outside"), "{e}");
    }
}
