//! Shared helpers for rl-core's integration tests.
#![allow(dead_code)]

pub mod fixture;

use glam::{DMat3, DQuat, DVec3};
use rl_core::joint::{Cylindrical, Helical, Joint, Planar, Prismatic, Revolute, SixDof, Spherical};
use rl_core::model::{JointLimits, ROOT};
use rl_core::spatial::{PlueckerTransform, RigidBodyInertia};
use rl_core::{Model, ModelBuilder};

/// SplitMix64: a tiny reproducible generator for test states.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    pub fn vec3(&mut self, r: f64) -> DVec3 {
        DVec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }
    pub fn quat(&mut self) -> DQuat {
        DQuat::from_scaled_axis(self.vec3(2.0)).normalize()
    }
    pub fn inertia(&mut self) -> RigidBodyInertia {
        let m = self.range(0.5, 3.0);
        let d = DVec3::new(
            self.range(0.02, 0.2),
            self.range(0.02, 0.2),
            self.range(0.02, 0.2),
        );
        let r = DMat3::from_quat(self.quat());
        let ic = r * DMat3::from_diagonal(d) * r.transpose();
        // principal moments from a box so the triangle inequality holds
        let ic = ic + DMat3::from_diagonal(DVec3::splat(d.max_element()));
        RigidBodyInertia::from_com(m, self.vec3(0.2), ic)
    }
    pub fn pose(&mut self) -> PlueckerTransform {
        PlueckerTransform::from_quat_translation(self.quat(), self.vec3(0.4))
    }
}

/// |a − b| ≤ tol · max(1, |a|, |b|) elementwise, with a readable failure.
#[track_caller]
pub fn assert_close(what: &str, a: &[f64], b: &[f64], tol: f64) {
    assert_eq!(a.len(), b.len(), "{what}: lengths differ");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let scale = 1.0f64.max(x.abs()).max(y.abs());
        assert!(
            (x - y).abs() <= tol * scale,
            "{what}[{i}]: {x} vs {y} (diff {:e}, tol {tol:e})\n  left:  {a:?}\n  right: {b:?}",
            (x - y).abs()
        );
    }
}

/// A 24-DOF tree with every joint type: a six-DOF base, then branches of revolute
/// (aligned and unaligned axes), prismatic, helical, cylindrical, planar and spherical
/// joints, with two tools on different branches and one on the base.
pub fn every_joint_type<const N: usize>(seed: u64) -> Model<N> {
    let mut r = Rng(seed);
    let mut b = ModelBuilder::<N>::new();
    b.name("every-joint-type").unwrap();
    b.gravity(DVec3::new(0.0, 0.0, -9.80665));
    let base = b
        .add_body(
            ROOT,
            "base",
            Joint::SixDof(SixDof),
            PlueckerTransform::IDENTITY,
            "base",
            r.inertia(),
        )
        .unwrap();
    let mut add = |b: &mut ModelBuilder<N>, parent: usize, name: &str, j: Joint| {
        let pose = r.pose();
        let inertia = r.inertia();
        b.add_body(parent, name, j, pose, name, inertia).unwrap()
    };
    // branch A: z-revolute, unaligned revolute, prismatic, helical, x-revolute
    let a1 = add(&mut b, base, "a1", Joint::Revolute(Revolute::new(DVec3::Z)));
    let a2 = add(
        &mut b,
        a1,
        "a2",
        Joint::Revolute(Revolute::new(DVec3::new(0.3, -0.4, 0.8))),
    );
    let a3 = add(
        &mut b,
        a2,
        "a3",
        Joint::Prismatic(Prismatic::new(DVec3::new(1.0, 0.2, 0.0))),
    );
    let a4 = add(
        &mut b,
        a3,
        "a4",
        Joint::Helical(Helical::new(DVec3::Y, 0.02)),
    );
    let a5 = add(&mut b, a4, "a5", Joint::Revolute(Revolute::new(DVec3::X)));
    // branch B: cylindrical, planar, spherical
    let b1 = add(
        &mut b,
        base,
        "b1",
        Joint::Cylindrical(Cylindrical::new(DVec3::new(0.0, 0.6, 0.8))),
    );
    let b2 = add(&mut b, b1, "b2", Joint::Planar(Planar));
    let b3 = add(&mut b, b2, "b3", Joint::Spherical(Spherical));
    // branch C off A: a short side chain
    let c1 = add(&mut b, a2, "c1", Joint::Revolute(Revolute::new(DVec3::Y)));
    let limits = JointLimits {
        lower: -2.0,
        upper: 2.0,
        velocity: 3.0,
        effort: 50.0,
        wraparound: false,
    };
    b.set_limits(a1, 0, limits).unwrap();
    b.add_fixed_inertia(a5, r.pose(), r.inertia()).unwrap();
    b.add_tool("tool_a", a5, r.pose()).unwrap();
    b.add_tool("tool_b", b3, r.pose()).unwrap();
    b.add_tool("tool_c", c1, r.pose()).unwrap();
    b.add_tool("tool_base", base, r.pose()).unwrap();
    b.build()
}

