//! MoveIt planning scenes in YAML: the obstacles of a cell as `world.collision_objects`, the
//! format of the MotionBenchMaker problems and of `moveit_msgs/PlanningScene` dumps.
//!
//! Each collision object becomes one body of an environment model, named by its `id`, at its
//! `pose` (identity when absent); its `primitives` (`box` `[x, y, z]`, `sphere` `[r]`,
//! `cylinder` `[height, radius]`, `cone` `[height, radius]`, also as the message's numeric
//! types 1–4) at their `primitive_poses` relative to that pose, and its `meshes` (`vertices`
//! and `triangles` with `vertex_indices`) at their `mesh_poses`. Positions are `[x, y, z]` or
//! `{x, y, z}`, orientations `[x, y, z, w]` or `{x, y, z, w}`. Planes, octomaps and operations
//! other than ADD are refused with an error that says so. Everything else in the file (robot
//! state, allowed-collision matrix, names) is ignored.

use std::path::Path;

use glam::DVec3;
use rl_core::spatial::PlueckerTransform;
use saphyr::{LoadableYamlNode, MarkedYaml, Scalar, YamlData};

use super::limits::{Budget, SceneLimits};
use super::read_text_within;
use crate::error::{SgError, SgErrorKind};
use crate::geometry::{Geometry, TriangleMesh};
use crate::pose;
use crate::scene::Model;

type Node<'a> = MarkedYaml<'a>;

/// Places `e` at `node`'s line and column.
fn at(node: &Node, e: SgError) -> SgError {
    let m = node.span.start;
    e.at_position(m.line() as u32, m.col() as u32 + 1)
}

fn get<'a, 'i>(node: &'a Node<'i>, key: &str) -> Option<&'a Node<'i>> {
    node.data.as_mapping_get(key)
}

fn need<'a, 'i>(node: &'a Node<'i>, key: &str) -> Result<&'a Node<'i>, SgError> {
    get(node, key).ok_or_else(|| at(node, SgError::missing(format!("field \"{key}\""))))
}

fn seq<'a, 'i>(node: &'a Node<'i>, what: &str) -> Result<&'a [Node<'i>], SgError> {
    match &node.data {
        YamlData::Sequence(v) => Ok(v),
        _ => Err(at(node, SgError::invalid(what, "", "not a list"))),
    }
}

fn number(node: &Node, what: &str) -> Result<f64, SgError> {
    let x = match &node.data {
        YamlData::Value(Scalar::FloatingPoint(x)) => x.into_inner(),
        YamlData::Value(Scalar::Integer(i)) => *i as f64,
        YamlData::Value(Scalar::String(s)) => {
            return Err(at(node, SgError::invalid(what, s, "not a number")));
        }
        _ => return Err(at(node, SgError::invalid(what, "", "not a number"))),
    };
    if x.is_finite() {
        Ok(x)
    } else {
        Err(at(node, SgError::invalid(what, x, "not finite")))
    }
}

fn numbers(node: &Node, what: &str) -> Result<Vec<f64>, SgError> {
    seq(node, what)?.iter().map(|n| number(n, what)).collect()
}

/// `[a, b, c…]` or `{keys[0]: a, …}`.
fn components<const N: usize>(
    node: &Node,
    what: &str,
    keys: [&str; N],
) -> Result<[f64; N], SgError> {
    let mut out = [0.0; N];
    match &node.data {
        YamlData::Sequence(v) => {
            if v.len() != N {
                return Err(at(
                    node,
                    SgError::invalid(what, format!("{} numbers", v.len()), "wrong count"),
                ));
            }
            for (o, n) in out.iter_mut().zip(v) {
                *o = number(n, what)?;
            }
        }
        YamlData::Mapping(_) => {
            for (o, k) in out.iter_mut().zip(keys) {
                *o = number(need(node, k)?, what)?;
            }
        }
        _ => {
            return Err(at(
                node,
                SgError::invalid(what, "", "neither a list nor a mapping"),
            ));
        }
    }
    Ok(out)
}

