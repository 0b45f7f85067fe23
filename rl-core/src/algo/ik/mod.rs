//! Inverse kinematics: joint positions that put one or several tools at their goals.
//!
//! Jacobian-based iteration, as RL's `JacobianInverseKinematics`, with three step rules
//! ([`IkMethod`]): damped least squares with a real damping factor, the SVD pseudo-inverse
//! with small singular values damped, and the Jacobian transpose. Each iteration runs forward
//! kinematics and the world Jacobian of every goal's tool ([`crate::algo::jacobian`]), stacks
//! the error twists (`[linear; angular]` per pose goal, `linear` per position goal), stops
//! when their Euclidean norm is below `epsilon`, and otherwise steps `q ← q ⊕ dq` through
//! [`Joint::integrate`](crate::joint::Joint::integrate) (so spherical and free joints stay
//! on the unit quaternion), then clamps every coordinate into its limits (wraparound joints
//! are wrapped into `[-π, π)`). A joint already at a limit that the step would push further
//! out is locked for that step and the step recomputed without it. An attempt ends after
//! `iterations_per_attempt` iterations, or earlier when the error stalls; the next attempt
//! starts from a random configuration drawn with a seeded [`SplitMix64`], until the total
//! iteration budget, the restart limit or the (optional) time budget is spent.
//!
//! Differences from RL, on purpose: "dls" damps (RL passes `λ = 0`); the step length is
//! bounded by default (RL's `delta` is infinite); stalled attempts restart early; the result
//! is reproducible (fixed default seed); on failure the best configuration found is returned
//! in `q_out` with its residual in the error.
//!
//! All scratch lives in [`IkSolver`] (fixed arrays sized by the model capacity `N` and
//! [`MAX_GOALS`]); solving does not allocate and never panics on bad input.
//!
//! ```
//! use glam::{DMat3, DVec3};
//! use rl_core::algo::ik::{IkGoal, IkSolver};
//! use rl_core::joint::{Joint, Revolute};
//! use rl_core::model::ROOT;
//! use rl_core::spatial::{PlueckerTransform, RigidBodyInertia};
//! use rl_core::{Data, ModelBuilder};
//!
//! // A planar 2R arm with 1 m links, its tool at the tip.
//! let mut b = ModelBuilder::<2>::new();
//! let link = RigidBodyInertia::from_com(1.0, DVec3::ZERO, DMat3::IDENTITY * 0.01);
//! let z = Joint::Revolute(Revolute::new(DVec3::Z));
//! let x1 = PlueckerTransform::from_translation(DVec3::X);
//! let b0 = b.add_body(ROOT, "j0", z, PlueckerTransform::IDENTITY, "l0", link).unwrap();
//! let b1 = b.add_body(b0, "j1", z, x1, "l1", link).unwrap();
//! b.add_tool("tip", b1, x1).unwrap();
//! let model = b.build();
//!
//! let mut solver = IkSolver::<2>::default();
//! let mut data = Data::new();
//! let mut q = [0.0; 2];
//! let goal = IkGoal::position(0, DVec3::new(1.0, 1.0, 0.0));
//! let s = solver.solve(&model, &mut data, &[goal], &[0.3, 0.3], &mut q).unwrap();
//! assert!(s.residual < 1e-6);
//! // Either elbow solution: (0, π/2) or (π/2, -π/2).
//! let elbow = q[1].abs();
//! assert!((elbow - core::f64::consts::FRAC_PI_2).abs() < 1e-5);
//! ```

mod dls;
mod error;
mod goal;
mod jacobi_svd;
mod pseudo_inverse;
mod rng;
mod transpose;

pub use error::IkError;
pub use goal::{IkGoal, IkTarget};
pub use rng::SplitMix64;

use crate::joint::{Joint, MAX_JOINT_NQ};
use crate::model::{Data, Model};

use super::jacobian::Jacobian;

/// The most goals one solve can take (one per tool).
pub const MAX_GOALS: usize = 4;

/// The most stacked error rows: six per goal.
pub(crate) const MAX_ROWS: usize = 6 * MAX_GOALS;

