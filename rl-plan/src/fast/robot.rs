//! The robot for the sphere kernel: its kinematic chain in `f32`, rearranged so every joint
//! turns about (or slides along) its frame's z axis, and its spheres per link.
//!
//! Any revolute or prismatic joint axis `a` is brought onto z by a constant rotation `A` with
//! `A e_z = a` (a signed permutation when `a` is a coordinate axis): the body frame `B` becomes
//! `B·A`, the joint's placement `P` becomes `A_parentᵀ P A`, and the spheres and child
//! placements are expressed in the new frame. Then a revolute joint changes only two columns
//! of the rotation (`c·Q₀ + s·Q₁`, `c·Q₁ − s·Q₀`), and a placement whose rotation is a signed
//! permutation (most URDF `rpy` of multiples of π/2, snapped within 1e-7) costs nothing but a
//! choice of columns.

use glam::{DMat3, DVec3};
use rl_core::Model;
use rl_core::joint::Joint;
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;

use super::spheres::SphereSet;
use crate::error::PlanError;

/// Most moving bodies the kernel handles.
pub const MAX_FAST_BODIES: usize = 24;

/// How a placement's rotation acts on the parent's columns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Rot {
    /// Column `j` of the product is `sign[j]` × parent column `col[j]`.
    Perm { col: [u8; 3], sign: [f32; 3] },
    /// A general rotation (column-major, `m[j]` is column `j`).
    General([[f32; 3]; 3]),
}

/// The joint's motion along its (new) z axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Motion {
    /// Rotation about z.
    Revolute,
    /// Translation along z.
    Prismatic,
}

/// One moving body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct FastJoint {
    /// Parent body, or `u32::MAX` for the base.
    pub(crate) parent: u32,
    /// Index of its coordinate in `q`.
    pub(crate) q: u32,
    pub(crate) motion: Motion,
    pub(crate) rot: Rot,
    pub(crate) trans: [f32; 3],
}

/// A link's spheres: world-fixed (`body == u32::MAX`) or on a moving body.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FastLink {
    pub(crate) name: String,
    pub(crate) body: u32,
    /// Bounding sphere of the link's spheres (centre in the body frame, radius).
    pub(crate) bound: [f32; 4],
    /// Range into `spheres`.
    pub(crate) first: u32,
    pub(crate) count: u32,
}

/// The links fixed to one body (or to the world), with a bounding sphere of all their spheres:
/// the first level of the sphere hierarchy (body, link, sphere).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Group {
    pub(crate) body: u32,
    pub(crate) bound: [f32; 4],
    pub(crate) links: Vec<u16>,
}

/// The self-collision link pairs between two groups.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct GroupPair {
    pub(crate) a: u16,
    pub(crate) b: u16,
    pub(crate) links: Vec<(u16, u16)>,
}

/// The robot in the kernel's form.
#[derive(Clone, Debug, PartialEq)]
pub struct SphereRobot {
    pub(crate) dof: usize,
    pub(crate) joints: Vec<FastJoint>,
    /// The base: rotation (column-major) and translation of the root frame in the world.
    pub(crate) base_rot: [[f32; 3]; 3],
    pub(crate) base_trans: [f32; 3],
    pub(crate) links: Vec<FastLink>,
    /// Sphere centres (body frame, or world for fixed links) and radii.
    pub(crate) spheres: Vec<[f32; 4]>,
    /// Link pairs checked for self-collision.
    pub(crate) self_pairs: Vec<(u16, u16)>,
    /// Self-collision pairs of the geometry this sphere model does not check (their spheres
    /// always touch).
    pub(crate) unmodelled: Vec<(String, String)>,
    /// Links grouped by body.
    pub(crate) groups: Vec<Group>,
    /// Moving groups, distal first: the order of the environment checks.
    pub(crate) env_order: Vec<u16>,
    /// The self-collision pairs grouped by the bodies' pair.
    pub(crate) group_pairs: Vec<GroupPair>,
}

/// The smallest-ish sphere around spheres (centre of their box, radius to the farthest
/// surface), a hair larger so `f32` rounding cannot escape it.
fn bounding(spheres: &[[f32; 4]]) -> [f32; 4] {
    let c: Vec<(DVec3, f64)> = spheres
        .iter()
        .map(|s| {
            (
                DVec3::new(s[0] as f64, s[1] as f64, s[2] as f64),
                s[3] as f64,
            )
        })
        .collect();
    let (lo, hi) = c.iter().fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), (p, _)| (lo.min(*p), hi.max(*p)),
    );
    let m = (lo + hi) * 0.5;
    let r = c
        .iter()
        .map(|(p, r)| (*p - m).length() + r)
        .fold(0.0f64, f64::max);
    [
        m.x as f32,
        m.y as f32,
        m.z as f32,
        (r * (1.0 + 1e-6) + 1e-6) as f32,
    ]
}