/// A `{position, orientation}` pose (either may be absent: zero, identity).
fn pose_of(node: &Node, what: &str) -> Result<PlueckerTransform, SgError> {
    let p = match get(node, "position") {
        Some(n) => components(n, "position", ["x", "y", "z"])?,
        None => [0.0; 3],
    };
    let q = match get(node, "orientation") {
        Some(n) => components(n, "orientation", ["x", "y", "z", "w"])?,
        None => [0.0, 0.0, 0.0, 1.0],
    };
    pose::from_xyz_quat(what, DVec3::from_array(p), q).map_err(|e| at(node, e))
}

fn text_of<'a>(node: &'a Node) -> Option<&'a str> {
    match &node.data {
        YamlData::Value(Scalar::String(s)) => Some(s),
        _ => None,
    }
}

fn primitive(node: &Node) -> Result<Geometry, SgError> {
    let ty_node = need(node, "type")?;
    let ty = match &ty_node.data {
        YamlData::Value(Scalar::String(s)) => s.to_ascii_lowercase(),
        YamlData::Value(Scalar::Integer(i)) => match i {
            1 => "box".into(),
            2 => "sphere".into(),
            3 => "cylinder".into(),
            4 => "cone".into(),
            _ => format!("{i}"),
        },
        _ => String::new(),
    };
    let dims_node = need(node, "dimensions")?;
    let dims = numbers(dims_node, "dimensions")?;
    let want = |n: usize| -> Result<(), SgError> {
        if dims.len() == n {
            Ok(())
        } else {
            Err(at(
                dims_node,
                SgError::invalid(
                    format!("{ty} dimensions"),
                    format!("{dims:?}"),
                    "wrong count",
                ),
            ))
        }
    };
    let g = match ty.as_str() {
        "box" => {
            want(3)?;
            Geometry::cuboid(DVec3::new(dims[0], dims[1], dims[2]))
        }
        "sphere" => {
            want(1)?;
            Geometry::sphere(dims[0])
        }
        "cylinder" => {
            want(2)?;
            Geometry::cylinder(dims[1], dims[0])
        }
        "cone" => {
            want(2)?;
            Geometry::cone(dims[1], dims[0])
        }
        _ => {
            return Err(at(
                ty_node,
                SgError::unsupported(format!(
                    "primitive type \"{ty}\" (supported: box, sphere, cylinder, cone)"
                )),
            ));
        }
    };
    g.map_err(|e| at(dims_node, e))
}

/// [`primitive`], counted as one shape.
fn counted_primitive(node: &Node, budget: &mut Budget) -> Result<Geometry, SgError> {
    budget.shape(0, 0).map_err(|e| at(node, e))?;
    primitive(node)
}

fn mesh(node: &Node, budget: &mut Budget) -> Result<Geometry, SgError> {
    let vs = need(node, "vertices")?;
    let ts = need(node, "triangles")?;
    budget
        .shape(seq(vs, "vertices")?.len(), seq(ts, "triangles")?.len())
        .map_err(|e| at(node, e))?;
    let vertices = seq(vs, "vertices")?
        .iter()
        .map(|v| components(v, "vertex", ["x", "y", "z"]).map(DVec3::from_array))
        .collect::<Result<Vec<_>, _>>()?;
    let mut triangles = Vec::new();
    for t in seq(ts, "triangles")? {
        let idx = get(t, "vertex_indices").unwrap_or(t);
        let [a, b, c] = components(idx, "vertex_indices", ["0", "1", "2"])?;
        let as_index = |x: f64| {
            if x >= 0.0 && x.fract() == 0.0 && x < f64::from(u32::MAX) {
                Ok(x as u32)
            } else {
                Err(at(idx, SgError::invalid("vertex index", x, "not an index")))
            }
        };
        triangles.push([as_index(a)?, as_index(b)?, as_index(c)?]);
    }
    let (m, _) = TriangleMesh::new(vertices, triangles).map_err(|e| at(node, e))?;
    Ok(Geometry::mesh(m))
}

/// Reads the collision objects of the planning scene in `text` into an environment model
/// called `name`.
pub fn environment_from_str(text: &str, name: &str) -> Result<Model, SgError> {
    environment_from_str_with(text, name, &SceneLimits::DEFAULT)
}

