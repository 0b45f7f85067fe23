//! Obstacles for the task-space law: the arm as capsules (rl-sg's allocation-free kernel),
//! obstacles fixed, streamed in while the arm moves, or scripted, and each cycle the arm's
//! points nearest to them for rl-core's repulsion ([`rl_core::task::repulsion`]).
//!
//! Streamed obstacles (a tracked worker) arrive as [`super::TaskInput::Obstacle`] into one of
//! [`MAX_OBSTACLES`] slots; each keeps its last shape and velocity until replaced or cleared.
//! Between two updates a moving sphere is predicted at its velocity from the cycle its update
//! arrived in, for at most [`PREDICTION_HORIZON_S`]: a tracker at camera rates (30 Hz) moves
//! the obstacle in steps of centimetres, and the repulsion would step with it (measured on the
//! fake FR3: a sphere sent every 50 ms at 0.5 m/s shook the held orientation by 11 mrad, every
//! 5 ms by 0.6; predicted, 50 ms updates hold it as 5 ms ones do). The prediction sweeps the
//! sphere from where it was seen to where it is predicted (a capsule), so the place it was
//! seen stays covered whatever the velocity says; a tracker that stops leaves it swept to where
//! it was predicted last (the conservative choice), with its velocity still damping the
//! approach. Capsule obstacles are not predicted (a sweep of a capsule is no capsule). An
//! obstacle given at the start ([`super::CartesianImpedance::obstacle`]) with a velocity is
//! swept for the horizon from the first cycle, as a streamed one. Velocities above
//! [`MAX_OBSTACLE_SPEED`] are refused.
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
/// The longest a streamed obstacle is predicted at its velocity after its last update, s;
/// after that it stays where it was predicted last.
pub const PREDICTION_HORIZON_S: f64 = 0.1;
/// The fastest obstacle the law takes, m/s (a hand moves at up to about 2 m/s; a faster
/// velocity is a tracker's error, and its prediction would reach far).
pub const MAX_OBSTACLE_SPEED: f64 = 5.0;
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

    /// Whether every number is finite, the radius ≥ 0 and the speed at most
    /// [`MAX_OBSTACLE_SPEED`].
    pub fn is_valid(&self) -> bool {
        self.shape.a.is_finite()
            && self.shape.b.is_finite()
            && self.shape.radius.is_finite()
            && self.shape.radius >= 0.0
            && self.velocity.is_finite()
            && self.velocity.length() <= MAX_OBSTACLE_SPEED
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
    /// When each slot's obstacle arrived (the law's time; NaN: this cycle, not yet seen).
    arrived: [f64; MAX_OBSTACLES],
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
            arrived: [f64::NAN; MAX_OBSTACLES],
            script: None,
            moving: None,
            shapes: [Capsule::sphere(DVec3::ZERO, 0.0); MAX_OBSTACLES + 1],
            velocities: [DVec3::ZERO; MAX_OBSTACLES + 1],
            proximities: [Proximity::at_rest(0, DVec3::ZERO, DVec3::X, f64::INFINITY);
                MAX_PROXIMITIES],
        }
    }

    /// Puts `obstacle` into `slot` (< [`MAX_OBSTACLES`]), or clears it; its prediction starts
    /// in the cycle that runs next ([`Self::nearest`]).
    pub fn set(&mut self, slot: usize, obstacle: Option<Obstacle>) {
        if let (Some(s), Some(a)) = (self.slots.get_mut(slot), self.arrived.get_mut(slot)) {
            *s = obstacle;
            *a = f64::NAN;
        }
    }

    /// At a run's start: the obstacles' predictions start again in its first cycle (the law's
    /// clock starts again).
    pub fn restart(&mut self) {
        self.arrived = [f64::NAN; MAX_OBSTACLES];
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
        for (o, arrived) in self.slots.iter().zip(self.arrived.iter_mut()) {
            let Some(o) = o else { continue };
            if arrived.is_nan() {
                *arrived = t;
            }
            // A sphere swept at its velocity since it arrived, for at most the horizon (NaN:
            // not at all).
            let elapsed = t - *arrived;
            let ahead = if elapsed.is_nan() {
                0.0
            } else {
                elapsed.clamp(0.0, PREDICTION_HORIZON_S)
            };
            self.shapes[n] = if o.shape.a == o.shape.b {
                Capsule::new(o.shape.a, o.shape.a + o.velocity * ahead, o.shape.radius)
            } else {
                o.shape
            };
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

#[cfg(test)]
mod tests {
    use super::*;
    use rl_core::algo;

    #[test]
    fn a_streamed_sphere_is_swept_at_its_velocity_up_to_the_horizon() {
        let model = crate::controller::rv6sl().expect("embedded model").model;
        let mut data = Box::new(Data::<16>::new());
        algo::forward_position(&model, &mut data, &[0.0; 6]).expect("fk");
        let mut o = Obstacles::new();
        o.enabled = true;
        o.ensure_capsules(&model).expect("skeleton");
        let v = DVec3::new(0.0, -0.5, 0.0);
        let start = DVec3::new(0.3, 2.0, 0.5);
        o.set(
            3,
            Some(Obstacle {
                shape: Capsule::sphere(start, 0.1),
                velocity: v,
            }),
        );
        // Where it was seen, and where it is predicted.
        let ends = |o: &mut Obstacles, t: f64| {
            o.nearest(&data, t, 0.2);
            (o.shapes[0].a, o.shapes[0].b)
        };
        let near = |a: DVec3, b: DVec3| (a - b).length() < 1e-12;
        // It arrived in the cycle at t = 2 s: there it is where it was sent.
        assert_eq!(ends(&mut o, 2.0), (start, start));
        let (seen, ahead) = ends(&mut o, 2.05);
        assert!(seen == start && near(ahead, start + v * 0.05));
        // After the horizon it reaches no farther.
        let (seen, ahead) = ends(&mut o, 2.5);
        assert!(seen == start && near(ahead, start + v * PREDICTION_HORIZON_S));
        // An update starts over from where it was sent; one at rest stays.
        o.set(3, Some(Obstacle::sphere(start, 0.1)));
        assert_eq!(ends(&mut o, 3.0), (start, start));
        assert_eq!(ends(&mut o, 3.05), (start, start));
        // A new run: the prediction starts again in its first cycle (its clock from 0).
        o.set(
            3,
            Some(Obstacle {
                shape: Capsule::sphere(start, 0.1),
                velocity: v,
            }),
        );
        o.nearest(&data, 5.0, 0.2);
        o.restart();
        assert_eq!(ends(&mut o, 0.0), (start, start));
        // A capsule is not predicted; a clear empties the slot.
        let capsule = Capsule::new(start, start + DVec3::X, 0.05);
        o.set(
            3,
            Some(Obstacle {
                shape: capsule,
                velocity: v,
            }),
        );
        o.nearest(&data, 1.0, 0.2);
        assert_eq!(ends(&mut o, 1.05), (capsule.a, capsule.b));
        o.set(3, None);
        assert!(o.slots.iter().all(Option::is_none));
        // Too fast is not valid.
        let fast = Obstacle {
            shape: Capsule::sphere(start, 0.1),
            velocity: DVec3::X * 6.0,
        };
        assert!(!fast.is_valid());
    }
}