fn f3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// A rotation taking `e_z` to the unit vector `a` (a signed permutation for coordinate axes).
fn align_z(a: DVec3) -> DMat3 {
    let ax = [DVec3::X, DVec3::Y, DVec3::Z];
    for (i, e) in ax.iter().enumerate() {
        for s in [1.0, -1.0] {
            if (a - *e * s).length() < 1e-12 {
                // z → s·e_i; complete to a right-handed frame with the other two axes.
                let j = (i + 1) % 3;
                let x = ax[j];
                let z = *e * s;
                let y = z.cross(x);
                return DMat3::from_cols(x, y, z);
            }
        }
    }
    let z = a.normalize();
    let t = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = t.cross(z).normalize();
    DMat3::from_cols(x, z.cross(x), z)
}

/// A rotation as a signed permutation, if it is one within 1e-7.
fn as_perm(m: &DMat3) -> Option<Rot> {
    let mut col = [0u8; 3];
    let mut sign = [1.0f32; 3];
    for j in 0..3 {
        let c = m.col(j);
        let mut found = None;
        for i in 0..3 {
            let v = c[i];
            if (v.abs() - 1.0).abs() < 1e-7 {
                if found.is_some() {
                    return None;
                }
                found = Some((i, v.signum()));
            } else if v.abs() > 1e-7 {
                return None;
            }
        }
        let (i, s) = found?;
        col[j] = i as u8;
        sign[j] = s as f32;
    }
    Some(Rot::Perm { col, sign })
}

fn rot_of(m: &DMat3) -> Rot {
    as_perm(m).unwrap_or(Rot::General([f3(m.x_axis), f3(m.y_axis), f3(m.z_axis)]))
}

