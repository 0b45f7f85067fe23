//! What RL's two XML formats share, read once for both: `rlmdl` (RL's `XmlFactory`) and `rlkin`
//! (RL's `Kinematics::create`). Both put their models in `<rlmdl>`/`<rlkin>` or `<rl><mdl>`/
//! `<rl><kin>`, describe a tree of frames by id (one `<world>`) joined by transform elements
//! whose `<frame>` names the frames `a` and `b`, write poses as `rotation` (degrees, `Rz·Ry·Rx`)
//! and `translation` (m), and number joint limits as `min`, `max`, `speed`, `wraparound`.

use std::collections::HashMap;
use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use glam::DVec3;
use roxmltree::Node;

use super::{
    Lines, attr, child, child_xyz, children, elem, err, invalid, number, reference, rot_zyx,
};
use crate::loader::error::{LoadError, LoadErrorKind};
use crate::loader::tree::{Assembly, ChildOrder, Edge, EdgeKind, Node as Frame, assemble};
use crate::loader::{Format, LoadOptions, LoadedModel};
use crate::model::{JointLimits, ModelBuilder};
use crate::spatial::{PlueckerTransform, RigidBodyInertia};

/// One degree in radians: RL writes angles in degrees.
pub(crate) const DEG: f64 = core::f64::consts::PI / 180.0;

/// The element holding the models: the root itself if it is `<own>`, else `<rl>`'s child
/// `<sub>`.
pub(crate) fn container<'a, 'i>(
    root: Node<'a, 'i>,
    own: &str,
    sub: &'static str,
) -> Result<Node<'a, 'i>, LoadError> {
    match root.tag_name().name() {
        tag if tag == own => Ok(root),
        "rl" => {
            child(root, sub).ok_or_else(|| err(root, LoadErrorKind::MissingElement { child: sub }))
        }
        tag => Err(err(
            root,
            LoadErrorKind::UnknownFormat {
                root: tag.to_string(),
            },
        )),
    }
}

/// `row:column` of `n` in its document, to start a warning with.
pub(crate) fn position(n: Node) -> String {
    let p = n.document().text_pos_at(n.range().start);
    format!("{}:{}", p.row, p.col)
}

/// The `rotation` (deg, `Rz·Ry·Rx`) and `translation` (m) children of `n`, identity where
/// absent.
pub(crate) fn pose(n: Node) -> Result<PlueckerTransform, LoadError> {
    let rot = match child(n, "rotation") {
        Some(r) => child_xyz(r, DVec3::ZERO)? * DEG,
        None => DVec3::ZERO,
    };
    let tr = match child(n, "translation") {
        Some(t) => child_xyz(t, DVec3::ZERO)?,
        None => DVec3::ZERO,
    };
    Ok(PlueckerTransform::new(rot_zyx(rot.x, rot.y, rot.z), tr))
}

/// The frames of a model element, by id.
pub(crate) struct Frames<'a, 'i> {
    /// Every frame, in file order.
    pub(crate) nodes: Vec<Frame>,
    /// Each frame's index in `nodes`, by id.
    pub(crate) index: HashMap<&'a str, usize>,
    /// The `<world>`'s index in `nodes`.
    pub(crate) world: usize,
    /// The `<world>` element.
    pub(crate) world_node: Node<'a, 'i>,
}

/// The frames of `model`: its one `<world>` and its elements tagged `tags`, in file order, with
/// unique ids. `frame(n, id)` reads each frame other than the world (in file order, after its
/// id is checked) and says its inertia.
pub(crate) fn frames<'a, 'i>(
    model: Node<'a, 'i>,
    tags: [&str; 2],
    lines: &Lines,
    mut frame: impl FnMut(Node<'a, 'i>, &str) -> Result<Option<RigidBodyInertia>, LoadError>,
) -> Result<Frames<'a, 'i>, LoadError> {
    let mut nodes: Vec<Frame> = Vec::new();
    let mut index: HashMap<&str, usize> = HashMap::new();
    let mut world: Option<(usize, Node)> = None;
    for n in model.children().filter(|n| n.is_element()) {
        let t = n.tag_name().name();
        if t != "world" && !tags.contains(&t) {
            continue;
        }
        let id = attr(n, "id")?;
        if index.insert(id, nodes.len()).is_some() {
            return Err(err(
                n,
                LoadErrorKind::DuplicateName {
                    name: id.to_string(),
                },
            ));
        }
        let inertia = if t == "world" {
            if let Some((_, first)) = world {
                return Err(err(
                    n,
                    LoadErrorKind::roots([first.attribute("id").unwrap_or(""), id].into_iter()),
                ));
            }
            world = Some((nodes.len(), n));
            None
        } else {
            frame(n, id)?
        };
        nodes.push(Frame {
            name: id.to_string(),
            inertia,
            elem: lines.elem(n),
        });
    }
    let Some((world, world_node)) = world else {
        return Err(err(model, LoadErrorKind::MissingElement { child: "world" }));
    };
    Ok(Frames {
        nodes,
        index,
        world,
        world_node,
    })
}