/// How each iteration turns the error twist `dx` into a joint step `dq`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IkMethod {
    /// Damped least squares `dq = Jᵀ (J Jᵀ + λ² I)⁻¹ dx`. `lambda` is in the Jacobian's units
    /// (m per rad for revolute arms). A fixed `λ` slows the final approach along singular
    /// directions with `σ < λ` (error factor `λ²/(σ² + λ²)` per iteration), so keep it small
    /// relative to the arm: the default 1e-3 suits arms of about 1 m reach (on a Puma-like
    /// arm, `λ = 1e-2` left 1 % of random targets near the wrist singularity unsolved, 1e-3
    /// none); large steps are bounded by `max_step` anyway. `lambda = 0` reproduces RL's
    /// "dls" (and fails at exact singularities).
    Dls {
        /// The damping factor `λ ≥ 0`.
        lambda: f64,
    },
    /// SVD pseudo-inverse: singular values `σ ≥ threshold` are inverted exactly, smaller ones
    /// are damped as `σ / threshold²` (zero ones dropped). RL's default method.
    PseudoInverse {
        /// The singular value `σ₀ > 0` below which damping starts (Jacobian units).
        threshold: f64,
    },
    /// Jacobian transpose with RL's step `α = ⟨dx, J Jᵀ dx⟩ / |J Jᵀ dx|²`: cheap per
    /// iteration, never singular, but linear convergence; give it many iterations per
    /// attempt (thousands) for a tight `epsilon`.
    Transpose,
}

impl Default for IkMethod {
    /// Damped least squares with `λ = 0.001`.
    fn default() -> Self {
        IkMethod::Dls { lambda: 0.001 }
    }
}

/// Options of [`IkSolver`]. `Default` gives RL's epsilon and iteration count with a damped
/// method, a bounded step and a fixed seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkOptions {
    /// The step rule.
    pub method: IkMethod,
    /// Success when the stacked error `|dx|` (m and rad) is below this. Default `1e-6`.
    pub epsilon: f64,
    /// Iterations from one start before a random restart. Default 100 (RL's `steps`).
    pub iterations_per_attempt: usize,
    /// Restart early when this many iterations in a row did not lower the attempt's best
    /// residual by 1 % (stuck in a local minimum, often against a joint limit). Default 5;
    /// `usize::MAX` turns it off (RL has no such test).
    pub stall_iterations: usize,
    /// Total iterations over all attempts. Default 10 000 (RL's `iterations`).
    pub max_iterations: usize,
    /// Most random restarts. Default `usize::MAX` (bounded by the iteration budget).
    pub max_restarts: usize,
    /// Largest Euclidean norm of one step `dq` (rad and m); longer steps are shortened,
    /// keeping their direction. Default 1. `f64::INFINITY` is RL's behaviour.
    pub max_step: f64,
    /// Seed of the restart generator; the same seed and inputs give the same result.
    pub seed: u64,
}

impl Default for IkOptions {
    fn default() -> Self {
        Self {
            method: IkMethod::default(),
            epsilon: 1e-6,
            iterations_per_attempt: 100,
            stall_iterations: 5,
            max_iterations: 10_000,
            max_restarts: usize::MAX,
            max_step: 1.0,
            seed: 0x5eed_1c0f_fee0_0001,
        }
    }
}

impl IkOptions {
    fn validate(&self) -> Result<(), IkError> {
        let bad = |option| Err(IkError::InvalidOption { option });
        match self.method {
            IkMethod::Dls { lambda } if !(lambda >= 0.0 && lambda.is_finite()) => {
                return bad("lambda");
            }
            IkMethod::PseudoInverse { threshold }
                if !(threshold > 0.0 && threshold.is_finite()) =>
            {
                return bad("threshold");
            }
            _ => {}
        }
        if !(self.epsilon > 0.0 && self.epsilon.is_finite()) {
            return bad("epsilon");
        }
        if self.iterations_per_attempt == 0 {
            return bad("iterations_per_attempt");
        }
        if self.stall_iterations == 0 {
            return bad("stall_iterations");
        }
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return bad("max_step");
        }
        Ok(())
    }
}

/// A success: the solution is in the caller's `q_out`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkSolution {
    /// Iterations spent in total (all attempts).
    pub iterations: usize,
    /// Random restarts made before the successful attempt.
    pub restarts: usize,
    /// The final error `|dx|`, below epsilon.
    pub residual: f64,
}

/// A source of time for [`IkSolver::solve_within`]: any monotonic clock in seconds. `no_std`
/// has no clock, so the caller brings one; closures returning `f64` qualify, e.g.
/// `|| start.elapsed().as_secs_f64()` with `std::time::Instant`.
pub trait Clock {
    /// The current time, seconds (any fixed origin).
    fn now_s(&mut self) -> f64;
}

