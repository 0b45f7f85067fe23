//! Certified edges: conservative advancement along a straight motion, so nothing can pass
//! between two checked configurations unseen.
//!
//! Sampling an edge at a resolution (the verifiers) misses a collision between samples; for a
//! path that a robot will follow, the exact question is whether every configuration of the
//! edge is free. Conservative advancement answers it with distances and a bound on how far any
//! point of a link can move (Schwarzer, Saha & Latombe, "Adaptive dynamic collision checking for
//! single and multiple articulated robots in complex environments", IEEE T-RO 21(3), 2005, §III;
//! the advancement is Mirtich's):
//!
//! - Along the edge `q(s) = a + s·Δ`, `s ∈ [0, 1]` (`Δ = b ⊖ a`, circles the short way), a point
//!   of scene body `i`, carried by rl-core body `k`, moves by at most `|s − s'|·Bᵢ` between `s`
//!   and `s'`, with `Bᵢ = Σⱼ λᵢⱼ·|Δⱼ|` over the joints `j` from `k` to the root: `λᵢⱼ = 1` for a
//!   prismatic joint, and for a revolute one `λᵢⱼ = Rᵢ + Lⱼₖ` — `Rᵢ` the radius of body `i`'s
//!   shapes about `k`'s origin, `Lⱼₖ` the length of the chain from joint `j`'s origin to `k`'s
//!   (the norms of the placements in between plus the travel of prismatic joints in between): a
//!   rotation by `|Δⱼ|` moves a point at most `|Δⱼ|` times its distance to the axis, and the
//!   moves of the joints add up (triangle inequality). `Δⱼ` is the joint's own displacement
//!   (mimic relations applied).
//! - Two bodies at distance `d` move towards each other by at most `(Bₐ + B_b)·δs` over a step
//!   `δs` (`B = 0` for the environment). Taking `δs = minₚ (dₚ − η/2) / Bₚ` over the checked pairs
//!   `p` keeps every pair at least `η/2` apart over the step; an edge on which some pair comes
//!   within `η` (the margin) of touching is not certified. Each step advances at least
//!   `η / (2·max B)`, so an edge ends after at most `2·max B / η` steps.
//! - Pairs are the exact checker's (self-collision pairs of the robot, the robot against every
//!   other model, bodies with collision off skipped); a pair whose bounding boxes are further
//!   apart than the step it could limit is not measured.
//!
//! - Any motion `q(t)` whose coordinates move no faster than `vₖ` is certified the same way in
//!   time, with `Bᵢ = Σⱼ λᵢⱼ·vⱼ` a speed ([`SceneValidity::certify_motion`]): a trajectory within
//!   its velocity limits, blends included. The straight edge is the motion of duration 1 at
//!   speeds `|Δ|`.
//!
//! Dimensions: `Δ` rad or m, `v` rad/s or m/s, `λ` m/rad (1 for prismatic joints), `B` m (m/s
//! in time), `d`, `η` m, `s` 1 (or s).
//! - Rotations (spherical and six-DOF joints, slerp in the space): a rotation by the angle `θ`
//!   about the joint's origin moves a point at most `θ` times its distance to that origin, so
//!   `λ = Rᵢ + Lⱼₖ` with `|Δⱼ| = θ = 2·acos |⟨a, b⟩|` (slerp turns at a constant rate about one
//!   axis); a six-DOF joint's translation adds `|Δx| + |Δy| + |Δz|` (its origin moves on a
//!   line) and, for the bodies below it, its largest reach to `L`. Other joints (helical,
//!   cylindrical, planar) are refused.

use std::fmt;

use glam::DVec3;
use rl_core::joint::Joint;
use rl_core::model::ROOT;

use super::SceneValidity;
use crate::error::PlanError;

/// How an edge is certified.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CertifyOptions {
    /// The clearance `η` below which an edge is not certified, m.
    pub margin: f64,
    /// The most advancement steps per edge before giving up.
    pub max_steps: usize,
}

