//! RL's XML model format (`rlmdl`), read as RL's `XmlFactory` reads it.
//!
//! Conventions (shared/reference/rl-models.md): angles in degrees with `Rz·Ry·Rx`, body inertia
//! about the centre of mass in body axes with defaults `m = 1`, `I = 1`, `cm = 0`, and `<g>` the
//! fictitious base acceleration (physical gravity is its negative). Only the first `<model>` is
//! loaded. Joint offsets are folded into the placement, so `q` here is RL's `q`.

use std::format;
use std::string::ToString;
use std::vec::Vec;

use glam::{DMat3, DVec3};
use roxmltree::Node;

use super::error::{LoadError, LoadErrorKind};
use super::tree::{Edge, EdgeKind};
use super::xml::rl::{self, DEG, Frames, Tree, indexed, limits, pose};
use super::xml::{
    Lines, child, child_number, child_xyz, children, err, invalid, number, unit_axis,
};
use super::{Format, LoadOptions, LoadedModel};
use crate::joint::{
    Cylindrical, Helical, Joint, MAX_JOINT_NV, Prismatic, Revolute, SixDof, Spherical,
};
use crate::model::JointLimits;
use crate::spatial::{PlueckerTransform, RigidBodyInertia};

const TRANSFORMS: [&str; 7] = [
    "fixed",
    "revolute",
    "prismatic",
    "helical",
    "cylindrical",
    "spherical",
    "sixDof",
];
const XINCLUDE: &str = "http://www.w3.org/2001/XInclude";

/// Loads the first model of an RL XML document.
pub(crate) fn from_document<const N: usize>(
    root: Node,
    options: &LoadOptions,
) -> Result<LoadedModel<N>, LoadError> {
    let tag = root.tag_name().name();
    if tag == "stylesheet" || tag == "transform" {
        return Err(err(
            root,
            LoadErrorKind::Unsupported {
                feature: "XSLT-parameterised model: apply the stylesheet first (e.g. `xsltproc \
                          file.xml > model.xml`) and load the result"
                    .into(),
            },
        ));
    }
    if let Some(x) = root
        .descendants()
        .find(|n| n.is_element() && n.tag_name().namespace() == Some(XINCLUDE))
    {
        return Err(err(
            x,
            LoadErrorKind::Unsupported {
                feature: "XInclude: expand it first (e.g. `xmllint --xinclude`)".into(),
            },
        ));
    }
    let container = rl::container(root, "rlmdl", "mdl")?;
    let model = child(container, "model")
        .ok_or_else(|| err(container, LoadErrorKind::MissingElement { child: "model" }))?;
    let mut warnings = Vec::new();
    if children(container, "model").nth(1).is_some() {
        warnings.push("only the first <model> is loaded, as RL does".to_string());
    }

    let lines = Lines::new(root.document().input_text());
    // Frames: world, bodies and plain frames, by id.
    let frames = rl::frames(model, ["body", "frame"], &lines, |n, _| {
        Ok(if n.tag_name().name() == "body" {
            Some(body_inertia(n)?)
        } else {
            None
        })
    })?;
    let base = pose(frames.world_node)?;
    let g = match child(frames.world_node, "g") {
        Some(g) => child_xyz(g, DVec3::ZERO)?,
        None => DVec3::ZERO,
    };

    // Transforms, in file order.
    let mut edges: Vec<Edge> = Vec::new();
    for n in model.children().filter(|n| n.is_element()) {
        let t = n.tag_name().name();
        if TRANSFORMS.contains(&t) {
            edges.push(transform(n, &frames, &lines)?);
        } else if matches!(
            t,
            "world" | "body" | "frame" | "manufacturer" | "name" | "home"
        ) {
        } else if matches!(t, "gammaPosition" | "gammaVelocity") {
            check_identity_gamma(n)?;
        } else {
            rl::unread(n, false, "RL's XmlFactory", &mut warnings)?;
        }
    }

    let tree = Tree {
        nodes: &frames.nodes,
        world: frames.world,
        edges: &edges,
        base,
        // `<g>` is the acceleration of the base that stands in for gravity, in world-frame axes.
        gravity: Some(DVec3::ZERO - base.rotation * g), // not -(..): no -0.0
    };
    // Amended in place: a fixed-capacity model is large, so it is not copied through `?`.
    let mut loaded = rl::assemble_model(model, &tree, Format::Rlmdl, options, warnings);
    if let (Ok(l), Some(h)) = (&mut loaded, child(model, "home")) {
        l.home = Some(home(h, l.model.nq())?);
    }
    loaded
}