impl<F: FnMut() -> f64> Clock for F {
    fn now_s(&mut self) -> f64 {
        self()
    }
}

/// The time source of [`IkSolver::solve`]: never read, because its budget is infinite.
struct NoClock;

impl Clock for NoClock {
    fn now_s(&mut self) -> f64 {
        0.0
    }
}

/// Inverse kinematics solver for models of capacity `N`: the options and all the scratch
/// memory of a solve (about `(12·MAX_GOALS + 9) · N + 650` floats), so solving allocates
/// nothing. Reuse one per thread.
#[derive(Clone, Debug)]
pub struct IkSolver<const N: usize> {
    /// The options used by every solve.
    pub options: IkOptions,
    /// Stacked Jacobian rows.
    jac: [[f64; N]; MAX_ROWS],
    /// The Jacobian with locked joints' columns zeroed (overwritten by the SVD).
    work: [[f64; N]; MAX_ROWS],
    /// One tool's Jacobian.
    tool_jac: Jacobian<N>,
    /// Stacked error.
    dx: [f64; MAX_ROWS],
    /// `J Jᵀ + λ² I` and its factor, or the SVD's `U`.
    square: [[f64; MAX_ROWS]; MAX_ROWS],
    /// Right-hand side / `J Jᵀ dx`.
    rows_tmp: [f64; MAX_ROWS],
    /// The step.
    dq: [f64; N],
    /// The best configuration so far (`nq ≤ 2N` elements, hence pairs).
    q_best: [[f64; 2]; N],
}

impl<const N: usize> Default for IkSolver<N> {
    fn default() -> Self {
        Self::new(IkOptions::default())
    }
}

impl<const N: usize> IkSolver<N> {
    /// A solver with the given options.
    pub fn new(options: IkOptions) -> Self {
        Self {
            options,
            jac: [[0.0; N]; MAX_ROWS],
            work: [[0.0; N]; MAX_ROWS],
            tool_jac: [[0.0; N]; 6],
            dx: [0.0; MAX_ROWS],
            square: [[0.0; MAX_ROWS]; MAX_ROWS],
            rows_tmp: [0.0; MAX_ROWS],
            dq: [0.0; N],
            q_best: [[0.0; 2]; N],
        }
    }

    /// Solves for `goals` starting at `q_init` (`nq` elements, clamped into the limits
    /// first), writing the solution into `q_out` (`nq`). On `NotConverged` `q_out` holds the
    /// best configuration found; on input errors it is untouched. Overwrites `data`'s poses.
    pub fn solve(
        &mut self,
        model: &Model<N>,
        data: &mut Data<N>,
        goals: &[IkGoal],
        q_init: &[f64],
        q_out: &mut [f64],
    ) -> Result<IkSolution, IkError> {
        self.run(
            model,
            data,
            goals,
            q_init,
            q_out,
            &mut NoClock,
            f64::INFINITY,
        )
    }

    /// As [`solve`](Self::solve), and gives up with [`IkError::TimeBudget`] once
    /// `budget_s` seconds of `clock` have passed (checked once per iteration; RL's default
    /// duration is 1 s).
    #[allow(clippy::too_many_arguments)]
    pub fn solve_within<C: Clock>(
        &mut self,
        model: &Model<N>,
        data: &mut Data<N>,
        goals: &[IkGoal],
        q_init: &[f64],
        q_out: &mut [f64],
        clock: &mut C,
        budget_s: f64,
    ) -> Result<IkSolution, IkError> {
        if budget_s.is_nan() || budget_s < 0.0 {
            return Err(IkError::InvalidOption { option: "budget_s" });
        }
        self.run(model, data, goals, q_init, q_out, clock, budget_s)
    }

