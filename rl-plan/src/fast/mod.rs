//! The fast path: a sphere-based collision checker that tests eight configurations at once in
//! SIMD lanes (VAMP's design, Thomason, Kingston and Kavraki, ICRA 2024), for any robot of
//! revolute and prismatic joints, built at run time from its model.
//!
//! - [`SphereSet`]: the robot's spheres, from a `*_spherized.urdf` or fitted around its
//!   meshes;
//! - [`SphereRobot`]: the kinematic chain in `f32` with every joint turned onto z, and the
//!   spheres per link with a bounding sphere each;
//! - [`Environment`]: boxes, spheres, cylinders, capsules and half-spaces in `f32`, sorted by
//!   distance from the base;
//! - [`SphereChecker`]: a [`Validity`] whose [`Validity::segment_valid`] puts up to eight
//!   points of an edge into the lanes, runs forward kinematics for all of them, and tests
//!   spheres distal links first, stopping at the first touch (`kernel`).
//!
//! Robot spheres are padded by [`PADDING`] (10 µm) so the `f32` forward kinematics (error
//! below 1 µm on arm-sized robots, tested against rl-core's `f64`) cannot make them smaller
//! than the file says.

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
mod dispatch;
mod environment;
mod hybrid;
mod kernel;
mod lanes;
mod robot;
mod spheres;

pub use dispatch::Backend;
pub use environment::Environment;
pub use hybrid::HybridChecker;
pub use robot::{MAX_FAST_BODIES, SphereRobot};
pub use spheres::{CoverReport, LinkCover, LinkSpheres, SphereSet};

use crate::error::PlanError;
use crate::space::JointSpace;
use crate::validity::Validity;
use kernel::FrameStore;
use lanes::{WIDTH, Wide};

/// The self-collision link pairs of `robot` whose spheres touch in every one of `samples`
/// configurations drawn uniformly from `space` (seeded): pairs the sphere model cannot tell
/// apart from adjacent ones (a force sensor's sphere reaching into the wrist that carries it).
/// MoveIt's setup assistant disables such "always in collision" pairs; the sphere checker
/// leaves them out the same way (the exact checker keeps them).
pub fn always_touching_pairs(
    robot: &SphereRobot,
    space: &JointSpace,
    samples: usize,
    seed: u64,
) -> Vec<(String, String)> {
    let mut hits = vec![0usize; robot.self_pairs.len()];
    let mut frames = vec![[[0.0f32; WIDTH]; 12]; robot.joints.len()];
    let mut lanes = vec![[0.0f32; WIDTH]; robot.dof()];
    let mut q = vec![0.0; space.nq()];
    let mut rng = crate::rng::Rng::seed_from(seed);
    let empty = Environment::new(glam::DVec3::ZERO);
    for _ in 0..samples {
        space.sample_uniform(&mut rng, &mut q);
        for (j, lane) in lanes.iter_mut().enumerate() {
            *lane = [q[j] as f32; WIDTH];
        }
        for (a, b, _) in kernel::contacts(robot, &empty, &lanes, &mut frames) {
            if let Some(b) = b
                && let Some(k) = robot
                    .self_pairs
                    .iter()
                    .position(|&(x, y)| (x as usize, y as usize) == (a, b))
            {
                hits[k] += 1;
            }
        }
    }
    robot
        .self_pairs
        .iter()
        .zip(&hits)
        .filter(|(_, h)| samples > 0 && **h == samples)
        .map(|(&(a, b), _)| {
            (
                robot.links[a as usize].name.clone(),
                robot.links[b as usize].name.clone(),
            )
        })
        .collect()
}

/// Added to every robot sphere radius, m.
pub const PADDING: f64 = 1e-5;

/// The SIMD sphere checker (see the module docs).
#[derive(Clone, Debug)]
pub struct SphereChecker {
    robot: SphereRobot,
    env: Environment,
    space: JointSpace,
    backend: Backend,
    frames: Vec<FrameStore>,
    lanes: Vec<Wide>,
    diff: Vec<f64>,
    checks: u64,
    free: u64,
}

impl SphereChecker {
    /// A checker of `robot` among `env`, configurations from `space` (one coordinate per
    /// joint, in the model's order), on the best backend of this CPU.
    pub fn new(robot: SphereRobot, env: Environment, space: JointSpace) -> Result<Self, PlanError> {
        if space.nq() != robot.dof() || !space.is_vector() {
            return Err(PlanError::Unsupported(format!(
                "a space of {} numbers for a sphere robot of {} joints",
                space.nq(),
                robot.dof()
            )));
        }
        let n = robot.joints.len();
        Ok(Self {
            frames: vec![[[0.0; WIDTH]; 12]; n],
            lanes: vec![[0.0; WIDTH]; robot.dof()],
            diff: vec![0.0; robot.dof()],
            robot,
            env,
            space,
            backend: Backend::detect(),
            checks: 0,
            free: 0,
        })
    }

    /// The same checker on `backend` (an error if this CPU cannot run it).
    pub fn with_backend(mut self, backend: Backend) -> Result<Self, PlanError> {
        if !backend.is_supported() {
            return Err(PlanError::Unsupported(format!(
                "the {} backend on this CPU",
                backend.name()
            )));
        }
        self.backend = backend;
        Ok(self)
    }

    /// The backend in use.
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The robot.
    pub fn robot(&self) -> &SphereRobot {
        &self.robot
    }