/// A body's inertia from `cm`, `i` (about the COM, body axes) and `m`, with RL's defaults.
fn body_inertia(n: Node) -> Result<RigidBodyInertia, LoadError> {
    let cm = match child(n, "cm") {
        Some(c) => child_xyz(c, DVec3::ZERO)?,
        None => DVec3::ZERO,
    };
    let (xx, yy, zz, yz, xz, xy) = match child(n, "i") {
        Some(i) => (
            child_number(i, "xx", 1.0)?,
            child_number(i, "yy", 1.0)?,
            child_number(i, "zz", 1.0)?,
            child_number(i, "yz", 0.0)?,
            child_number(i, "xz", 0.0)?,
            child_number(i, "xy", 0.0)?,
        ),
        None => (1.0, 1.0, 1.0, 0.0, 0.0, 0.0),
    };
    let m = child_number(n, "m", 1.0)?;
    if m < 0.0 {
        let c = child(n, "m").unwrap_or(n);
        return Err(invalid(c, "m", &m.to_string(), "negative mass"));
    }
    let ic = DMat3::from_cols(
        DVec3::new(xx, xy, xz),
        DVec3::new(xy, yy, yz),
        DVec3::new(xz, yz, zz),
    );
    Ok(RigidBodyInertia::from_com(m, cm, ic))
}

/// The `k`-th (from 1) `axis` child, or `default` if absent. Missing components are 0.
fn axis(n: Node, k: usize, default: DVec3) -> Result<DVec3, LoadError> {
    match children(n, "axis").nth(k - 1) {
        Some(a) => unit_axis(a, "axis", child_xyz(a, DVec3::ZERO)?),
        None => Ok(default),
    }
}

fn no_offset(n: Node, kind: &str) -> Result<(), LoadError> {
    for o in children(n, "offset") {
        if number(o, "offset", o.text().unwrap_or(""))? != 0.0 {
            return Err(err(
                o,
                LoadErrorKind::Unsupported {
                    feature: format!("an offset on a {kind} joint"),
                },
            ));
        }
    }
    Ok(())
}

fn same_axis(n: Node, a: DVec3, b: DVec3, kind: &str) -> Result<(), LoadError> {
    if (a - b).length() > 1e-12 {
        return Err(err(
            n,
            LoadErrorKind::Unsupported {
                feature: format!("a {kind} joint whose two axes differ"),
            },
        ));
    }
    Ok(())
}

/// One transform element.
fn transform(n: Node, frames: &Frames, lines: &Lines) -> Result<Edge, LoadError> {
    rl::edge(n, &frames.index, lines, |_| moving_or_fixed(n))
}