    #[allow(clippy::too_many_arguments)]
    fn run<C: Clock>(
        &mut self,
        model: &Model<N>,
        data: &mut Data<N>,
        goals: &[IkGoal],
        q_init: &[f64],
        q_out: &mut [f64],
        clock: &mut C,
        budget_s: f64,
    ) -> Result<IkSolution, IkError> {
        let nq = model.nq();
        let nv = model.dof();
        let opts = self.options;
        opts.validate()?;
        if q_init.len() != nq {
            return Err(IkError::Dimension {
                argument: "q_init",
                expected: nq,
                got: q_init.len(),
            });
        }
        if q_out.len() != nq {
            return Err(IkError::Dimension {
                argument: "q_out",
                expected: nq,
                got: q_out.len(),
            });
        }
        if let Some(index) = q_init.iter().position(|x| !x.is_finite()) {
            return Err(IkError::NotFiniteStart { index });
        }
        if goals.is_empty() {
            return Err(IkError::NoGoals);
        }
        if goals.len() > MAX_GOALS {
            return Err(IkError::TooManyGoals { got: goals.len() });
        }
        for (g, goal) in goals.iter().enumerate() {
            if goal.tool >= model.tools().len() {
                return Err(IkError::UnknownTool {
                    goal: g,
                    tool: goal.tool,
                });
            }
            goal.validate(g)?;
        }
        let rows: usize = goals.iter().map(IkGoal::rows).sum();

        let timed = budget_s.is_finite();
        let start = if timed { clock.now_s() } else { 0.0 };
        let mut rng = SplitMix64::new(opts.seed);
        q_out.copy_from_slice(q_init);
        model.normalize(q_out);
        clamp_to_limits(model, q_out);

        let mut best = f64::INFINITY;
        let (mut attempt_best, mut stalled) = (f64::INFINITY, 0usize);
        let (mut iterations, mut restarts, mut in_attempt) = (0usize, 0usize, 0usize);
        loop {
            let residual = self.evaluate(model, data, goals, q_out);
            if residual < best {
                best = residual;
                self.q_best.as_flattened_mut()[..nq].copy_from_slice(q_out);
            }
            if residual < opts.epsilon {
                return Ok(IkSolution {
                    iterations,
                    restarts,
                    residual,
                });
            }
            if residual < 0.99 * attempt_best {
                attempt_best = residual;
                stalled = 0;
            } else {
                stalled += 1;
            }
            let failed = |s: &Self, q_out: &mut [f64]| {
                q_out.copy_from_slice(&s.q_best.as_flattened()[..nq]);
            };
            if iterations >= opts.max_iterations {
                failed(self, q_out);
                return Err(IkError::NotConverged {
                    residual: best,
                    iterations,
                    restarts,
                });
            }
            if timed && clock.now_s() - start > budget_s {
                failed(self, q_out);
                return Err(IkError::TimeBudget {
                    residual: best,
                    iterations,
                    restarts,
                });
            }
            iterations += 1;
            in_attempt += 1;
            let stepped = residual.is_finite() && self.step(model, q_out, rows, nv);
            let budget_left = iterations < opts.max_iterations;
            let give_up = !stepped
                || in_attempt >= opts.iterations_per_attempt
                || stalled >= opts.stall_iterations;
            if give_up && budget_left {
                if restarts >= opts.max_restarts {
                    failed(self, q_out);
                    return Err(IkError::NotConverged {
                        residual: best,
                        iterations,
                        restarts,
                    });
                }
                restarts += 1;
                in_attempt = 0;
                attempt_best = f64::INFINITY;
                stalled = 0;
                model.random_configuration(q_out, || rng.next_f64());
                clamp_to_limits(model, q_out);
            }
        }
    }

    /// Forward kinematics, the stacked Jacobian and error at `q`; returns `|dx|`.
    fn evaluate(
        &mut self,
        model: &Model<N>,
        data: &mut Data<N>,
        goals: &[IkGoal],
        q: &[f64],
    ) -> f64 {
        let mut row = 0;
        for goal in goals {
            // Lengths and tool indices were checked, so neither call can fail; a failure
            // would still only end this attempt (NaN residual), never panic.
            if super::jacobian(model, data, q, goal.tool, &mut self.tool_jac).is_err() {
                return f64::NAN;
            }
            let Ok(pose) = super::tool_pose(model, data, goal.tool) else {
                return f64::NAN;
            };
            let n = goal.rows();
            goal.error(&pose, &mut self.dx[row..row + n]);
            for r in 0..n {
                self.jac[row + r] = self.tool_jac[r];
            }
            row += n;
        }
        libm::sqrt(self.dx[..row].iter().map(|x| x * x).sum::<f64>())
    }

