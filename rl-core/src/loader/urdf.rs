//! URDF, read as urdfdom and Pinocchio read it.
//!
//! Links become bodies (inertial origin with `xyz` and `rpy`: rotated inertial frames are
//! supported), joints `revolute`, `continuous` (one angle that wraps around, nq = 1, where
//! Pinocchio uses nq = 2 with cos/sin), `prismatic`, `fixed` (merged), `floating` (six-DOF) and
//! `planar` (the axis is the plane's normal). The joint order is depth-first from the root
//! link with siblings in file order (RL's) by default; [`super::JointOrder::Pinocchio`] orders
//! siblings by joint name, as Pinocchio does (urdfdom keeps joints in a sorted map).
//!
//! `<mimic joint= multiplier= offset=>` on a revolute, continuous or prismatic joint makes it
//! follow the named joint, `q = multiplier · q_leader + offset` (defaults 1 and 0, as urdfdom),
//! by default ([`super::MimicJoints`]); the leader may be anywhere in the tree, and a mimic of
//! a mimic follows the first leader. A mimic of a locked joint is locked at the position the
//! relation gives. Names are looked up in hash maps: loading is linear in the file's size.

use std::collections::HashMap;
use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use glam::{DMat3, DQuat, DVec3};
use roxmltree::Node;

use super::error::{LoadError, LoadErrorKind};
use super::tree::{Assembly, ChildOrder, Edge, EdgeKind, Node as Link, assemble};
use super::xml::{
    Lines, attr, attr_number, attr_vec3, child, children, elem, err, invalid, rot_zyx, unit_axis,
};
use super::{Format, JointOrder, LoadOptions, LoadedModel, MimicJoints};
use crate::joint::{Joint, MAX_JOINT_NV, Planar, Prismatic, Revolute, SixDof};
use crate::model::{JointLimits, ModelBuilder};
use crate::spatial::{PlueckerTransform, RigidBodyInertia};

/// URDF's default physical gravity (RL and Pinocchio use the same value).
const GRAVITY: DVec3 = DVec3::new(0.0, 0.0, -9.80665);

/// `<origin xyz rpy>` of `n`, identity when absent.
fn origin(n: Node) -> Result<PlueckerTransform, LoadError> {
    match child(n, "origin") {
        Some(o) => {
            let xyz = attr_vec3(o, "xyz", DVec3::ZERO)?;
            let rpy = attr_vec3(o, "rpy", DVec3::ZERO)?;
            Ok(PlueckerTransform::new(rot_zyx(rpy.x, rpy.y, rpy.z), xyz))
        }
        None => Ok(PlueckerTransform::IDENTITY),
    }
}

/// A link's inertia in the link frame, `None` without `<inertial>`.
fn link_inertia(link: Node) -> Result<Option<RigidBodyInertia>, LoadError> {
    let Some(inertial) = child(link, "inertial") else {
        return Ok(None);
    };
    let frame = origin(inertial)?;
    let mass = child(inertial, "mass")
        .ok_or_else(|| err(link, LoadErrorKind::MissingInertia { part: "mass" }))?;
    let m = attr_number(mass, "value", f64::NAN)?;
    if m.is_nan() {
        return Err(err(
            mass,
            LoadErrorKind::MissingAttribute { attribute: "value" },
        ));
    }
    if m < 0.0 {
        return Err(invalid(mass, "value", &m.to_string(), "negative mass"));
    }
    let i = child(inertial, "inertia")
        .ok_or_else(|| err(link, LoadErrorKind::MissingInertia { part: "inertia" }))?;
    let get = |name: &'static str| -> Result<f64, LoadError> {
        let t = attr(i, name)?;
        super::xml::number(i, name, t)
    };
    let (ixx, ixy, ixz, iyy, iyz, izz) = (
        get("ixx")?,
        get("ixy")?,
        get("ixz")?,
        get("iyy")?,
        get("iyz")?,
        get("izz")?,
    );
    let ic = DMat3::from_cols(
        DVec3::new(ixx, ixy, ixz),
        DVec3::new(ixy, iyy, iyz),
        DVec3::new(ixz, iyz, izz),
    );
    let r = frame.rotation;
    Ok(Some(RigidBodyInertia::from_com(
        m,
        frame.translation,
        r * ic * r.transpose(),
    )))
}