/// The kind and origin of transform element `n`.
fn moving_or_fixed(n: Node) -> Result<(EdgeKind, PlueckerTransform), LoadError> {
    let t = n.tag_name().name();
    let mut lim = [JointLimits::UNLIMITED; MAX_JOINT_NV];
    let id = PlueckerTransform::IDENTITY;
    // A moving joint sits at the frame it is attached to; `post` is its offset.
    let moving = |joint, post, limits| {
        let kind = EdgeKind::Moving {
            joint,
            post,
            child_offset: id,
            limits,
        };
        (kind, id)
    };
    Ok(match t {
        "fixed" => (EdgeKind::Fixed, pose(n)?),
        "revolute" => {
            let j = Revolute::new(axis(n, 1, DVec3::Z)?);
            lim[0] = limits(n, 1, DEG)?;
            let post = j.transform(indexed(n, "offset", 1, 0.0)? * DEG);
            let joint = Joint::Revolute(j);
            moving(joint, post, lim)
        }
        "prismatic" => {
            let j = Prismatic::new(axis(n, 1, DVec3::Z)?);
            lim[0] = limits(n, 1, 1.0)?;
            let post = j.transform(indexed(n, "offset", 1, 0.0)?);
            let joint = Joint::Prismatic(j);
            moving(joint, post, lim)
        }
        "helical" => {
            // RL reads helical limits without unit conversion; its rotation ignores the offset
            // while its translation uses it.
            let a = axis(n, 1, DVec3::Z)?;
            same_axis(n, a, axis(n, 2, DVec3::Z)?, "helical")?;
            let pitch = child_number(n, "pitch", 1.0)?;
            lim[0] = limits(n, 1, 1.0)?;
            let post =
                PlueckerTransform::from_translation(a * pitch * indexed(n, "offset", 1, 0.0)?);
            let joint = Joint::Helical(Helical::new(a, pitch));
            moving(joint, post, lim)
        }
        "cylindrical" => {
            // RL reads cylindrical limits and offsets without unit conversion (rad, m).
            let a = axis(n, 1, DVec3::Z)?;
            same_axis(n, a, axis(n, 2, DVec3::Z)?, "cylindrical")?;
            let j = Cylindrical::new(a);
            lim[0] = limits(n, 1, 1.0)?;
            lim[1] = limits(n, 2, 1.0)?;
            let post = j.transform(indexed(n, "offset", 1, 0.0)?, indexed(n, "offset", 2, 0.0)?);
            let joint = Joint::Cylindrical(j);
            moving(joint, post, lim)
        }
        "spherical" => {
            no_offset(n, "spherical")?;
            let joint = Joint::Spherical(Spherical);
            moving(joint, id, lim)
        }
        "sixDof" => {
            // max[k]/min[k], k = 1..3: the translation, m; speed[k], k = 1..6: [linear; angular].
            no_offset(n, "sixDof")?;
            for (k, l) in lim.iter_mut().enumerate() {
                let full = limits(n, k + 1, 1.0)?;
                *l = if k < 3 {
                    full
                } else {
                    JointLimits {
                        velocity: full.velocity,
                        ..*l
                    }
                };
            }
            let joint = Joint::SixDof(SixDof);
            moving(joint, id, lim)
        }
        _ => {
            return Err(err(
                n,
                LoadErrorKind::UnknownJointType {
                    joint_type: t.to_string(),
                },
            ));
        }
    })
}

/// `home/q` (rad, or degrees with `unit="deg"`); must have `nq` entries.
fn home(h: Node, nq: usize) -> Result<Vec<f64>, LoadError> {
    let mut q = Vec::new();
    for c in children(h, "q") {
        let mut x = number(c, "q", c.text().unwrap_or(""))?;
        if c.attribute("unit") == Some("deg") {
            x *= DEG;
        }
        q.push(x);
    }
    if q.len() != nq {
        return Err(invalid(
            h,
            "home position",
            &format!("{} values", q.len()),
            "the model's position has a different length",
        ));
    }
    Ok(q)
}

/// RL's joint coupling matrices: only the identity is supported.
fn check_identity_gamma(g: Node) -> Result<(), LoadError> {
    for (r, row) in children(g, "row").enumerate() {
        for (c, col) in children(row, "col").enumerate() {
            let x = number(col, "col", col.text().unwrap_or(""))?;
            if x != if r == c { 1.0 } else { 0.0 } {
                return Err(err(
                    g,
                    LoadErrorKind::Unsupported {
                        feature: "a joint coupling matrix other than the identity".into(),
                    },
                ));
            }
        }
    }
    Ok(())
}