impl Default for CertifyOptions {
    fn default() -> Self {
        Self {
            margin: 1e-4,
            max_steps: 100_000,
        }
    }
}

/// A certified edge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Certificate {
    /// Advancement steps taken (configurations measured).
    pub steps: usize,
    /// The smallest distance measured between a checked pair, m.
    pub min_distance: f64,
}

/// How far [`SceneValidity::certify_path_with_progress`] has got.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CertifyProgress {
    /// Edges certified so far.
    pub edges_done: usize,
    /// Edges of the path.
    pub edges: usize,
    /// Advancement steps taken so far (configurations measured).
    pub steps: usize,
}

/// A path's edges certified one after the other.
#[derive(Clone, Debug, PartialEq)]
pub struct PathCertificate {
    /// Edges of the path.
    pub edges: usize,
    /// Edges certified (all of them, or those before the first that was not).
    pub certified: usize,
    /// Advancement steps over all edges certified.
    pub steps: usize,
    /// The smallest distance measured on them, m.
    pub min_distance: f64,
    /// The first edge not certified (its index) and why.
    pub failure: Option<(usize, Uncertified)>,
}

impl PathCertificate {
    /// Whether every edge is certified.
    pub fn is_certified(&self) -> bool {
        self.failure.is_none()
    }
}

/// Why an edge is not certified.
#[derive(Clone, Debug, PartialEq)]
pub enum Uncertified {
    /// A pair came within the margin (or into contact) at `s`.
    TooClose {
        /// Where along the edge, `[0, 1]`.
        s: f64,
        /// The pair, `model/body` names.
        a: String,
        /// The other body.
        b: String,
        /// Their distance there, m (negative: penetration).
        distance: f64,
    },
    /// The kinematics or the space refused the configuration at `s`.
    Refused {
        /// Where along the edge.
        s: f64,
    },
    /// More steps than allowed before the end.
    StepLimit {
        /// Where along the edge it stopped.
        s: f64,
        /// Steps taken.
        steps: usize,
    },
}

impl fmt::Display for Uncertified {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooClose { s, a, b, distance } => write!(
                f,
                "{a} and {b} come within {:.3} mm of each other at {:.1} % of the edge",
                distance * 1e3,
                s * 100.0
            ),
            Self::Refused { s } => write!(
                f,
                "the configuration at {:.1} % of the edge is outside the space or the kinematics",
                s * 100.0
            ),
            Self::StepLimit { s, steps } => write!(
                f,
                "not decided after {steps} steps (stopped at {:.1} % of the edge)",
                s * 100.0
            ),
        }
    }
}

/// Per scene body of the robot: the coordinates that move it, each with its factor `λ` (times
/// the mimic multiplier of the joint it drives).
#[derive(Clone, Debug, Default)]
pub(super) struct MotionBounds {
    chains: Vec<Vec<(usize, f64)>>,
}