/// `<limit>` of `j` (position limits only when `positional`).
fn limit(j: Node, required: bool, positional: bool) -> Result<JointLimits, LoadError> {
    let Some(l) = child(j, "limit") else {
        if required {
            return Err(err(j, LoadErrorKind::MissingElement { child: "limit" }));
        }
        return Ok(JointLimits::UNLIMITED);
    };
    let mut out = JointLimits {
        velocity: super::rate_limit(attr_number(l, "velocity", f64::INFINITY)?),
        effort: super::rate_limit(attr_number(l, "effort", f64::INFINITY)?),
        ..JointLimits::UNLIMITED
    };
    if positional {
        // urdfdom's defaults: 0 for a missing bound.
        out.lower = attr_number(l, "lower", 0.0)?;
        out.upper = attr_number(l, "upper", 0.0)?;
        if out.lower > out.upper {
            return Err(invalid(
                l,
                "lower",
                l.attribute("lower").unwrap_or(""),
                "greater than upper",
            ));
        }
    }
    if out.velocity < 0.0 || out.effort < 0.0 {
        return Err(invalid(l, "velocity/effort", "", "negative"));
    }
    Ok(out)
}

pub(crate) fn from_document<const N: usize>(
    robot: Node,
    options: &LoadOptions,
) -> Result<LoadedModel<N>, LoadError> {
    let opt = &options.urdf;
    let tag = robot.tag_name().name();
    if tag != "robot" {
        return Err(err(
            robot,
            LoadErrorKind::UnknownFormat {
                root: tag.to_string(),
            },
        ));
    }
    let mut warnings = Vec::new();
    let lines = Lines::new(robot.document().input_text());

    let mut links: Vec<Link> = Vec::new();
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for l in children(robot, "link") {
        let name = attr(l, "name")?;
        if link_index.insert(name, links.len()).is_some() {
            return Err(err(
                l,
                LoadErrorKind::DuplicateName {
                    name: name.to_string(),
                },
            ));
        }
        links.push(Link {
            name: name.to_string(),
            inertia: link_inertia(l)?,
            elem: lines.elem(l),
        });
    }

    let joints: Vec<Node> = children(robot, "joint").collect();
    let mut joint_index: HashMap<&str, usize> = HashMap::new();
    for (k, j) in joints.iter().enumerate() {
        let name = attr(*j, "name")?;
        if joint_index.insert(name, k).is_some() {
            return Err(err(
                *j,
                LoadErrorKind::DuplicateName {
                    name: name.to_string(),
                },
            ));
        }
    }
    let locked: HashMap<&str, usize> = opt
        .locked_joints
        .iter()
        .enumerate()
        .map(|(k, (n, _))| (n.as_str(), k))
        .collect();
    let mimics = Mimics {
        joints: &joints,
        index: &joint_index,
        locked: &locked,
    };

    let mut edges: Vec<Edge> = Vec::new();
    // Moving joints that follow another: (edge, leader joint, multiplier, offset).
    let mut followers: Vec<(usize, String, f64, f64)> = Vec::new();
    let mut locked_used = std::vec![false; opt.locked_joints.len()];
    for &j in &joints {
        let name = attr(j, "name")?.to_string();
        let ty = attr(j, "type")?;
        let find = |tag: &'static str| -> Result<usize, LoadError> {
            let e = child(j, tag)
                .ok_or_else(|| err(j, LoadErrorKind::MissingElement { child: tag }))?;
            let link = attr(e, "link")?;
            link_index.get(link).copied().ok_or_else(|| {
                err(
                    j,
                    LoadErrorKind::UnresolvedReference {
                        target: link.to_string(),
                    },
                )
            })
        };
        let (parent, child_link) = (find("parent")?, find("child")?);
        let o = origin(j)?;
        // As urdfdom: fixed and floating joints have no axis (files often write "0 0 0").
        let axis = match child(j, "axis") {
            Some(a) if ty != "fixed" && ty != "floating" => {
                unit_axis(a, "xyz", attr_vec3(a, "xyz", DVec3::X)?)?
            }
            _ => DVec3::X,
        };
        let mut lock = locked
            .get(name.as_str())
            .map(|&k| (k, opt.locked_joints[k].1));
        if let Some((k, _)) = lock {
            locked_used[k] = true;
        }
        let mut follows = None;
        if ty != "fixed" && lock.is_none() && child(j, "mimic").is_some() {
            match opt.mimic {
                MimicJoints::Reject => {
                    return Err(err(
                        j,
                        LoadErrorKind::Unsupported {
                            feature: "<mimic> (a joint coupled to another): this load refuses \
                                      mimic joints"
                                .into(),
                        },
                    ));
                }
                MimicJoints::Independent => warnings.push(format!(
                    "mimic joint \"{name}\" loaded as an independent joint"
                )),
                MimicJoints::Follow => match mimics.resolve(j)? {
                    Ok((leader, m, off)) => match locked.get(leader.as_str()) {
                        // Following a locked joint: locked where the relation puts it.
                        Some(&k) => lock = Some((usize::MAX, m * opt.locked_joints[k].1 + off)),
                        None => follows = Some((leader, m, off)),
                    },
                    // As urdfdom and Pinocchio's default read it: an independent joint.
                    Err(missing) => warnings.push(format!(
                        "mimic joint \"{name}\" follows \"{missing}\", which does not exist: \
                         loaded as an independent joint"
                    )),
                },
            }
        }
        let id = PlueckerTransform::IDENTITY;
        let mut lim = [JointLimits::UNLIMITED; MAX_JOINT_NV];
        let (joint, post, child_offset) = match ty {
            "fixed" => (None, id, id),
            "revolute" => {
                lim[0] = limit(j, true, true)?;
                (Some(Joint::Revolute(Revolute::new(axis))), id, id)
            }
            "continuous" => {
                let pi = core::f64::consts::PI;
                let l = limit(j, false, false)?;
                lim[0] = JointLimits {
                    lower: -pi,
                    upper: pi,
                    wraparound: true,
                    ..l
                };
                (Some(Joint::Revolute(Revolute::new(axis))), id, id)
            }
            "prismatic" => {
                lim[0] = limit(j, true, true)?;
                (Some(Joint::Prismatic(Prismatic::new(axis))), id, id)
            }
            "floating" => (Some(Joint::SixDof(SixDof)), id, id),
            "planar" => {
                // Our planar joint moves in its frame's x-y plane: turn that frame so its z is the
                // URDF normal, and give the child link its original axes back.
                let align = DMat3::from_quat(DQuat::from_rotation_arc(DVec3::Z, axis));
                let (post, off) = if axis == DVec3::Z {
                    (id, id)
                } else {
                    (
                        PlueckerTransform::from_rotation(align),
                        PlueckerTransform::from_rotation(align.transpose()),
                    )
                };
                (Some(Joint::Planar(Planar)), post, off)
            }
            _ => {
                return Err(err(
                    j,
                    LoadErrorKind::UnknownJointType {
                        joint_type: ty.to_string(),
                    },
                ));
            }
        };
        let kind = match (joint, lock) {
            (None, _) => EdgeKind::Fixed,
            (Some(joint), Some((_, value))) => {
                if joint.nq() != 1 {
                    return Err(err(
                        j,
                        LoadErrorKind::Unsupported {
                            feature: format!("locking a {ty} joint (only 1-DOF joints lock)"),
                        },
                    ));
                }
                edges.push(Edge {
                    parent,
                    child: child_link,
                    name,
                    source_type: format!("{ty} (locked)"),
                    origin: o * post * joint.transform(&[value]) * child_offset,
                    kind: EdgeKind::Fixed,
                    elem: lines.elem(j),
                });
                continue;
            }
            (Some(joint), None) => EdgeKind::Moving {
                joint,
                post,
                child_offset,
                limits: lim,
            },
        };
        if let Some((leader, m, off)) = follows {
            followers.push((edges.len(), leader, m, off));
        }
        edges.push(Edge {
            parent,
            child: child_link,
            name,
            source_type: ty.to_string(),
            origin: o,
            kind,
            elem: lines.elem(j),
        });
    }
    if let Some(k) = locked_used.iter().position(|u| !u) {
        return Err(err(
            robot,
            LoadErrorKind::UnresolvedReference {
                target: opt.locked_joints[k].0.clone(),
            },
        ));
    }

    if links.is_empty() {
        return Err(err(robot, LoadErrorKind::MissingElement { child: "link" }));
    }
    let mut has_parent = std::vec![false; links.len()];
    for e in &edges {
        has_parent[e.child] = true;
    }
    let roots: Vec<usize> = (0..links.len()).filter(|&i| !has_parent[i]).collect();
    if roots.len() != 1 {
        return Err(err(
            robot,
            LoadErrorKind::roots(roots.iter().map(|&i| links[i].name.as_str())),
        ));
    }

    let mut builder = ModelBuilder::<N>::new();
    builder
        .name(super::display_name(robot.attribute("name").unwrap_or("")))
        .map_err(|e| err(robot, LoadErrorKind::Model(e)))?;
    builder.gravity(GRAVITY);
    let how = Assembly {
        root: roots[0],
        base: PlueckerTransform::IDENTITY,
        floating: opt.floating_base.then_some("root_joint"),
        order: match opt.joint_order {
            JointOrder::Pinocchio => ChildOrder::ByName,
            JointOrder::File => ChildOrder::File,
        },
        leaf_tools: opt.leaf_tools,
        extra_tools: &opt.extra_tools,
        doc_elem: elem(robot),
        inertia: options.inertia,
    };
    let assembled = assemble(&links, &edges, &how, &mut builder)?;
    warnings.extend(assembled.warnings.iter().cloned());
    if !followers.is_empty() {
        let body_of: HashMap<&str, usize> = assembled
            .transforms
            .iter()
            .filter(|t| t.moving)
            .map(|t| (t.name.as_str(), t.body))
            .collect();
        for (e, leader, m, off) in &followers {
            let edge = &edges[*e];
            let mimic_err = |reason: String| {
                LoadError::at(
                    edge.elem.clone(),
                    LoadErrorKind::Mimic {
                        joint: edge.name.clone(),
                        reason,
                    },
                )
            };
            let (Some(&b), Some(&l)) = (
                body_of.get(edge.name.as_str()),
                body_of.get(leader.as_str()),
            ) else {
                return Err(mimic_err(format!(
                    "it follows \"{leader}\", which is not a moving joint of the model"
                )));
            };
            builder.set_mimic(b, l, *m, *off).map_err(|e| match e {
                crate::model::ModelError::InvalidMimic { reason, .. } => {
                    mimic_err(format!("it cannot follow \"{leader}\": {reason}"))
                }
                e => LoadError::at(edge.elem.clone(), LoadErrorKind::Model(e)),
            })?;
        }
    }
    Ok(LoadedModel {
        model: builder.build(),
        format: Format::Urdf,
        home: None,
        frames: assembled.frames,
        transforms: assembled.transforms,
        warnings,
    })
}