    /// Computes `dq` by the chosen method and moves `q` by it (bounded, integrated, clamped).
    /// Returns `false` when no usable step exists (the attempt should restart).
    ///
    /// A joint sitting at a limit whose step would push it further out is locked (its
    /// Jacobian column zeroed) and the step recomputed, so the other joints take over the
    /// motion it cannot make instead of the step being clipped away.
    fn step(&mut self, model: &Model<N>, q: &mut [f64], m: usize, nv: usize) -> bool {
        let mut locked = [false; N];
        for _ in 0..=nv {
            for r in 0..m {
                self.work[r] = self.jac[r];
                for (x, _) in self.work[r][..nv]
                    .iter_mut()
                    .zip(&locked)
                    .filter(|(_, l)| **l)
                {
                    *x = 0.0;
                }
            }
            if !self.direction(m, nv) {
                return false;
            }
            let mut newly_locked = false;
            for (k, lock) in locked.iter_mut().enumerate().take(nv) {
                if *lock {
                    continue;
                }
                let Some(iq) = scalar_q_index(model, k) else {
                    continue;
                };
                let l = model.limits(k);
                if l.wraparound {
                    continue;
                }
                let d = self.dq[k];
                if (q[iq] <= l.lower && d < 0.0) || (q[iq] >= l.upper && d > 0.0) {
                    *lock = true;
                    newly_locked = true;
                }
            }
            if !newly_locked {
                break;
            }
        }
        let dq = &mut self.dq[..nv];
        let norm = libm::sqrt(dq.iter().map(|x| x * x).sum::<f64>());
        if norm.is_nan() || norm <= 0.0 {
            return false;
        }
        if norm > self.options.max_step {
            let s = self.options.max_step / norm;
            dq.iter_mut().for_each(|x| *x *= s);
        }
        integrate_in_place(model, q, dq);
        clamp_to_limits(model, q);
        true
    }

    /// The method's step from the Jacobian in `work` (which the SVD overwrites) into `dq`.
    fn direction(&mut self, m: usize, nv: usize) -> bool {
        let dq = &mut self.dq[..nv];
        let dx = &self.dx[..m];
        match self.options.method {
            IkMethod::Dls { lambda } => dls::dls_step(
                &self.work,
                m,
                nv,
                dx,
                lambda,
                &mut self.square,
                &mut self.rows_tmp,
                dq,
            ),
            IkMethod::PseudoInverse { threshold } => pseudo_inverse::pseudo_inverse_step(
                &mut self.work,
                m,
                nv,
                dx,
                threshold,
                &mut self.square,
                dq,
            ),
            IkMethod::Transpose => {
                transpose::transpose_step(&self.work, m, nv, dx, &mut self.rows_tmp, dq)
            }
        }
    }
}

/// The index in `q` of DOF `k` if that DOF is a plain scalar coordinate (not part of a
/// quaternion's rotation).
fn scalar_q_index<const N: usize>(model: &Model<N>, k: usize) -> Option<usize> {
    let b = model.dof_body(k);
    let within = k - model.v_index(b);
    let scalar = match model.joint(b) {
        Joint::Spherical(_) => false,
        Joint::SixDof(_) => within < 3,
        _ => true,
    };
    scalar.then(|| model.q_index(b) + within)
}

/// `q ← q ⊕ dq` joint by joint (exact on quaternion joints), renormalised.
fn integrate_in_place<const N: usize>(model: &Model<N>, q: &mut [f64], dq: &[f64]) {
    for i in 0..model.body_count() {
        if model.mimic(i).is_some() {
            continue;
        }
        let j = model.joint(i);
        let (sq, sv, nq) = (model.q_index(i), model.v_index(i), j.nq());
        let mut next = [0.0; MAX_JOINT_NQ];
        j.integrate(&q[sq..sq + nq], &dq[sv..sv + j.nv()], 1.0, &mut next[..nq]);
        q[sq..sq + nq].copy_from_slice(&next[..nq]);
        j.normalize(&mut q[sq..sq + nq]);
    }
}

/// Clamps every scalar coordinate into its limits (wraps wraparound ones); quaternion parts
/// have no limits.
fn clamp_to_limits<const N: usize>(model: &Model<N>, q: &mut [f64]) {
    for i in 0..model.body_count() {
        if model.mimic(i).is_some() {
            continue;
        }
        let j = model.joint(i);
        let (sq, sv) = (model.q_index(i), model.v_index(i));
        let scalars = match j {
            Joint::Spherical(_) => 0,
            // Translation first, then the quaternion.
            Joint::SixDof(_) => 3,
            _ => j.nv(),
        };
        for k in 0..scalars {
            q[sq + k] = model.limits(sv + k).clamp(q[sq + k]);
        }
    }
}