/// [`environment_from_str`] within `limits` (shapes, mesh vertices and triangles).
pub fn environment_from_str_with(
    text: &str,
    name: &str,
    limits: &SceneLimits,
) -> Result<Model, SgError> {
    let mut budget = Budget::new(*limits);
    let docs = MarkedYaml::load_from_str(text).map_err(|e| {
        let m = e.marker();
        SgError::syntax(e.info().to_string()).at_position(m.line() as u32, m.col() as u32 + 1)
    })?;
    let doc = docs
        .first()
        .ok_or_else(|| SgError::missing("a YAML document"))?;
    let world = need(doc, "world")?;
    let mut model = Model::new(name);
    let Some(objects) = get(world, "collision_objects") else {
        return Ok(model);
    };
    for (k, o) in seq(objects, "collision_objects")?.iter().enumerate() {
        let id = get(o, "id")
            .and_then(|n| text_of(n))
            .unwrap_or("")
            .to_string();
        let what = format!("collision object #{k} \"{id}\"");
        read_object(o, &id, &mut model, &mut budget).map_err(|e| e.at(what))?;
    }
    Ok(model)
}

fn read_object(o: &Node, id: &str, model: &mut Model, budget: &mut Budget) -> Result<(), SgError> {
    if let Some(op) = get(o, "operation") {
        let add = match &op.data {
            YamlData::Value(Scalar::Integer(0)) => true,
            YamlData::Value(Scalar::String(s)) => s.eq_ignore_ascii_case("add"),
            _ => false,
        };
        if !add {
            return Err(at(op, SgError::unsupported("operations other than ADD")));
        }
    }
    for unsupported in ["planes", "octomap"] {
        if get(o, unsupported)
            .is_some_and(|n| !matches!(&n.data, YamlData::Sequence(v) if v.is_empty()))
        {
            return Err(at(
                o,
                SgError::unsupported(format!("\"{unsupported}\" in a collision object")),
            ));
        }
    }
    if model.body_index(id).is_some() {
        return Err(at(
            o,
            SgError::new(SgErrorKind::DuplicateName {
                name: id.to_string(),
            }),
        ));
    }
    let object_pose = match get(o, "pose") {
        Some(p) => pose_of(p, "object pose")?,
        None => PlueckerTransform::IDENTITY,
    };
    let mut shapes = Vec::new();
    for (list, poses, read) in [
        (
            "primitives",
            "primitive_poses",
            counted_primitive as fn(&Node, &mut Budget) -> Result<Geometry, SgError>,
        ),
        ("meshes", "mesh_poses", mesh),
    ] {
        let Some(items) = get(o, list) else { continue };
        let items = seq(items, list)?;
        let pose_list = match get(o, poses) {
            Some(p) => seq(p, poses)?,
            None => &[],
        };
        if pose_list.len() != items.len() {
            return Err(at(
                o,
                SgError::invalid(
                    format!("number of {poses}"),
                    pose_list.len(),
                    "differs from the number of shapes",
                ),
            ));
        }
        for (j, (item, p)) in items.iter().zip(pose_list).enumerate() {
            let g = read(item, budget)?;
            let local = pose_of(p, poses)?;
            shapes.push((format!("{id}/{list}/{j}"), g, local));
        }
    }
    let body = model.add_body(id);
    for (name, g, local) in shapes {
        body.add_shape(name, g, local)?;
    }
    body.place(&object_pose);
    Ok(())
}

/// Reads the planning scene file at `path` into a model named after the file (its stem).
pub fn load_environment(path: &Path) -> Result<Model, SgError> {
    load_environment_with(path, &SceneLimits::DEFAULT)
}

/// [`load_environment`] within `limits` (the file's size, shapes, mesh vertices and triangles).
pub fn load_environment_with(path: &Path, limits: &SceneLimits) -> Result<Model, SgError> {
    let text = read_text_within(path, limits.max_file_bytes)?;
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("environment");
    environment_from_str_with(&text, name, limits).map_err(|e| e.in_file(path))
}