/// A child element of a model that `reader` does not read: a [`LoadErrorKind::UnknownJointType`]
/// if it looks like a transform (its `<frame>` names an `a`, or `transform_like`), else a
/// warning.
pub(crate) fn unread(
    n: Node,
    transform_like: bool,
    reader: &str,
    warnings: &mut Vec<String>,
) -> Result<(), LoadError> {
    let t = n.tag_name().name();
    if child(n, "frame").is_some_and(|f| child(f, "a").is_some()) || transform_like {
        return Err(err(
            n,
            LoadErrorKind::UnknownJointType {
                joint_type: t.to_string(),
            },
        ));
    }
    warnings.push(format!(
        "{}: <{t}> ignored ({reader} does not read it)",
        position(n)
    ));
    Ok(())
}

/// Transform element `n` as an edge of the frame tree: its id, the frames its `<frame>` names
/// as `a` (parent) and `b` (child), and the kind and origin `read(id)` makes of it.
pub(crate) fn edge(
    n: Node,
    nodes: &HashMap<&str, usize>,
    lines: &Lines,
    read: impl FnOnce(&str) -> Result<(EdgeKind, PlueckerTransform), LoadError>,
) -> Result<Edge, LoadError> {
    let name = attr(n, "id")?.to_string();
    let f = child(n, "frame")
        .ok_or_else(|| err(n, LoadErrorKind::MissingElement { child: "frame" }))?;
    let parent = reference(f, "a", "idref", nodes, n)?;
    let child_frame = reference(f, "b", "idref", nodes, n)?;
    let (kind, origin) = read(&name)?;
    Ok(Edge {
        parent,
        child: child_frame,
        name,
        source_type: n.tag_name().name().to_string(),
        origin,
        kind,
        elem: lines.elem(n),
    })
}

/// The `k`-th (from 1) child `tag` as a number, or `default`.
pub(crate) fn indexed(n: Node, tag: &str, k: usize, default: f64) -> Result<f64, LoadError> {
    match children(n, tag).nth(k - 1) {
        Some(c) => number(c, tag, c.text().unwrap_or("")),
        None => Ok(default),
    }
}

/// Limits of DOF `k` (from 1) of joint element `n`, positions and speed scaled by `scale`.
/// Without `min`/`max` the joint is unlimited; a `speed` of 0 or none is unknown (infinite).
pub(crate) fn limits(n: Node, k: usize, scale: f64) -> Result<JointLimits, LoadError> {
    let lower = indexed(n, "min", k, f64::NEG_INFINITY)?;
    let upper = indexed(n, "max", k, f64::INFINITY)?;
    if lower > upper {
        let c = children(n, "min").nth(k - 1).unwrap_or(n);
        return Err(invalid(c, "min", &lower.to_string(), "greater than max"));
    }
    let speed = crate::loader::rate_limit(indexed(n, "speed", k, f64::INFINITY)?);
    if speed < 0.0 {
        let c = children(n, "speed").nth(k - 1).unwrap_or(n);
        return Err(invalid(c, "speed", &speed.to_string(), "negative"));
    }
    Ok(JointLimits {
        lower: lower * scale,
        upper: upper * scale,
        velocity: speed * scale,
        effort: f64::INFINITY,
        wraparound: children(n, "wraparound").nth(k - 1).is_some()
            || (k == 1 && child(n, "wraparound").is_some()),
    })
}

/// The frame tree of a model element, to assemble.
pub(crate) struct Tree<'t> {
    /// The frames ([`Frames::nodes`]).
    pub(crate) nodes: &'t [Frame],
    /// The world's index in `nodes`.
    pub(crate) world: usize,
    /// The transforms, in file order.
    pub(crate) edges: &'t [Edge],
    /// The world's pose: the model's base.
    pub(crate) base: PlueckerTransform,
    /// The physical gravity, if the file gives one (else the builder's default).
    pub(crate) gravity: Option<DVec3>,
}

/// Assembles `tree`, read from `model` (an rlmdl `<model>` or an rlkin `<kinematics>`), into a
/// model named after the element's `<name>`, its tools the tree's leaves: `warnings` gets the
/// assembly's notes and the frames not connected to the world (RL skips them). No home
/// position.
pub(crate) fn assemble_model<const N: usize>(
    model: Node,
    tree: &Tree,
    format: Format,
    options: &LoadOptions,
    mut warnings: Vec<String>,
) -> Result<LoadedModel<N>, LoadError> {
    let mut builder = ModelBuilder::<N>::new();
    let name = child(model, "name")
        .and_then(|n| n.text())
        .unwrap_or("")
        .trim();
    builder
        .name(crate::loader::display_name(name))
        .map_err(|e| err(model, LoadErrorKind::Model(e)))?;
    if let Some(g) = tree.gravity {
        builder.gravity(g);
    }
    let how = Assembly {
        root: tree.world,
        base: tree.base,
        floating: None,
        order: ChildOrder::File,
        leaf_tools: true,
        extra_tools: &[],
        doc_elem: elem(model),
        inertia: options.inertia,
    };
    let assembled = assemble(tree.nodes, tree.edges, &how, &mut builder)?;
    warnings.extend(assembled.warnings.iter().cloned());
    for f in &assembled.unconnected {
        warnings.push(format!(
            "frame \"{f}\" is not connected to the world and is skipped, as RL does"
        ));
    }
    Ok(LoadedModel {
        model: builder.build(),
        format,
        home: None,
        frames: assembled.frames,
        transforms: assembled.transforms,
        warnings,
    })
}
