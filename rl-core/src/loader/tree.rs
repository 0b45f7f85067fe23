//! The frame tree both formats parse into, and its assembly into a [`ModelBuilder`].
//!
//! A file describes frames (RL frames and bodies, URDF links) joined by transforms (RL
//! transforms, URDF joints). Assembly walks the tree depth-first from the root, adds one
//! moving body per moving joint, and merges every frame reached through fixed transforms into
//! its nearest moving ancestor (or the world): placements are composed along the way and
//! inertias are added at the composed pose.

use std::string::String;
use std::vec;
use std::vec::Vec;

use super::error::{ElementRef, LoadError, LoadErrorKind};
use super::{FrameInfo, TransformInfo};
use crate::joint::{Joint, MAX_JOINT_NV, SixDof};
use crate::model::{JointLimits, ModelBuilder, ROOT};
use crate::spatial::{PlueckerTransform, RigidBodyInertia};

/// A frame: an RL frame/body/world or a URDF link.
pub(crate) struct Node {
    pub name: String,
    /// Inertia in the node's own frame, if it has mass.
    pub inertia: Option<RigidBodyInertia>,
    pub elem: ElementRef,
}

/// How a transform moves.
#[allow(clippy::large_enum_variant)] // a few per file, built once at load time
pub(crate) enum EdgeKind {
    /// A constant transform (also URDF joints locked at a value).
    Fixed,
    /// A joint. The body frame is the joint's child frame.
    Moving {
        joint: Joint,
        /// Appended to the placement after `origin` (RL's offsets).
        post: PlueckerTransform,
        /// The child node's pose in the body frame (identity but for re-aligned joints).
        child_offset: PlueckerTransform,
        /// Limits per DOF (first `joint.nv()` used).
        limits: [JointLimits; MAX_JOINT_NV],
    },
}

/// A transform from `parent` to `child`.
pub(crate) struct Edge {
    pub parent: usize,
    pub child: usize,
    pub name: String,
    /// The type as the file writes it (`revolute`, `continuous`, `sixDof`, ...).
    pub source_type: String,
    /// The joint frame (or the child frame, for fixed transforms) in the parent frame.
    pub origin: PlueckerTransform,
    pub kind: EdgeKind,
    pub elem: ElementRef,
}

/// In which order the children of a frame are visited.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ChildOrder {
    /// File order of the transforms (RL).
    File,
    /// Ascending byte order of the joint names (Pinocchio's URDF parser, via urdfdom's map).
    ByName,
}

/// How to assemble.
pub(crate) struct Assembly<'a> {
    pub root: usize,
    /// The root frame's pose in the world (RL's world transform).
    pub base: PlueckerTransform,
    /// Name of a six-DOF joint between the world and the root frame, if floating.
    pub floating: Option<&'a str>,
    pub order: ChildOrder,
    /// Frames with no outgoing transform become tools.
    pub leaf_tools: bool,
    /// More tools, by frame name, after the leaves.
    pub extra_tools: &'a [String],
    /// Where to report a name in `extra_tools` that does not exist.
    pub doc_elem: ElementRef,
    /// What an unphysical body inertia is.
    pub inertia: super::InertiaCheck,
}

/// What assembly found besides the model itself.
pub(crate) struct Assembled {
    pub frames: Vec<FrameInfo>,
    pub transforms: Vec<TransformInfo>,
    /// Frames that are not connected to the root (RL skips them).
    pub unconnected: Vec<String>,
    /// Notes from the physical checks.
    pub warnings: Vec<String>,
}

fn model_err(elem: &ElementRef, e: crate::model::ModelError) -> LoadError {
    LoadError::at(elem.clone(), LoadErrorKind::Model(e))
}

