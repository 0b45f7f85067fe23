//! RL's older kinematics format (`rlkin`, RL's `rl::kin`): Denavit–Hartenberg joints, read as
//! RL's `Kinematics::create` reads it.
//!
//! ```xml
//! <rlkin>
//!   <puma>                                      <!-- or <kinematics>, <rhino> -->
//!     <world id="world"> <rotation>…</rotation> <translation>…</translation> </world>
//!     <transform id="base"> <frame><a idref="world"/><b idref="link0"/></frame> … </transform>
//!     <link id="link0"> <ignore/> <ignore idref="link1"/> </link>
//!     <revolute id="joint0">
//!       <frame><a idref="link0"/><b idref="link1"/></frame>
//!       <dh><d>0.6604</d><theta>0</theta><a>0</a><alpha>-90</alpha></dh>
//!       <max>160</max> <min>-160</min> <speed>250</speed>
//!     </revolute>
//!     …
//!   </puma>
//! </rlkin>
//! ```
//!
//! The root is `<rlkin>` or `<rl><kin>`; its first `<kinematics>`, `<puma>` or `<rhino>` is
//! loaded (RL picks `<puma>`/`<rhino>` for their closed-form inverse kinematics; here all three
//! are the same general kinematics). Frames are `<world>` (the root), `<link>` and `<frame>`;
//! transforms are `<transform>` (fixed), `<revolute>` and `<prismatic>`, each from frame `a` to
//! frame `b`. The tree is walked depth-first from the world, children in file order, so joints
//! are numbered as RL numbers them; its leaves are the tools (RL's operational frames).
//!
//! Conventions (RL's `Kinematics.cpp`, `Revolute.cpp`, `Prismatic.cpp` and Eigen's
//! `fromDenavitHartenbergPaul`):
//! - A joint's transform from frame `a` to frame `b` is Paul's Denavit–Hartenberg product
//!   `Tz(d) · Rz(θ) · Tx(a) · Rx(α)`, i.e. rotation `Rz(θ)·Rx(α)` and translation
//!   `(a cos θ, a sin θ, d)`. A revolute joint turns `θ = theta + q + offset`; a prismatic
//!   joint slides `d = d + q + offset`. So `theta` (and `offset`) are constant offsets added to
//!   the joint variable, and `q = 0` is the file's DH pose.
//! - Units: `theta` and `alpha` in degrees; for revolute joints also `min`, `max`, `offset` and
//!   `speed` (deg, deg/s); prismatic `d`, `a`, `min`, `max`, `offset` in m, `speed` in m/s.
//!   Everything is converted to rad and m here. Without `min`/`max` a joint is unlimited; a
//!   `speed` of 0 or none is unknown (infinite). `<wraparound/>` marks a joint whose range
//!   wraps.
//! - `<world>` and fixed `<transform>` rotations are degrees about x, y, z applied as
//!   `Rz·Ry·Rx`; translations in m. The world's pose is the model's base. A `<frame>` other
//!   than the world has no pose of its own in RL (its rotation and translation are
//!   overwritten by the transform into it); here they are ignored with a warning.
//!
//! In the model, each joint is a body whose frame is the joint frame: frame `a` turned (or
//! slid) about its z axis by `q`; frame `b` (the link) sits at the constant DH pose in that
//! body, and [`super::LoadedModel::frames`] says where. The format has no masses: the bodies
//! have zero inertia, so the model is for kinematics only.
//!
//! Bad input is a [`LoadError`] naming the element; where RL would silently read a missing
//! number as 0, `<dh>` and its four parameters are required here, as RL's schema requires
//! them.

use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use glam::{DMat3, DVec3};
use roxmltree::Node;

use super::error::{LoadError, LoadErrorKind};
use super::tree::{Edge, EdgeKind};
use super::xml::rl::{self, DEG, Frames, Tree, limits, pose, position};
use super::xml::{Lines, child, child_number, children, err, number};
use super::{Format, LoadOptions, LoadedModel};
use crate::joint::{Joint, MAX_JOINT_NV, Prismatic, Revolute};
use crate::model::JointLimits;
use crate::spatial::PlueckerTransform;

/// The elements RL reads as a kinematic model, in the order of its XPath union.
const INSTANCES: [&str; 3] = ["kinematics", "puma", "rhino"];
const TRANSFORMS: [&str; 3] = ["transform", "revolute", "prismatic"];

/// Whether `root` is an rlkin document (`<rlkin>` or `<rl>` holding `<kin>`).
pub(crate) fn is_rlkin(root: Node) -> bool {
    match root.tag_name().name() {
        "rlkin" => true,
        "rl" => child(root, "kin").is_some() && child(root, "mdl").is_none(),
        _ => false,
    }
}

/// The model element (`<kinematics>`, `<puma>` or `<rhino>`) of an rlkin document, and whether
/// it has more than one.
pub(crate) fn instance<'a, 'i>(root: Node<'a, 'i>) -> Result<(Node<'a, 'i>, bool), LoadError> {
    let container = rl::container(root, "rlkin", "kin")?;
    let mut found = container
        .children()
        .filter(|n| n.is_element() && INSTANCES.contains(&n.tag_name().name()));
    let first = found.next().ok_or_else(|| {
        err(
            container,
            LoadErrorKind::MissingElement {
                child: "kinematics",
            },
        )
    })?;
    Ok((first, found.next().is_some()))
}