    /// The environment.
    pub fn environment(&self) -> &Environment {
        &self.env
    }

    /// Replaces the environment (a new problem for the same robot).
    pub fn set_environment(&mut self, env: Environment) {
        self.env = env;
    }

    /// What the spheres of configuration `q` touch: `"link ↔ obstacle k"` and `"link ↔ link"`
    /// (empty when `q` is valid for the spheres). For messages; slow.
    pub fn contacts(&mut self, q: &[f64]) -> Vec<String> {
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            *lane = [q[j] as f32; WIDTH];
        }
        kernel::contacts(&self.robot, &self.env, &self.lanes, &mut self.frames)
            .into_iter()
            .map(|(a, b, o)| {
                let name = |i: usize| self.robot.links[i].name.clone();
                match b {
                    Some(b) => format!("{} ↔ {}", name(a), name(b)),
                    None => format!("{} ↔ obstacle {o}", name(a)),
                }
            })
            .collect()
    }

    /// Every robot sphere at configuration `q` in the world: `(link, centre, radius)`, in the
    /// robot's link order, as the kernel's `f32` forward kinematics places them (for tests and
    /// viewers).
    pub fn world_spheres(&mut self, q: &[f64]) -> Vec<(String, glam::DVec3, f64)> {
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            *lane = [q[j] as f32; WIDTH];
        }
        kernel::world_spheres(&self.robot, &self.lanes, &mut self.frames)
            .into_iter()
            .map(|(l, c, r)| {
                (
                    self.robot.links[l].name.clone(),
                    glam::DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64),
                    r as f64,
                )
            })
            .collect()
    }

    /// The self-collision link pairs the sphere model leaves out (see
    /// [`always_touching_pairs`]).
    pub fn unmodelled_pairs(&self) -> &[(String, String)] {
        &self.robot.unmodelled
    }

    /// Configurations checked in one pass (the backend's lanes: 8 or 16).
    pub fn batch(&self) -> usize {
        self.backend.lanes()
    }

    /// Whether all of up to [`SphereChecker::batch`] configurations `qs` (each `dof` numbers)
    /// are valid.
    pub fn all_valid(&mut self, qs: &[&[f64]]) -> bool {
        let Some(last) = qs.last() else {
            return true;
        };
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            for (i, l) in lane.iter_mut().enumerate() {
                *l = qs.get(i).unwrap_or(last)[j] as f32;
            }
        }
        self.run(qs.len())
    }

    fn run(&mut self, n: usize) -> bool {
        self.checks += n as u64;
        let ok = dispatch::run(
            self.backend,
            &self.robot,
            &self.env,
            &self.lanes,
            &mut self.frames,
        );
        if ok {
            self.free += n as u64;
        }
        ok
    }
}

impl SphereChecker {
    /// The lanes (bit `i` for `ts[i]`) in which `space.interpolate(a, b, t)` collides, every
    /// lane checked (`ts.len() ≤` [`SphereChecker::batch`]; more are ignored).
    pub fn segment_mask(&mut self, space: &JointSpace, a: &[f64], b: &[f64], ts: &[f64]) -> u32 {
        let n = ts.len().min(self.batch());
        if n == 0 {
            return 0;
        }
        space.difference(a, b, &mut self.diff);
        let last = ts[n - 1];
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            let (x, d) = (a[j], self.diff[j]);
            for (i, l) in lane.iter_mut().enumerate() {
                *l = (x + ts[..n].get(i).copied().unwrap_or(last) * d) as f32;
            }
        }
        let live = (1u32 << n) - 1;
        self.checks += n as u64;
        let hit = dispatch::run_mask(
            self.backend,
            &self.robot,
            &self.env,
            &self.lanes,
            &mut self.frames,
            live,
        );
        self.free += u64::from((live & !hit).count_ones());
        hit
    }
}

impl Validity for SphereChecker {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        if !self.space.contains(q) {
            self.checks += 1;
            return false;
        }
        self.all_valid(&[q])
    }

    fn lanes(&self) -> usize {
        self.batch()
    }

    fn segment_valid(
        &mut self,
        space: &JointSpace,
        a: &[f64],
        b: &[f64],
        ts: &[f64],
        _scratch: &mut Vec<f64>,
    ) -> bool {
        if ts.is_empty() {
            return true;
        }
        let lanes = self.batch();
        if ts.len() > lanes {
            // Batches, in order, stopping at the first with a collision.
            return ts
                .chunks(lanes)
                .all(|c| self.segment_valid_batch(space, a, b, c));
        }
        self.segment_valid_batch(space, a, b, ts)
    }

    fn checks(&self) -> u64 {
        self.checks
    }

    fn free_checks(&self) -> u64 {
        self.free
    }
}

impl SphereChecker {
    /// [`Validity::segment_valid`] for at most [`SphereChecker::batch`] fractions.
    fn segment_valid_batch(
        &mut self,
        space: &JointSpace,
        a: &[f64],
        b: &[f64],
        ts: &[f64],
    ) -> bool {
        // Lane i holds a + tᵢ·(b ⊖ a); circles need no wrapping for sin/cos.
        space.difference(a, b, &mut self.diff);
        let last = ts[ts.len() - 1];
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            let (x, d) = (a[j], self.diff[j]);
            for (i, l) in lane.iter_mut().enumerate() {
                *l = (x + ts.get(i).copied().unwrap_or(last) * d) as f32;
            }
        }
        self.run(ts.len())
    }
}