impl MotionBounds {
    /// The bounds of `v`'s robot: `Err` for a joint type the bound does not cover.
    pub(super) fn new(v: &SceneValidity) -> Result<Self, PlanError> {
        let model = &v.kinematics;
        let sg = v
            .scene
            .model(v.robot)
            .ok_or_else(|| PlanError::Unsupported("the robot is not in the scene".into()))?;
        // Travel of a prismatic joint: the largest |joint position| within the space's bounds.
        let travel = |j: usize| -> f64 {
            let i = model.q_index(j);
            let (lo, hi) = v
                .space
                .coordinates()
                .iter()
                .find(|c| c.offset == i)
                .and_then(|c| match c.topology {
                    crate::space::Topology::Interval { lower, upper } => Some((lower, upper)),
                    _ => None,
                })
                .unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
            let mut q = vec![0.0; model.nq()];
            let mut at = |x: f64| {
                q[i] = x;
                model.joint_position(j, &q).map_or(f64::INFINITY, f64::abs)
            };
            at(lo).max(at(hi))
        };
        // Travel of a six-DOF joint's origin: the largest |(x, y, z)| within the space's bounds.
        let reach = |j: usize| -> f64 {
            let i = model.q_index(j);
            (i..i + 3)
                .map(|k| {
                    v.space
                        .coordinates()
                        .iter()
                        .find(|c| c.offset == k)
                        .and_then(|c| match c.topology {
                            crate::space::Topology::Interval { lower, upper } => {
                                Some(lower.abs().max(upper.abs()))
                            }
                            _ => None,
                        })
                        .unwrap_or(f64::INFINITY)
                        .powi(2)
                })
                .sum::<f64>()
                .sqrt()
        };
        // |d joint / d coordinate|: the mimic multiplier (1 for a joint of its own).
        let rate = |j: usize| -> f64 {
            let mut q = vec![0.0; model.nq()];
            let x0 = model.joint_position(j, &q).unwrap_or(0.0);
            q[model.q_index(j)] = 1.0;
            (model.joint_position(j, &q).unwrap_or(0.0) - x0).abs()
        };
        let mut chains = Vec::with_capacity(v.frames.len());
        for (i, frame) in v.frames.iter().enumerate() {
            let Some((k, placement)) = *frame else {
                chains.push(Vec::new());
                continue;
            };
            if k == ROOT {
                chains.push(Vec::new());
                continue;
            }
            // Radius of the body's shapes about k's origin.
            let mut radius: f64 = 0.0;
            for s in sg.bodies()[i].shapes() {
                let local = placement * *s.local_pose();
                let balls = s.geometry().bounding_balls().ok_or_else(|| {
                    PlanError::Unsupported(format!(
                        "robot body \"{}\" has an unbounded shape",
                        sg.bodies()[i].name()
                    ))
                })?;
                for (c, r) in balls {
                    radius = radius.max(local.transform_point(c).length() + r);
                }
            }
            let mut chain = Vec::new();
            let mut length = 0.0;
            let mut j = k;
            while j != ROOT {
                match model.joint(j) {
                    Joint::Revolute(_) => {
                        chain.push((model.q_index(j), (radius + length) * rate(j)))
                    }
                    Joint::Prismatic(_) => {
                        chain.push((model.q_index(j), rate(j)));
                        length += travel(j);
                    }
                    // A rotation about the joint's origin by the angle θ that the rotation
                    // coordinate's slot holds (see `rotation_angles`).
                    Joint::Spherical(_) => chain.push((model.q_index(j), radius + length)),
                    // p = t + R·x: the origin's translation (|Δt| ≤ |Δx| + |Δy| + |Δz|), then a
                    // rotation about it.
                    Joint::SixDof(_) => {
                        let i = model.q_index(j);
                        chain.extend([(i, 1.0), (i + 1, 1.0), (i + 2, 1.0)]);
                        chain.push((i + 3, radius + length));
                        length += reach(j);
                    }
                    other => {
                        return Err(PlanError::Unsupported(format!(
                            "certified edges cover revolute, prismatic, spherical and six-DOF joints, not joint \"{}\" ({other:?})",
                            model.joint_name(j)
                        )));
                    }
                }
                length += model.placement(j).translation.length();
                j = model.parent(j);
            }
            if !length.is_finite() {
                return Err(PlanError::Unsupported(format!(
                    "an unbounded prismatic joint carries robot body \"{}\"",
                    sg.bodies()[i].name()
                )));
            }
            chains.push(chain);
        }
        Ok(Self { chains })
    }

    /// `Bᵢ` for every scene body of the robot, for coordinate displacements (or speeds)
    /// `delta`.
    fn bounds(&self, delta: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend(
            self.chains
                .iter()
                .map(|c| c.iter().map(|&(j, l)| l * delta[j]).sum::<f64>()),
        );
    }
}