/// Loads the first kinematic model of an rlkin document.
pub(crate) fn from_document<const N: usize>(
    root: Node,
    options: &LoadOptions,
) -> Result<LoadedModel<N>, LoadError> {
    let (kin, more) = instance(root)?;
    let mut warnings = Vec::new();
    if more {
        warnings.push(String::from(
            "only the first <kinematics>/<puma>/<rhino> is loaded, as RL does",
        ));
    }
    let lines = Lines::new(root.document().input_text());

    // Frames: world, links and frames, by id.
    let mut links: Vec<Node> = Vec::new();
    let frames = rl::frames(kin, ["link", "frame"], &lines, |n, id| {
        if n.tag_name().name() == "link" {
            links.push(n);
        } else if pose(n)? != PlueckerTransform::IDENTITY {
            warnings.push(format!(
                "{}: the rotation and translation of <frame \"{id}\"> are ignored \
                 (RL overwrites them with the transform into the frame)",
                position(n)
            ));
        }
        Ok(None)
    })?;
    // `<ignore idref>` must name a link (RL throws on an unknown one).
    for l in &links {
        for ig in children(*l, "ignore") {
            if let Some(r) = ig.attribute("idref").filter(|r| !r.is_empty()) {
                if !links.iter().any(|k| k.attribute("id") == Some(r)) {
                    return Err(err(
                        ig,
                        LoadErrorKind::UnresolvedReference {
                            target: r.to_string(),
                        },
                    ));
                }
            }
        }
    }

    // Transforms, in file order.
    let mut edges: Vec<Edge> = Vec::new();
    for n in kin.children().filter(|n| n.is_element()) {
        let t = n.tag_name().name();
        if TRANSFORMS.contains(&t) {
            edges.push(transform(n, &frames, &lines, &mut warnings)?);
        } else if !matches!(t, "world" | "link" | "frame" | "manufacturer" | "name") {
            let dh = child(n, "dh").is_some();
            rl::unread(n, dh, "RL's rlkin reader", &mut warnings)?;
        }
    }

    let tree = Tree {
        nodes: &frames.nodes,
        world: frames.world,
        edges: &edges,
        base: pose(frames.world_node)?,
        gravity: None,
    };
    rl::assemble_model(kin, &tree, Format::Rlkin, options, warnings)
}

/// Paul's Denavit–Hartenberg transform `Tz(d)·Rz(θ)·Tx(a)·Rx(α)` (m, rad).
pub(crate) fn dh_transform(d: f64, theta: f64, a: f64, alpha: f64) -> PlueckerTransform {
    let rotation = DMat3::from_rotation_z(theta) * DMat3::from_rotation_x(alpha);
    let (s, c) = libm::sincos(theta);
    PlueckerTransform::new(rotation, DVec3::new(a * c, a * s, d))
}

/// A required child `tag` of `dh` as a number.
fn dh_number(dh: Node, tag: &'static str) -> Result<f64, LoadError> {
    let c = child(dh, tag).ok_or_else(|| err(dh, LoadErrorKind::MissingElement { child: tag }))?;
    number(c, tag, c.text().unwrap_or(""))
}

/// One transform element: `transform`, `revolute` or `prismatic`.
fn transform(
    n: Node,
    frames: &Frames,
    lines: &Lines,
    warnings: &mut Vec<String>,
) -> Result<Edge, LoadError> {
    let t = n.tag_name().name();
    rl::edge(n, &frames.index, lines, |name| {
        if t == "transform" {
            return Ok((EdgeKind::Fixed, pose(n)?));
        }
        let dh =
            child(n, "dh").ok_or_else(|| err(n, LoadErrorKind::MissingElement { child: "dh" }))?;
        let d = dh_number(dh, "d")?;
        let theta = dh_number(dh, "theta")? * DEG;
        let a = dh_number(dh, "a")?;
        let alpha = dh_number(dh, "alpha")? * DEG;
        if child(n, "center").is_some() {
            warnings.push(format!(
                "{}: <center> of <{t} \"{name}\"> ignored (RL's reader does not read it)",
                position(n)
            ));
        }
        let mut lim = [JointLimits::UNLIMITED; MAX_JOINT_NV];
        let (joint, child_offset) = if t == "revolute" {
            lim[0] = limits(n, 1, DEG)?;
            let offset = child_number(n, "offset", 0.0)? * DEG;
            (
                Joint::Revolute(Revolute::new(DVec3::Z)),
                dh_transform(d, theta + offset, a, alpha),
            )
        } else {
            lim[0] = limits(n, 1, 1.0)?;
            let offset = child_number(n, "offset", 0.0)?;
            (
                Joint::Prismatic(Prismatic::new(DVec3::Z)),
                dh_transform(d + offset, theta, a, alpha),
            )
        };
        // Rz(q) (or Tz(q)) commutes with the rest of the DH product's leading Rz(θ)·Tz(d), so
        // the joint turns frame `a` about its z axis and the link sits at the constant DH pose.
        let kind = EdgeKind::Moving {
            joint,
            post: PlueckerTransform::IDENTITY,
            child_offset,
            limits: lim,
        };
        Ok((kind, PlueckerTransform::IDENTITY))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dh_is_pauls_product() {
        // Tz(d)·Rz(θ)·Tx(a)·Rx(α) by hand for θ = 90°, α = 90°:
        // x₁ = y₀, y₁ = z₀, z₁ = x₀, origin (0, a, d).
        let t = dh_transform(0.5, 90.0 * DEG, 0.25, 90.0 * DEG);
        let x = t.rotation * DVec3::X;
        let y = t.rotation * DVec3::Y;
        let z = t.rotation * DVec3::Z;
        assert!((x - DVec3::Y).length() < 1e-15, "{x}");
        assert!((y - DVec3::Z).length() < 1e-15, "{y}");
        assert!((z - DVec3::X).length() < 1e-15, "{z}");
        assert!((t.translation - DVec3::new(0.0, 0.25, 0.5)).length() < 1e-15);
    }
}
