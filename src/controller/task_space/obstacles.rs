//! Obstacles for the task-space law: the arm as capsules (rl-sg's allocation-free kernel),
//! obstacles fixed, streamed in while the arm moves, or scripted, and each cycle the arm's
//! points nearest to them for rl-core's repulsion ([`rl_core::task::repulsion`]).
//!
//! Streamed obstacles (a tracked worker) arrive as [`super::TaskInput::Obstacle`] into one of
//! [`MAX_OBSTACLES`] slots; each keeps its last shape and velocity until replaced or cleared
//! (a tracker that stops leaves the obstacle where it was last seen: the conservative choice).
//! A scripted [`MovingSphere`] goes back and forth between two points along a cosine profile
//! (no step in velocity), for demonstrations and tests.

use std::f64::consts::PI;

use glam::DVec3;
use rl_core::task::{MAX_PROXIMITIES, Proximity};
use rl_core::{Data, Model};
use rl_sg::capsule::{CapacityError, Capsule, CapsuleModel};

/// The most obstacles the law holds (streamed slots; a scripted sphere comes on top).
pub const MAX_OBSTACLES: usize = 64;
/// The most capsules of the arm.
pub const MAX_ARM_CAPSULES: usize = 64;
/// The radius of the skeleton capsules the law puts on an arm when given none, m (a Franka
/// arm's links are 6–7 cm thick around their axes: this is a little under; give fitted
/// capsules for a bound).
pub const SKELETON_RADIUS: f64 = 0.06;

/// An obstacle: a sphere or a capsule in the world, and its velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Obstacle {
    /// Its shape, world coordinates (a sphere: both ends equal).
    pub shape: Capsule,
    /// Its velocity, m/s (the repulsion damps the approach with it).
    pub velocity: DVec3,
}

impl Obstacle {
    /// A sphere at rest.
    pub const fn sphere(center: DVec3, radius: f64) -> Self {
        Self {
            shape: Capsule::sphere(center, radius),
            velocity: DVec3::ZERO,
        }
    }

    /// Whether every number is finite and the radius ≥ 0.
    pub fn is_valid(&self) -> bool {
        self.shape.a.is_finite()
            && self.shape.b.is_finite()
            && self.shape.radius.is_finite()
            && self.shape.radius >= 0.0
            && self.velocity.is_finite()
    }
}

/// A sphere going back and forth between `from` and `to`, once each `period_s`:
/// `c(t) = from + (to − from)(1 − cos 2πt/T)/2` (at `from` with zero velocity at `t = 0`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MovingSphere {
    /// Radius, m.
    pub radius: f64,
    /// Where it starts and returns, m.
    pub from: DVec3,
    /// The far end of its way, m.
    pub to: DVec3,
    /// Time for one way there and back, s.
    pub period_s: f64,
}

impl MovingSphere {
    /// The sphere at time `t`.
    pub fn at(&self, t: f64) -> Obstacle {
        let w = 2.0 * PI / self.period_s;
        let d = self.to - self.from;
        Obstacle {
            shape: Capsule::sphere(self.from + d * (0.5 * (1.0 - (w * t).cos())), self.radius),
            velocity: d * (0.5 * w * (w * t).sin()),
        }
    }
}

/// Where a scripted sphere goes, relative to the tool's pose at the start of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TowardTool {
    /// Radius, m.
    pub radius: f64,
    /// How near the sphere's centre comes to the tool's start position, m.
    pub nearest_m: f64,
    /// How far it travels, m.
    pub travel_m: f64,
    /// Time for one way there and back, s.
    pub period_s: f64,
}

impl Default for TowardTool {
    /// A sphere of 8 cm radius coming from 55 cm away to 15 cm of the tool's start position and
    /// back, every 8 s: without avoidance it would overlap the tool's skeleton capsule.
    fn default() -> Self {
        Self {
            radius: 0.08,
            nearest_m: 0.15,
            travel_m: 0.4,
            period_s: 8.0,
        }
    }
}