/// Writes into the first slot of each rotation coordinate of `speed` the angle `θ` (rad) of the
/// rotation from `a`'s quaternion to `b`'s along the geodesic the space interpolates on (the
/// shorter way: `θ = 2·acos |⟨a, b⟩|`), and zeroes the other three slots, which the bounds do
/// not read.
fn rotation_angles(space: &crate::space::JointSpace, a: &[f64], b: &[f64], speed: &mut [f64]) {
    for c in space.coordinates() {
        if c.topology == crate::space::Topology::Rotation {
            let i = c.offset;
            let dot: f64 = (i..i + 4).map(|k| a[k] * b[k]).sum();
            speed[i] = 2.0 * dot.abs().min(1.0).acos();
            speed[i + 1..i + 4].fill(0.0);
        }
    }
}

/// The gap between two axis-aligned boxes (0 when they overlap).
fn box_gap(a: Option<(DVec3, DVec3)>, b: Option<(DVec3, DVec3)>) -> f64 {
    let (Some((alo, ahi)), Some((blo, bhi))) = (a, b) else {
        return 0.0;
    };
    let gap = (blo - ahi).max(alo - bhi).max(DVec3::ZERO);
    gap.length()
}

impl SceneValidity {
    /// Certifies the straight motion from `a` to `b` by conservative advancement (see the
    /// [module docs](self)): `Ok` if no checked pair comes within `options.margin` anywhere on
    /// it, ends included. `Err(PlanError)` if the robot's joints or shapes are outside what the
    /// bound covers.
    pub fn certify_edge(
        &mut self,
        a: &[f64],
        b: &[f64],
        options: &CertifyOptions,
    ) -> Result<Result<Certificate, Uncertified>, PlanError> {
        self.space.check("edge start", a)?;
        self.space.check("edge end", b)?;
        let mut speed = vec![0.0; self.space.nq()];
        self.space.difference(a, b, &mut speed);
        for v in &mut speed {
            *v = v.abs();
        }
        rotation_angles(&self.space, a, b, &mut speed);
        let space = self.space.clone();
        self.certify_motion(1.0, &speed, options, |s, q| space.interpolate(a, b, s, q))
    }

    /// Certifies the edges of `path` in order, up to the first that is not certified.
    pub fn certify_path(
        &mut self,
        path: &crate::path::Path,
        options: &CertifyOptions,
    ) -> Result<PathCertificate, PlanError> {
        self.certify_path_with_progress(path, options, &mut |_| {})
    }

    /// [`SceneValidity::certify_path`], telling `progress` before the first edge and after each
    /// certified one what was done so far (a command shows it; this prints nothing).
    pub fn certify_path_with_progress(
        &mut self,
        path: &crate::path::Path,
        options: &CertifyOptions,
        progress: &mut dyn FnMut(&CertifyProgress),
    ) -> Result<PathCertificate, PlanError> {
        let edges = path.len().saturating_sub(1);
        let mut out = PathCertificate {
            edges,
            certified: 0,
            steps: 0,
            min_distance: f64::INFINITY,
            failure: None,
        };
        progress(&CertifyProgress {
            edges_done: 0,
            edges,
            steps: 0,
        });
        for e in 0..edges {
            match self.certify_edge(path.point(e), path.point(e + 1), options)? {
                Ok(c) => {
                    out.certified += 1;
                    out.steps += c.steps;
                    out.min_distance = out.min_distance.min(c.min_distance);
                    progress(&CertifyProgress {
                        edges_done: e + 1,
                        edges,
                        steps: out.steps,
                    });
                }
                Err(why) => {
                    out.failure = Some((e, why));
                    break;
                }
            }
        }
        Ok(out)
    }