/// A 19-body tree on a six-DOF base with mimic joints in every relation to their leaders: a
/// leader later in the tree on another branch, a mimic below its leader, a mimic above its
/// leader, two mimics of one leader, a prismatic and a helical joint following a revolute and a
/// prismatic one, multipliers other than 1 and offsets (12 + 6 DOF, 19 internal coordinates).
pub fn mimic_tree<const N: usize>(seed: u64) -> Model<N> {
    let mut r = Rng(seed);
    let mut b = ModelBuilder::<N>::new();
    b.name("mimic-tree").unwrap();
    b.gravity(DVec3::new(0.0, 0.0, -9.80665));
    let base = b
        .add_body(
            ROOT,
            "base",
            Joint::SixDof(SixDof),
            PlueckerTransform::IDENTITY,
            "base",
            r.inertia(),
        )
        .unwrap();
    let mut add = |b: &mut ModelBuilder<N>, parent: usize, name: &str, j: Joint| {
        let pose = r.pose();
        let inertia = r.inertia();
        b.add_body(parent, name, j, pose, name, inertia).unwrap()
    };
    let rz = Joint::Revolute(Revolute::new(DVec3::Z));
    let ru = Joint::Revolute(Revolute::new(DVec3::new(0.3, -0.4, 0.8)));
    let px = Joint::Prismatic(Prismatic::new(DVec3::new(1.0, 0.2, 0.0)));
    // Branch B first in the tree: its mimic joints' leaders come later, on branch A.
    let b1 = add(&mut b, base, "b1", rz);
    let b2 = add(&mut b, b1, "b2", ru); // follows a2
    let b3 = add(&mut b, b2, "b3", px); // follows a3 (prismatic)
    let b4 = add(&mut b, b3, "b4", rz);
    // Branch A.
    let a1 = add(&mut b, base, "a1", rz);
    let a2 = add(&mut b, a1, "a2", Joint::Revolute(Revolute::new(DVec3::Y)));
    let a3 = add(&mut b, a2, "a3", px);
    let a4 = add(&mut b, a3, "a4", rz); // below a2, follows a2
    let a5 = add(&mut b, a4, "a5", Joint::Revolute(Revolute::new(DVec3::X)));
    let a6 = add(
        &mut b,
        a5,
        "a6",
        Joint::Helical(Helical::new(DVec3::Y, 0.02)),
    ); // follows a3
    // Branch C: a mimic above its leader.
    let c1 = add(&mut b, base, "c1", ru); // follows c3, below it
    let c2 = add(&mut b, c1, "c2", rz);
    let c3 = add(&mut b, c2, "c3", Joint::Revolute(Revolute::new(DVec3::X)));
    let c4 = add(&mut b, c3, "c4", px);
    b.set_mimic(b2, a2, -0.7, 0.1).unwrap();
    b.set_mimic(b3, a3, 1.5, -0.02).unwrap();
    b.set_mimic(a4, a2, 2.0, 0.3).unwrap();
    b.set_mimic(a6, a3, 0.8, 0.0).unwrap();
    b.set_mimic(c1, c3, -1.2, 0.05).unwrap();
    let limits = JointLimits {
        lower: -2.0,
        upper: 2.0,
        velocity: 3.0,
        effort: 50.0,
        wraparound: false,
    };
    b.set_limits(a2, 0, limits).unwrap();
    b.add_tool("tool_a", a6, r.pose()).unwrap();
    b.add_tool("tool_b", b4, r.pose()).unwrap();
    b.add_tool("tool_c", c4, r.pose()).unwrap();
    b.add_tool("tool_b2", b2, r.pose()).unwrap();
    b.build()
}

/// A random serial chain of `n` revolute joints with random axes and placements.
pub fn random_chain<const N: usize>(n: usize, seed: u64) -> Model<N> {
    let mut r = Rng(seed);
    let mut b = ModelBuilder::<N>::new();
    let mut parent = ROOT;
    for i in 0..n {
        let axis = match i % 4 {
            0 => DVec3::Z,
            1 => DVec3::Y,
            2 => DVec3::X,
            _ => r.vec3(1.0),
        };
        let name = format!("j{i}");
        let pose = r.pose();
        let inertia = r.inertia();
        parent = b
            .add_body(
                parent,
                &name,
                Joint::Revolute(Revolute::new(axis)),
                pose,
                &name,
                inertia,
            )
            .unwrap();
    }
    let pose = r.pose();
    b.add_tool("tool", parent, pose).unwrap();
    b.build()
}

/// A random state: configuration, velocity, acceleration.
pub fn random_state<const N: usize>(
    model: &Model<N>,
    r: &mut Rng,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut q = vec![0.0; model.nq()];
    model.random_configuration(&mut q, || r.uniform());
    let qd = (0..model.dof()).map(|_| r.range(-2.0, 2.0)).collect();
    let qdd = (0..model.dof()).map(|_| r.range(-3.0, 3.0)).collect();
    (q, qd, qdd)
}