impl TowardTool {
    /// The sphere for a tool that starts at `tool`: it comes horizontally from beyond the tool
    /// as seen from the robot's base (the world's origin) toward it.
    pub fn sphere(&self, tool: DVec3) -> MovingSphere {
        let out = DVec3::new(tool.x, tool.y, 0.0);
        let u = if out.length() > 1e-6 {
            out.normalize()
        } else {
            DVec3::X
        };
        MovingSphere {
            radius: self.radius,
            from: tool + u * (self.nearest_m + self.travel_m),
            to: tool + u * self.nearest_m,
            period_s: self.period_s,
        }
    }

    /// Checks the numbers: finite, radius and nearest approach ≥ 0, travel ≥ 0, period > 0.
    pub fn check(&self) -> Result<(), String> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if ok(self.radius)
            && ok(self.nearest_m)
            && ok(self.travel_m)
            && self.period_s.is_finite()
            && self.period_s > 0.0
        {
            Ok(())
        } else {
            Err(format!(
                "a moving sphere needs finite sizes ≥ 0 and a period > 0 ({self:?})"
            ))
        }
    }
}

/// The law's obstacle state: the arm's capsules, the obstacles, and this cycle's proximities.
pub(super) struct Obstacles {
    /// Avoidance asked for.
    pub enabled: bool,
    pub capsules: Option<Box<CapsuleModel<MAX_ARM_CAPSULES>>>,
    pub slots: [Option<Obstacle>; MAX_OBSTACLES],
    pub script: Option<TowardTool>,
    pub moving: Option<MovingSphere>,
    shapes: [Capsule; MAX_OBSTACLES + 1],
    velocities: [DVec3; MAX_OBSTACLES + 1],
    pub proximities: [Proximity; MAX_PROXIMITIES],
}

impl Obstacles {
    pub fn new() -> Self {
        Self {
            enabled: false,
            capsules: None,
            slots: [None; MAX_OBSTACLES],
            script: None,
            moving: None,
            shapes: [Capsule::sphere(DVec3::ZERO, 0.0); MAX_OBSTACLES + 1],
            velocities: [DVec3::ZERO; MAX_OBSTACLES + 1],
            proximities: [Proximity::at_rest(0, DVec3::ZERO, DVec3::X, f64::INFINITY);
                MAX_PROXIMITIES],
        }
    }

    /// The arm's skeleton when no capsules were given (at the run's start).
    pub fn ensure_capsules<const B: usize>(
        &mut self,
        model: &Model<B>,
    ) -> Result<(), CapacityError> {
        if self.capsules.is_none() {
            self.capsules = Some(Box::new(CapsuleModel::skeleton(model, SKELETON_RADIUS)?));
        }
        Ok(())
    }

    /// This cycle's proximities within `within` m (the arm's world poses in `data` must be
    /// those at the measured position), nearest first: how many, and the smallest distance
    /// between the arm and an obstacle (∞ without obstacles). Does not allocate.
    pub fn nearest<const B: usize>(&mut self, data: &Data<B>, t: f64, within: f64) -> (usize, f64) {
        let Some(caps) = self.capsules.as_mut().filter(|_| self.enabled) else {
            return (0, f64::INFINITY);
        };
        caps.update(data);
        let mut n = 0;
        for o in self.slots.iter().flatten() {
            self.shapes[n] = o.shape;
            self.velocities[n] = o.velocity;
            n += 1;
        }
        if let Some(m) = &self.moving {
            let o = m.at(t);
            self.shapes[n] = o.shape;
            self.velocities[n] = o.velocity;
            n += 1;
        }
        let k = caps.proximities(
            &self.shapes[..n],
            &self.velocities[..n],
            within,
            &mut self.proximities,
        );
        let min = if k > 0 {
            self.proximities[0].distance
        } else {
            caps.min_distance(&self.shapes[..n])
                .map_or(f64::INFINITY, |d| d.distance)
        };
        (k, min)
    }
}