    /// Certifies any motion `q(t)`, `t ∈ [0, duration]` (written by `position(t, q)`), along
    /// which coordinate `k` moves no faster than `speed[k]` (rad/s or m/s): a trajectory within
    /// its velocity limits, a blend. For a rotation (a quaternion over four slots) the first slot
    /// bounds its angular speed (rad/s) and the other three are not read. The edge of [`SceneValidity::certify_edge`] is the motion of
    /// duration 1 at speeds `|b ⊖ a|`. `s` in the answer is the time `t`.
    pub fn certify_motion(
        &mut self,
        duration: f64,
        speed: &[f64],
        options: &CertifyOptions,
        mut position: impl FnMut(f64, &mut [f64]),
    ) -> Result<Result<Certificate, Uncertified>, PlanError> {
        if self.bounds.is_none() {
            self.bounds = Some(MotionBounds::new(self)?);
        }
        let nq = self.space.nq();
        if speed.len() != nq {
            return Err(PlanError::Length {
                what: "the speed bounds".into(),
                expected: nq,
                got: speed.len(),
            });
        }
        if !(duration.is_finite() && duration >= 0.0) || speed.iter().any(|v| !v.is_finite()) {
            return Err(PlanError::Unsupported(format!(
                "a motion of duration {duration} s at speeds {speed:?} cannot be certified"
            )));
        }
        let eta = options.margin.max(0.0);
        let mut moves = Vec::new();
        if let Some(m) = &self.bounds {
            let speed: Vec<f64> = speed.iter().map(|v| v.abs()).collect();
            m.bounds(&speed, &mut moves);
        }
        let robot = self.robot.0;
        let Some(sg) = self.scene.model(self.robot) else {
            return Err(PlanError::Unsupported(
                "the robot is not in the scene".into(),
            ));
        };
        let checked = |m: &rl_sg::Model, i: usize| {
            let body = &m.bodies()[i];
            body.collision_enabled() && !body.shapes().is_empty()
        };
        let id = |model: usize, body: usize| rl_sg::BodyId { model, body };
        // The pairs: (body of the robot, other body, how fast they can close in).
        let mut pairs: Vec<(rl_sg::BodyId, rl_sg::BodyId, f64)> = Vec::new();
        for &(i, j) in sg.self_collision_pairs() {
            let (i, j) = (i as usize, j as usize);
            pairs.push((id(robot, i), id(robot, j), moves[i] + moves[j]));
        }
        for (m, other) in self.scene.models().iter().enumerate() {
            if m == robot {
                continue;
            }
            for i in (0..sg.bodies().len()).filter(|&i| checked(sg, i)) {
                for x in (0..other.bodies().len()).filter(|&x| checked(other, x)) {
                    pairs.push((id(robot, i), id(m, x), moves[i]));
                }
            }
        }
        let mut q = vec![0.0; nq];
        let mut t = 0.0_f64;
        let mut steps = 0;
        let mut min_distance = f64::INFINITY;
        loop {
            position(t, &mut q);
            if !self.space.contains(&q) || !self.place(&q) {
                return Ok(Err(Uncertified::Refused { s: t }));
            }
            steps += 1;
            let mut advance = f64::INFINITY;
            for &(x, y, bound) in &pairs {
                // A pair that cannot move relative to the other needs measuring once.
                if bound == 0.0 && steps > 1 {
                    continue;
                }
                let (bx, by) = (self.scene.body(x), self.scene.body(y));
                let gap = box_gap(
                    bx.and_then(|b| b.world_aabb()),
                    by.and_then(|b| b.world_aabb()),
                );
                if gap >= eta && (bound == 0.0 || (gap - eta / 2.0) / bound >= advance) {
                    continue;
                }
                let Some(d) = self.scene.body_distance(x, y) else {
                    continue;
                };
                min_distance = min_distance.min(d.distance);
                if d.distance < eta {
                    return Ok(Err(Uncertified::TooClose {
                        s: t,
                        a: self.scene.body_name(x),
                        b: self.scene.body_name(y),
                        distance: d.distance,
                    }));
                }
                if bound > 0.0 {
                    advance = advance.min((d.distance - eta / 2.0) / bound);
                }
            }
            if t >= duration {
                return Ok(Ok(Certificate {
                    steps,
                    min_distance,
                }));
            }
            if steps >= options.max_steps {
                return Ok(Err(Uncertified::StepLimit { s: t, steps }));
            }
            t = (t + advance).min(duration);
        }
    }
}