impl SphereRobot {
    /// The kernel's robot from an rl-core model (revolute and prismatic joints only), its base
    /// pose in the world, the spheres of its links, and the link pairs (by name) to check for
    /// self-collision. Links of `spheres` the model does not place are left out.
    pub fn new<const N: usize>(
        model: &Model<N>,
        base: PlueckerTransform,
        spheres: &SphereSet,
        self_pairs: &[(String, String)],
    ) -> Result<Self, PlanError> {
        let n = model.body_count();
        if n > MAX_FAST_BODIES {
            return Err(PlanError::Unsupported(format!(
                "{n} moving bodies in the sphere checker (at most {MAX_FAST_BODIES})"
            )));
        }
        if model.nq() != model.dof() || model.dof() != n {
            return Err(PlanError::Unsupported(
                "joints of more than one coordinate (spherical, free, planar, cylindrical) in \
                 the sphere checker; use the exact checker"
                    .into(),
            ));
        }
        // The alignment of every body frame.
        let mut align = Vec::with_capacity(n);
        let mut motions = Vec::with_capacity(n);
        for b in 0..n {
            let (axis, motion) = match model.joint(b) {
                Joint::Revolute(j) => (j.axis, Motion::Revolute),
                Joint::Prismatic(j) => (j.axis, Motion::Prismatic),
                other => {
                    return Err(PlanError::Unsupported(format!(
                        "{} joints in the sphere checker (joint \"{}\")",
                        other.kind().name(),
                        model.joint_name(b)
                    )));
                }
            };
            align.push(align_z(axis.normalize()));
            motions.push(motion);
        }
        let align_of = |b: usize| if b == ROOT { DMat3::IDENTITY } else { align[b] };
        let mut joints = Vec::with_capacity(n);
        for b in 0..n {
            let p = model.parent(b);
            let x = model.placement(b);
            let ap = align_of(p);
            let rot = ap.transpose() * x.rotation * align[b];
            let trans = ap.transpose() * x.translation;
            joints.push(FastJoint {
                parent: if p == ROOT { u32::MAX } else { p as u32 },
                q: model.q_index(b) as u32,
                motion: motions[b],
                rot: rot_of(&rot),
                trans: f3(trans),
            });
        }
        let mut links = Vec::new();
        let mut all = Vec::new();
        for l in &spheres.links {
            let Some((body, placement)) = l.frame else {
                continue;
            };
            let (a, to_frame) = if body == ROOT {
                // World-fixed: centres in the world.
                (DMat3::IDENTITY, base * placement)
            } else {
                (align[body], placement)
            };
            let centres: Vec<(DVec3, f64)> = l
                .spheres
                .iter()
                .map(|(c, r)| (a.transpose() * to_frame.transform_point(*c), *r))
                .collect();
            let first = all.len() as u32;
            for (c, r) in &centres {
                all.push([c.x as f32, c.y as f32, c.z as f32, *r as f32]);
            }
            links.push(FastLink {
                name: l.name.clone(),
                body: if body == ROOT { u32::MAX } else { body as u32 },
                bound: bounding(&all[first as usize..]),
                first,
                count: centres.len() as u32,
            });
        }
        let index = |name: &str| links.iter().position(|l| l.name == name);
        let mut pairs = Vec::new();
        for (a, b) in self_pairs {
            if let (Some(i), Some(j)) = (index(a), index(b)) {
                if links[i].body == u32::MAX && links[j].body == u32::MAX {
                    continue; // two fixed links never move against each other
                }
                pairs.push((i as u16, j as u16));
            }
        }
        // Groups: the links of each body (and of the world).
        let mut groups: Vec<Group> = Vec::new();
        for (i, l) in links.iter().enumerate() {
            match groups.iter_mut().find(|g| g.body == l.body) {
                Some(g) => g.links.push(i as u16),
                None => groups.push(Group {
                    body: l.body,
                    bound: [0.0; 4],
                    links: vec![i as u16],
                }),
            }
        }
        for g in &mut groups {
            let spheres: Vec<[f32; 4]> = g
                .links
                .iter()
                .flat_map(|&i| {
                    let l = &links[i as usize];
                    all[l.first as usize..(l.first + l.count) as usize]
                        .iter()
                        .copied()
                })
                .collect();
            g.bound = bounding(&spheres);
        }
        let group_of = |link: u16| {
            groups
                .iter()
                .position(|g| g.links.contains(&link))
                .expect("every link is in a group") as u16
        };
        let mut group_pairs: Vec<GroupPair> = Vec::new();
        for &(a, b) in &pairs {
            let (ga, gb) = (group_of(a), group_of(b));
            let (ga, gb, a, b) = if ga <= gb {
                (ga, gb, a, b)
            } else {
                (gb, ga, b, a)
            };
            match group_pairs.iter_mut().find(|p| (p.a, p.b) == (ga, gb)) {
                Some(p) => p.links.push((a, b)),
                None => group_pairs.push(GroupPair {
                    a: ga,
                    b: gb,
                    links: vec![(a, b)],
                }),
            }
        }
        // Distal bodies (deeper in the tree) first.
        let depth = |mut b: usize| {
            let mut d = 0;
            while b != ROOT {
                b = model.parent(b);
                d += 1;
            }
            d
        };
        let mut env_order: Vec<u16> = (0..groups.len())
            .filter(|&i| groups[i].body != u32::MAX)
            .map(|i| i as u16)
            .collect();
        env_order.sort_by_key(|&i| std::cmp::Reverse(depth(groups[i as usize].body as usize)));
        let r = base.rotation;
        Ok(Self {
            dof: n,
            joints,
            base_rot: [f3(r.x_axis), f3(r.y_axis), f3(r.z_axis)],
            base_trans: f3(base.translation),
            links,
            spheres: all,
            self_pairs: pairs,
            unmodelled: Vec::new(),
            groups,
            env_order,
            group_pairs,
        })
    }

    /// Degrees of freedom.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// The number of spheres.
    pub fn sphere_count(&self) -> usize {
        self.spheres.len()
    }

    /// The same robot, noting link pairs it leaves out of the self-collision check.
    pub fn with_unmodelled(mut self, pairs: Vec<(String, String)>) -> Self {
        self.unmodelled = pairs;
        self
    }

    /// Self-collision pairs of the geometry this model does not check.
    pub fn unmodelled_pairs(&self) -> &[(String, String)] {
        &self.unmodelled
    }

    /// The number of link pairs checked for self-collision.
    pub fn self_pair_count(&self) -> usize {
        self.self_pairs.len()
    }

    /// The base position in the world (the environment's reference point).
    pub fn base_position(&self) -> DVec3 {
        DVec3::new(
            self.base_trans[0] as f64,
            self.base_trans[1] as f64,
            self.base_trans[2] as f64,
        )
    }
}