/// The `<mimic>` tags of a file's joints, by joint name.
struct Mimics<'a, 'i> {
    joints: &'a [Node<'a, 'i>],
    index: &'a HashMap<&'a str, usize>,
    /// Locked joints end a chain: their position is known.
    locked: &'a HashMap<&'a str, usize>,
}

impl Mimics<'_, '_> {
    /// The joint that mimic joint `j` finally follows (through other mimic joints, up to the
    /// first that is not one or is locked), with the multiplier and offset composed along the
    /// way: `q_j = m q_leader + o`; or the name of a joint in the chain that does not exist.
    #[allow(clippy::type_complexity)]
    fn resolve(&self, j: Node) -> Result<Result<(String, f64, f64), String>, LoadError> {
        let name = j.attribute("name").unwrap_or("");
        let fail = |reason: String| {
            err(
                j,
                LoadErrorKind::Mimic {
                    joint: name.to_string(),
                    reason,
                },
            )
        };
        let (mut m, mut o) = (1.0, 0.0);
        let mut at = j;
        // A chain longer than the number of joints has a loop.
        for _ in 0..=self.joints.len() {
            let end = at != j && self.locked.contains_key(at.attribute("name").unwrap_or(""));
            let Some(tag) = child(at, "mimic").filter(|_| !end) else {
                let leader = at.attribute("name").unwrap_or("");
                let ty = at.attribute("type").unwrap_or("");
                if !matches!(ty, "revolute" | "continuous" | "prismatic") {
                    return Err(fail(format!(
                        "it follows \"{leader}\", a {ty} joint (only revolute, continuous and \
                         prismatic joints can be followed)"
                    )));
                }
                return Ok(Ok((leader.to_string(), m, o)));
            };
            let ty = at.attribute("type").unwrap_or("");
            if !matches!(ty, "revolute" | "continuous" | "prismatic") {
                return Err(fail(format!(
                    "a {ty} joint cannot follow another (only revolute, continuous and \
                     prismatic joints can)"
                )));
            }
            let target = attr(tag, "joint")?;
            let mult = super::xml::attr_number(tag, "multiplier", 1.0)?;
            let off = super::xml::attr_number(tag, "offset", 0.0)?;
            // q_at = mult q_target + off, and q_j = m q_at + o.
            o += m * off;
            m *= mult;
            let Some(&k) = self.index.get(target) else {
                return Ok(Err(target.to_string()));
            };
            at = self.joints[k];
            if at == j {
                return Err(fail("its mimic chain loops back to it".to_string()));
            }
        }
        Err(fail("its mimic chain has a loop".to_string()))
    }
}