/// Checks that the edges form a tree below `root` and builds the model.
pub(crate) fn assemble<const N: usize>(
    nodes: &[Node],
    edges: &[Edge],
    how: &Assembly,
    builder: &mut ModelBuilder<N>,
) -> Result<Assembled, LoadError> {
    // Each frame has at most one parent.
    let mut parent_edge: Vec<Option<usize>> = vec![None; nodes.len()];
    for (e, edge) in edges.iter().enumerate() {
        if let Some(other) = parent_edge[edge.child] {
            return Err(LoadError::at(
                edge.elem.clone(),
                LoadErrorKind::TwoParents {
                    frame: nodes[edge.child].name.clone(),
                    other: edges[other].name.clone(),
                },
            ));
        }
        parent_edge[edge.child] = Some(e);
    }
    if let Some(e) = parent_edge[how.root] {
        // The root on a loop, or the world below something.
        return Err(LoadError::at(edges[e].elem.clone(), LoadErrorKind::Cycle));
    }
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    for (e, edge) in edges.iter().enumerate() {
        children[edge.parent].push(e);
    }
    if how.order == ChildOrder::ByName {
        for c in &mut children {
            c.sort_by(|&a, &b| edges[a].name.as_bytes().cmp(edges[b].name.as_bytes()));
        }
    }

    let mut map: Vec<Option<(usize, PlueckerTransform)>> = vec![None; nodes.len()];
    let mut out = Assembled {
        frames: Vec::new(),
        transforms: Vec::new(),
        unconnected: Vec::new(),
        warnings: Vec::new(),
    };
    // Per body: its first node with mass (or its own node) and how many more nodes with mass
    // were merged into it; per node with mass: whether it went to the world.
    let mut body_node: Vec<(usize, usize)> = Vec::new();
    let note_mass = |body_node: &mut Vec<(usize, usize)>, b: usize, n: usize| {
        let (first, more) = &mut body_node[b];
        if nodes[*first].inertia.is_none() {
            *first = n;
        } else if *first != n {
            *more += 1;
        }
    };
    let mut massive: Vec<(usize, bool)> = Vec::new();
    let mut leaves = Vec::new();

    let root = &nodes[how.root];
    let root_map = match how.floating {
        Some(joint_name) => {
            let inertia = root.inertia.unwrap_or(RigidBodyInertia::ZERO);
            let b = builder
                .add_body(
                    ROOT,
                    joint_name,
                    Joint::SixDof(SixDof),
                    how.base,
                    &root.name,
                    inertia,
                )
                .map_err(|e| model_err(&root.elem, e))?;
            out.transforms.push(TransformInfo {
                name: joint_name.into(),
                source_type: "floating base".into(),
                body: b,
                moving: true,
            });
            body_node.push((how.root, 0));
            if root.inertia.is_some() {
                massive.push((how.root, false));
            }
            (b, PlueckerTransform::IDENTITY)
        }
        None => {
            if let Some(i) = root.inertia {
                builder
                    .add_fixed_inertia(ROOT, how.base, i)
                    .map_err(|e| model_err(&root.elem, e))?;
                massive.push((how.root, true));
            }
            (ROOT, how.base)
        }
    };
    map[how.root] = Some(root_map);
    out.frames.push(FrameInfo {
        name: root.name.clone(),
        body: root_map.0,
        placement: root_map.1,
    });
    if children[how.root].is_empty() {
        leaves.push(how.root);
    }
    let mut stack: Vec<usize> = children[how.root].iter().rev().copied().collect();
    while let Some(e) = stack.pop() {
        let edge = &edges[e];
        let Some((pb, ppose)) = map[edge.parent] else {
            return Err(LoadError::at(edge.elem.clone(), LoadErrorKind::Cycle));
        };
        if map[edge.child].is_some() {
            return Err(LoadError::at(edge.elem.clone(), LoadErrorKind::Cycle));
        }
        let child = &nodes[edge.child];
        let (b, pose, moving) = match &edge.kind {
            EdgeKind::Fixed => {
                let pose = ppose * edge.origin;
                if let Some(i) = child.inertia {
                    builder
                        .add_fixed_inertia(pb, pose, i)
                        .map_err(|e| model_err(&edge.elem, e))?;
                    massive.push((edge.child, pb == ROOT));
                    if pb != ROOT {
                        note_mass(&mut body_node, pb, edge.child);
                    }
                }
                (pb, pose, false)
            }
            EdgeKind::Moving {
                joint,
                post,
                child_offset,
                limits,
            } => {
                let placement = ppose * edge.origin * *post;
                let inertia = child
                    .inertia
                    .map(|i| i.transform_to_parent(child_offset))
                    .unwrap_or(RigidBodyInertia::ZERO);
                let b = builder
                    .add_body(pb, &edge.name, *joint, placement, &child.name, inertia)
                    .map_err(|e| model_err(&edge.elem, e))?;
                body_node.push((edge.child, 0));
                if child.inertia.is_some() {
                    massive.push((edge.child, false));
                }
                for (k, l) in limits.iter().enumerate().take(joint.nv()) {
                    builder
                        .set_limits(b, k, *l)
                        .map_err(|e| model_err(&edge.elem, e))?;
                }
                (b, *child_offset, true)
            }
        };
        map[edge.child] = Some((b, pose));
        out.frames.push(FrameInfo {
            name: child.name.clone(),
            body: b,
            placement: pose,
        });
        out.transforms.push(TransformInfo {
            name: edge.name.clone(),
            source_type: edge.source_type.clone(),
            body: b,
            moving,
        });
        if children[edge.child].is_empty() {
            leaves.push(edge.child);
        }
        stack.extend(children[edge.child].iter().rev().copied());
    }

    // Frames not reached: on a cycle (an error) or just not connected (RL skips those). Each
    // walk towards the root stops at a frame already known to be clear, so this is linear.
    let mut clear = vec![false; nodes.len()];
    let mut on_walk = vec![false; nodes.len()];
    let mut walk = Vec::new();
    for (n, m) in map.iter().enumerate() {
        if m.is_some() {
            continue;
        }
        walk.clear();
        let mut at = n;
        loop {
            if clear[at] {
                break;
            }
            if on_walk[at] {
                let e = parent_edge[at].unwrap_or(0);
                return Err(LoadError::at(edges[e].elem.clone(), LoadErrorKind::Cycle));
            }
            on_walk[at] = true;
            walk.push(at);
            match parent_edge[at] {
                Some(e) => at = edges[e].parent,
                None => break,
            }
        }
        for &w in &walk {
            on_walk[w] = false;
            clear[w] = true;
        }
        out.unconnected.push(nodes[n].name.clone());
    }

    let bodies: Vec<super::physical::BodyInertia> = body_node
        .iter()
        .enumerate()
        .map(|(b, &(n, merged_links))| super::physical::BodyInertia {
            link: &nodes[n].name,
            elem: &nodes[n].elem,
            merged_links,
            inertia: builder.inertia(b).copied().unwrap_or_default(),
        })
        .collect();
    let links: Vec<(&str, RigidBodyInertia, bool)> = massive
        .iter()
        .filter_map(|&(n, world)| nodes[n].inertia.map(|i| (nodes[n].name.as_str(), i, world)))
        .collect();
    super::physical::check_inertias(&bodies, &links, how.inertia, &mut out.warnings)?;

    if how.leaf_tools {
        for &n in &leaves {
            let (b, pose) = map[n].unwrap_or((ROOT, PlueckerTransform::IDENTITY));
            builder
                .add_tool(&nodes[n].name, b, pose)
                .map_err(|e| model_err(&nodes[n].elem, e))?;
        }
    }
    for name in how.extra_tools {
        let Some(f) = out.frames.iter().find(|f| &f.name == name) else {
            return Err(LoadError::at(
                how.doc_elem.clone(),
                LoadErrorKind::UnresolvedReference {
                    target: name.clone(),
                },
            ));
        };
        builder
            .add_tool(name, f.body, f.placement)
            .map_err(|e| model_err(&how.doc_elem, e))?;
    }
    Ok(out)
}
